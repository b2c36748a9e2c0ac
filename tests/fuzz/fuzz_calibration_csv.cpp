// The localization calibration CSV (parseSamplesCsv) and, when it parses, the candump log reader
// on the same bytes (both are line-oriented text that users hand-edit).
#include <cstddef>
#include <cstdint>

#include "aerotrack/hal/replay/candump.hpp"
#include "aerotrack/localization/localization_io.hpp"
#include "fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  (void)aerotrack::localization::parseSamplesCsv(aerotrack::fuzz::text(data, size), "fuzz.csv");
  const aerotrack::fuzz::MemoryFile memory(data, size);
  (void)aerotrack::hal::replay::loadCandump(memory.path(), aerotrack::hal::replay::BadRowPolicy::kSkip);
  return 0;
}
