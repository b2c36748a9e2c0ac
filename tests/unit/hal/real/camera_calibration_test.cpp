// Camera calibration files (hal/real/camera_calibration.hpp, issue 11 items 1 and 2): our format and
// ROS camera_info give the same intrinsics; every bad or missing key is one line naming the file and
// the key; the shipped examples parse; the per-serial file name and the USB serial lookup through a
// sysfs tree built in a temporary folder.
#include "aerotrack/hal/real/camera_calibration.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

namespace aerotrack::hal::real {
namespace {

const std::string kOurs = R"(width_px: 640
height_px: 480
fx_px: 457.3
fy_px: 456.8
cx_px: 321.6
cy_px: 238.9
distortion: [-0.312, 0.094, 0.0004, -0.0008, 0.01]
)";

// As ROS camera_calibration writes it (camera_info_manager's YAML).
const std::string kRos = R"(image_width: 640
image_height: 480
camera_name: gimbal_cam
camera_matrix:
  rows: 3
  cols: 3
  data: [457.3, 0, 321.6, 0, 456.8, 238.9, 0, 0, 1]
distortion_model: plumb_bob
distortion_coefficients:
  rows: 1
  cols: 5
  data: [-0.312, 0.094, 0.0004, -0.0008, 0.01]
rectification_matrix:
  rows: 3
  cols: 3
  data: [1, 0, 0, 0, 1, 0, 0, 0, 1]
projection_matrix:
  rows: 3
  cols: 4
  data: [400.1, 0, 322.0, 0, 0, 420.5, 240.2, 0, 0, 0, 1, 0]
)";

void expectExample(const CameraIntrinsics& k) {
  EXPECT_EQ(k.width_px, 640);
  EXPECT_EQ(k.height_px, 480);
  EXPECT_DOUBLE_EQ(k.fx_px, 457.3);
  EXPECT_DOUBLE_EQ(k.fy_px, 456.8);
  EXPECT_DOUBLE_EQ(k.cx_px, 321.6);
  EXPECT_DOUBLE_EQ(k.cy_px, 238.9);
  EXPECT_DOUBLE_EQ(k.distortion[0], -0.312);
  EXPECT_DOUBLE_EQ(k.distortion[1], 0.094);
  EXPECT_DOUBLE_EQ(k.distortion[2], 0.0004);
  EXPECT_DOUBLE_EQ(k.distortion[3], -0.0008);
  EXPECT_DOUBLE_EQ(k.distortion[4], 0.01);
}

/// Replaces the first line starting with `key:` by `replacement` (a whole line, or "" to delete it).
std::string withLine(const std::string& text, const std::string& key, const std::string& replacement) {
  // Plain search, not std::regex: GCC 12's <regex> raises -Wmaybe-uninitialized under ASan at -O2.
  std::size_t at = text.rfind(key + ":", 0) == 0 ? 0 : text.find("\n" + key + ":");
  if (at == std::string::npos) return text;
  if (text[at] == '\n') ++at;
  const std::size_t end = text.find('\n', at);
  const std::size_t line_end = end == std::string::npos ? text.size() : end + 1;
  return text.substr(0, at) + replacement + text.substr(line_end);
}

TEST(CameraCalibration, GivenOurFormatWhenParsedThenIntrinsicsAndDistortionAreRead) {
  auto c = parseCameraCalibration(kOurs, "gimbal.yaml");
  ASSERT_TRUE(c) << c.error().message;
  expectExample(c->intrinsics);
  EXPECT_EQ(c->serial, "");
  EXPECT_DOUBLE_EQ(c->depth_scale_m, 0.001);
}

TEST(CameraCalibration, GivenDepthKeysWhenParsedThenSerialAndScaleAreRead) {
  auto c = parseCameraCalibration(kOurs + "serial: \"841512070123\"\ndepth_scale_m: 0.0001\n", "d435.yaml");
  ASSERT_TRUE(c) << c.error().message;
  EXPECT_EQ(c->serial, "841512070123");
  EXPECT_DOUBLE_EQ(c->depth_scale_m, 0.0001);
}

TEST(CameraCalibration, GivenRosCameraInfoWhenParsedThenTheSameIntrinsicsAreRead) {
  auto c = parseCameraCalibration(kRos, "ost.yaml");
  ASSERT_TRUE(c) << c.error().message;
  expectExample(c->intrinsics);
  EXPECT_EQ(c->serial, "gimbal_cam");
}

struct BadCase {
  const char* key;          // the line replaced
  const char* replacement;  // "" deletes it
  const char* named;        // the key the message must name
};

TEST(CameraCalibration, GivenEachBadKeyWhenParsedThenOneLineNamesTheFileAndTheKey) {
  const BadCase cases[] = {
      {"width_px", "", "width_px"},
      {"height_px", "height_px: -480\n", "height_px"},
      {"fx_px", "", "fx_px"},
      {"fy_px", "fy_px: wide\n", "fy_px"},
      {"cx_px", "cx_px: 700\n", "cx_px"},  // outside the 640-pixel width
      {"cy_px", "", "cy_px"},
      {"distortion", "distortion: [0.1, 0.2, 0.0, 0.0]\n", "distortion"},
      {"distortion", "", "distortion"},
      {"fx_px", "fx_px: 457.3\nfocal_mm: 4\n", "focal_mm"},  // an unknown key
  };
  for (const BadCase& bad : cases) {
    const std::string text = withLine(kOurs, bad.key, bad.replacement);
    ASSERT_NE(text, kOurs) << bad.key;
    auto c = parseCameraCalibration(text, "calib/gimbal.yaml");
    ASSERT_FALSE(c) << bad.key << " " << bad.replacement;
    const std::string& m = c.error().message;
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    EXPECT_EQ(m.rfind("calib/gimbal.yaml", 0), 0U) << m;
    EXPECT_NE(m.find(bad.named), std::string::npos) << m;
  }
}

TEST(CameraCalibration, GivenBadRosKeysWhenParsedThenOneLineNamesTheKey) {
  const BadCase cases[] = {
      {"distortion_model", "distortion_model: equidistant\n", "distortion_model"},
      {"image_height", "", "image_height"},
  };
  for (const BadCase& bad : cases) {
    auto c = parseCameraCalibration(withLine(kRos, bad.key, bad.replacement), "ost.yaml");
    ASSERT_FALSE(c) << bad.key;
    EXPECT_EQ(c.error().message.find('\n'), std::string::npos) << c.error().message;
    EXPECT_NE(c.error().message.find("ost.yaml"), std::string::npos) << c.error().message;
    EXPECT_NE(c.error().message.find(bad.named), std::string::npos) << c.error().message;
  }
  std::string skewed = kRos;
  skewed.replace(skewed.find("[457.3, 0,"), 10, "[457.3, 2,");
  auto c = parseCameraCalibration(skewed, "ost.yaml");
  ASSERT_FALSE(c);
  EXPECT_NE(c.error().message.find("camera_matrix"), std::string::npos) << c.error().message;
  std::string short_distortion = kRos;
  short_distortion.replace(short_distortion.find("  cols: 5"), 9, "  cols: 4");
  EXPECT_FALSE(parseCameraCalibration(short_distortion, "ost.yaml"));
}

TEST(CameraCalibration, GivenAMissingFileWhenLoadedThenTheErrorNamesIt) {
  auto c = loadCameraCalibration("/nonexistent/d435_1.yaml");
  ASSERT_FALSE(c);
  EXPECT_EQ(c.error().message.rfind("/nonexistent/d435_1.yaml: ", 0), 0U) << c.error().message;
}

TEST(CameraCalibration, GivenTheShippedExamplesWhenLoadedThenTheyParse) {
  auto gimbal = loadCameraCalibration(AEROTRACK_SOURCE_DIR "/config/calibration/gimbal_camera.example.yaml");
  ASSERT_TRUE(gimbal) << gimbal.error().message;
  EXPECT_EQ(gimbal->intrinsics.width_px, 640);
  auto d435 = loadCameraCalibration(AEROTRACK_SOURCE_DIR "/config/calibration/d435_123456789012.example.yaml");
  ASSERT_TRUE(d435) << d435.error().message;
  EXPECT_EQ(d435->serial, "123456789012");
  EXPECT_DOUBLE_EQ(d435->depth_scale_m, 0.001);
  EXPECT_EQ(d435->intrinsics.height_px, 480);
}

TEST(CameraCalibration, GivenASerialWhenResolvedThenTheFileIsD435UnderscoreSerial) {
  EXPECT_EQ(depthCalibrationPath("/etc/aerotrack/calibration", "841512070123"),
            "/etc/aerotrack/calibration/d435_841512070123.yaml");
}

TEST(CameraCalibration, GivenASysfsTreeWhenTheSerialIsReadThenItComesFromTheUsbDevice) {
  namespace fs = std::filesystem;
  const fs::path root = fs::temp_directory_path() / ("aerotrack_sysfs_" + std::to_string(::getpid()));
  fs::remove_all(root);
  // /dev/video2 -> sysfs video4linux/video2/device -> the USB interface 1-2:1.0, whose parent 1-2 is
  // the USB device holding `serial`; /dev/d435 is a udev-style symlink to /dev/video2.
  fs::create_directories(root / "dev");
  std::ofstream(root / "dev" / "video2").put('\0');
  fs::create_symlink(root / "dev" / "video2", root / "dev" / "d435");
  fs::create_directories(root / "usb" / "1-2" / "1-2:1.0");
  std::ofstream(root / "usb" / "1-2" / "serial") << "841512070123\n";
  fs::create_directories(root / "v4l" / "video2");
  fs::create_directory_symlink(root / "usb" / "1-2" / "1-2:1.0", root / "v4l" / "video2" / "device");

  auto serial = usbSerialOfVideoNode((root / "dev" / "d435").string(), (root / "v4l").string());
  ASSERT_TRUE(serial) << serial.error().message;
  EXPECT_EQ(*serial, "841512070123");

  auto missing = usbSerialOfVideoNode("/dev/video99", (root / "v4l").string());
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().message.rfind("/dev/video99: ", 0), 0U) << missing.error().message;
  fs::remove_all(root);
}

}  // namespace
}  // namespace aerotrack::hal::real
