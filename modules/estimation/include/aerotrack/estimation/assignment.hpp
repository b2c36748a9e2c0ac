// The cheapest assignment of the people in one frame to tracks (issue 22, item 2): global nearest neighbour
// solved exactly (Blackman and Popoli, Design and Analysis of Modern Tracking Systems, Sect. 6.4), not greedily.
// The greedy rule -- the cheapest pair first, then the cheapest of what is left -- can give the followed person's
// own detection to a bystander's track whose prediction it also fits, and the followed track the next person in
// its gate (traced: crowd seed 77 in image mode, the person at d2 0.02 from the followed track taken by a
// bystander's track, the look-alike at d2 7.6 left to the followed track).
//
// A frame holds at most hal::kMaxPersons (6) people, so the solver enumerates the subsets of people taken with
// a table over the tracks (dynamic programming, 2^6 subsets x 13 tracks): exact, without allocation, and simpler
// to check than the Hungarian method, which no Debian package offers without a large dependency (dlib). The unit
// test checks it against the enumeration of every assignment.
#pragma once

#include <array>
#include <cstddef>
#include <limits>

#include "aerotrack/estimation/target_estimator.hpp"
#include "aerotrack/hal/types.hpp"

namespace aerotrack::estimation {

/// Rows: the people of a frame. Columns: tracks (the target task's: the followed track and the bystanders').
inline constexpr std::size_t kMaxAssignmentRows = hal::kMaxPersons;
inline constexpr std::size_t kMaxAssignmentColumns = kMaxOtherPeople + 1;

/// Pair costs; infinity (the default) where the pair is not allowed (outside a gate).
class AssignmentCosts {
 public:
  static constexpr double kNotAllowed = std::numeric_limits<double>::infinity();
  AssignmentCosts() {
    for (auto& row : cost_) row.fill(kNotAllowed);
  }
  void set(std::size_t row, std::size_t column, double cost) { cost_[row][column] = cost; }
  double at(std::size_t row, std::size_t column) const { return cost_[row][column]; }

 private:
  std::array<std::array<double, kMaxAssignmentColumns>, kMaxAssignmentRows> cost_{};
};

struct AssignmentResult {
  static constexpr int kNone = -1;
  std::array<int, kMaxAssignmentRows> column{};  ///< Each row's column, or kNone.
  double cost = 0.0;                             ///< Pair costs plus miss_cost for each row with no column.
};

/// The assignment of rows [0, rows) to columns [0, columns) -- each row to at most one column and each column to
/// at most one row, allowed pairs only -- that minimises the sum of its pair costs plus `miss_cost` for every
/// row left without a column. With miss_cost at least every allowed pair's cost, no row that could take a free
/// column is left out. Among assignments of equal cost the choice is deterministic. rows <= kMaxAssignmentRows,
/// columns <= kMaxAssignmentColumns (clamped).
AssignmentResult cheapestAssignment(const AssignmentCosts& costs, std::size_t rows, std::size_t columns,
                                    double miss_cost);

}  // namespace aerotrack::estimation
