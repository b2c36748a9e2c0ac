// `aerotrack import-video VIDEO --out DIR --hfov-deg DEG [--fps N] [--start-s S] [--max-frames N]
// [--format jpg|png]` (issue 10 item 4): a video with people becomes a recording with one gimbal-camera
// stream and a stated camera model (hal/replay/video_import.hpp), for `aerotrack replay DIR --config
// FILE`.
#include <cstdio>

#include "aerotrack/hal/replay/video_import.hpp"
#include "commands.hpp"

namespace aerotrack::app {
int importVideoCommand(const ParsedArgs& args) {
  hal::replay::VideoImportOptions options;
  options.video = *args.positional;
  options.dir = args.values.at("out");
  const auto hfov = parseDouble("hfov-deg", args.values.at("hfov-deg"), 1.0, 179.0);
  if (!hfov) return failCommand("import-video", hfov.error().message);
  options.hfov_deg = *hfov;
  if (args.has("fps")) {
    const auto fps = parseDouble("fps", args.values.at("fps"), 0.1, 1000.0);
    if (!fps) return failCommand("import-video", fps.error().message);
    options.fps = *fps;
  }
  if (args.has("start-s")) {
    const auto start = parseDouble("start-s", args.values.at("start-s"), 0.0, 1e6);
    if (!start) return failCommand("import-video", start.error().message);
    options.start_s = *start;
  }
  if (args.has("max-frames")) {
    const auto n = parseInt("max-frames", args.values.at("max-frames"), 1, INT64_MAX);
    if (!n) return failCommand("import-video", n.error().message);
    options.max_frames = static_cast<std::uint64_t>(*n);
  }
  options.image_format = args.valueOr("format", "jpg");
  if (options.image_format != "jpg" && options.image_format != "png")
    return failCommand("import-video", "--format: expected jpg or png, got '" + options.image_format + "'");
  const auto report = hal::replay::importVideo(options);
  if (!report) return failCommand("import-video", report.error().message);
  const hal::CameraIntrinsics& k = report->intrinsics;
  std::printf(
      "imported %s into %s: %llu frames at %.3g fps, %d x %d px, fx = fy = %.1f px (%.0f deg across)%s\n",
      options.video.c_str(), options.dir.c_str(), static_cast<unsigned long long>(report->frames), report->fps,
      k.width_px, k.height_px, k.fx_px, options.hfov_deg,
      report->unreadable > 0 ? (", " + std::to_string(report->unreadable) + " unusable frames skipped").c_str() : "");
  return 0;
}

}  // namespace aerotrack::app
