// The replay backend's cameras (hal/replay/replay_devices.hpp) on small hand-made recordings: depth
// frames served newest-first at the instant they were delivered, with the manifest's intrinsics and
// mount; a keypoint-mode camera's detections served as a queue, each once, restamped; images from PNG
// or JPEG files. A missing frame file stops a strict start naming the index and the file, or is
// skipped and counted; a frame that cannot be decoded when its turn comes is skipped and reported in
// the device's health.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "aerotrack/hal/replay/frame_files.hpp"
#include "aerotrack/hal/replay/replay_devices.hpp"
#include "support/temp_dir.hpp"

namespace aerotrack::hal::replay {
namespace {

constexpr rt::TimeNs kStart = 2'000'000'000;
constexpr rt::TimeNs kMs = 1'000'000;

CameraIntrinsics smallCamera() {
  CameraIntrinsics k;
  k.width_px = 8;
  k.height_px = 6;
  k.fx_px = k.fy_px = 4.0;
  k.cx_px = 4.0;
  k.cy_px = 3.0;
  return k;
}

/// A recording with depth frames 1..5 (stamped every 33 ms, delivered 5 ms later; frame i holds depth
/// i metres), detections at the same stamps (delivered 40 ms later) and PNG images every 100 ms.
class CameraRecording {
 public:
  CameraRecording() {
    DatasetManifest m;
    m.software_version = "test";
    m.start_ns = kStart;
    m.source = "sim";
    m.streams = {{"depth_camera", "depth_camera/frames.csv"},
                 {"detections", "gimbal_camera/detections.csv"},
                 {"gimbal_camera", "gimbal_camera/frames.csv"}};
    RecordedCamera depth;
    depth.intrinsics = smallCamera();
    depth.mount_B_m = {0.1, 0.0, 0.05};
    depth.R_BC << 0, 0, 1, -1, 0, 0, 0, -1, 0;  // optical axes in FLU
    m.depth_camera = depth;
    RecordedCamera gimbal;
    gimbal.intrinsics = smallCamera();
    m.gimbal_camera = gimbal;
    std::filesystem::create_directories(dir_.file("depth_camera"));
    std::filesystem::create_directories(dir_.file("gimbal_camera"));
    EXPECT_TRUE(writeManifest(m, dir_.file("manifest.yaml")));
    auto depth_index =
        CsvStreamWriter::create(dir_.file("depth_camera/frames.csv"), DeliveredFrameIndexCodec::columns());
    auto detections =
        CsvStreamWriter::create(dir_.file("gimbal_camera/detections.csv"), DeliveredDetectionCodec::columns());
    auto images = CsvStreamWriter::create(dir_.file("gimbal_camera/frames.csv"), DeliveredFrameIndexCodec::columns());
    EXPECT_TRUE(depth_index && detections && images);
    for (std::uint64_t i = 1; i <= 5; ++i) {
      const rt::TimeNs stamp_ns = kStart + static_cast<rt::TimeNs>(i) * 33 * kMs;
      EXPECT_TRUE(writeDepthPng(dir_.file("depth_camera/" + frameFileName(i, "png")),
                                cv::Mat(6, 8, CV_32FC1, cv::Scalar(static_cast<double>(i)))));
      EXPECT_TRUE(depth_index->write(stamp_ns, DeliveredFrameIndexCodec::encode({{i, i, stamp_ns}, 5 * kMs})));
      DetectionFrame f;
      f.stamp_ns = stamp_ns;
      f.result_ns = stamp_ns + 35 * kMs;
      f.sequence = i;
      f.person_count = 1;
      f.target_index = 0;
      f.persons[0].score = 0.1 * static_cast<double>(i);
      EXPECT_TRUE(detections->write(stamp_ns, DeliveredDetectionCodec::encode({f, 40 * kMs})));
    }
    for (std::uint64_t i = 1; i <= 3; ++i) {
      const rt::TimeNs stamp_ns = kStart + static_cast<rt::TimeNs>(i) * 100 * kMs;
      EXPECT_TRUE(writeImage(dir_.file("gimbal_camera/" + frameFileName(i, "png")),
                             cv::Mat(6, 8, CV_8UC3, cv::Scalar(10.0 * static_cast<double>(i), 0, 0))));
      EXPECT_TRUE(images->write(stamp_ns, DeliveredFrameIndexCodec::encode({{100 + i, i, stamp_ns}, 0})));
    }
  }
  std::string dir() const { return dir_.path(); }
  std::string file(const std::string& name) const { return dir_.file(name); }

 private:
  test::TempDir dir_;
};

std::shared_ptr<ReplayDataset> open(const CameraRecording& rec, BadRowPolicy policy = BadRowPolicy::kStrict) {
  ReplayOptions options;
  options.dir = rec.dir();
  options.bad_rows = policy;
  auto dataset = ReplayDataset::open(options, kStart);  // replayed on the recording's own clock
  EXPECT_TRUE(dataset) << (dataset ? "" : dataset.error().message);
  return dataset ? *dataset : nullptr;
}

TEST(ReplayCameras, DepthFramesComeWhenTheyWereDeliveredWithTheManifestsCamera) {
  const CameraRecording rec;
  const auto dataset = open(rec);
  ASSERT_NE(dataset, nullptr);
  ReplayDepthCamera depth(dataset);
  EXPECT_FALSE(depth.grab(kStart + 37 * kMs));  // frame 1 was taken at 33 ms, delivered at 38 ms
  const DepthFrameHandle first = depth.grab(kStart + 38 * kMs);
  ASSERT_TRUE(first);
  EXPECT_EQ(first->stamp_ns, kStart + 33 * kMs);
  EXPECT_EQ(first->sequence, 1U);
  EXPECT_EQ(first->depth_m.at<float>(2, 3), 1.0F);
  EXPECT_EQ(first->intrinsics.width_px, 8);
  EXPECT_EQ(first->T_BC.translation(), Eigen::Vector3d(0.1, 0.0, 0.05));
  EXPECT_EQ(first->T_BC.linear()(1, 0), -1.0);
  EXPECT_FALSE(depth.grab(kStart + 50 * kMs));                     // nothing new
  const DepthFrameHandle newest = depth.grab(kStart + 120 * kMs);  // frames 2 and 3 delivered: the newest
  ASSERT_TRUE(newest);
  EXPECT_EQ(newest->sequence, 3U);
  EXPECT_EQ(depth.health(kStart + 120 * kMs).state, DeviceHealth::State::kOk);
}

TEST(ReplayCameras, DetectionsAreAQueueEachFrameOnceInOrder) {
  const CameraRecording rec;
  const auto dataset = open(rec);
  ASSERT_NE(dataset, nullptr);
  ReplayGimbalCamera camera(dataset);
  EXPECT_FALSE(camera.grabDetections(kStart + 72 * kMs));  // 33 + 40 ms
  std::vector<DetectionFrame> got;
  while (auto f = camera.grabDetections(kStart + 140 * kMs))
    got.push_back(*f);  // frames 1 (73 ms), 2 (106 ms), 3 (139 ms)
  ASSERT_EQ(got.size(), 3U);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(got[i].sequence, i + 1);
    EXPECT_EQ(got[i].result_ns - got[i].stamp_ns, 35 * kMs);
    EXPECT_DOUBLE_EQ(got[i].persons[0].score, 0.1 * static_cast<double>(i + 1));
  }
  EXPECT_FALSE(camera.grabDetections(kStart + 140 * kMs));
}

TEST(ReplayCameras, ReplayedLaterTheStampsMoveWithTheClockAndTheOffsetSkipsEarlierDetections) {
  const CameraRecording rec;
  ReplayOptions options;
  options.dir = rec.dir();
  options.offset_s = 0.1;  // from 100 ms: frames 1 and 2 (delivered 73 and 106 ms)... frame 2 is after it
  auto dataset = ReplayDataset::open(options, 0);
  ASSERT_TRUE(dataset);
  ReplayGimbalCamera camera(*dataset);
  const auto first = camera.grabDetections(10 * kMs);  // recording time 110 ms: frame 2 (delivered 106 ms)
  ASSERT_TRUE(first);
  EXPECT_EQ(first->sequence, 2U);
  EXPECT_EQ(first->stamp_ns, 66 * kMs - 100 * kMs);  // stamped before the replay started, as recorded
  EXPECT_EQ(first->result_ns, first->stamp_ns + 35 * kMs);
}

TEST(ReplayCameras, ImagesAreReadWhenServed) {
  const CameraRecording rec;
  const auto dataset = open(rec);
  ASSERT_NE(dataset, nullptr);
  ReplayGimbalCamera camera(dataset);
  const ImageFrameHandle image = camera.grab(kStart + 250 * kMs);  // images 1 and 2 delivered: the newest
  ASSERT_TRUE(image);
  EXPECT_EQ(image->sequence, 102U);
  EXPECT_EQ(image->bgr.at<cv::Vec3b>(0, 0)[0], 20);
  EXPECT_EQ(image->intrinsics.fx_px, 4.0);
  EXPECT_FALSE(camera.grab(kStart + 260 * kMs));
}

TEST(ReplayCameras, AMissingFrameStopsAStrictStartOrIsSkippedAndAnUnreadableOneIsReportedWhenServed) {
  const CameraRecording rec;
  std::filesystem::remove(rec.file("depth_camera/000002.png"));
  ReplayOptions options;
  options.dir = rec.dir();
  options.bad_rows = BadRowPolicy::kStrict;
  auto strict = ReplayDataset::open(options, kStart);
  ASSERT_FALSE(strict);
  EXPECT_NE(strict.error().message.find("depth_camera/frames.csv: frame 2: "), std::string::npos)
      << strict.error().message;
  EXPECT_NE(strict.error().message.find("000002.png is missing"), std::string::npos);

  std::filesystem::resize_file(rec.file("depth_camera/000003.png"), 40);  // cut short
  const auto dataset = open(rec, BadRowPolicy::kSkip);
  ASSERT_NE(dataset, nullptr);
  const auto* frames = dataset->depthFrames();
  EXPECT_EQ(frames != nullptr ? frames->samples.size() : 0U, 4U);
  ReplayDepthCamera depth(dataset);
  EXPECT_EQ(depth.grab(kStart + 38 * kMs)->sequence, 1U);
  EXPECT_FALSE(depth.grab(kStart + 104 * kMs));  // frame 3 (frame 2 is gone) cannot be decoded
  const DeviceHealth h = depth.health(kStart + 104 * kMs);
  EXPECT_EQ(h.state, DeviceHealth::State::kDegraded);
  EXPECT_NE(h.detail.find("000003.png"), std::string::npos) << h.detail;
  EXPECT_EQ(depth.grab(kStart + 140 * kMs)->sequence, 4U);  // and the stream goes on
}

TEST(ReplayCameras, ARecordedCanLogIsCheckedWhenTheDatasetOpens) {
  const CameraRecording rec;
  auto manifest = readManifest(rec.file("manifest.yaml"));
  ASSERT_TRUE(manifest);
  manifest->streams.push_back({"can", "can.log"});
  ASSERT_TRUE(writeManifest(*manifest, rec.file("manifest.yaml")));
  std::ofstream(rec.file("can.log")) << "(2.000000) can0 141#A200000010270000\n(2.000500) can0 241#A2\n";
  const auto dataset = open(rec);
  ASSERT_NE(dataset, nullptr);
  const LoadedCanLog* log = dataset->canLog();
  EXPECT_EQ(log != nullptr ? log->frames.size() : 0U, 2U);
  std::ofstream(rec.file("can.log"), std::ios::app) << "(2.001000) can0 141#XYZ\n";
  ReplayOptions options;
  options.dir = rec.dir();
  options.bad_rows = BadRowPolicy::kStrict;
  const auto strict = ReplayDataset::open(options, kStart);
  ASSERT_FALSE(strict);
  EXPECT_NE(strict.error().message.find("can.log:3: "), std::string::npos) << strict.error().message;
}

}  // namespace
}  // namespace aerotrack::hal::replay
