// The one place where devices, channels, modules and tasks are wired (DESIGN.md: app/). A System
// is built from an AppConfig: the HAL factory makes the devices, then every row of the task table
// becomes a task bound to its channels. A name in the table that no task answers to is an error,
// and so is a simulated device without the task that steps the simulation.
#pragma once

#include <atomic>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "aerotrack/hal/factory.hpp"
#include "aerotrack/hal/replay/recorder.hpp"
#include "aerotrack/mapping/mapping_task.hpp"
#include "aerotrack/perception/detection_task.hpp"
#include "aerotrack/planning/planning_task.hpp"
#include "aerotrack/rt/doorbell.hpp"
#include "aerotrack/rt/latest_slot.hpp"
#include "aerotrack/rt/shared_slot.hpp"
#include "aerotrack/rt/spsc_queue.hpp"
#include "aerotrack/rt/task.hpp"
#include "aerotrack/supervisor/supervisor_task.hpp"
#include "aerotrack/trajectory_server/trajectory.hpp"
#include "aerotrack/trajectory_server/trajectory_server_task.hpp"
#include "app_config.hpp"
#include "camera_strip.hpp"
#include "output_recorder.hpp"

namespace aerotrack::app {

class TargetTruthCheckTask;
class FlightLogTask;

/// With --record, the modules' outputs are polled this often: the target task's fastest (its 10 ms rate
/// cap in the shipped tables; it runs on each detection and at 50 Hz), so estimates are seen as they come.
inline constexpr double kOutputRecordRateHz = 100.0;

/// The channels a task's `trigger` may name (System::attachTrigger), for messages.
inline constexpr const char* kTriggerChannels =
    "odometry, setpoints, trajectories, detections, images, target, depth, gimbal_state, local_grid";

/// Every channel of the process. Names here are the names a task's `trigger` may use.
struct Channels {
  rt::LatestSlot<hal::OdometrySample> odometry;
  rt::LatestSlot<hal::Setpoint> setpoints;
  rt::SharedSlot<trajectory_server::TimedTrajectory> trajectories;
  rt::SpscQueue<hal::DetectionFrame> detections{16, rt::OverflowPolicy::kDropOldest};
  rt::SharedSlot<hal::DepthFrame> depth;
  rt::SharedSlot<hal::ImageFrame> images;
  rt::SpscQueue<hal::OdometrySample> odometry_target_stream{256,
                                                            rt::OverflowPolicy::kDropOldest};  ///< for the target task
  rt::SpscQueue<hal::GimbalState> gimbal_stream{512, rt::OverflowPolicy::kDropOldest};  ///< every encoder reading
  rt::LatestSlot<estimation::TargetEstimate> target;  ///< the target estimator's newest estimate  ///< gimbal-camera
                                                      ///< images (image-mode cameras), for the detector
  rt::LatestSlot<hal::GimbalState> gimbal_state;
  rt::SpscQueue<hal::OdometrySample> odometry_stream{
      256, rt::OverflowPolicy::kDropOldest};  ///< every sample, for the mapper
  rt::SharedSlot<mapping::LocalGrid> local_grid;
  rt::SharedSlot<octomap::OcTree> octree;
  std::atomic<bool> gimbal_search_requested{false};        ///< the supervisor asks the gimbal to sweep
  std::atomic<rt::TimeNs> newest_camera_frame_ns{-1};      ///< capture time of the newest gimbal-camera frame
  rt::LatestSlot<supervisor::SupervisorState> supervisor;  ///< the supervisor's mode
  std::atomic<int> planner_failures_in_a_row{0};           ///< written by the planning task
  rt::LatestSlot<hal::DetectionFrame> newest_detection;    ///< the newest detector output (for pictures)
  rt::LatestSlot<hal::DetectionFrame> followed_detection;  ///< each frame the estimator took, with whom (target task)
  std::atomic<std::uint64_t> deadline_misses{0};           ///< periods skipped, fed by the real-time executor only
  std::atomic<bool> vehicle_link_lost{false};              ///< the vehicle link was up and is down (trajectory server)
  rt::LatestSlot<planning::PlanSnapshot> plan_snapshots;   ///< What each planning cycle found (for the flight log)
  std::atomic<rt::TimeNs> refused_trajectory_start_ns{
      -1};  ///< the newest trajectory refused as late (trajectory server)
};

class System {
 public:
  /// Builds devices and tasks. scenario: the trial the sim backends fly (needed only if a
  /// backend is "sim"). start_ns: the executor clock's time at start (the simulation's epoch).
  System(const System&) = delete;
  System& operator=(const System&) = delete;
  ~System();
  static rt::Expected<std::unique_ptr<System>> build(const AppConfig& config,
                                                     const hal::sim::ScenarioInstance* scenario, rt::TimeNs start_ns);

  const std::vector<rt::TaskBinding>& bindings() const { return bindings_; }
  Channels& channels() { return channels_; }
  hal::Devices& devices() { return devices_; }
  /// After the executor has stopped: ends the recording (if any) and says what it holds, in one line
  /// ("" without --record). The Error is a write failure; what was written before it stays readable.
  /// end_ns: the run's last instant (into the manifest, so a replay runs as long).
  rt::Expected<std::string> finishRecording(rt::TimeNs end_ns);
  /// After the executor has stopped: closes the flight log (if any) and says what it holds, in one line
  /// ("" without --mcap). A log that stopped early (a full disk) says so in that line; the Error is only
  /// for a file that could not be closed.
  std::string finishFlightLog();
  /// Hands the executor's per-task statistics to the flight log (if any), once every task is added.
  void watchTimings(std::vector<rt::TaskSet::NamedStats> timings);
  const AppConfig& config() const { return config_; }
  /// The real-time executor's options from the config, reporting missed deadlines to the supervisor.
  rt::RealtimeOptions realtimeOptions() {
    rt::RealtimeOptions options = config_.realtime;
    options.deadline_misses = &channels_.deadline_misses;
    return options;
  }
  /// The mapping task, if the table has one (for its statistics).
  const mapping::MappingTask* mappingTask() const { return mapping_task_; }
  /// The simulator's check of the target estimate against the truth, if the table has one.
  const TargetTruthCheckTask* targetCheckTask() const { return target_check_task_; }
  /// The target task, if the table has one (for its statistics).
  const estimation::TargetTask* targetTask() const { return target_task_; }
  /// The detection task, if the table has one (for its statistics).
  const perception::DetectionTask* detectionTask() const { return detection_task_; }

  /// The camera strip recorder, if the table has one (sim only).
  const CameraStripTask* cameraStripTask() const { return camera_strip_task_; }
  /// The trajectory server task, if the table has one (for the end-to-end latency).
  const trajectory_server::TrajectoryServerTask* trajectoryServerTask() const { return server_task_; }
  /// The supervisor task, if the table has one.
  const supervisor::SupervisorTask* supervisorTask() const { return supervisor_task_; }
  /// The planning task, if the table has one (for its statistics and the replan hand-over).
  const planning::PlanningTask* planningTask() const { return planning_task_; }

  /// Names of the tasks the task table may use (the registry's rows, in order), for messages and tests.
  static std::vector<std::string> knownTasks();

  /// `--mode truth_flight` (simulator only): the table's flight tasks (planning, gimbal control, supervisor,
  /// trajectory server, and the mapping and camera strip that serve them) replaced by the truth-fed
  /// baseline_follow, which flies the drone and aims the gimbal at the true person. Perception and estimation
  /// run as the table has them, but nothing they decide moves the camera: two configurations of the detector or
  /// the association see the same images, so their identity results compare trial by trial (a paired measure;
  /// in closed loop a different association flies another path, and every later frame differs).
  static void flyFromTruth(std::vector<rt::TaskSpec>& tasks);

  using TaskResult = rt::Expected<std::unique_ptr<rt::Task>>;

 private:
  /// A row of the task registry (system.cpp): the name a task-table row uses, whether the task needs the
  /// simulator, and how it is built. `where` is the table row, for messages.
  struct TaskKind {
    const char* name;
    bool needs_sim;
    TaskResult (*make)(System& system, const std::string& where);
  };
  static std::span<const TaskKind> taskKinds();
  static TaskResult makeSimFollower(System& s, bool command_vehicle);
  static TaskResult makeCameraStripTask(System& s, const std::string& where);
  static TaskResult makeMappingTask(System& s, const std::string& where);
  static TaskResult makeDetectionTask(System& s, const std::string& where);
  static TaskResult makeTargetTask(System& s, const std::string& where);
  static TaskResult makeGimbalControlTask(System& s, const std::string& where);
  static TaskResult makeSupervisorTask(System& s, const std::string& where);
  static TaskResult makePlanningTask(System& s, const std::string& where);
  static TaskResult makeTrajectoryServerTask(System& s, const std::string& where);

  explicit System(AppConfig config) : config_(std::move(config)) {}
  /// Adds the flight log (--mcap) after every other task, as an observer.
  rt::Status addFlightLog();
  rt::Status addTask(const rt::TaskSpec& spec, std::size_t index);
  /// Rings doorbell on every write to the named channel (one triggered task per channel).
  rt::Status attachTrigger(const std::string& channel, rt::Doorbell* doorbell);

  AppConfig config_;
  std::unique_ptr<hal::replay::DatasetRecorder> recorder_;  // before devices_: the recording decorators use it
  hal::Devices devices_;
  Channels channels_;
  std::vector<std::unique_ptr<rt::Task>> tasks_;
  std::vector<std::unique_ptr<rt::Doorbell>> doorbells_;
  std::vector<std::pair<std::string, std::string>> triggered_by_;  ///< (channel, the task it triggers)
  std::vector<rt::TaskBinding> bindings_;
  const mapping::MappingTask* mapping_task_ = nullptr;
  const perception::DetectionTask* detection_task_ = nullptr;
  const estimation::TargetTask* target_task_ = nullptr;
  const TargetTruthCheckTask* target_check_task_ = nullptr;
  const planning::PlanningTask* planning_task_ = nullptr;
  const supervisor::SupervisorTask* supervisor_task_ = nullptr;
  const trajectory_server::TrajectoryServerTask* server_task_ = nullptr;
  const CameraStripTask* camera_strip_task_ = nullptr;
  OutputRecorderTask* output_recorder_ = nullptr;  // with --record
  FlightLogTask* flight_log_ = nullptr;            // with --mcap
  rt::TimeNs start_ns_ = 0;                        ///< The executor clock's time at start.
  rt::MonotonicClock stats_clock_;                 ///< Measures work inside tasks for statistics only.
};

}  // namespace aerotrack::app
