// Depth frames in a recorded dataset (issue 10; hal/replay/README.md): each frame a 16-bit
// single-channel PNG in millimetres, 0 meaning no return (the usual convention of depth cameras and
// their tools), named after its sequence number, and listed in the stream's index
// (depth_camera/frames.csv: stamp_ns, sequence). Pure functions over files; no threads.
//
// Writing goes to `<file>.part` and is renamed into place only when complete, and the index row is
// written after that: a recording cut at any moment lists only frames that are whole on disk.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "aerotrack/hal/replay/csv_stream.hpp"
#include "aerotrack/hal/types.hpp"
#include "aerotrack/rt/expected.hpp"

namespace aerotrack::hal::replay {

/// The largest depth a 16-bit millimetre PNG holds.
inline constexpr double kMaxPngDepthM = 65.535;

/// The frame's file name inside the stream's folder: the sequence number, 6 digits at least.
std::string depthFrameFileName(std::uint64_t sequence);

/// depth_m (CV_32FC1, metres) to millimetres, rounded; 0, negative, NaN, inf and depths beyond
/// kMaxPngDepthM become 0 (no return). Error for another image type.
rt::Expected<cv::Mat> depthToMillimetres(const cv::Mat& depth_m);

/// Writes depth_m as a 16-bit PNG at path (atomically: path.part, then rename). Error naming the
/// file if it cannot be written.
rt::Status writeDepthPng(const std::string& path, const cv::Mat& depth_m);

/// Reads a depth PNG back as CV_32FC1 metres (0: no return). Error naming the file: missing,
/// not decodable (not a PNG, truncated), or not 16-bit single-channel.
rt::Expected<cv::Mat> readDepthPng(const std::string& path);

/// depth_camera/frames.csv: the frame's sequence number after stamp_ns.
struct DepthIndexCodec {
  static const std::vector<std::string>& columns();
};

/// A depth stream read whole: the frames (with the manifest's intrinsics and mount) in time order.
struct LoadedDepthStream {
  std::vector<DepthFrame> frames;
  std::string path;                ///< The index file.
  std::uint64_t skipped_rows = 0;  ///< Bad index rows and frames whose file is missing or corrupt.
  std::string first_skip_message;
  bool truncated_tail = false;
};

/// Reads the index at index_path and every frame it lists from the index's folder. Strict: the
/// first bad row or unreadable frame is an error ("file:line: ..." or the image's path). Skip: they
/// are dropped and counted. Frames whose size differs from the intrinsics are bad too.
rt::Expected<LoadedDepthStream> loadDepthStream(const std::string& index_path, const CameraIntrinsics& intrinsics,
                                                const Eigen::Isometry3d& T_BC, BadRowPolicy policy);

}  // namespace aerotrack::hal::replay
