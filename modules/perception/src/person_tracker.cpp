// Lock-on to the followed person: see person_tracker.hpp.
#include "aerotrack/perception/person_tracker.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace aerotrack::perception {

rt::Status validate(const TrackerParams& p) {
  if (!(p.gate_torso_multiples > 0.0)) return rt::Error{"gate_torso_multiples: must be > 0"};
  if (!(p.max_torso_ratio > 1.0)) return rt::Error{"max_torso_ratio: must be > 1"};
  if (!(p.max_appearance_distance > 0.0 && p.max_appearance_distance <= 1.0))
    return rt::Error{"max_appearance_distance: must be in (0, 1]"};
  if (!(p.appearance_weight >= 0.0)) return rt::Error{"appearance_weight: must be >= 0"};
  if (!(p.lost_after_s > 0.0)) return rt::Error{"lost_after_s: must be > 0"};
  if (!(p.appearance_rate >= 0.0 && p.appearance_rate <= 1.0)) return rt::Error{"appearance_rate: must be in [0, 1]"};
  return rt::ok();
}

bool PersonTracker::locked(rt::TimeNs stamp_ns) const {
  return has_track_ && rt::nsToSeconds(stamp_ns - last_ns_) <= params_.lost_after_s;
}

std::optional<ImagePrediction> PersonTracker::predict(rt::TimeNs stamp_ns) const {
  if (!has_track_) return std::nullopt;
  // Extrapolate at most lost_after_s: beyond it a constant image velocity means nothing.
  const double dt_s = std::clamp(rt::nsToSeconds(stamp_ns - last_ns_), 0.0, params_.lost_after_s);
  ImagePrediction p = last_;
  p.u_px += du_pxps_ * dt_s;
  p.v_px += dv_pxps_ * dt_s;
  p.torso_px = std::max(1.0, p.torso_px + dtorso_pxps_ * dt_s);
  return p;
}

void PersonTracker::reset() {
  *this = PersonTracker(params_);
}

std::optional<std::size_t> PersonTracker::acquire(std::span<const TrackCandidate> candidates) const {
  std::optional<std::size_t> best;
  double best_value = -std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    const TrackCandidate& c = candidates[i];
    double value = 0.0;
    if (reference_.valid) {
      // Re-acquisition after a loss: only the person we lost, judged by appearance.
      const double d = appearanceDistance(reference_, c.appearance);
      if (d > params_.max_appearance_distance) continue;
      value = -d;
    } else {
      // First lock: the most confident person, the nearest (largest torso) breaking near-ties.
      value = c.score * std::sqrt(std::max(c.torso.torso_px, 1.0));
    }
    if (value > best_value) {
      best_value = value;
      best = i;
    }
  }
  return best;
}

void PersonTracker::accept(rt::TimeNs stamp_ns, const TrackCandidate& c) {
  const ImagePrediction now{c.torso.u_px, c.torso.v_px, c.torso.torso_px};
  if (has_track_) {
    const double dt_s = rt::nsToSeconds(stamp_ns - last_ns_);
    if (dt_s > 1e-3 && dt_s <= params_.lost_after_s) {
      // Smoothed finite difference: detections are noisy at a few percent of the torso.
      constexpr double kAlpha = 0.5;
      du_pxps_ = (1.0 - kAlpha) * du_pxps_ + kAlpha * (now.u_px - last_.u_px) / dt_s;
      dv_pxps_ = (1.0 - kAlpha) * dv_pxps_ + kAlpha * (now.v_px - last_.v_px) / dt_s;
      dtorso_pxps_ = (1.0 - kAlpha) * dtorso_pxps_ + kAlpha * (now.torso_px - last_.torso_px) / dt_s;
    } else {
      du_pxps_ = dv_pxps_ = dtorso_pxps_ = 0.0;
    }
  }
  has_track_ = true;
  last_ns_ = stamp_ns;
  last_ = now;
  blendAppearance(reference_, c.appearance, params_.appearance_rate);
}

void PersonTracker::reseat(rt::TimeNs stamp_ns, const TorsoFeatures& torso) {
  has_track_ = true;
  last_ns_ = stamp_ns;
  last_ = {torso.u_px, torso.v_px, torso.torso_px};
  du_pxps_ = dv_pxps_ = dtorso_pxps_ = 0.0;
}

std::optional<std::size_t> PersonTracker::update(rt::TimeNs stamp_ns, std::span<const TrackCandidate> candidates,
                                                 const std::optional<ImagePrediction>& external) {
  std::optional<ImagePrediction> prediction = external;
  if (!prediction && locked(stamp_ns)) prediction = predict(stamp_ns);

  std::optional<std::size_t> chosen;
  if (prediction) {
    double best_cost = std::numeric_limits<double>::infinity();
    const double torso_ref_px = std::max(prediction->torso_px, 1.0);
    for (std::size_t i = 0; i < candidates.size(); ++i) {
      const TrackCandidate& c = candidates[i];
      const double distance_torsos =
          std::hypot(c.torso.u_px - prediction->u_px, c.torso.v_px - prediction->v_px) / torso_ref_px;
      const double ratio = std::max(c.torso.torso_px, 1.0) / torso_ref_px;
      const double appearance = reference_.valid ? appearanceDistance(reference_, c.appearance) : 0.0;
      if (distance_torsos > params_.gate_torso_multiples) continue;
      if (ratio > params_.max_torso_ratio || ratio < 1.0 / params_.max_torso_ratio) continue;
      if (c.appearance.valid && appearance > params_.max_appearance_distance) continue;
      const double cost = distance_torsos / params_.gate_torso_multiples +
                          std::abs(std::log(ratio)) / std::log(params_.max_torso_ratio) +
                          params_.appearance_weight * appearance / params_.max_appearance_distance;
      if (cost < best_cost) {
        best_cost = cost;
        chosen = i;
      }
    }
    // Nothing passes the motion gate: the prediction may be wrong (a constant image velocity
    // across a fast gimbal turn or an occlusion; estimator drift). Re-identify by appearance at once
    // when the reference is known (acquire() then takes only the person who looks like the target),
    // rather than drop a visible target until the track times out; without a reference, only once
    // the track is lost.
    if (!chosen && (reference_.valid || !locked(stamp_ns))) chosen = acquire(candidates);
  } else {
    chosen = acquire(candidates);
  }
  if (chosen) accept(stamp_ns, candidates[*chosen]);
  return chosen;
}

}  // namespace aerotrack::perception
