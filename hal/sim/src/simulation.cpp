// The closed-loop simulator: see simulation.hpp.
#include "aerotrack/hal/sim/simulation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <span>

namespace aerotrack::hal::sim {
namespace {

// Stream ids of the disturbances (issue 20), far from the small ids of the sensors.
constexpr std::uint64_t kDriftWalkStream = 0xd21f7;
constexpr std::uint64_t kDriftJumpStream = 0xd21f8;
constexpr std::uint64_t kWindStream = 0x817d;

std::mt19937_64 streamRng(std::uint64_t seed, std::uint64_t stream) {
  std::seed_seq seq{seed, stream, std::uint64_t{0x5eed}};
  return std::mt19937_64(seq);
}

Eigen::Vector3d midpoint(const PersonState& p, CocoKeypoint a, CocoKeypoint b) {
  return 0.5 * (p.keypoints_W_m[index(a)] + p.keypoints_W_m[index(b)]);
}

/// The keypoint camera's measured signature: the truth with noise, its legs region only where the image
/// pipeline would measure one (both knees seen: perception/appearance.hpp).
AppearanceHistogram measuredSignature(const AppearanceHistogram& truth, const PersonDetection& detection,
                                      const CameraIntrinsics& camera, std::mt19937_64& rng) {
  AppearanceHistogram sig = noisySignature(truth, rng);
  const auto seen = [&](CocoKeypoint k) {
    const Keypoint2D& p = detection.keypoints[index(k)];
    return p.score >= kLegsMinKeypointScore && p.v_px >= 0.0 && p.v_px < camera.height_px && p.u_px >= 0.0 &&
           p.u_px < camera.width_px;
  };
  if (!seen(CocoKeypoint::kLeftKnee) || !seen(CocoKeypoint::kRightKnee)) {
    const std::size_t offset = regionOffset(SignatureRegion::kLegs);
    std::fill(sig.begin() + static_cast<std::ptrdiff_t>(offset),
              sig.begin() + static_cast<std::ptrdiff_t>(offset + kSignatureRegionBins), 0.0F);
  }
  return sig;
}

}  // namespace

rt::Expected<std::unique_ptr<Simulation>> Simulation::create(const ScenarioInstance& scenario,
                                                             const SimulationOptions& options, TimeNs start_ns) {
  const ScenarioSpec& s = scenario.spec;
  auto obstacles = ObstacleWorld::create(s.boxes, s.cylinders);
  if (!obstacles) return rt::Error{s.source + ": world: " + obstacles.error().message};
  auto person = WalkingPerson::create(s.person, s.path);
  if (!person) return rt::Error{s.source + ": person: " + person.error().message};

  QuadrotorParams quad_params;
  quad_params.mass_kg = s.drone.mass_kg;
  quad_params.max_thrust_n = s.drone.thrust_to_weight * s.drone.mass_kg * quad_params.gravity_mps2;
  QuadrotorState initial;
  initial.p_W_m = s.drone.start_m;
  initial.R_WB = Eigen::AngleAxisd(s.drone.start_yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  // On the ground at rest, or hovering (thrust already at weight, so it does not sag at start).
  initial.on_ground = s.drone.start_m.z() <= 0.0;
  if (!initial.on_ground) initial.thrust_n = s.drone.mass_kg * quad_params.gravity_mps2;
  auto quad = Quadrotor::create(quad_params, initial);
  if (!quad) return rt::Error{s.source + ": drone: " + quad.error().message};
  auto controller = GeometricController::create(GeometricControllerParams{}, quad_params);
  if (!controller) return rt::Error{s.source + ": drone controller: " + controller.error().message};
  if (!(options.physics_step_s > 0.0 && options.physics_step_s <= 0.01))
    return rt::Error{"simulation: physics_step_s must be in (0, 0.01]"};
  std::optional<SceneRenderer> renderer;
  if (s.gimbal_camera.mode == GimbalCameraMode::kImage) {
    SceneRenderParams render_params;
    render_params.intrinsics = s.gimbal_camera.camera.intrinsics;
    auto created = SceneRenderer::create(render_params, s.gimbal_camera.cast);
    if (!created) return rt::Error{s.source + ": sensors.gimbal_camera: " + created.error().message};
    renderer = std::move(created.value());
  }
  auto sim = std::unique_ptr<Simulation>(new Simulation(scenario, options, std::move(obstacles.value()),
                                                        std::move(person.value()), std::move(quad.value()),
                                                        std::move(controller.value()), start_ns));
  sim->renderer_ = std::move(renderer);
  for (const Bystander& b : scenario.bystanders.people) {
    auto walker = WalkingPerson::create(b.params, b.path);
    if (!walker) return rt::Error{s.source + ": " + b.origin + ": " + walker.error().message};
    sim->bystanders_.push_back(std::move(walker.value()));
    sim->bystander_delay_s_.push_back(b.start_delay_s);
  }
  sim->bodies_.resize(sim->personCount());
  sim->candidates_.reserve(sim->personCount());
  sim->refreshBodies(start_ns);
  return sim;
}

Simulation::Simulation(const ScenarioInstance& scenario, const SimulationOptions& options, ObstacleWorld obstacles,
                       WalkingPerson person, Quadrotor quad, GeometricController controller, TimeNs start_ns)
    : scenario_(scenario),
      options_(options),
      obstacles_(std::move(obstacles)),
      person_(std::move(person)),
      quad_(std::move(quad)),
      controller_(std::move(controller)),
      gimbal_(scenario.spec.gimbal),
      start_ns_(start_ns),
      now_ns_(start_ns),
      physics_step_ns_(rt::secondsToNs(options.physics_step_s)),
      camera_rng_(streamRng(scenario.seed, 1)),
      depth_rng_(streamRng(scenario.seed, 2)),
      odometry_rng_(streamRng(scenario.seed, 3)),
      crowd_rng_(streamRng(scenario.seed, 0xB1)),
      appearance_rng_(streamRng(scenario.seed, 0xB2)),
      next_camera_ns_(start_ns),
      next_depth_ns_(start_ns),
      next_odometry_ns_(start_ns),
      next_metrics_ns_(start_ns),
      camera_period_ns_(rt::periodFromRateHz(scenario.spec.gimbal_camera.rate_hz)),
      depth_period_ns_(rt::periodFromRateHz(scenario.spec.depth_camera.rate_hz)),
      odometry_period_ns_(rt::periodFromRateHz(scenario.spec.odometry.rate_hz)),
      metrics_period_ns_(rt::periodFromRateHz(options.metrics_rate_hz)),
      metrics_(scenario.spec) {
  const QuadrotorState& drone = quad_.state();
  active_setpoint_.stamp_ns = start_ns;
  active_setpoint_.p_W_m = drone.p_W_m;  // hold the start until told otherwise
  active_setpoint_.yaw_rad = scenario.spec.drone.start_yaw_rad;
  active_gimbal_command_.mode = GimbalCommand::Mode::kRate;
  truth_.stamp_ns = start_ns;
  truth_.drone = drone;
  truth_.person = personAt(start_ns);
  truth_.T_WC = cameraPose(drone, 0.0);
  gimbal_out_.write(gimbal_.encoder(start_ns));
  if (scenario.spec.odometry.drift.enabled()) {
    drift_.emplace(scenario.spec.odometry.drift, streamRng(scenario.seed, kDriftWalkStream),
                   streamRng(scenario.seed, kDriftJumpStream), drone.p_W_m);
  }
  if (scenario.spec.wind) wind_.emplace(*scenario.spec.wind, streamRng(scenario.seed, kWindStream));
  publishTruth();
}

PersonState Simulation::personAt(TimeNs t_ns) const {
  return person_.state(rt::nsToSeconds(t_ns - start_ns_) - scenario_.spec.person_start_delay_s);
}

PersonState Simulation::personStateAt(std::size_t id, TimeNs t_ns) const {
  if (id == 0) return personAt(t_ns);
  // Their generated walk, side-stepping the target where it would run into them (give_way.hpp).
  const double t_s = rt::nsToSeconds(t_ns - start_ns_);
  return withOffset(bystanders_[id - 1].state(t_s - bystander_delay_s_[id - 1]),
                    scenario_.bystanders.people[id - 1].give_way, t_s);
}

const AppearanceSignature& Simulation::personAppearance(std::size_t id) const {
  return id == 0 ? scenario_.bystanders.target_appearance : scenario_.bystanders.people[id - 1].appearance;
}

void Simulation::refreshBodies(TimeNs t_ns) {
  if (t_ns == bodies_ns_) return;
  bodies_ns_ = t_ns;
  for (std::size_t id = 0; id < bodies_.size(); ++id) {
    const PersonState p = personStateAt(id, t_ns);
    const double height_m = id == 0 ? person_.params().height_m : bystanders_[id - 1].params().height_m;
    bodies_[id] = Cylinder{p.p_W_m.head<2>(), kPersonBodyRadiusM, 0.0, height_m};
  }
}

bool Simulation::sightClear(const Eigen::Vector3d& a_W_m, const Eigen::Vector3d& b_W_m, std::size_t skip_id) const {
  if (!obstacles_.segmentClear(a_W_m, b_W_m)) return false;
  const Eigen::Vector3d ab = b_W_m - a_W_m;
  const double length_m = ab.norm();
  if (!(length_m > 0.0)) return true;
  const Ray ray(a_W_m, ab / length_m);
  for (std::size_t id = 0; id < bodies_.size(); ++id) {
    if (id == skip_id) continue;
    if (firstHit(bodies_[id], ray, length_m)) return false;
  }
  return true;
}

Eigen::Isometry3d Simulation::cameraPose(const QuadrotorState& drone, double gimbal_angle_rad) const {
  Eigen::Isometry3d T_WC = Eigen::Isometry3d::Identity();
  const Eigen::Matrix3d R_BG = Eigen::AngleAxisd(gimbal_angle_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T_WC.linear() = drone.R_WB * R_BG * opticalAxesInFlu();
  T_WC.translation() = drone.p_W_m + drone.R_WB * scenario_.spec.gimbal_camera.mount_B_m;
  return T_WC;
}

Sight Simulation::personSight(const Eigen::Isometry3d& T_WC, const PersonState& person) const {
  const CameraIntrinsics& k = scenario_.spec.gimbal_camera.camera.intrinsics;
  const Eigen::Isometry3d T_CW = T_WC.inverse();
  const std::array<Eigen::Vector3d, 2> torso_W_m = {
      midpoint(person, CocoKeypoint::kLeftShoulder, CocoKeypoint::kRightShoulder),
      midpoint(person, CocoKeypoint::kLeftHip, CocoKeypoint::kRightHip)};
  for (const Eigen::Vector3d& p_W : torso_W_m) {
    const auto uv = project(T_CW * p_W, k);
    if (!uv || uv->x() < 0.0 || uv->y() < 0.0 || uv->x() >= k.width_px || uv->y() >= k.height_px) {
      return Sight::kOutOfImage;
    }
  }
  for (const Eigen::Vector3d& p_W : torso_W_m) {
    if (!sightClear(T_WC.translation(), p_W, 0)) return Sight::kOccluded;
  }
  return Sight::kVisible;
}

void Simulation::step(TimeNs now_ns) {
  if (setpoint_in_.readIfNewer(setpoint_version_, active_setpoint_)) offboard_hold_ = false;
  // The flight controller's offboard-loss failsafe (PX4: COM_OF_LOSS_T, then hold): no setpoint for
  // kOffboardLossS and it holds where its estimator says it is, at rest, facing the same way.
  if (setpoint_version_ != 0 && !offboard_hold_ &&
      now_ns_ - active_setpoint_.stamp_ns > rt::secondsToNs(kOffboardLossS)) {
    const QuadrotorState& drone = quad_.state();
    const QuadrotorState seen = drift_ ? inOdometryFrame(drift_->error(), drone) : drone;
    active_setpoint_ =
        Setpoint{now_ns_, seen.p_W_m, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), active_setpoint_.yaw_rad, 0.0};
    offboard_hold_ = true;
    ++offboard_losses_;
  }
  gimbal_in_.readIfNewer(gimbal_version_, active_gimbal_command_);
  // Sensors due at the current instant sample before physics moves on, so that samples fall on
  // their own schedule (start + k * period) whatever the physics step.
  for (;;) {
    sampleDueSensors();
    if (now_ns_ >= now_ns) break;
    const DurationNs dt_ns = std::min(physics_step_ns_, now_ns - now_ns_);
    physicsStep(rt::nsToSeconds(dt_ns));
    now_ns_ += dt_ns;
  }
  gimbal_out_.write(gimbal_.encoder(now_ns_));
  publishTruth();
}

void Simulation::sampleDueSensors() {
  truth_.stamp_ns = now_ns_;
  truth_.drone = quad_.state();
  truth_.gimbal_angle_rad = gimbal_.angleRad();
  if (now_ns_ >= next_odometry_ns_) {
    sampleOdometry();
    next_odometry_ns_ += odometry_period_ns_;
  }
  // The bodies: bystanders' for sight lines and images; everyone's, the followed person's too, for depth.
  if ((!bystanders_.empty() && (now_ns_ >= next_camera_ns_ || now_ns_ >= next_metrics_ns_)) ||
      (options_.render_depth && now_ns_ >= next_depth_ns_)) {
    refreshBodies(now_ns_);
  }
  if (now_ns_ >= next_camera_ns_) {
    captureCamera();
    next_camera_ns_ += camera_period_ns_;
  }
  if (options_.render_depth && now_ns_ >= next_depth_ns_) {
    captureDepth();
    next_depth_ns_ += depth_period_ns_;
  }
  releaseDetections();
  if (now_ns_ >= next_metrics_ns_) {
    truth_.person = personAt(now_ns_);
    truth_.T_WC = cameraPose(truth_.drone, truth_.gimbal_angle_rad);
    const double t_s = rt::nsToSeconds(now_ns_ - start_ns_);
    MetricsSample sample;
    sample.t_s = t_s;
    sample.dt_s = rt::nsToSeconds(metrics_period_ns_);
    sample.drone_m = truth_.drone.p_W_m;
    sample.odometry_m = drift_ ? inOdometryFrame(drift_->error(), truth_.drone).p_W_m : truth_.drone.p_W_m;
    sample.person_m = truth_.person.p_W_m;
    sample.person_speed_mps = truth_.person.speed_mps;
    sample.tracking = t_s >= personStartS();
    sample.person_walking = sample.tracking && t_s - personStartS() < person_.durationS();
    // Clearance: to the static obstacles and to the bystanders' bodies (the target's is not an
    // obstacle, as before bystanders existed).
    sample.clearance_m = obstacles_.distance(truth_.drone.p_W_m);
    for (std::size_t id = 1; id < bodies_.size(); ++id)
      sample.clearance_m = std::min(sample.clearance_m, distanceTo(bodies_[id], truth_.drone.p_W_m));
    for (std::size_t id = 1; id < bodies_.size(); ++id) {  // the bodies stand where the people are now (above)
      const double apart_m = (bodies_[id].center_W_m - truth_.person.p_W_m.head<2>()).norm();
      sample.nearest_bystander_m = std::min(sample.nearest_bystander_m, apart_m);
      if (scenario_.bystanders.people[id - 1].look_alike)
        sample.nearest_look_alike_m = std::min(sample.nearest_look_alike_m, apart_m);
    }
    sample.sight = personSight(truth_.T_WC, truth_.person);
    metrics_.record(sample);
    next_metrics_ns_ += metrics_period_ns_;
  }
}

void Simulation::publishTruth() {
  const QuadrotorState& drone = quad_.state();
  const PersonState person = personAt(now_ns_);
  TruthSnapshot t;
  t.stamp_ns = now_ns_;
  t.drone_p_W_m = drone.p_W_m;
  t.drone_v_W_mps = drone.v_W_mps;
  t.drone_yaw_rad = std::atan2(drone.R_WB(1, 0), drone.R_WB(0, 0));
  t.person_p_W_m = person.p_W_m;
  t.person_v_W_mps = person.v_W_mps;
  t.camera_p_W_m = cameraPose(drone, gimbal_.angleRad()).translation();
  t.gimbal_angle_rad = gimbal_.angleRad();
  t.person_walking = rt::nsToSeconds(now_ns_ - start_ns_) >= personStartS();
  const OdometryFrameError T_OW = odometryFrameError();
  t.odom_t_OW_m = T_OW.t_m;
  t.odom_yaw_OW_rad = T_OW.yaw_rad;
  truth_out_.write(t);
}

void Simulation::physicsStep(double dt_s) {
  // The flight controller flies the odometry frame (what its estimator fuses), unaware of the wind.
  const QuadrotorState& drone = quad_.state();
  const QuadrotorCommand command =
      controller_.update(active_setpoint_, drift_ ? inOdometryFrame(drift_->error(), drone) : drone);
  if (wind_) {
    const Eigen::Vector3d f_W_n = windForceW(quad_.params(), drone, wind_->velocityW(), wind_->spec());
    quad_.step(command, dt_s, f_W_n);
    wind_->step(dt_s);
  } else {
    quad_.step(command, dt_s);
  }
  gimbal_.step(active_gimbal_command_, dt_s);
}

void Simulation::captureCamera() {
  const PersonState person = personAt(now_ns_);
  const Eigen::Isometry3d T_WC = cameraPose(quad_.state(), gimbal_.angleRad());
  const GimbalCameraSpec& spec = scenario_.spec.gimbal_camera;
  exposures_[(camera_sequence_ + 1) % exposures_.size()] = {camera_sequence_ + 1, now_ns_, T_WC};
  if (spec.mode == GimbalCameraMode::kImage) {  // the device renders it; no detector model here
    CameraExposure exposure;
    exposure.stamp_ns = now_ns_;
    exposure.sequence = ++camera_sequence_;
    exposure.T_WC = T_WC;
    exposure.person = person;
    // The nearest bystanders (a bounded insertion: the farthest kept is replaced by a nearer one).
    std::array<double, kMaxExposureBystanders> range_m{};
    for (std::size_t id = 1; id < personCount(); ++id) {
      const double r = (bodies_[id].center_W_m - T_WC.translation().head<2>()).norm();
      std::size_t slot = exposure.bystander_count;
      if (slot == kMaxExposureBystanders) {
        slot = static_cast<std::size_t>(std::max_element(range_m.begin(), range_m.end()) - range_m.begin());
        if (range_m[slot] <= r) continue;
      } else {
        ++exposure.bystander_count;
      }
      range_m[slot] = r;
      exposure.bystander_ids[slot] = id;
      exposure.bystanders[slot] = personStateAt(id, now_ns_);
    }
    exposures_out_.try_push(exposure);
    return;
  }
  const LineOfSight line_of_sight = [this](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return bystanders_.empty() ? obstacles_.segmentClear(a, b) : sightClear(a, b, sight_skip_id_);
  };
  DetectionFrame frame;
  frame.stamp_ns = now_ns_;
  frame.result_ns = now_ns_ + rt::secondsToNs(spec.latency_s);
  frame.sequence = ++camera_sequence_;
  frame.intrinsics = spec.camera.intrinsics;
  sight_skip_id_ = 0;
  target_slot_ = -1;
  if (const auto detection = observe(person.keypoints_W_m, T_WC, spec.camera, line_of_sight, camera_rng_)) {
    frame.persons[0] = *detection;
    frame.person_count = 1;
    target_slot_ = 0;
    // Which detection is followed is not the camera's to say: a multi-person detector reports
    // everyone, and the lock-on downstream chooses (perception/keypoint_lock_on.hpp), so that it can
    // be fooled by a bystander as on a real camera.
    frame.target_index = -1;
    frame.persons[0].appearance =
        measuredSignature(personAppearance(0), frame.persons[0], spec.camera.intrinsics, appearance_rng_);
    frame.persons[0].has_appearance = true;
  }
  if (!bystanders_.empty()) observeCrowd(T_WC, frame);
  // The operator designates the target while it waits to start (a follow-me app's tap on the
  // person): until then the frames name it; afterwards the lock-on is on its own.
  if (secondsSinceStart(now_ns_) < personStartS()) frame.target_index = target_slot_;
  if (pending_count_ == pending_.size()) {  // cannot happen with sane rates; drop the oldest
    pending_head_ = (pending_head_ + 1) % pending_.size();
    --pending_count_;
  }
  pending_[(pending_head_ + pending_count_) % pending_.size()] = frame;
  ++pending_count_;
}

void Simulation::observeCrowd(const Eigen::Isometry3d& T_WC, DetectionFrame& frame) {
  const GimbalCameraSpec& spec = scenario_.spec.gimbal_camera;
  const LineOfSight line_of_sight = [this](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return sightClear(a, b, sight_skip_id_);
  };
  const auto area = [](const PersonDetection& d) { return d.bbox_w_px * d.bbox_h_px; };
  candidates_.clear();
  if (frame.person_count == 1) candidates_.push_back({frame.persons[0], 0, area(frame.persons[0])});
  for (std::size_t id = 1; id < personCount(); ++id) {
    const PersonState p = personStateAt(id, now_ns_);
    sight_skip_id_ = id;
    if (const auto detection = observe(p.keypoints_W_m, T_WC, spec.camera, line_of_sight, crowd_rng_)) {
      candidates_.push_back({*detection, id, area(*detection)});
      candidates_.back().detection.appearance = measuredSignature(personAppearance(id), candidates_.back().detection,
                                                                  spec.camera.intrinsics, appearance_rng_);
      candidates_.back().detection.has_appearance = true;
    }
  }
  sight_skip_id_ = 0;
  // MoveNet multipose keeps the most salient persons: the largest boxes (ties by id, deterministic).
  const auto by_size = [](const Candidate& a, const Candidate& b) {
    return a.area_px2 != b.area_px2 ? a.area_px2 > b.area_px2 : a.id < b.id;
  };
  const std::size_t kept = std::min(candidates_.size(), kMaxPersons);
  std::partial_sort(candidates_.begin(), candidates_.begin() + static_cast<std::ptrdiff_t>(kept), candidates_.end(),
                    by_size);
  // Reported left to right, so the order does not tell which one is the target.
  const auto by_position = [](const Candidate& a, const Candidate& b) {
    if (a.detection.bbox_u_px != b.detection.bbox_u_px) return a.detection.bbox_u_px < b.detection.bbox_u_px;
    return a.id < b.id;
  };
  std::sort(candidates_.begin(), candidates_.begin() + static_cast<std::ptrdiff_t>(kept), by_position);
  frame.person_count = kept;
  frame.target_index = -1;  // the lock-on's to choose (see captureCamera)
  target_slot_ = -1;
  for (std::size_t slot = 0; slot < kept; ++slot) {
    frame.persons[slot] = candidates_[slot].detection;
    if (candidates_[slot].id == 0) target_slot_ = static_cast<int>(slot);
  }
}

void Simulation::releaseDetections() {
  while (pending_count_ > 0 && pending_[pending_head_].result_ns <= now_ns_) {
    detections_out_.try_push(pending_[pending_head_]);
    pending_head_ = (pending_head_ + 1) % pending_.size();
    --pending_count_;
  }
}

void Simulation::captureDepth() {
  const DepthCameraSpec& spec = scenario_.spec.depth_camera;
  const QuadrotorState& drone = quad_.state();
  Eigen::Isometry3d T_WC = Eigen::Isometry3d::Identity();
  T_WC.linear() = drone.R_WB * opticalAxesInFlu();
  T_WC.translation() = drone.p_W_m + drone.R_WB * spec.mount_B_m;
  auto frame = std::make_shared<DepthFrame>();
  frame->stamp_ns = now_ns_;
  frame->sequence = ++depth_sequence_;
  frame->intrinsics = depthIntrinsics(spec.camera);
  frame->T_BC.linear() = opticalAxesInFlu();
  frame->T_BC.translation() = spec.mount_B_m;
  // Everyone's body, the followed person's too, as a real depth camera sees them (issue 22: their range is a
  // measurement; the mapper leaves them out of the map) -- but not through a forced occlusion of the person, which
  // hides them from every camera on the drone (the depth camera's people would carry the track through it).
  const bool occluded = options_.faults.person_occluded.active(secondsSinceStart(now_ns_));
  std::span<const Cylinder> bodies(bodies_);
  renderDepth(obstacles_, T_WC, spec.camera, depth_rng_, frame->depth_m, occluded ? bodies.subspan(1) : bodies);
  depth_out_.write(std::move(frame));
}

void Simulation::sampleOdometry() {
  const OdometrySpec& spec = scenario_.spec.odometry;
  if (drift_) drift_->update(secondsSinceStart(now_ns_), quad_.state().p_W_m);
  // The true state expressed in the odometry frame O (O = W without drift).
  const QuadrotorState drone = drift_ ? inOdometryFrame(drift_->error(), quad_.state()) : quad_.state();
  std::normal_distribution<double> unit(0.0, 1.0);
  OdometrySample sample;
  sample.stamp_ns = now_ns_;
  sample.p_WB_m = drone.p_W_m + spec.position_noise_m *
                                    Eigen::Vector3d(unit(odometry_rng_), unit(odometry_rng_), unit(odometry_rng_));
  sample.v_WB_mps = drone.v_W_mps + spec.velocity_noise_mps *
                                        Eigen::Vector3d(unit(odometry_rng_), unit(odometry_rng_), unit(odometry_rng_));
  const Eigen::Matrix3d yaw_error =
      Eigen::AngleAxisd(spec.yaw_noise_rad * unit(odometry_rng_), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  sample.q_WB = Eigen::Quaterniond(yaw_error * drone.R_WB);
  sample.w_WB_B_radps = drone.w_B_radps;
  odometry_delay_[(odometry_head_ + odometry_count_) % odometry_delay_.size()] = sample;
  if (odometry_count_ < odometry_delay_.size())
    ++odometry_count_;
  else
    odometry_head_ = (odometry_head_ + 1) % odometry_delay_.size();
  // Publish the newest sample at least `latency` old: its stamp is when it was measured.
  const TimeNs due_ns = now_ns_ - rt::secondsToNs(spec.latency_s);
  bool published = false;
  OdometrySample ready;
  while (odometry_count_ > 0 && odometry_delay_[odometry_head_].stamp_ns <= due_ns) {
    ready = odometry_delay_[odometry_head_];
    published = true;
    odometry_head_ = (odometry_head_ + 1) % odometry_delay_.size();
    --odometry_count_;
  }
  if (published) odometry_out_.write(ready);
}

}  // namespace aerotrack::hal::sim

namespace aerotrack::hal::sim {

int Simulation::matchDetection(std::uint64_t sequence, const PersonDetection& detection, int keep_id) const {
  return match(sequence, detection, keep_id).kept;
}

Simulation::DetectionMatch Simulation::match(std::uint64_t sequence, const PersonDetection& detection,
                                             int keep_id) const {
  const Exposure& exposure = exposures_[sequence % exposures_.size()];
  if (exposure.sequence != sequence || sequence == 0) return {};
  // Within half a torso on average: farther, the detection is of nobody we simulate.
  constexpr double kMatchMaxError = 0.5;
  // Every reported keypoint against the same keypoint of each person, projected at the exposure:
  // the torso centre alone confuses two people who overlap in the image, their limbs do not.
  const CameraIntrinsics& k = scenario_.spec.gimbal_camera.camera.intrinsics;
  const Eigen::Isometry3d T_CW = exposure.T_WC.inverse();
  DetectionMatch m;
  bool keep_fits = false;
  double best_error = std::numeric_limits<double>::infinity();
  for (std::size_t id = 0; id < personCount(); ++id) {
    const PersonState p = personStateAt(id, exposure.stamp_ns);
    std::array<Eigen::Vector3d, kNumKeypoints> keypoints_C_m;
    for (std::size_t i = 0; i < kNumKeypoints; ++i) keypoints_C_m[i] = T_CW * p.keypoints_W_m[i];
    const std::optional<double> error = keypointMatchError(detection, keypoints_C_m, k);
    if (!error || !(*error <= kMatchMaxError)) continue;
    keep_fits = keep_fits || static_cast<int>(id) == keep_id;
    if (*error < best_error) {
      best_error = *error;
      m.nearest = static_cast<int>(id);
    }
  }
  m.kept = keep_fits ? keep_id : m.nearest;
  return m;
}

void Simulation::recordFollowed(const DetectionFrame& frame) {
  const double t_s = rt::nsToSeconds(frame.stamp_ns - start_ns_);
  if (frame.target_index < 0 || frame.target_index >= static_cast<int>(std::min(frame.person_count, kMaxPersons))) {
    metrics_.recordFollowed(t_s, -1);
    return;
  }
  const int before = metrics_.lastFollowedPersonId();
  const DetectionMatch m = match(frame.sequence, frame.persons[static_cast<std::size_t>(frame.target_index)], before);
  if (before >= 0 && m.kept >= 0 && m.kept != before) {
    const TimeNs exposed_ns = exposures_[frame.sequence % exposures_.size()].stamp_ns;
    const auto lookAlike = [&](int id) {
      return id >= 1 && scenario_.bystanders.people[static_cast<std::size_t>(id - 1)].look_alike;
    };
    IdentitySwitch event;
    event.t_s = t_s;
    event.from_id = before;
    event.to_id = m.kept;
    event.separation_m = (personStateAt(static_cast<std::size_t>(m.kept), exposed_ns).p_W_m -
                          personStateAt(static_cast<std::size_t>(before), exposed_ns).p_W_m)
                             .head<2>()
                             .norm();
    event.look_alike = lookAlike(before) || lookAlike(m.kept);
    metrics_.noteSwitch(event);
  }
  metrics_.recordFollowed(t_s, m.kept, m.nearest);
}

}  // namespace aerotrack::hal::sim
