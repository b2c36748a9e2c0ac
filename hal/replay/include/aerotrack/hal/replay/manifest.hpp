// A recorded dataset's manifest (issue 10; hal/replay/README.md): `manifest.yaml` in the recording's
// folder says which format version wrote it, which software, when the recording started, and which
// device streams it holds (with each camera's intrinsics and mount), so a replay needs nothing else.
// Reading is strict (rt::ConfigNode): an unknown key, a missing one, a wrong type, or a format
// version this build cannot read is an error naming the file, the line and the key.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "aerotrack/hal/types.hpp"
#include "aerotrack/rt/expected.hpp"
#include "aerotrack/rt/time.hpp"

namespace aerotrack::hal::replay {

/// The format version this build writes and the only one it reads.
inline constexpr int kDatasetFormatVersion = 2;  // 2: appearance signatures of 80 bins (torso and legs; issue 22)

/// A camera as recorded: its image size and intrinsics, and where it sits on the drone.
struct RecordedCamera {
  CameraIntrinsics intrinsics;
  Eigen::Vector3d mount_B_m = Eigen::Vector3d::Zero();  ///< Camera (gimbal axis for the gimbal camera) in B.
  /// Rotates camera-frame vectors into B (the depth camera's T_BC rotation; identity for the gimbal
  /// camera, whose pose follows the gimbal). YAML: `rotation_B_C`, 9 numbers row by row (optional).
  Eigen::Matrix3d R_BC = Eigen::Matrix3d::Identity();
  std::string image_format = "png";  ///< The frame files: "png" or "jpg" (gimbal camera only).
};

/// One device stream: the device ("odometry", "gimbal", "gimbal_commands", "setpoints",
/// "gimbal_camera" (images), "detections" (a keypoint-mode camera's output), "depth_camera", "can") and its file,
/// relative to the manifest's folder.
struct StreamEntry {
  std::string device;
  std::string file;
};

struct DatasetManifest {
  int format_version = kDatasetFormatVersion;
  std::string software_version;  ///< What wrote it (the aerotrack version, git describe).
  rt::TimeNs start_ns = 0;       ///< The recording's first instant, on its one clock.
  /// The recorded run's last instant (YAML `end_ns`, optional): written when the recording is closed,
  /// so a replay runs exactly as long; absent after a kill -9 or in an import.
  std::optional<rt::TimeNs> end_ns;
  std::string source;  ///< The backend recorded: "sim", "real", "import" (a video turned into a stream).
  std::vector<StreamEntry> streams;
  std::optional<RecordedCamera> gimbal_camera;
  std::optional<RecordedCamera> depth_camera;

  /// The entry of `device`, if recorded.
  const StreamEntry* stream(const std::string& device) const;
};

/// Reads `path` (…/manifest.yaml). Errors name the file, line and key.
rt::Expected<DatasetManifest> readManifest(const std::string& path);
/// Writes `manifest` to `path` as YAML, replacing it atomically (path.part, then rename).
rt::Status writeManifest(const DatasetManifest& manifest, const std::string& path);

}  // namespace aerotrack::hal::replay
