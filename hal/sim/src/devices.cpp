// Sim device views onto the simulation.
#include "aerotrack/hal/sim/devices.hpp"

#include <algorithm>

namespace aerotrack::hal::sim {
namespace {

DeviceHealth simulated(const char* what, TimeNs last_ns) {
  return {DeviceHealth::State::kOk, what, last_ns, 0};
}

}  // namespace

std::optional<OdometrySample> SimOdometry::read(TimeNs now_ns) {
  auto sample = sim_->odometryOut().read();
  if (!sim_->options().faults.odometry_freeze.active(sim_->secondsSinceStart(now_ns))) {
    frozen_.reset();
    return sample;
  }
  if (!frozen_) frozen_ = sample;  // the last sample before the freeze, repeated with its old stamp
  return frozen_;
}

void SimVehicleLink::send(const Setpoint& setpoint) {
  if (sim_->options().faults.vehicle_link_lost.active(sim_->secondsSinceStart(setpoint.stamp_ns))) return;
  sim_->setpointInbox().write(setpoint);
}

VehicleStatus SimVehicleLink::status(TimeNs now_ns) {
  if (sim_->options().faults.vehicle_link_lost.active(sim_->secondsSinceStart(now_ns)))
    return {now_ns, false, true, FlightMode::kHold};
  return {now_ns, true, true, FlightMode::kOffboard};
}

void SimGimbal::command(const GimbalCommand& command) {
  if (sim_->options().faults.gimbal_stuck.active(sim_->secondsSinceStart(command.stamp_ns))) {
    sim_->gimbalInbox().write(GimbalCommand{command.stamp_ns, GimbalCommand::Mode::kRate, 0.0, 0.0, 0.0});
    return;
  }
  sim_->gimbalInbox().write(command);
}

std::optional<GimbalState> SimGimbal::read(TimeNs now_ns) {
  if (sim_->options().faults.gimbal_silent.active(sim_->secondsSinceStart(now_ns))) return std::nullopt;
  return sim_->gimbalOut().read();
}

std::optional<DetectionFrame> SimGimbalCamera::grabDetections(TimeNs now_ns) {
  const SimFaults& faults = sim_->options().faults;
  const double t_s = sim_->secondsSinceStart(now_ns);
  std::optional<DetectionFrame> frame;
  if (faults.camera_late.active(t_s) || !late_.empty()) {
    // Frames wait until kCameraLateS after their exposure; the newest due one is delivered.
    while (auto f = sim_->detectionsOut().try_pop()) {
      if (late_.size() >= 64) late_.pop_front();
      late_.push_back(*f);
    }
    const TimeNs due_ns = now_ns - (faults.camera_late.active(t_s) ? rt::secondsToNs(kCameraLateS) : 0);
    while (!late_.empty() && late_.front().stamp_ns <= due_ns) {
      frame = late_.front();
      late_.pop_front();
    }
  } else {
    frame = sim_->detectionsOut().try_pop();
  }
  if (!frame) return frame;
  if (faults.camera_stop.active(t_s)) {
    while (sim_->detectionsOut().try_pop()) {
    }
    late_.clear();
    return std::nullopt;
  }
  if (faults.person_occluded.active(t_s)) {
    frame->person_count = 0;
    frame->target_index = -1;
  }
  if (faults.detector_garbage.active(t_s)) {
    // Keypoints anywhere in the image with any score: what a detector with corrupt weights returns.
    const CameraIntrinsics& k = sim_->scenario().spec.gimbal_camera.camera.intrinsics;
    std::uniform_real_distribution<double> u(0.0, k.width_px), v(0.0, k.height_px), score(0.0, 1.0);
    for (std::size_t i = 0; i < std::min(frame->person_count, kMaxPersons); ++i) {
      for (Keypoint2D& kp : frame->persons[i].keypoints) kp = {u(garbage_rng_), v(garbage_rng_), score(garbage_rng_)};
    }
  }
  return frame;
}

DeviceHealth SimOdometry::health(TimeNs) const {
  const auto last = sim_->odometryOut().read();
  return simulated("simulated odometry (truth + noise, delayed)", last ? last->stamp_ns : 0);
}

DeviceHealth SimVehicleLink::health(TimeNs now_ns) const {
  return simulated("simulated flight controller", now_ns);
}

DeviceHealth SimGimbal::health(TimeNs) const {
  const auto last = sim_->gimbalOut().read();
  return simulated("simulated gimbal motor", last ? last->stamp_ns : 0);
}

DeviceHealth SimGimbalCamera::health(TimeNs now_ns) const {
  if (sim_->renderer() != nullptr) return simulated("simulated gimbal camera, image mode", last_stamp_ns_);
  return simulated("simulated gimbal camera, keypoint mode", now_ns);
}

std::shared_ptr<ImageFrame> SimGimbalCamera::freeFrame() {
  std::shared_ptr<ImageFrame> frame = pool_.acquire();  // a frame no one holds any more
  // Its pixels may still be shared by a cv::Mat someone copied out of it: then they are theirs, and the
  // renderer draws into new ones. OpenCV counts Mat references with acq_rel atomics; this acquire load
  // pairs with the other holder's release of them.
  if (frame->bgr.u != nullptr && __atomic_load_n(&frame->bgr.u->refcount, __ATOMIC_ACQUIRE) != 1) frame->bgr.release();
  return frame;
}

ImageFrameHandle SimGimbalCamera::grab(TimeNs now_ns) {
  const SceneRenderer* renderer = sim_->renderer();
  if (renderer == nullptr) return {};
  const SimFaults& faults = sim_->options().faults;
  const double t_s = sim_->secondsSinceStart(now_ns);
  std::optional<CameraExposure> newest;
  if (faults.camera_late.active(t_s) || !late_exposures_.empty()) {
    // As grabDetections: exposures wait until kCameraLateS after they were taken; the newest due one
    // is rendered (the frame shows the world as it was then, stamped then).
    while (auto exposure = sim_->exposuresOut().try_pop()) {
      if (late_exposures_.size() >= 64) late_exposures_.pop_front();
      late_exposures_.push_back(std::move(*exposure));
    }
    const TimeNs due_ns = now_ns - (faults.camera_late.active(t_s) ? rt::secondsToNs(kCameraLateS) : 0);
    while (!late_exposures_.empty() && late_exposures_.front().stamp_ns <= due_ns) {
      newest = std::move(late_exposures_.front());
      late_exposures_.pop_front();
    }
  } else {
    while (auto exposure = sim_->exposuresOut().try_pop()) newest = std::move(exposure);
  }
  if (!newest) return {};
  if (faults.camera_stop.active(t_s)) return {};
  const bool occluded = faults.person_occluded.active(t_s);
  std::shared_ptr<ImageFrame> frame = freeFrame();
  frame->stamp_ns = newest->stamp_ns;
  frame->sequence = newest->sequence;
  frame->intrinsics = renderer->params().intrinsics;
  // The target wears the scenario's person of the cast; a look-alike the same; every other bystander
  // another person of the cast (by their id), or, with a cast of one, the same photo recoloured.
  const std::size_t target = sim_->scenario().spec.gimbal_camera.target_person;
  const std::size_t cast_size = renderer->castSize();
  std::array<RenderedPerson, kMaxExposureBystanders + 1> persons{};
  persons[0] = RenderedPerson{occluded ? nullptr : &newest->person, target};
  for (std::size_t i = 0; i < newest->bystander_count; ++i) {
    const std::size_t id = newest->bystander_ids[i];
    const Bystander& b = sim_->scenario().bystanders.people[id - 1];
    RenderedPerson& look = persons[i + 1];
    look.state = &newest->bystanders[i];
    look.person = castPersonFor(id, b.look_alike, target, cast_size);
    look.recolour = !b.look_alike && cast_size == 1;
    look.clothing_bgr = clothingBgr(b.clothing);
  }
  renderer->render(sim_->obstacles(), newest->T_WC,
                   std::span<const RenderedPerson>(persons.data(), newest->bystander_count + 1), frame->bgr, scratch_);
  last_stamp_ns_ = newest->stamp_ns;
  return frame;
}

DeviceHealth SimDepthCamera::health(TimeNs) const {
  const auto last = sim_->depthOut().read();
  return simulated("simulated depth camera", last ? last->stamp_ns : 0);
}

DepthFrameHandle SimDepthCamera::grab(TimeNs now_ns) {
  const std::uint64_t version = sim_->depthOut().version();
  if (version == version_) return {};
  version_ = version;
  const double t_s = sim_->secondsSinceStart(now_ns);
  if (sim_->options().faults.depth_stop.active(t_s)) return {};
  DepthFrameHandle frame = sim_->depthOut().read();
  if (!frame || !sim_->options().faults.depth_zero.active(t_s)) return frame;
  if (!zeros_ || zeros_.use_count() > 1) zeros_ = std::make_shared<DepthFrame>();
  *zeros_ = *frame;
  zeros_->depth_m = cv::Mat::zeros(frame->depth_m.size(), CV_32FC1);
  return zeros_;
}

}  // namespace aerotrack::hal::sim
