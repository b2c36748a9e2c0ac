// summary.json and topdown.png of a simulated run: see sim_report.hpp.
#include "sim_report.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "device_tasks.hpp"
#include "paths.hpp"

namespace aerotrack::app {

nlohmann::json mapSummary(const mapping::MappingTask* task, const std::vector<TaskTiming>& timings) {
  if (task == nullptr) return nullptr;
  const mapping::MapperStats& s = task->mapper().stats();
  nlohmann::json out = {{"frames_inserted", s.frames_inserted},
                        {"frames_skipped_no_pose", s.frames_skipped_no_pose},
                        {"frames_skipped_bad", s.frames_skipped_bad},
                        {"frames_dropped_waiting_for_odometry", task->framesDroppedWaiting()},
                        {"occupied_voxels", s.occupied_voxels},
                        {"returns_excluded", s.returns_excluded},
                        {"voxels_cleared", s.voxels_cleared},
                        {"grid_snapshots_allocated", s.grid_snapshots_allocated}};
  (void)timings;
  const rt::TimingSnapshot insert = task->insertStats().snapshot();
  const rt::TimingSnapshot snapshot = task->snapshotStats().snapshot();
  out["map_insert_ms_p50"] = insert.p50_ms;
  out["map_insert_ms_p99"] = insert.p99_ms;
  out["map_insert_ms_max"] = insert.max_ms;
  out["octree_snapshots"] = snapshot.runs;
  out["octree_snapshot_ms_p50"] = snapshot.p50_ms;
  out["octree_snapshot_ms_max"] = snapshot.max_ms;
  return out;
}

nlohmann::json estimationSummary(const estimation::TargetTask* task, const TargetTruthCheckTask* check) {
  if (task == nullptr) return nullptr;
  const estimation::TargetTaskStats& s = task->stats();
  nlohmann::json out = {
      {"detections", s.detections},     {"unreliable", s.unreliable},
      {"bearings", s.bearings},         {"reassigned", s.reassigned},
      {"swapped_back", s.swapped_back}, {"no_pose", s.no_pose},
      {"accepted", s.accepted},         {"rejected", s.rejected},
      {"depth_ranged", s.depth_ranged}, {"depth_disagreed", s.depth_disagreed},
      {"depth_unseen", s.depth_unseen},
  };
  out["scale_samples"] = s.scale_samples;
  out["range_scale"] = s.range_scale;
  out["in_front"] = s.in_front;
  out["behind_bystander"] = s.behind_bystander;
  out["seen_through"] = s.seen_through;
  out["refused_alone_tracks"] = s.refused_alone_tracks;
  out["look_refused_kept_off"] = s.look_refused_kept_off;
  out["lost_colour_capped"] = s.lost_colour_capped;
  out["depth_frames_searched"] = s.depth_frames_searched;
  out["depth_people"] = s.depth_people;
  out["depth_people_followed"] = s.depth_people_followed;
  out["depth_people_fed"] = s.depth_people_fed;
  out["depth_people_updates"] = s.depth_people_updates;
  out["depth_people_tracks"] = s.depth_people_tracks;
  if (check != nullptr) {
    out["checked_steps"] = check->steps();
    out["live_ratio"] =
        check->steps() ? static_cast<double>(check->liveSteps()) / static_cast<double>(check->steps()) : 0.0;
    out["position_error_mean_m"] = check->positionErrorMeanM();
    out["position_error_max_m"] = check->positionErrorMaxM();
    out["velocity_error_mean_mps"] = check->velocityErrorMeanMps();
  }
  return out;
}

nlohmann::json latencySummary(const trajectory_server::TrajectoryServerTask* task) {
  if (task == nullptr) return nullptr;
  const rt::LatencyHistogram& h = task->server().captureToSetpoint();
  return {{"samples", h.count()},
          {"capture_to_setpoint_ms_p50", h.quantileNs(0.5) * 1e-6},
          {"capture_to_setpoint_ms_p99", h.quantileNs(0.99) * 1e-6},
          {"capture_to_setpoint_ms_max", h.maxNs() * 1e-6}};
}

nlohmann::json planningSummary(const planning::PlanningTask* task) {
  if (task == nullptr) return nullptr;
  nlohmann::json outcomes = nlohmann::json::object();
  for (int i = 0; i < planning::kPlanStatusCount; ++i) {
    const auto status = static_cast<planning::PlanStatus>(i);
    outcomes[std::string(planning::toString(status))] = task->count(status);
  }
  nlohmann::json search_failures = nlohmann::json::object();
  for (const auto status : {planning::SearchStatus::kNoPath, planning::SearchStatus::kStartBlocked,
                            planning::SearchStatus::kInvalidInput}) {
    search_failures[std::string(planning::toString(status))] = task->searchFailures(status);
  }
  nlohmann::json check_failures = nlohmann::json::object();
  for (int i = 1; i < planning::kCheckVerdictCount; ++i) {
    const auto verdict = static_cast<planning::CheckVerdict>(i);
    check_failures[std::string(planning::toString(verdict))] = task->checkFailures(verdict);
  }
  // The final check's verdicts (issue 21): passed first time, repaired by re-timing (by the first
  // verdict), or rejected (check_failures above, by the final verdict; repair_failed: repairs tried).
  nlohmann::json repaired = nlohmann::json::object();
  nlohmann::json repair_failed = nlohmann::json::object();
  std::uint64_t repaired_total = 0;
  for (int i = 1; i < planning::kCheckVerdictCount; ++i) {
    const auto verdict = static_cast<planning::CheckVerdict>(i);
    if (!planning::isDynamicLimit(verdict)) continue;
    repaired[std::string(planning::toString(verdict))] = task->checkRepairs(verdict);
    repair_failed[std::string(planning::toString(verdict))] = task->checkRepairFailures(verdict);
    repaired_total += task->checkRepairs(verdict);
  }
  const nlohmann::json check = {{"runs", task->checksRun()},
                                {"passed_first_time", task->checksPassedFirstTime()},
                                {"repaired", repaired_total},
                                {"rejected", task->checksRejected()},
                                {"repaired_by_first_verdict", repaired},
                                {"repair_failed_by_first_verdict", repair_failed},
                                {"max_repair_stretch", task->maxRepairStretch()}};
  const rt::TimingSnapshot cycle = task->cycleStats().snapshot();
  return {{"cycles", task->cycles()},
          {"relocation_search",
           {{"cycles", task->searchCycles()},
            {"idle_cycles", task->searchIdleCycles()},
            {"update_ms_max", task->searchUpdateMaxMs()}}},
          {"check", check},
          {"search_failures", search_failures},
          {"check_failures", check_failures},
          {"outcomes", outcomes},
          {"cycle_ms_p50", cycle.p50_ms},
          {"cycle_ms_p99", cycle.p99_ms},
          {"cycle_ms_max", cycle.max_ms},
          {"cycle_ms_mean", cycle.mean_ms},
          {"timed_cycles", cycle.runs},
          {"search_partial", task->searchPartial()},
          {"corridor_boxes_mean", task->meanCorridorBoxes()},
          {"optimizer_max_iterations", task->optimizerMaxIterations()},
          {"optimizer_line_search", task->optimizerLineSearch()},
          {"trajectory_pool_growths", task->poolGrowths()},
          // Its plans the trajectory server refused for taking over late (a planner held up past its budget).
          {"refused_late_by_server", task->refusedByServer()}};
}

nlohmann::json supervisorSummary(const supervisor::SupervisorTask* task, rt::TimeNs start_ns, double step_s) {
  if (task == nullptr) return nullptr;
  nlohmann::json transitions = nlohmann::json::array();
  for (std::size_t i = 0; i < task->transitionCount(); ++i) {
    const supervisor::SupervisorTask::Transition& t = task->transitions()[i];
    transitions.push_back({{"t_s", rt::nsToSeconds(t.at_ns - start_ns)},
                           {"mode", std::string(supervisor::toString(t.mode))},
                           {"reason", std::string(supervisor::toString(t.reason))}});
  }
  nlohmann::json seconds = nlohmann::json::object();
  for (const auto mode :
       {supervisor::Mode::kTakeOff, supervisor::Mode::kSearch, supervisor::Mode::kTrack, supervisor::Mode::kRelocate,
        supervisor::Mode::kHold, supervisor::Mode::kLand, supervisor::Mode::kDegraded}) {
    seconds[std::string(supervisor::toString(mode))] = static_cast<double>(task->stepsIn(mode)) * step_s;
  }
  // Each relocation: when it began, when its timeout ran out and the search began (null: it did not), when and
  // how it ended (end null: still relocating or searching when the run ended), how long it took (to the end of the
  // run if open) and how much of that was the search (null: no search).
  nlohmann::json relocations = nlohmann::json::array();
  const rt::TimeNs last_ns = task->lastStepNs();
  for (std::size_t i = 0; i < task->relocationCount(); ++i) {
    const supervisor::SupervisorTask::Relocation& r = task->relocations()[i];
    const auto at = [&](rt::TimeNs t_ns) {
      return t_ns >= 0 ? nlohmann::json(rt::nsToSeconds(t_ns - start_ns)) : nlohmann::json(nullptr);
    };
    relocations.push_back(
        {{"start_s", at(r.start_ns)},
         {"timeout_s", at(r.timeout_ns)},
         {"end_s", at(r.end_ns)},
         {"duration_s", rt::nsToSeconds((r.end_ns >= 0 ? r.end_ns : last_ns) - r.start_ns)},
         {"search_s", r.searched ? nlohmann::json(rt::nsToSeconds((r.end_ns >= 0 ? r.end_ns : last_ns) - r.timeout_ns))
                                 : nlohmann::json(nullptr)},
         {"outcome", std::string(supervisor::toString(r.outcome))}});
  }
  return {{"mode", std::string(supervisor::toString(task->state().mode))},
          {"reason", std::string(supervisor::toString(task->state().reason))},
          {"transitions", transitions},
          {"relocations", relocations},
          {"seconds_in", seconds}};
}

nlohmann::json perceptionSummary(const perception::DetectionTask* task) {
  if (task == nullptr) return nullptr;
  const rt::TimingSnapshot detect = task->detectStats().snapshot();
  nlohmann::json runs = nlohmann::json::object();
  const perception::TrackCounts& counts = task->trackCounts();
  for (std::size_t i = 0; i < counts.runs.size(); ++i)
    runs[perception::toString(static_cast<perception::WholeFrameReason>(i))] = counts.runs[i];
  return {{"frames_detected", task->framesDetected()},
          {"network_runs", runs},
          {"reseated_by_estimator", counts.reseated},
          {"crops_at_prediction", counts.to_prediction},
          {"whole_frames_beside_crop", counts.beside_crop},
          {"people_added_beside_crop", counts.beside_crop_added},
          {"frames_with_target", task->framesWithTarget()},
          {"target_ratio", task->framesDetected() > 0 ? static_cast<double>(task->framesWithTarget()) /
                                                            static_cast<double>(task->framesDetected())
                                                      : 0.0},
          {"failures", task->failures()},
          {"detect_ms_p50", detect.p50_ms},
          {"detect_ms_p99", detect.p99_ms},
          {"detect_ms_max", detect.max_ms}};
}

namespace {

/// Each loss of sight: when, until when (null: never re-acquired) and why it began.
nlohmann::json lossEvents(const hal::sim::SimMetrics& m) {
  nlohmann::json out = nlohmann::json::array();
  for (const hal::sim::LossEvent& l : m.losses()) {
    out.push_back({{"start_s", l.start_s},
                   {"end_s", l.end_s < 0.0 ? nlohmann::json(nullptr) : nlohmann::json(l.end_s)},
                   {"cause", hal::sim::sightName(l.cause)}});
  }
  return out;
}

nlohmann::json finiteOrNull(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
}

nlohmann::json switchEvents(const hal::sim::SimMetrics& m) {
  nlohmann::json out = nlohmann::json::array();
  for (const hal::sim::IdentitySwitch& e : m.switchEvents())
    out.push_back({{"t_s", e.t_s},
                   {"from", e.from_id},
                   {"to", e.to_id},
                   {"separation_m", e.separation_m},
                   {"look_alike", e.look_alike}});
  return out;
}

}  // namespace

nlohmann::json simSummary(const hal::sim::Simulation& sim, const RunInfo& run) {
  const hal::sim::SimMetrics& m = sim.metrics();
  const hal::sim::ScenarioInstance& trial = sim.scenario();
  const std::string reason = m.failureReason();
  nlohmann::json out = {
      {"scenario", trial.spec.name},
      {"seed", trial.seed},
      {"success", reason.empty()},
      {"failure_reason", reason.empty() ? nlohmann::json(nullptr) : nlohmann::json(reason)},
      {"collisions", m.collisions()},
      {"min_clearance_m", finiteOrNull(m.minClearanceM())},
      {"visible_ratio", m.visibleRatio()},
      {"losses", m.losses().size()},
      {"longest_loss_s", m.longestLossS()},
      {"hidden_s", {{"out_of_image", m.outOfImageS()}, {"occluded", m.occludedS()}}},
      {"loss_events", lossEvents(m)},
      {"distance_mean_m", m.distanceMeanM()},
      {"distance_max_m", m.distanceMaxM()},
      {"final_distance_m", m.finalDistanceM()},
      // The paper's verdict beside ours (issue 20 item 5; metrics.hpp).
      {"followed_all_the_way", m.followedAllTheWay()},
      {"follow_failure_reason",
       m.followFailureReason().empty() ? nlohmann::json(nullptr) : nlohmann::json(m.followFailureReason())},
      {"max_loss_s", trial.spec.success.max_loss_s},
      {"max_distance_m", m.maxDistanceM()},
      {"longest_excursion_s", m.longestExcursionS()},
      // Null when the run reported no followed identities (recordFollowed never called).
      {"identity_switches", m.followedFrames() > 0 ? nlohmann::json(m.identitySwitches()) : nlohmann::json(nullptr)},
      {"identity_switches_nearest",
       m.followedFrames() > 0 ? nlohmann::json(m.identitySwitchesNearest()) : nlohmann::json(nullptr)},
      // The first kMaxSwitchEvents switches: when, between whom, how far apart the two were, a look-alike or not.
      {"identity_switch_events", switchEvents(m)},
      // How close others came to the person (null: nobody of that kind in the world).
      {"closest_approach_m",
       {{"bystander", finiteOrNull(m.closestBystanderM())}, {"look_alike", finiteOrNull(m.closestLookAlikeM())}}},
      {"time_on_wrong_person_s",
       m.followedFrames() > 0 ? nlohmann::json(m.timeOnWrongPersonS()) : nlohmann::json(nullptr)},
      {"person_top_speed_mps", m.personTopSpeedMps()},
      {"person_mean_speed_mps", m.personMeanSpeedMps()},
      {"person_speed_scale", trial.speed_scale},
      {"mirrored", trial.mirrored},
      {"odometry_drift",
       {{"position_m", sim.odometryPositionErrorM().norm()},  // issue 20: VIO drift at the end
        {"yaw_rad", sim.odometryFrameError().yaw_rad}}},
      {"controller", run.controller},
      {"executor", run.executor},
      {"interrupted", run.interrupted},
      {"sim_time_s", run.sim_time_s},
      {"wall_time_s", run.wall_time_s},
      {"realtime_factor", run.wall_time_s > 0.0 ? run.sim_time_s / run.wall_time_s : 0.0},
      {"tasks", timingJson(run.timings)},
      {"map", run.map},
      {"perception", run.perception},
      {"estimation", run.estimation},
      {"planning", run.planning},
      {"supervisor", run.supervisor},
      {"latency", run.latency},
  };
  if (!run.trace_hash.empty()) out["trace_hash"] = run.trace_hash;
  return out;
}

rt::Status drawTopdown(const hal::sim::Simulation& sim, const std::string& png_path) {
  constexpr int kHeaderPx = 50;  // two lines: the verdict, then the legend
  const hal::sim::ScenarioSpec& spec = sim.scenario().spec;
  const Eigen::Vector2d lo = spec.bounds_min_m.head<2>(), hi = spec.bounds_max_m.head<2>();
  const double scale = std::min(1400.0 / (hi.x() - lo.x()), 1000.0 / (hi.y() - lo.y()));  // px per metre
  const int margin = 40;
  const int width = static_cast<int>(std::ceil((hi.x() - lo.x()) * scale)) + 2 * margin;
  const int height = static_cast<int>(std::ceil((hi.y() - lo.y()) * scale)) + 2 * margin + kHeaderPx;
  cv::Mat image(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
  const auto px = [&](const Eigen::Vector3d& p) {
    return cv::Point(static_cast<int>(std::lround(margin + (p.x() - lo.x()) * scale)),
                     static_cast<int>(std::lround(margin + kHeaderPx + (hi.y() - p.y()) * scale)));
  };
  cv::rectangle(image, px({lo.x(), hi.y(), 0}), px({hi.x(), lo.y(), 0}), cv::Scalar(200, 200, 200), 1);
  for (const auto& b : sim.obstacles().boxes())
    cv::rectangle(image, px({b.min_W_m.x(), b.max_W_m.y(), 0}), px({b.max_W_m.x(), b.min_W_m.y(), 0}),
                  cv::Scalar(150, 150, 150), cv::FILLED);
  for (const auto& c : sim.obstacles().cylinders())
    cv::circle(image, px({c.center_W_m.x(), c.center_W_m.y(), 0}), std::max(1, static_cast<int>(c.radius_m * scale)),
               cv::Scalar(90, 110, 90), cv::FILLED);

  const auto& track = sim.metrics().track();
  // Bystanders (issue 20) in grey, look-alikes darker, each ending in a dot, under the others.
  for (std::size_t id = 1; id < sim.personCount(); ++id) {
    const bool look_alike = sim.scenario().bystanders.people[id - 1].look_alike;
    const cv::Scalar grey = look_alike ? cv::Scalar(110, 110, 110) : cv::Scalar(185, 185, 185);
    const auto at = [&](std::size_t i) {
      return sim.personStateAt(id, sim.startNs() + rt::secondsToNs(track[i].t_s)).p_W_m;
    };
    for (std::size_t i = 1; i < track.size(); ++i) cv::line(image, px(at(i - 1)), px(at(i)), grey, 1, cv::LINE_AA);
    if (!track.empty()) cv::circle(image, px(at(track.size() - 1)), 3, grey, cv::FILLED);
  }
  for (std::size_t i = 1; i < track.size(); ++i)
    cv::line(image, px(track[i - 1].person_m), px(track[i].person_m), cv::Scalar(200, 120, 30), 2, cv::LINE_AA);
  for (std::size_t i = 1; i < track.size(); ++i) {
    const cv::Scalar colour = track[i].visible ? cv::Scalar(60, 170, 40) : cv::Scalar(40, 40, 220);
    cv::line(image, px(track[i - 1].drone_m), px(track[i].drone_m), colour, 2, cv::LINE_AA);
  }
  // The odometry's drift (issue 20's drifting VIO): where the odometry put the drone, in purple, when it
  // strays from the truth by more than 5 cm anywhere (the world's map and the plans are in that frame).
  double max_drift_m = 0.0;
  for (const auto& s : track) max_drift_m = std::max(max_drift_m, (s.odometry_m - s.drone_m).head<2>().norm());
  if (max_drift_m > 0.05) {
    for (std::size_t i = 1; i < track.size(); ++i)
      cv::line(image, px(track[i - 1].odometry_m), px(track[i].odometry_m), cv::Scalar(200, 60, 170), 1, cv::LINE_AA);
  }
  for (const auto& loss : sim.metrics().losses()) cv::circle(image, px(loss.drone_m), 7, cv::Scalar(0, 140, 255), 2);
  if (!track.empty()) {
    cv::drawMarker(image, px(track.front().drone_m), cv::Scalar(0, 0, 0), cv::MARKER_TRIANGLE_UP, 14, 2);
    cv::drawMarker(image, px(track.back().drone_m), cv::Scalar(0, 0, 0), cv::MARKER_SQUARE, 12, 2);
    cv::drawMarker(image, px(track.back().person_m), cv::Scalar(200, 120, 30), cv::MARKER_SQUARE, 12, 2);
  }
  const std::string reason = sim.metrics().failureReason();
  char title[256];
  std::snprintf(title, sizeof(title), "%s seed %llu: %s   visible %.0f%%", spec.name.c_str(),
                static_cast<unsigned long long>(sim.scenario().seed), reason.empty() ? "success" : reason.c_str(),
                100.0 * sim.metrics().visibleRatio());
  char legend[256];
  char drift[64] = "";
  if (max_drift_m > 0.05) std::snprintf(drift, sizeof(drift), "  purple: odometry (drift up to %.2f m)", max_drift_m);
  std::snprintf(legend, sizeof(legend),
                "blue: person  green/red: drone (person visible / not)  orange: loss  grey: bystanders%s", drift);
  cv::putText(image, title, cv::Point(10, 20), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  cv::putText(image, legend, cv::Point(10, 42), cv::FONT_HERSHEY_SIMPLEX, 0.42, cv::Scalar(60, 60, 60), 1, cv::LINE_AA);
  try {
    if (!cv::imwrite(png_path, image)) return rt::Error{png_path + ": cannot write image"};
  } catch (const cv::Exception& e) {
    return rt::Error{png_path + ": cannot write image: " + e.what()};
  }
  return rt::ok();
}

rt::Expected<hal::sim::ScenarioInstance> loadTrial(const std::string& name_or_file, std::uint64_t seed,
                                                   std::optional<double> speed_override_mps) {
  const auto spec = hal::sim::loadScenarioSpec(resolveScenario(name_or_file));
  if (!spec) return spec.error();
  return hal::sim::instantiate(*spec, seed, speed_override_mps);
}

}  // namespace aerotrack::app
