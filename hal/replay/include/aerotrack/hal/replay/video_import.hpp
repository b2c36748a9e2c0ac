// Real footage as a recording (issue 10 item 4): a video file with people in it (e.g. vtest.avi from
// Debian's opencv-doc) becomes a dataset holding one gimbal-camera stream (hal/replay/README.md), so
// that the detector, the target's localization and the rest of the binary run on real images through
// the replay backend (`aerotrack replay DIR --config FILE`).
//
// The camera model is stated, not guessed: a pinhole with square pixels, the principal point at the
// image centre, no distortion, and the horizontal field of view given by the caller (a video does not
// say which lens took it). Frames are stamped at their index / fps on the dataset's clock, starting
// at start_ns, with no delivery delay; each is written (JPEG or PNG) before its index row, as the
// recorder does.
#pragma once

#include <cstdint>
#include <string>

#include "aerotrack/hal/types.hpp"
#include "aerotrack/rt/expected.hpp"

namespace aerotrack::hal::replay {

struct VideoImportOptions {
  std::string video;                 ///< Any file OpenCV's videoio reads.
  std::string dir;                   ///< The dataset's folder; must not hold a manifest.yaml already.
  double hfov_deg = 0.0;             ///< The camera's horizontal field of view, (0, 180).
  double fps = 0.0;                  ///< Frame rate for the stamps; 0: the video's own.
  double start_s = 0.0;              ///< Skip the video's first seconds.
  std::uint64_t max_frames = 0;      ///< 0: to the end of the video.
  std::string image_format = "jpg";  ///< "jpg" or "png".
  std::string software_version = "aerotrack";
};

struct VideoImportReport {
  std::uint64_t frames = 0;      ///< Written.
  std::uint64_t unreadable = 0;  ///< Frames not 8-bit BGR or of another size than the first, skipped.
  double fps = 0.0;
  CameraIntrinsics intrinsics;
};

/// The stated camera for a width x height image with the given horizontal field of view.
CameraIntrinsics pinholeFromFieldOfView(int width_px, int height_px, double hfov_deg);

/// Writes the dataset. Errors are one line naming the file: the video cannot be opened or has no
/// readable frame, no frame rate is known, the folder already holds a recording or cannot be written.
rt::Expected<VideoImportReport> importVideo(const VideoImportOptions& options);

}  // namespace aerotrack::hal::replay
