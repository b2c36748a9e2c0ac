// What one planning cycle found, for people to look at (issue 24: the flight log's corridor, search
// path and prediction): a fixed-size copy the planning task publishes through a latest-value slot
// after each cycle that ran the planner. Nothing in the flight reads it. The arrays hold at most
// their capacity: the search path and the prediction are sampled evenly in time, the corridor's
// boxes beyond kMaxSnapshotBoxes (the optimiser's limit is lower) are left out and counted.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <type_traits>

#include "aerotrack/planning/kinodynamic_search.hpp"
#include "aerotrack/planning/tracking_planner.hpp"
#include "aerotrack/rt/bitwise_copyable.hpp"
#include "aerotrack/rt/time.hpp"

namespace aerotrack::planning {

inline constexpr std::size_t kMaxSnapshotBoxes = 32;
inline constexpr std::size_t kSnapshotPathSamples = 48;
inline constexpr std::size_t kSnapshotPredictionSamples = 24;

struct PlanSnapshot {
  rt::TimeNs stamp_ns = 0;  ///< The cycle's time.
  PlanReport report;
  double cycle_ms = 0.0;  ///< The cycle's duration on the stats clock.
  std::size_t box_count = 0;
  std::size_t boxes_left_out = 0;
  std::array<Eigen::Vector3d, kMaxSnapshotBoxes> box_lo_W_m{};
  std::array<Eigen::Vector3d, kMaxSnapshotBoxes> box_hi_W_m{};
  std::size_t search_count = 0;  ///< Samples of the kinodynamic search's path (0: none found).
  std::array<Eigen::Vector3d, kSnapshotPathSamples> search_W_m{};
  std::size_t prediction_count = 0;  ///< Samples of the person's Bezier prediction (0: not used this cycle).
  std::array<Eigen::Vector3d, kSnapshotPredictionSamples> prediction_W_m{};
};

/// Fills `out` from the planner's state after a cycle (its corridor, search path and prediction).
/// No allocation.
void takeSnapshot(const TrackingPlanner& planner, const PlanReport& report, rt::TimeNs now_ns, double cycle_ms,
                  PlanSnapshot& out);

}  // namespace aerotrack::planning

static_assert(std::is_standard_layout_v<aerotrack::planning::PlanSnapshot>);
template <>
struct aerotrack::rt::IsBitwiseCopyable<aerotrack::planning::PlanSnapshot> : std::true_type {};
