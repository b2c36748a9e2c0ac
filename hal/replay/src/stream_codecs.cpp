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

}  // namespace

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

}  // namespace aerotrack::hal::replay
