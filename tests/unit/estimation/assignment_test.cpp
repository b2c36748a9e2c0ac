// The cheapest assignment of people to tracks (assignment.hpp), checked against the slow, obvious reference:
// every assignment enumerated.
#include <gtest/gtest.h>

#include <random>

#include "aerotrack/estimation/assignment.hpp"

namespace aerotrack::estimation {
namespace {

constexpr int kNone = AssignmentResult::kNone;

double costOf(const AssignmentCosts& costs, const std::array<int, kMaxAssignmentRows>& column, std::size_t rows,
              double miss_cost) {
  double total = 0.0;
  for (std::size_t r = 0; r < rows; ++r)
    total += column[r] == kNone ? miss_cost : costs.at(r, static_cast<std::size_t>(column[r]));
  return total;
}

// Every row tries none and every free column in turn (at most 14^6 leaves for 6 rows and 13 columns).
void enumerate(const AssignmentCosts& costs, std::size_t rows, std::size_t columns, double miss_cost, std::size_t row,
               std::array<int, kMaxAssignmentRows>& column, std::array<bool, kMaxAssignmentColumns>& used,
               double& best) {
  if (row == rows) {
    best = std::min(best, costOf(costs, column, rows, miss_cost));
    return;
  }
  column[row] = kNone;
  enumerate(costs, rows, columns, miss_cost, row + 1, column, used, best);
  for (std::size_t c = 0; c < columns; ++c) {
    if (used[c] || costs.at(row, c) == AssignmentCosts::kNotAllowed) continue;
    used[c] = true;
    column[row] = static_cast<int>(c);
    enumerate(costs, rows, columns, miss_cost, row + 1, column, used, best);
    used[c] = false;
  }
  column[row] = kNone;
}

double bruteForce(const AssignmentCosts& costs, std::size_t rows, std::size_t columns, double miss_cost) {
  std::array<int, kMaxAssignmentRows> column{};
  std::array<bool, kMaxAssignmentColumns> used{};
  double best = std::numeric_limits<double>::infinity();
  enumerate(costs, rows, columns, miss_cost, 0, column, used, best);
  return best;
}

// The result is an assignment (each column once, allowed pairs only) and its cost is what it claims.
void expectValid(const AssignmentCosts& costs, const AssignmentResult& result, std::size_t rows, std::size_t columns,
                 double miss_cost) {
  std::array<bool, kMaxAssignmentColumns> used{};
  for (std::size_t r = 0; r < kMaxAssignmentRows; ++r) {
    const int c = result.column[r];
    if (c == kNone) continue;
    ASSERT_LT(r, rows);
    ASSERT_GE(c, 0);
    ASSERT_LT(static_cast<std::size_t>(c), columns);
    EXPECT_FALSE(used[static_cast<std::size_t>(c)]) << "column " << c << " taken twice";
    used[static_cast<std::size_t>(c)] = true;
    EXPECT_NE(costs.at(r, static_cast<std::size_t>(c)), AssignmentCosts::kNotAllowed);
  }
  EXPECT_NEAR(result.cost, costOf(costs, result.column, rows, miss_cost), 1e-12);
}

TEST(CheapestAssignment, GivenThePersonNearerABystanderTrackThanTheLookAlike_ThenEachGoesToTheirOwnTrack) {
  // Column 0 the followed track, 1 a bystander's. The greedy rule takes the cheapest pair first (the person to
  // the bystander's track, 0.05) and leaves the look-alike to the followed track (0.64): 0.69 in all, against
  // 0.002 + 0.3 the other way round.
  AssignmentCosts costs;
  costs.set(0, 0, 0.002);  // the person: followed track
  costs.set(0, 1, 0.05);   //             bystander track
  costs.set(1, 0, 0.64);   // the look-alike
  costs.set(1, 1, 0.3);
  const AssignmentResult result = cheapestAssignment(costs, 2, 2, 1.5);
  expectValid(costs, result, 2, 2, 1.5);
  EXPECT_EQ(result.column[0], 0);
  EXPECT_EQ(result.column[1], 1);
  EXPECT_NEAR(result.cost, 0.302, 1e-12);
}

TEST(CheapestAssignment, GivenAMissDearerThanEveryPair_ThenNoRowThatCouldTakeAFreeColumnIsLeftOut) {
  AssignmentCosts costs;
  costs.set(0, 0, 0.1);
  costs.set(1, 0, 0.2);
  costs.set(1, 1, 0.9);  // dearer than the miss of row 0, cheaper than a miss of its own
  const AssignmentResult kept = cheapestAssignment(costs, 2, 2, 1.0);
  EXPECT_EQ(kept.column[0], 0);
  EXPECT_EQ(kept.column[1], 1);
  // A cheap miss leaves a dear pair out.
  const AssignmentResult left = cheapestAssignment(costs, 2, 2, 0.5);
  EXPECT_EQ(left.column[0], 0);
  EXPECT_EQ(left.column[1], kNone);
  EXPECT_NEAR(left.cost, 0.6, 1e-12);
}

TEST(CheapestAssignment, GivenNoAllowedPairOrNoRows_ThenEveryRowIsMissed) {
  const AssignmentCosts none;
  const AssignmentResult result = cheapestAssignment(none, 3, 4, 1.0);
  for (const int c : result.column) EXPECT_EQ(c, kNone);
  EXPECT_NEAR(result.cost, 3.0, 1e-12);
  EXPECT_NEAR(cheapestAssignment(none, 0, 4, 1.0).cost, 0.0, 1e-12);
  // An infinite miss cost with nothing to miss is no NaN.
  EXPECT_EQ(cheapestAssignment(none, 0, 0, AssignmentCosts::kNotAllowed).cost, 0.0);
}

TEST(CheapestAssignment, GivenRandomGates_ThenItsCostIsTheEnumeratedMinimum) {
  std::mt19937 rng(22);
  std::uniform_real_distribution<double> cost(0.0, 1.5);
  std::bernoulli_distribution allowed(0.4);
  std::uniform_int_distribution<std::size_t> row_count(0, kMaxAssignmentRows);
  std::uniform_int_distribution<std::size_t> column_count(0, 6);  // 7^6 leaves: the reference stays fast
  for (int trial = 0; trial < 300; ++trial) {
    const std::size_t rows = row_count(rng);
    const std::size_t columns = column_count(rng);
    AssignmentCosts costs;
    for (std::size_t r = 0; r < rows; ++r)
      for (std::size_t c = 0; c < columns; ++c)
        if (allowed(rng)) costs.set(r, c, cost(rng));
    const double miss_cost = trial % 2 == 0 ? 1.5 : 0.7;
    const AssignmentResult result = cheapestAssignment(costs, rows, columns, miss_cost);
    expectValid(costs, result, rows, columns, miss_cost);
    EXPECT_NEAR(result.cost, bruteForce(costs, rows, columns, miss_cost), 1e-12) << "trial " << trial;
  }
}

TEST(CheapestAssignment, GivenAFullFrameAndEveryTrack_ThenItsCostIsTheEnumeratedMinimum) {
  // Six people, thirteen tracks, every pair allowed: the largest problem the target task poses.
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> cost(0.0, 1.5);
  for (int trial = 0; trial < 3; ++trial) {
    AssignmentCosts costs;
    for (std::size_t r = 0; r < kMaxAssignmentRows; ++r)
      for (std::size_t c = 0; c < kMaxAssignmentColumns; ++c) costs.set(r, c, cost(rng));
    const AssignmentResult result = cheapestAssignment(costs, kMaxAssignmentRows, kMaxAssignmentColumns, 1.5);
    expectValid(costs, result, kMaxAssignmentRows, kMaxAssignmentColumns, 1.5);
    EXPECT_NEAR(result.cost, bruteForce(costs, kMaxAssignmentRows, kMaxAssignmentColumns, 1.5), 1e-12);
  }
}

}  // namespace
}  // namespace aerotrack::estimation
