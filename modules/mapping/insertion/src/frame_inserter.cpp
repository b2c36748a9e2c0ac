// FrameInserter: pose lookup, depth back-projection and OctoMap insertion for one depth frame
// (see frame_inserter.hpp).
#include "aerotrack/mapping/frame_inserter.hpp"

namespace aerotrack::mapping {

const char* toString(FrameInsertStatus status) {
  switch (status) {
    case FrameInsertStatus::kInserted:
      return "depth frame inserted";
    case FrameInsertStatus::kSkippedNoPose:
      return "depth frame skipped: no pose at its capture time";
  }
  return "unknown";
}

rt::Expected<FrameInserter> FrameInserter::create(const DepthPointsParams& params) {
  if (rt::Status status = validate(params); !status) return status.error();
  return FrameInserter(params);
}

rt::Expected<FrameInsertReport> FrameInserter::insert(const hal::DepthFrame& frame, const PoseHistory& poses,
                                                      OctomapMap& map, std::span<const ExcludedBody> excluded) {
  FrameInsertReport report;
  const PoseLookup pose = poses.lookup(frame.stamp_ns);
  if (pose.status != PoseLookupStatus::kOk) {
    ++frames_skipped_no_pose_;
    report.status = FrameInsertStatus::kSkippedNoPose;
    report.pose_status = pose.status;
    return report;
  }
  const Eigen::Isometry3d& T_WB = pose.value;
  const Eigen::Isometry3d T_WC = T_WB * frame.T_BC;
  rt::Expected<DepthPointsStats> points = depthToPoints(frame, T_WC, params_, hits_W_, misses_W_, excluded);
  if (!points) {
    ++frames_invalid_;
    return points.error();
  }
  report.points = *points;
  rt::Expected<InsertStats> inserted = map.insert(hits_W_, misses_W_, T_WC.translation());
  if (!inserted) {
    ++frames_invalid_;
    return inserted.error();
  }
  report.insert = *inserted;
  ++frames_inserted_;
  return report;
}

}  // namespace aerotrack::mapping
