// Detection task and its config section: see detection_task.hpp.
#include "aerotrack/perception/detection_task.hpp"

namespace aerotrack::perception {

DetectorParams parseDetectorParams(const rt::ConfigNode& node) {
  DetectorParams p;
  p.model_dir = node.getString("model_dir");
  p.tracking_model = node.getEnum("tracking_model", {"lightning", "thunder"});
  p.search_model = node.getEnum("search_model", {"multipose", "lightning", "thunder"});
  p.dnn.backend = node.getEnum("dnn_backend", {"auto", "opencv", "cuda"});
  p.dnn.target = node.getEnum("dnn_target", {"auto", "cpu", "cuda", "cuda_fp16"});
  p.min_person_score = node.getDouble("min_person_score", 0.0, 1.0);
  p.min_multipose_score = node.getDouble("min_multipose_score", 0.0, 1.0);
  const rt::ConfigNode whole = node.child("whole_frame");
  p.whole_frame.near_crop_sides = whole.getDouble("near_crop_sides", -1.0, 10.0);
  p.whole_frame.every_s = whole.getDouble("every_s", 0.0, 3600.0);
  p.whole_frame.on_crop_lost = whole.getBoolOr("on_crop_lost", p.whole_frame.on_crop_lost);
  p.whole_frame.beside_crop_every_s =
      whole.getDoubleOr("beside_crop_every_s", p.whole_frame.beside_crop_every_s, 0.0, 3600.0);
  whole.finish();
  p.follow_estimator = node.getBool("follow_estimator");
  p.torso.min_joint_score = node.getDouble("torso_min_joint_score", 0.0, 1.0);
  p.torso.border_margin_px = node.getDouble("torso_border_margin_px", 0.0, 100.0);
  p.torso.edge_margin_torso_fraction = node.getDouble("torso_edge_margin_fraction", 0.0, 2.0);
  p.torso.edge_guess_max_score = node.getDouble("torso_edge_guess_max_score", 0.0, 1.0);
  const rt::ConfigNode tracker = node.child("tracker");
  p.tracker.gate_torso_multiples = tracker.getDouble("gate_torso_multiples", 0.1, 20.0);
  p.tracker.max_torso_ratio = tracker.getDouble("max_torso_ratio", 1.01, 10.0);
  p.tracker.max_appearance_distance = tracker.getDouble("max_appearance_distance", 0.01, 1.0);
  p.tracker.appearance_weight = tracker.getDouble("appearance_weight", 0.0, 100.0);
  p.tracker.lost_after_s = tracker.getDouble("lost_after_s", 0.01, 60.0);
  p.tracker.appearance_rate = tracker.getDouble("appearance_rate", 0.0, 1.0);
  tracker.finish();
  node.finish();
  return p;
}

hal::DetectionFrame toDetectionFrame(const DetectorOutput& output, const hal::ImageFrame& image, rt::TimeNs result_ns) {
  hal::DetectionFrame frame;
  frame.stamp_ns = image.stamp_ns;
  frame.result_ns = result_ns;
  frame.sequence = image.sequence;
  frame.intrinsics = image.intrinsics;
  frame.person_count = output.count;
  for (std::size_t i = 0; i < output.count; ++i) {
    // The signature measured from the image travels with the detection: the target task's association
    // compares it with each track's learnt colour (before, image mode's association was colour-blind).
    frame.persons[i] = output.persons[i].detection;
    frame.persons[i].appearance = output.persons[i].appearance.histogram;
    frame.persons[i].has_appearance = output.persons[i].appearance.valid;
  }
  frame.target_index = output.target ? static_cast<int>(*output.target) : -1;
  return frame;
}

bool DetectionTask::gather(rt::TimeNs /*now_ns*/) {
  if (images_.version() == image_version_) return false;
  image_version_ = images_.version();
  auto image = images_.read();
  if (!image || image->bgr.empty()) return false;
  image_ = std::move(image);
  if (verdicts_ != nullptr) verdict_ = verdicts_->read();
  return true;
}

void DetectionTask::work() {
  const rt::TimeNs begin_ns = stats_clock_.now();
  if (verdict_) {
    detector_.judged(*verdict_);
    verdict_.reset();
  }
  output_ = detector_.track(image_->bgr, image_->stamp_ns);
  detect_stats_.recordRun(stats_clock_.now() - begin_ns);
}

void DetectionTask::publish(rt::TimeNs publish_ns) {
  const std::shared_ptr<const hal::ImageFrame> image = std::move(image_);  // leaves image_ empty
  if (!output_ || !*output_) {
    ++failures_;
    output_.reset();
    return;
  }
  const DetectorOutput& output = output_->value();
  ++frames_detected_;
  if (output.target) ++frames_with_target_;
  const hal::DetectionFrame frame = toDetectionFrame(output, *image, publish_ns);
  output_.reset();
  out_.try_push(frame);
  if (newest_ != nullptr) newest_->write(frame);
}

}  // namespace aerotrack::perception
