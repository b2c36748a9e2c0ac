// The camera strip: see camera_strip.hpp.
#include "camera_strip.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace aerotrack::app {
namespace {

constexpr int kPanelW = 320;
constexpr int kCameraH = 240;
constexpr int kMapH = 320;
constexpr double kMapHalfM = 5.0;  // the map shows 10 x 10 m around the drone
constexpr std::size_t kMaxPanels = 48;

void label(cv::Mat& image, const std::string& text, cv::Point at) {
  cv::putText(image, text, at, cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(20, 20, 20), 1, cv::LINE_AA);
}

}  // namespace

CameraStripTask::CameraStripTask(std::shared_ptr<hal::sim::Simulation> sim, const CameraStripSources& sources,
                                 double every_s, double camera_hfov_rad)
    : sim_(std::move(sim)), sources_(sources), every_ns_(rt::secondsToNs(every_s)), hfov_rad_(camera_hfov_rad) {
  panels_.reserve(kMaxPanels);
}

cv::Mat CameraStripTask::cameraPanel(const hal::DetectionFrame* frame, const hal::ImageFrame* image, double t_s) const {
  cv::Mat panel(kCameraH, kPanelW, CV_8UC3, cv::Scalar(215, 215, 215));
  if (image != nullptr && !image->bgr.empty() && image->bgr.type() == CV_8UC3) {
    cv::resize(image->bgr, panel, panel.size(), 0.0, 0.0, cv::INTER_AREA);
    // The label on a light band, readable over any picture.
    cv::rectangle(panel, cv::Rect(0, 0, kPanelW, 26), cv::Scalar(235, 235, 235), cv::FILLED);
  }
  char text[96];
  if (frame == nullptr) {
    std::snprintf(text, sizeof(text), "t %.0f s: no detection yet", t_s);
    label(panel, text, {8, 18});
    return panel;
  }
  const double scale = frame->intrinsics.width_px > 0 ? static_cast<double>(kPanelW) / frame->intrinsics.width_px : 0.5;
  constexpr double kMinScore = 0.3;
  for (std::size_t i = 0; i < frame->person_count; ++i) {
    const bool followed = static_cast<int>(i) == frame->target_index;
    const cv::Scalar colour = followed           ? cv::Scalar(40, 200, 40)
                              : image != nullptr ? cv::Scalar(0, 140, 255)
                                                 : cv::Scalar(90, 90, 90);
    const auto& k = frame->persons[i].keypoints;
    const auto pt = [&](int j) {
      const hal::Keypoint2D& p = k[static_cast<std::size_t>(j)];
      return cv::Point2d(p.u_px * scale, p.v_px * scale);
    };
    for (const auto& [a, b] : hal::kCocoSkeleton) {
      if (k[static_cast<std::size_t>(a)].score >= kMinScore && k[static_cast<std::size_t>(b)].score >= kMinScore)
        cv::line(panel, pt(a), pt(b), colour, 2, cv::LINE_AA);
    }
  }
  cv::line(panel, {kPanelW / 2, 0}, {kPanelW / 2, kCameraH}, cv::Scalar(160, 160, 160), 1);  // image centre
  std::snprintf(text, sizeof(text), "t %.0f s: %s, %zu person(s)%s", t_s,
                image != nullptr ? "the network's frame" : "camera", frame->person_count,
                frame->target_index >= 0 ? "" : ", target not found");
  label(panel, text, {8, 18});
  return panel;
}

cv::Mat CameraStripTask::mapPanel(const hal::sim::TruthSnapshot& truth, rt::TimeNs now_ns) const {
  cv::Mat panel(kMapH, kPanelW, CV_8UC3, cv::Scalar(250, 250, 250));
  const double px_per_m = kMapH / (2.0 * kMapHalfM);
  const Eigen::Vector3d& c = truth.drone_p_W_m;
  // x east to the right, y north up, centred on the drone
  const auto px = [&](const Eigen::Vector3d& p) {
    return cv::Point2d(kPanelW / 2.0 + (p.x() - c.x()) * px_per_m, kMapH / 2.0 - (p.y() - c.y()) * px_per_m);
  };
  if (const auto grid = sources_.grid.read()) {
    const double res = grid->params().resolution_m;
    for (double y = c.y() - kMapHalfM; y < c.y() + kMapHalfM; y += res) {
      for (double x = c.x() - kMapHalfM * kPanelW / kMapH; x < c.x() + kMapHalfM * kPanelW / kMapH; x += res) {
        const Eigen::Vector3d p(x, y, c.z());
        if (grid->state(p) == mapping::CellState::kOccupied) {
          const cv::Point2d a = px(p);
          cv::rectangle(panel, cv::Rect2d(a.x, a.y - res * px_per_m, res * px_per_m + 1, res * px_per_m + 1),
                        cv::Scalar(70, 90, 70), cv::FILLED);
        }
      }
    }
  }
  if (const auto timed = sources_.trajectories.read(); timed && timed->trajectory) {
    const trajectory_server::Trajectory& traj = *timed->trajectory;
    const double t0 = std::max(0.0, rt::nsToSeconds(now_ns - timed->start_ns));
    cv::Point2d last = px(traj.sample(t0).p_W_m);
    for (double t = t0 + 0.05; t <= traj.durationS(); t += 0.05) {
      const cv::Point2d next = px(traj.sample(t).p_W_m);
      cv::line(panel, last, next, cv::Scalar(60, 170, 60), 2, cv::LINE_AA);
      last = next;
    }
  }
  // The camera's field of view (87 degrees), from the gimbal's heading.
  const double heading = truth.drone_yaw_rad + truth.gimbal_angle_rad;
  const cv::Point2d eye = px(c);
  for (const double side : {-0.5, 0.5}) {
    const double a = heading + side * hfov_rad_;
    cv::line(panel, eye, eye + cv::Point2d(std::cos(a), -std::sin(a)) * 4.0 * px_per_m, cv::Scalar(120, 120, 220), 1,
             cv::LINE_AA);
  }
  cv::circle(panel, eye, 5, cv::Scalar(30, 30, 200), cv::FILLED);
  cv::circle(panel, px(truth.person_p_W_m), 6, cv::Scalar(200, 120, 30), cv::FILLED);  // truth, blue
  if (const auto estimate = sources_.target.read(); estimate && estimate->initialised && !estimate->lost)
    cv::circle(panel, px(estimate->p_WT_m), 8, cv::Scalar(0, 140, 255), 2, cv::LINE_AA);  // estimate, orange
  label(panel, "10 m map, plan, person, estimate", {8, kMapH - 8});
  return panel;
}

void CameraStripTask::step(rt::TimeNs now_ns) {
  if (next_ns_ < 0) next_ns_ = now_ns + every_ns_;
  if (panels_.size() >= kMaxPanels) return;
  if (!waiting_) {
    if (now_ns < next_ns_) return;
    next_ns_ += every_ns_;
    waiting_ = true;
    give_up_ns_ = now_ns + rt::secondsToNs(1.0);
    held_image_ = sources_.images != nullptr ? sources_.images->read() : nullptr;
  }
  const auto frame = sources_.detection.read();
  // In image mode, the panel waits for the detection of the frame it holds (the detector's latency, a
  // frame or two); a detector that skipped it moves the panel on to the newest frame.
  const bool matched = held_image_ && frame && frame->stamp_ns == held_image_->stamp_ns;
  if (held_image_ && !matched && now_ns < give_up_ns_) {
    if (frame && frame->stamp_ns > held_image_->stamp_ns) held_image_ = sources_.images->read();
    return;
  }
  waiting_ = false;
  const hal::ImageFrameHandle image = matched ? std::move(held_image_) : nullptr;
  held_image_.reset();
  const auto truth = sim_->truthOut().read();
  if (!truth) return;
  const double t_s = sim_->secondsSinceStart(now_ns);
  cv::Mat panel;
  cv::vconcat(cameraPanel(frame ? &*frame : nullptr, image.get(), t_s), mapPanel(*truth, now_ns), panel);
  cv::rectangle(panel, cv::Rect(0, 0, panel.cols, panel.rows), cv::Scalar(120, 120, 120), 1);
  panels_.push_back(std::move(panel));
}

rt::Status CameraStripTask::write(const std::string& png_path) const {
  if (panels_.empty()) return rt::Error{png_path + ": no panels were recorded (run shorter than one period)"};
  constexpr std::size_t kPerRow = 6;
  std::vector<cv::Mat> rows;
  for (std::size_t i = 0; i < panels_.size(); i += kPerRow) {
    std::vector<cv::Mat> row(panels_.begin() + static_cast<std::ptrdiff_t>(i),
                             panels_.begin() + static_cast<std::ptrdiff_t>(std::min(panels_.size(), i + kPerRow)));
    while (row.size() < kPerRow && i > 0)
      row.emplace_back(panels_[0].size(), panels_[0].type(), cv::Scalar(255, 255, 255));
    cv::Mat joined;
    cv::hconcat(row, joined);
    rows.push_back(joined);
  }
  cv::Mat strip;
  cv::vconcat(rows, strip);
  try {
    if (!cv::imwrite(png_path, strip)) return rt::Error{png_path + ": cannot write"};
  } catch (const cv::Exception& e) {
    return rt::Error{png_path + ": cannot write: " + e.msg};
  }
  return rt::ok();
}

}  // namespace aerotrack::app
