// Bystanders in the simulator (issue 20): the generators against the geometry they promise
// (a crossing crosses the target's path between the follower and the target at the given time,
// an alongside walker keeps its offset, group members stand off the path within reach), the
// appearance signatures (look-alikes close, others far), and the Simulation with bystanders:
// depth frames see them, touching one is a collision, they hide the target (personSight and the
// keypoints), the keypoint camera reports several persons with signatures, runs are deterministic.
// Parse errors name file, line and key.
#include <gtest/gtest.h>

#include <algorithm>

#include <cmath>
#include <filesystem>
#include <string>

#include "aerotrack/hal/sim/devices.hpp"
#include "aerotrack/hal/sim/simulation.hpp"
#include "support/require.hpp"

namespace aerotrack::hal::sim {
namespace {

using rt::kNsPerSecond;

/// The target walks 1.2 m/s along +x from (0, 0) to (40, 0) after 2 s, or (walk = false) stands at
/// (target_x, 0) until 500 s. The drone hovers at (0, 0, 1.5) (or starts 3 m behind), looking along +x.
std::string crowdYaml(const std::string& bystanders, bool walk = true, double target_x = 6.0,
                      const std::string& boxes = "") {
  const std::string person = walk ? "  start_delay_s: 2.0\n  path:\n    - {p_m: [0.0, 0.0], speed_mps: 1.2}\n"
                                    "    - {p_m: [40.0, 0.0], speed_mps: 0.0}\n"
                                  : "  start_delay_s: 500.0\n  path:\n    - {p_m: [" + std::to_string(target_x) +
                                        ", 0.0], speed_mps: 1.0}\n    - {p_m: [" + std::to_string(target_x) +
                                        ", 3.0], speed_mps: 0.0}\n";
  return R"(name: test
end_margin_s: 1.0
max_duration_s: 2000.0
world:
  bounds_min_m: [-10.0, -15.0, 0.0]
  bounds_max_m: [50.0, 15.0, 4.0]
)" + (boxes.empty() ? std::string() : "  boxes:\n" + boxes) +
         "person:\n  height_m: 1.75\n  torso_m: 0.5\n" + person + R"(drone:
  start_m: [)" +
         (walk ? "-3.0" : "0.0") +
         R"(, 0.0, 1.5]
  start_yaw_rad: 0.0
  radius_m: 0.25
  mass_kg: 1.0
  thrust_to_weight: 2.5
success:
  tracking_distance_m: 2.5
  final_distance_factor: 2.0
)" + bystanders;
}

ScenarioInstance crowdInstance(const std::string& text, std::uint64_t seed = 1) {
  const ScenarioSpec spec = aerotrack::test::require(parseScenarioSpec(text, "test.yaml"), "parse");
  return aerotrack::test::require(instantiate(spec, seed), "instantiate");
}

std::unique_ptr<Simulation> crowdSim(const std::string& text, bool depth = false, std::uint64_t seed = 1) {
  SimulationOptions options;
  options.render_depth = depth;
  return aerotrack::test::require(Simulation::create(crowdInstance(text, seed), options, 0), "Simulation::create");
}

std::string crowdParseError(const std::string& text) {
  const auto spec = parseScenarioSpec(text, "test.yaml");
  return spec ? std::string("no error") : spec.error().message;
}

void hoverCrowd(Simulation& sim, double seconds, std::vector<DetectionFrame>* detections = nullptr,
                const Eigen::Vector3d& at = Eigen::Vector3d(0, 0, 1.5)) {
  Setpoint hold;
  hold.p_W_m = at;
  const rt::TimeNs start = sim.truth().stamp_ns;
  for (rt::TimeNs t = start; t <= start + rt::secondsToNs(seconds); t += 5'000'000) {
    hold.stamp_ns = t;  // streamed (the flight controller holds after 1 s without)
    sim.setpointInbox().write(hold);
    sim.step(t);
    while (auto f = sim.detectionsOut().try_pop())
      if (detections != nullptr) detections->push_back(*f);
  }
}

rt::TimeNs simNs(double t_s) {
  return rt::secondsToNs(t_s);
}

TEST(Bystanders, GivenNoSectionThenNoBystandersAndOnlyTheTargetIsAPerson) {
  const auto sim = crowdSim(crowdYaml(""));
  EXPECT_EQ(sim->personCount(), 1U);
  EXPECT_TRUE(sim->scenario().bystanders.people.empty());
  EXPECT_EQ(sim->personStateAt(0, simNs(5.0)).p_W_m, sim->personAt(simNs(5.0)).p_W_m);
}

TEST(Bystanders, CrossingCrossesTheTargetsPathBehindTheTargetAtTheGivenTime) {
  const auto sim = crowdSim(crowdYaml("bystanders:\n  crossings:\n    - {at_s: [10.0, 20.0], behind_m: 1.2}\n"));
  ASSERT_EQ(sim->personCount(), 3U);
  for (std::size_t id = 1; id <= 2; ++id) {
    const double when_s = id == 1 ? 10.0 : 20.0;
    // The time the crosser passes y = 0 (the target's path), by bisection over a sign change.
    double lo = when_s - 4.0, hi = when_s + 4.0;
    const double y_lo = sim->personStateAt(id, simNs(lo)).p_W_m.y();
    ASSERT_LT(y_lo * sim->personStateAt(id, simNs(hi)).p_W_m.y(), 0.0) << "person " << id << " does not cross";
    for (int i = 0; i < 40; ++i) {
      const double mid = 0.5 * (lo + hi);
      (sim->personStateAt(id, simNs(mid)).p_W_m.y() * y_lo > 0.0 ? lo : hi) = mid;
    }
    EXPECT_NEAR(lo, when_s, 0.3);
    // Where: 1.2 m behind the target, i.e. between the target and a follower 2.5 m behind it.
    const double target_x = sim->personAt(simNs(lo)).p_W_m.x();
    const double cross_x = sim->personStateAt(id, simNs(lo)).p_W_m.x();
    EXPECT_NEAR(target_x - cross_x, 1.2, 0.3);
    EXPECT_LT(target_x - cross_x, sim->scenario().spec.success.tracking_distance_m);
  }
}

TEST(Bystanders, AlongsideWalkerKeepsItsLateralOffsetOverTheStretch) {
  const auto sim =
      crowdSim(crowdYaml("bystanders:\n  alongside:\n    - {from_s: 6.0, to_s: 20.0, offset_m: 1.0, side: left}\n"));
  ASSERT_EQ(sim->personCount(), 2U);
  for (double t_s = 6.0; t_s <= 20.0; t_s += 0.5) {
    const Eigen::Vector3d target = sim->personAt(simNs(t_s)).p_W_m;
    const Eigen::Vector3d beside = sim->personStateAt(1, simNs(t_s)).p_W_m;
    EXPECT_NEAR(beside.y() - target.y(), 1.0, 0.05) << "t = " << t_s;
    EXPECT_NEAR(beside.x() - target.x(), 0.0, 0.35) << "t = " << t_s;
  }
}

TEST(Bystanders, GroupMembersStandOffThePathWithinReachOfTheMeetingPoint) {
  const auto sim = crowdSim(
      crowdYaml("bystanders:\n  groups:\n    - {at_s: 12.0, count: 5, radius_m: 2.5, path_clearance_m: 0.8}\n"));
  ASSERT_EQ(sim->personCount(), 6U);
  const Eigen::Vector3d meeting = sim->personAt(simNs(12.0)).p_W_m;
  for (std::size_t id = 1; id < 6; ++id) {
    for (const double t_s : {0.0, 12.0, 30.0}) {  // standing: always there
      const Eigen::Vector3d p = sim->personStateAt(id, simNs(t_s)).p_W_m;
      EXPECT_GE(std::abs(p.y()), 0.8 - 1e-9) << "member " << id;  // the path is y = 0
      EXPECT_LE((p - meeting).norm(), 2.5 + 1e-9) << "member " << id;
    }
  }
}

TEST(Bystanders, MillingMembersStayOffThePath) {
  const auto sim = crowdSim(crowdYaml(
      "bystanders:\n  groups:\n    - {at_s: 12.0, count: 4, radius_m: 3.0, path_clearance_m: 1.0, milling: true}\n"));
  for (std::size_t id = 1; id < sim->personCount(); ++id)
    for (double t_s = 0.0; t_s < 60.0; t_s += 0.25)
      EXPECT_GE(std::abs(sim->personStateAt(id, simNs(t_s)).p_W_m.y()), 1.0 - 0.3) << id << " at " << t_s;
}

TEST(Bystanders, RandomWalkersStayInTheirRegionAndAwayFromTheDronesAndTheTargetsStart) {
  const auto sim = crowdSim(crowdYaml(
      "bystanders:\n  random_walkers: {count: 8, region_min_m: [-8.0, -8.0], region_max_m: [20.0, 8.0], legs: 5}\n"));
  ASSERT_EQ(sim->personCount(), 9U);
  const Eigen::Vector2d drone_start = sim->scenario().spec.drone.start_m.head<2>();
  const Eigen::Vector2d target_start = sim->personStateAt(0, simNs(0.0)).p_W_m.head<2>();
  for (std::size_t id = 1; id < sim->personCount(); ++id) {
    for (double t_s = 0.0; t_s < 80.0; t_s += 0.2) {
      const Eigen::Vector2d p = sim->personStateAt(id, simNs(t_s)).p_W_m.head<2>();
      EXPECT_GT((p - drone_start).norm(), kDroneStartKeepOutM - 0.3) << id << " at " << t_s;
      // Nobody walks through the target where they stand (the legs keep the body's radius off the disc).
      EXPECT_GT((p - target_start).norm(), kTargetStartKeepOutM - 0.3) << id << " at " << t_s;
      EXPECT_TRUE(p.x() >= -7.0 && p.x() <= 19.0 && p.y() >= -7.0 && p.y() <= 7.0) << id << " at " << t_s;
    }
  }
}

TEST(Bystanders, LookAlikeSignatureIsCloseToTheTargetsAndOthersAreFar) {
  const ScenarioInstance inst = crowdInstance(crowdYaml(R"(bystanders:
  target_clothing: {hue_deg: 0.0, saturation: 0.8, second_hue_deg: 220.0, second_saturation: 0.5}
  people:
    - {path: [{p_m: [5.0, 3.0]}], look_alike: true}
    - {path: [{p_m: [5.0, -3.0]}], clothing: {hue_deg: 120.0, saturation: 0.8}}
    - {path: [{p_m: [6.0, -3.0]}], clothing: {hue_deg: 60.0, saturation: 0.5, second_hue_deg: 300.0, second_saturation: 0.9}}
)"));
  const AppearanceSignature& target = inst.bystanders.target_appearance;
  ASSERT_EQ(inst.bystanders.people.size(), 3U);
  EXPECT_LT(signatureDistance(inst.bystanders.people[0].appearance, target), 0.25);
  EXPECT_GT(signatureDistance(inst.bystanders.people[1].appearance, target), 0.6);
  EXPECT_GT(signatureDistance(inst.bystanders.people[2].appearance, target), 0.6);
  // Noisy measurements: the target's own closest, the look-alike near, the others far.
  std::mt19937_64 rng(7);
  for (int i = 0; i < 20; ++i) {
    EXPECT_LT(signatureDistance(noisySignature(target, rng), target), 0.15);
    EXPECT_LT(signatureDistance(noisySignature(inst.bystanders.people[0].appearance, rng), target), 0.3);
    EXPECT_GT(signatureDistance(noisySignature(inst.bystanders.people[1].appearance, rng), target), 0.6);
  }
}

TEST(Bystanders, GivenTheSameShirtOverOtherTrousersOrAnotherGrey_WhenSigned_ThenTheyAreFarApart) {
  // Issue 22 item 2: two people in black-and-grey tops told apart by the grey's brightness or the legs.
  const ScenarioInstance inst = crowdInstance(crowdYaml(R"(bystanders:
  target_clothing: {hue_deg: 0.0, saturation: 0.8, grey_share: 0.9, grey_value: 0.1, legs_grey_share: 1.0, legs_grey_value: 0.1}
  people:
    - {path: [{p_m: [5.0, 3.0]}], clothing: {hue_deg: 0.0, saturation: 0.8, grey_share: 0.9, grey_value: 0.6, legs_grey_share: 1.0, legs_grey_value: 0.1}}
    - {path: [{p_m: [5.0, -3.0]}], clothing: {hue_deg: 0.0, saturation: 0.8, grey_share: 0.9, grey_value: 0.1, legs_hue_deg: 220.0, legs_saturation: 0.6, legs_grey_share: 0.1}}
)"));
  const AppearanceSignature& target = inst.bystanders.target_appearance;
  ASSERT_EQ(inst.bystanders.people.size(), 2U);
  EXPECT_GT(signatureDistance(inst.bystanders.people[0].appearance, target), 0.6);  // a lighter grey top
  EXPECT_GT(signatureDistance(inst.bystanders.people[1].appearance, target), 0.6);  // blue jeans
  const std::string bad =
      crowdParseError(crowdYaml("bystanders:\n  people:\n    - {path: [{p_m: [5.0, 3.0]}], clothing: {hue_deg: 0.0, "
                                "saturation: 0.8, legs_grey_value: 2.0}}\n"));
  EXPECT_NE(bad.find("legs_grey_value"), std::string::npos) << bad;
}

TEST(Bystanders, GivenRandomClothing_WhenDrawn_ThenTheStreamAdvancesBySixDrawsAsBeforeTheLegsExisted) {
  // The legs and the greys' brightness come from a stream of their own, so that every scenario's
  // bystanders walk where they did before those fields were added.
  std::mt19937_64 drawn(42), reference(42);
  const Clothing a = randomClothing(drawn);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 6; ++i) (void)u(reference);
  EXPECT_EQ(drawn(), reference());
  std::mt19937_64 again(42);
  const Clothing b = randomClothing(again);
  EXPECT_EQ(a.legs_hue_deg, b.legs_hue_deg);
  EXPECT_EQ(a.grey_value, b.grey_value);
  EXPECT_GE(a.legs_grey_share, 0.2);
  EXPECT_LE(a.legs_grey_share, 1.0);
}

TEST(Bystanders, DepthFrameSeesAStandingBystanderAtItsRange) {
  auto sim = crowdSim(crowdYaml("bystanders:\n  people:\n    - {path: [{p_m: [3.0, 0.0]}]}\n", false, 8.0), true);
  hoverCrowd(*sim, 0.5);
  const DepthFrameHandle frame = sim->depthOut().read();
  ASSERT_TRUE(frame);
  // Straight ahead at camera height: the body's front, 3 - 0.25 m from the drone's centre, 0.12 m
  // in front of which the depth camera sits. The noise is 0.0015 z^2 (~1 cm).
  const float z = frame->depth_m.at<float>(frame->depth_m.rows / 2, frame->depth_m.cols / 2);
  EXPECT_NEAR(z, 3.0 - kPersonBodyRadiusM - 0.12, 0.05);
}

TEST(Bystanders, FlyingIntoABystanderIsACollision) {
  auto sim = crowdSim(crowdYaml("bystanders:\n  people:\n    - {path: [{p_m: [3.0, 0.0]}]}\n", false, 8.0));
  hoverCrowd(*sim, 8.0, nullptr, Eigen::Vector3d(3.0, 0.0, 1.2));
  EXPECT_GE(sim->metrics().collisions(), 1);
  EXPECT_LT(sim->metrics().minClearanceM(), 0.0);
}

TEST(Bystanders, BystanderBetweenHidesTheTargetFromSightAndKeypoints) {
  auto sim = crowdSim(crowdYaml("bystanders:\n  people:\n    - {path: [{p_m: [2.0, 0.0]}]}\n", false, 5.0));
  std::vector<DetectionFrame> frames;
  hoverCrowd(*sim, 1.0, &frames);
  EXPECT_EQ(sim->personSight(sim->truth().T_WC, sim->truth().person), Sight::kOccluded);
  ASSERT_FALSE(frames.empty());
  for (const DetectionFrame& f : frames) {
    EXPECT_EQ(f.target_index, -1);  // hidden
    EXPECT_EQ(f.person_count, 1U);  // the bystander is seen
  }
  // Without the bystander the same target is visible.
  auto clear = crowdSim(crowdYaml("", false, 5.0));
  hoverCrowd(*clear, 0.2);
  EXPECT_EQ(clear->personSight(clear->truth().T_WC, clear->truth().person), Sight::kVisible);
}

TEST(Bystanders, KeypointCameraReportsEveryVisiblePersonWithSignaturesAndTheDesignatedTarget) {
  auto sim = crowdSim(crowdYaml(R"(bystanders:
  target_clothing: {hue_deg: 0.0, saturation: 0.8}
  people:
    - {path: [{p_m: [6.0, 2.0]}], clothing: {hue_deg: 120.0, saturation: 0.8}}
    - {path: [{p_m: [7.0, -2.5]}], clothing: {hue_deg: 240.0, saturation: 0.8}}
    - {path: [{p_m: [5.0, -1.2]}], look_alike: true}
)",
                                false, 6.0));
  std::vector<DetectionFrame> frames;
  hoverCrowd(*sim, 1.0, &frames);
  ASSERT_GT(frames.size(), 20U);
  int full = 0;
  for (const DetectionFrame& f : frames) {
    if (f.person_count != 4) continue;
    ++full;
    ASSERT_GE(f.target_index, 0);
    for (std::size_t i = 0; i < f.person_count; ++i) {
      EXPECT_TRUE(f.persons[i].has_appearance);
      if (i > 0) {
        EXPECT_LE(f.persons[i - 1].bbox_u_px, f.persons[i].bbox_u_px);  // left to right
      }
    }
    // The target stands on the optical axis: its box holds the image centre.
    const PersonDetection& t = f.persons[static_cast<std::size_t>(f.target_index)];
    EXPECT_LT(t.bbox_u_px, 320.0);
    EXPECT_GT(t.bbox_u_px + t.bbox_w_px, 320.0);
    EXPECT_LT(signatureDistance(t.appearance, sim->personAppearance(0)), 0.15);
  }
  EXPECT_GT(full, static_cast<int>(frames.size()) * 8 / 10);
}

TEST(Bystanders, EachReportedDetectionIsMatchedToItsOwnPersonAndFollowingABystanderIsASwitch) {
  auto sim = crowdSim(crowdYaml(R"(bystanders:
  people:
    - {path: [{p_m: [6.0, 2.0]}]}
    - {path: [{p_m: [7.0, -2.5]}]}
    - {path: [{p_m: [5.0, -1.2]}], look_alike: true}
)",
                                false, 6.0));
  std::vector<DetectionFrame> frames;
  hoverCrowd(*sim, 1.0, &frames);
  int full = 0;
  for (const DetectionFrame& f : frames) {
    if (f.person_count != 4) continue;
    ++full;
    std::vector<int> ids;
    for (std::size_t i = 0; i < f.person_count; ++i) ids.push_back(sim->matchDetection(f.sequence, f.persons[i]));
    std::sort(ids.begin(), ids.end());
    EXPECT_EQ(ids, (std::vector<int>{0, 1, 2, 3})) << "frame " << f.sequence;
    // The designated target (before the start) is the true target.
    ASSERT_GE(f.target_index, 0);
    EXPECT_EQ(sim->matchDetection(f.sequence, f.persons[static_cast<std::size_t>(f.target_index)]), 0);
  }
  ASSERT_GT(full, 10);
  // A detection of nobody, and a frame the simulator no longer remembers, match no one.
  const DetectionFrame& last = frames.back();
  PersonDetection nobody = last.persons[0];
  for (Keypoint2D& k : nobody.keypoints) k.v_px -= 400.0;  // up in the sky
  EXPECT_EQ(sim->matchDetection(last.sequence, nobody), -1);
  EXPECT_EQ(sim->matchDetection(last.sequence + 1000, last.persons[0]), -1);
  // Following the target, then a bystander, then nobody, then the target again: two switches.
  DetectionFrame followed = last;
  followed.target_index = last.target_index;
  sim->recordFollowed(followed);
  followed.target_index = last.target_index == 0 ? 1 : 0;
  sim->recordFollowed(followed);
  followed.target_index = -1;
  sim->recordFollowed(followed);
  followed.target_index = last.target_index;
  sim->recordFollowed(followed);
  EXPECT_EQ(sim->metrics().identitySwitches(), 2);
  // Each switch is described: between whom, how far apart they stood, whether a look-alike was one of them.
  const int other = sim->matchDetection(last.sequence, last.persons[last.target_index == 0 ? 1U : 0U]);
  ASSERT_GE(other, 1);
  const std::vector<IdentitySwitch>& events = sim->metrics().switchEvents();
  ASSERT_EQ(events.size(), 2U);
  EXPECT_EQ(events[0].from_id, 0);
  EXPECT_EQ(events[0].to_id, other);
  EXPECT_EQ(events[1].from_id, other);
  EXPECT_EQ(events[1].to_id, 0);
  const double apart_m = (sim->personStateAt(static_cast<std::size_t>(other), last.stamp_ns).p_W_m -
                          sim->personStateAt(0, last.stamp_ns).p_W_m)
                             .head<2>()
                             .norm();
  EXPECT_GT(apart_m, 1.0);  // standing metres apart
  for (const IdentitySwitch& e : events) {
    EXPECT_NEAR(e.separation_m, apart_m, 1e-9);
    EXPECT_EQ(e.look_alike, other == 3);  // the third listed wears the target's clothes
  }
}

TEST(Bystanders, GivenTwoOverlappingPeople_WhenADetectionFitsBoth_ThenTheOneMatchedBeforeIsKept) {
  // A bystander stands 0.5 m behind the target, 0.2 m aside (their bodies all but touching: no nearer, give_way.hpp),
  // both facing the hovering drone (6 m away): a detection of the target fits the bystander within half a torso too.
  // The nearest match names the target; one kept from before (CLEAR MOT) names whoever was matched before while the
  // detection still fits them.
  auto sim = crowdSim(crowdYaml(R"(bystanders:
  people:
    - {path: [{p_m: [6.5, 0.2]}]}
)",
                                false, 6.0));
  std::vector<DetectionFrame> frames;
  hoverCrowd(*sim, 1.0, &frames);
  ASSERT_FALSE(frames.empty());
  const DetectionFrame& f = frames.back();
  ASSERT_GE(f.target_index, 0);
  const PersonDetection& target = f.persons[static_cast<std::size_t>(f.target_index)];
  ASSERT_EQ(sim->matchDetection(f.sequence, target), 0);
  EXPECT_EQ(sim->matchDetection(f.sequence, target, 1), 1) << "it fits the bystander behind too";
  EXPECT_EQ(sim->matchDetection(f.sequence, target, 0), 0);
  // Moved a torso aside, it fits neither: nobody, whoever was matched before.
  PersonDetection aside = target;
  const double torso_px = std::abs(aside.keypoints[11].v_px - aside.keypoints[5].v_px);
  for (Keypoint2D& k : aside.keypoints) k.u_px += 1.5 * torso_px;
  EXPECT_EQ(sim->matchDetection(f.sequence, aside, 1), -1);
  // Recorded: following the bystander (nearest: them), then the same detection of both -- no switch by CLEAR
  // MOT's rule, one by the nearest match.
  DetectionFrame followed = f;
  PersonDetection bystander = target;
  const auto b = std::find_if(f.persons.begin(), f.persons.begin() + static_cast<std::ptrdiff_t>(f.person_count),
                              [&](const PersonDetection& p) { return sim->matchDetection(f.sequence, p) == 1; });
  if (b != f.persons.begin() + static_cast<std::ptrdiff_t>(f.person_count)) bystander = *b;
  followed.persons[0] = bystander;
  followed.persons[1] = target;
  followed.person_count = 2;
  followed.target_index = 0;
  ASSERT_EQ(sim->matchDetection(f.sequence, followed.persons[0]), 1) << "the bystander is detected on their own";
  sim->recordFollowed(followed);
  followed.target_index = 1;
  sim->recordFollowed(followed);
  EXPECT_EQ(sim->metrics().identitySwitches(), 0);
  EXPECT_EQ(sim->metrics().identitySwitchesNearest(), 1);
}

TEST(Bystanders, AtMostSixPersonsAreReportedTheLargestFirst) {
  std::string people = "bystanders:\n  people:\n";
  for (int i = 0; i < 8; ++i)  // a row across the view, farther and farther
    people += "    - {path: [{p_m: [" + std::to_string(4.0 + i) + ", " + std::to_string(i % 2 ? 1.5 : -1.5) + "]}]}\n";
  auto sim = crowdSim(crowdYaml(people, false, 3.0));
  std::vector<DetectionFrame> frames;
  hoverCrowd(*sim, 0.5, &frames);
  ASSERT_FALSE(frames.empty());
  for (const DetectionFrame& f : frames) {
    EXPECT_LE(f.person_count, kMaxPersons);
    EXPECT_GE(f.target_index, 0);  // the nearest, largest, always kept
  }
  EXPECT_EQ(frames.back().person_count, kMaxPersons);
}

TEST(Bystanders, GivenSameSeedThenIdenticalDetections) {
  const std::string text = crowdYaml(R"(bystanders:
  crossings:
    - {count: 2, window_s: [6.0, 14.0]}
  random_walkers: {count: 4, region_min_m: [0.0, -10.0], region_max_m: [30.0, 10.0]}
  groups:
    - {at_s: 10.0, count: 3, milling: true, look_alikes: 1}
)");
  auto a = crowdSim(text, true, 5), b = crowdSim(text, true, 5);
  std::vector<DetectionFrame> fa, fb;
  hoverCrowd(*a, 4.0, &fa);
  hoverCrowd(*b, 4.0, &fb);
  ASSERT_EQ(fa.size(), fb.size());
  for (std::size_t i = 0; i < fa.size(); ++i) {
    ASSERT_EQ(fa[i].person_count, fb[i].person_count);
    EXPECT_EQ(fa[i].target_index, fb[i].target_index);
    for (std::size_t p = 0; p < fa[i].person_count; ++p) {
      EXPECT_EQ(fa[i].persons[p].appearance, fb[i].persons[p].appearance);
      for (std::size_t k = 0; k < kNumKeypoints; ++k)
        EXPECT_EQ(fa[i].persons[p].keypoints[k].u_px, fb[i].persons[p].keypoints[k].u_px);
    }
  }
  EXPECT_EQ(a->truth().drone.p_W_m, b->truth().drone.p_W_m);
  // Another seed places them elsewhere.
  auto c = crowdSim(text, false, 6);
  EXPECT_NE(a->personStateAt(1, simNs(1.0)).p_W_m, c->personStateAt(1, simNs(1.0)).p_W_m);
}

TEST(Bystanders, AnUnseenBystanderLeavesTheTargetsDetectionsBitForBit) {
  // The target is observed from the camera's own stream, bystanders from another: a bystander behind
  // the drone changes nothing in the target's detections.
  auto alone = crowdSim(crowdYaml("", false, 6.0));
  auto with = crowdSim(crowdYaml("bystanders:\n  people:\n    - {path: [{p_m: [-4.0, 3.0]}]}\n", false, 6.0));
  std::vector<DetectionFrame> a, b;
  hoverCrowd(*alone, 1.0, &a);
  hoverCrowd(*with, 1.0, &b);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].person_count, 1U);
    ASSERT_EQ(b[i].person_count, 1U);
    EXPECT_EQ(b[i].target_index, 0);
    for (std::size_t k = 0; k < kNumKeypoints; ++k) {
      EXPECT_EQ(a[i].persons[0].keypoints[k].u_px, b[i].persons[0].keypoints[k].u_px);
      EXPECT_EQ(a[i].persons[0].keypoints[k].score, b[i].persons[0].keypoints[k].score);
    }
  }
}

TEST(Bystanders, ParseErrorsNameFileLineAndKey) {
  const std::string through_wall = crowdParseError(
      crowdYaml("bystanders:\n  people:\n    - path:\n        - {p_m: [5.0, -4.0]}\n        - {p_m: [5.0, 4.0]}\n",
                true, 6.0, "    - {min_m: [4.5, -1.0, 0.0], max_m: [5.5, 1.0, 3.0]}\n"));
  EXPECT_NE(through_wall.find("test.yaml:"), std::string::npos) << through_wall;
  EXPECT_NE(through_wall.find("p_m"), std::string::npos) << through_wall;
  EXPECT_NE(through_wall.find("obstacle"), std::string::npos) << through_wall;
  const std::string negative = crowdParseError(crowdYaml(
      "bystanders:\n  random_walkers: {count: -2, region_min_m: [0.0, -10.0], region_max_m: [30.0, 10.0]}\n"));
  EXPECT_NE(negative.find("bystanders.random_walkers.count"), std::string::npos) << negative;
  const std::string fast =
      crowdParseError(crowdYaml("bystanders:\n  crossings:\n    - {at_s: [5.0], speed_mps: 7.0}\n"));
  EXPECT_NE(fast.find("speed_mps"), std::string::npos) << fast;
  EXPECT_NE(fast.find("out of range"), std::string::npos) << fast;
  const std::string unknown = crowdParseError(crowdYaml("bystanders:\n  crowds: []\n"));
  EXPECT_NE(unknown.find("bystanders.crowds: unknown key"), std::string::npos) << unknown;
  const std::string early = [&] {
    const auto spec = parseScenarioSpec(crowdYaml("bystanders:\n  crossings:\n    - {at_s: [1.0]}\n"), "test.yaml");
    if (!spec) return spec.error().message;
    const auto inst = instantiate(*spec, 1);
    return inst ? std::string("no error") : inst.error().message;
  }();
  EXPECT_NE(early.find("crossings[0]"), std::string::npos) << early;
}

TEST(Bystanders, AListedPathThroughAGeneratedTreeIsAnErrorOfThatSeed) {
  // The file's own obstacles leave the path clear; a dense generated forest (kept off the target's
  // path only) does not.
  const std::string forest = R"(    - {min_m: [100.0, 100.0, 0.0], max_m: [101.0, 101.0, 1.0]}
  forest:
    region_min_m: [10.0, -10.0]
    region_max_m: [30.0, 10.0]
    density_per_m2: 0.5
    radius_m: [0.2, 0.2]
    height_m: 3.0
    min_gap_m: 0.1
    path_clearance_m: 0.5
)";
  const auto spec = parseScenarioSpec(
      crowdYaml("bystanders:\n  people:\n    - path:\n        - {p_m: [20.0, -9.0]}\n        - {p_m: [20.0, -1.0]}\n",
                true, 6.0, forest),
      "test.yaml");
  ASSERT_TRUE(spec) << spec.error().message;
  const auto inst = instantiate(*spec, 1);
  ASSERT_FALSE(inst);
  EXPECT_NE(inst.error().message.find("bystanders.people[0]: the listed path passes through an obstacle"),
            std::string::npos)
      << inst.error().message;
}

// The image-mode frame of a bystander 3 m ahead of a target 6 m ahead (both standing), and the
// simulation; cast_of_one: the cast is cut to the target's photo alone.
std::pair<ImageFrameHandle, std::shared_ptr<Simulation>> nearBystanderFrame(bool cast_of_one) {
  // Given the target standing 6 m ahead and a bystander in green 3 m ahead, on the same line
  const std::string text = crowdYaml(
      "sensors:\n  gimbal_camera:\n    mode: image\n    rate_hz: 10\n    latency_s: 0.04\n"
      "    width_px: 320\n    height_px: 240\n    hfov_deg: 87\n    pixel_noise_torso_fraction: 0.028\n"
      "    keypoint_miss_probability: 0.03\n"
      "bystanders:\n  people:\n    - {path: [{p_m: [3.0, 0.0]}], clothing: {hue_deg: 120.0, saturation: 1.0}}\n",
      false, 6.0);
  SimulationOptions options;
  options.render_depth = false;
  ScenarioInstance inst = crowdInstance(text);
  if (cast_of_one) inst.spec.gimbal_camera.cast.people.resize(1);
  std::shared_ptr<Simulation> sim =
      aerotrack::test::require(Simulation::create(std::move(inst), options, 0), "Simulation::create");
  SimGimbalCamera camera(sim);
  ImageFrameHandle frame;
  for (rt::TimeNs t = 0; t <= rt::secondsToNs(0.3) && !frame; t += 5'000'000) {
    sim->step(t);
    frame = camera.grab(t);
  }
  return {std::move(frame), sim};
}

/// Mean colour of the 5 x 5 pixels around the projected torso centre of person `id`.
cv::Vec3d torsoColour(const cv::Mat& bgr, const Simulation& sim, std::size_t id, rt::TimeNs stamp_ns,
                      const CameraIntrinsics& intrinsics) {
  const PersonState by = sim.personStateAt(id, stamp_ns);
  const Eigen::Vector3d torso_W =
      0.25 *
      (by.keypoints_W_m[index(CocoKeypoint::kLeftShoulder)] + by.keypoints_W_m[index(CocoKeypoint::kRightShoulder)] +
       by.keypoints_W_m[index(CocoKeypoint::kLeftHip)] + by.keypoints_W_m[index(CocoKeypoint::kRightHip)]);
  const auto uv = project(sim.truth().T_WC.inverse() * torso_W, intrinsics);
  cv::Vec3d mean(0, 0, 0);
  if (!uv) return mean;
  for (int dv = -2; dv <= 2; ++dv)
    for (int du = -2; du <= 2; ++du) {
      const cv::Vec3b px = bgr.at<cv::Vec3b>(static_cast<int>(uv->y()) + dv, static_cast<int>(uv->x()) + du);
      for (int ch = 0; ch < 3; ++ch) mean[ch] += px[ch] / 25.0;
    }
  return mean;
}

bool castInstalled() {
  for (const PersonSpriteSpec& p : defaultCast().people) {
    if (!std::filesystem::exists(p.image_path)) return false;
  }
  return true;
}

TEST(Bystanders, ImageModeDrawsANearerBystanderOverTheTargetAsAnotherPersonOfTheCast) {
  if (!castInstalled()) GTEST_SKIP() << "opencv-doc's sample data is missing: install the Debian package opencv-doc";
  // Given the default cast, the target standing 6 m ahead and a bystander 3 m ahead on the same line
  const auto [frame, sim] = nearBystanderFrame(false);
  ASSERT_TRUE(frame);
  // When the bystander's person of the cast is drawn alone from the same pose
  const SceneRenderer& renderer = *sim->renderer();
  const std::size_t who = castPersonFor(1, false, 0, renderer.castSize());
  ASSERT_NE(who, 0U);
  const PersonState by = sim->personStateAt(1, frame->stamp_ns);
  cv::Mat alone;
  RenderScratch scratch;
  renderer.render(sim->obstacles(), sim->truth().T_WC, &by, alone, scratch, who);
  // Then the frame shows that person at the bystander's torso, over the target behind them
  const cv::Vec3d in_frame = torsoColour(frame->bgr, *sim, 1, frame->stamp_ns, frame->intrinsics);
  const cv::Vec3d expected = torsoColour(alone, *sim, 1, frame->stamp_ns, frame->intrinsics);
  for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(in_frame[ch], expected[ch], 1.0) << ch;
}

TEST(Bystanders, WithACastOfOneABystanderWearsTheTargetsPhotoInItsOwnClothes) {
  if (!castInstalled()) GTEST_SKIP() << "opencv-doc's sample data is missing: install the Debian package opencv-doc";
  const auto [frame, sim] = nearBystanderFrame(true);
  ASSERT_TRUE(frame);
  // Then the bystander's torso is green: the recoloured bystander is drawn over the target's photo
  const cv::Vec3d mean = torsoColour(frame->bgr, *sim, 1, frame->stamp_ns, frame->intrinsics);
  EXPECT_GT(mean[1], 1.3 * mean[0]) << mean[0] << " " << mean[1] << " " << mean[2];
  EXPECT_GT(mean[1], 1.3 * mean[2]) << mean[0] << " " << mean[1] << " " << mean[2];
}

}  // namespace
}  // namespace aerotrack::hal::sim
