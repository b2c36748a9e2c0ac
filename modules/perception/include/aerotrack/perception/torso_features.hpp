// The distance features of the paper's localization (Sect. IV-B): the torso length L_t, from the
// neck (midpoint of the shoulders) to the mid-hip, and the person's horizontal image position u_t.
// A distance is only as good as the four torso joints behind it, so each result carries a
// reliability flag and, when unreliable, the reason: a joint with a low score, or a joint on the
// image border -- MoveNet clamps joints of a person cut off by the frame to the border, and such a
// torso is too short, which the regression would read as a person too far away (issue 5, item 4).
// A person cut off at the waist is subtler: the network guesses the hips a few pixels inside the
// bottom edge with scores of 0.35-0.5 (messi5.jpg cut at rows 152-212: hips 7-15 px above the edge,
// torso 32-83 px against 116 uncut), so near the top and bottom edges the margin grows with the torso
// (issue 22, item 4) -- for joints scored as guesses; a confident joint near the edge is a real one. When
// the torso is unreliable but one joint pair (shoulders, else hips) is
// whole, its midpoint still gives the person's bearing (the estimator's fallback).
#pragma once

#include <array>
#include <string_view>

#include "aerotrack/hal/types.hpp"

namespace aerotrack::perception {

struct TorsoFeatureParams {
  double min_joint_score = 0.3;   ///< Each of the four torso joints needs at least this score.
  double border_margin_px = 4.0;  ///< A torso joint closer than this to the image edge is "on the border".
  /// ... or, scored under edge_guess_max_score, closer than this many torso lengths (or shoulder or hip
  /// widths, if larger) to the top or bottom edge, where a cut-off body's guessed joints land (0: the
  /// pixel margin alone).
  double edge_margin_torso_fraction = 0.5;
  /// A joint scored at least this is taken where the network puts it, however near the top or bottom: a
  /// person standing close to a low camera has confident shoulders near the top. Guesses scored 0.31-0.47.
  double edge_guess_max_score = 0.5;
  double min_torso_px = 1.0;  ///< A shorter torso (degenerate) is unreliable.
};

enum class TorsoReason : std::uint8_t { kOk, kLowScore, kOnBorder, kTooShort };

/// "ok", "low_score", "on_border", "too_short".
std::string_view toString(TorsoReason reason);

struct TorsoFeatures {
  double torso_px = 0.0;  ///< Neck to mid-hip length, pixels.
  double u_px = 0.0;      ///< Horizontal centre of the torso (midpoint of neck and mid-hip), pixels.
  double v_px = 0.0;      ///< Vertical centre of the torso, pixels.
  bool reliable = false;
  TorsoReason reason = TorsoReason::kLowScore;
  hal::CocoKeypoint culprit = hal::CocoKeypoint::kLeftShoulder;  ///< The joint behind an unreliable verdict.
  /// A whole joint pair (both scores and positions pass, shoulders first, else hips) whose midpoint
  /// gives the person's bearing; set whether or not the torso is reliable.
  bool bearing_ok = false;
  double bearing_u_px = 0.0;           ///< That pair's horizontal midpoint, pixels.
  bool bearing_from_shoulders = true;  ///< Which pair gave it (when bearing_ok).
};

/// Features of one detection in an image of width_px x height_px. Pure, allocation-free.
TorsoFeatures torsoFeatures(const std::array<hal::Keypoint2D, hal::kNumKeypoints>& keypoints, int width_px,
                            int height_px, const TorsoFeatureParams& params);

/// The features' measurements (torso_px, u_px, v_px, bearing_u_px from the pair `verdicts` took its bearing
/// from) taken from `moved`, the same keypoints moved to other pixels (a level camera's image, issue 22 item 3);
/// the verdicts (reliable, reason, culprit, bearing_ok), judged in the image the network saw, are kept. Pure.
TorsoFeatures remeasured(const TorsoFeatures& verdicts, const std::array<hal::Keypoint2D, hal::kNumKeypoints>& moved);

/// COCO name of a joint ("left_hip"), for reasons printed to people.
std::string_view keypointName(hal::CocoKeypoint k);

}  // namespace aerotrack::perception
