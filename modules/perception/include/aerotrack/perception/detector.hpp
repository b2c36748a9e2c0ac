// The person detector of the gimbal camera (issue 5, item 3; the paper's Sect. IV-A uses OpenPose,
// we use MoveNet): image in, persons with COCO keypoints in image pixels out, and which of them is
// the followed person.
//
// Two ways to run it:
//   - detectFrame(): one model on the whole (letterboxed) frame, no memory -- the `detect` command
//     on a photo;
//   - track(): the tracking loop MoveNet was designed for. While locked, the singlepose model runs
//     on a square crop around the person's last keypoints (the person fills the input, so distant
//     people keep their detail); when the crop finds nobody the tracker accepts, or before the first
//     lock, the search model (multipose by default) runs on the whole frame and the tracker picks
//     the target among everyone it finds (person_tracker.hpp), so a bystander cannot steal the track.
// Not thread-safe: one Detector per thread. Allocation-free per frame after the first frames of a
// given size (OpenCV's DNN reuses its buffers).
#pragma once

#include <array>
#include <optional>
#include <string>

#include <opencv2/core/mat.hpp>

#include "aerotrack/hal/types.hpp"
#include "aerotrack/perception/input_transform.hpp"
#include "aerotrack/perception/movenet_model.hpp"
#include "aerotrack/perception/person_tracker.hpp"
#include "aerotrack/perception/torso_features.hpp"
#include "aerotrack/rt/expected.hpp"

namespace aerotrack::perception {

struct DetectorParams {
  std::string model_dir = "models";
  std::string tracking_model = "lightning";  ///< Singlepose model for crops: lightning | thunder.
  std::string search_model = "multipose";    ///< Full-frame model without a lock: multipose | lightning | thunder.
  DnnOptions dnn;
  /// Persons below these scores are dropped. Singlepose always outputs a pose: its score is the mean
  /// joint score (people in the test photos 0.31-0.62, photos without people 0.03-0.21 but up to
  /// 0.40 on a building facade). Multipose's score is centre x mean confident joint (pedestrians of
  /// 60 px in vtest.avi 0.165-0.32, photos without people at most 0.115).
  double min_person_score = 0.25;
  double min_multipose_score = 0.15;
  double bbox_min_keypoint_score = 0.2;  ///< Singlepose boxes bound the joints above this score...
  double bbox_margin_fraction = 0.1;     ///< ...grown by this fraction of the larger side.
  CropParams crop;
  TorsoFeatureParams torso;
  TrackerParams tracker;
};
rt::Status validate(const DetectorParams& params);

struct DetectedPerson {
  hal::PersonDetection detection;
  TorsoFeatures torso;
  Appearance appearance;
};

struct DetectorOutput {
  std::array<DetectedPerson, hal::kMaxPersons> persons{};
  std::size_t count = 0;
  std::optional<std::size_t> target;  ///< Index of the followed person (track() only).
  const char* model = "";             ///< The model whose result this is.
  bool cropped = false;               ///< The model ran on a tracking crop, not the whole frame.
};

class Detector {
 public:
  /// Loads the tracking and search models (once each when they are the same).
  static rt::Expected<Detector> create(const DetectorParams& params);

  /// One model (any loaded or loadable name) on the whole frame; no tracking state is touched.
  rt::Expected<DetectorOutput> detectFrame(const cv::Mat& bgr, const std::string& model_name);

  /// One step of the tracking loop on an image exposed at stamp_ns. external: where the target
  /// estimator expects the person in this image, if it knows.
  rt::Expected<DetectorOutput> track(const cv::Mat& bgr, rt::TimeNs stamp_ns,
                                     const std::optional<ImagePrediction>& external = std::nullopt);

  const PersonTracker& tracker() const { return tracker_; }
  const DetectorParams& params() const { return params_; }
  /// The loaded model of that name, loading it on first use.
  rt::Expected<MoveNetModel*> model(const std::string& name);

 private:
  explicit Detector(const DetectorParams& params) : params_(params), tracker_(params.tracker) {}
  rt::Expected<DetectorOutput> runModel(MoveNetModel& model, const cv::Mat& bgr, const InputTransform& transform);

  DetectorParams params_;
  std::array<std::optional<MoveNetModel>, 3> models_;  ///< By knownModelNames() index.
  PersonTracker tracker_;
  TransformScratch scratch_;
  std::array<cv::Mat, 3> blobs_;  ///< By model index.
  std::optional<std::array<hal::Keypoint2D, hal::kNumKeypoints>> last_target_keypoints_;
};

/// The person a singlepose result describes, in image pixels: keypoints mapped back through the
/// transform, the box around the joints above min_score grown by margin_fraction and clipped to the
/// image, the score the mean joint score. Pure.
hal::PersonDetection singlePoseToImage(const NormalisedPose& pose, const InputTransform& transform, int width_px,
                                       int height_px, double bbox_min_keypoint_score, double bbox_margin_fraction);

/// One multipose instance in image pixels (box from the model, clipped to the image). Pure.
hal::PersonDetection multiPoseToImage(const MultiPoseInstance& instance, const InputTransform& transform, int width_px,
                                      int height_px);

}  // namespace aerotrack::perception
