// Prints MAVLink v2 frames made by our codec (hal/protocol/mavlink.hpp), for tools/mavlink/check.js to
// decode with node-mavlink, an independent implementation (issue 11 item 4). One line per frame:
//   NAME HEX {"field": value, ...}
// with node-mavlink's field names. Values are drawn from a fixed seed, across each field's range
// (floats of every magnitude and sign, full-width integers), so a wrong offset, width, byte order,
// CRC_EXTRA or payload truncation shows as a mismatch. usage: mavlink_frames [COUNT_PER_MESSAGE]
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "aerotrack/hal/protocol/mavlink.hpp"

namespace mav = aerotrack::hal::protocol::mavlink;

namespace {

class Draw {
 public:
  float real() {
    // A mix of magnitudes, and exact zeros (they exercise the v2 payload truncation at the end).
    const int kind = static_cast<int>(rng_() % 4);
    if (kind == 0) return 0.0F;
    std::uniform_real_distribution<float> u(-1.0F, 1.0F);
    const float scale = kind == 1 ? 1.0F : (kind == 2 ? 1000.0F : 1e-3F);
    return u(rng_) * scale;
  }
  template <class T>
  T integer() {
    return static_cast<T>(rng_() % 3 == 0 ? 0 : rng_());
  }

 private:
  std::mt19937_64 rng_{20261123};
};

std::string hex(const std::vector<std::uint8_t>& bytes) {
  std::string s;
  char b[3];
  for (const std::uint8_t x : bytes) {
    std::snprintf(b, sizeof(b), "%02x", x);
    s += b;
  }
  return s;
}

// Every field of a frame, a float or an integer, printed through a double: exact for every float and every
// integer below 2^53 (the conversion is explicit, so a float is not promoted silently: -Wdouble-promotion).
template <class T>
std::string num(T v) {
  char b[40];
  std::snprintf(b, sizeof(b), "%.17g", static_cast<double>(v));
  return b;
}

std::string list(const float* v, std::size_t n) {
  std::string s = "[";
  for (std::size_t i = 0; i < n; ++i) s += (i ? "," : "") + num(v[i]);
  return s + "]";
}

void print(const char* name, std::uint32_t id, const std::vector<std::uint8_t>& payload, std::uint8_t sequence,
           const std::string& fields) {
  const mav::Sender sender{1, 191};
  std::printf("%s %s {%s}\n", name, hex(mav::frame(id, payload, sender, sequence)).c_str(), fields.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  const int count = argc > 1 ? std::atoi(argv[1]) : 50;
  if (count < 1 || count > 100000) {
    std::fprintf(stderr, "mavlink_frames: COUNT_PER_MESSAGE must be 1..100000\n");
    return 1;
  }
  Draw d;
  std::uint8_t sequence = 0;
  for (int i = 0; i < count; ++i) {
    mav::Heartbeat h;
    h.custom_mode = d.integer<std::uint32_t>();
    h.type = d.integer<std::uint8_t>();
    h.autopilot = d.integer<std::uint8_t>();
    h.base_mode = d.integer<std::uint8_t>();
    h.system_status = d.integer<std::uint8_t>();
    print("HEARTBEAT", mav::kHeartbeat, mav::encodePayload(h), sequence++,
          "\"customMode\":" + num(h.custom_mode) + ",\"type\":" + num(h.type) + ",\"autopilot\":" + num(h.autopilot) +
              ",\"baseMode\":" + num(h.base_mode) + ",\"systemStatus\":" + num(h.system_status) +
              ",\"mavlinkVersion\":3");

    mav::SetPositionTargetLocalNed s;
    s.time_boot_ms = d.integer<std::uint32_t>();
    s.target_system = d.integer<std::uint8_t>();
    s.target_component = d.integer<std::uint8_t>();
    s.coordinate_frame = d.integer<std::uint8_t>();
    s.type_mask = d.integer<std::uint16_t>();
    const float sf[] = {d.real(), d.real(), d.real(), d.real(), d.real(), d.real(),
                        d.real(), d.real(), d.real(), d.real(), d.real()};
    s.x = sf[0], s.y = sf[1], s.z = sf[2], s.vx = sf[3], s.vy = sf[4], s.vz = sf[5];
    s.afx = sf[6], s.afy = sf[7], s.afz = sf[8], s.yaw = sf[9], s.yaw_rate = sf[10];
    print("SET_POSITION_TARGET_LOCAL_NED", mav::kSetPositionTargetLocalNed, mav::encodePayload(s), sequence++,
          "\"timeBootMs\":" + num(s.time_boot_ms) + ",\"targetSystem\":" + num(s.target_system) +
              ",\"targetComponent\":" + num(s.target_component) + ",\"coordinateFrame\":" + num(s.coordinate_frame) +
              ",\"typeMask\":" + num(s.type_mask) + ",\"x\":" + num(s.x) + ",\"y\":" + num(s.y) + ",\"z\":" + num(s.z) +
              ",\"vx\":" + num(s.vx) + ",\"vy\":" + num(s.vy) + ",\"vz\":" + num(s.vz) + ",\"afx\":" + num(s.afx) +
              ",\"afy\":" + num(s.afy) + ",\"afz\":" + num(s.afz) + ",\"yaw\":" + num(s.yaw) +
              ",\"yawRate\":" + num(s.yaw_rate));

    mav::LocalPositionNed l;
    l.time_boot_ms = d.integer<std::uint32_t>();
    l.x = d.real(), l.y = d.real(), l.z = d.real(), l.vx = d.real(), l.vy = d.real(), l.vz = d.real();
    print("LOCAL_POSITION_NED", mav::kLocalPositionNed, mav::encodePayload(l), sequence++,
          "\"timeBootMs\":" + num(l.time_boot_ms) + ",\"x\":" + num(l.x) + ",\"y\":" + num(l.y) + ",\"z\":" + num(l.z) +
              ",\"vx\":" + num(l.vx) + ",\"vy\":" + num(l.vy) + ",\"vz\":" + num(l.vz));

    mav::Attitude a;
    a.time_boot_ms = d.integer<std::uint32_t>();
    a.roll = d.real(), a.pitch = d.real(), a.yaw = d.real();
    a.rollspeed = d.real(), a.pitchspeed = d.real(), a.yawspeed = d.real();
    print("ATTITUDE", mav::kAttitude, mav::encodePayload(a), sequence++,
          "\"timeBootMs\":" + num(a.time_boot_ms) + ",\"roll\":" + num(a.roll) + ",\"pitch\":" + num(a.pitch) +
              ",\"yaw\":" + num(a.yaw) + ",\"rollspeed\":" + num(a.rollspeed) + ",\"pitchspeed\":" + num(a.pitchspeed) +
              ",\"yawspeed\":" + num(a.yawspeed));

    mav::Odometry o;
    o.time_usec = d.integer<std::uint32_t>() * 1000ULL;  // exact in a JSON number (< 2^53)
    o.x = d.real(), o.y = d.real(), o.z = d.real();
    for (float& q : o.q) q = d.real();
    o.vx = d.real(), o.vy = d.real(), o.vz = d.real();
    o.rollspeed = d.real(), o.pitchspeed = d.real(), o.yawspeed = d.real();
    for (float& c : o.pose_covariance) c = d.real();
    for (float& c : o.velocity_covariance) c = d.real();
    o.frame_id = d.integer<std::uint8_t>();
    o.child_frame_id = d.integer<std::uint8_t>();
    o.reset_counter = d.integer<std::uint8_t>();
    o.estimator_type = d.integer<std::uint8_t>();
    o.quality = static_cast<std::int8_t>(d.integer<std::uint8_t>() % 101);
    print("ODOMETRY", mav::kOdometry, mav::encodePayload(o), sequence++,
          "\"timeUsec\":" + num(static_cast<double>(o.time_usec)) + ",\"x\":" + num(o.x) + ",\"y\":" + num(o.y) +
              ",\"z\":" + num(o.z) + ",\"q\":" + list(o.q.data(), 4) + ",\"vx\":" + num(o.vx) + ",\"vy\":" + num(o.vy) +
              ",\"vz\":" + num(o.vz) + ",\"rollspeed\":" + num(o.rollspeed) + ",\"pitchspeed\":" + num(o.pitchspeed) +
              ",\"yawspeed\":" + num(o.yawspeed) + ",\"poseCovariance\":" + list(o.pose_covariance.data(), 21) +
              ",\"velocityCovariance\":" + list(o.velocity_covariance.data(), 21) + ",\"frameId\":" + num(o.frame_id) +
              ",\"childFrameId\":" + num(o.child_frame_id) + ",\"resetCounter\":" + num(o.reset_counter) +
              ",\"estimatorType\":" + num(o.estimator_type) + ",\"quality\":" + num(o.quality));
  }
  return 0;
}
