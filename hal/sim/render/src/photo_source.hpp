// Reading the photos people are cut out of: a still image, or frames of a video (read in order from
// its start, so that the frames are the same whatever the container's seeking does). Private to
// hal/sim/render.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "aerotrack/rt/expected.hpp"

namespace aerotrack::hal::sim {

/// Largest photo or video file read, bytes, and largest decoded side, pixels: a person's photo needs
/// neither more, and a bigger file is a mistake (or /dev/zero), not a person.
inline constexpr long long kMaxPhotoFileBytes = 512LL << 20;
inline constexpr int kMaxPhotoSidePx = 8192;
/// Frames read from a video at most (its first 20000: 11 min at 30 fps).
inline constexpr int kMaxVideoFrame = 20000;

/// frame -1: path is a still image; frame >= 0: that frame of the video at path. BGR, CV_8UC3.
/// Errors name the file (missing, a directory or special file, too large, undecodable, a frame past
/// the video's end).
rt::Expected<cv::Mat> readPhoto(const std::string& path, int frame);

/// Several frames of one video, read in one pass; frames must be >= 0 and sorted ascending.
rt::Expected<std::vector<cv::Mat>> readVideoFrames(const std::string& path, const std::vector<int>& frames);

}  // namespace aerotrack::hal::sim
