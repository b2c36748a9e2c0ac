// The V4L2 cameras (hal/real v4l2_device, frame_source, v4l2_gimbal_camera, v4l2_depth_camera; issue
// 11 items 1 and 2). No camera is attached where this runs, so the device logic runs over a fake
// FrameSource: newest-frame semantics, stamps, sequence gaps, corrupt frames, unplug and reconnect,
// frame timeout. The pure conversions (Z16 to metres, YUYV and MJPG to BGR, timeval to ns, FourCC)
// are checked with exact values, and the real V4L2 path is checked where it can be without a camera:
// a missing node and a node that is not a capture device are one-line errors naming them.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <linux/videodev2.h>
#include <unistd.h>

#include <deque>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <vector>

#include "aerotrack/hal/real/v4l2_depth_camera.hpp"
#include "aerotrack/hal/real/v4l2_device.hpp"
#include "aerotrack/hal/real/v4l2_gimbal_camera.hpp"
#include "support/require.hpp"

namespace aerotrack::hal::real {
namespace {

constexpr rt::TimeNs kMs = rt::kNsPerMillisecond;
constexpr rt::TimeNs kT0 = 1000 * rt::kNsPerSecond;  // any monotonic time; tests move it by hand

struct FakeFrame {
  std::vector<std::uint8_t> bytes;
  std::uint64_t sequence = 0;
  std::optional<rt::TimeNs> monotonic_ns;
};

/// A device under the test's control. The state lives in a shared struct so the test keeps a handle
/// after the camera takes the source.
struct FakeDevice {
  std::deque<FakeFrame> ready;  // filled, not yet dequeued (oldest first)
  FakeFrame current;            // what the last dequeue returned (its bytes back the RawFrame)
  bool plugged = true;
  int opens = 0;
  int closes = 0;
  bool is_open = false;
};

class FakeSource final : public FrameSource {
 public:
  explicit FakeSource(std::shared_ptr<FakeDevice> device) : device_(std::move(device)) {}
  rt::Status open() override {
    ++device_->opens;
    if (!device_->plugged) return rt::Error{name_ + ": cannot open: No such file or directory"};
    device_->is_open = true;
    return rt::ok();
  }
  rt::Expected<std::optional<RawFrame>> dequeue() override {
    if (!device_->is_open) return rt::Error{name_ + ": not open"};
    if (!device_->plugged) return rt::Error{name_ + ": unplugged (VIDIOC_DQBUF: No such device)"};
    if (device_->ready.empty()) return std::optional<RawFrame>{};
    RawFrame raw;
    raw.skipped = static_cast<std::uint32_t>(device_->ready.size() - 1);  // drained to the newest
    device_->current = device_->ready.back();
    device_->ready.clear();
    raw.data = device_->current.bytes.data();
    raw.size_bytes = device_->current.bytes.size();
    raw.sequence = device_->current.sequence;
    raw.monotonic_ns = device_->current.monotonic_ns;
    return std::optional<RawFrame>{raw};
  }
  void close() override {
    ++device_->closes;
    device_->is_open = false;
    device_->ready.clear();
  }
  const std::string& name() const override { return name_; }

 private:
  std::shared_ptr<FakeDevice> device_;
  std::string name_ = "/dev/fake0";
};

CameraIntrinsics intrinsics(int width_px, int height_px) {
  CameraIntrinsics k;
  k.width_px = width_px;
  k.height_px = height_px;
  k.fx_px = k.fy_px = 100.0;
  k.cx_px = width_px / 2.0;
  k.cy_px = height_px / 2.0;
  return k;
}

/// A YUYV image of one colour (Y, U, V for every pixel pair).
std::vector<std::uint8_t> yuyv(int width_px, int height_px, std::uint8_t y, std::uint8_t u, std::uint8_t v) {
  std::vector<std::uint8_t> out;
  for (int i = 0; i < width_px * height_px / 2; ++i) {
    out.push_back(y);
    out.push_back(u);
    out.push_back(y);
    out.push_back(v);
  }
  return out;
}

/// A JPEG whose left half is red and right half blue.
std::vector<std::uint8_t> redBlueJpeg(int width_px, int height_px) {
  cv::Mat bgr(height_px, width_px, CV_8UC3, cv::Scalar(255, 0, 0));
  bgr.colRange(0, width_px / 2).setTo(cv::Scalar(0, 0, 255));
  std::vector<std::uint8_t> jpeg;
  EXPECT_TRUE(cv::imencode(".jpg", bgr, jpeg, {cv::IMWRITE_JPEG_QUALITY, 95}));
  return jpeg;
}

void expectOneLine(const std::string& message, const std::string& names) {
  EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  EXPECT_NE(message.find(names), std::string::npos) << message;
}

// ---- pure conversions ----------------------------------------------------------------------------

TEST(V4l2Conversions, GivenFourccTextWhenConvertedThenTheKernelsCodesResult) {
  EXPECT_EQ(*fourccFromString("YUYV"), V4L2_PIX_FMT_YUYV);
  EXPECT_EQ(*fourccFromString("MJPG"), V4L2_PIX_FMT_MJPEG);
  EXPECT_EQ(*fourccFromString("Z16"), V4L2_PIX_FMT_Z16);  // padded with a space, as the kernel's
  EXPECT_EQ(fourccToString(V4L2_PIX_FMT_Z16), "Z16 ");
  EXPECT_FALSE(fourccFromString(""));
  EXPECT_FALSE(fourccFromString("MJPEG"));
}

TEST(V4l2Conversions, GivenAKernelTimevalWhenConvertedThenNanosecondsOnTheSameClock) {
  EXPECT_EQ(timevalToNs(timeval{12, 345678}), 12'345'678'000);
  EXPECT_EQ(timevalToNs(timeval{0, 1}), 1000);
  // A monotonic clock a month after boot still fits: 2.6e6 s.
  EXPECT_EQ(timevalToNs(timeval{2'600'000, 999'999}), 2'600'000'999'999'000);
}

TEST(V4l2Conversions, GivenZ16UnitsWhenConvertedThenMetresWithZeroForNoDataAndOutOfRange) {
  // 0: no data; 1000 units = 1 m; 1234 = 1.234 m; 50 = 0.05 m < min 0.1; 20000 = 20 m > max 10;
  // 65535 > max; 100 = exactly min; 10000 = exactly max.
  const std::uint16_t units[8] = {0, 1000, 1234, 50, 20000, 65535, 100, 10000};
  std::vector<std::uint8_t> bytes;
  for (const std::uint16_t u : units) {
    bytes.push_back(static_cast<std::uint8_t>(u & 0xFFU));
    bytes.push_back(static_cast<std::uint8_t>(u >> 8U));
  }
  auto depth = z16ToMetres(bytes.data(), bytes.size(), 4, 2, 0.001, 0.1, 10.0);
  ASSERT_TRUE(depth) << depth.error().message;
  ASSERT_EQ(depth->type(), CV_32FC1);
  ASSERT_EQ(depth->cols, 4);
  ASSERT_EQ(depth->rows, 2);
  const float expected[8] = {0.0F, 1.0F, 1.234F, 0.0F, 0.0F, 0.0F, 0.1F, 10.0F};
  for (int i = 0; i < 8; ++i) EXPECT_FLOAT_EQ(depth->at<float>(i / 4, i % 4), expected[i]) << i;
  // A D435 told to use 100 um units: 1234 units = 0.1234 m.
  auto fine = z16ToMetres(bytes.data(), bytes.size(), 4, 2, 0.0001, 0.1, 10.0);
  ASSERT_TRUE(fine);
  EXPECT_FLOAT_EQ(fine->at<float>(0, 2), 0.1234F);
  auto short_buffer = z16ToMetres(bytes.data(), bytes.size() - 1, 4, 2, 0.001, 0.1, 10.0);
  ASSERT_FALSE(short_buffer);
  expectOneLine(short_buffer.error().message, "15 bytes, expected 16");
}

TEST(V4l2Conversions, GivenYuyvWhenDecodedThenBt601Colours) {
  // BT.601 limited range: Y 128, U = V = 128 is mid grey; Y 81, U 90, V 240 is pure red.
  auto grey = yuyv(4, 2, 128, 128, 128);
  auto bgr = decodeToBgr(grey.data(), grey.size(), RawImageFormat::kYuyv, 4, 2);
  ASSERT_TRUE(bgr) << bgr.error().message;
  ASSERT_EQ(bgr->type(), CV_8UC3);
  const cv::Vec3b g = bgr->at<cv::Vec3b>(1, 3);
  EXPECT_NEAR(g[0], 128, 3);
  EXPECT_NEAR(g[1], 128, 3);
  EXPECT_NEAR(g[2], 128, 3);
  auto red = yuyv(4, 2, 81, 90, 240);
  bgr = decodeToBgr(red.data(), red.size(), RawImageFormat::kYuyv, 4, 2);
  ASSERT_TRUE(bgr);
  const cv::Vec3b r = bgr->at<cv::Vec3b>(0, 0);
  EXPECT_LE(r[0], 3);
  EXPECT_LE(r[1], 3);
  EXPECT_GE(r[2], 250);
  auto truncated = decodeToBgr(red.data(), red.size() - 2, RawImageFormat::kYuyv, 4, 2);
  ASSERT_FALSE(truncated);
  expectOneLine(truncated.error().message, "YUYV frame of 14 bytes, expected 16");
}

TEST(V4l2Conversions, GivenMjpgWhenDecodedThenColoursSurviveAndCorruptFramesAreErrors) {
  const auto jpeg = redBlueJpeg(64, 48);
  auto bgr = decodeToBgr(jpeg.data(), jpeg.size(), RawImageFormat::kMjpg, 64, 48);
  ASSERT_TRUE(bgr) << bgr.error().message;
  const cv::Vec3b left = bgr->at<cv::Vec3b>(24, 8);
  const cv::Vec3b right = bgr->at<cv::Vec3b>(24, 56);
  EXPECT_GE(left[2], 240);  // red
  EXPECT_LE(left[0], 15);
  EXPECT_GE(right[0], 240);  // blue
  EXPECT_LE(right[2], 15);

  EXPECT_FALSE(decodeToBgr(jpeg.data(), jpeg.size(), RawImageFormat::kMjpg, 640, 480));  // wrong size
  auto cut = decodeToBgr(jpeg.data(), jpeg.size() / 2, RawImageFormat::kMjpg, 64, 48);   // USB transfer cut short
  ASSERT_FALSE(cut);
  expectOneLine(cut.error().message, "corrupt JPEG data");
  std::vector<std::uint8_t> garbage(500, 0x5A);
  garbage[498] = 0xFF;
  garbage[499] = 0xD9;  // ends like a JPEG, is not one
  auto bad = decodeToBgr(garbage.data(), garbage.size(), RawImageFormat::kMjpg, 64, 48);
  ASSERT_FALSE(bad);
  expectOneLine(bad.error().message, "not a PNG or JPEG image");
}

// ---- the gimbal camera over a fake source --------------------------------------------------------

V4l2GimbalCameraParams gimbalParams(const std::string& pixel_format) {
  V4l2GimbalCameraParams p;
  p.width_px = 64;
  p.height_px = 48;
  p.pixel_format = pixel_format;
  p.intrinsics = intrinsics(64, 48);
  return p;
}

struct GimbalRig {
  std::shared_ptr<FakeDevice> device = std::make_shared<FakeDevice>();
  std::unique_ptr<V4l2GimbalCamera> camera;
  std::vector<std::uint8_t> jpeg = redBlueJpeg(64, 48);

  explicit GimbalRig(const std::string& pixel_format = "MJPG") {
    camera = aerotrack::test::require(
        V4l2GimbalCamera::open(std::make_unique<FakeSource>(device), gimbalParams(pixel_format), kT0),
        "V4l2GimbalCamera::open");
  }
  void push(std::uint64_t sequence, std::optional<rt::TimeNs> stamp_ns) {
    device->ready.push_back({jpeg, sequence, stamp_ns});
  }
};

TEST(V4l2GimbalCamera, GivenFramesWhenGrabbedThenTheNewestOnceWithTheDriversMonotonicStamp) {
  GimbalRig rig;
  EXPECT_EQ(rig.camera->backend(), "real");
  EXPECT_EQ(rig.camera->grab(kT0 + 1 * kMs), nullptr);  // nothing yet
  rig.push(0, kT0 + 5 * kMs);
  rig.push(1, kT0 + 21 * kMs);  // two ready at once: the older one is passed over, not a drop
  const ImageFrameHandle f = rig.camera->grab(kT0 + 30 * kMs);
  ASSERT_NE(f, nullptr);
  EXPECT_EQ(f->stamp_ns, kT0 + 21 * kMs);  // the exposure's kernel stamp, not the poll time
  EXPECT_EQ(f->sequence, 1U);
  EXPECT_EQ(f->bgr.cols, 64);
  EXPECT_EQ(f->bgr.rows, 48);
  EXPECT_GE(f->bgr.at<cv::Vec3b>(10, 5)[2], 240);
  EXPECT_DOUBLE_EQ(f->intrinsics.fx_px, 100.0);
  EXPECT_EQ(rig.camera->grab(kT0 + 31 * kMs), nullptr);  // not returned twice
  const DeviceHealth h = rig.camera->health(kT0 + 32 * kMs);
  EXPECT_EQ(h.state, DeviceHealth::State::kOk) << h.detail;
  EXPECT_EQ(h.last_sample_ns, kT0 + 21 * kMs);
  EXPECT_EQ(h.error_count, 0U);
}

TEST(V4l2GimbalCamera, GivenASequenceGapWhenGrabbedThenDroppedFramesAreCountedAndDegradedForAWhile) {
  GimbalRig rig;
  rig.push(10, kT0 + 10 * kMs);
  ASSERT_NE(rig.camera->grab(kT0 + 11 * kMs), nullptr);
  rig.push(13, kT0 + 60 * kMs);  // the device lost 11 and 12
  ASSERT_NE(rig.camera->grab(kT0 + 61 * kMs), nullptr);
  DeviceHealth h = rig.camera->health(kT0 + 62 * kMs);
  EXPECT_EQ(h.state, DeviceHealth::State::kDegraded);
  EXPECT_EQ(h.error_count, 2U);
  EXPECT_NE(h.detail.find("2 frames dropped"), std::string::npos) << h.detail;
  // Frames keep flowing without gaps: ok again once kDegradedHoldS has passed since the drop.
  const rt::TimeNs later = kT0 + 61 * kMs + rt::secondsToNs(ReconnectingSource::kDegradedHoldS) + 10 * kMs;
  rig.push(14, later - 5 * kMs);
  ASSERT_NE(rig.camera->grab(later), nullptr);
  h = rig.camera->health(later);
  EXPECT_EQ(h.state, DeviceHealth::State::kOk) << h.detail;
  EXPECT_EQ(h.error_count, 2U);  // the count stays
}

TEST(V4l2GimbalCamera, GivenACorruptJpegWhenGrabbedThenItIsDroppedAndCountedAndTheNextFrameArrives) {
  GimbalRig rig;
  std::vector<std::uint8_t> cut(rig.jpeg.begin(), rig.jpeg.begin() + static_cast<long>(rig.jpeg.size() / 3));
  rig.device->ready.push_back({cut, 0, kT0 + 10 * kMs});
  EXPECT_EQ(rig.camera->grab(kT0 + 11 * kMs), nullptr);
  DeviceHealth h = rig.camera->health(kT0 + 12 * kMs);
  EXPECT_EQ(h.state, DeviceHealth::State::kDegraded);
  EXPECT_EQ(h.error_count, 1U);
  EXPECT_NE(h.detail.find("1 undecodable"), std::string::npos) << h.detail;
  EXPECT_NE(h.detail.find("corrupt JPEG data"), std::string::npos) << h.detail;
  rig.push(1, kT0 + 43 * kMs);
  const ImageFrameHandle f = rig.camera->grab(kT0 + 44 * kMs);
  ASSERT_NE(f, nullptr);
  EXPECT_EQ(f->sequence, 1U);
}

TEST(V4l2GimbalCamera, GivenYuyvFramesWhenGrabbedThenBgrImages) {
  GimbalRig rig("YUYV");
  rig.device->ready.push_back({yuyv(64, 48, 81, 90, 240), 0, kT0});
  const ImageFrameHandle f = rig.camera->grab(kT0 + 1 * kMs);
  ASSERT_NE(f, nullptr);
  EXPECT_GE(f->bgr.at<cv::Vec3b>(47, 63)[2], 250);
}

TEST(V4l2GimbalCamera, GivenNoMonotonicDriverStampWhenGrabbedThenThePollTimeIsUsedAndHealthSaysSo) {
  GimbalRig rig;
  rig.push(0, std::nullopt);
  const ImageFrameHandle f = rig.camera->grab(kT0 + 7 * kMs);
  ASSERT_NE(f, nullptr);
  EXPECT_EQ(f->stamp_ns, kT0 + 7 * kMs);
  const DeviceHealth h = rig.camera->health(kT0 + 8 * kMs);
  EXPECT_EQ(h.state, DeviceHealth::State::kOk);
  EXPECT_NE(h.detail.find("stamps are poll times"), std::string::npos) << h.detail;
}

TEST(V4l2GimbalCamera, GivenAnUnplugWhenGrabbedThenFailedAndReopenedEveryPeriodUntilItIsBack) {
  GimbalRig rig;
  rig.push(5, kT0 + 10 * kMs);
  const ImageFrameHandle before = rig.camera->grab(kT0 + 11 * kMs);
  ASSERT_NE(before, nullptr);
  EXPECT_EQ(rig.device->opens, 1);

  rig.device->plugged = false;
  const rt::TimeNs unplug_ns = kT0 + 40 * kMs;
  EXPECT_EQ(rig.camera->grab(unplug_ns), nullptr);
  EXPECT_EQ(rig.device->closes, 1);
  DeviceHealth h = rig.camera->health(unplug_ns);
  EXPECT_EQ(h.state, DeviceHealth::State::kFailed);
  EXPECT_NE(h.detail.find("/dev/fake0: unplugged"), std::string::npos) << h.detail;
  EXPECT_EQ(h.detail.find('\n'), std::string::npos);

  // Polled at 60 Hz: no reopen before reconnect_period_s (1 s) has passed.
  for (rt::TimeNs t = unplug_ns; t < unplug_ns + 990 * kMs; t += 16 * kMs) EXPECT_EQ(rig.camera->grab(t), nullptr);
  EXPECT_EQ(rig.device->opens, 1);
  EXPECT_EQ(rig.camera->grab(unplug_ns + 1000 * kMs), nullptr);  // tries, and fails: still unplugged
  EXPECT_EQ(rig.device->opens, 2);
  h = rig.camera->health(unplug_ns + 1001 * kMs);
  EXPECT_EQ(h.state, DeviceHealth::State::kFailed);
  EXPECT_NE(h.detail.find("cannot open"), std::string::npos) << h.detail;

  rig.device->plugged = true;  // plugged back: the driver restarts its counter
  EXPECT_EQ(rig.camera->grab(unplug_ns + 1500 * kMs), nullptr);
  EXPECT_EQ(rig.device->opens, 2);                               // the next attempt is at +2 s
  EXPECT_EQ(rig.camera->grab(unplug_ns + 2000 * kMs), nullptr);  // reopened; no frame yet
  EXPECT_EQ(rig.device->opens, 3);
  EXPECT_EQ(rig.camera->health(unplug_ns + 2001 * kMs).state, DeviceHealth::State::kOk);
  rig.push(0, unplug_ns + 2020 * kMs);
  const ImageFrameHandle after = rig.camera->grab(unplug_ns + 2021 * kMs);
  ASSERT_NE(after, nullptr);
  EXPECT_EQ(after->sequence, before->sequence + 1);  // numbering continues across the reconnect
  h = rig.camera->health(unplug_ns + 2022 * kMs);
  EXPECT_EQ(h.state, DeviceHealth::State::kOk) << h.detail;
  EXPECT_EQ(h.error_count, 1U);  // the one disconnect
}

TEST(V4l2GimbalCamera, GivenNoFrameForTheTimeoutWhenPolledThenFailedAndTheDeviceIsReopened) {
  GimbalRig rig;
  rig.push(0, kT0 + 10 * kMs);
  ASSERT_NE(rig.camera->grab(kT0 + 10 * kMs), nullptr);
  EXPECT_EQ(rig.camera->grab(kT0 + 500 * kMs), nullptr);
  EXPECT_EQ(rig.camera->health(kT0 + 500 * kMs).state, DeviceHealth::State::kOk);  // 490 ms < 500 ms
  DeviceHealth h = rig.camera->health(kT0 + 520 * kMs);                            // another thread, between polls
  EXPECT_EQ(h.state, DeviceHealth::State::kFailed);
  EXPECT_NE(h.detail.find("no frame for 510 ms"), std::string::npos) << h.detail;
  EXPECT_EQ(rig.camera->grab(kT0 + 520 * kMs), nullptr);  // the poll gives the device up ...
  EXPECT_EQ(rig.device->closes, 1);
  EXPECT_EQ(rig.camera->health(kT0 + 521 * kMs).state, DeviceHealth::State::kFailed);
  EXPECT_EQ(rig.camera->grab(kT0 + 1520 * kMs), nullptr);  // ... and reopens it a period later
  EXPECT_EQ(rig.device->opens, 2);
  rig.push(0, kT0 + 1530 * kMs);
  EXPECT_NE(rig.camera->grab(kT0 + 1531 * kMs), nullptr);
  EXPECT_EQ(rig.camera->health(kT0 + 1532 * kMs).state, DeviceHealth::State::kOk);
}

TEST(V4l2GimbalCamera, GivenAFreshlyOpenedCameraWhenItsFirstFrameIsSlowThenItHasAGracePeriod) {
  GimbalRig rig;  // opened at kT0, frame_timeout_s 0.5
  const rt::TimeNs grace_ns = rt::secondsToNs(ReconnectingSource::kFirstFrameGraceS);
  EXPECT_EQ(rig.camera->grab(kT0 + 1000 * kMs), nullptr);
  EXPECT_EQ(rig.camera->health(kT0 + 1000 * kMs).state, DeviceHealth::State::kOk);
  EXPECT_EQ(rig.device->closes, 0);
  EXPECT_EQ(rig.camera->health(kT0 + grace_ns + 1 * kMs).state, DeviceHealth::State::kFailed);
  EXPECT_EQ(rig.camera->grab(kT0 + grace_ns + 1 * kMs), nullptr);
  EXPECT_EQ(rig.device->closes, 1);
}

TEST(V4l2GimbalCamera, GivenBadParamsOrAMissingCameraWhenOpenedThenOneLineErrors) {
  auto device = std::make_shared<FakeDevice>();
  device->plugged = false;
  auto missing = V4l2GimbalCamera::open(std::make_unique<FakeSource>(device), gimbalParams("MJPG"), kT0);
  ASSERT_FALSE(missing);
  expectOneLine(missing.error().message, "/dev/fake0: cannot open");
  V4l2GimbalCameraParams p = gimbalParams("H264");
  EXPECT_FALSE(validate(p));
  p = gimbalParams("MJPG");
  p.intrinsics = intrinsics(640, 480);  // a calibration of another resolution
  auto mismatch = validate(p);
  ASSERT_FALSE(mismatch);
  expectOneLine(mismatch.error().message, "640x480");
}

// ---- the depth camera over a fake source ---------------------------------------------------------

TEST(V4l2DepthCamera, GivenZ16FramesWhenGrabbedThenMetresWithIntrinsicsAndExtrinsics) {
  auto device = std::make_shared<FakeDevice>();
  V4l2DepthCameraParams p;
  p.device = "/dev/fake0";
  p.width_px = 2;
  p.height_px = 2;
  p.calibration_file = "unused-with-a-given-calibration.yaml";
  p.T_BC.translation() << 0.1, 0.0, -0.05;
  CameraCalibration calibration;
  calibration.intrinsics = intrinsics(2, 2);
  calibration.depth_scale_m = 0.001;
  auto camera = V4l2DepthCamera::open(std::make_unique<FakeSource>(device), p, calibration, kT0);
  ASSERT_TRUE(camera) << camera.error().message;
  EXPECT_EQ((*camera)->backend(), "real");
  // 1500 mm, 0 (no data), 250 mm, 12 m (beyond max_range_m 10)
  device->ready.push_back({{0xDC, 0x05, 0x00, 0x00, 0xFA, 0x00, 0xE0, 0x2E}, 3, kT0 + 33 * kMs});
  const DepthFrameHandle f = (*camera)->grab(kT0 + 40 * kMs);
  ASSERT_NE(f, nullptr);
  EXPECT_EQ(f->stamp_ns, kT0 + 33 * kMs);
  EXPECT_FLOAT_EQ(f->depth_m.at<float>(0, 0), 1.5F);
  EXPECT_FLOAT_EQ(f->depth_m.at<float>(0, 1), 0.0F);
  EXPECT_FLOAT_EQ(f->depth_m.at<float>(1, 0), 0.25F);
  EXPECT_FLOAT_EQ(f->depth_m.at<float>(1, 1), 0.0F);
  EXPECT_DOUBLE_EQ(f->T_BC.translation().x(), 0.1);
  EXPECT_EQ(f->intrinsics.width_px, 2);
  // A short buffer is dropped and counted, like a corrupt JPEG.
  device->ready.push_back({{0xDC, 0x05}, 4, kT0 + 66 * kMs});
  EXPECT_EQ((*camera)->grab(kT0 + 70 * kMs), nullptr);
  EXPECT_EQ((*camera)->health(kT0 + 71 * kMs).state, DeviceHealth::State::kDegraded);

  calibration.intrinsics = intrinsics(640, 480);
  auto mismatch = V4l2DepthCamera::open(std::make_unique<FakeSource>(device), p, calibration, kT0);
  ASSERT_FALSE(mismatch);
  expectOneLine(mismatch.error().message, "/dev/fake0");
}

// ---- the real V4L2 path, without a camera ---------------------------------------------------------

TEST(V4l2Device, GivenAMissingNodeWhenOpenedThenOneLineNamesIt) {
  auto device = V4l2Device::open("/dev/video99", V4l2Format{V4L2_PIX_FMT_MJPEG, 640, 480, 30.0});
  ASSERT_FALSE(device);
  EXPECT_EQ(device.error().message.rfind("/dev/video99: cannot open: ", 0), 0U) << device.error().message;
  expectOneLine(device.error().message, "/dev/video99");

  V4l2GimbalCameraParams p = gimbalParams("MJPG");
  p.device = "/dev/video99";
  auto camera = V4l2GimbalCamera::open(p, kT0);
  ASSERT_FALSE(camera);
  expectOneLine(camera.error().message, "/dev/video99");

  V4l2DepthCameraParams d;
  d.device = "/dev/video99";
  d.calibration_dir = "/etc/aerotrack/calibration";
  auto depth = V4l2DepthCamera::open(d, kT0);
  ASSERT_FALSE(depth);
  expectOneLine(depth.error().message, "/dev/video99");
}

TEST(V4l2Device, GivenANodeThatIsNotACaptureDeviceWhenOpenedThenOneLineSaysSo) {
  auto device = V4l2Device::open("/dev/null", V4l2Format{V4L2_PIX_FMT_YUYV, 640, 480, 30.0});
  ASSERT_FALSE(device);
  EXPECT_EQ(device.error().message, "/dev/null: not a V4L2 capture device");

  V4l2GimbalCameraParams p = gimbalParams("YUYV");
  p.device = "/dev/null";
  auto camera = V4l2GimbalCamera::open(p, kT0);
  ASSERT_FALSE(camera);
  expectOneLine(camera.error().message, "/dev/null: not a V4L2 capture device");

  auto formats = listPixelFormats("/dev/null");
  ASSERT_FALSE(formats);
  EXPECT_EQ(formats.error().message, "/dev/null: not a V4L2 capture device");
}

TEST(V4l2Device, GivenNoNodeOfferingZ16WhenSearchedThenOneLineSaysSo) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("aerotrack_dev_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "video0") << "not a device";
  auto found = findVideoNodeWithFormat(V4L2_PIX_FMT_Z16, dir.string());
  ASSERT_FALSE(found);
  expectOneLine(found.error().message, "no V4L2 capture node offers pixel format Z16");
  fs::remove_all(dir);
}

}  // namespace
}  // namespace aerotrack::hal::real
