// Field tables: see field_table.hpp. The parts that do not depend on the struct type.
#include "aerotrack/rt/field_table.hpp"

#include <cmath>

namespace aerotrack::rt {

std::string formatYamlNumber(double value) {
  if (std::isnan(value)) return ".nan";
  if (std::isinf(value)) return value > 0.0 ? ".inf" : "-.inf";
  return formatConfigNumber(value);
}

namespace field_detail {

std::string outOfRange(const std::string& key, const Range& range, double value) {
  return key + " must be in " + range.toString() + ", got " + formatConfigNumber(value);
}

}  // namespace field_detail
}  // namespace aerotrack::rt
