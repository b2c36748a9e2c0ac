// Dataset manifest: see manifest.hpp.
#include "aerotrack/hal/replay/manifest.hpp"

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <system_error>

#include "aerotrack/rt/config_node.hpp"
#include "aerotrack/rt/input_limits.hpp"

namespace aerotrack::hal::replay {
namespace {

const std::set<std::string>& knownDevices() {
  static const std::set<std::string> kDevices = {"odometry",      "gimbal",     "gimbal_commands", "setpoints",
                                                 "gimbal_camera", "detections", "depth_camera",    "can"};
  return kDevices;
}

RecordedCamera parseCamera(const rt::ConfigNode& node) {
  RecordedCamera c;
  c.intrinsics.width_px = node.getInt("width_px", 1, 100000);
  c.intrinsics.height_px = node.getInt("height_px", 1, 100000);
  c.intrinsics.fx_px = node.getDouble("fx_px", 1e-3, 1e7);
  c.intrinsics.fy_px = node.getDouble("fy_px", 1e-3, 1e7);
  c.intrinsics.cx_px = node.getDouble("cx_px", -1e6, 1e6);
  c.intrinsics.cy_px = node.getDouble("cy_px", -1e6, 1e6);
  const std::vector<double> d = node.getDoubleList("distortion", 5, -1e3, 1e3);
  for (std::size_t i = 0; i < 5; ++i) c.intrinsics.distortion[i] = d[i];
  const std::vector<double> mount = node.getDoubleList("mount_m", 3, -10.0, 10.0);
  c.mount_B_m = Eigen::Vector3d(mount[0], mount[1], mount[2]);
  if (node.has("rotation_B_C")) {
    const std::vector<double> r = node.getDoubleList("rotation_B_C", 9, -1.5, 1.5);
    for (int i = 0; i < 9; ++i) c.R_BC(i / 3, i % 3) = r[static_cast<std::size_t>(i)];
    if (!(c.R_BC * c.R_BC.transpose()).isIdentity(1e-6) || c.R_BC.determinant() < 0.0)
      node.fail("rotation_B_C", "is not a rotation matrix");
  }
  if (node.has("image_format")) c.image_format = node.getEnum("image_format", {"png", "jpg"});
  node.finish();
  return c;
}

void emitCamera(YAML::Emitter& out, const char* key, const RecordedCamera& c) {
  out << YAML::Key << key << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "width_px" << YAML::Value << c.intrinsics.width_px;
  out << YAML::Key << "height_px" << YAML::Value << c.intrinsics.height_px;
  out << YAML::Key << "fx_px" << YAML::Value << c.intrinsics.fx_px;
  out << YAML::Key << "fy_px" << YAML::Value << c.intrinsics.fy_px;
  out << YAML::Key << "cx_px" << YAML::Value << c.intrinsics.cx_px;
  out << YAML::Key << "cy_px" << YAML::Value << c.intrinsics.cy_px;
  out << YAML::Key << "distortion" << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (const double k : c.intrinsics.distortion) out << k;
  out << YAML::EndSeq;
  out << YAML::Key << "mount_m" << YAML::Value << YAML::Flow << YAML::BeginSeq << c.mount_B_m.x() << c.mount_B_m.y()
      << c.mount_B_m.z() << YAML::EndSeq;
  out << YAML::Key << "rotation_B_C" << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (int i = 0; i < 9; ++i) out << c.R_BC(i / 3, i % 3);
  out << YAML::EndSeq;
  out << YAML::Key << "image_format" << YAML::Value << c.image_format;
  out << YAML::EndMap;
}

}  // namespace

const StreamEntry* DatasetManifest::stream(const std::string& device) const {
  for (const StreamEntry& s : streams) {
    if (s.device == device) return &s;
  }
  return nullptr;
}

rt::Expected<DatasetManifest> readManifest(const std::string& path) {
  auto root = rt::ConfigNode::loadFile(path);
  if (!root) return root.error();
  try {
    DatasetManifest m;
    if (root->getString("format") != "aerotrack-dataset") root->fail("format", "expected 'aerotrack-dataset'");
    m.format_version = root->getInt("format_version", 1, 1000000);
    if (m.format_version != kDatasetFormatVersion) {
      root->fail("format_version", std::to_string(m.format_version) + " is not supported (this build reads " +
                                       std::to_string(kDatasetFormatVersion) + ")");
    }
    m.software_version = root->getString("software_version");
    const std::uint64_t start_ns = root->getUint64("start_ns");
    if (start_ns > static_cast<std::uint64_t>(rt::limits::kMaxStampNs))
      root->fail("start_ns", "must be at most " + std::to_string(rt::limits::kMaxStampNs) + " (the input policy)");
    m.start_ns = static_cast<rt::TimeNs>(start_ns);
    if (root->has("end_ns")) {
      const std::uint64_t end_ns = root->getUint64("end_ns");
      if (end_ns < start_ns) root->fail("end_ns", "is before start_ns");
      if (end_ns - start_ns > static_cast<std::uint64_t>(rt::limits::kMaxRunNs))
        root->fail("end_ns", "lies more than " + std::to_string(static_cast<long long>(rt::limits::kMaxRunS)) +
                                 " s after start_ns, the longest recording (the input policy)");
      m.end_ns = static_cast<rt::TimeNs>(end_ns);
    }
    m.source = root->getEnum("source", {"sim", "real", "replay", "import"});
    for (const rt::ConfigNode& s : root->childList("streams")) {
      StreamEntry entry{s.getString("device"), s.getString("file")};
      if (knownDevices().count(entry.device) == 0) s.fail("device", "unknown device '" + entry.device + "'");
      if (entry.file.empty() || entry.file.front() == '/' || entry.file.find("..") != std::string::npos) {
        s.fail("file", "must be a path inside the dataset's folder, got '" + entry.file + "'");
      }
      if (m.stream(entry.device) != nullptr) s.fail("device", "'" + entry.device + "' listed twice");
      s.finish();
      m.streams.push_back(entry);
    }
    if (root->has("gimbal_camera")) m.gimbal_camera = parseCamera(root->child("gimbal_camera"));
    if (root->has("depth_camera")) m.depth_camera = parseCamera(root->child("depth_camera"));
    root->finish();
    return m;
  } catch (const rt::ConfigError& e) {
    return rt::Error{e.what()};
  }
}

rt::Status writeManifest(const DatasetManifest& m, const std::string& path) {
  YAML::Emitter out;
  out.SetDoublePrecision(17);
  out << YAML::BeginMap;
  out << YAML::Key << "format" << YAML::Value << "aerotrack-dataset";
  out << YAML::Key << "format_version" << YAML::Value << m.format_version;
  out << YAML::Key << "software_version" << YAML::Value << m.software_version;
  out << YAML::Key << "start_ns" << YAML::Value << m.start_ns;
  if (m.end_ns) out << YAML::Key << "end_ns" << YAML::Value << *m.end_ns;
  out << YAML::Key << "source" << YAML::Value << m.source;
  out << YAML::Key << "streams" << YAML::Value << YAML::BeginSeq;
  for (const StreamEntry& s : m.streams) {
    out << YAML::Flow << YAML::BeginMap << YAML::Key << "device" << YAML::Value << s.device << YAML::Key << "file"
        << YAML::Value << s.file << YAML::EndMap;
  }
  out << YAML::EndSeq;
  if (m.gimbal_camera) emitCamera(out, "gimbal_camera", *m.gimbal_camera);
  if (m.depth_camera) emitCamera(out, "depth_camera", *m.depth_camera);
  out << YAML::EndMap;
  // Written whole, then renamed into place: the recorder rewrites it when a camera's first frame
  // tells its intrinsics, and a recording cut at that moment must still have a readable manifest.
  const std::string part = path + ".part";
  std::ofstream file(part, std::ios::trunc);
  file << "# aerotrack recorded dataset (hal/replay/README.md)\n" << out.c_str() << "\n";
  file.close();
  if (!file) return rt::Error{path + ": write failed"};
  std::error_code ec;
  std::filesystem::rename(part, path, ec);
  if (ec) return rt::Error{path + ": cannot rename " + part + ": " + ec.message()};
  return rt::ok();
}

}  // namespace aerotrack::hal::replay
