// Tracks of the other people in view (issue 22 item 2: the followed person never swapped for a
// bystander). A single track, gated on its own prediction, takes in whoever comes near enough once
// its covariance has grown while the person is hidden: a look-alike standing 1.25 m beside the path
// after 0.7 s (target_task_association_test.cpp). Tracking everyone else as well, in the same world
// frame and with the same constant-velocity filter (target_estimator.hpp), turns each choice into an
// assignment (global nearest neighbour): a bystander's measurement goes to the bystander's own track,
// whose prediction it fits better, and the hidden person's track coasts until they reappear.
//
// A track also remembers whether it was updated in a frame where the followed person was measured
// too: such a person is someone else, whatever their colour or position later (the re-identification
// after a loss may take over only a track never seen beside the followed person).
//
// A track's colour is the mean of its first frames until there are 1/rate of them, then a running blend at
// `rate` (as the followed person's colour spread is learnt): blended at `rate` from the first frame, a young
// track's colour was its first crop's, which in a crowd holds parts of the people beside them (traced: crowd
// seed 80, the look-alike's own next frames 0.23-0.37 from their three-frame colour).
#pragma once

#include <cstddef>
#include <optional>
#include <vector>

#include "aerotrack/estimation/target_estimator.hpp"
#include "aerotrack/perception/appearance.hpp"
#include "aerotrack/rt/expected.hpp"

namespace aerotrack::estimation {

class BystanderTracks {
 public:
  /// `capacity` filters of `params` (each with its buffer: all allocation happens here). A track is
  /// live until lost_after_s without a measurement; then its slot is free.
  static rt::Expected<BystanderTracks> create(const TargetEstimatorParams& params, std::size_t capacity);

  std::size_t capacity() const { return tracks_.size(); }
  /// Track `i` is live at t_ns (started and not lost).
  bool live(std::size_t i, rt::TimeNs t_ns) const;
  /// Live track i's predicted position at t_ns; nothing if it is not live.
  std::optional<Eigen::Vector3d> position(std::size_t i, rt::TimeNs t_ns) const;
  /// The squared Mahalanobis distance of m from live track i's prediction (TargetEstimator::mahalanobisSq).
  std::optional<double> mahalanobisSq(std::size_t i, const TargetMeasurement& m) const;
  /// The same with ln|S| (TargetEstimator::fit).
  std::optional<TargetEstimator::Fit> fit(std::size_t i, const TargetMeasurement& m) const;
  /// ... across a bearing's line of sight (TargetEstimator::fitAcrossLine).
  std::optional<TargetEstimator::Fit> fitAcrossLine(std::size_t i, const TargetMeasurement& m) const;
  /// Updates live track i with m (its own gate applies) and blends `look` into its colour at `rate` (at
  /// 1/n for its n-th colour while that is larger); `with_followed`: the followed person was measured in the
  /// same frame.
  MeasurementVerdict update(std::size_t i, const TargetMeasurement& m, const perception::Appearance& look, double rate,
                            bool with_followed);
  /// Starts a track at m, of colour `look`, in a free slot (or the one measured longest ago); returns its index.
  std::size_t start(const TargetMeasurement& m, const perception::Appearance& look, bool with_followed);
  /// The torso colour learnt for track i (invalid if none was seen).
  const perception::Appearance& look(std::size_t i) const { return tracks_[i].look; }
  /// How many frames track i's colour was learnt from.
  int lookSamples(std::size_t i) const { return tracks_[i].look_samples; }
  /// Track i was measured in a frame where the followed person was too.
  bool seenWithFollowed(std::size_t i) const { return tracks_[i].seen_with_followed; }
  /// When track i was started (the capture time of its first measurement).
  rt::TimeNs startedNs(std::size_t i) const { return tracks_[i].started_ns; }
  /// Forgets track i (its measurements are the followed person's after all).
  void drop(std::size_t i);
  /// Live tracks at t_ns.
  std::size_t liveCount(rt::TimeNs t_ns) const;
  /// Writes the live tracks' states at t_ns into estimate.others (as many as fit) and their number.
  void fillOthers(rt::TimeNs t_ns, TargetEstimate& estimate) const;

 private:
  struct Track {
    TargetEstimator filter;
    bool used = false;
    bool seen_with_followed = false;
    rt::TimeNs started_ns = 0;
    perception::Appearance look;
    int look_samples = 0;
  };
  explicit BystanderTracks(std::vector<Track> tracks) : tracks_(std::move(tracks)) {}
  std::vector<Track> tracks_;
};

}  // namespace aerotrack::estimation
