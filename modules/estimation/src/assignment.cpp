#include "aerotrack/estimation/assignment.hpp"

#include <algorithm>
#include <bit>

namespace aerotrack::estimation {

AssignmentResult cheapestAssignment(const AssignmentCosts& costs, std::size_t rows, std::size_t columns,
                                    double miss_cost) {
  rows = std::min(rows, kMaxAssignmentRows);
  columns = std::min(columns, kMaxAssignmentColumns);
  constexpr std::size_t kSubsets = std::size_t{1} << kMaxAssignmentRows;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  // best[c][taken]: the cheapest pairs of the first c columns whose rows are the set `taken`; row_of[c][taken]:
  // the row column c took in it (kNone: none), to walk the choices back.
  std::array<std::array<double, kSubsets>, kMaxAssignmentColumns + 1> best{};
  std::array<std::array<int, kSubsets>, kMaxAssignmentColumns> row_of{};
  const std::size_t subsets = std::size_t{1} << rows;
  for (auto& b : best) b.fill(kInf);
  best[0][0] = 0.0;
  for (std::size_t c = 0; c < columns; ++c) {
    row_of[c].fill(AssignmentResult::kNone);
    for (std::size_t taken = 0; taken < subsets; ++taken) {
      const double before = best[c][taken];
      if (before == kInf) continue;
      if (before < best[c + 1][taken]) {
        best[c + 1][taken] = before;
        row_of[c][taken] = AssignmentResult::kNone;
      }
      for (std::size_t r = 0; r < rows; ++r) {
        const std::size_t with = taken | (std::size_t{1} << r);
        const double cost = costs.at(r, c);
        if (with == taken || cost == kInf) continue;
        if (before + cost < best[c + 1][with]) {
          best[c + 1][with] = before + cost;
          row_of[c][with] = static_cast<int>(r);
        }
      }
    }
  }
  AssignmentResult result;
  result.column.fill(AssignmentResult::kNone);
  result.cost = kInf;
  std::size_t taken = 0;
  for (std::size_t t = 0; t < subsets; ++t) {
    const auto missed = static_cast<double>(rows - static_cast<std::size_t>(std::popcount(t)));
    const double total = missed > 0.0 ? best[columns][t] + miss_cost * missed : best[columns][t];
    if (total < result.cost) {
      result.cost = total;
      taken = t;
    }
  }
  for (std::size_t c = columns; c-- > 0;) {
    const int r = row_of[c][taken];
    if (r == AssignmentResult::kNone) continue;
    result.column[static_cast<std::size_t>(r)] = static_cast<int>(c);
    taken &= ~(std::size_t{1} << static_cast<std::size_t>(r));
  }
  return result;
}

}  // namespace aerotrack::estimation
