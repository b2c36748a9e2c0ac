// The application's configuration (app/src/app_config.cpp: every section, each module's parser, the
// task table, the file references resolved beside config/), and its printout: a configuration that
// parses must print to YAML that parses back to the same printout (what `--print-config` and a
// recording's config.yaml rely on). Not in CI's short runs: it links the whole application, whose
// build in the fuzz tree costs more than the run (tests/fuzz/README.md).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "app_config.hpp"
#include "fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // Named as if beside the shipped configs, so that their relative file names (localization.yaml)
  // resolve and the parser goes on past them.
  const std::string source = AEROTRACK_CONFIG_DIR "/fuzz.yaml";
  const auto config = aerotrack::app::parseAppConfig(aerotrack::fuzz::text(data, size), source);
  if (!config) return 0;
  const std::string printed = aerotrack::app::toYaml(*config);
  const auto again = aerotrack::app::parseAppConfig(printed, source);
  if (!again || aerotrack::app::toYaml(*again) != printed) std::abort();  // the round trip broke
  return 0;
}
