// A planning cycle's snapshot: see plan_snapshot.hpp.
#include "aerotrack/planning/plan_snapshot.hpp"

#include <algorithm>

namespace aerotrack::planning {

void takeSnapshot(const TrackingPlanner& planner, const PlanReport& report, rt::TimeNs now_ns, double cycle_ms,
                  PlanSnapshot& out) {
  out.stamp_ns = now_ns;
  out.report = report;
  out.cycle_ms = cycle_ms;
  const std::vector<CorridorBox>& boxes = planner.corridor().boxes;
  out.box_count = std::min(boxes.size(), kMaxSnapshotBoxes);
  out.boxes_left_out = boxes.size() - out.box_count;
  for (std::size_t i = 0; i < out.box_count; ++i) {
    out.box_lo_W_m[i] = boxes[i].lo_W_m;
    out.box_hi_W_m[i] = boxes[i].hi_W_m;
  }
  const SearchPath& path = planner.searchPath();
  out.search_count = 0;
  if (!path.segments.empty()) {
    out.search_count = kSnapshotPathSamples;
    for (std::size_t i = 0; i < kSnapshotPathSamples; ++i) {
      out.search_W_m[i] = path.stateAt(path.duration_s * static_cast<double>(i) / (kSnapshotPathSamples - 1)).p_W_m;
    }
  }
  out.prediction_count = 0;
  const auto& prediction = planner.lastPrediction();
  if (report.predicted && prediction && prediction->end_ns > now_ns) {
    out.prediction_count = kSnapshotPredictionSamples;
    const double span_s = rt::nsToSeconds(prediction->end_ns - now_ns);
    for (std::size_t i = 0; i < kSnapshotPredictionSamples; ++i) {
      const double t_s = span_s * static_cast<double>(i) / (kSnapshotPredictionSamples - 1);
      out.prediction_W_m[i] = prediction->position(now_ns + rt::secondsToNs(t_s));
    }
  }
}

}  // namespace aerotrack::planning
