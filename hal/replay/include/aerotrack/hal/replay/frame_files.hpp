// The image files of a recorded dataset's camera streams (issue 10; hal/replay/README.md): depth
// frames as 16-bit single-channel PNGs in millimetres, 0 meaning no return (the usual convention of
// depth cameras and their tools), and gimbal-camera images as 8-bit PNG or JPEG. Each file is named
// after its number in the stream's index (frames.csv: FrameIndexCodec). Pure functions over files.
//
// Writing goes to `<file>.part` and is renamed into place only when complete, and the recorder writes
// the index row after that: a recording cut at any moment lists only frames that are whole on disk.
#pragma once

#include <cstdint>
#include <string>

#include <opencv2/core.hpp>

#include "aerotrack/rt/expected.hpp"

namespace aerotrack::hal::replay {

/// A frame's file name inside its stream's folder: the file number, 6 digits at least, and the
/// extension ("png" or "jpg").
std::string frameFileName(std::uint64_t file_index, const std::string& extension);

/// depth_m (CV_32FC1, metres) to Z16 millimetres (hal/depth_units.hpp): rounded; 0, negative, NaN,
/// inf and depths beyond kMaxZ16DepthM become 0 (no return). Error for another image type.
rt::Expected<cv::Mat> depthToMillimetres(const cv::Mat& depth_m);

/// Writes depth_m as a 16-bit PNG at path (atomically: path.part, then rename). Error naming the
/// file if it cannot be written.
rt::Status writeDepthPng(const std::string& path, const cv::Mat& depth_m);

/// Reads a depth PNG back as CV_32FC1 metres (0: no return). Error naming the file: missing,
/// not decodable (not a PNG, truncated), or not 16-bit single-channel.
rt::Expected<cv::Mat> readDepthPng(const std::string& path);

/// Writes an 8-bit BGR image as PNG or JPEG (by path's extension; JPEG at quality 95), atomically.
rt::Status writeImage(const std::string& path, const cv::Mat& bgr);

/// Reads an 8-bit image as BGR. Error naming the file: missing, not decodable (corrupt, truncated).
rt::Expected<cv::Mat> readImage(const std::string& path);

}  // namespace aerotrack::hal::replay
