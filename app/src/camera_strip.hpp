// The demo's second picture (issue 9 item 5): a strip of panels, one every few seconds of the run, each
// showing what the gimbal camera's detector saw (the skeletons it returned, the followed person in green,
// over the very frame the network ran on in image mode)
// above the map around the drone (the occupied cells of the local grid at flight height, the drone and
// its camera's field of view, the person's true and estimated positions, the trajectory being flown).
// Simulator only: the panels read the truth for the drone's pose and the person. Recording allocates;
// it is a reporting task, not part of the flight software.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "aerotrack/estimation/target_estimator.hpp"
#include "aerotrack/hal/sim/simulation.hpp"
#include "aerotrack/mapping/local_grid.hpp"
#include "aerotrack/rt/latest_slot.hpp"
#include "aerotrack/rt/shared_slot.hpp"
#include "aerotrack/rt/task.hpp"
#include "aerotrack/trajectory_server/trajectory.hpp"

namespace aerotrack::app {

struct CameraStripSources {
  const rt::LatestSlot<hal::DetectionFrame>& detection;
  const rt::LatestSlot<estimation::TargetEstimate>& target;
  const rt::SharedSlot<mapping::LocalGrid>& grid;
  const rt::SharedSlot<trajectory_server::TimedTrajectory>& trajectories;
  /// Image-mode frames (issue 24 item 4): a panel waits (up to a second) for the detection of the frame it
  /// holds, and shows that frame under the skeletons. Null, or never written (keypoint mode): skeletons on grey.
  const rt::SharedSlot<hal::ImageFrame>* images = nullptr;
};

class CameraStripTask final : public rt::Task {
 public:
  CameraStripTask(std::shared_ptr<hal::sim::Simulation> sim, const CameraStripSources& sources, double every_s,
                  double camera_hfov_rad);
  void step(rt::TimeNs now_ns) override;
  std::size_t panels() const { return panels_.size(); }
  /// Writes the panels side by side (up to six a row) as a PNG; error if there are none or the write fails.
  rt::Status write(const std::string& png_path) const;

 private:
  cv::Mat cameraPanel(const hal::DetectionFrame* frame, const hal::ImageFrame* image, double t_s) const;
  cv::Mat mapPanel(const hal::sim::TruthSnapshot& truth, rt::TimeNs now_ns) const;

  std::shared_ptr<hal::sim::Simulation> sim_;
  CameraStripSources sources_;
  rt::DurationNs every_ns_;
  double hfov_rad_;
  rt::TimeNs next_ns_ = -1;
  bool waiting_ = false;       ///< A panel is due, waiting for the detection of held_image_.
  rt::TimeNs give_up_ns_ = 0;  ///< Then drawn with what there is.
  hal::ImageFrameHandle held_image_;
  std::vector<cv::Mat> panels_;
};

}  // namespace aerotrack::app
