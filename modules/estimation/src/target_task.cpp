// The target pipeline task: see target_task.hpp.
#include "aerotrack/estimation/target_task.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "aerotrack/estimation/assignment.hpp"

namespace aerotrack::estimation {

void parseTargetTaskParams(const rt::ConfigNode& node, TargetTaskParams& params) {
  params.extrinsics = parseGimbalCameraExtrinsics(node.child("gimbal_camera"));
  params.measurement_std_per_m = node.getDouble("measurement_std_per_m", 0.0, 1.0);
  params.min_measurement_std_m = node.getDouble("min_measurement_std_m", 0.001, 10.0);
  params.max_wait_ns = rt::secondsToNs(node.getDouble("max_wait_s", 0.0, 2.0));
  params.bearing_fallback = node.getEnum("unreliable_torso", {"bearing", "skip"}) == "bearing";
  params.look_gate_sigmas = node.getDoubleOr("look_gate_sigmas", params.look_gate_sigmas, 0.0, 100.0);
  params.look_gate_confirm_s = node.getDoubleOr("look_gate_confirm_s", params.look_gate_confirm_s, 0.0, 60.0);
  params.look_gate_after_loss = node.getBoolOr("look_gate_after_loss", params.look_gate_after_loss);
  params.choose_by_estimate = node.getEnum("association", {"estimate", "lock_on"}) == "estimate";
  params.in_front_after_ranged = node.getIntOr("in_front_after_ranged", params.in_front_after_ranged, 0, 1000);
  params.in_front_streak_spans_unseen =
      node.getBoolOr("in_front_streak_spans_unseen", params.in_front_streak_spans_unseen);
  params.in_front_unseen_limit = node.getIntOr("in_front_unseen_limit", params.in_front_unseen_limit, 0, 1000);
  params.in_front_gate_chi2 = node.getDoubleOr("in_front_gate_chi2", params.in_front_gate_chi2, 0.0, 1000.0);
  params.in_front_doubtful_starts_track =
      node.getBoolOr("in_front_doubtful_starts_track", params.in_front_doubtful_starts_track);
  if (node.has("in_front_test"))
    params.in_front_test = node.getEnum("in_front_test", {"nearer", "gate"}) == "gate"
                               ? TargetTaskParams::InFrontTest::kGate
                               : TargetTaskParams::InFrontTest::kNearer;
  params.hidden_behind_m = node.getDoubleOr("hidden_behind_m", params.hidden_behind_m, 0.0, 5.0);
  params.depth_vets_bearings = node.getBoolOr("depth_vets_bearings", params.depth_vets_bearings);
  params.bearing_by_likelihood = node.getBoolOr("bearing_by_likelihood", params.bearing_by_likelihood);
  params.refused_alone_frames = node.getIntOr("refused_alone_frames", params.refused_alone_frames, 0, 100);
  params.look_refused_off_tracks = node.getBoolOr("look_refused_off_tracks", params.look_refused_off_tracks);
  params.lost_competing_colour_capped =
      node.getBoolOr("lost_competing_colour_capped", params.lost_competing_colour_capped);
  params.verdict_torso_height_m = node.getDoubleOr("verdict_torso_height_m", params.verdict_torso_height_m, 0.1, 3.0);
  params.verdict_torso_m = node.getDoubleOr("verdict_torso_m", params.verdict_torso_m, 0.1, 2.0);
  params.estimator = parseTargetEstimatorParams(node.child("estimator"));
  if (node.has("depth_range")) params.depth_range = parseDepthRangeParams(node.child("depth_range"));
  if (node.has("depth_people")) params.depth_people = parseDepthPeopleParams(node.child("depth_people"));
  if (node.has("swap_check")) params.swap_check = parseSwapCheckParams(node.child("swap_check"));
}

rt::Expected<TargetTask> TargetTask::create(const TargetTaskParams& params,
                                            rt::SpscQueue<hal::DetectionFrame>& detections,
                                            rt::SpscQueue<hal::OdometrySample>& odometry,
                                            rt::SpscQueue<hal::GimbalState>& gimbal,
                                            rt::LatestSlot<TargetEstimate>& out) {
  if (auto s = localization::validate(params.localization); !s) return rt::Error{"localization: " + s.error().message};
  if (auto s = validate(params.depth_range); !s) return s.error();
  if (auto s = validate(params.depth_people); !s) return s.error();
  auto poses = hal::OdometryHistory::create({});
  if (!poses) return poses.error();
  auto gimbal_history = GimbalAngleHistory::create({});
  if (!gimbal_history) return gimbal_history.error();
  auto estimator = TargetEstimator::create(params.estimator);
  if (!estimator) return rt::Error{"estimator: " + estimator.error().message};
  auto bystanders = BystanderTracks::create(params.estimator, params.choose_by_estimate ? kMaxBystanderTracks : 0);
  if (!bystanders) return rt::Error{"bystander tracks: " + bystanders.error().message};
  SwapCheckParams swap = params.swap_check;
  if (!params.choose_by_estimate) swap.frames = 0;  // no other tracks to swap with
  auto swap_check = SwapCheck::create(swap, params.estimator);
  if (!swap_check) return swap_check.error();
  return TargetTask(params, std::move(poses.value()), std::move(gimbal_history.value()), std::move(estimator.value()),
                    std::move(bystanders.value()), std::move(swap_check.value()), detections, odometry, gimbal, out);
}

TargetTask::TargetTask(const TargetTaskParams& params, hal::OdometryHistory poses, GimbalAngleHistory gimbal_history,
                       TargetEstimator estimator, BystanderTracks bystanders, SwapCheck swap_check,
                       rt::SpscQueue<hal::DetectionFrame>& detections, rt::SpscQueue<hal::OdometrySample>& odometry,
                       rt::SpscQueue<hal::GimbalState>& gimbal, rt::LatestSlot<TargetEstimate>& out)
    : params_(params),
      poses_(std::move(poses)),
      gimbal_history_(std::move(gimbal_history)),
      estimator_(std::move(estimator)),
      detections_(detections),
      odometry_(odometry),
      gimbal_(gimbal),
      out_(out),
      bystanders_(std::move(bystanders)),
      swap_check_(std::move(swap_check)),
      depth_people_(params.depth_people) {}

Eigen::Vector3d TargetTask::localize(const perception::TorsoFeatures& torso, const Eigen::Isometry3d& T_WC,
                                     Eigen::Vector3d& p_C_m) const {
  p_C_m = localization::predict(params_.localization, torso.torso_px, torso.u_px);
  // The regression was fitted on a level camera: read its output in the level frame.
  return cameraToWorld(p_C_m, T_WC, CameraFrame::kLevel);
}

double TargetTask::measurementStdM(const Eigen::Vector3d& p_C_m) const {
  // The regression's own noise where its fit measured one (issue 22 item 3: the network scatters three times as
  // much as the keypoint camera), else the configured one.
  const localization::LocalizationParams& fit = params_.localization;
  const double fitted_m = fit.noise_std_m + fit.noise_std_per_m * p_C_m.x();
  if (fitted_m > 0.0) return std::max(params_.min_measurement_std_m, fitted_m);
  return std::max(params_.min_measurement_std_m, params_.measurement_std_per_m * p_C_m.head<2>().norm());
}

TargetTask::Candidate TargetTask::candidate(const hal::DetectionFrame& frame, int index,
                                            const std::optional<Eigen::Isometry3d>& T_WC) const {
  const auto& person = frame.persons[static_cast<std::size_t>(index)];
  Candidate c;
  // Judged in the image the network saw (its edges, its scores)...
  c.torso =
      perception::torsoFeatures(person.keypoints, frame.intrinsics.width_px, frame.intrinsics.height_px, params_.torso);
  c.look = perception::toAppearance(person);
  if (!T_WC) return c;  // the capture time's pose unknown: no measurement (stats: no_pose)
  // ... measured in the level camera's (levelHomography): the regression's inputs as it was fitted.
  const Eigen::Matrix3d H = levelHomography(*T_WC, frame.intrinsics);
  std::array<hal::Keypoint2D, hal::kNumKeypoints> level = person.keypoints;
  for (const hal::CocoKeypoint k : {hal::CocoKeypoint::kLeftShoulder, hal::CocoKeypoint::kRightShoulder,
                                    hal::CocoKeypoint::kLeftHip, hal::CocoKeypoint::kRightHip}) {
    hal::Keypoint2D& kp = level[hal::index(k)];
    const Eigen::Vector3d h = H * Eigen::Vector3d(kp.u_px, kp.v_px, 1.0);
    if (!(h.z() > 0.0)) return c;  // behind the level camera: no measurement
    kp.u_px = h.x() / h.z();
    kp.v_px = h.y() / h.z();
  }
  const perception::TorsoFeatures seen = c.torso;  // the image's pixels, for the depth camera's line of sight
  c.torso = perception::remeasured(c.torso, level);
  if (c.torso.reliable) {
    Eigen::Vector3d p_C_m;
    const Eigen::Vector3d p_WT_m = localize(c.torso, *T_WC, p_C_m);
    if (p_WT_m.allFinite()) {
      c.measurement.emplace();
      c.measurement->stamp_ns = frame.stamp_ns;
      c.measurement->p_WT_m = p_WT_m;
      c.measurement->std_xy_m = measurementStdM(p_C_m);
      c.regression_range_m = p_C_m.head<2>().norm();
      if (stats_.range_scale != 1.0) {
        // As the followed person: their own scale along the line of sight (depth_range.scale_rate), the height the
        // regression's as a ranged measurement's is. As someone else: the fit's, kept in `unscaled`.
        c.unscaled = *c.measurement;
        p_C_m.head<2>() *= stats_.range_scale;
        c.measurement->p_WT_m = cameraToWorld(p_C_m, *T_WC, CameraFrame::kLevel);
        c.measurement->std_xy_m = measurementStdM(p_C_m);
      }
    }
  } else if (params_.bearing_fallback) {
    c.measurement = bearingMeasurement(frame, c.torso, *T_WC);
  }
  if (c.measurement && params_.depth_range.enabled && depth_count_ > 0) {
    // The line of sight through the torso's centre; a cut-off torso's through its whole pair's midpoint.
    Eigen::Vector2d pixel(seen.u_px, seen.v_px);
    if (!seen.reliable) {
      const auto kp = [&](hal::CocoKeypoint k) { return person.keypoints[hal::index(k)]; };
      const hal::Keypoint2D a =
          seen.bearing_from_shoulders ? kp(hal::CocoKeypoint::kLeftShoulder) : kp(hal::CocoKeypoint::kLeftHip);
      const hal::Keypoint2D b =
          seen.bearing_from_shoulders ? kp(hal::CocoKeypoint::kRightShoulder) : kp(hal::CocoKeypoint::kRightHip);
      pixel = Eigen::Vector2d(0.5 * (a.u_px + b.u_px), 0.5 * (a.v_px + b.v_px));
    }
    rangeByDepth(frame, pixel, *T_WC, c);
  }
  return c;
}

void TargetTask::rangeByDepth(const hal::DetectionFrame& frame, const Eigen::Vector2d& pixel,
                              const Eigen::Isometry3d& T_WC, Candidate& c) const {
  const DepthRangeParams& p = params_.depth_range;
  // The newest depth image taken at or before the photo (within max_offset_s), and where its camera was. Not a
  // later one: whether it has arrived when the detection does depends on the two devices' latencies, and a
  // replay of the run must range the person as the run did.
  const hal::DepthFrame* depth = nullptr;
  for (std::size_t i = 0; i < depth_count_; ++i) {
    const rt::DurationNs before_ns = frame.stamp_ns - depth_frames_[i]->stamp_ns;
    if (before_ns >= 0 && before_ns <= rt::secondsToNs(p.max_offset_s)) depth = depth_frames_[i].get();
  }
  c.depth = DepthRangeStatus::kOutOfView;
  if (depth == nullptr) return;
  // Only a live track's own measurement -- one its gate takes as it is -- is ranged: the depth camera sharpens
  // the followed person's distance, it does not vouch for a detection. Random keypoints (issue 23's
  // detector_garbage) put the line of sight on a wall, which the depth camera ranges as sharply as a person,
  // and the same wall every frame: sharp, consistent measurements a lost track would restart on. A start or a
  // restart is the regression's; bystanders' tracks keep theirs.
  const TargetEstimate prior = estimator_.estimate(frame.stamp_ns);
  if (!prior.initialised || prior.lost) return;
  const std::optional<double> d2 = estimator_.mahalanobisSq(*c.measurement);
  if (!d2 || !(*d2 <= params_.estimator.gate_chi2)) return;
  const hal::OdometryHistory::Lookup pose = poses_.lookup(depth->stamp_ns);
  if (pose.status != rt::HistoryStatus::kOk) return;
  const Eigen::Isometry3d T_WD = pose.value * depth->T_BC;
  // The pixel's line of sight in W (the optical ray turned into C, then W; lens distortion not modelled).
  const hal::CameraIntrinsics& k = frame.intrinsics;
  const Eigen::Vector3d ray_optical((pixel.x() - k.cx_px) / k.fx_px, (pixel.y() - k.cy_px) / k.fy_px, 1.0);
  const Eigen::Vector3d dir_W = (T_WC.linear() * opticalAxesInCamera() * ray_optical).normalized();
  const Eigen::Vector3d origin_W = T_WC.translation();
  const DepthSurface surface = surfaceAlongLine(*depth, T_WD, origin_W, dir_W, p);
  c.depth = surface.status;
  if (surface.status != DepthRangeStatus::kFound) return;
  // Where the depth image saw them, at its own time. Not carried to the photo's along the estimate's velocity:
  // a wrong velocity (a restart that jumped) would move every measurement with it and confirm itself
  // (measured: 6 m/s held for a second after a detector fault); the offset's reach is noise instead.
  const Eigen::Vector2d p_xy = bodyCentreBehind(origin_W, dir_W, surface.range_m, p);
  const double moved_m = p.person_speed_mps * rt::nsToSeconds(frame.stamp_ns - depth->stamp_ns);
  // The same person as the regression (or the prior's range, for a bearing) places, within a factor.
  TargetMeasurement& m = *c.measurement;
  const double depth_range_m = (p_xy - origin_W.head<2>()).norm();
  const double regression_range_m = (m.p_WT_m.head<2>() - origin_W.head<2>()).norm();
  if (!(depth_range_m * p.max_ratio >= regression_range_m && depth_range_m <= p.max_ratio * regression_range_m)) {
    c.depth_disagreed = true;
    return;
  }
  const Eigen::Vector2d line_W = (p_xy - origin_W.head<2>()) / depth_range_m;
  c.unranged = m;
  m.p_WT_m.head<2>() = p_xy;  // the height stays the regression's (the estimator's z is its ground level)
  m.bearing_W = line_W;
  m.ranged = true;
  c.depth_range_m = depth_range_m;
  m.range_std_m = std::hypot(depthRangeStdM(surface.range_m, p), moved_m);
  m.std_xy_m = std::hypot(std::max(params_.min_measurement_std_m, p.cross_std_per_m * depth_range_m), moved_m);
}

TargetTask::Association TargetTask::associate(const hal::DetectionFrame& frame,
                                              std::array<Candidate, hal::kMaxPersons>& candidates) const {
  Association a;
  a.track.fill(kNoTrack);
  const int count = static_cast<int>(std::min(frame.person_count, hal::kMaxPersons));
  const int lock_on = frame.target_index >= 0 && frame.target_index < count ? frame.target_index : -1;
  const TargetEstimate prior = estimator_.estimate(frame.stamp_ns);
  const auto pose = cameraPoseAt(frame.stamp_ns, poses_, gimbal_history_, params_.extrinsics);
  const std::optional<Eigen::Isometry3d> T_WC =
      pose ? std::optional<Eigen::Isometry3d>(pose.value()) : std::optional<Eigen::Isometry3d>();
  if (!params_.choose_by_estimate) {
    if (lock_on >= 0) candidates[static_cast<std::size_t>(lock_on)] = candidate(frame, lock_on, T_WC);
    a.followed = lock_on;
    return a;
  }
  for (int i = 0; i < count; ++i) candidates[static_cast<std::size_t>(i)] = candidate(frame, i, T_WC);
  const auto distance = [&](int i) {
    const auto& m = candidates[static_cast<std::size_t>(i)].measurement;
    return m && !m->bearingOnly();
  };
  if (!prior.initialised) {  // the lock-on designates; beside their distance, everyone else is someone else
    a.followed = lock_on;
    for (int i = 0; i < count && lock_on >= 0 && distance(lock_on); ++i)
      if (i != lock_on && distance(i)) a.track[static_cast<std::size_t>(i)] = kNewTrack;
    return a;
  }
  // Every (person, track) pair within the track's gate -- the estimator's own test against the state it would update:
  // live, the prediction; lost, the prediction with its grown covariance (where the person can have gone since: the
  // re-identification after an occlusion). The followed track's pairs also pass the colour the task has learnt, a
  // bystander's the colour learnt for their track; the cost is the lock-on's form (gate fraction plus weighted colour
  // fraction) for every track alike. While the followed person is lost, a bystander track never seen beside them may be
  // them, and does not compete. The cheapest assignment of distances to tracks (global nearest neighbour, solved
  // exactly: assignment.hpp); then, if nobody went to the followed track, a bearing -- unless it fits better (by its
  // likelihood with bearing_by_likelihood) a bystander track that no one in the frame explains (a bearing fits anyone
  // on its line of sight), or the depth camera sees through where the person would be on it (depth_vets_bearings).
  // Nobody for the followed track: it coasts (never the lock-on's choice, whose bystander the estimator's restart rule
  // would hand the track to). Column 0 of the costs is the followed track, column 1 + j bystander track j.
  AssignmentCosts costs;
  std::array<double, hal::kMaxPersons> bearing_cost{};  // the followed track's, for bearings; inf: out of its gates
  std::array<double, hal::kMaxPersons> bearing_d2{};
  std::array<double, hal::kMaxPersons> bearing_nll{};  // across its line: twice the negative log-likelihood
  std::array<bool, hal::kMaxPersons> in_front{};       // ranged in front of the followed person: someone else
  std::array<bool, hal::kMaxPersons> doubtful{};       // ... refused by in_front_gate_chi2 only: maybe the person
  std::array<bool, hal::kMaxPersons> beyond_gate{};    // a distance the live followed track's gate refused
  std::array<bool, hal::kMaxPersons> kept_off{};       // refused by the look gate, kept off the bystander tracks
  bearing_cost.fill(std::numeric_limits<double>::infinity());
  const double gate = params_.estimator.gate_chi2;
  const perception::TrackerParams& t = params_.tracker;
  const auto competes = [&](std::size_t j) { return !prior.lost || bystanders_.seenWithFollowed(j); };
  for (int i = 0; i < count; ++i) {
    const Candidate& c = candidates[static_cast<std::size_t>(i)];
    if (!c.measurement) continue;
    const bool bearing = c.measurement->bearingOnly();
    // The colour distance to a track's colour (none: no colour to judge by).
    const auto appearance_to = [&](const perception::Appearance& colour) -> std::optional<double> {
      if (!colour.valid || !c.look.valid) return std::nullopt;
      return perception::appearanceDistance(colour, c.look);
    };
    // The cost against a track's prediction and colour (the gate fraction); nothing outside either gate.
    const auto cost_of = [&](std::optional<TargetEstimator::Fit> fit,
                             std::optional<double> appearance) -> std::optional<double> {
      if (!fit || !(fit->d2 <= gate)) return std::nullopt;
      if (appearance && *appearance > t.max_appearance_distance) return std::nullopt;
      return fit->d2 / gate + t.appearance_weight * appearance.value_or(0.0) / t.max_appearance_distance;
    };
    const std::optional<double> to_followed = appearance_to(reference_);
    for (std::size_t j = 0; j < bystanders_.capacity() && !bearing; ++j) {
      if (!competes(j)) continue;
      const std::optional<TargetEstimator::Fit> fit_j = bystanders_.fit(j, c.judgedAsOther());
      if (!fit_j || !(fit_j->d2 <= gate)) continue;  // outside the gate: no colour to compare (a free slot too)
      std::optional<double> appearance = appearance_to(bystanders_.look(j));
      // Lost: only competing tracks reach here (competes), and place decides between them and the followed track.
      if (appearance && to_followed && prior.lost && params_.lost_competing_colour_capped &&
          *to_followed < *appearance) {
        appearance = *to_followed;
        a.lost_colour_capped = true;
      }
      if (const auto cost = cost_of(fit_j, appearance)) costs.set(static_cast<std::size_t>(i), 1 + j, *cost);
    }
    const std::optional<TargetEstimator::Fit> fit = estimator_.fit(c.judged());
    const std::optional<double> followed_cost = cost_of(fit, to_followed);
    beyond_gate[static_cast<std::size_t>(i)] = !bearing && !prior.lost && fit && fit->d2 > gate;
    if (!followed_cost) continue;
    const double d2 = fit->d2;
    if (T_WC && hiddenBehindABystander(i, costs, prior, T_WC->translation(), frame.stamp_ns)) {
      a.behind_bystander = true;
      in_front[static_cast<std::size_t>(i)] = true;
      continue;
    }
    if (bearing && params_.depth_vets_bearings && c.depth &&
        (*c.depth == DepthRangeStatus::kNoSurface || (*c.depth == DepthRangeStatus::kFound && c.depth_disagreed))) {
      a.seen_through = true;  // the depth camera sees past (or something before) where the person would be
      continue;
    }
    if (const InFront verdict = inFrontOfTheFollowed(c, prior); verdict != InFront::kNo) {
      a.in_front = true;
      in_front[static_cast<std::size_t>(i)] = true;
      doubtful[static_cast<std::size_t>(i)] = verdict == InFront::kDoubtful && !params_.in_front_doubtful_starts_track;
      continue;
    }
    const double cost = *followed_cost;
    if ((!prior.lost || params_.look_gate_after_loss) && !looksLikeTheFollowed(c.look, frame.stamp_ns)) {
      a.look_refused = true;
      if (!bearing) a.look_refused_d2 = std::min(a.look_refused_d2, d2);
      if (!bearing && !prior.lost && params_.look_refused_off_tracks &&
          fitsFollowedBest(i, d2, c.judgedAsOther(), costs)) {
        for (std::size_t j = 0; j < bystanders_.capacity(); ++j)
          costs.set(static_cast<std::size_t>(i), 1 + j, AssignmentCosts::kNotAllowed);
        kept_off[static_cast<std::size_t>(i)] = true;
        a.look_refused_kept_off = true;
      }
      continue;
    }
    if (bearing) {
      bearing_cost[static_cast<std::size_t>(i)] = cost;
      bearing_d2[static_cast<std::size_t>(i)] = d2;
      if (params_.bearing_by_likelihood) {  // another prediction of the track: only where it is compared
        const std::optional<TargetEstimator::Fit> across = estimator_.fitAcrossLine(c.judged());
        bearing_nll[static_cast<std::size_t>(i)] =
            across ? across->d2 + across->log_det_S : std::numeric_limits<double>::infinity();
      }
    } else {
      costs.set(static_cast<std::size_t>(i), 0, cost);
    }
  }
  // A person left without a track costs as much as the dearest pair the gates allow (at both gates' edges), so that
  // nobody who could take a free track is left out: of the assignments that pair the most people, the cheapest.
  const double miss_cost = 1.0 + t.appearance_weight;
  const AssignmentResult assigned =
      cheapestAssignment(costs, static_cast<std::size_t>(count), 1 + bystanders_.capacity(), miss_cost);
  std::array<bool, kMaxBystanderTracks> track_taken{};
  std::array<bool, hal::kMaxPersons> person_taken{};
  for (int i = 0; i < count; ++i) {
    const int column = assigned.column[static_cast<std::size_t>(i)];
    if (column == AssignmentResult::kNone) continue;
    if (column == 0) {
      a.followed = i;
    } else {
      track_taken[static_cast<std::size_t>(column - 1)] = true;
      a.track[static_cast<std::size_t>(i)] = column - 1;
    }
    person_taken[static_cast<std::size_t>(i)] = true;
  }
  double best_bearing_cost = std::numeric_limits<double>::infinity();
  int best_bearing = -1;
  for (int i = 0; i < count && a.followed < 0; ++i) {
    const double cost = bearing_cost[static_cast<std::size_t>(i)];
    if (!(cost < best_bearing_cost)) continue;
    bool explains_bystander = false;
    for (std::size_t j = 0; j < bystanders_.capacity() && !explains_bystander; ++j) {
      if (track_taken[j] || !competes(j)) continue;
      const auto k = static_cast<std::size_t>(i);
      const TargetMeasurement& m = candidates[k].judgedAsOther();
      const std::optional<double> d2_j = bystanders_.mahalanobisSq(j, m);
      if (!d2_j) continue;
      if (!params_.bearing_by_likelihood) {
        explains_bystander = *d2_j <= bearing_d2[k];
        continue;
      }
      const std::optional<TargetEstimator::Fit> across_j = bystanders_.fitAcrossLine(j, m);
      explains_bystander = *d2_j <= gate && across_j && across_j->d2 + across_j->log_det_S <= bearing_nll[k];
    }
    if (explains_bystander) continue;
    best_bearing_cost = cost;
    best_bearing = i;
  }
  if (a.followed < 0) a.followed = best_bearing;
  // Someone new is someone else only beside the followed person's distance in the same frame: alone, they may
  // be the followed person whom the gate lost (a turn, a jump of the localization), and a track started on
  // them would then take the person's measurements from their own track. Someone the depth camera ranged in front
  // of the followed person is someone else alone too: on their own track they compete for the next frames, where
  // their range may come nearer the person's prediction (traced: crowd seed 40, a look-alike refused in front two
  // frames in a row, then ranged 0.85 m nearer than the person at d2 14.2, inside the gate, and taken) -- unless
  // only the tighter bound refused them (in_front_doubtful_starts_track false): they may be the person.
  const bool followed_ranged = a.followed >= 0 && distance(a.followed);
  if (a.followed >= 0) person_taken[static_cast<std::size_t>(a.followed)] = true;
  for (int i = 0; i < count; ++i) {
    const auto k = static_cast<std::size_t>(i);
    person_taken[k] = person_taken[k] || kept_off[k];  // they may be the person: no track of their own either
    if ((followed_ranged || (in_front[k] && !doubtful[k])) && !person_taken[k] && distance(i)) a.track[k] = kNewTrack;
    a.refused_alone[k] = beyond_gate[k] && !person_taken[k] && a.track[k] == kNoTrack;
  }
  return a;
}

bool TargetTask::fitsFollowedBest(int person, double followed_d2, const TargetMeasurement& judged,
                                  const AssignmentCosts& costs) const {
  for (std::size_t j = 0; j < bystanders_.capacity(); ++j) {
    if (!std::isfinite(costs.at(static_cast<std::size_t>(person), 1 + j))) continue;  // not a pair the gates allow
    const std::optional<double> d2 = bystanders_.mahalanobisSq(j, judged);
    if (d2 && *d2 <= followed_d2) return false;
  }
  return true;
}

TargetTask::InFront TargetTask::inFrontOfTheFollowed(const Candidate& c, const TargetEstimate& prior) const {
  const int after = params_.in_front_after_ranged;
  if (after <= 0 || ranged_streak_ < after || prior.lost || !c.measurement || !c.measurement->ranged || !c.unranged)
    return InFront::kNo;
  if (params_.in_front_test == TargetTaskParams::InFrontTest::kGate) {
    const std::optional<double> d2 = estimator_.mahalanobisSq(*c.measurement);
    const double gate = params_.estimator.gate_chi2;
    const double bound = params_.in_front_gate_chi2 > 0.0 ? params_.in_front_gate_chi2 : gate;
    if (!(d2 && *d2 > bound)) return InFront::kNo;
    return *d2 > gate ? InFront::kBeyondGate : InFront::kDoubtful;
  }
  const std::optional<TargetEstimator::Innovation> innovation = estimator_.innovation(*c.measurement);
  if (!innovation) return InFront::kNo;
  // The innovation along the line of sight, against its own standard deviation: nearer (negative) by more than the
  // gate's reach in one dimension. Across the line the regression's gate has judged them already.
  Eigen::Vector3d line_W = Eigen::Vector3d::Zero();
  line_W.head<2>() = c.measurement->bearing_W;
  const double along_m = innovation->nu_m.dot(line_W);
  const double variance_m2 = line_W.dot(innovation->S_m2 * line_W);
  const bool nearer =
      variance_m2 > 0.0 && along_m < 0.0 && along_m * along_m > params_.estimator.gate_chi2 * variance_m2;
  return nearer ? InFront::kBeyondGate : InFront::kNo;
}

bool TargetTask::hiddenBehindABystander(int person, const AssignmentCosts& costs, const TargetEstimate& prior,
                                        const Eigen::Vector3d& p_WC_m, rt::TimeNs t_ns) const {
  const double body_m = params_.hidden_behind_m;
  if (!(body_m > 0.0) || prior.lost) return false;
  // The line of sight from the camera to the followed person's prediction, on the ground plane.
  const Eigen::Vector2d camera_m = p_WC_m.head<2>();
  const Eigen::Vector2d line_m = prior.p_WT_m.head<2>() - camera_m;
  const double range_m = line_m.norm();
  if (!(range_m > body_m)) return false;
  const Eigen::Vector2d toward = line_m / range_m;
  for (std::size_t j = 0; j < bystanders_.capacity(); ++j) {
    if (costs.at(static_cast<std::size_t>(person), 1 + j) == AssignmentCosts::kNotAllowed) continue;
    const std::optional<Eigen::Vector3d> p_m = bystanders_.position(j, t_ns);
    if (!p_m) continue;
    const Eigen::Vector2d from_camera_m = p_m->head<2>() - camera_m;
    const double along_m = from_camera_m.dot(toward);
    const double across_m = std::abs(from_camera_m.x() * toward.y() - from_camera_m.y() * toward.x());
    if (along_m > 0.0 && along_m < range_m - body_m && across_m < body_m) return true;
  }
  return false;
}

bool TargetTask::checkSwap(const hal::DetectionFrame& frame, const std::array<Candidate, hal::kMaxPersons>& candidates,
                           Association& a) {
  if (!swap_check_.active(frame.stamp_ns)) return false;
  const TargetEstimator& kept = swap_check_.kept();
  const double gate = params_.estimator.gate_chi2;
  const auto fitsKept = [&](int i) -> std::optional<double> {
    const Candidate& c = candidates[static_cast<std::size_t>(i)];
    if (!c.measurement || c.measurement->bearingOnly()) return std::nullopt;
    const std::optional<double> d2 = kept.mahalanobisSq(c.judged());
    if (!d2 || !(*d2 <= gate)) return std::nullopt;
    return d2;
  };
  // Evidence needs the followed track to hold someone the kept track does not explain (the look-alike walking
  // away from where the person would be). Holding nobody, it is coasting, and the re-identification in its grown
  // gate is the association's (measured: taking whoever fit the coasted kept track then took bystanders, crowd
  // seed 4 at 20.8 s, 1.8 s into the coasting). Holding someone the kept track explains: a turn of the person's
  // own set it aside.
  if (a.followed < 0 || fitsKept(a.followed)) {
    (void)swap_check_.vote(false);
    return false;
  }
  // Someone else who fits the kept track, looks like the person (the colour gate), and is on no track older than
  // the hypothesis (a track seen before it is someone known to be someone else).
  const int count = static_cast<int>(std::min(frame.person_count, hal::kMaxPersons));
  int best = -1;
  double best_d2 = std::numeric_limits<double>::infinity();
  for (int i = 0; i < count; ++i) {
    if (i == a.followed) continue;
    const int track = a.track[static_cast<std::size_t>(i)];
    if (track >= 0 && bystanders_.startedNs(static_cast<std::size_t>(track)) < swap_check_.keptSinceNs()) continue;
    const Candidate& c = candidates[static_cast<std::size_t>(i)];
    if (c.look.valid && reference_.valid &&
        perception::appearanceDistance(reference_, c.look) > params_.tracker.max_appearance_distance)
      continue;
    const std::optional<double> d2 = fitsKept(i);
    if (d2 && *d2 < best_d2) {
      best_d2 = *d2;
      best = i;
    }
  }
  if (!swap_check_.vote(best >= 0)) return true;
  // Confirmed: the kept track was the person. It takes their measurement; whom the followed track held is someone
  // else from now on (a new bystander track), and the track the person was given as a stranger is forgotten.
  ++stats_.swapped_back;
  estimator_ = kept;
  const int held = a.followed;
  const int track = a.track[static_cast<std::size_t>(best)];
  if (track >= 0) bystanders_.drop(static_cast<std::size_t>(track));
  a.track[static_cast<std::size_t>(best)] = kNoTrack;
  a.followed = best;
  if (held >= 0) {
    const auto& m = candidates[static_cast<std::size_t>(held)].measurement;
    a.track[static_cast<std::size_t>(held)] = m && !m->bearingOnly() ? kNewTrack : kNoTrack;
  }
  return false;
}

bool TargetTask::withinReach(const TargetMeasurement& m, const TargetMeasurement& before) const {
  constexpr double kRunningSpeedMps = 3.0;
  const auto stdXy = [&](const TargetMeasurement& x) {
    return x.std_xy_m > 0.0 ? x.std_xy_m : params_.estimator.measurement_std_xy_m;
  };
  const double dt_s = rt::nsToSeconds(m.stamp_ns - before.stamp_ns);
  const double reach_m = kRunningSpeedMps * std::max(0.0, dt_s) + 3.0 * std::hypot(stdXy(m), stdXy(before));
  return (m.p_WT_m - before.p_WT_m).head<2>().norm() <= reach_m;
}

void TargetTask::trackTheRefusedAlone(const std::array<Candidate, hal::kMaxPersons>& candidates, Association& a) {
  if (params_.refused_alone_frames <= 0) return;
  // The one who continues the run (where the one refused the frame before was), else the first refused: a new run.
  int first = -1;
  int continuing = -1;
  for (std::size_t k = 0; k < a.refused_alone.size(); ++k) {
    if (!a.refused_alone[k]) continue;
    const int i = static_cast<int>(k);
    if (first < 0) first = i;
    if (continuing < 0 && refused_alone_streak_ > 0 && withinReach(candidates[k].judgedAsOther(), refused_alone_last_))
      continuing = i;
  }
  if (first < 0) {
    refused_alone_streak_ = 0;  // "in a row": a frame without anyone refused alone ends the run
    return;
  }
  const int person = continuing >= 0 ? continuing : first;
  refused_alone_streak_ = continuing >= 0 ? refused_alone_streak_ + 1 : 1;
  refused_alone_last_ = candidates[static_cast<std::size_t>(person)].judgedAsOther();
  if (refused_alone_streak_ < params_.refused_alone_frames) return;
  a.track[static_cast<std::size_t>(person)] = kNewTrack;
  ++stats_.refused_alone_tracks;
  refused_alone_streak_ = 0;
}

int TargetTask::choosePerson(const hal::DetectionFrame& frame) const {
  std::array<Candidate, hal::kMaxPersons> candidates;
  return associate(frame, candidates).followed;
}

void TargetTask::trackDepthPeople(rt::TimeNs t_ns) {
  // In capture order, each depth frame once: the tracks' filters take measurements in time order, and a depth frame
  // older than a detection frame already given is skipped (it arrived late; its people have moved on).
  for (std::size_t f = 0; f < depth_count_; ++f) {
    const hal::DepthFrame& depth = *depth_frames_[f];
    if (depth.stamp_ns <= depth_people_done_ns_ || depth.stamp_ns > t_ns) continue;
    const hal::OdometryHistory::Lookup pose = poses_.lookup(depth.stamp_ns);
    if (pose.status != rt::HistoryStatus::kOk) continue;
    std::array<DepthPerson, kMaxAssignmentRows> people;
    const std::size_t count = depth_people_.find(depth, pose.value * depth.T_BC, people);
    ++stats_.depth_frames_searched;
    stats_.depth_people += count;
    if (count == 0) continue;
    const TargetEstimate prior = estimator_.estimate(depth.stamp_ns);
    const bool live = prior.initialised && !prior.lost;
    // The depth camera gives no height: the measurement carries the followed track's (the regression's ground level,
    // as every track's), with a noise that leaves every track's height alone.
    constexpr double kNoHeightStdM = 100.0;
    constexpr double kTwoBodiesM = 0.5;  // two people's centres at least two body radii apart
    const double z_m = prior.initialised ? prior.p_WT_m.z() : params_.verdict_torso_height_m;
    std::array<TargetMeasurement, kMaxAssignmentRows> m{};
    std::array<bool, kMaxAssignmentRows> beyond_followed{};
    AssignmentCosts costs;
    const double gate = params_.estimator.gate_chi2;
    for (std::size_t i = 0; i < count; ++i) {
      m[i].stamp_ns = depth.stamp_ns;
      m[i].p_WT_m = Eigen::Vector3d(people[i].p_W_m.x(), people[i].p_W_m.y(), z_m);
      m[i].std_xy_m = people[i].std_m;
      m[i].std_z_m = kNoHeightStdM;
      const std::optional<double> d2 = live ? estimator_.mahalanobisSq(m[i]) : std::nullopt;
      beyond_followed[i] = live && !(d2 && *d2 <= gate);
      if (live && !beyond_followed[i]) costs.set(i, 0, *d2 / gate);
      for (std::size_t j = 0; j < bystanders_.capacity(); ++j) {
        if (!live && !bystanders_.seenWithFollowed(j)) continue;  // lost: someone unknown may be the person
        const std::optional<double> d2_j = bystanders_.mahalanobisSq(j, m[i]);
        if (d2_j && *d2_j <= gate) costs.set(i, 1 + j, *d2_j / gate);
      }
    }
    const AssignmentResult assigned = cheapestAssignment(costs, count, 1 + bystanders_.capacity(), 1.0);
    bool followed_seen = false;
    int in_followed_gate = 0;
    for (std::size_t i = 0; i < count; ++i) {
      followed_seen = followed_seen || assigned.column[i] == 0;
      in_followed_gate += live && !beyond_followed[i] ? 1 : 0;
    }
    stats_.depth_people_followed += followed_seen ? 1 : 0;
    // The followed track's spread: a starved or young track is not fed (DepthPeopleParams::feed_max_std_m).
    const auto fed_spread = [&] {
      const Eigen::Matrix2d P_xy = prior.covariance.topLeftCorner<2, 2>();
      const double larger_variance =  // the larger eigenvalue of the 2 x 2
          0.5 * (P_xy(0, 0) + P_xy(1, 1)) + std::hypot(0.5 * (P_xy(0, 0) - P_xy(1, 1)), P_xy(0, 1));
      return live && std::sqrt(std::max(0.0, larger_variance)) <= params_.depth_people.feed_max_std_m;
    };
    const perception::Appearance no_colour;
    // Two bodies do not overlap: a piece of the followed person's body (something thin in front of them splits it) is
    // not someone else.
    const auto apart_from_followed = [&](std::size_t i) {
      for (std::size_t k = 0; k < count; ++k)
        if (assigned.column[k] == 0 && (people[k].p_W_m - people[i].p_W_m).norm() < kTwoBodiesM) return false;
      return true;
    };
    for (std::size_t i = 0; i < count; ++i) {
      const int column = assigned.column[i];
      if (column == 0 && in_followed_gate == 1 && params_.depth_people.feed_followed && fed_spread()) {
        if (estimator_.add(m[i]) == MeasurementVerdict::kAccepted) ++stats_.depth_people_fed;
      } else if (column > 0) {
        bystanders_.update(static_cast<std::size_t>(column - 1), m[i], no_colour, params_.tracker.appearance_rate,
                           followed_seen);
        ++stats_.depth_people_updates;
      } else if (column == AssignmentResult::kNone && followed_seen && beyond_followed[i] && apart_from_followed(i)) {
        bystanders_.start(m[i], no_colour, true);
        ++stats_.depth_people_tracks;
      }
    }
  }
  depth_people_done_ns_ = std::max(depth_people_done_ns_, t_ns);
}

bool TargetTask::process(const Candidate& c) {
  if (c.depth) {
    if (c.measurement && c.measurement->ranged)
      ++stats_.depth_ranged;
    else if (c.depth_disagreed)
      ++stats_.depth_disagreed;
    else
      ++stats_.depth_unseen;
  }
  const bool ranged = c.measurement && c.measurement->ranged;
  if (!c.torso.reliable && !ranged) {
    ++stats_.unreliable;
    if (!c.measurement) return false;
    const MeasurementVerdict verdict = estimator_.add(*c.measurement);
    if (verdict == MeasurementVerdict::kAccepted) ++stats_.bearings;
    return false;
  }
  if (!c.measurement) {
    ++stats_.no_pose;
    return false;
  }
  if (!c.torso.reliable) ++stats_.unreliable;  // ... but the depth camera gave their distance
  // A ranged measurement too sharp for the gate of a track that the regression's still fits (the track
  // restarted with a wrong velocity, a step ago the person was behind something): the regression's, whose
  // looser noise pulls the track back, after which the ranges pass again. Refused, a sharp range would leave
  // the track coasting away from the person it was given.
  const TargetMeasurement* given = &*c.measurement;
  if (ranged && c.unranged) {
    const std::optional<double> d2 = estimator_.mahalanobisSq(*c.measurement);
    if (!(d2 && *d2 <= params_.estimator.gate_chi2)) given = &*c.unranged;
  }
  const bool was_lost = estimator_.estimate(given->stamp_ns).lost;
  const MeasurementVerdict verdict = estimator_.add(*given);
  if (verdict == MeasurementVerdict::kAccepted || verdict == MeasurementVerdict::kStarted) {
    ++stats_.accepted;
    // A start or a re-identification after a loss is the regression's; a fallback or a distance without the depth
    // camera's is not the camera's either.
    const bool agreed = verdict == MeasurementVerdict::kAccepted && !was_lost && ranged && given == &*c.measurement;
    // Not seen by the depth camera (in_front_streak_spans_unseen): no word on the track's distance either way.
    const bool unseen = verdict == MeasurementVerdict::kAccepted && !was_lost && !ranged && !c.depth_disagreed &&
                        c.depth != DepthRangeStatus::kFound;
    // The person's scale from every frame of theirs the depth camera ranged, whichever form the track took: a scale
    // far from 1 leaves the ranged form beyond the gate until it is learnt.
    if (verdict == MeasurementVerdict::kAccepted && !was_lost && ranged && c.torso.reliable) learnScale(c);
    if (agreed) {
      ++ranged_streak_;
      unseen_run_ = 0;
    } else if (unseen && params_.in_front_streak_spans_unseen) {
      // The regression alone has carried the track since its last range: past the limit its distance is the
      // regression's, whose bias the person's own ranged frames would then show as someone else.
      if (++unseen_run_ > params_.in_front_unseen_limit && params_.in_front_unseen_limit > 0) ranged_streak_ = 0;
    } else {
      ranged_streak_ = 0;
      unseen_run_ = 0;
    }
    if (!c.torso.reliable) return true;  // a cut-off person's colour is not their whole torso's: not learnt
    // The colour of whom the track follows, learnt slowly from the first lock on; kept through restarts
    // (a restart is a re-identification of the same person, or the lock-on's choice after a long loss).
    if (c.look.valid && reference_.valid) {
      // The spread of the person's own colour distance, learnt at the colour's rate (the first samples averaged).
      const double d = perception::appearanceDistance(reference_, c.look);
      ++own_look_count_;
      const double rate = std::max(params_.tracker.appearance_rate, 1.0 / own_look_count_);
      own_look_mean_ += rate * (d - own_look_mean_);
      own_look_mean_sq_ += rate * (d * d - own_look_mean_sq_);
    }
    if (c.look.valid) perception::blendAppearance(reference_, c.look, params_.tracker.appearance_rate);
    return true;
  }
  ++stats_.rejected;
  return false;
}

void TargetTask::learnScale(const Candidate& c) {
  const DepthRangeParams& p = params_.depth_range;
  if (!(p.scale_rate > 0.0) || !(c.regression_range_m > 0.0) || !(c.depth_range_m > 0.0)) return;
  // The mean in log: a factor and its inverse weigh alike. The first frames are averaged (rate 1/n), so the first
  // ranged frame does not set the scale alone; then the rate forgets, as the regression's error changes with the
  // distance (its fit's terms in 1/torso^2 weigh more far away).
  ++stats_.scale_samples;
  const double rate = std::max(p.scale_rate, 1.0 / static_cast<double>(stats_.scale_samples));
  const double bound = std::log(p.max_ratio);
  log_range_scale_ += rate * (std::log(c.depth_range_m / c.regression_range_m) - log_range_scale_);
  log_range_scale_ = std::clamp(log_range_scale_, -bound, bound);
  stats_.range_scale = std::exp(log_range_scale_);
}

bool TargetTask::looksLikeTheFollowed(const perception::Appearance& look, rt::TimeNs stamp_ns) const {
  // Too few of the person's own distances to know their spread, or no colour to judge: the colour gate alone.
  constexpr int kMinSamples = 10;
  if (params_.look_gate_sigmas <= 0.0 || own_look_count_ < kMinSamples || !look.valid || !reference_.valid) return true;
  if (look_refused_since_ns_ >= 0 &&
      rt::nsToSeconds(stamp_ns - look_refused_since_ns_) >= params_.look_gate_confirm_s && look_refused_d2_count_ > 0) {
    // Confirmed over frames if the refused sat on the prediction: the mean of n chi-square (3 dof) values is 3
    // with a standard deviation of sqrt(6 / n).
    const double n = look_refused_d2_count_;
    if (look_refused_d2_sum_ / n <= 3.0 + 3.0 * std::sqrt(6.0 / n)) return true;
  }
  const double std_dev = std::sqrt(std::max(0.0, own_look_mean_sq_ - own_look_mean_ * own_look_mean_));
  return perception::appearanceDistance(reference_, look) <= own_look_mean_ + params_.look_gate_sigmas * std_dev;
}

std::optional<TargetMeasurement> TargetTask::bearingMeasurement(const hal::DetectionFrame& frame,
                                                                const perception::TorsoFeatures& torso,
                                                                const Eigen::Isometry3d& T_WC) const {
  if (!torso.bearing_ok) return std::nullopt;
  const TargetEstimate prior = estimator_.estimate(frame.stamp_ns);
  if (!prior.initialised || prior.lost) return std::nullopt;
  // The level camera frame at the capture time: its origin and forward axis in W.
  const Eigen::Vector3d origin_W = T_WC.translation();
  const Eigen::Vector3d ahead_W = cameraToWorld(Eigen::Vector3d::UnitX(), T_WC, CameraFrame::kLevel);
  const Eigen::Vector2d forward_W = (ahead_W - origin_W).head<2>();
  const Eigen::Vector2d prior_W = (prior.p_WT_m - origin_W).head<2>();
  const double x_m = prior_W.dot(forward_W);
  // Nearer than this the person is under the camera, where u says little of the bearing.
  constexpr double kMinDistanceM = 0.5;
  if (!(x_m > kMinDistanceM)) return std::nullopt;
  // The line of sight the regression gives u at the prior's forward distance, and on it the point at the
  // prior's range: the innovation then lies across the line (to first order the EKF update of a measured
  // bearing), so the range the filter carries is kept, not pulled.
  Eigen::Vector3d p_C_m = localization::predictAtDistance(params_.localization, x_m, torso.bearing_u_px);
  p_C_m.head<2>() *= prior_W.norm() / p_C_m.head<2>().norm();
  const Eigen::Vector3d p_WT_m = cameraToWorld(p_C_m, T_WC, CameraFrame::kLevel);
  const Eigen::Vector2d line_W = (p_WT_m - origin_W).head<2>();
  if (!(line_W.norm() > 0.0) || !p_WT_m.allFinite()) return std::nullopt;
  TargetMeasurement m;
  m.stamp_ns = frame.stamp_ns;
  m.p_WT_m = p_WT_m;
  m.std_xy_m = measurementStdM(p_C_m);
  m.bearing_W = line_W.normalized();
  // No distance information: along the line of sight the noise dwarfs any error the filter carries.
  constexpr double kNoRangeStdM = 100.0;
  m.range_std_m = kNoRangeStdM;
  return m;
}

hal::DetectionFrame::PredictedTorso TargetTask::predictedTorso(const hal::DetectionFrame& frame) const {
  // Taking nobody, the track coasts where the person should be; the lock-on's crop may sit on whom the track
  // refused (a look-alike beside the person, crowd seed 24: the crop stayed on them while the person stood
  // unseen at the prediction). Saying where the prediction falls lets the detector look there.
  const TargetEstimate e = estimator_.estimate(frame.stamp_ns);
  if (!e.initialised || e.lost) return {};
  const auto T_WC = cameraPoseAt(frame.stamp_ns, poses_, gimbal_history_, params_.extrinsics);
  if (!T_WC) return {};
  const Eigen::Vector3d torso_W(e.p_WT_m.x(), e.p_WT_m.y(), params_.verdict_torso_height_m);
  const std::optional<PixelAndDepth> seen = worldToPixel(torso_W, *T_WC, frame.intrinsics);
  if (!seen || seen->u_px < 0.0 || seen->u_px >= frame.intrinsics.width_px || seen->v_px < 0.0 ||
      seen->v_px >= frame.intrinsics.height_px)
    return {};  // out of the image: the detector searches the whole frame
  return {seen->u_px, seen->v_px, frame.intrinsics.fy_px * params_.verdict_torso_m / seen->depth_m};
}

void TargetTask::step(rt::TimeNs now_ns) {
  while (const auto sample = odometry_.try_pop())
    if (poses_.push(*sample) == rt::HistoryPush::kAccepted) newest_pose_ns_ = sample->stamp_ns;
  while (const auto state = gimbal_.try_pop())
    if (gimbal_history_.push(*state) == rt::HistoryPush::kAccepted) newest_gimbal_ns_ = state->stamp_ns;
  if (depth_in_ != nullptr && depth_in_->version() != depth_version_) {
    depth_version_ = depth_in_->version();
    if (auto depth = depth_in_->read()) {
      if (depth_count_ == depth_frames_.size()) {
        std::move(depth_frames_.begin() + 1, depth_frames_.end(), depth_frames_.begin());
        --depth_count_;
      }
      depth_frames_[depth_count_++] = std::move(depth);
    }
  }
  while (const auto frame = detections_.try_pop()) {
    // A frame without the lock-on's choice still counts when the track's prediction may find the person in it.
    const bool chosen = frame->target_index >= 0 && frame->target_index < static_cast<int>(frame->person_count);
    if (!chosen && !(params_.choose_by_estimate && frame->person_count > 0)) continue;
    if (pending_count_ == pending_.size()) {  // far behind: give up on the oldest
      ++stats_.no_pose;
      std::move(pending_.begin() + 1, pending_.end(), pending_.begin());
      --pending_count_;
    }
    pending_[pending_count_++] = *frame;
  }
  std::size_t done = 0;
  for (; done < pending_count_; ++done) {
    const hal::DetectionFrame& frame = pending_[done];
    const bool covered = newest_pose_ns_ >= frame.stamp_ns && newest_gimbal_ns_ >= frame.stamp_ns;
    if (!covered && now_ns - frame.stamp_ns < params_.max_wait_ns) break;  // readings still on their way
    if (params_.depth_people.enabled && params_.choose_by_estimate) trackDepthPeople(frame.stamp_ns);
    std::array<Candidate, hal::kMaxPersons> candidates;
    Association a = associate(frame, candidates);
    const bool whole_frame_wanted = checkSwap(frame, candidates, a);
    const int person = a.followed;
    if (a.in_front) ++stats_.in_front;
    if (a.behind_bystander) ++stats_.behind_bystander;
    if (a.seen_through) ++stats_.seen_through;
    if (a.look_refused_kept_off) ++stats_.look_refused_kept_off;
    if (a.lost_colour_capped) ++stats_.lost_colour_capped;
    trackTheRefusedAlone(candidates, a);
    if (person >= 0 || !a.look_refused) {
      look_refused_since_ns_ = -1;
      look_refused_d2_sum_ = 0.0;
      look_refused_d2_count_ = 0;
    } else {
      if (look_refused_since_ns_ < 0) look_refused_since_ns_ = frame.stamp_ns;
      if (std::isfinite(a.look_refused_d2)) {
        look_refused_d2_sum_ += a.look_refused_d2;
        ++look_refused_d2_count_;
      }
    }
    bool followed_measured = false;
    if (person >= 0) {
      ++stats_.detections;
      if (swap_check_.enabled()) {  // off (the default): no estimate or innovation computed for it
        const Candidate& c = candidates[static_cast<std::size_t>(person)];
        const TargetEstimate before = estimator_.estimate(frame.stamp_ns);
        if (c.measurement && !c.measurement->bearingOnly() && before.initialised && !before.lost) {
          if (const auto innovation = estimator_.innovation(c.judged()))
            swap_check_.beforeUpdate(estimator_, *innovation, frame.stamp_ns);
        } else if (!before.initialised || before.lost) {
          swap_check_.reset();  // a window or a kept track from the track's earlier life
        }
      }
      if (person != frame.target_index) ++stats_.reassigned;
      followed_measured = process(candidates[static_cast<std::size_t>(person)]);
    } else if (frame.target_index >= 0 &&
               frame.target_index < static_cast<int>(std::min(frame.person_count, hal::kMaxPersons)) &&
               !candidates[static_cast<std::size_t>(frame.target_index)].measurement) {
      process(candidates[static_cast<std::size_t>(frame.target_index)]);  // counted: why it gave nothing
    }
    for (std::size_t i = 0; i < a.track.size(); ++i) {
      if (a.track[i] == kNoTrack) continue;
      const TargetMeasurement& m = candidates[i].givenAsOther();
      // Someone refused alone over frames (refused_alone_frames: only they are on a track and refused alone) is
      // someone else.
      const bool with_followed = followed_measured || a.refused_alone[i];
      if (a.track[i] == kNewTrack)
        bystanders_.start(m, candidates[i].look, with_followed);
      else
        bystanders_.update(static_cast<std::size_t>(a.track[i]), m, candidates[i].look, params_.tracker.appearance_rate,
                           with_followed);
    }
    if (followed_out_ != nullptr) {
      hal::DetectionFrame followed = frame;
      followed.target_index = person;
      followed.whole_frame_wanted = whole_frame_wanted;
      if (person < 0) followed.predicted_torso = predictedTorso(frame);
      followed_out_->write(followed);
    }
  }
  std::move(pending_.begin() + static_cast<std::ptrdiff_t>(done),
            pending_.begin() + static_cast<std::ptrdiff_t>(pending_count_), pending_.begin());
  pending_count_ -= done;
  // Depth frames are searched before each detection frame up to its capture time, and, while no detection comes
  // (a crop that found nobody is not queued), once a detection taken then could no longer be waited for: the
  // tracks stay fed, and take their measurements in time order.
  if (params_.depth_people.enabled && params_.choose_by_estimate && pending_count_ == 0)
    trackDepthPeople(std::min(newest_pose_ns_, now_ns - params_.max_wait_ns));
  TargetEstimate estimate = estimator_.estimate(now_ns);
  bystanders_.fillOthers(estimate.stamp_ns, estimate);
  const bool news =
      estimate.initialised && (estimate.last_accepted_ns != notified_accepted_ns_ || estimate.lost != notified_lost_);
  if (news) {
    notified_accepted_ns_ = estimate.last_accepted_ns;
    notified_lost_ = estimate.lost;
  }
  out_.write(estimate, news ? rt::Notify::kYes : rt::Notify::kNo);
}

}  // namespace aerotrack::estimation
