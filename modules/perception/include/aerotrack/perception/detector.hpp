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
//     While locked, the whole frame is searched too when the crop would hide someone (WholeFrameParams):
//     another person near the crop, the target estimator refusing the crop's person, and now and then.
//   The target estimator has the last word on who the person is (its association sees the people in the
//   world): judged() takes its verdict on an earlier frame, and where it took someone other than the
//   lock-on's choice, the crop moves to them (issue 22, item 2: a crop on the look-alike showed the
//   network nobody else, and the person, back in view, was never detected again).
// Not thread-safe: one Detector per thread. Allocation-free per frame after the first frames of a
// given size (OpenCV's DNN reuses its buffers).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>

#include <opencv2/core/mat.hpp>

#include "aerotrack/hal/types.hpp"
#include "aerotrack/perception/input_transform.hpp"
#include "aerotrack/perception/movenet_model.hpp"
#include "aerotrack/perception/person_tracker.hpp"
#include "aerotrack/perception/torso_features.hpp"
#include "aerotrack/rt/expected.hpp"

namespace aerotrack::perception {

/// When the tracking loop, locked, runs the search model on the whole frame instead of the crop (issue 22,
/// item 2). Singlepose on a crop reports one person: with two people in it, the estimator sees one of them,
/// whichever the network prefers, and cannot keep both on their tracks.
struct WholeFrameParams {
  /// Another person of the last whole-frame result whose box comes within this many crop sides of the crop
  /// around the followed person: the next frame is searched whole as well (< 0: never, the default: measured in
  /// the image-mode crowd it did not help, docs/benchmarks.md; 0.5 tried).
  double near_crop_sides = -1.0;
  /// At least this often (a newcomer walking towards the crop is noticed before they are in it; 0: never; 1 tried).
  double every_s = 0.0;
  /// When the crop finds nobody the lock-on accepts: true, the whole frame at once (kCropLost); false, while the
  /// estimator's newest verdict (follow_estimator) says its track is live, the crop's own result is published
  /// instead, for the estimator to judge, and its verdict sends the next crop to where it predicts the person. The
  /// whole frame shows everyone the estimator might take for the person: after an occlusion, a look-alike beside the
  /// hidden person (traced: image-mode crowd seed 41). Measured level in the image-mode crowd (docs/benchmarks.md).
  bool on_crop_lost = true;
  /// Locked, the crop published: at least this often the search model also runs on the whole frame, and the people
  /// it shows other than the crop's are added to the crop's frame (0: never). The followed person keeps the crop's
  /// measurement (a whole frame replacing the crop measured them small, or not at all, and a bystander near their
  /// prediction was taken: every_s, docs/benchmarks.md), while a newcomer -- a look-alike walking up to the person --
  /// is seen, and tracked as someone else, before they reach the crop (issue 22, item 2). One more inference each time.
  double beside_crop_every_s = 0.0;
};

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
  WholeFrameParams whole_frame;
  /// The app hands the detection task the target estimator's verdicts (DetectionTask::judgedBy): the crop
  /// follows whom the estimator follows. The detector itself only acts on verdicts it is given.
  bool follow_estimator = false;
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

/// Why track() ran the search model on the whole frame.
enum class WholeFrameReason : std::uint8_t {
  kNone,        ///< It did not: the crop found the person.
  kNoLock,      ///< No lock (before the first, or lost).
  kCropLost,    ///< The crop found nobody the lock-on accepts.
  kOthersNear,  ///< Someone else was near the crop (WholeFrameParams::near_crop_sides).
  kRefused,     ///< The estimator's newest verdict did not take the lock-on's choice.
  kPeriodic,    ///< WholeFrameParams::every_s.
  kWanted,      ///< The estimator's newest verdict asked for it (DetectionFrame::whole_frame_wanted).
};
inline constexpr std::size_t kWholeFrameReasons = 7;
/// "crop", "no_lock", "crop_lost", "others_near", "refused", "periodic", "wanted".
const char* toString(WholeFrameReason reason);

/// How often each way of running the network was taken, and the verdicts that moved the crop.
struct TrackCounts {
  std::array<std::uint64_t, kWholeFrameReasons> runs{};  ///< By WholeFrameReason (kNone: the crop alone).
  std::uint64_t reseated = 0;                            ///< Verdicts that moved the lock to another person.
  std::uint64_t to_prediction = 0;      ///< Verdicts that took nobody and moved the crop to the track's prediction.
  std::uint64_t beside_crop = 0;        ///< Whole frames run beside a crop (WholeFrameParams::beside_crop_every_s)...
  std::uint64_t beside_crop_added = 0;  ///< ... and the people they added to the crop's frames.
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

  /// The target estimator's verdict on an earlier frame of track(): that frame as published (its stamp
  /// names it), target_index the person the estimator took (-1: nobody). Where the estimator took someone
  /// else than the lock-on did, the lock moves to them; where it took nobody, the lock and the next crop move to
  /// where its live track predicts the person (predicted_torso), and without a prediction the next frame is
  /// searched whole, as it is where the verdict asks for it (whole_frame_wanted). A verdict on a frame this
  /// detector does not remember (too old, or another's) is ignored.
  void judged(const hal::DetectionFrame& verdict);

  const PersonTracker& tracker() const { return tracker_; }
  const TrackCounts& counts() const { return counts_; }
  const DetectorParams& params() const { return params_; }
  /// The loaded model of that name, loading it on first use.
  rt::Expected<MoveNetModel*> model(const std::string& name);

 private:
  explicit Detector(const DetectorParams& params) : params_(params), tracker_(params.tracker) {}
  rt::Expected<DetectorOutput> runModel(MoveNetModel& model, const cv::Mat& bgr, const InputTransform& transform);
  /// The lock and the next crop go to a predicted torso in the image stamped stamp_ns.
  void lookAt(rt::TimeNs stamp_ns, const hal::DetectionFrame::PredictedTorso& torso);

  DetectorParams params_;
  std::array<std::optional<MoveNetModel>, 3> models_;  ///< By knownModelNames() index.
  PersonTracker tracker_;
  TransformScratch scratch_;
  std::array<cv::Mat, 3> blobs_;  ///< By model index.
  std::optional<std::array<hal::Keypoint2D, hal::kNumKeypoints>> last_target_keypoints_;
  /// After a whole-frame result: nearby people (WholeFrameParams::near_crop_sides).
  bool others_near_ = false;
  /// The newest verdict did not take the lock-on's choice.
  bool refused_ = false;
  /// The newest verdict asked for the whole frame.
  bool wanted_ = false;
  /// The newest verdict took someone or predicted where the person is: the estimator's track is live.
  bool estimator_live_ = false;
  rt::TimeNs last_whole_ns_ = 0;
  rt::TimeNs newest_verdict_ns_ = -1;
  /// The lock-on's choice on the latest frames (stamp, person; -1 nobody), oldest overwritten first.
  struct Choice {
    rt::TimeNs stamp_ns = -1;
    int person = -1;
  };
  std::array<Choice, 8> recent_{};
  std::size_t recent_next_ = 0;
  int width_px_ = 0, height_px_ = 0;  ///< Of the latest image.
  TrackCounts counts_;
};

/// Adds to `crop` (a crop's result) the people of `whole` (the same image's whole-frame result) who are not the
/// crop's. Each of the crop's people is the whole frame's person nearest to them -- the mean distance of the joints
/// both score above min_keypoint_score (at least three), in units of the taller box's height; with fewer common joints,
/// a box overlapping theirs by more than half of the smaller one's area -- if within same_fraction. Returns how many
/// were added (at most hal::kMaxPersons in all).
std::size_t addOthersBesideCrop(DetectorOutput& crop, const DetectorOutput& whole, double min_keypoint_score,
                                double same_fraction = 0.3);

/// Whether a person other than persons[target] has a box within margin_sides x the region's side of the
/// region (the crop around the target). Pure.
bool someoneNearRegion(std::span<const hal::PersonDetection> persons, std::size_t target, const InputTransform& region,
                       double margin_sides);

/// The person a singlepose result describes, in image pixels: keypoints mapped back through the
/// transform, the box around the joints above min_score grown by margin_fraction and clipped to the
/// image, the score the mean joint score. Pure.
hal::PersonDetection singlePoseToImage(const NormalisedPose& pose, const InputTransform& transform, int width_px,
                                       int height_px, double bbox_min_keypoint_score, double bbox_margin_fraction);

/// One multipose instance in image pixels (box from the model, clipped to the image). Pure.
hal::PersonDetection multiPoseToImage(const MultiPoseInstance& instance, const InputTransform& transform, int width_px,
                                      int height_px);

}  // namespace aerotrack::perception
