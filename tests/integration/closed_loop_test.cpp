// The closed loop on the sim HAL in lockstep (issue 9): the planner flies from the estimated person, the
// gimbal controller keeps them in frame, the supervisor watches. Tracking through sharp_turn at 1.5 m/s;
// holding the tracking distance at 2.5 m/s; relocation after a forced 2 s occlusion; each failsafe under its injected
// fault (camera frames stop, odometry freezes, depth stops; issue 23: depth frames of zeros, the gimbal encoder silent,
// the vehicle link lost) holds the drone without collision; the gimbal stuck, frames late and garbage keypoints are
// ridden out; a planner forced to fail degrades to a hover; each task of the drone held up 2 s ends safe.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <ostream>
#include <sstream>
#include <string>

#include "app_config.hpp"
#include "run_executors.hpp"
#include "sim_report.hpp"
#include "support/require.hpp"
#include "system.hpp"

namespace aerotrack::app {
namespace {

const std::string kConfigDir = AEROTRACK_SOURCE_DIR "/config";

// config/sim.yaml with the localization path made absolute and `line` replaced by `with` (if given).
std::string simYaml(const std::string& line = "", const std::string& with = "") {
  std::ifstream in(kConfigDir + "/sim.yaml");
  std::stringstream buffer;
  buffer << in.rdbuf();
  std::string text = buffer.str();
  const std::string relative = "localization_params: localization.yaml";
  text.replace(text.find(relative), relative.size(), "localization_params: " + kConfigDir + "/localization.yaml");
  const std::string relative_image = "localization_params_image: localization_image.yaml";
  text.replace(text.find(relative_image), relative_image.size(),
               "localization_params_image: " + kConfigDir + "/localization_image.yaml");
  if (!line.empty()) {
    const auto pos = text.find(line);
    EXPECT_NE(pos, std::string::npos) << line;
    text.replace(pos, line.size(), with);
  }
  return text;
}

std::string withFault(const std::string& fault) {
  return simYaml("  render_depth: true\n", "  render_depth: true\n  faults:\n    " + fault + "\n");
}

struct Flight {
  nlohmann::json summary;
  std::string mode;                // the supervisor's at the end
  std::string reason;              // and why
  std::vector<std::string> modes;  // every mode entered, in order
  std::vector<double> modes_at_s;  // and when
  double final_speed_mps = 0.0;
  std::uint64_t plans_refused_late = 0;  // by the trajectory server (issue 23's task overrun)
};

Flight fly(const std::string& yaml, std::uint64_t seed, double sim_s, std::optional<double> speed_mps = std::nullopt,
           const std::string& scenario = "sharp_turn") {
  auto config = parseAppConfig(yaml, "closed_loop.yaml");
  EXPECT_TRUE(config) << (config ? "" : config.error().message);
  auto trial = loadTrial(kConfigDir + "/scenarios/" + scenario + ".yaml", seed, speed_mps);
  EXPECT_TRUE(trial) << (trial ? "" : trial.error().message);
  if (!config || !trial) return {};
  auto system = System::build(*config, &trial.value(), 0);
  EXPECT_TRUE(system) << (system ? "" : system.error().message);
  if (!system) return {};
  rt::ManualClock clock(0);
  const std::atomic<bool> stop{false};
  RunInfo info;  // as `aerotrack sim` runs it (a task_overrun fault included)
  const rt::Status ran = runLockstep(**system, clock, rt::secondsToNs(std::min(sim_s, trial->duration_s)), stop, info);
  EXPECT_TRUE(ran) << (ran ? "" : ran.error().message);
  const hal::sim::Simulation& sim = aerotrack::test::require((*system)->devices().simulation.get(), "the simulation");
  Flight f;
  f.summary = simSummary(sim, info);
  const supervisor::SupervisorTask& sup = aerotrack::test::require((*system)->supervisorTask(), "the supervisor task");
  f.mode = supervisor::toString(sup.state().mode);
  f.reason = supervisor::toString(sup.state().reason);
  for (std::size_t i = 0; i < sup.transitionCount(); ++i) {
    f.modes.emplace_back(supervisor::toString(sup.transitions()[i].mode));
    f.modes_at_s.push_back(static_cast<double>(sup.transitions()[i].at_ns) * 1e-9);
  }
  f.final_speed_mps = sim.truth().drone.v_W_mps.norm();
  if (const planning::PlanningTask* planner = (*system)->planningTask())
    f.plans_refused_late = planner->refusedByServer();
  return f;
}

TEST(ClosedLoop, TracksThePersonThroughTheSharpTurnAt1_5Mps) {
  for (const std::uint64_t seed : {1U, 2U}) {
    const Flight f = fly(simYaml(), seed, 1000.0, 1.5);
    EXPECT_TRUE(f.summary["success"].get<bool>()) << f.summary.dump(2);
    EXPECT_EQ(f.summary["collisions"], 0);
    // The building's corner hides the person for a second or two at the turn (the path keeps 0.9 m from
    // the wall); every loss must end with the person found again (the success verdict above).
    EXPECT_GT(f.summary["visible_ratio"].get<double>(), 0.9);
    EXPECT_EQ(f.mode, "track");
  }
}

TEST(ClosedLoop, AtARunnersPaceTheDroneHoldsTheTrackingDistanceWhereAGoalAtAFixedHorizonTrailed) {
  // sharp_turn at 2.5 m/s, seed 1 (issue 21). Before: x_tp at the 1.5 s horizon, half of it in x_g and a time
  // weight of 20 at every speed: each plan slowed towards a goal the person had long passed, the drone settled 1.5 m
  // farther back than the tracking distance, fell more than 5 m behind at the corner and was not followed
  // all the way (mean 4.0 m). Now x_tp is taken when the drone would get there.
  const Flight now = fly(simYaml(), 1, 1000.0, 2.5);
  EXPECT_TRUE(now.summary["followed_all_the_way"].get<bool>()) << now.summary["follow_failure_reason"];
  // Measured 3.03 when written, 3.29 by issue 21's end, 3.32 since the camera guesses cut-off joints (issue 22),
  // 3.08 since a plan starts the moment the person sets off and rho_t grows with the speed change (issue 21);
  // the corner included. The claim is the gap to the trailing goal below.
  EXPECT_LT(now.summary["distance_mean_m"].get<double>(), 3.25);
  EXPECT_EQ(now.summary["collisions"], 0);

  std::string before = simYaml("    max_lead_s: 3.0 ", "    max_lead_s: 0.0 ");
  for (const auto& [line, with] :
       {std::pair<std::string, std::string>{"    predicted_weight: 0.7 ", "    predicted_weight: 0.5 "},
        {"  max_time_weight_scale: 10.0 ", "  max_time_weight_scale: 1.0 "}}) {
    const auto pos = before.find(line);
    ASSERT_NE(pos, std::string::npos) << line;
    before.replace(pos, line.size(), with);
  }
  // Trailing: 3.74 m (not followed all the way until the plan from the hover, issue 21, rescued the corner).
  const Flight trailed = fly(before, 1, 1000.0, 2.5);
  EXPECT_GT(trailed.summary["distance_mean_m"].get<double>(), 3.5);
  EXPECT_GT(trailed.summary["distance_mean_m"].get<double>() - now.summary["distance_mean_m"].get<double>(), 0.4);
}

TEST(ClosedLoop, InTheCrowdTheTrackStaysOnThePersonWhereTheLockOnSwapsToABystander) {
  // The crowd scenario (issue 22 item 2): the lock-on moves to a bystander of the group and back, again and
  // again. Given only the lock-on's choice, the estimator follows it; choosing by the estimate (position and
  // colour gates), it stays on the person. The identity metrics count whom the estimator was given.
  // One seed was not enough: the test was moved from seed 4 to 6 to 3 to 1 as the system changed, and on
  // 2026-12-07 seed 1 itself went the other way when only the compiler changed (clang 16's ASan tree instead of
  // GCC 12's: a different rounding, a different flight): choosing by the estimate, 10.54 s on the look-alike
  // after one switch (the failure issue 22 leaves open, 5-10 % of the crowd trials), by the lock-on 0.64 s
  // after 24 switches. Measured over seeds 1-6 on both: by the estimate 1 switch in all (clang) and 0 (GCC),
  // by the lock-on 93 and 57, every seed at least 4. So three seeds by the estimate, at most one of them
  // more than 1 s on a bystander, against the lock-on's switches on seed 1.
  int estimate_switches = 0;
  int trials_on_a_bystander = 0;
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const Flight by_estimate = fly(simYaml(), seed, 1000.0, std::nullopt, "crowd");
    estimate_switches += by_estimate.summary["identity_switches"].get<int>();
    const double wrong_s = by_estimate.summary["time_on_wrong_person_s"].get<double>();
    if (wrong_s > 1.0) ++trials_on_a_bystander;
    std::printf("seed %llu by the estimate: %.2f s on a bystander\n", static_cast<unsigned long long>(seed), wrong_s);
  }
  const Flight by_lock_on =
      fly(simYaml("  association: estimate ", "  association: lock_on  "), 1, 1000.0, std::nullopt, "crowd");
  const int lock_on_switches = by_lock_on.summary["identity_switches"].get<int>();
  EXPECT_LE(trials_on_a_bystander, 1);
  EXPECT_LE(estimate_switches, 2);
  EXPECT_GE(lock_on_switches, 5) << by_lock_on.summary.dump(2);
  std::printf("identity switches: %d over seeds 1-3 choosing by the estimate, %d on seed 1 by the lock-on\n",
              estimate_switches, lock_on_switches);
}

TEST(ClosedLoop, RelocationReacquiresAfterAForcedTwoSecondOcclusion) {
  const Flight f = fly(withFault("person_occluded_s: [15.0, 17.0]"), 1, 1000.0);
  ASSERT_GE(f.modes.size(), 4U);
  EXPECT_NE(std::find(f.modes.begin(), f.modes.end(), "relocate"), f.modes.end());
  EXPECT_EQ(f.mode, "track");  // found again
  EXPECT_TRUE(f.summary["success"].get<bool>()) << f.summary.dump(2);
  EXPECT_EQ(f.summary["collisions"], 0);
}

struct FaultCase {
  const char* fault;  // the sim fault, or a config line to replace
  const char* with;
  const char* reason;
};
void PrintTo(const FaultCase& c, std::ostream* os) {
  *os << c.fault;
}  // the test's name in ctest

class Failsafe : public ::testing::TestWithParam<FaultCase> {};

TEST_P(Failsafe, FiresAndTheDroneHoldsWithoutCollision) {
  const FaultCase c = GetParam();
  const std::string yaml = std::string(c.with).empty() ? withFault(c.fault) : simYaml(c.fault, c.with);
  const Flight f = fly(yaml, 1, 18.0);
  EXPECT_EQ(f.mode, "hold");
  EXPECT_EQ(f.reason, c.reason);
  EXPECT_EQ(f.summary["collisions"], 0);
  EXPECT_LT(f.final_speed_mps, 0.3);  // braked to a hover
}

INSTANTIATE_TEST_SUITE_P(
    Faults, Failsafe,
    ::testing::Values(FaultCase{"camera_stop_s: [10.0, 1000.0]", "", "failsafe: no camera frames"},
                      FaultCase{"odometry_freeze_s: [10.0, 1000.0]", "", "failsafe: stale odometry"},
                      FaultCase{"depth_stop_s: [10.0, 1000.0]", "", "failsafe: no depth images"},
                      // Issue 23's fault matrix: each ends in a latched hold.
                      FaultCase{"depth_zero_s: [10.0, 1000.0]", "", "failsafe: no depth images"},
                      FaultCase{"gimbal_silent_s: [10.0, 1000.0]", "", "failsafe: no gimbal state"},
                      FaultCase{"vehicle_link_lost_s: [10.0, 1000.0]", "", "failsafe: vehicle link lost"}));

// Issue 23's fault matrix, the faults that pass: the drone rides them out, tracking again after.
class TransientFault : public ::testing::TestWithParam<const char*> {};

TEST_P(TransientFault, IsRiddenOutWithoutCollisionAndTheTrackResumes) {
  // The track resumes: tracking when the fault ends, or tracking again within the 8-10 s left of the flight;
  // never a failsafe hold or a landing. (Until 2026-12-07 the claim was "tracking at t = 24 s": with clang's
  // ASan tree instead of GCC's, seed 1's garbage keypoints were ridden out -- tracking again at 19.0 s -- and the
  // person was lost once more at 19.7 s and found at 24.9 s; GCC's seed 2 does the same, 20.7 to 27.2 s.)
  const std::string fault = GetParam();
  const double fault_end_s = std::stod(fault.substr(fault.find(',') + 1));  // "name: [start, end]"
  const Flight f = fly(withFault(fault), 1, 24.0);
  std::string mode_at_fault_end;
  bool tracked_again = false;
  std::string transitions;  // for the failure message
  for (std::size_t i = 0; i < f.modes.size(); ++i) {
    const std::string& mode = f.modes[i];
    transitions += " " + mode + "@" + std::to_string(f.modes_at_s[i]);
    if (f.modes_at_s[i] <= fault_end_s)
      mode_at_fault_end = mode;
    else if (mode == "track")
      tracked_again = true;
    EXPECT_NE(mode, "hold") << f.reason;
    EXPECT_NE(mode, "land") << f.reason;
  }
  EXPECT_TRUE(mode_at_fault_end == "track" || tracked_again) << transitions;
  EXPECT_EQ(f.summary["collisions"], 0);
}

INSTANTIATE_TEST_SUITE_P(Faults, TransientFault,
                         ::testing::Values("gimbal_stuck_s: [12.0, 14.0]",        // the motor ignores commands 2 s
                                           "camera_late_s: [12.0, 16.0]",         // frames 0.5 s late for 4 s
                                           "detector_garbage_s: [12.0, 14.0]"));  // random keypoints 2 s

// Issue 23's fault matrix, a task overrunning its budget: one release of each of the drone's tasks takes 2 s
// (rt::LockstepExecutor::stall). Measured 2026-11-27 (docs/modules/closed-loop.md, "Fault matrix"): the
// planner's is ridden out (its late plan refused by the trajectory server); a device task's silence trips
// that device's failsafe; every other task misses more than overrun_storm (50) periods, and the supervisor
// holds. Each is safe; a collision, a hold still moving or any other end is not.
struct OverrunCase {
  const char* task;
  const char* end;  // the supervisor's reason at the end
};
void PrintTo(const OverrunCase& c, std::ostream* os) {
  *os << c.task;
}

class TaskOverrun : public ::testing::TestWithParam<OverrunCase> {};

TEST_P(TaskOverrun, OfTwoSecondsEndsInTheTrackOrABrakedFailsafeHoldWithoutCollision) {
  const OverrunCase c = GetParam();
  const Flight f = fly(withFault(std::string("task_overrun: {task: ") + c.task + ", window_s: [12.0, 14.0]}"), 1, 20.0);
  EXPECT_EQ(f.summary["collisions"], 0);
  EXPECT_EQ(f.reason, c.end);
  if (std::string(c.task) == "planning") {
    EXPECT_EQ(f.mode, "track");
    EXPECT_EQ(f.plans_refused_late, 1U);  // the plan made at 12 s, handed over at 14 s
  } else {
    EXPECT_EQ(f.mode, "hold");
    EXPECT_LT(f.final_speed_mps, 0.3);  // braked to a hover
  }
}

INSTANTIATE_TEST_SUITE_P(Faults, TaskOverrun,
                         ::testing::Values(OverrunCase{"odometry", "failsafe: stale odometry"},
                                           OverrunCase{"gimbal", "failsafe: no gimbal state"},
                                           OverrunCase{"gimbal_camera", "failsafe: no camera frames"},
                                           OverrunCase{"depth_camera", "failsafe: no depth images"},
                                           OverrunCase{"mapping", "failsafe: deadline overrun storm"},
                                           OverrunCase{"target", "failsafe: deadline overrun storm"},
                                           OverrunCase{"planning", "person found"},
                                           OverrunCase{"gimbal_control", "failsafe: deadline overrun storm"},
                                           OverrunCase{"supervisor", "failsafe: deadline overrun storm"},
                                           OverrunCase{"trajectory_server", "failsafe: deadline overrun storm"}));

// Every plan fails its final check (an impossible speed limit): failures in a row are no failsafe (issue 21).
// The supervisor degrades: the drone brakes to a hover, the gimbal stays on the person, planning goes on.
TEST(ClosedLoop, PlannerFailuresInARowDegradeToAHoverWithoutCollisionNotToALatchedHold) {
  // Every plan fails its final check: the collision sweep's sphere is made 3 m wide, so every
  // trajectory touches the mapped building or pillars (the take-off is not checked against the map).
  const std::string yaml =
      simYaml("    radius_m: 0.25\n    sample_step_m: 0.05", "    radius_m: 3.0\n    sample_step_m: 0.05");
  const Flight f = fly(yaml, 1, 18.0);
  EXPECT_EQ(f.mode, "degraded");
  EXPECT_EQ(f.reason, "planner failures in a row");
  EXPECT_EQ(f.summary["collisions"], 0);
  EXPECT_LT(f.final_speed_mps, 0.3);  // braked to a hover
}

}  // namespace
}  // namespace aerotrack::app
