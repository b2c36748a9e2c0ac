// Dataset stream codecs: see stream_codecs.hpp.
#include "aerotrack/hal/replay/stream_codecs.hpp"

#include <cmath>

namespace aerotrack::hal::replay {
namespace {

rt::Error badValue(const CsvRecord& record, const std::string& path, const std::string& what) {
  return rt::Error{path + ":" + std::to_string(record.line) + ": " + what};
}

Eigen::Vector3d vec(const std::vector<double>& v, std::size_t at) {
  return {v[at], v[at + 1], v[at + 2]};
}

void put(std::vector<double>& out, const Eigen::Vector3d& v) {
  out.insert(out.end(), {v.x(), v.y(), v.z()});
}

constexpr double kMaxWhole = 9007199254740992.0;  // 2^53: every whole number up to it is exact in a double

}  // namespace

rt::Expected<std::int64_t> wholeNumber(const CsvRecord& record, std::size_t at, const std::string& path,
                                       const char* column) {
  const double x = record.values[at];
  if (!(x >= 0.0 && x <= kMaxWhole && x == std::floor(x)))
    return badValue(record, path, std::string(column) + " is not a whole number >= 0");
  return static_cast<std::int64_t>(x);
}

const std::vector<std::string>& OdometryCodec::columns() {
  static const std::vector<std::string> kColumns = {
      "px_m", "py_m", "pz_m", "qw", "qx", "qy", "qz", "vx_mps", "vy_mps", "vz_mps", "wx_radps", "wy_radps", "wz_radps"};
  return kColumns;
}

std::vector<double> OdometryCodec::encode(const OdometrySample& s) {
  std::vector<double> out;
  out.reserve(columns().size());
  put(out, s.p_WB_m);
  out.insert(out.end(), {s.q_WB.w(), s.q_WB.x(), s.q_WB.y(), s.q_WB.z()});
  put(out, s.v_WB_mps);
  put(out, s.w_WB_B_radps);
  return out;
}

rt::Expected<OdometrySample> OdometryCodec::decode(const CsvRecord& r, const std::string& path) {
  const std::vector<double>& v = r.values;
  OdometrySample s;
  s.stamp_ns = r.stamp_ns;
  s.p_WB_m = vec(v, 0);
  s.q_WB = Eigen::Quaterniond(v[3], v[4], v[5], v[6]);
  s.v_WB_mps = vec(v, 7);
  s.w_WB_B_radps = vec(v, 10);
  for (const double x : v) {
    if (!std::isfinite(x)) return badValue(r, path, "odometry: a value is not finite");
  }
  if (std::abs(s.q_WB.norm() - 1.0) > 1e-6) {
    return badValue(r, path, "odometry: quaternion norm " + std::to_string(s.q_WB.norm()) + " is not 1");
  }
  return s;
}

const std::vector<std::string>& GimbalStateCodec::columns() {
  static const std::vector<std::string> kColumns = {"angle_rad", "rate_radps"};
  return kColumns;
}

std::vector<double> GimbalStateCodec::encode(const GimbalState& s) {
  return {s.angle_rad, s.rate_radps};
}

rt::Expected<GimbalState> GimbalStateCodec::decode(const CsvRecord& r, const std::string& path) {
  if (!std::isfinite(r.values[0]) || !std::isfinite(r.values[1])) {
    return badValue(r, path, "gimbal: a value is not finite");
  }
  GimbalState s;
  s.stamp_ns = r.stamp_ns;
  s.angle_rad = r.values[0];
  s.rate_radps = r.values[1];
  return s;
}

const std::vector<std::string>& GimbalCommandCodec::columns() {
  static const std::vector<std::string> kColumns = {"mode", "rate_radps", "angle_rad", "max_rate_radps"};
  return kColumns;
}

std::vector<double> GimbalCommandCodec::encode(const GimbalCommand& c) {
  return {c.mode == GimbalCommand::Mode::kAngle ? 1.0 : 0.0, c.rate_radps, c.angle_rad, c.max_rate_radps};
}

rt::Expected<GimbalCommand> GimbalCommandCodec::decode(const CsvRecord& r, const std::string& path) {
  const std::vector<double>& v = r.values;
  if (v[0] != 0.0 && v[0] != 1.0) return badValue(r, path, "gimbal command: mode must be 0 (rate) or 1 (angle)");
  for (std::size_t i = 1; i < v.size(); ++i) {
    if (!std::isfinite(v[i])) return badValue(r, path, "gimbal command: a value is not finite");
  }
  GimbalCommand c;
  c.stamp_ns = r.stamp_ns;
  c.mode = v[0] == 1.0 ? GimbalCommand::Mode::kAngle : GimbalCommand::Mode::kRate;
  c.rate_radps = v[1];
  c.angle_rad = v[2];
  c.max_rate_radps = v[3];
  return c;
}

const std::vector<std::string>& SetpointCodec::columns() {
  static const std::vector<std::string> kColumns = {"px_m",    "py_m",    "pz_m",          "vx_mps",
                                                    "vy_mps",  "vz_mps",  "ax_mps2",       "ay_mps2",
                                                    "az_mps2", "yaw_rad", "yaw_rate_radps"};
  return kColumns;
}

std::vector<double> SetpointCodec::encode(const Setpoint& s) {
  std::vector<double> out;
  out.reserve(columns().size());
  put(out, s.p_W_m);
  put(out, s.v_W_mps);
  put(out, s.a_W_mps2);
  out.insert(out.end(), {s.yaw_rad, s.yaw_rate_radps});
  return out;
}

rt::Expected<Setpoint> SetpointCodec::decode(const CsvRecord& r, const std::string& path) {
  for (const double x : r.values) {
    if (!std::isfinite(x)) return badValue(r, path, "setpoint: a value is not finite");
  }
  Setpoint s;
  s.stamp_ns = r.stamp_ns;
  s.p_W_m = vec(r.values, 0);
  s.v_W_mps = vec(r.values, 3);
  s.a_W_mps2 = vec(r.values, 6);
  s.yaw_rad = r.values[9];
  s.yaw_rate_radps = r.values[10];
  return s;
}

namespace {

// DetectionCodec's layout: the frame's fields, then kPersonColumns per person.
constexpr std::size_t kFrameColumns = 15;
constexpr std::size_t kPersonColumns = 5 + 3 * kNumKeypoints;
constexpr std::size_t kAppearanceColumns = 1 + kAppearanceSignatureBins;  // per person, after all persons

}  // namespace

const std::vector<std::string>& DetectionCodec::columns() {
  static const std::vector<std::string> kColumns = [] {
    std::vector<std::string> c = {
        "result_delay_ns", "sequence", "width_px", "height_px", "fx_px", "fy_px", "cx_px",
        "cy_px",           "k1",       "k2",       "p1",        "p2",    "k3",    "person_count",
        "target_index"};
    for (std::size_t p = 0; p < kMaxPersons; ++p) {
      const std::string person = "p" + std::to_string(p) + "_";
      for (const char* field : {"score", "bbox_u_px", "bbox_v_px", "bbox_w_px", "bbox_h_px"})
        c.push_back(person + field);
      for (std::size_t k = 0; k < kNumKeypoints; ++k) {
        const std::string keypoint = person + "k" + std::to_string(k) + "_";
        for (const char* field : {"u_px", "v_px", "score"}) c.push_back(keypoint + field);
      }
    }
    // Appearance signatures after everything else (issue 20: the lock-on reruns in replay on them).
    for (std::size_t p = 0; p < kMaxPersons; ++p) {
      const std::string person = "p" + std::to_string(p) + "_";
      c.push_back(person + "has_appearance");
      for (std::size_t b = 0; b < kAppearanceSignatureBins; ++b) c.push_back(person + "a" + std::to_string(b));
    }
    return c;
  }();
  return kColumns;
}

std::vector<double> DetectionCodec::encode(const DetectionFrame& f) {
  const CameraIntrinsics& k = f.intrinsics;
  std::vector<double> out = {static_cast<double>(f.result_ns - f.stamp_ns),
                             static_cast<double>(f.sequence),
                             static_cast<double>(k.width_px),
                             static_cast<double>(k.height_px),
                             k.fx_px,
                             k.fy_px,
                             k.cx_px,
                             k.cy_px};
  out.insert(out.end(), k.distortion.begin(), k.distortion.end());
  out.push_back(static_cast<double>(f.person_count));
  out.push_back(static_cast<double>(f.target_index));
  for (const PersonDetection& p : f.persons) {
    out.insert(out.end(), {p.score, p.bbox_u_px, p.bbox_v_px, p.bbox_w_px, p.bbox_h_px});
    for (const Keypoint2D& kp : p.keypoints) out.insert(out.end(), {kp.u_px, kp.v_px, kp.score});
  }
  for (const PersonDetection& p : f.persons) {
    out.push_back(p.has_appearance ? 1.0 : 0.0);
    for (const float bin : p.appearance) out.push_back(static_cast<double>(bin));
  }
  return out;
}

rt::Expected<DetectionFrame> DetectionCodec::decode(const CsvRecord& r, const std::string& path) {
  const std::vector<double>& v = r.values;
  for (const double x : v) {
    if (!std::isfinite(x)) return badValue(r, path, "detections: a value is not finite");
  }
  DetectionFrame f;
  f.stamp_ns = r.stamp_ns;
  auto delay_ns = wholeNumber(r, 0, path, "result_delay_ns");
  if (!delay_ns) return delay_ns.error();
  f.result_ns = r.stamp_ns + *delay_ns;
  auto sequence = wholeNumber(r, 1, path, "sequence");
  if (!sequence) return sequence.error();
  f.sequence = static_cast<std::uint64_t>(*sequence);
  auto width = wholeNumber(r, 2, path, "width_px");
  auto height = wholeNumber(r, 3, path, "height_px");
  if (!width || !height || *width > 100000 || *height > 100000)
    return badValue(r, path, "detections: the image size is not whole pixels in [0, 100000]");
  CameraIntrinsics& k = f.intrinsics;
  k.width_px = static_cast<int>(*width);
  k.height_px = static_cast<int>(*height);
  k.fx_px = v[4];
  k.fy_px = v[5];
  k.cx_px = v[6];
  k.cy_px = v[7];
  for (std::size_t i = 0; i < 5; ++i) k.distortion[i] = v[8 + i];
  auto count = wholeNumber(r, 13, path, "person_count");
  if (!count || *count > static_cast<std::int64_t>(kMaxPersons))
    return badValue(r, path,
                    "detections: person_count must be a whole number in [0, " + std::to_string(kMaxPersons) + "]");
  f.person_count = static_cast<std::size_t>(*count);
  const double target = v[14];
  if (target != std::floor(target) || target < -1.0 || target >= static_cast<double>(f.person_count))
    return badValue(r, path, "detections: target_index must be -1 or a listed person");
  f.target_index = static_cast<int>(target);
  for (std::size_t p = 0; p < kMaxPersons; ++p) {
    const double* x = v.data() + kFrameColumns + p * kPersonColumns;
    PersonDetection& person = f.persons[p];
    person.score = x[0];
    person.bbox_u_px = x[1];
    person.bbox_v_px = x[2];
    person.bbox_w_px = x[3];
    person.bbox_h_px = x[4];
    for (std::size_t i = 0; i < kNumKeypoints; ++i) person.keypoints[i] = {x[5 + 3 * i], x[6 + 3 * i], x[7 + 3 * i]};
    const double* a = v.data() + kFrameColumns + kMaxPersons * kPersonColumns + p * kAppearanceColumns;
    if (a[0] != 0.0 && a[0] != 1.0) return badValue(r, path, "detections: has_appearance must be 0 or 1");
    person.has_appearance = a[0] == 1.0;
    for (std::size_t b = 0; b < kAppearanceSignatureBins; ++b) {
      if (a[1 + b] < 0.0 || a[1 + b] > 1.0) return badValue(r, path, "detections: an appearance bin is not in [0, 1]");
      person.appearance[b] = static_cast<float>(a[1 + b]);
    }
  }
  return f;
}

const std::vector<std::string>& FrameIndexCodec::columns() {
  static const std::vector<std::string> kColumns = {"sequence", "file_index"};
  return kColumns;
}

std::vector<double> FrameIndexCodec::encode(const FrameIndexRow& row) {
  return {static_cast<double>(row.sequence), static_cast<double>(row.file_index)};
}

rt::Expected<FrameIndexRow> FrameIndexCodec::decode(const CsvRecord& r, const std::string& path) {
  auto sequence = wholeNumber(r, 0, path, "sequence");
  if (!sequence) return sequence.error();
  auto file_index = wholeNumber(r, 1, path, "file_index");
  if (!file_index) return file_index.error();
  return FrameIndexRow{static_cast<std::uint64_t>(*sequence), static_cast<std::uint64_t>(*file_index), r.stamp_ns};
}

}  // namespace aerotrack::hal::replay
