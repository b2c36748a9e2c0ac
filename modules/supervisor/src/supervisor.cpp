// The mode machine: see supervisor.hpp.
#include "aerotrack/supervisor/supervisor.hpp"

#include "aerotrack/supervisor/supervisor_task.hpp"

#include <cmath>

namespace aerotrack::supervisor {

std::string_view toString(Mode mode) {
  switch (mode) {
    case Mode::kTakeOff:
      return "take_off";
    case Mode::kSearch:
      return "search";
    case Mode::kTrack:
      return "track";
    case Mode::kRelocate:
      return "relocate";
    case Mode::kHold:
      return "hold";
    case Mode::kLand:
      return "land";
    case Mode::kDegraded:
      return "degraded";
  }
  return "unknown";
}

std::string_view toString(Reason reason) {
  switch (reason) {
    case Reason::kStart:
      return "start";
    case Reason::kAltitudeReached:
      return "altitude reached";
    case Reason::kPersonFound:
      return "person found";
    case Reason::kPersonLost:
      return "person lost";
    case Reason::kPersonNotFound:
      return "person not found while relocating";
    case Reason::kStaleOdometry:
      return "failsafe: stale odometry";
    case Reason::kNoDepth:
      return "failsafe: no depth images";
    case Reason::kNoCameraFrames:
      return "failsafe: no camera frames";
    case Reason::kNoGimbalState:
      return "failsafe: no gimbal state";
    case Reason::kPlannerFailures:
      return "planner failures in a row";
    case Reason::kOverrunStorm:
      return "failsafe: deadline overrun storm";
    case Reason::kVehicleLinkLost:
      return "failsafe: vehicle link lost";
    case Reason::kHoldTimeout:
      return "held too long";
    case Reason::kPlanSucceeded:
      return "a plan succeeded";
    case Reason::kPathFlown:
      return "relocation path flown, searching";
  }
  return "unknown";
}

bool isFailsafe(Reason reason) {
  switch (reason) {
    case Reason::kStaleOdometry:
    case Reason::kNoDepth:
    case Reason::kNoCameraFrames:
    case Reason::kNoGimbalState:
    case Reason::kOverrunStorm:
    case Reason::kVehicleLinkLost:
      return true;
    default:
      return false;
  }
}

std::string_view toString(SupervisorTask::RelocationOutcome outcome) {
  using O = SupervisorTask::RelocationOutcome;
  switch (outcome) {
    case O::kSearching:
      return "searching";
    case O::kFoundRelocating:
      return "found while relocating";
    case O::kFoundSearching:
      return "found while searching";
    case O::kNotFound:
      return "not found";
    case O::kFailsafe:
      return "failsafe";
    case O::kLanded:
      return "landed";
  }
  return "unknown";
}

rt::Status validate(const SupervisorParams& p) {
  if (!(p.takeoff_altitude_m > 0.0)) return rt::Error{"takeoff_altitude_m must be > 0"};
  if (!(p.takeoff_tolerance_m >= 0.0)) return rt::Error{"takeoff_tolerance_m must be >= 0"};
  if (!(p.relocate_after_s > 0.0)) return rt::Error{"relocate_after_s must be > 0"};
  if (!(p.relocate_timeout_s > 0.0)) return rt::Error{"relocate_timeout_s must be > 0"};
  if (!(p.search_timeout_s >= 0.0)) return rt::Error{"search_timeout_s must be >= 0"};
  if (!(p.hold_then_land_s >= 0.0)) return rt::Error{"hold_then_land_s must be >= 0"};
  if (!(p.odometry_timeout_s > 0.0)) return rt::Error{"odometry_timeout_s must be > 0"};
  if (!(p.depth_timeout_s > 0.0)) return rt::Error{"depth_timeout_s must be > 0"};
  if (!(p.gimbal_timeout_s > 0.0)) return rt::Error{"gimbal_timeout_s must be > 0"};
  if (!(p.camera_timeout_s > 0.0)) return rt::Error{"camera_timeout_s must be > 0"};
  if (p.max_planner_failures < 1) return rt::Error{"max_planner_failures must be >= 1"};
  if (p.overrun_storm < 1) return rt::Error{"overrun_storm must be >= 1"};
  if (!(p.overrun_window_s > 0.0)) return rt::Error{"overrun_window_s must be > 0"};
  if (!(p.startup_grace_s >= 0.0)) return rt::Error{"startup_grace_s must be >= 0"};
  return rt::ok();
}

SupervisorParams parseSupervisorParams(const rt::ConfigNode& node) {
  SupervisorParams p;
  p.takeoff_altitude_m = node.getDouble("takeoff_altitude_m", 0.1, 100.0);
  p.takeoff_tolerance_m = node.getDouble("takeoff_tolerance_m", 0.0, 10.0);
  p.relocate_after_s = node.getDouble("relocate_after_s", 0.01, 60.0);
  p.relocate_timeout_s = node.getDouble("relocate_timeout_s", 0.01, 600.0);
  p.search_timeout_s = node.getDouble("search_timeout_s", 0.0, 3600.0);
  p.hold_then_land_s = node.getDouble("hold_then_land_s", 0.0, 3600.0);
  p.odometry_timeout_s = node.getDouble("odometry_timeout_s", 0.01, 60.0);
  p.depth_timeout_s = node.getDouble("depth_timeout_s", 0.01, 60.0);
  p.camera_timeout_s = node.getDouble("camera_timeout_s", 0.01, 60.0);
  p.gimbal_timeout_s = node.getDouble("gimbal_timeout_s", 0.01, 60.0);
  p.max_planner_failures = node.getInt("max_planner_failures", 1, 100000);
  p.overrun_storm = node.getInt("overrun_storm", 1, 1000000);
  p.overrun_window_s = node.getDouble("overrun_window_s", 0.01, 60.0);
  p.startup_grace_s = node.getDouble("startup_grace_s", 0.0, 60.0);
  node.finish();
  return p;
}

Supervisor::Supervisor(const SupervisorParams& params, rt::TimeNs start_ns)
    : params_(params), start_ns_(start_ns), overrun_window_start_ns_(start_ns) {
  state_.since_ns = start_ns;
}

void Supervisor::enter(Mode mode, Reason reason, rt::TimeNs now_ns) {
  if (state_.mode == mode && state_.reason == reason) return;
  state_.mode = mode;
  state_.reason = reason;
  state_.since_ns = now_ns;
  ++state_.transitions;
}

bool Supervisor::failsafe(const SupervisorInputs& in, Reason& reason) {
  const double since_start_s = rt::nsToSeconds(in.now_ns - start_ns_);
  const bool grace = since_start_s < params_.startup_grace_s;
  // In the grace no stream is stale, whether it was never heard or heard once at start and not since: a
  // slow start (System::build under a sanitizer took 0.57 s, so the sim's first gimbal state, stamped at
  // start, was 0.57 s old at the supervisor's first step) is not a dead sensor (docs/testing.md History).
  auto stale = [&](rt::TimeNs stamp_ns, double timeout_s) {
    if (grace) return false;
    if (stamp_ns < 0) return true;
    return rt::nsToSeconds(in.now_ns - stamp_ns) > timeout_s;
  };
  // Overruns: counted from the start of a window that restarts every overrun_window_s (checked before
  // the restart, so the overruns of the window just ended count).
  const bool storm =
      in.deadline_overruns - overruns_at_window_start_ >= static_cast<std::uint64_t>(params_.overrun_storm);
  if (rt::nsToSeconds(in.now_ns - overrun_window_start_ns_) > params_.overrun_window_s) {
    overrun_window_start_ns_ = in.now_ns;
    overruns_at_window_start_ = in.deadline_overruns;
  }
  if (in.vehicle_link_lost) {  // first: with the link down, nothing else we decide reaches the vehicle
    reason = Reason::kVehicleLinkLost;
  } else if (stale(in.odometry_stamp_ns, params_.odometry_timeout_s)) {
    reason = Reason::kStaleOdometry;
  } else if (stale(in.depth_stamp_ns, params_.depth_timeout_s)) {
    reason = Reason::kNoDepth;
  } else if (stale(in.camera_stamp_ns, params_.camera_timeout_s)) {
    reason = Reason::kNoCameraFrames;
  } else if (stale(in.gimbal_stamp_ns, params_.gimbal_timeout_s)) {
    reason = Reason::kNoGimbalState;
  } else if (storm) {
    reason = Reason::kOverrunStorm;
  } else {
    return false;
  }
  return true;
}

const SupervisorState& Supervisor::update(const SupervisorInputs& in) {
  const rt::TimeNs now = in.now_ns;
  if (state_.mode == Mode::kLand) return state_;
  if (state_.mode == Mode::kHold && isFailsafe(state_.reason)) {  // latched
    if (params_.hold_then_land_s > 0.0 && rt::nsToSeconds(now - state_.since_ns) > params_.hold_then_land_s)
      enter(Mode::kLand, Reason::kHoldTimeout, now);
    return state_;
  }
  if (Reason reason{}; failsafe(in, reason)) {
    enter(Mode::kHold, reason, now);
    return state_;
  }
  const bool fresh =
      in.person_accepted_ns >= 0 && rt::nsToSeconds(now - in.person_accepted_ns) <= params_.relocate_after_s;
  switch (state_.mode) {
    case Mode::kTakeOff:
      if (in.altitude_m >= params_.takeoff_altitude_m - params_.takeoff_tolerance_m)
        enter(Mode::kSearch, Reason::kAltitudeReached, now);
      break;
    case Mode::kSearch:
      if (state_.reason == Reason::kPathFlown) {  // the search after a relocation
        if (in.person_accepted_ns > lost_accepted_ns_ && fresh) {
          enter(Mode::kTrack, Reason::kPersonFound, now);
        } else if (rt::nsToSeconds(now - state_.since_ns) > params_.search_timeout_s) {
          enter(Mode::kHold, Reason::kPersonNotFound, now);
        }
      } else if (in.person_live && fresh) {
        enter(Mode::kTrack, Reason::kPersonFound, now);
      }
      break;
    case Mode::kTrack:
    case Mode::kDegraded:
      if (!fresh) {
        lost_accepted_ns_ = in.person_accepted_ns;
        enter(Mode::kRelocate, Reason::kPersonLost, now);
      } else if (state_.mode == Mode::kTrack && in.planner_failures_in_a_row >= params_.max_planner_failures) {
        enter(Mode::kDegraded, Reason::kPlannerFailures, now);
      } else if (state_.mode == Mode::kDegraded && in.planner_failures_in_a_row == 0) {
        enter(Mode::kTrack, Reason::kPlanSucceeded, now);
      }
      break;
    case Mode::kRelocate:
    case Mode::kHold:
      if (in.person_accepted_ns > lost_accepted_ns_ && fresh) {
        enter(Mode::kTrack, Reason::kPersonFound, now);
      } else if (state_.mode == Mode::kRelocate &&
                 rt::nsToSeconds(now - state_.since_ns) > params_.relocate_timeout_s) {
        if (params_.search_timeout_s > 0.0) {
          enter(Mode::kSearch, Reason::kPathFlown, now);
        } else {
          enter(Mode::kHold, Reason::kPersonNotFound, now);
        }
      } else if (state_.mode == Mode::kHold && params_.hold_then_land_s > 0.0 &&
                 rt::nsToSeconds(now - state_.since_ns) > params_.hold_then_land_s) {
        enter(Mode::kLand, Reason::kHoldTimeout, now);
      }
      break;
    case Mode::kLand:
      break;
  }
  return state_;
}

}  // namespace aerotrack::supervisor
