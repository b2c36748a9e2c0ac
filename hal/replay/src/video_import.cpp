// Video import: see video_import.hpp.
#include "aerotrack/hal/replay/video_import.hpp"

#include <cmath>
#include <filesystem>
#include <numbers>
#include <system_error>

#include <opencv2/videoio.hpp>

#include "aerotrack/hal/replay/frame_files.hpp"
#include "aerotrack/hal/replay/manifest.hpp"
#include "aerotrack/hal/replay/stream_codecs.hpp"

namespace aerotrack::hal::replay {

CameraIntrinsics pinholeFromFieldOfView(int width_px, int height_px, double hfov_deg) {
  CameraIntrinsics k;
  k.width_px = width_px;
  k.height_px = height_px;
  k.cx_px = 0.5 * width_px;
  k.cy_px = 0.5 * height_px;
  k.fx_px = k.cx_px / std::tan(0.5 * hfov_deg * std::numbers::pi / 180.0);
  k.fy_px = k.fx_px;  // square pixels
  return k;
}

rt::Expected<VideoImportReport> importVideo(const VideoImportOptions& options) {
  namespace fs = std::filesystem;
  if (!(options.hfov_deg > 0.0 && options.hfov_deg < 180.0))
    return rt::Error{"import: the horizontal field of view must be in (0, 180) degrees"};
  if (!(options.fps >= 0.0 && options.fps <= 10000.0)) return rt::Error{"import: fps must be in [0, 10000]"};
  if (!(options.start_s >= 0.0)) return rt::Error{"import: start_s must be >= 0"};
  if (options.image_format != "jpg" && options.image_format != "png")
    return rt::Error{"import: the image format must be jpg or png"};
  std::error_code ec;
  if (!fs::is_regular_file(options.video, ec)) return rt::Error{options.video + ": no such file"};
  cv::VideoCapture capture;
  try {
    // FFmpeg only: CAP_ANY would go on to probe camera backends (OpenNI2 through libusb) on a file
    // FFmpeg cannot read, which leaks (LeakSanitizer) and is slow.
    capture.open(options.video, cv::CAP_FFMPEG);
  } catch (const cv::Exception&) {
  }
  if (!capture.isOpened()) return rt::Error{options.video + ": cannot open the video"};
  VideoImportReport report;
  report.fps = options.fps > 0.0 ? options.fps : capture.get(cv::CAP_PROP_FPS);
  if (!(report.fps > 0.0 && report.fps <= 10000.0))
    return rt::Error{options.video + ": the video states no frame rate; give one"};

  const fs::path manifest_path = fs::path(options.dir) / "manifest.yaml";
  if (fs::exists(manifest_path, ec))
    return rt::Error{"import: " + options.dir + " already holds a recording (manifest.yaml); choose a new folder"};
  const fs::path frames_dir = fs::path(options.dir) / "gimbal_camera";
  fs::create_directories(frames_dir, ec);
  if (ec) return rt::Error{"import: " + frames_dir.string() + ": cannot create: " + ec.message()};
  auto index = CsvStreamWriter::create((frames_dir / "frames.csv").string(), DeliveredFrameIndexCodec::columns());
  if (!index) return rt::Error{"import: " + index.error().message};

  const auto skip = static_cast<std::uint64_t>(std::llround(options.start_s * report.fps));
  cv::Mat bgr;
  std::uint64_t position = 0;  // frames of the video read so far
  for (;; ++position) {
    if (options.max_frames > 0 && report.frames >= options.max_frames) break;
    bool ok = false;
    try {
      ok = capture.read(bgr);
    } catch (const cv::Exception&) {
      ok = false;
    }
    if (!ok) break;  // the end, or a frame the decoder cannot read: what came before is kept
    if (position < skip) continue;
    if (bgr.empty() || bgr.type() != CV_8UC3) {
      ++report.unreadable;
      continue;
    }
    if (report.frames == 0) report.intrinsics = pinholeFromFieldOfView(bgr.cols, bgr.rows, options.hfov_deg);
    if (bgr.cols != report.intrinsics.width_px || bgr.rows != report.intrinsics.height_px) {
      ++report.unreadable;
      continue;
    }
    const std::uint64_t number = report.frames + 1;
    const auto stamp_ns = static_cast<rt::TimeNs>(
        std::llround(static_cast<double>(position - skip) / report.fps * static_cast<double>(rt::kNsPerSecond)));
    if (rt::Status s = writeImage((frames_dir / frameFileName(number, options.image_format)).string(), bgr); !s)
      return rt::Error{"import: " + s.error().message};
    if (rt::Status s = index->write(stamp_ns, DeliveredFrameIndexCodec::encode({{position, number, stamp_ns}, 0})); !s)
      return rt::Error{"import: " + s.error().message};
    ++report.frames;
  }
  if (rt::Status s = index->close(); !s) return rt::Error{"import: " + s.error().message};
  if (report.frames == 0) {
    fs::remove_all(frames_dir, ec);
    return rt::Error{options.video + ": the video has no readable frame" +
                     (skip > 0 ? std::string(" after ") + std::to_string(options.start_s) + " s" : std::string())};
  }
  DatasetManifest manifest;
  manifest.software_version =
      options.software_version + " (import of " + fs::path(options.video).filename().string() + ")";
  manifest.start_ns = 0;
  manifest.source = "import";
  manifest.streams.push_back({"gimbal_camera", "gimbal_camera/frames.csv"});
  RecordedCamera camera;
  camera.intrinsics = report.intrinsics;
  camera.image_format = options.image_format;
  manifest.gimbal_camera = camera;
  // Last: a folder without a manifest is not a recording, so an import cut short is not mistaken for one.
  if (rt::Status s = writeManifest(manifest, manifest_path.string()); !s)
    return rt::Error{"import: " + s.error().message};
  return report;
}

}  // namespace aerotrack::hal::replay
