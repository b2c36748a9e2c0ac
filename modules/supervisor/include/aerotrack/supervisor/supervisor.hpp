// The supervisor (issue 9 item 2): one mode machine that decides what the drone is doing, from the
// health of every stream and the state of the person estimate. Transitions (each tested):
//   take_off --(altitude reached)--> search
//   search   --(person estimate live)--> track
//   track    --(no accepted measurement for relocate_after_s)--> relocate   (paper: target relocating)
//   relocate --(a new measurement accepted)--> track
//   relocate --(relocate_timeout_s without one; search_timeout_s > 0)--> search (reason: relocation path flown)
//   relocate --(relocate_timeout_s without one; search_timeout_s = 0)--> hold (reason: person not found)
//   search (relocation path flown) --(a new measurement accepted)--> track
//   search (relocation path flown) --(search_timeout_s without one)--> hold (reason: person not found)
//   hold (person not found) --(a new measurement accepted)--> track
//   track    --(max_planner_failures failed planning cycles in a row)--> degraded (issue 21)
//   degraded --(a planning cycle succeeds, the person still seen)--> track
//   degraded --(no accepted measurement for relocate_after_s)--> relocate
//            (failed plans while relocating or searching do not count: the relocation timeout ends those)
//   any but land --(failsafe)--> hold, with the reason: the flight controller's link lost, stale odometry,
//            no depth images, no camera frames, a storm of deadline overruns. A failsafe hold is latched.
//   hold --(hold_then_land_s, if > 0)--> land
// In relocate the planner flies along the person's last predicted path and the gimbal sweeps (the
// paper's strategy); in search after a relocation (issue 21 item 3) the planner flies a search pattern over where
// the person can be (modules/planning/relocation) while the gimbal sweeps; in hold the drone brakes and hovers (and, in
// hold "person not found", the gimbal keeps sweeping: the search goes on from the hover); in land it descends. In
// degraded the planner brakes to a hover once and goes on planning every cycle, the gimbal kept on the person's
// estimate: a failed plan is the planner's problem, not the sensors', so it must not end the flight (issue 21: a
// latched hold on a planner streak lost a person who only doubled back past the drone). Pure: the time and every health
// signal come in; the supervisor reads no clock and no channel.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "aerotrack/rt/config_node.hpp"
#include "aerotrack/rt/expected.hpp"
#include "aerotrack/rt/time.hpp"

namespace aerotrack::supervisor {

enum class Mode : std::uint8_t { kTakeOff, kSearch, kTrack, kRelocate, kHold, kLand, kDegraded };
inline constexpr std::size_t kModeCount = 7;
std::string_view toString(Mode mode);

/// Why the mode is what it is (the last transition's cause).
enum class Reason : std::uint8_t {
  kStart,
  kAltitudeReached,
  kPersonFound,
  kPersonLost,
  kPersonNotFound,
  kStaleOdometry,
  kNoDepth,
  kNoCameraFrames,
  kNoGimbalState,  ///< The gimbal motor's encoder went silent: the camera's bearing is unknown.
  kPlannerFailures,
  kOverrunStorm,
  kVehicleLinkLost,
  kHoldTimeout,
  kPlanSucceeded,  ///< Degraded ends: a planning cycle succeeded.
  kPathFlown,      ///< Relocation's predicted path flown without finding them: search where they can be.
};
std::string_view toString(Reason reason);
/// Whether the reason is a failsafe (a latched hold).
bool isFailsafe(Reason reason);

struct SupervisorParams {
  double takeoff_altitude_m = 1.5;   ///< Take-off ends within takeoff_tolerance_m of this; > 0.
  double takeoff_tolerance_m = 0.3;  ///< >= 0.
  double relocate_after_s = 0.4;     ///< Lost this long (no accepted measurement): relocate; > 0.
  double relocate_timeout_s = 5.0;   ///< Relocating this long without finding them: search; > 0.
  double search_timeout_s = 20.0;    ///< Searching this long after that: hold (0: no search, hold at once); >= 0.
  double hold_then_land_s = 0.0;     ///< Holding this long: land (0: hold forever); >= 0.
  double odometry_timeout_s = 0.2;   ///< Newest odometry older than this: failsafe; > 0.
  double depth_timeout_s = 1.0;      ///< Newest depth image older than this: failsafe; > 0.
  double camera_timeout_s = 1.0;     ///< Newest gimbal-camera frame older than this: failsafe; > 0.
  double gimbal_timeout_s = 0.5;     ///< Newest gimbal encoder reading older than this: failsafe; > 0.
  int max_planner_failures = 20;     ///< Failed planning cycles in a row while tracking: degraded; >= 1.
  int overrun_storm = 50;            ///< Deadline overruns within overrun_window_s: failsafe; >= 1.
  double overrun_window_s = 1.0;     ///< > 0.
  double startup_grace_s = 2.0;      ///< No stream is stale this long after start (silent or heard once); >= 0.
};

rt::Status validate(const SupervisorParams& params);
/// Every field by its name, all required; throws rt::ConfigError naming the key.
SupervisorParams parseSupervisorParams(const rt::ConfigNode& node);

/// What the supervisor watches. Stamps of -1: never received.
struct SupervisorInputs {
  rt::TimeNs now_ns = 0;
  rt::TimeNs odometry_stamp_ns = -1;
  double altitude_m = 0.0;
  rt::TimeNs depth_stamp_ns = -1;
  rt::TimeNs camera_stamp_ns = -1;
  rt::TimeNs gimbal_stamp_ns = -1;     ///< The newest gimbal encoder reading.
  bool person_live = false;            ///< The estimate is initialised and not lost.
  rt::TimeNs person_accepted_ns = -1;  ///< Capture time of its newest accepted measurement.
  int planner_failures_in_a_row = 0;
  std::uint64_t deadline_overruns = 0;  ///< Cumulative missed deadlines of the periodic tasks (real-time only).
  /// The vehicle link was up and is now down (issue 11: e.g. no MAVLink heartbeat from the autopilot).
  /// Setpoints no longer reach the vehicle, whose own failsafe flies it; holding keeps the plan from
  /// running on, so that a link that comes back resumes from a hover, not a stale trajectory.
  bool vehicle_link_lost = false;
};

struct SupervisorState {
  Mode mode = Mode::kTakeOff;
  Reason reason = Reason::kStart;
  rt::TimeNs since_ns = 0;  ///< When the mode was entered.
  std::uint64_t transitions = 0;
};

/// Not thread-safe (one task). No allocation.
class Supervisor {
 public:
  Supervisor(const SupervisorParams& params, rt::TimeNs start_ns);
  const SupervisorState& update(const SupervisorInputs& in);
  const SupervisorState& state() const { return state_; }
  const SupervisorParams& params() const { return params_; }

 private:
  void enter(Mode mode, Reason reason, rt::TimeNs now_ns);
  bool failsafe(const SupervisorInputs& in, Reason& reason);

  SupervisorParams params_;
  rt::TimeNs start_ns_;
  SupervisorState state_;
  rt::TimeNs lost_accepted_ns_ = -1;  ///< The newest accepted measurement when the person was lost.
  rt::TimeNs overrun_window_start_ns_ = 0;
  std::uint64_t overruns_at_window_start_ = 0;
};

}  // namespace aerotrack::supervisor
