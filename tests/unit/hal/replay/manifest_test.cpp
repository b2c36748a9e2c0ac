// A dataset's manifest (hal/replay/manifest.hpp): written and read back whole; a version this build
// cannot read, an unknown device, a stream file outside the folder, a missing key: one-line errors
// naming the file, line and key.
#include "aerotrack/hal/replay/manifest.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

namespace aerotrack::hal::replay {
namespace {

std::string tempFile(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("aerotrack-manifest-" + std::to_string(::getpid()) + "-" + name))
      .string();
}

/// `message` has "<file>:<digits>: " in it (the file and the line).
bool namesALine(const std::string& message, const std::string& file) {
  const std::size_t at = message.find(file);
  if (at == std::string::npos) return false;
  std::size_t i = at + file.size();
  const std::size_t digits_begin = i;
  while (i < message.size() && message[i] >= '0' && message[i] <= '9') ++i;
  return i > digits_begin && message.compare(i, 2, ": ") == 0;
}

DatasetManifest sample() {
  DatasetManifest m;
  m.software_version = "aerotrack 0.9.0-42-gabcdef";
  m.start_ns = 1'700'000'000'123'456'789;
  m.source = "sim";
  m.streams = {{"odometry", "odometry.csv"}, {"gimbal", "gimbal.csv"}, {"gimbal_camera", "gimbal_camera/frames.csv"}};
  RecordedCamera cam;
  cam.intrinsics.width_px = 640;
  cam.intrinsics.height_px = 480;
  cam.intrinsics.fx_px = 337.2;
  cam.intrinsics.fy_px = 337.2;
  cam.intrinsics.cx_px = 319.5;
  cam.intrinsics.cy_px = 239.5;
  cam.intrinsics.distortion = {0.01, -0.002, 0.0, 0.0, 1.0 / 3.0};
  cam.mount_B_m = Eigen::Vector3d(0.1, 0.0, -0.05);
  m.gimbal_camera = cam;
  return m;
}

TEST(DatasetManifest, WrittenAndReadBackWhole) {
  const std::string path = tempFile("ok.yaml");
  const DatasetManifest m = sample();
  ASSERT_TRUE(writeManifest(m, path));
  auto back = readManifest(path);
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(back->format_version, kDatasetFormatVersion);
  EXPECT_EQ(back->software_version, m.software_version);
  EXPECT_EQ(back->start_ns, m.start_ns);
  EXPECT_EQ(back->source, "sim");
  ASSERT_EQ(back->streams.size(), 3U);
  ASSERT_NE(back->stream("gimbal_camera"), nullptr);
  EXPECT_EQ(back->stream("gimbal_camera")->file, "gimbal_camera/frames.csv");
  EXPECT_EQ(back->stream("depth_camera"), nullptr);
  ASSERT_TRUE(back->gimbal_camera.has_value());
  EXPECT_EQ(back->gimbal_camera->intrinsics.distortion[4], 1.0 / 3.0);  // 17 digits: exact
  EXPECT_EQ(back->gimbal_camera->mount_B_m, m.gimbal_camera->mount_B_m);
  EXPECT_FALSE(back->depth_camera.has_value());
  std::filesystem::remove(path);
}

TEST(DatasetManifest, BadManifestsGetOneLineErrorsNamingFileLineAndKey) {
  const std::string good_path = tempFile("good.yaml");
  ASSERT_TRUE(writeManifest(sample(), good_path));
  std::ifstream in(good_path);
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string good = buffer.str();
  struct Case {
    std::string from, to, message;
  };
  const std::vector<Case> cases = {
      {"format_version: 2", "format_version: 1", "format_version: 1 is not supported (this build reads 2)"},
      {"device: gimbal,", "device: lidar,", "streams[1].device: unknown device 'lidar'"},
      {"file: gimbal.csv", "file: ../gimbal.csv", "streams[1].file: must be a path inside the dataset's folder"},
      {"device: gimbal,", "device: odometry,", "streams[1].device: 'odometry' listed twice"},
      {"source: sim", "source: mars", "source"},
      {"software_version: aerotrack 0.9.0-42-gabcdef\n", "", "software_version: missing required key"},
      {"format: aerotrack-dataset", "format: something-else", "format: expected 'aerotrack-dataset'"},
  };
  for (const Case& c : cases) {
    std::string text = good;
    const std::size_t at = text.find(c.from);
    ASSERT_NE(at, std::string::npos) << c.from << " in\n" << text;
    text.replace(at, c.from.size(), c.to);
    const std::string path = tempFile("bad.yaml");
    std::ofstream(path) << text;
    auto m = readManifest(path);
    ASSERT_FALSE(m) << c.to;
    EXPECT_NE(m.error().message.find(c.message), std::string::npos) << m.error().message;
    EXPECT_TRUE(namesALine(m.error().message, "bad.yaml:")) << m.error().message;
    EXPECT_EQ(m.error().message.find('\n'), std::string::npos);
  }
  auto missing = readManifest(tempFile("absent.yaml"));
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("absent.yaml"), std::string::npos);
  std::filesystem::remove(good_path);
  std::filesystem::remove(tempFile("bad.yaml"));
}

}  // namespace
}  // namespace aerotrack::hal::replay
