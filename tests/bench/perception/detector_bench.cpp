// Detector speed (issue 5): per frame, letterbox + inference + decoding on one thread, for each
// MoveNet model, on real photos (opencv-doc's messi5.jpg, 548 x 342, and a 768 x 576 frame of
// vtest.avi), beside OpenCV's HOG people detector (its default SVM) on the same images in the same
// run, so that the two compare as a ratio on this machine. Also the decoders alone and the
// tracking step (crop + lightning) on the video. Needs models/ (scripts/setup.sh) and opencv-doc.
#include <benchmark/benchmark.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/objdetect.hpp>
#include <opencv2/videoio.hpp>

#include "aerotrack/perception/detector.hpp"

namespace {

using namespace aerotrack;

const std::string kData = "/usr/share/doc/opencv-doc/examples/data/";

cv::Mat image(const std::string& which) {
  if (which == "messi5") return cv::imread(kData + "messi5.jpg");
  cv::VideoCapture video(kData + "vtest.avi");
  cv::Mat frame;
  for (int i = 0; i <= 200; ++i) video.read(frame);
  return frame;
}

std::optional<perception::Detector> makeDetector(benchmark::State& state) {
  cv::setNumThreads(1);  // the target is per core
  perception::DetectorParams params;
  params.model_dir = AEROTRACK_SOURCE_DIR "/models";
  auto detector = perception::Detector::create(params);
  if (!detector) {
    state.SkipWithError(detector.error().message.c_str());
    return std::nullopt;
  }
  return std::move(detector.value());
}

void BM_MoveNet(benchmark::State& state, const std::string& model, const std::string& which) {
  auto detector = makeDetector(state);
  const cv::Mat frame = image(which);
  if (!detector || frame.empty()) {
    if (frame.empty()) state.SkipWithError("opencv-doc image missing");
    return;
  }
  std::size_t persons = 0;
  for (auto _ : state) {
    auto out = detector->detectFrame(frame, model);
    if (!out) {
      state.SkipWithError(out.error().message.c_str());
      return;
    }
    persons = out->count;
  }
  state.counters["persons"] = static_cast<double>(persons);
}

void BM_Hog(benchmark::State& state, const std::string& which) {
  cv::setNumThreads(1);
  const cv::Mat frame = image(which);
  cv::HOGDescriptor hog;
  hog.setSVMDetector(cv::HOGDescriptor::getDefaultPeopleDetector());
  std::vector<cv::Rect> found;
  for (auto _ : state) {
    hog.detectMultiScale(frame, found);
    benchmark::DoNotOptimize(found.data());
  }
  state.counters["persons"] = static_cast<double>(found.size());
}

void BM_TrackingStep(benchmark::State& state) {
  auto detector = makeDetector(state);
  if (!detector) return;
  cv::VideoCapture video(kData + "vtest.avi");
  std::vector<cv::Mat> frames(40);
  for (cv::Mat& f : frames) video.read(f);
  std::size_t i = 0, cropped = 0, steps = 0;
  for (auto _ : state) {
    auto out = detector->track(frames[i % frames.size()], rt::secondsToNs(static_cast<double>(i) / 10.0));
    ++i;
    ++steps;
    cropped += out && out->cropped ? 1 : 0;
  }
  state.counters["cropped_share"] = static_cast<double>(cropped) / static_cast<double>(steps);
}

void BM_DecodeOnly(benchmark::State& state, const std::string& model) {
  auto detector = makeDetector(state);
  if (!detector) return;
  auto m = detector->model(model);
  const cv::Mat frame = image("vtest");
  if (!m || !detector->detectFrame(frame, model)) {
    state.SkipWithError("model");
    return;
  }
  const perception::MoveNetModel& net = **m;
  for (auto _ : state) {
    if (net.info().kind == perception::ModelKind::kSinglePose)
      benchmark::DoNotOptimize(perception::decodeSinglePose(net.singlePoseHeads(), net.info().constants));
    else
      benchmark::DoNotOptimize(perception::decodeMultiPose(net.multiPoseHeads(), net.info().constants));
  }
}

BENCHMARK_CAPTURE(BM_MoveNet, lightning_messi5, "lightning", "messi5")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_MoveNet, thunder_messi5, "thunder", "messi5")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_MoveNet, multipose_messi5, "multipose", "messi5")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Hog, messi5, "messi5")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_MoveNet, lightning_vtest, "lightning", "vtest")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_MoveNet, thunder_vtest, "thunder", "vtest")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_MoveNet, multipose_vtest, "multipose", "vtest")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Hog, vtest, "vtest")->Unit(benchmark::kMillisecond);
BENCHMARK(BM_TrackingStep)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_DecodeOnly, lightning, "lightning")->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_DecodeOnly, multipose, "multipose")->Unit(benchmark::kMicrosecond);

}  // namespace
