// FrameInserter: one depth frame into the OctoMap (issue 4). Looks up the body pose at the
// frame's capture time in the PoseHistory (interpolated, never extrapolated), forms the camera
// pose T_WC = T_WB(stamp_ns) * T_BC, converts the pixels to world hit / miss points
// (depthToPoints) and integrates them from the camera centre (OctomapMap::insert). A frame
// without a pose at its capture time is skipped and counted; the result says why.
#pragma once

#include <cstdint>

#include <octomap/Pointcloud.h>

#include "aerotrack/hal/types.hpp"
#include "aerotrack/mapping/depth_points.hpp"
#include "aerotrack/mapping/octomap_map.hpp"
#include "aerotrack/mapping/pose_history.hpp"
#include "aerotrack/rt/expected.hpp"

namespace aerotrack::mapping {

enum class FrameInsertStatus : std::uint8_t {
  kInserted,
  kSkippedNoPose,  ///< No pose at the frame's capture time (see FrameInsertReport::pose_status).
};
/// "depth frame inserted" / "depth frame skipped: no pose at its capture time".
const char* toString(FrameInsertStatus status);

struct FrameInsertReport {
  FrameInsertStatus status = FrameInsertStatus::kInserted;
  PoseLookupStatus pose_status = PoseLookupStatus::kOk;  ///< Why there was no pose, when skipped.
  DepthPointsStats points;                               ///< Zero when skipped.
  InsertStats insert;                                    ///< Zero when skipped.
};

/// Thread safety: none (one owner, the mapping task). Allocation: the two point clouds grow to
/// the largest frame once; see OctomapMap for the tree's own allocation.
class FrameInserter {
 public:
  /// Validates params.
  static rt::Expected<FrameInserter> create(const DepthPointsParams& params = {});

  /// Inserts frame into map if poses has T_WB at frame.stamp_ns; otherwise skips it (map
  /// unchanged, counted) and reports why. Error (map unchanged, counted as invalid): a malformed
  /// frame (see depthToPoints) or a camera origin outside the map's extent. Returns inside `excluded` clear
  /// space and mark nothing (depthToPoints).
  rt::Expected<FrameInsertReport> insert(const hal::DepthFrame& frame, const PoseHistory& poses, OctomapMap& map,
                                         std::span<const ExcludedBody> excluded = {});

  std::uint64_t framesInserted() const { return frames_inserted_; }
  std::uint64_t framesSkippedNoPose() const { return frames_skipped_no_pose_; }
  std::uint64_t framesInvalid() const { return frames_invalid_; }
  const DepthPointsParams& params() const { return params_; }

 private:
  explicit FrameInserter(const DepthPointsParams& params) : params_(params) {}

  DepthPointsParams params_;
  octomap::Pointcloud hits_W_;
  octomap::Pointcloud misses_W_;
  std::uint64_t frames_inserted_ = 0;
  std::uint64_t frames_skipped_no_pose_ = 0;
  std::uint64_t frames_invalid_ = 0;
};

}  // namespace aerotrack::mapping
