// Torso length, horizontal position and reliability: see torso_features.hpp.
#include "aerotrack/perception/torso_features.hpp"

#include <algorithm>
#include <cmath>

namespace aerotrack::perception {

using hal::CocoKeypoint;
using hal::index;

std::string_view toString(TorsoReason reason) {
  switch (reason) {
    case TorsoReason::kOk:
      return "ok";
    case TorsoReason::kLowScore:
      return "low_score";
    case TorsoReason::kOnBorder:
      return "on_border";
    case TorsoReason::kTooShort:
      return "too_short";
  }
  return "unknown";
}

std::string_view keypointName(CocoKeypoint k) {
  static constexpr std::array<std::string_view, hal::kNumKeypoints> kNames = {
      "nose",           "left_eye",   "right_eye",   "left_ear",   "right_ear",   "left_shoulder",
      "right_shoulder", "left_elbow", "right_elbow", "left_wrist", "right_wrist", "left_hip",
      "right_hip",      "left_knee",  "right_knee",  "left_ankle", "right_ankle"};
  return kNames[index(k)];
}

namespace {

struct TorsoGeometry {
  double torso_px, u_px, v_px, neck_u_px, hip_u_px;
};

TorsoGeometry torsoGeometry(const std::array<hal::Keypoint2D, hal::kNumKeypoints>& keypoints) {
  const hal::Keypoint2D& ls = keypoints[index(CocoKeypoint::kLeftShoulder)];
  const hal::Keypoint2D& rs = keypoints[index(CocoKeypoint::kRightShoulder)];
  const hal::Keypoint2D& lh = keypoints[index(CocoKeypoint::kLeftHip)];
  const hal::Keypoint2D& rh = keypoints[index(CocoKeypoint::kRightHip)];
  const double neck_u = 0.5 * (ls.u_px + rs.u_px);
  const double neck_v = 0.5 * (ls.v_px + rs.v_px);
  const double hip_u = 0.5 * (lh.u_px + rh.u_px);
  const double hip_v = 0.5 * (lh.v_px + rh.v_px);
  return {std::hypot(neck_u - hip_u, neck_v - hip_v), 0.5 * (neck_u + hip_u), 0.5 * (neck_v + hip_v), neck_u, hip_u};
}

}  // namespace

TorsoFeatures remeasured(const TorsoFeatures& verdicts, const std::array<hal::Keypoint2D, hal::kNumKeypoints>& moved) {
  const TorsoGeometry g = torsoGeometry(moved);
  TorsoFeatures f = verdicts;
  f.torso_px = g.torso_px;
  f.u_px = g.u_px;
  f.v_px = g.v_px;
  f.bearing_u_px = f.bearing_from_shoulders ? g.neck_u_px : g.hip_u_px;
  return f;
}

TorsoFeatures torsoFeatures(const std::array<hal::Keypoint2D, hal::kNumKeypoints>& keypoints, int width_px,
                            int height_px, const TorsoFeatureParams& params) {
  const hal::Keypoint2D& ls = keypoints[index(CocoKeypoint::kLeftShoulder)];
  const hal::Keypoint2D& rs = keypoints[index(CocoKeypoint::kRightShoulder)];
  const hal::Keypoint2D& lh = keypoints[index(CocoKeypoint::kLeftHip)];
  const hal::Keypoint2D& rh = keypoints[index(CocoKeypoint::kRightHip)];
  const TorsoGeometry g = torsoGeometry(keypoints);

  TorsoFeatures f;
  f.torso_px = g.torso_px;
  f.u_px = g.u_px;
  f.v_px = g.v_px;

  // The vertical margin scales with the body as measured: a waist cut shortens the torso, but the guessed
  // hips then lie within a fraction of even the shortened torso of the edge (the header's numbers). A cut
  // at the chest puts shoulders and hips all just inside the edge, and the torso between them comes out a
  // few pixels long; the shoulders' and hips' widths, which a cut does not shorten, keep the margin then.
  const double span_px =
      std::max(std::hypot(ls.u_px - rs.u_px, ls.v_px - rs.v_px), std::hypot(lh.u_px - rh.u_px, lh.v_px - rh.v_px));
  const double margin_u_px = params.border_margin_px;
  const double margin_v_px =
      std::max(params.border_margin_px, params.edge_margin_torso_fraction * std::max(f.torso_px, span_px));
  const auto low_score = [&](CocoKeypoint k) { return keypoints[index(k)].score < params.min_joint_score; };
  const auto on_border = [&](CocoKeypoint k) {
    const hal::Keypoint2D& p = keypoints[index(k)];
    const double margin_px = p.score < params.edge_guess_max_score ? margin_v_px : params.border_margin_px;
    return p.u_px < margin_u_px || p.v_px < margin_px || p.u_px > width_px - margin_u_px ||
           p.v_px > height_px - margin_px;
  };
  const auto whole = [&](CocoKeypoint a, CocoKeypoint b) {
    return !low_score(a) && !low_score(b) && !on_border(a) && !on_border(b);
  };
  if (whole(CocoKeypoint::kLeftShoulder, CocoKeypoint::kRightShoulder)) {
    f.bearing_ok = true;
    f.bearing_u_px = g.neck_u_px;
  } else if (whole(CocoKeypoint::kLeftHip, CocoKeypoint::kRightHip)) {
    f.bearing_ok = true;
    f.bearing_u_px = g.hip_u_px;
    f.bearing_from_shoulders = false;
  }

  constexpr std::array<CocoKeypoint, 4> kTorso = {CocoKeypoint::kLeftShoulder, CocoKeypoint::kRightShoulder,
                                                  CocoKeypoint::kLeftHip, CocoKeypoint::kRightHip};
  for (CocoKeypoint k : kTorso)
    if (low_score(k)) {
      f.reason = TorsoReason::kLowScore;
      f.culprit = k;
      return f;
    }
  for (CocoKeypoint k : kTorso)
    if (on_border(k)) {
      f.reason = TorsoReason::kOnBorder;
      f.culprit = k;
      return f;
    }
  if (!(f.torso_px >= params.min_torso_px)) {
    f.reason = TorsoReason::kTooShort;
    return f;
  }
  f.reliable = true;
  f.reason = TorsoReason::kOk;
  return f;
}

}  // namespace aerotrack::perception
