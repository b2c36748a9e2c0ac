// The target pipeline task: see target_task.hpp.
#include "aerotrack/estimation/target_task.hpp"

#include <algorithm>
#include <limits>

namespace aerotrack::estimation {

void parseTargetTaskParams(const rt::ConfigNode& node, TargetTaskParams& params) {
  params.extrinsics = parseGimbalCameraExtrinsics(node.child("gimbal_camera"));
  params.measurement_std_per_m = node.getDouble("measurement_std_per_m", 0.0, 1.0);
  params.min_measurement_std_m = node.getDouble("min_measurement_std_m", 0.001, 10.0);
  params.max_wait_ns = rt::secondsToNs(node.getDouble("max_wait_s", 0.0, 2.0));
  params.bearing_fallback = node.getEnum("unreliable_torso", {"bearing", "skip"}) == "bearing";
  params.choose_by_estimate = node.getEnum("association", {"estimate", "lock_on"}) == "estimate";
  params.estimator = parseTargetEstimatorParams(node.child("estimator"));
}

rt::Expected<TargetTask> TargetTask::create(const TargetTaskParams& params,
                                            rt::SpscQueue<hal::DetectionFrame>& detections,
                                            rt::SpscQueue<hal::OdometrySample>& odometry,
                                            rt::SpscQueue<hal::GimbalState>& gimbal,
                                            rt::LatestSlot<TargetEstimate>& out) {
  if (auto s = localization::validate(params.localization); !s) return rt::Error{"localization: " + s.error().message};
  auto poses = hal::OdometryHistory::create({});
  if (!poses) return poses.error();
  auto gimbal_history = GimbalAngleHistory::create({});
  if (!gimbal_history) return gimbal_history.error();
  auto estimator = TargetEstimator::create(params.estimator);
  if (!estimator) return rt::Error{"estimator: " + estimator.error().message};
  return TargetTask(params, std::move(poses.value()), std::move(gimbal_history.value()), std::move(estimator.value()),
                    detections, odometry, gimbal, out);
}

TargetTask::TargetTask(const TargetTaskParams& params, hal::OdometryHistory poses, GimbalAngleHistory gimbal_history,
                       TargetEstimator estimator, rt::SpscQueue<hal::DetectionFrame>& detections,
                       rt::SpscQueue<hal::OdometrySample>& odometry, rt::SpscQueue<hal::GimbalState>& gimbal,
                       rt::LatestSlot<TargetEstimate>& out)
    : params_(params),
      poses_(std::move(poses)),
      gimbal_history_(std::move(gimbal_history)),
      estimator_(std::move(estimator)),
      detections_(detections),
      odometry_(odometry),
      gimbal_(gimbal),
      out_(out) {}

std::optional<Eigen::Vector3d> TargetTask::localize(const hal::DetectionFrame& frame,
                                                    const perception::TorsoFeatures& torso,
                                                    Eigen::Vector3d& p_C_m) const {
  if (!torso.reliable) return std::nullopt;
  p_C_m = localization::predict(params_.localization, torso.torso_px, torso.u_px);
  // The regression was fitted on a level camera: read its output in the level frame.
  const auto p_WT_m =
      cameraToWorldAt(frame.stamp_ns, p_C_m, poses_, gimbal_history_, params_.extrinsics, CameraFrame::kLevel);
  if (!p_WT_m) return std::nullopt;
  return *p_WT_m;
}

double TargetTask::measurementStdM(const Eigen::Vector3d& p_C_m) const {
  return std::max(params_.min_measurement_std_m, params_.measurement_std_per_m * p_C_m.head<2>().norm());
}

int TargetTask::choosePerson(const hal::DetectionFrame& frame) const {
  const int count = static_cast<int>(std::min(frame.person_count, hal::kMaxPersons));
  const int lock_on = frame.target_index >= 0 && frame.target_index < count ? frame.target_index : -1;
  if (!params_.choose_by_estimate) return lock_on;
  const TargetEstimate prior = estimator_.estimate(frame.stamp_ns);
  if (!prior.initialised || prior.lost) return lock_on;
  // Each person with a distance: the squared Mahalanobis distance of their localized position from the
  // prediction, horizontally (the regression's height is a constant), S = P_xy + R; inside the estimator's
  // gate and (where both are known) the appearance gate, the cost is the lock-on's form.
  const Eigen::Matrix2d p_xy = prior.covariance.topLeftCorner<2, 2>();
  const double gate = params_.estimator.gate_chi2;
  const perception::TrackerParams& t = params_.tracker;
  int best = -1;
  double best_cost = std::numeric_limits<double>::infinity();
  for (int i = 0; i < count; ++i) {
    const auto& person = frame.persons[static_cast<std::size_t>(i)];
    const perception::TorsoFeatures torso = perception::torsoFeatures(person.keypoints, frame.intrinsics.width_px,
                                                                      frame.intrinsics.height_px, params_.torso);
    Eigen::Vector3d p_C_m;
    const auto p_WT_m = localize(frame, torso, p_C_m);
    if (!p_WT_m) continue;
    const double std_m = measurementStdM(p_C_m);
    const Eigen::Matrix2d s = p_xy + std_m * std_m * Eigen::Matrix2d::Identity();
    const Eigen::Vector2d d = (*p_WT_m - prior.p_WT_m).head<2>();
    const double d2 = d.dot(s.ldlt().solve(d));
    if (!(d2 < gate)) continue;
    const perception::Appearance look = perception::toAppearance(person);
    double appearance = 0.0;
    if (reference_.valid && look.valid) {
      appearance = perception::appearanceDistance(reference_, look);
      if (appearance > t.max_appearance_distance) continue;
    }
    const double cost = d2 / gate + t.appearance_weight * appearance / t.max_appearance_distance;
    if (cost < best_cost) {
      best_cost = cost;
      best = i;
    }
  }
  return best >= 0 ? best : lock_on;
}

void TargetTask::process(const hal::DetectionFrame& frame, int person_index) {
  const auto& person = frame.persons[static_cast<std::size_t>(person_index)];
  const perception::TorsoFeatures torso =
      perception::torsoFeatures(person.keypoints, frame.intrinsics.width_px, frame.intrinsics.height_px, params_.torso);
  if (!torso.reliable) {
    ++stats_.unreliable;
    if (!params_.bearing_fallback) return;
    if (const auto bearing = bearingMeasurement(frame, torso)) {
      const MeasurementVerdict verdict = estimator_.add(*bearing);
      if (verdict == MeasurementVerdict::kAccepted) ++stats_.bearings;
    }
    return;
  }
  Eigen::Vector3d p_C_m;
  const auto p_WT_m = localize(frame, torso, p_C_m);
  if (!p_WT_m) {
    ++stats_.no_pose;
    return;
  }
  TargetMeasurement m;
  m.stamp_ns = frame.stamp_ns;
  m.p_WT_m = *p_WT_m;
  m.std_xy_m = measurementStdM(p_C_m);
  const MeasurementVerdict verdict = estimator_.add(m);
  if (verdict == MeasurementVerdict::kAccepted || verdict == MeasurementVerdict::kStarted) {
    ++stats_.accepted;
    // The colour of whom the track follows: learnt slowly, and afresh when the track (re)starts on someone.
    const perception::Appearance look = perception::toAppearance(person);
    if (verdict == MeasurementVerdict::kStarted)
      reference_ = look;
    else if (look.valid)
      perception::blendAppearance(reference_, look, params_.tracker.appearance_rate);
  } else {
    ++stats_.rejected;
  }
}

std::optional<TargetMeasurement> TargetTask::bearingMeasurement(const hal::DetectionFrame& frame,
                                                                const perception::TorsoFeatures& torso) const {
  if (!torso.bearing_ok) return std::nullopt;
  const TargetEstimate prior = estimator_.estimate(frame.stamp_ns);
  if (!prior.initialised || prior.lost) return std::nullopt;
  // The level camera frame at the capture time: its origin and forward axis in W.
  const auto origin_W = cameraToWorldAt(frame.stamp_ns, Eigen::Vector3d::Zero(), poses_, gimbal_history_,
                                        params_.extrinsics, CameraFrame::kLevel);
  const auto ahead_W = cameraToWorldAt(frame.stamp_ns, Eigen::Vector3d::UnitX(), poses_, gimbal_history_,
                                       params_.extrinsics, CameraFrame::kLevel);
  if (!origin_W || !ahead_W) return std::nullopt;
  const Eigen::Vector2d forward_W = (*ahead_W - *origin_W).head<2>();
  const Eigen::Vector2d prior_W = (prior.p_WT_m - *origin_W).head<2>();
  const double x_m = prior_W.dot(forward_W);
  // Nearer than this the person is under the camera, where u says little of the bearing.
  constexpr double kMinDistanceM = 0.5;
  if (!(x_m > kMinDistanceM)) return std::nullopt;
  // The line of sight the regression gives u at the prior's forward distance, and on it the point at the
  // prior's range: the innovation then lies across the line (to first order the EKF update of a measured
  // bearing), so the range the filter carries is kept, not pulled.
  Eigen::Vector3d p_C_m = localization::predictAtDistance(params_.localization, x_m, torso.bearing_u_px);
  p_C_m.head<2>() *= prior_W.norm() / p_C_m.head<2>().norm();
  const auto p_WT_m =
      cameraToWorldAt(frame.stamp_ns, p_C_m, poses_, gimbal_history_, params_.extrinsics, CameraFrame::kLevel);
  if (!p_WT_m) return std::nullopt;
  const Eigen::Vector2d line_W = (*p_WT_m - *origin_W).head<2>();
  if (!(line_W.norm() > 0.0)) return std::nullopt;
  TargetMeasurement m;
  m.stamp_ns = frame.stamp_ns;
  m.p_WT_m = *p_WT_m;
  m.std_xy_m = measurementStdM(p_C_m);
  m.bearing_W = line_W.normalized();
  // No distance information: along the line of sight the noise dwarfs any error the filter carries.
  constexpr double kNoRangeStdM = 100.0;
  m.range_std_m = kNoRangeStdM;
  return m;
}

void TargetTask::step(rt::TimeNs now_ns) {
  while (const auto sample = odometry_.try_pop())
    if (poses_.push(*sample) == rt::HistoryPush::kAccepted) newest_pose_ns_ = sample->stamp_ns;
  while (const auto state = gimbal_.try_pop())
    if (gimbal_history_.push(*state) == rt::HistoryPush::kAccepted) newest_gimbal_ns_ = state->stamp_ns;
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
    const int person = choosePerson(frame);
    if (person >= 0) {
      ++stats_.detections;
      if (person != frame.target_index) ++stats_.reassigned;
      process(frame, person);
    }
    if (followed_out_ != nullptr) {
      hal::DetectionFrame followed = frame;
      followed.target_index = person;
      followed_out_->write(followed);
    }
  }
  std::move(pending_.begin() + static_cast<std::ptrdiff_t>(done),
            pending_.begin() + static_cast<std::ptrdiff_t>(pending_count_), pending_.begin());
  pending_count_ -= done;
  const TargetEstimate estimate = estimator_.estimate(now_ns);
  const bool news =
      estimate.initialised && (estimate.last_accepted_ns != notified_accepted_ns_ || estimate.lost != notified_lost_);
  if (news) {
    notified_accepted_ns_ = estimate.last_accepted_ns;
    notified_lost_ = estimate.lost;
  }
  out_.write(estimate, news ? rt::Notify::kYes : rt::Notify::kNo);
}

}  // namespace aerotrack::estimation
