// Tracks of the other people in view: see bystander_tracks.hpp.
#include "aerotrack/estimation/bystander_tracks.hpp"

#include <algorithm>
#include <limits>

namespace aerotrack::estimation {

rt::Expected<BystanderTracks> BystanderTracks::create(const TargetEstimatorParams& params, std::size_t capacity) {
  std::vector<Track> tracks;
  tracks.reserve(capacity);
  for (std::size_t i = 0; i < capacity; ++i) {
    auto filter = TargetEstimator::create(params);
    if (!filter) return filter.error();
    tracks.push_back(Track{std::move(filter.value()), false, false, 0, perception::Appearance{}, 0});
  }
  return BystanderTracks(std::move(tracks));
}

bool BystanderTracks::live(std::size_t i, rt::TimeNs t_ns) const {
  return position(i, t_ns).has_value();
}

std::optional<double> BystanderTracks::mahalanobisSq(std::size_t i, const TargetMeasurement& m) const {
  if (!live(i, m.stamp_ns)) return std::nullopt;
  return tracks_[i].filter.mahalanobisSq(m);
}

std::optional<TargetEstimator::Fit> BystanderTracks::fit(std::size_t i, const TargetMeasurement& m) const {
  if (!live(i, m.stamp_ns)) return std::nullopt;
  return tracks_[i].filter.fit(m);
}

std::optional<TargetEstimator::Fit> BystanderTracks::fitAcrossLine(std::size_t i, const TargetMeasurement& m) const {
  if (!live(i, m.stamp_ns)) return std::nullopt;
  return tracks_[i].filter.fitAcrossLine(m);
}

MeasurementVerdict BystanderTracks::update(std::size_t i, const TargetMeasurement& m,
                                           const perception::Appearance& look, double rate, bool with_followed) {
  const MeasurementVerdict verdict = tracks_[i].filter.add(m);
  if (verdict != MeasurementVerdict::kAccepted) return verdict;
  Track& t = tracks_[i];
  if (with_followed) t.seen_with_followed = true;
  if (!look.valid) return verdict;
  ++t.look_samples;
  perception::blendAppearance(t.look, look, std::max(rate, 1.0 / t.look_samples));
  return verdict;
}

std::size_t BystanderTracks::start(const TargetMeasurement& m, const perception::Appearance& look, bool with_followed) {
  std::size_t slot = 0;
  rt::TimeNs oldest_ns = std::numeric_limits<rt::TimeNs>::max();
  for (std::size_t i = 0; i < tracks_.size(); ++i) {
    if (!live(i, m.stamp_ns)) {
      slot = i;
      break;
    }
    const rt::TimeNs last_ns = tracks_[i].filter.estimate(m.stamp_ns).last_accepted_ns;
    if (last_ns < oldest_ns) {
      oldest_ns = last_ns;
      slot = i;
    }
  }
  Track& t = tracks_[slot];
  t.filter.reset();
  t.used = true;
  t.seen_with_followed = with_followed;
  t.started_ns = m.stamp_ns;
  t.look = look;
  t.look_samples = look.valid ? 1 : 0;
  (void)t.filter.add(m);  // the first measurement starts the filter
  return slot;
}

void BystanderTracks::drop(std::size_t i) {
  tracks_[i].filter.reset();
  tracks_[i].used = false;
  tracks_[i].seen_with_followed = false;
  tracks_[i].look = perception::Appearance{};
  tracks_[i].look_samples = 0;
}

std::size_t BystanderTracks::liveCount(rt::TimeNs t_ns) const {
  std::size_t n = 0;
  for (std::size_t i = 0; i < tracks_.size(); ++i) n += live(i, t_ns) ? 1 : 0;
  return n;
}

std::optional<Eigen::Vector3d> BystanderTracks::position(std::size_t i, rt::TimeNs t_ns) const {
  if (!tracks_[i].used) return std::nullopt;
  const TargetEstimate e = tracks_[i].filter.estimate(t_ns);
  if (!e.initialised || e.lost) return std::nullopt;
  return e.p_WT_m;
}

void BystanderTracks::fillOthers(rt::TimeNs t_ns, TargetEstimate& estimate) const {
  estimate.other_count = 0;
  for (const Track& track : tracks_) {
    if (!track.used || estimate.other_count == estimate.others.size()) continue;
    const TargetEstimate e = track.filter.estimate(t_ns);
    if (!e.initialised || e.lost) continue;
    estimate.others[estimate.other_count++] = {e.p_WT_m, e.v_WT_mps};
  }
}

}  // namespace aerotrack::estimation
