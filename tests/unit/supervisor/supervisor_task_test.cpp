// The supervisor task reads every health signal from its channels: here the real-time executor's
// missed deadlines reach the overrun-storm failsafe, the gimbal is asked to sweep while searching (also after a
// relocation's timeout), planner failures degrade, and every relocation is logged with how it ended.
#include "aerotrack/supervisor/supervisor_task.hpp"

#include <gtest/gtest.h>

#include <memory>

namespace aerotrack::supervisor {
namespace {

struct Rig {
  rt::LatestSlot<hal::OdometrySample> odometry;
  rt::SharedSlot<hal::DepthFrame> depth;
  std::atomic<rt::TimeNs> camera_ns{-1};
  rt::LatestSlot<hal::GimbalState> gimbal;
  rt::LatestSlot<estimation::TargetEstimate> target;
  std::atomic<int> planner_failures{0};
  std::atomic<std::uint64_t> deadline_misses{0};
  std::atomic<bool> link_lost{false};
  rt::LatestSlot<SupervisorState> out;
  std::atomic<bool> sweep{false};
  bool gimbal_alive = true;
  SupervisorTask task{SupervisorParams{}, 0,
                      SupervisorChannels{odometry, depth, camera_ns, gimbal, target, planner_failures, deadline_misses,
                                         link_lost, out, sweep},
                      /*sweep_when_searching=*/true};

  // Every stream fresh at t_s, flying at 1.5 m; the person seen now when `seen`.
  void step(double t_s, bool seen) {
    const rt::TimeNs now_ns = rt::secondsToNs(t_s);
    hal::OdometrySample o;
    o.stamp_ns = now_ns;
    o.p_WB_m.z() = 1.5;
    odometry.write(o);
    auto frame = std::make_shared<hal::DepthFrame>();
    frame->stamp_ns = now_ns;
    depth.write(std::move(frame));
    camera_ns.store(now_ns);
    if (gimbal_alive) {
      hal::GimbalState g;
      g.stamp_ns = now_ns;
      gimbal.write(g);
    }
    estimation::TargetEstimate e;
    e.stamp_ns = now_ns;
    e.initialised = true;
    e.lost = !seen;
    e.last_accepted_ns = seen ? now_ns : 0;
    target.write(e);
    task.step(now_ns);
  }
};

TEST(SupervisorTask, AGimbalEncoderGoneSilentIsAFailsafeHold) {
  // Issue 23's fault matrix: with the encoder silent, the camera's bearing is unknown and the person
  // is placed wrongly; the drone flew on and passed 0.16 m from an obstacle.
  Rig rig;
  double t = 0.0;
  for (; t < 3.0; t += 0.02) rig.step(t, true);
  ASSERT_EQ(rig.out.read()->mode, Mode::kTrack);
  rig.gimbal_alive = false;
  for (const double end = t + 0.4; t < end; t += 0.02) rig.step(t, true);
  EXPECT_EQ(rig.out.read()->mode, Mode::kTrack);  // within gimbal_timeout_s (0.5 s)
  for (const double end = t + 0.3; t < end; t += 0.02) rig.step(t, true);
  EXPECT_EQ(rig.out.read()->mode, Mode::kHold);
  EXPECT_EQ(rig.out.read()->reason, Reason::kNoGimbalState);
}

TEST(SupervisorTask, MissedDeadlinesFromTheExecutorTriggerTheOverrunStorm) {
  Rig rig;
  double t = 0.0;
  for (; t < 3.0; t += 0.02) rig.step(t, true);
  ASSERT_EQ(rig.out.read()->mode, Mode::kTrack);
  EXPECT_FALSE(rig.sweep.load());
  rig.deadline_misses.store(10);  // a few: below the storm (50 per 1 s window)
  for (const double end = t + 1.5; t < end; t += 0.02) rig.step(t, true);
  EXPECT_EQ(rig.out.read()->mode, Mode::kTrack);
  rig.deadline_misses.store(10 + SupervisorParams{}.overrun_storm);
  for (const double end = t + 1.5; t < end; t += 0.02) rig.step(t, true);
  EXPECT_EQ(rig.out.read()->mode, Mode::kHold);
  EXPECT_EQ(rig.out.read()->reason, Reason::kOverrunStorm);
  EXPECT_EQ(rig.task.transitions()[rig.task.transitionCount() - 1].reason, Reason::kOverrunStorm);
}

TEST(SupervisorTask, LostPersonAsksTheGimbalToSweepWhileRelocating) {
  Rig rig;
  double t = 0.0;
  for (; t < 3.0; t += 0.02) rig.step(t, true);
  for (const double end = t + 1.0; t < end; t += 0.02) rig.step(t, false);
  EXPECT_EQ(rig.out.read()->mode, Mode::kRelocate);
  EXPECT_TRUE(rig.sweep.load());
}

TEST(SupervisorTask, LostVehicleLinkHoldsAndTheHoldIsLatched) {
  Rig rig;
  double t = 0.0;
  for (; t < 3.0; t += 0.02) rig.step(t, true);
  ASSERT_EQ(rig.out.read()->mode, Mode::kTrack);
  rig.link_lost.store(true);
  rig.step(t, true);
  EXPECT_EQ(rig.out.read()->mode, Mode::kHold);
  EXPECT_EQ(rig.out.read()->reason, Reason::kVehicleLinkLost);
  rig.link_lost.store(false);  // the link is back: the hold stays (a failsafe is latched)
  for (const double end = t + 1.0; t < end; t += 0.02) rig.step(t, true);
  EXPECT_EQ(rig.out.read()->mode, Mode::kHold);
  EXPECT_EQ(rig.out.read()->reason, Reason::kVehicleLinkLost);
}

TEST(SupervisorTask, TheGimbalKeepsSweepingInTheSearchAfterTheRelocationTimeoutAndTheRelocationIsLogged) {
  Rig rig;
  double t = 0.0;
  for (; t < 3.0; t += 0.02) rig.step(t, true);
  const double lost_s = t;
  for (const double end = t + 8.0; t < end; t += 0.02) rig.step(t, false);  // 0.4 s + 5 s timeout, and more
  ASSERT_EQ(rig.out.read()->mode, Mode::kSearch);
  ASSERT_EQ(rig.out.read()->reason, Reason::kPathFlown);
  EXPECT_TRUE(rig.sweep.load());  // the search pattern, the gimbal sweeping
  ASSERT_EQ(rig.task.relocationCount(), 1U);
  EXPECT_EQ(rig.task.relocations()[0].outcome, SupervisorTask::RelocationOutcome::kSearching);
  EXPECT_GE(rig.task.relocations()[0].timeout_ns, 0);
  EXPECT_EQ(rig.task.relocations()[0].end_ns, -1);
  for (const double end = t + 0.2; t < end; t += 0.02) rig.step(t, true);
  EXPECT_EQ(rig.out.read()->mode, Mode::kTrack);
  EXPECT_FALSE(rig.sweep.load());
  const SupervisorTask::Relocation& r = rig.task.relocations()[0];
  EXPECT_EQ(r.outcome, SupervisorTask::RelocationOutcome::kFoundSearching);
  EXPECT_TRUE(r.searched);
  // The rig's lost estimate carries no accepted measurement since t = 0: relocation begins at once.
  EXPECT_NEAR(rt::nsToSeconds(r.start_ns), lost_s, 0.03);
  EXPECT_NEAR(rt::nsToSeconds(r.timeout_ns - r.start_ns), 5.0, 0.03);
  EXPECT_NEAR(rt::nsToSeconds(r.end_ns), lost_s + 8.0, 0.03);
}

TEST(SupervisorTask, ASearchThatTimesOutIsLoggedAsNotFoundAndTheHoverKeepsSweeping) {
  Rig rig;
  double t = 0.0;
  for (; t < 3.0; t += 0.02) rig.step(t, true);
  const double lost_s = t;
  for (const double end = t + 26.0; t < end; t += 0.02) rig.step(t, false);  // 0.4 + 5 + 20 s, and more
  ASSERT_EQ(rig.out.read()->mode, Mode::kHold);
  ASSERT_EQ(rig.out.read()->reason, Reason::kPersonNotFound);
  EXPECT_TRUE(rig.sweep.load());
  ASSERT_EQ(rig.task.relocationCount(), 1U);
  const SupervisorTask::Relocation& r = rig.task.relocations()[0];
  EXPECT_EQ(r.outcome, SupervisorTask::RelocationOutcome::kNotFound);
  EXPECT_EQ(toString(r.outcome), "not found");
  EXPECT_NEAR(rt::nsToSeconds(r.start_ns), lost_s, 0.03);
  EXPECT_NEAR(rt::nsToSeconds(r.timeout_ns - r.start_ns), 5.0, 0.03);
  EXPECT_NEAR(rt::nsToSeconds(r.end_ns - r.timeout_ns), 20.0, 0.03);
  for (const double end = t + 0.2; t < end; t += 0.02) rig.step(t, true);
  EXPECT_EQ(rig.out.read()->mode, Mode::kTrack);  // found from the hover: the closed relocation stays as it was
  EXPECT_EQ(rig.task.relocations()[0].outcome, SupervisorTask::RelocationOutcome::kNotFound);
}

TEST(SupervisorTask, ARelocationThatFindsThePersonIsLoggedAsFound) {
  Rig rig;
  double t = 0.0;
  for (; t < 3.0; t += 0.02) rig.step(t, true);
  for (const double end = t + 1.0; t < end; t += 0.02) rig.step(t, false);
  ASSERT_EQ(rig.out.read()->mode, Mode::kRelocate);
  rig.step(t, true);
  ASSERT_EQ(rig.task.relocationCount(), 1U);
  EXPECT_EQ(rig.task.relocations()[0].outcome, SupervisorTask::RelocationOutcome::kFoundRelocating);
  EXPECT_EQ(rig.task.relocations()[0].timeout_ns, -1);
  EXPECT_NEAR(rt::nsToSeconds(rig.task.relocations()[0].end_ns - rig.task.relocations()[0].start_ns), 1.0, 0.03);
}

TEST(SupervisorTask, AFailsafeEndsARelocationAndTheFailsafeHoldDoesNotSweep) {
  Rig rig;
  double t = 0.0;
  for (; t < 3.0; t += 0.02) rig.step(t, true);
  for (const double end = t + 1.0; t < end; t += 0.02) rig.step(t, false);
  ASSERT_EQ(rig.out.read()->mode, Mode::kRelocate);
  rig.link_lost.store(true);
  rig.step(t, false);
  EXPECT_EQ(rig.out.read()->reason, Reason::kVehicleLinkLost);
  EXPECT_FALSE(rig.sweep.load());
  EXPECT_EQ(rig.task.relocations()[0].outcome, SupervisorTask::RelocationOutcome::kFailsafe);
}

TEST(SupervisorTask, PlannerFailuresDegradeWithTheGimbalKeptOnThePersonAndAPlanReturnsToTrack) {
  Rig rig;
  double t = 0.0;
  for (; t < 3.0; t += 0.02) rig.step(t, true);
  rig.planner_failures.store(SupervisorParams{}.max_planner_failures);
  for (const double end = t + 5.0; t < end; t += 0.02) rig.step(t, true);
  EXPECT_EQ(rig.out.read()->mode, Mode::kDegraded);
  EXPECT_FALSE(rig.sweep.load());                                                   // the gimbal tracks the estimate
  EXPECT_NEAR(static_cast<double>(rig.task.stepsIn(Mode::kDegraded)), 250.0, 1.0);  // all of the 5 s
  rig.planner_failures.store(0);
  rig.step(t, true);
  EXPECT_EQ(rig.out.read()->mode, Mode::kTrack);
  EXPECT_EQ(rig.out.read()->reason, Reason::kPlanSucceeded);
}

}  // namespace
}  // namespace aerotrack::supervisor
