// Lock-on for detection-delivering cameras: see keypoint_lock_on.hpp.
#include "aerotrack/perception/keypoint_lock_on.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <span>

namespace aerotrack::perception {

Appearance toAppearance(const hal::PersonDetection& person) {
  Appearance a;
  if (!person.has_appearance) return a;
  for (const float bin : person.appearance) {
    if (!(bin >= 0.0F) || !std::isfinite(bin)) return a;  // negative or NaN: not a histogram
  }
  // Renormalise each measured region: the Bhattacharyya distance assumes histograms that sum to 1.
  for (std::size_t r = 0; r < hal::kSignatureRegions; ++r) {
    const auto region = static_cast<hal::SignatureRegion>(r);
    const double total = hal::regionSum(person.appearance, region);
    if (!(total > 0.0)) continue;
    const std::size_t offset = hal::regionOffset(region);
    for (std::size_t i = offset; i < offset + hal::kSignatureRegionBins; ++i)
      a.histogram[i] = static_cast<float>(static_cast<double>(person.appearance[i]) / total);
    a.valid = true;
  }
  return a;
}

void KeypointLockOn::apply(hal::DetectionFrame& frame) {
  const std::size_t count = std::min(frame.person_count, hal::kMaxPersons);
  if (frame.target_index >= static_cast<int>(count)) frame.target_index = -1;  // names no listed person
  std::array<TrackCandidate, hal::kMaxPersons> candidates{};
  for (std::size_t i = 0; i < count; ++i) {
    const hal::PersonDetection& person = frame.persons[i];
    candidates[i].torso =
        torsoFeatures(person.keypoints, frame.intrinsics.width_px, frame.intrinsics.height_px, torso_);
    candidates[i].appearance = toAppearance(person);
    candidates[i].score = person.score;
  }
  if (frame.target_index >= 0) {
    // Designated (or chosen upstream): the tracker learns this person -- position, size, appearance --
    // and follows them on its own in the frames that leave the choice open.
    const auto target = static_cast<std::size_t>(frame.target_index);
    tracker_.update(frame.stamp_ns, std::span(candidates.data() + target, 1));
    return;
  }
  const auto chosen = tracker_.update(frame.stamp_ns, std::span(candidates.data(), count));
  frame.target_index = chosen ? static_cast<int>(*chosen) : -1;
}

}  // namespace aerotrack::perception
