// `aerotrack detect IMAGE|VIDEO [--model lightning|thunder|multipose] [--json] [--draw OUT.png]`:
// the gimbal camera's person detector (modules/perception) on a file. An image runs the chosen
// model once on the whole letterboxed frame; a video runs the tracking loop frame by frame (a
// singlepose model on the crop around the followed person, the same model on the whole frame to
// find them again; multipose: every person in every frame, the followed one marked). --json prints
// one JSON object per image or video frame; --draw writes the skeletons over the image (over the
// last frame of a video). Models come from models/ (scripts/setup.sh provisions them).
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "aerotrack/hal/image_decode.hpp"
#include "aerotrack/perception/detector.hpp"
#include "aerotrack/rt/clock.hpp"
#include "commands.hpp"
#include "paths.hpp"

namespace aerotrack::app {
namespace {

std::string reasonText(const perception::TorsoFeatures& torso) {
  if (torso.reliable) return "ok";
  std::string text(perception::toString(torso.reason));
  if (torso.reason != perception::TorsoReason::kTooShort)
    text += ":" + std::string(perception::keypointName(torso.culprit));
  return text;
}

nlohmann::json toJson(const perception::DetectorOutput& out, const cv::Mat& image, double latency_ms) {
  nlohmann::json persons = nlohmann::json::array();
  for (std::size_t i = 0; i < out.count; ++i) {
    const perception::DetectedPerson& p = out.persons[i];
    const hal::PersonDetection& d = p.detection;
    nlohmann::json keypoints = nlohmann::json::array();
    for (const hal::Keypoint2D& k : d.keypoints) keypoints.push_back({k.u_px, k.v_px, k.score});
    persons.push_back({{"score", d.score},
                       {"bbox", {d.bbox_u_px, d.bbox_v_px, d.bbox_w_px, d.bbox_h_px}},
                       {"keypoints", keypoints},
                       {"torso_px", p.torso.torso_px},
                       {"u_px", p.torso.u_px},
                       {"torso_reliable", p.torso.reliable},
                       {"reason", reasonText(p.torso)}});
  }
  nlohmann::json j = {{"width", image.cols},
                      {"height", image.rows},
                      {"latency_ms", latency_ms},
                      {"model", out.model},
                      {"persons", persons}};
  if (out.target) j["target"] = *out.target;
  return j;
}

void printText(const perception::DetectorOutput& out, double latency_ms, const std::string& prefix) {
  std::printf("%s%zu person(s), %s, %.1f ms\n", prefix.c_str(), out.count, out.model, latency_ms);
  for (std::size_t i = 0; i < out.count; ++i) {
    const perception::DetectedPerson& p = out.persons[i];
    std::printf("  person %zu%s: score %.2f, torso %.1f px at u %.1f px, %s\n", i,
                out.target && *out.target == i ? " (followed)" : "", p.detection.score, p.torso.torso_px, p.torso.u_px,
                reasonText(p.torso).c_str());
  }
}

void draw(cv::Mat& image, const perception::DetectorOutput& out) {
  constexpr double kMinScore = 0.3;
  for (std::size_t i = 0; i < out.count; ++i) {
    const perception::DetectedPerson& p = out.persons[i];
    const bool followed = out.target && *out.target == i;
    const cv::Scalar colour = followed ? cv::Scalar(0, 255, 0) : cv::Scalar(0, 200, 255);
    const auto& k = p.detection.keypoints;
    const auto pt = [&](int j) {
      return cv::Point2d(k[static_cast<std::size_t>(j)].u_px, k[static_cast<std::size_t>(j)].v_px);
    };
    for (const auto& [a, b] : hal::kCocoSkeleton)
      if (k[static_cast<std::size_t>(a)].score >= kMinScore && k[static_cast<std::size_t>(b)].score >= kMinScore)
        cv::line(image, pt(a), pt(b), colour, 2, cv::LINE_AA);
    for (int j = 0; j < static_cast<int>(k.size()); ++j)
      if (k[static_cast<std::size_t>(j)].score >= kMinScore) cv::circle(image, pt(j), 3, cv::Scalar(255, 0, 0), -1);
    const hal::PersonDetection& d = p.detection;
    cv::rectangle(image, cv::Rect2d(d.bbox_u_px, d.bbox_v_px, d.bbox_w_px, d.bbox_h_px), colour, 1);
    char label[96];
    std::snprintf(label, sizeof(label), "%.2f torso %.0fpx%s", d.score, p.torso.torso_px,
                  p.torso.reliable ? "" : " (unreliable)");
    cv::putText(image, label, cv::Point2d(d.bbox_u_px, std::max(12.0, d.bbox_v_px - 4.0)), cv::FONT_HERSHEY_SIMPLEX,
                0.45, colour, 1, cv::LINE_AA);
  }
}

bool looksLikeVideo(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  for (const char* v : {".avi", ".mp4", ".mkv", ".mov", ".webm", ".mpg", ".mpeg", ".m4v"})
    if (ext == v) return true;
  return false;
}

}  // namespace

int detectCommand(const ParsedArgs& args) {
  const std::string input = *args.positional;
  const std::string model_name = args.valueOr("model", "lightning");
  const bool json = args.flags.count("json") != 0;
  const auto draw_path = args.values.count("draw") ? std::optional(args.values.at("draw")) : std::nullopt;
  bool known = false;
  for (const std::string& n : perception::knownModelNames()) known = known || n == model_name;
  if (!known)
    return failCommand("detect", "--model: expected lightning, thunder or multipose, got '" + model_name + "'");
  if (!std::filesystem::is_regular_file(input)) return failCommand("detect", input + ": no such file");

  perception::DetectorParams params;
  params.model_dir = modelDir();
  const bool multipose = model_name == "multipose";
  params.tracking_model = multipose ? "lightning" : model_name;
  params.search_model = model_name;
  auto detector = perception::Detector::create(params);
  if (!detector) return failCommand("detect", detector.error().message);

  const rt::MonotonicClock clock;
  cv::Mat last;
  perception::DetectorOutput last_out;
  if (!looksLikeVideo(input)) {
    // Sizes, kinds of file and corrupt data are refused before anything is decoded (image_decode.hpp).
    auto decoded = hal::readImageFile(input, cv::IMREAD_COLOR);
    if (!decoded) return failCommand("detect", decoded.error().message);
    const cv::Mat image = std::move(decoded.value());
    const rt::TimeNs begin = clock.now();
    auto out = detector->detectFrame(image, model_name);
    const double latency_ms = rt::nsToMilliseconds(clock.now() - begin);
    if (!out) return failCommand("detect", input + ": " + out.error().message);
    if (json)
      std::printf("%s\n", toJson(*out, image, latency_ms).dump().c_str());
    else
      printText(*out, latency_ms, input + ": ");
    last = image;
    last_out = *out;
  } else {
    cv::VideoCapture video;
    try {
      // FFmpeg only: the other backends OpenCV would try on a bad file (GStreamer, image sequences,
      // cameras) print to stderr and leak.
      video.open(input, cv::CAP_FFMPEG);
    } catch (const cv::Exception&) {
    }
    if (!video.isOpened()) return failCommand("detect", input + ": cannot open the video");
    const double fps = video.get(cv::CAP_PROP_FPS) > 0.0 ? video.get(cv::CAP_PROP_FPS) : 30.0;
    cv::Mat frame;
    std::size_t index = 0;
    for (; video.read(frame) && !frame.empty(); ++index) {
      const rt::TimeNs stamp_ns = rt::secondsToNs(static_cast<double>(index) / fps);
      const rt::TimeNs begin = clock.now();
      auto out = multipose ? detector->detectFrame(frame, model_name) : detector->track(frame, stamp_ns);
      const double latency_ms = rt::nsToMilliseconds(clock.now() - begin);
      if (!out) return failCommand("detect", input + ": frame " + std::to_string(index) + ": " + out.error().message);
      if (json) {
        nlohmann::json j = toJson(*out, frame, latency_ms);
        j["frame"] = index;
        std::printf("%s\n", j.dump().c_str());
      } else {
        printText(*out, latency_ms, "frame " + std::to_string(index) + ": ");
      }
      last = frame;
      last_out = *out;
    }
    if (index == 0) return failCommand("detect", input + ": the video has no readable frame");
  }
  if (draw_path) {
    draw(last, last_out);
    bool written = false;
    try {
      written = cv::imwrite(*draw_path, last);
    } catch (const cv::Exception&) {
      written = false;
    }
    if (!written) return failCommand("detect", *draw_path + ": cannot write the image");
  }
  return 0;
}

}  // namespace aerotrack::app
