// Lock-on to the followed person (issue 5, item 3). The detector hands over every person it sees
// in a frame; the tracker picks the one it is following, so that a bystander who walks past does
// not steal the track. Each candidate is gated against a prediction of where the target should be
// in the image (its torso centre and length): a constant-velocity extrapolation of the last
// accepted observations in image space, or a prediction from the target estimator when the caller
// has one (the estimator knows the drone's and the gimbal's motion, which the image alone does
// not). Among the gated candidates the cost is position error, size error and appearance distance
// (torso colour, appearance.hpp), each normalised. Without a track the tracker acquires: before
// any lock, the most confident person with the largest torso; after a loss, only a person whose
// appearance matches the one it lost. While locked, if nobody passes the motion gate, the person
// who looks like the target is re-identified at once (issue 20: a constant image velocity does not
// predict a fast gimbal turn, and waiting out lost_after_s dropped a visible target for a second).
// Pure: time is passed in; no allocation.
#pragma once

#include <optional>
#include <span>

#include "aerotrack/perception/appearance.hpp"
#include "aerotrack/perception/torso_features.hpp"
#include "aerotrack/rt/expected.hpp"
#include "aerotrack/rt/time.hpp"

namespace aerotrack::perception {

struct TrackerParams {
  double gate_torso_multiples = 2.0;      ///< Torso centre within this many torso lengths of the prediction.
  double max_torso_ratio = 1.6;           ///< Torso length within [1/r, r] x the predicted.
  double max_appearance_distance = 0.45;  ///< Bhattacharyya; above it a candidate is someone else.
  double appearance_weight = 2.0;         ///< Cost weight of the appearance distance.
  double lost_after_s = 1.0;              ///< No accepted observation for this long: the track is lost.
  double appearance_rate = 0.1;           ///< How fast the reference appearance follows the target.
};
rt::Status validate(const TrackerParams& params);

struct TrackCandidate {
  TorsoFeatures torso;
  Appearance appearance;
  double score = 0.0;  ///< Person confidence.
};

/// Where the target is expected in the image.
struct ImagePrediction {
  double u_px = 0.0, v_px = 0.0;  ///< Torso centre.
  double torso_px = 0.0;
};

class PersonTracker {
 public:
  explicit PersonTracker(const TrackerParams& params) : params_(params) {}

  /// Chooses the target among this frame's candidates (image stamped stamp_ns); returns its index
  /// or nothing. external, if given, replaces the tracker's own image-space prediction.
  std::optional<std::size_t> update(rt::TimeNs stamp_ns, std::span<const TrackCandidate> candidates,
                                    const std::optional<ImagePrediction>& external = std::nullopt);

  /// Someone who knows better (the target estimator) judged the target in the image stamped stamp_ns to be
  /// the person with this torso: the track goes on from them, its image velocity unknown (zero), its
  /// reference appearance kept.
  void reseat(rt::TimeNs stamp_ns, const TorsoFeatures& torso);
  /// True while the target was accepted within lost_after_s of stamp_ns.
  bool locked(rt::TimeNs stamp_ns) const;
  /// The tracker's own prediction of the target at stamp_ns; nothing before the first lock.
  std::optional<ImagePrediction> predict(rt::TimeNs stamp_ns) const;
  /// The reference appearance of the target (invalid before the first lock).
  const Appearance& appearance() const { return reference_; }
  /// Forget everything, including the appearance (a new target will be chosen).
  void reset();

 private:
  std::optional<std::size_t> acquire(std::span<const TrackCandidate> candidates) const;
  void accept(rt::TimeNs stamp_ns, const TrackCandidate& c);

  TrackerParams params_;
  bool has_track_ = false;
  rt::TimeNs last_ns_ = 0;
  ImagePrediction last_{};
  double du_pxps_ = 0.0, dv_pxps_ = 0.0, dtorso_pxps_ = 0.0;  ///< Image-space velocity estimate.
  Appearance reference_;
};

}  // namespace aerotrack::perception
