// The supervisor's transitions, one by one, and every failsafe.
#include "aerotrack/supervisor/supervisor.hpp"

#include <gtest/gtest.h>

namespace aerotrack::supervisor {
namespace {

rt::TimeNs sec(double s) {
  return rt::secondsToNs(s);
}

// Every stream healthy at t, at altitude, the person seen at `seen_s` (-1: never).
SupervisorInputs healthy(double t, double seen_s = -1.0, double altitude_m = 1.5) {
  SupervisorInputs in;
  in.now_ns = sec(t);
  in.odometry_stamp_ns = sec(t);
  in.altitude_m = altitude_m;
  in.depth_stamp_ns = sec(t);
  in.camera_stamp_ns = sec(t);
  in.gimbal_stamp_ns = sec(t);
  in.person_live = seen_s >= 0.0;
  in.person_accepted_ns = seen_s >= 0.0 ? sec(seen_s) : -1;
  return in;
}

// A supervisor that took off and found the person at t = 3 s.
Supervisor tracking(const SupervisorParams& params = SupervisorParams{}) {
  Supervisor s(params, 0);
  EXPECT_EQ(s.update(healthy(1.0, -1.0, 0.5)).mode, Mode::kTakeOff);
  EXPECT_EQ(s.update(healthy(2.0, -1.0, 1.4)).mode, Mode::kSearch);
  EXPECT_EQ(s.update(healthy(3.0, 3.0)).mode, Mode::kTrack);
  return s;
}

TEST(Supervisor, TakeOffSearchTrack) {
  Supervisor s(SupervisorParams{}, 0);
  EXPECT_EQ(s.state().mode, Mode::kTakeOff);
  EXPECT_EQ(s.update(healthy(1.0, 1.0, 0.3)).mode, Mode::kTakeOff);  // seen, but still climbing
  EXPECT_EQ(s.update(healthy(2.0, -1.0, 1.3)).mode, Mode::kSearch);
  EXPECT_EQ(s.state().reason, Reason::kAltitudeReached);
  EXPECT_EQ(s.update(healthy(2.5)).mode, Mode::kSearch);  // no one yet
  EXPECT_EQ(s.update(healthy(3.0, 3.0)).mode, Mode::kTrack);
  EXPECT_EQ(s.state().reason, Reason::kPersonFound);
  EXPECT_EQ(s.state().transitions, 2U);
}

TEST(Supervisor, LostForRelocateAfterThenRelocatesAndReturnsOnReacquisition) {
  Supervisor s = tracking();
  EXPECT_EQ(s.update(healthy(3.3, 3.0)).mode, Mode::kTrack);      // 0.3 s without a measurement: still tracking
  EXPECT_EQ(s.update(healthy(3.45, 3.0)).mode, Mode::kRelocate);  // 0.45 s > 0.4 s
  EXPECT_EQ(s.state().reason, Reason::kPersonLost);
  EXPECT_EQ(s.update(healthy(4.0, 3.0)).mode, Mode::kRelocate);
  EXPECT_EQ(s.update(healthy(5.0, 4.95)).mode, Mode::kTrack);  // a new measurement
}

TEST(Supervisor, WithoutASearchRelocationTimesOutIntoHoldAndHoldEndsWhenFound) {
  SupervisorParams p;
  p.search_timeout_s = 0.0;  // no search: the hold at once (the behaviour before issue 21 item 3)
  Supervisor s = tracking(p);
  s.update(healthy(3.5, 3.0));
  ASSERT_EQ(s.state().mode, Mode::kRelocate);
  EXPECT_EQ(s.update(healthy(8.4, 3.0)).mode, Mode::kRelocate);
  EXPECT_EQ(s.update(healthy(8.6, 3.0)).mode, Mode::kHold);  // 5.1 s relocating
  EXPECT_EQ(s.state().reason, Reason::kPersonNotFound);
  EXPECT_FALSE(isFailsafe(s.state().reason));
  EXPECT_EQ(s.update(healthy(10.0, 9.9)).mode, Mode::kTrack);
}

// Issue 21 item 3: after the relocation's predicted path, a search where the person can be, for search_timeout_s.
TEST(Supervisor, RelocationTimesOutIntoTheSearchAndANewMeasurementEndsItInTrack) {
  Supervisor s = tracking();
  s.update(healthy(3.5, 3.0));
  ASSERT_EQ(s.state().mode, Mode::kRelocate);
  EXPECT_EQ(s.update(healthy(8.4, 3.0)).mode, Mode::kRelocate);
  EXPECT_EQ(s.update(healthy(8.6, 3.0)).mode, Mode::kSearch);  // 5.1 s relocating
  EXPECT_EQ(s.state().reason, Reason::kPathFlown);
  EXPECT_FALSE(isFailsafe(s.state().reason));
  EXPECT_EQ(s.update(healthy(20.0, 3.0)).mode, Mode::kSearch);
  EXPECT_EQ(s.update(healthy(21.0, 20.95)).mode, Mode::kTrack);  // a new measurement
  EXPECT_EQ(s.state().reason, Reason::kPersonFound);
}

TEST(Supervisor, TheSearchTimesOutIntoHoldPersonNotFoundWhichStillEndsWhenFound) {
  SupervisorParams p;
  p.search_timeout_s = 7.0;
  Supervisor s = tracking(p);
  s.update(healthy(3.5, 3.0));
  s.update(healthy(8.6, 3.0));
  ASSERT_EQ(s.state().mode, Mode::kSearch);
  EXPECT_EQ(s.update(healthy(15.5, 3.0)).mode, Mode::kSearch);  // 6.9 s searching
  EXPECT_EQ(s.update(healthy(15.7, 3.0)).mode, Mode::kHold);    // 7.1 s
  EXPECT_EQ(s.state().reason, Reason::kPersonNotFound);
  EXPECT_EQ(s.update(healthy(30.0, 29.9)).mode, Mode::kTrack);
}

TEST(Supervisor, OnlyAMeasurementNewerThanTheLossEndsTheSearch) {
  Supervisor s = tracking();
  s.update(healthy(3.5, 3.0));
  s.update(healthy(8.6, 3.0));
  ASSERT_EQ(s.state().mode, Mode::kSearch);
  SupervisorInputs in = healthy(9.0, 3.0);
  in.person_live = true;  // an estimate that claims to be live, but on the measurement before the loss
  EXPECT_EQ(s.update(in).mode, Mode::kSearch);
  EXPECT_EQ(s.state().reason, Reason::kPathFlown);
}

TEST(Supervisor, HoldLandsAfterItsTimeoutWhenConfigured) {
  SupervisorParams p;
  p.hold_then_land_s = 10.0;
  p.search_timeout_s = 0.0;
  Supervisor s = tracking(p);
  s.update(healthy(3.5, 3.0));
  s.update(healthy(9.0, 3.0));
  ASSERT_EQ(s.state().mode, Mode::kHold);
  EXPECT_EQ(s.update(healthy(18.0, 3.0)).mode, Mode::kHold);
  EXPECT_EQ(s.update(healthy(19.5, 3.0)).mode, Mode::kLand);
  EXPECT_EQ(s.update(healthy(20.0, 19.9)).mode, Mode::kLand);  // landing is final
}

struct Fault {
  const char* name;
  void (*apply)(SupervisorInputs&);
  Reason reason;
};

/// Every dead-sensor, link and overrun failsafe, each as a change to healthy inputs.
const Fault kFailsafeFaults[] = {
    {"odometry freezes", [](SupervisorInputs& in) { in.odometry_stamp_ns = in.now_ns - sec(0.5); },
     Reason::kStaleOdometry},
    {"depth stops", [](SupervisorInputs& in) { in.depth_stamp_ns = in.now_ns - sec(1.5); }, Reason::kNoDepth},
    {"camera frames stop", [](SupervisorInputs& in) { in.camera_stamp_ns = in.now_ns - sec(1.5); },
     Reason::kNoCameraFrames},
    {"overrun storm", [](SupervisorInputs& in) { in.deadline_overruns = 1000; }, Reason::kOverrunStorm},
    {"vehicle link lost", [](SupervisorInputs& in) { in.vehicle_link_lost = true; }, Reason::kVehicleLinkLost},
};

TEST(Supervisor, EveryFailsafeHoldsWithItsReasonAndLatches) {
  for (const Fault& fault : kFailsafeFaults) {
    Supervisor s = tracking();
    SupervisorInputs in = healthy(3.1, 3.1);
    fault.apply(in);
    EXPECT_EQ(s.update(in).mode, Mode::kHold) << fault.name;
    EXPECT_EQ(s.state().reason, fault.reason) << fault.name;
    EXPECT_TRUE(isFailsafe(s.state().reason)) << fault.name;
    // Latched: the streams recover, the person is there, it still holds.
    SupervisorInputs recovered = healthy(4.0, 4.0);
    recovered.deadline_overruns = 1000;  // cumulative counter stays where it was
    EXPECT_EQ(s.update(recovered).mode, Mode::kHold) << fault.name;
  }
}

TEST(Supervisor, PlannerFailuresWhileTrackingDegradeAndAPlanReturnsToTrack) {
  Supervisor s = tracking();
  SupervisorInputs in = healthy(3.1, 3.1);
  in.planner_failures_in_a_row = 19;
  EXPECT_EQ(s.update(in).mode, Mode::kTrack);  // one short of max_planner_failures (20)
  in = healthy(3.2, 3.2);
  in.planner_failures_in_a_row = 20;
  EXPECT_EQ(s.update(in).mode, Mode::kDegraded);
  EXPECT_EQ(s.state().reason, Reason::kPlannerFailures);
  EXPECT_FALSE(isFailsafe(s.state().reason));
  in = healthy(3.3, 3.3);
  in.planner_failures_in_a_row = 22;
  EXPECT_EQ(s.update(in).mode, Mode::kDegraded);  // still failing: still degraded
  in = healthy(3.4, 3.4);
  in.planner_failures_in_a_row = 0;  // a plan succeeded
  EXPECT_EQ(s.update(in).mode, Mode::kTrack);
  EXPECT_EQ(s.state().reason, Reason::kPlanSucceeded);
}

TEST(Supervisor, PlannerFailuresAloneNeverHoldHoweverLongTheyLast) {
  Supervisor s = tracking();
  for (int k = 0; k < 600; ++k) {  // a minute of failed plans at 10 Hz, the person seen throughout
    SupervisorInputs in = healthy(3.1 + 0.1 * k, 3.1 + 0.1 * k);
    in.planner_failures_in_a_row = 20 + k;
    ASSERT_EQ(s.update(in).mode, Mode::kDegraded) << k;
  }
  EXPECT_EQ(s.state().transitions, 3U);  // search, track, degraded: no flapping
}

TEST(Supervisor, DegradedDoesNotMaskADeadSensorAndTheFailsafeStillLatches) {
  for (const Fault& fault : kFailsafeFaults) {
    Supervisor s = tracking();
    SupervisorInputs in = healthy(3.1, 3.1);
    in.planner_failures_in_a_row = 20;
    ASSERT_EQ(s.update(in).mode, Mode::kDegraded) << fault.name;
    in = healthy(3.2, 3.2);
    in.planner_failures_in_a_row = 21;
    fault.apply(in);
    EXPECT_EQ(s.update(in).mode, Mode::kHold) << fault.name;
    EXPECT_EQ(s.state().reason, fault.reason) << fault.name;
    // Latched: the streams recover and a plan succeeds; it still holds.
    SupervisorInputs recovered = healthy(4.0, 4.0);
    recovered.deadline_overruns = 1000;
    recovered.planner_failures_in_a_row = 0;
    EXPECT_EQ(s.update(recovered).mode, Mode::kHold) << fault.name;
    EXPECT_EQ(s.state().reason, fault.reason) << fault.name;
  }
}

TEST(Supervisor, PersonLostWhileDegradedRelocates) {
  Supervisor s = tracking();
  SupervisorInputs in = healthy(3.1, 3.1);
  in.planner_failures_in_a_row = 20;
  ASSERT_EQ(s.update(in).mode, Mode::kDegraded);
  in = healthy(3.6, 3.1);  // 0.5 s without a measurement
  in.planner_failures_in_a_row = 25;
  EXPECT_EQ(s.update(in).mode, Mode::kRelocate);
  EXPECT_EQ(s.state().reason, Reason::kPersonLost);
  EXPECT_EQ(s.update(healthy(4.0, 3.95)).mode, Mode::kTrack);  // found again
}

TEST(Supervisor, PlannerFailuresWhileRelocatingOrSearchingDoNotDegradeOrHold) {
  Supervisor s = tracking();
  s.update(healthy(3.5, 3.0));
  ASSERT_EQ(s.state().mode, Mode::kRelocate);
  SupervisorInputs in = healthy(6.0, 3.0);
  in.planner_failures_in_a_row = 100;
  EXPECT_EQ(s.update(in).mode, Mode::kRelocate);  // the relocation timeout decides
  in = healthy(8.6, 3.0);
  in.planner_failures_in_a_row = 150;
  EXPECT_EQ(s.update(in).mode, Mode::kSearch);  // the search timeout decides
  EXPECT_EQ(s.state().reason, Reason::kPathFlown);
  in = healthy(28.7, 3.0);
  in.planner_failures_in_a_row = 250;
  EXPECT_EQ(s.update(in).mode, Mode::kHold);
  EXPECT_EQ(s.state().reason, Reason::kPersonNotFound);
  in = healthy(29.0, 3.0);
  in.planner_failures_in_a_row = 300;
  EXPECT_EQ(s.update(in).mode, Mode::kHold);
  EXPECT_EQ(s.state().reason, Reason::kPersonNotFound);
  EXPECT_EQ(s.update(healthy(30.0, 29.9)).mode, Mode::kTrack);  // found at last, minutes later
}

TEST(Supervisor, ADeadSensorWhileSearchingAfterTheTimeoutLatchesAFailsafeHold) {
  for (const double search_timeout_s : {20.0, 0.0}) {  // in the search, and in hold "person not found"
    SupervisorParams p;
    p.search_timeout_s = search_timeout_s;
    Supervisor s = tracking(p);
    s.update(healthy(3.5, 3.0));
    s.update(healthy(8.6, 3.0));
    ASSERT_EQ(s.state().reason, search_timeout_s > 0.0 ? Reason::kPathFlown : Reason::kPersonNotFound);
    SupervisorInputs in = healthy(9.0, 3.0);
    in.depth_stamp_ns = sec(7.0);
    EXPECT_EQ(s.update(in).mode, Mode::kHold);
    EXPECT_EQ(s.state().reason, Reason::kNoDepth);
    EXPECT_EQ(s.update(healthy(10.0, 9.9)).mode, Mode::kHold);  // latched: finding the person does not end it
  }
}

TEST(Supervisor, OverrunsAreCountedPerWindow) {
  Supervisor s = tracking();
  SupervisorInputs in = healthy(3.1, 3.1);
  std::uint64_t overruns = 0;
  for (int k = 0; k < 100; ++k) {  // 10 overruns a second for 10 s: below 50 per window
    in = healthy(3.1 + 0.1 * k, 3.1 + 0.1 * k);
    overruns += 1;
    in.deadline_overruns = overruns;
    EXPECT_EQ(s.update(in).mode, Mode::kTrack) << k;
  }
}

TEST(Supervisor, SilentStreamsAreToleratedDuringStartupGraceOnly) {
  Supervisor s(SupervisorParams{}, 0);
  SupervisorInputs in;
  in.now_ns = sec(1.0);  // nothing received yet
  EXPECT_EQ(s.update(in).mode, Mode::kTakeOff);
  in.now_ns = sec(2.5);
  EXPECT_EQ(s.update(in).mode, Mode::kHold);
  EXPECT_EQ(s.state().reason, Reason::kStaleOdometry);
}

// A slow start: every stream stamped once at start, the first step 0.57 s later (what System::build under
// ASan cost in CI): not a failsafe while the grace lasts, but one once the grace is over and a stream is still old.
TEST(Supervisor, AStreamHeardOnceAtStartIsNotStaleDuringTheGrace) {
  Supervisor s(SupervisorParams{}, 0);
  SupervisorInputs in = healthy(0.0, -1.0, 0.0);
  in.now_ns = sec(0.57);
  EXPECT_EQ(s.update(in).mode, Mode::kTakeOff);
  SupervisorInputs fresh = healthy(1.9, -1.0, 0.5);
  fresh.gimbal_stamp_ns = 0;  // the gimbal still at its first state, the others renewed
  EXPECT_EQ(s.update(fresh).mode, Mode::kTakeOff);
  fresh = healthy(2.1, -1.0, 0.5);
  fresh.gimbal_stamp_ns = 0;
  EXPECT_EQ(s.update(fresh).mode, Mode::kHold);
  EXPECT_EQ(s.state().reason, Reason::kNoGimbalState);
}

TEST(SupervisorParams, EveryKeyIsRequiredAndChecked) {
  auto node = rt::ConfigNode::fromString(
      "s:\n  takeoff_altitude_m: 1.5\n  takeoff_tolerance_m: 0.3\n  relocate_after_s: 0.4\n"
      "  relocate_timeout_s: 5.0\n  search_timeout_s: 20.0\n  hold_then_land_s: 0.0\n  odometry_timeout_s: 0.2\n  "
      "depth_timeout_s: 1.0\n"
      "  camera_timeout_s: 1.0\n  gimbal_timeout_s: 0.5\n  max_planner_failures: 20\n  overrun_storm: 50\n  "
      "overrun_window_s: 1.0\n"
      "  startup_grace_s: 2.0\n",
      "s.yaml");
  ASSERT_TRUE(node.has_value());
  const SupervisorParams p = parseSupervisorParams(node->child("s"));
  EXPECT_TRUE(validate(p).has_value());
  EXPECT_EQ(p.relocate_after_s, 0.4);
  EXPECT_EQ(p.search_timeout_s, 20.0);
  SupervisorParams bad = p;
  bad.search_timeout_s = -1.0;
  EXPECT_EQ(validate(bad).error().message, "search_timeout_s must be >= 0");
  auto missing = rt::ConfigNode::fromString("s:\n  takeoff_altitude_m: 1.5\n", "s.yaml");
  ASSERT_TRUE(missing.has_value());
  EXPECT_THROW(parseSupervisorParams(missing->child("s")), rt::ConfigError);
}

}  // namespace
}  // namespace aerotrack::supervisor
