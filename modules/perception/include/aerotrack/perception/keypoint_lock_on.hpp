// Lock-on for cameras that deliver detections rather than images (issue 20): the simulator's
// keypoint mode, or a camera with its own detector. Such a device reports every person it sees, in
// no particular order and without saying which one is followed (target_index < 0), each with a
// measured appearance signature (hal::PersonDetection::appearance). This stage makes the same choice
// the image pipeline's Detector::track makes (person_tracker.hpp: gating on the predicted torso
// position and size, appearance distance, re-acquisition of the lost person by appearance), so that
// a bystander can steal the track here exactly as on a real camera -- which is what the closed-loop
// identity metrics measure. Pure: time comes from the frames' stamps; no allocation.
#pragma once

#include "aerotrack/hal/types.hpp"
#include "aerotrack/perception/person_tracker.hpp"
#include "aerotrack/perception/torso_features.hpp"

namespace aerotrack::perception {

/// A detection's signature as the tracker's appearance (invalid without one).
Appearance toAppearance(const hal::PersonDetection& person);

class KeypointLockOn {
 public:
  KeypointLockOn(const TrackerParams& tracker, const TorsoFeatureParams& torso) : tracker_(tracker), torso_(torso) {}

  /// Chooses the followed person of a frame whose device left the choice open (target_index < 0)
  /// and writes it into target_index (-1 if none passes). A frame that names its target (an operator's
  /// designation before the start; a recording made before this stage existed) keeps it, and the
  /// tracker locks onto that person, to follow them in the frames that do not.
  void apply(hal::DetectionFrame& frame);

  const PersonTracker& tracker() const { return tracker_; }

 private:
  PersonTracker tracker_;
  TorsoFeatureParams torso_;
};

}  // namespace aerotrack::perception
