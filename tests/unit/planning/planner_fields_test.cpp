// The planner's parameters have one field table (trackingPlannerFields(), its sections owned by their
// modules) that drives parsing, validate() and printing (issue 19 item 4). These tests walk that table,
// not a hand-written list of fields: the `planning:` section written and read back is the same; at both
// ends of every field's range the parser and validate() agree (they did not: planning_budget_s was
// [0, 0.999] in the parser and [0, 1) in validate); the printed keys are exactly the keys read.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <string>

#include "aerotrack/planning/tracking_planner.hpp"
#include "support/field_table_checks.hpp"

namespace aerotrack::planning {
namespace {

field_checks::FieldTableUnderTest<TrackingPlannerParams> planner() {
  return {trackingPlannerFields(), [](const TrackingPlannerParams& p) { return trackingPlannerFields().toYaml(p); },
          [](const std::string& yaml) -> rt::Expected<TrackingPlannerParams> {
            const auto root = rt::ConfigNode::fromString(yaml, "planning.yaml");
            if (!root) return root.error();
            return rt::parseConfig<TrackingPlannerParams>([&root] { return parseTrackingPlannerParams(*root); });
          },
          [](const TrackingPlannerParams& p) { return validate(p); }};
}

TEST(PlannerFields, GivenParamsWhenWrittenAndReadBackThenEveryFieldIsTheSame) {
  // The defaults, then each field moved on its own (flags flipped, numbers elsewhere in their range).
  const int variants = field_checks::roundTrip(planner(), TrackingPlannerParams{});
  EXPECT_GT(variants, 70);  // of 78: every field but the few a rule refuses to move alone
}

TEST(PlannerFields, GivenEachFieldAtTheEndsOfItsRangeThenParserAndValidateAgree) {
  int probes = 0;
  const std::set<std::string> refused_inside = field_checks::rangeEnds(planner(), TrackingPlannerParams{}, &probes);
  // Four per number: 72 fields, max_box_size_m counting three (issue 21: the optimiser's three limits went,
  // optimizer_limit_fraction, check.max_repair_stretch and optimizer.corridor_margin_per_speed_s came;
  // issue 21 item 3: relocation's 14, its list three; goal.max_lead_s and the time weight's two; the camera
  // view's four: person_torso_half_m and optimizer.camera_view_weight, camera_half_vfov_rad, camera_view_margin_rad;
  // the time weight's speed change; the predictor's newest_velocity_weight; the altitude band's two;
  // goal.trail_speed_mps; min_bystander_distance_m; issue 22: bystander_sight_radius_m).
  EXPECT_EQ(probes, 4 * 102);
  // In range, yet refused by both because of a rule across fields, with the other field at its default.
  EXPECT_EQ(refused_inside, (std::set<std::string>{
                                "flight_altitude_m@lo",        // 0.1 is not above takeoff_below_m (0.5)
                                "takeoff_below_m@hi",          // 100 is not below flight_altitude_m (1.5)
                                "flight_altitude_m@hi",        // 100 is above max_altitude_m (3)
                                "min_altitude_m@hi",           // 100 is above flight_altitude_m (1.5)
                                "max_altitude_m@lo",           // 0.1 is below flight_altitude_m (1.5)
                                "prediction.min_samples@hi",   // 100000 is above max_samples (128)
                                "prediction.max_samples@lo",   // 2 is below min_samples (5)
                                "collision.radius_m@lo",       // 0.01 is below sample_step_m (0.05)
                                "collision.sample_step_m@hi",  // 5 is above radius_m (0.25)
                            }));
}

TEST(PlannerFields, GivenThePlanningBudgetThenBothSidesTakeTheHalfOpenRange) {
  // The disagreement issue 19 found, spelt out: [0, 1) on both sides.
  TrackingPlannerParams p;
  p.planning_budget_s = 0.9995;
  EXPECT_TRUE(validate(p));
  EXPECT_TRUE(planner().read(planner().write(p)));
  p.planning_budget_s = 1.0;
  ASSERT_FALSE(validate(p));
  EXPECT_EQ(validate(p).error().message, "planning_budget_s must be in [0, 1), got 1");
  const auto read = planner().read(planner().write(p));
  ASSERT_FALSE(read);
  EXPECT_EQ(read.error().message, "planning.yaml:1: planning_budget_s: 1 is out of range [0, 1)");
}

TEST(PlannerFields, GivenTheWrittenSectionThenItsKeysAreExactlyTheKeysTheParserReads) {
  const std::vector<std::string> written = field_checks::keys(planner(), TrackingPlannerParams{});
  // 82 before issue 21, which removed the optimizer's three limits (derived from the check's) and added
  // optimizer_limit_fraction, check.max_repair_stretch and optimizer.corridor_margin_per_speed_s; issue 21
  // item 3 the relocation section's 12 (and its own key); goal.max_lead_s and the time weight's two; the
  // camera view's four; the time weight's speed change; the predictor's two velocity keys; the altitude band's two;
  // goal.trail_speed_mps; min_bystander_distance_m; issue 22: bystander_sight_radius_m.
  EXPECT_EQ(written.size(), 110U);
  for (const char* key : {"planning_budget_s", "goal.visible_max_turn_rad", "goal.max_lead_s", "search.occlusion_aware",
                          "corridor.max_box_size_m", "optimizer.max_pieces", "prediction.qp_max_iterations",
                          "check.margin_escape_s", "check.max_repair_stretch", "optimizer_limit_fraction",
                          "collision.broad_phase_group", "relocation.viewpoint_radii_m"}) {
    EXPECT_NE(std::find(written.begin(), written.end(), key), written.end()) << key;
  }
}

TEST(PlannerFields, GivenARuleAcrossFieldsThenParseNamesTheKeyAndValidateToo) {
  TrackingPlannerParams p;
  p.takeoff_below_m = 2.0;  // above flight_altitude_m (1.5)
  ASSERT_FALSE(validate(p));
  EXPECT_EQ(validate(p).error().message, "flight_altitude_m must be > takeoff_below_m");
  const auto read = planner().read(planner().write(p));
  ASSERT_FALSE(read);
  EXPECT_EQ(read.error().message, "planning.yaml:6: flight_altitude_m: must be > takeoff_below_m");
  p = TrackingPlannerParams{};
  p.prediction.max_samples = 4;  // below min_samples (5): the section's own rule, under its key
  EXPECT_EQ(validate(p).error().message, "prediction.max_samples must be >= min_samples");
  p = TrackingPlannerParams{};
  p.corridor.max_box_size_m.y() = 0.0;
  EXPECT_EQ(validate(p).error().message, "corridor.max_box_size_m[1] must be in [0.01, 100], got 0");
  EXPECT_NE(
      planner().read(planner().write(p)).error().message.find("corridor.max_box_size_m: item 1: 0 is out of range"),
      std::string::npos);
}

}  // namespace
}  // namespace aerotrack::planning
