// Scenario files: the whole reader (rt::ConfigNode underneath, every section, the cross checks:
// paths through obstacles, forests within the limits, names that are not paths).
#include <cstddef>
#include <cstdint>

#include "aerotrack/hal/sim/scenario.hpp"
#include "fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  (void)aerotrack::hal::sim::parseScenarioSpec(aerotrack::fuzz::text(data, size), "fuzz.yaml");
  return 0;
}
