// The target pipeline of the paper's Sect. IV-B as one task: each detection of the followed person
// (chosen by the association, TargetTaskParams::choose_by_estimate) with a reliable torso becomes a
// position in the camera frame (the fitted localization regression, its inputs measured in the image
// of a level camera at the same place: levelHomography), then in the world at the image's capture time
// (drone pose and gimbal angle interpolated from their histories, camera_to_world.hpp), then a
// measurement of the target estimator, whose newest estimate is published. A detection waits (up to max_wait)
// until odometry and encoder readings cover its capture time; the measurement noise grows with
// distance as the localization's error does (measured: about 2.5 % of the distance).
//
// The estimate is written at every step; the write wakes a task triggered by it (the planner) only when
// there is news: a newly accepted measurement, or the person found or lost. A step that only carries
// the estimate forward in time does not.
//
// Where a depth camera's frames are given (rangeFrom) and it sees the followed person, the distance of the live
// track's measurements comes from it instead of the regression (depth_range.hpp, issue 22 item 3): the
// measurement keeps the line of sight and the regression's height, takes the depth camera's range, and is
// ranged (its noise small along the line). Who a person is stays judged on the regression's measurement.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <optional>

#include "aerotrack/estimation/assignment.hpp"
#include "aerotrack/estimation/bystander_tracks.hpp"
#include "aerotrack/estimation/camera_to_world.hpp"
#include "aerotrack/estimation/depth_people.hpp"
#include "aerotrack/estimation/depth_range.hpp"
#include "aerotrack/estimation/gimbal_history.hpp"
#include "aerotrack/estimation/swap_check.hpp"
#include "aerotrack/estimation/target_estimator.hpp"
#include "aerotrack/hal/odometry_history.hpp"
#include "aerotrack/localization/localization_model.hpp"
#include "aerotrack/perception/keypoint_lock_on.hpp"
#include "aerotrack/perception/person_tracker.hpp"
#include "aerotrack/perception/torso_features.hpp"
#include "aerotrack/rt/latest_slot.hpp"
#include "aerotrack/rt/shared_slot.hpp"
#include "aerotrack/rt/spsc_queue.hpp"
#include "aerotrack/rt/task.hpp"

namespace aerotrack::estimation {

struct TargetTaskParams {
  localization::LocalizationParams localization;
  GimbalCameraExtrinsics extrinsics;
  TargetEstimatorParams estimator;
  perception::TorsoFeatureParams torso;
  /// The appearance gate, weight and learning rate of the association (the lock-on's; the app copies them).
  perception::TrackerParams tracker;
  double measurement_std_per_m = 0.025;  ///< Horizontal noise per metre of distance...
  double min_measurement_std_m = 0.05;   ///< ...but at least this.
  /// A torso unreliable for a distance whose shoulders (or hips) are whole: a bearing-only measurement
  /// at the estimate's distance (issue 22, item 4; docs/modules/localization-estimation.md), or skipped.
  bool bearing_fallback = true;
  /// While the followed track is live, a person is given to it only if they look like the followed person as
  /// closely as the person's own frames have: their colour distance to the learnt colour within the running mean
  /// of the person's own distances plus this many standard deviations (one-sided: looking more alike is never
  /// refused). A look-alike beside a hidden person passes the colour gate (tracker.max_appearance_distance) and,
  /// in reach of the prediction, the motion gate; in the crowd in keypoint mode every identity switch left was one
  /// (0.11-0.23 against the person's own 0.05 +- 0.015). After a loss (re-identification) too, unless
  /// look_gate_after_loss is false. 0: off.
  double look_gate_sigmas = 3.0;
  /// ... unless the look gate alone has refused someone the followed track would have taken in every frame for
  /// this long, with distances that sat on the prediction as the person's own do (the mean Mahalanobis
  /// distance of the refused, 3 dof, within 3 + 3 sqrt(6 / n) over n frames): the person's own look has changed
  /// (a turn, the light, a partial view -- image mode), and a gate learnt only from the frames it lets through
  /// would otherwise shut the person out for good. A newcomer beside the hidden person sits off the prediction
  /// and drifts from it.
  double look_gate_confirm_s = 0.5;
  /// Whether the look gate also judges a lost followed track's re-identification (else only the colour gate does).
  /// A loss is often a turn or a long occlusion after which the person's look has changed by more than their own
  /// spread, while a look-alike still looks like the learnt colour: with the gate, the person was refused and the
  /// look-alike taken (traced: image-mode crowd seed 40 with refused_alone_frames, the person at d2 0.14 and colour
  /// 0.14 refused, the look-alike at d2 1.18 and 0.07 taken; seed 77, the person turned, 0.33). Without it, someone
  /// dressed otherwise is still refused by the colour gate, and the two are told apart by where they stand.
  bool look_gate_after_loss = true;
  /// Which detected person the estimator is given (issue 22 item 2; docs/modules/localization-estimation.md):
  /// true (`association: estimate`): once the filter has started, an assignment (global nearest neighbour) of
  /// the frame's people to the followed track and to tracks of the other people (bystander_tracks.hpp), each
  /// pair within the track's gate (the estimator's own test; lost, the prediction's grown covariance is the
  /// re-identification's reach) and colour gate, the cheapest distances first, then a bearing that no
  /// unexplained bystander track fits better; nobody left, nobody. Before the first measurement, the
  /// lock-on's choice. false (`association: lock_on`): always the lock-on's choice. Why: the lock-on judges in
  /// the image, where a bystander beside the target matches as well; in the world they stand apart.
  bool choose_by_estimate = true;
  /// With choose_by_estimate and depth_range: once the followed track's last this many accepted measurements
  /// were ranged by the depth camera as they were (the track's distance agrees with the depth camera's), a
  /// person whose depth range lies nearer than the track predicts by more than its gate allows along the line
  /// of sight is someone in front of the followed person, and is not given to the followed track. Without it the
  /// regression's distance of that person, which the gate still took, was given instead (the fallback for a
  /// track restarted with a wrong velocity, which this many agreeing ranges rule out): a crosser between the
  /// drone and the person was taken (image-mode crowd seeds 44 and 53, 0.9-1.1 m nearer). Someone so refused starts
  /// a bystander track: they are someone else, and compete on it for the frames after (crowd seed 40). 0: off.
  int in_front_after_ranged = 0;
  /// With in_front_after_ranged: an accepted measurement the depth camera did not see (out of its view, hidden, no
  /// surface) keeps the streak of ranged agreements instead of ending it. The streak rules out a track restarted
  /// with a wrong velocity; a measurement the depth camera could not judge says nothing of that, while ending the
  /// streak left the rule off whenever the person stepped out of the depth camera's narrower view: a look-alike
  /// ranged at d2 17.0 and 31.4 against the gate's 16.3 was taken with a streak of 0 and 1 (image-mode crowd seeds
  /// 77 and 117). A restart, a re-identification after a loss, a fallback to the regression and a range that
  /// disagreed still end it. false: every measurement not ranged ends it.
  bool in_front_streak_spans_unseen = false;
  /// With in_front_streak_spans_unseen: more than this many accepted measurements in a row that the depth camera
  /// did not see end the streak after all (0: no limit). Carried by the regression alone, the track's distance
  /// becomes the regression's, which reads a person of another build than its fit's short or long (the walking crowd
  /// 3-8 % near at the following distance): when the depth camera saw the person again they were ranged beyond the
  /// drifted track's bound and refused as someone else (traced, image-mode crowd seed 1: 8 frames unseen, the person
  /// 0.4-0.9 m farther, refused for 0.9 s while the drone stopped; in 12 traced failing seeds the rule refused the
  /// person in 107 frames, 70 of them after 3 or more unseen frames, and someone else in 30, 9 of them so). The
  /// streak that rebuilds it is in_front_after_ranged's, of ranges that agree with the track again.
  int in_front_unseen_limit = 0;
  /// With in_front_after_ranged: the bound on a ranged measurement's squared Mahalanobis distance above which the
  /// kGate test calls them someone else; 0: the estimator's gate_chi2. The ranged innovation's covariance is
  /// conservative (the prediction's, made for a turning person, plus the regression's height noise): the followed
  /// person's own ranged measurements with the rule armed lie at a median d2 of 0.30 and 99.9 % below 4.9 (27 410
  /// frames of traced image-mode crowd trials, docs/benchmarks.md), where a calibrated 3-dof one would lie at 2.4
  /// and 16.3. A look-alike at the person's side was ranged at 5.1-15.8 and taken (seeds 3, 29, 41, 46, 78, 80, 128).
  double in_front_gate_chi2 = 0.0;
  /// With in_front_gate_chi2 below the estimator's gate: whether someone that bound refuses while the gate would take
  /// them (d2 between the two) starts a bystander track when nobody else is given to the followed track. true: they
  /// do, as anyone refused in front. false: the frame is refused but no track is started, as they may be the followed
  /// person at the tail of their own spread: a track started on the person competed with the followed track for
  /// their next frames (image-mode Table I with the bound 5: 9 of the person's frames refused, every such flight's
  /// error grew, docs/benchmarks.md). Beyond the gate they start one either way.
  bool in_front_doubtful_starts_track = true;
  /// With in_front_after_ranged, whom the depth camera shows to be someone else (`in_front_test:`):
  ///  - kNearer: someone ranged nearer than the track predicts by more than the gate allows along the line of sight;
  ///  - kGate: someone whose ranged measurement the track's gate refuses, whichever way: nearer, farther (behind
  ///    the person and beside them in the image, where the depth camera sees past the person's body to theirs:
  ///    traced, image-mode crowd seed 3, ranged 0.32 m farther at d2 59 and given at the regression's distance), or
  ///    nearer and aside together (seed 41: d2 18.9, the regression's 12.8 taken; seed 46: 0.31 m nearer at d2
  ///    17.7, a look-alike who then took the track for 4.8 s). Its squared Mahalanobis distance is at least the
  ///    line of sight's part of it, so it refuses everyone kNearer does.
  enum class InFrontTest { kNearer, kGate };
  InFrontTest in_front_test = InFrontTest::kNearer;
  /// With choose_by_estimate: someone on a bystander track who stands between the camera and the followed
  /// person's prediction -- nearer along the line of sight by more than this, their centre within this of the line
  /// -- hides the person, and whoever fits that bystander's track is not given to the followed track (they are the
  /// one in front). The person's body and theirs, two body radii: nearer, they would overlap. Without it, a
  /// look-alike stepping between the drone and the person, alone in the crop, fit the coasting followed track's
  /// grown gate as well as their own young track (colour learnt from few frames) and was taken (traced: image-mode
  /// crowd seed 46, 0.6 m in front, d2 5.7 to the followed track, for 4.8 s). 0: off.
  double hidden_behind_m = 0.0;
  /// With depth_range: a bearing (bearing_fallback) whose line of sight the depth camera sees through where the
  /// followed track predicts the person -- free space up to a surface farther than max_ratio times the predicted
  /// range, or no surface within max_range_m, or a surface nearer than that range by the same factor (someone in
  /// front, whose keypoints the bearing is) -- is not the person, and is not given to the followed track. A bearing
  /// fits anyone on its line of sight at any range: a look-alike 1.3 m in front of the person, their torso cut off,
  /// was taken (traced: image-mode crowd seed 9, flown from the truth, depth 1.3 m against 2.4 m predicted), and a
  /// low-scored person 7 m behind (seed 100, closed loop: no surface within 8 m). false: off.
  bool depth_vets_bearings = false;
  /// A bearing (bearing_fallback) that no one else in the frame took goes to the followed track unless a bystander
  /// track nobody in the frame explains fits it better. true: better by its likelihood across its line of sight on the
  /// ground plane (TargetEstimator::fitAcrossLine: the squared distance plus the log of the innovation's variance
  /// there), for a track whose gate holds it; false: by the squared Mahalanobis distance alone.
  /// A bearing is placed at the followed track's predicted range and fits anyone on its line of sight; when that line
  /// passes near both the followed track's prediction and a bystander's, the distances alone favour the wider track --
  /// the followed track starved while the person is hidden, whose gate has grown (traced: image-mode crowd seed 19
  /// with the depth camera's people, a bystander in front of the hidden person, 4 degrees off their line of sight,
  /// taken at d2 0.00 while their own track's position lay 0.02 m from that line). The likelihood weighs in each
  /// track's spread: a young bystander track's wide gate does not take the person's own bearing either (measured: "any
  /// bystander track whose gate holds the bearing" refused the person's own bearings beside a one-frame track). Across
  /// the line only: in 3-D the depth camera's tracks, which carry no height, are unlikely for anyone (traced: seed 29,
  /// three bearings a depth-fed track fitted at d2 0.00-1.23 given to the followed track for its ln|S| 12-13 against
  /// 4), which lost seeds 3, 29 and 31 of the first 60.
  bool bearing_by_likelihood = false;
  /// With choose_by_estimate: someone with a distance whom the live followed track's gate refuses (beyond it, and on
  /// no bystander track) in this many detection frames in a row, each within a running person's reach of the one
  /// before, is someone else: a bystander track is started on them, counted as seen beside the followed person (it
  /// competes with a lost followed track's re-identification). Alone in the frame, a refused person was otherwise
  /// never tracked (they may be the person whom the gate lost), and when they then came into the gate -- the
  /// person hidden behind them -- nothing said they were someone else (traced: image-mode crowd seed 40, a
  /// look-alike refused 5 frames in a row at d2 60 down to 12 as they walked up to the standing person, then taken at
  /// d2 7.5; seed 73, refused 6 frames, then their bearing taken). One frame could be a jump of the person's own
  /// measurement; several in a row, each where the one before was, are someone walking. 0: off.
  int refused_alone_frames = 0;
  /// With choose_by_estimate: someone the look gate (look_gate_sigmas) refuses for the live followed track -- inside
  /// its gate and the colour gate -- who fits the followed track better (by d2) than every bystander track whose
  /// gates allow them is given to no bystander track in that frame, nor starts one: they may be the person, turned.
  /// Otherwise the assignment gave them to whichever bystander track's gate reached them: traced, image-mode crowd seed
  /// 66, the person refused by the look gate (colour 0.151, d2 1.33) took the look-alike's young track (d2 4.2),
  /// counted as seen beside the person, and the look-alike a new track never seen beside them -- which, the person
  /// hidden a second later and the followed track lost, did not compete, and the re-identification took the look-alike.
  bool look_refused_off_tracks = false;
  /// With choose_by_estimate: while the followed track is lost, a competing bystander track's colour term (the
  /// track of someone seen beside the person) is at most the candidate's colour distance to the person's, so that
  /// place, not colour, tells whether a look-alike is the person come back or the bystander they are. A track's
  /// colour is learnt from crowded crops and blended over frames; a look-alike's clean crop can lie nearer the
  /// person's colour than their own track's. Otherwise the lost track's wide gate won on colour what the bystander
  /// track won by place (traced: image-mode crowd seed 66, the lost track took the look-alike at d2 3.5 while the
  /// look-alike's own competing track, seen beside the person, fit them at d2 0.1).
  bool lost_competing_colour_capped = false;
  /// A second opinion on whom the followed track holds (`swap_check:`, swap_check.hpp; with choose_by_estimate):
  /// when its innovations run large the track as it was is kept aside, and it takes back its place if someone
  /// new fits it while the followed track's person does not. frames 0: off (the default here; config/sim.yaml and
  /// drone.yaml turn it on with the detector's crop at the prediction and in_front_after_ranged: alone it did not
  /// improve the image-mode crowd; together they halve the time on others over 70 trials, docs/benchmarks.md).
  SwapCheckParams swap_check{.frames = 0};
  /// Where a frame's verdict that took nobody says the live track predicts the person
  /// (DetectionFrame::predicted_torso): their torso centre this high above the ground (z = 0; the estimate's own z is
  /// the regression's ground-plane constant, as planning.person_sight_height_m says) and a torso this long (neck to
  /// mid-hip), to size the crop.
  double verdict_torso_height_m = 1.1;
  double verdict_torso_m = 0.5;
  /// The distance from the depth camera where it sees the person (`depth_range:`; absent: off).
  DepthRangeParams depth_range;
  /// With choose_by_estimate and the depth frames (rangeFrom): the people the depth camera sees keep the other people's
  /// tracks fed (`depth_people:`, depth_people.hpp; absent: off). Each depth frame up to a detection frame's capture
  /// time, once its pose is known, is segmented into people; they are assigned (global nearest neighbour, each pair
  /// within the track's gate) to the live followed track -- whose own measurements stay the detector's: the depth
  /// camera vouches for nobody -- and to the bystander tracks, which they update (their colour untouched); someone
  /// beyond the followed track's gate, while another person of the same depth frame went to it, starts a track, seen
  /// beside the followed person. While the followed track is lost, nobody starts one, and only the tracks of people
  /// seen beside it are updated (a person the depth camera places where nobody is tracked may be them). Why: the
  /// detector runs on a crop around the followed person, and a look-alike walking up to them, on no track of their
  /// own, was taken by the followed track once hidden and starved (docs/benchmarks.md).
  DepthPeopleParams depth_people;
  rt::DurationNs max_wait_ns = 200 * rt::kNsPerMillisecond;
};

/// The most other people tracked at once (choose_by_estimate): MoveNet reports six a frame.
inline constexpr std::size_t kMaxBystanderTracks = kMaxOtherPeople;

/// Reads the `estimation:` config section except `localization_params` (a file the app loads):
/// gimbal_camera extrinsics, measurement noise, estimator. Throws rt::ConfigError naming the key.
void parseTargetTaskParams(const rt::ConfigNode& node, TargetTaskParams& params);

struct TargetTaskStats {
  std::uint64_t detections = 0;            ///< Frames with the followed person.
  std::uint64_t unreliable = 0;            ///< ... whose torso was not reliable.
  std::uint64_t bearings = 0;              ///< ... of which the estimator used a bearing (bearing_fallback).
  std::uint64_t no_pose = 0;               ///< ... whose capture time the histories did not cover.
  std::uint64_t accepted = 0;              ///< Measurements the estimator used (or started from).
  std::uint64_t rejected = 0;              ///< Measurements the estimator refused.
  std::uint64_t reassigned = 0;            ///< Frames whose person the track's prediction chose over the lock-on's.
  std::uint64_t swapped_back = 0;          ///< Times the swap check gave the followed track back its kept hypothesis.
  std::uint64_t in_front = 0;              ///< Frames someone it would take was ranged in front of the followed person.
  std::uint64_t behind_bystander = 0;      ///< Frames someone it would take fit a bystander in front of the person.
  std::uint64_t seen_through = 0;          ///< Frames a bearing it would take was one the depth camera sees through.
  std::uint64_t refused_alone_tracks = 0;  ///< Tracks started on someone refused alone (refused_alone_frames).
  std::uint64_t look_refused_kept_off = 0;  ///< Frames someone the look gate refused was kept off tracks.
  std::uint64_t lost_colour_capped = 0;     ///< Frames a competing track's colour term was capped while lost.
  std::uint64_t depth_ranged = 0;           ///< ... of the followed person's frames, ranged by the depth camera.
  std::uint64_t depth_disagreed = 0;        ///< ... whose depth range the regression's disagreed with (not used).
  std::uint64_t depth_unseen = 0;           ///< ... for which no depth image near in time saw them (out of view).
  std::uint64_t scale_samples = 0;          ///< Frames the person's scale was learnt from (depth_range.scale_rate).
  std::uint64_t depth_frames_searched = 0;  ///< Depth frames searched for people (depth_people).
  std::uint64_t depth_people = 0;           ///< ... the people found in them...
  std::uint64_t depth_people_followed = 0;  ///< ... of whom the followed track's...
  std::uint64_t depth_people_fed = 0;       ///< ... (given to it: depth_people.feed_followed)...
  std::uint64_t depth_people_updates = 0;   ///< ... a bystander track's...
  std::uint64_t depth_people_tracks = 0;    ///< ... and tracks started on them.
  double range_scale = 1.0;                 ///< ... and the scale the regression's distances are multiplied by now.
};

class TargetTask final : public rt::Task {
 public:
  /// Errors if the histories or the estimator cannot be made from the params.
  static rt::Expected<TargetTask> create(const TargetTaskParams& params, rt::SpscQueue<hal::DetectionFrame>& detections,
                                         rt::SpscQueue<hal::OdometrySample>& odometry,
                                         rt::SpscQueue<hal::GimbalState>& gimbal, rt::LatestSlot<TargetEstimate>& out);

  void step(rt::TimeNs now_ns) override;
  const TargetTaskStats& stats() const { return stats_; }
  /// Each frame the estimator was given, its target_index set to the person it was given (-1: none): whom
  /// the pipeline follows (the simulator's identity metrics). Optional; the slot outlives the task.
  void publishFollowedTo(rt::LatestSlot<hal::DetectionFrame>& slot) { followed_out_ = &slot; }
  /// Depth frames (the mapper's channel) for the person's distance (TargetTaskParams::depth_range). Optional;
  /// the slot outlives the task.
  void rangeFrom(const rt::SharedSlot<hal::DepthFrame>& depth) { depth_in_ = &depth; }
  /// The person of the frame the estimator is given (see TargetTaskParams::choose_by_estimate), or -1.
  int choosePerson(const hal::DetectionFrame& frame) const;

 private:
  TargetTask(const TargetTaskParams& params, hal::OdometryHistory poses, GimbalAngleHistory gimbal_history,
             TargetEstimator estimator, BystanderTracks bystanders, SwapCheck swap_check,
             rt::SpscQueue<hal::DetectionFrame>& detections, rt::SpscQueue<hal::OdometrySample>& odometry,
             rt::SpscQueue<hal::GimbalState>& gimbal, rt::LatestSlot<TargetEstimate>& out);
  /// A detected person as the estimator would be given them.
  struct Candidate {
    perception::TorsoFeatures torso;
    perception::Appearance look;
    /// A distance (a reliable torso whose capture pose is known, or any torso the depth camera ranged) or a
    /// bearing (bearing_fallback, a live track); nothing otherwise.
    std::optional<TargetMeasurement> measurement;
    /// What the depth camera said of them (kFound and not used: the regression disagreed), when it was asked.
    std::optional<DepthRangeStatus> depth;
    bool depth_disagreed = false;
    /// A ranged measurement's regression-only form: who a person is (the association's gates) is judged
    /// on it, so the depth camera changes how well the followed person is placed, never who is followed.
    std::optional<TargetMeasurement> unranged;
    const TargetMeasurement& judged() const { return unranged ? *unranged : *measurement; }
    /// The regression's own horizontal range, before the person's scale (depth_range.scale_rate); 0: none.
    double regression_range_m = 0.0;
    /// The depth camera's horizontal range of them (measurement ranged); 0: none.
    double depth_range_m = 0.0;
    /// The regression's measurement at its fit's own scale, where the person's scale changed it: the scale is the
    /// followed person's, and whether someone is a bystander is judged, and their track kept, without it.
    std::optional<TargetMeasurement> unscaled;
    /// The measurement as a bystander track's gate judges it.
    const TargetMeasurement& judgedAsOther() const { return unscaled ? *unscaled : judged(); }
    /// ... and as their track is given it: a depth range as it is (the depth camera's, whoever they are).
    const TargetMeasurement& givenAsOther() const {
      return measurement->ranged || !unscaled ? *measurement : *unscaled;
    }
  };
  /// Person `index` of the frame, its torso measured in the level camera's image of the camera at T_WC
  /// (the capture time's pose; unknown: no measurement).
  Candidate candidate(const hal::DetectionFrame& frame, int index, const std::optional<Eigen::Isometry3d>& T_WC) const;
  static constexpr int kNoTrack = -1;
  static constexpr int kNewTrack = -2;
  struct Association {
    int followed = -1;                          ///< The person given to the estimator, or -1.
    std::array<int, hal::kMaxPersons> track{};  ///< Each person's bystander track, kNoTrack or kNewTrack.
    bool look_refused = false;                  ///< Someone fit the followed track but for the look gate...
    double look_refused_d2 = std::numeric_limits<double>::infinity();  ///< ... the nearest such distance's d2.
    bool in_front = false;  ///< Someone its gate took was ranged in front of the person (in_front_after_ranged).
    bool behind_bystander = false;  ///< Someone its gate took fit a bystander in front of the person (hidden_behind_m).
    bool seen_through = false;      ///< A bearing its gate took was seen through by the depth camera.
    /// Each person with a distance the live followed track's gate refused and nobody took (refused_alone_frames).
    std::array<bool, hal::kMaxPersons> refused_alone{};
    bool look_refused_kept_off = false;  ///< Someone the look gate refused kept off tracks (look_refused_off_tracks).
    bool lost_colour_capped = false;     ///< A competing track's colour term was capped (lost_competing_colour_capped).
  };
  /// Whom the frame's people are (see choose_by_estimate), filling the candidates it judged (choosing by the
  /// estimate: everyone's; else the lock-on's choice's).
  Association associate(const hal::DetectionFrame& frame, std::array<Candidate, hal::kMaxPersons>& candidates) const;
  /// Whether the candidate's depth range puts them in front of the followed person (in_front_after_ranged), and
  /// whether only in_front_gate_chi2 does (their d2 inside the estimator's gate: doubtful).
  enum class InFront { kNo, kDoubtful, kBeyondGate };
  InFront inFrontOfTheFollowed(const Candidate& c, const TargetEstimate& prior) const;
  /// Whether `person` fits (an allowed pair in `costs`) a bystander track standing in front of the followed
  /// person's prediction, seen from the camera at p_WC_m (hidden_behind_m).
  bool hiddenBehindABystander(int person, const AssignmentCosts& costs, const TargetEstimate& prior,
                              const Eigen::Vector3d& p_WC_m, rt::TimeNs t_ns) const;
  /// The swap check's evidence in this frame (SwapCheck); true while its kept hypothesis is open and the followed
  /// track holds someone it does not explain (the verdict then asks the detector for the whole frame). If confirmed,
  /// the followed track becomes the kept one and `a` is rewritten (its person the one who fit the kept track, whom the
  /// followed track held a new bystander).
  bool checkSwap(const hal::DetectionFrame& frame, const std::array<Candidate, hal::kMaxPersons>& candidates,
                 Association& a);
  /// Feeds the bystander tracks from the depth frames taken after the last ones searched, up to t_ns (depth_people).
  void trackDepthPeople(rt::TimeNs t_ns);
  /// Gives the candidate to the estimator; true if it took a distance.
  bool process(const Candidate& candidate);
  /// The person's position in W from their (levelled) torso: the regression, read in the level camera frame
  /// of the camera at T_WC; and the camera-frame point.
  Eigen::Vector3d localize(const perception::TorsoFeatures& torso, const Eigen::Isometry3d& T_WC,
                           Eigen::Vector3d& p_C_m) const;
  /// Learns the person's scale from a frame the followed track took and the depth camera ranged
  /// (depth_range.scale_rate).
  void learnScale(const Candidate& c);
  double measurementStdM(const Eigen::Vector3d& p_C_m) const;
  /// Where the live track predicts the person's torso in the frame's image (nothing: lost, no pose, out of view).
  hal::DetectionFrame::PredictedTorso predictedTorso(const hal::DetectionFrame& frame) const;
  /// c's measurement ranged along the line of sight through `pixel` (the photo's) by the depth image nearest the
  /// frame's time, if one sees the person where the regression (or the prior, for a bearing) roughly does; c learns
  /// what the depth camera said. Only a measurement the live followed track's gate takes is ranged.
  void rangeByDepth(const hal::DetectionFrame& frame, const Eigen::Vector2d& pixel, const Eigen::Isometry3d& T_WC,
                    Candidate& c) const;
  /// Whether `person`, at followed_d2 from the followed track's prediction, fits it at least as well as every
  /// bystander track whose pair `costs` allows (look_refused_off_tracks).
  bool fitsFollowedBest(int person, double followed_d2, const TargetMeasurement& judged,
                        const AssignmentCosts& costs) const;
  /// The bearing-only measurement of an unreliable torso, or nothing (no live track, no pose, the person
  /// behind or beside the camera).
  std::optional<TargetMeasurement> bearingMeasurement(const hal::DetectionFrame& frame,
                                                      const perception::TorsoFeatures& torso,
                                                      const Eigen::Isometry3d& T_WC) const;

  TargetTaskParams params_;
  hal::OdometryHistory poses_;
  GimbalAngleHistory gimbal_history_;
  TargetEstimator estimator_;
  rt::SpscQueue<hal::DetectionFrame>& detections_;
  rt::SpscQueue<hal::OdometrySample>& odometry_;
  rt::SpscQueue<hal::GimbalState>& gimbal_;
  rt::LatestSlot<TargetEstimate>& out_;
  std::array<hal::DetectionFrame, 8> pending_{};  ///< Waiting for the histories, oldest first.
  std::size_t pending_count_ = 0;
  rt::TimeNs newest_pose_ns_ = -1;
  rt::TimeNs newest_gimbal_ns_ = -1;
  rt::TimeNs notified_accepted_ns_ = -1;  ///< last_accepted_ns of the last estimate that woke its readers
  bool notified_lost_ = true;
  TargetTaskStats stats_;
  rt::LatestSlot<hal::DetectionFrame>* followed_out_ = nullptr;
  perception::Appearance reference_;
  /// The followed person's own colour distances to reference_ (taken distances): running mean and mean square.
  double own_look_mean_ = 0.0, own_look_mean_sq_ = 0.0;
  int own_look_count_ = 0;
  /// Someone refused alone in the frames before (refused_alone_frames): how many frames in a row, and the newest one's
  /// measurement.
  int refused_alone_streak_ = 0;
  TargetMeasurement refused_alone_last_;
  /// Starts a bystander track on whom the association refused alone for the refused_alone_frames-th frame in a row.
  void trackTheRefusedAlone(const std::array<Candidate, hal::kMaxPersons>& candidates, Association& a);
  /// Whether measurement m can be the same person as `before`: no farther than a running person goes in the time
  /// between, plus three standard deviations of the two measurements' difference.
  bool withinReach(const TargetMeasurement& m, const TargetMeasurement& before) const;
  int ranged_streak_ = 0;  ///< The followed track's last accepted measurements in a row that were ranged as they were.
  int unseen_run_ = 0;     ///< ... and those since the last of them that the depth camera did not see.
  double log_range_scale_ = 0.0;  ///< The person's scale (depth_range.scale_rate), in log; stats_ holds the count.
  /// Whether a colour is as near the learnt one as the followed person's own frames are (look_gate_sigmas).
  bool looksLikeTheFollowed(const perception::Appearance& look, rt::TimeNs stamp_ns) const;
  rt::TimeNs look_refused_since_ns_ = -1;  ///< First frame of the look gate's current run of refusals; -1: none.
  double look_refused_d2_sum_ = 0.0;       ///< Over the run's frames with a refused distance...
  int look_refused_d2_count_ = 0;          ///< ... and their number.
  BystanderTracks bystanders_;             ///< The torso colour of the people given to the estimator and taken.
  SwapCheck swap_check_;
  const rt::SharedSlot<hal::DepthFrame>* depth_in_ = nullptr;
  std::uint64_t depth_version_ = 0;
  /// The newest depth frames, oldest first (a detection arrives ~50 ms after its photo: older frames are needed).
  std::array<hal::DepthFrameHandle, 8> depth_frames_{};
  std::size_t depth_count_ = 0;
  DepthPeopleFinder depth_people_;
  rt::TimeNs depth_people_done_ns_ = -1;  ///< Depth frames up to this capture time were searched (or skipped).
};

}  // namespace aerotrack::estimation
