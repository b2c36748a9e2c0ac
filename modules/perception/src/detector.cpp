// The detector and its tracking loop: see detector.hpp.
#include "aerotrack/perception/detector.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace aerotrack::perception {

namespace {

std::size_t modelIndex(const std::string& name) {
  const auto& names = knownModelNames();
  return static_cast<std::size_t>(std::find(names.begin(), names.end(), name) - names.begin());
}

void clipBox(hal::PersonDetection& p, double u0, double v0, double u1, double v1, int width_px, int height_px) {
  u0 = std::clamp(u0, 0.0, static_cast<double>(width_px));
  u1 = std::clamp(u1, 0.0, static_cast<double>(width_px));
  v0 = std::clamp(v0, 0.0, static_cast<double>(height_px));
  v1 = std::clamp(v1, 0.0, static_cast<double>(height_px));
  p.bbox_u_px = u0;
  p.bbox_v_px = v0;
  p.bbox_w_px = std::max(0.0, u1 - u0);
  p.bbox_h_px = std::max(0.0, v1 - v0);
}

void mapKeypoints(const NormalisedPose& pose, const InputTransform& t, hal::PersonDetection& p) {
  const double s = t.input_size_px;
  for (std::size_t k = 0; k < hal::kNumKeypoints; ++k) {
    p.keypoints[k].u_px = t.toImageU(static_cast<double>(pose[k].x) * s);
    p.keypoints[k].v_px = t.toImageV(static_cast<double>(pose[k].y) * s);
    p.keypoints[k].score = static_cast<double>(pose[k].score);
  }
}

}  // namespace

rt::Status validate(const DetectorParams& p) {
  if (modelIndex(p.tracking_model) >= 2)
    return rt::Error{"tracking_model: expected lightning or thunder (a singlepose model), got '" + p.tracking_model +
                     "'"};
  if (modelIndex(p.search_model) >= knownModelNames().size())
    return rt::Error{"search_model: expected multipose, lightning or thunder, got '" + p.search_model + "'"};
  if (auto s = validate(p.dnn); !s) return rt::Error{"dnn." + s.error().message};
  if (!(p.min_person_score >= 0.0 && p.min_person_score <= 1.0))
    return rt::Error{"min_person_score: must be in [0, 1]"};
  if (!(p.min_multipose_score >= 0.0 && p.min_multipose_score <= 1.0))
    return rt::Error{"min_multipose_score: must be in [0, 1]"};
  if (!(p.bbox_min_keypoint_score >= 0.0 && p.bbox_min_keypoint_score <= 1.0))
    return rt::Error{"bbox_min_keypoint_score: must be in [0, 1]"};
  if (!(p.bbox_margin_fraction >= 0.0 && p.bbox_margin_fraction <= 1.0))
    return rt::Error{"bbox_margin_fraction: must be in [0, 1]"};
  if (!(p.crop.min_score >= 0.0 && p.crop.min_score <= 1.0)) return rt::Error{"crop.min_score: must be in [0, 1]"};
  if (!(p.crop.torso_factor > 0.0 && p.crop.body_factor > 0.0)) return rt::Error{"crop: factors must be > 0"};
  if (!(p.whole_frame.near_crop_sides <= 10.0)) return rt::Error{"whole_frame.near_crop_sides: must be <= 10"};
  if (!(p.whole_frame.every_s >= 0.0 && p.whole_frame.every_s <= 3600.0))
    return rt::Error{"whole_frame.every_s: must be in [0, 3600]"};
  if (!(p.whole_frame.beside_crop_every_s >= 0.0 && p.whole_frame.beside_crop_every_s <= 3600.0))
    return rt::Error{"whole_frame.beside_crop_every_s: must be in [0, 3600]"};
  if (!(p.crop.min_side_fraction > 0.0 && p.crop.min_side_fraction <= 1.0))
    return rt::Error{"crop.min_side_fraction: must be in (0, 1]"};
  if (!(p.torso.min_joint_score >= 0.0 && p.torso.min_joint_score <= 1.0))
    return rt::Error{"torso.min_joint_score: must be in [0, 1]"};
  if (!(p.torso.border_margin_px >= 0.0)) return rt::Error{"torso.border_margin_px: must be >= 0"};
  if (!(p.torso.edge_margin_torso_fraction >= 0.0 && p.torso.edge_margin_torso_fraction <= 2.0))
    return rt::Error{"torso.edge_margin_torso_fraction: must be in [0, 2]"};
  if (!(p.torso.edge_guess_max_score >= 0.0 && p.torso.edge_guess_max_score <= 1.0))
    return rt::Error{"torso.edge_guess_max_score: must be in [0, 1]"};
  if (auto s = validate(p.tracker); !s) return rt::Error{"tracker." + s.error().message};
  return rt::ok();
}

hal::PersonDetection singlePoseToImage(const NormalisedPose& pose, const InputTransform& transform, int width_px,
                                       int height_px, double bbox_min_keypoint_score, double bbox_margin_fraction) {
  hal::PersonDetection p;
  mapKeypoints(pose, transform, p);
  double score_sum = 0.0;
  double u0 = 1e300, v0 = 1e300, u1 = -1e300, v1 = -1e300;
  for (const hal::Keypoint2D& k : p.keypoints) {
    score_sum += k.score;
    if (k.score < bbox_min_keypoint_score) continue;
    u0 = std::min(u0, k.u_px);
    u1 = std::max(u1, k.u_px);
    v0 = std::min(v0, k.v_px);
    v1 = std::max(v1, k.v_px);
  }
  p.score = score_sum / static_cast<double>(hal::kNumKeypoints);
  if (u1 >= u0) {
    const double margin = bbox_margin_fraction * std::max(u1 - u0, v1 - v0);
    clipBox(p, u0 - margin, v0 - margin, u1 + margin, v1 + margin, width_px, height_px);
  }
  return p;
}

hal::PersonDetection multiPoseToImage(const MultiPoseInstance& instance, const InputTransform& transform, int width_px,
                                      int height_px) {
  hal::PersonDetection p;
  mapKeypoints(instance.keypoints, transform, p);
  p.score = static_cast<double>(instance.score);
  const double s = transform.input_size_px;
  clipBox(p, transform.toImageU(static_cast<double>(instance.box_xmin) * s),
          transform.toImageV(static_cast<double>(instance.box_ymin) * s),
          transform.toImageU(static_cast<double>(instance.box_xmax) * s),
          transform.toImageV(static_cast<double>(instance.box_ymax) * s), width_px, height_px);
  return p;
}

rt::Expected<Detector> Detector::create(const DetectorParams& params) {
  if (auto s = validate(params); !s) return s.error();
  Detector detector(params);
  for (const std::string& name : {params.tracking_model, params.search_model})
    if (auto m = detector.model(name); !m) return m.error();
  return detector;
}

rt::Expected<MoveNetModel*> Detector::model(const std::string& name) {
  const std::size_t i = modelIndex(name);
  if (i >= models_.size()) return rt::Error{"unknown model '" + name + "' (known: lightning, thunder, multipose)"};
  if (!models_[i]) {
    auto loaded = MoveNetModel::load(params_.model_dir, name, params_.dnn);
    if (!loaded) return loaded.error();
    models_[i].emplace(std::move(loaded.value()));
    blobs_[i] = makeInputBlob(models_[i]->info().input_size_px);
  }
  return &*models_[i];
}

rt::Expected<DetectorOutput> Detector::runModel(MoveNetModel& model, const cv::Mat& bgr,
                                                const InputTransform& transform) {
  cv::Mat& blob = blobs_[modelIndex(model.info().name)];
  fillInputBlob(bgr, transform, scratch_, blob);
  if (auto s = model.run(blob); !s) return s.error();

  DetectorOutput out;
  out.model = knownModelNames()[modelIndex(model.info().name)].c_str();
  const double min_score =
      model.info().kind == ModelKind::kSinglePose ? params_.min_person_score : params_.min_multipose_score;
  const auto add = [&](const hal::PersonDetection& person) {
    if (person.score < min_score || out.count >= out.persons.size()) return;
    DetectedPerson& d = out.persons[out.count++];
    d.detection = person;
    d.torso = torsoFeatures(person.keypoints, bgr.cols, bgr.rows, params_.torso);
    d.appearance = personAppearance(bgr, person.keypoints);
  };
  if (model.info().kind == ModelKind::kSinglePose) {
    const SinglePoseHeads heads = model.singlePoseHeads();
    if (!shapesValid(heads)) return rt::Error{model.info().name + ": heads do not match the decoder"};
    add(singlePoseToImage(decodeSinglePose(heads, model.info().constants), transform, bgr.cols, bgr.rows,
                          params_.bbox_min_keypoint_score, params_.bbox_margin_fraction));
  } else {
    const MultiPoseHeads heads = model.multiPoseHeads();
    if (!shapesValid(heads)) return rt::Error{model.info().name + ": heads do not match the decoder"};
    const MultiPoseResult result = decodeMultiPose(heads, model.info().constants);
    for (const MultiPoseInstance& instance : result.instances)
      add(multiPoseToImage(instance, transform, bgr.cols, bgr.rows));
  }
  return out;
}

rt::Expected<DetectorOutput> Detector::detectFrame(const cv::Mat& bgr, const std::string& model_name) {
  if (bgr.empty() || bgr.type() != CV_8UC3) return rt::Error{"expected a non-empty 8-bit BGR image"};
  auto m = model(model_name);
  if (!m) return m.error();
  return runModel(**m, bgr, letterbox(bgr.cols, bgr.rows, (*m)->info().input_size_px));
}

const char* toString(WholeFrameReason reason) {
  switch (reason) {
    case WholeFrameReason::kNone:
      return "crop";
    case WholeFrameReason::kNoLock:
      return "no_lock";
    case WholeFrameReason::kCropLost:
      return "crop_lost";
    case WholeFrameReason::kOthersNear:
      return "others_near";
    case WholeFrameReason::kRefused:
      return "refused";
    case WholeFrameReason::kPeriodic:
      return "periodic";
    case WholeFrameReason::kWanted:
      return "wanted";
  }
  return "?";
}

std::size_t addOthersBesideCrop(DetectorOutput& crop, const DetectorOutput& whole, double min_keypoint_score,
                                double same_fraction) {
  // How far apart two detections lie, in units of the taller one's box: the mean distance of the joints both are sure
  // of, or, with fewer than three such joints, 0 for boxes overlapping by more than half of the smaller one's area.
  const auto apart = [&](const hal::PersonDetection& a, const hal::PersonDetection& b) {
    double sum_px = 0.0;
    int common = 0;
    for (std::size_t k = 0; k < hal::kNumKeypoints; ++k) {
      const hal::Keypoint2D& ka = a.keypoints[k];
      const hal::Keypoint2D& kb = b.keypoints[k];
      if (!(ka.score >= min_keypoint_score && kb.score >= min_keypoint_score)) continue;
      sum_px += std::hypot(ka.u_px - kb.u_px, ka.v_px - kb.v_px);
      ++common;
    }
    constexpr int kMinCommonJoints = 3;
    if (common >= kMinCommonJoints) return sum_px / common / std::max({a.bbox_h_px, b.bbox_h_px, 1.0});
    const double du =
        std::min(a.bbox_u_px + a.bbox_w_px, b.bbox_u_px + b.bbox_w_px) - std::max(a.bbox_u_px, b.bbox_u_px);
    const double dv =
        std::min(a.bbox_v_px + a.bbox_h_px, b.bbox_v_px + b.bbox_h_px) - std::max(a.bbox_v_px, b.bbox_v_px);
    const double smaller = std::min(a.bbox_w_px * a.bbox_h_px, b.bbox_w_px * b.bbox_h_px);
    const bool overlapping = du > 0.0 && dv > 0.0 && smaller > 0.0 && du * dv > 0.5 * smaller;
    return overlapping ? 0.0 : std::numeric_limits<double>::infinity();
  };
  // Each of the crop's people is at most one of the whole frame's: the nearest, if near enough. The coarser whole frame
  // places a small pedestrian's joints up to a fifth of their height off the crop's (vtest.avi); a neighbour beside
  // them, found in the whole frame too, is not their nearest and stays.
  std::array<bool, hal::kMaxPersons> duplicate{};
  const std::size_t whole_count = std::min(whole.count, hal::kMaxPersons);
  for (std::size_t c = 0; c < std::min(crop.count, hal::kMaxPersons); ++c) {
    double nearest = std::numeric_limits<double>::infinity();
    std::size_t nearest_w = whole_count;
    for (std::size_t w = 0; w < whole_count; ++w) {
      const double d = duplicate[w] ? std::numeric_limits<double>::infinity()
                                    : apart(crop.persons[c].detection, whole.persons[w].detection);
      if (d < nearest) {
        nearest = d;
        nearest_w = w;
      }
    }
    if (nearest_w < whole_count && nearest <= same_fraction) duplicate[nearest_w] = true;
  }
  std::size_t added = 0;
  for (std::size_t w = 0; w < whole_count && crop.count < hal::kMaxPersons; ++w) {
    if (duplicate[w]) continue;
    crop.persons[crop.count++] = whole.persons[w];
    ++added;
  }
  return added;
}

bool someoneNearRegion(std::span<const hal::PersonDetection> persons, std::size_t target, const InputTransform& region,
                       double margin_sides) {
  if (margin_sides < 0.0) return false;
  const double grow_px = margin_sides * region.region_side_px;
  const double u0 = region.region_u0_px - grow_px;
  const double v0 = region.region_v0_px - grow_px;
  const double u1 = region.region_u0_px + region.region_side_px + grow_px;
  const double v1 = region.region_v0_px + region.region_side_px + grow_px;
  for (std::size_t i = 0; i < persons.size(); ++i) {
    const hal::PersonDetection& p = persons[i];
    if (i == target || !(p.bbox_w_px > 0.0 && p.bbox_h_px > 0.0)) continue;
    if (p.bbox_u_px < u1 && p.bbox_u_px + p.bbox_w_px > u0 && p.bbox_v_px < v1 && p.bbox_v_px + p.bbox_h_px > v0)
      return true;
  }
  return false;
}

void Detector::judged(const hal::DetectionFrame& verdict) {
  if (verdict.stamp_ns <= newest_verdict_ns_) return;
  const auto mine =
      std::find_if(recent_.begin(), recent_.end(), [&](const Choice& c) { return c.stamp_ns == verdict.stamp_ns; });
  if (mine == recent_.end()) return;  // not a frame of ours, or too old to matter
  newest_verdict_ns_ = verdict.stamp_ns;
  wanted_ = verdict.whole_frame_wanted;
  const int count = static_cast<int>(std::min(verdict.person_count, hal::kMaxPersons));
  const int taken = verdict.target_index >= 0 && verdict.target_index < count ? verdict.target_index : -1;
  const hal::DetectionFrame::PredictedTorso& predicted = verdict.predicted_torso;
  const bool prediction = predicted.torso_px > 0.0 && std::isfinite(predicted.torso_px) &&
                          std::isfinite(predicted.u_px) && std::isfinite(predicted.v_px);
  estimator_live_ = taken >= 0 || prediction;
  if (taken < 0 && prediction) {
    // The estimator took nobody and its live track says where the person should be: the next crop looks there.
    // The lock-on's crop may sit on whom the estimator refused, a look-alike beside the person (crowd seed 24).
    lookAt(verdict.stamp_ns, predicted);
    return;
  }
  if (taken == mine->person) {
    refused_ = false;
    return;
  }
  if (taken < 0) {  // the lock-on's choice was not the person, or not one the estimator could place
    refused_ = true;
    return;
  }
  // The estimator took someone else: continue from them. The frame a lock-on disagreed on is usually a whole-frame
  // one, which shows who is near them; with whole_frame.on_crop_lost false it may be a crop the lock-on chose nobody
  // in, whose one person is then all there is to look at.
  const auto& keypoints = verdict.persons[static_cast<std::size_t>(taken)].keypoints;
  tracker_.reseat(verdict.stamp_ns, torsoFeatures(keypoints, width_px_, height_px_, params_.torso));
  last_target_keypoints_ = keypoints;
  refused_ = false;
  ++counts_.reseated;
  InputTransform crop;  // its region does not depend on the network's input size
  if (cropAroundPerson(keypoints, width_px_, height_px_, /*input_size_px=*/1, params_.crop, crop))
    others_near_ = someoneNearRegion(std::span(verdict.persons.data(), static_cast<std::size_t>(count)),
                                     static_cast<std::size_t>(taken), crop, params_.whole_frame.near_crop_sides);
}

void Detector::lookAt(rt::TimeNs stamp_ns, const hal::DetectionFrame::PredictedTorso& torso) {
  // A torso of the predicted centre and length, upright, its shoulders 0.7 torso lengths apart (a crop's size
  // only): the crop is cut around it as around a detected person's joints, and the lock-on goes on from it.
  std::array<hal::Keypoint2D, hal::kNumKeypoints> keypoints{};  // scores 0: nothing but the torso is known
  const double half_width_px = 0.35 * torso.torso_px;
  const double half_length_px = 0.5 * torso.torso_px;
  const auto place = [&](hal::CocoKeypoint k, double du_px, double dv_px) {
    keypoints[hal::index(k)] = {torso.u_px + du_px, torso.v_px + dv_px, 1.0};
  };
  place(hal::CocoKeypoint::kLeftShoulder, half_width_px, -half_length_px);
  place(hal::CocoKeypoint::kRightShoulder, -half_width_px, -half_length_px);
  place(hal::CocoKeypoint::kLeftHip, half_width_px, half_length_px);
  place(hal::CocoKeypoint::kRightHip, -half_width_px, half_length_px);
  TorsoFeatures predicted;
  predicted.u_px = torso.u_px;
  predicted.v_px = torso.v_px;
  predicted.torso_px = torso.torso_px;
  tracker_.reseat(stamp_ns, predicted);
  last_target_keypoints_ = keypoints;
  refused_ = false;
  others_near_ = false;
  ++counts_.to_prediction;
}

rt::Expected<DetectorOutput> Detector::track(const cv::Mat& bgr, rt::TimeNs stamp_ns,
                                             const std::optional<ImagePrediction>& external) {
  if (bgr.empty() || bgr.type() != CV_8UC3) return rt::Error{"expected a non-empty 8-bit BGR image"};
  width_px_ = bgr.cols;
  height_px_ = bgr.rows;
  std::array<TrackCandidate, hal::kMaxPersons> candidates{};
  const auto choose = [&](DetectorOutput& out) {
    for (std::size_t i = 0; i < out.count; ++i)
      candidates[i] = {out.persons[i].torso, out.persons[i].appearance, out.persons[i].detection.score};
    out.target = tracker_.update(stamp_ns, std::span(candidates.data(), out.count), external);
    if (out.target) last_target_keypoints_ = out.persons[*out.target].detection.keypoints;
  };
  const auto remember = [&](const DetectorOutput& out) {
    recent_[recent_next_] = {stamp_ns, out.target ? static_cast<int>(*out.target) : -1};
    recent_next_ = (recent_next_ + 1) % recent_.size();
  };

  auto tracking_model = model(params_.tracking_model);
  if (!tracking_model) return tracking_model.error();
  MoveNetModel* tracking = tracking_model.value();
  const WholeFrameParams& whole = params_.whole_frame;
  WholeFrameReason reason = WholeFrameReason::kNone;
  if (!tracker_.locked(stamp_ns) || !last_target_keypoints_)
    reason = WholeFrameReason::kNoLock;
  else if (refused_)
    reason = WholeFrameReason::kRefused;
  else if (wanted_)
    reason = WholeFrameReason::kWanted;
  else if (others_near_)
    reason = WholeFrameReason::kOthersNear;
  else if (whole.every_s > 0.0 && stamp_ns - last_whole_ns_ >= rt::secondsToNs(whole.every_s))
    reason = WholeFrameReason::kPeriodic;

  // Locked, alone: singlepose on the crop around the last keypoints.
  InputTransform crop;
  if (reason == WholeFrameReason::kNone) {
    if (cropAroundPerson(*last_target_keypoints_, bgr.cols, bgr.rows, tracking->info().input_size_px, params_.crop,
                         crop)) {
      auto out = runModel(*tracking, bgr, crop);
      if (!out) return out.error();
      out->cropped = true;
      choose(*out);
      // Verdicts come only with follow_estimator (the app hands them over): the estimator judges the crop.
      const bool judged_by_estimator = !params_.whole_frame.on_crop_lost && estimator_live_;
      if (out->target || judged_by_estimator) {
        ++counts_.runs[static_cast<std::size_t>(WholeFrameReason::kNone)];
        if (whole.beside_crop_every_s > 0.0 &&
            stamp_ns - last_whole_ns_ >= rt::secondsToNs(whole.beside_crop_every_s)) {
          // Everyone in view, beside the crop's measurement of the person (WholeFrameParams::beside_crop_every_s).
          auto all = detectFrame(bgr, params_.search_model);
          if (!all) return all.error();
          counts_.beside_crop_added += addOthersBesideCrop(*out, *all, params_.bbox_min_keypoint_score);
          ++counts_.beside_crop;
          last_whole_ns_ = stamp_ns;
        }
        remember(*out);
        return out;
      }
    }
    reason = WholeFrameReason::kCropLost;
  }

  // Otherwise the whole frame, and the lock-on picks the person among everyone in it.
  auto search_model = model(params_.search_model);
  if (!search_model) return search_model.error();
  MoveNetModel* search = search_model.value();
  auto out = runModel(*search, bgr, letterbox(bgr.cols, bgr.rows, search->info().input_size_px));
  if (!out) return out.error();
  choose(*out);
  ++counts_.runs[static_cast<std::size_t>(reason)];
  last_whole_ns_ = stamp_ns;
  refused_ = false;
  wanted_ = false;
  others_near_ = false;
  if (out->target && cropAroundPerson(out->persons[*out->target].detection.keypoints, bgr.cols, bgr.rows,
                                      tracking->info().input_size_px, params_.crop, crop)) {
    std::array<hal::PersonDetection, hal::kMaxPersons> people{};
    for (std::size_t i = 0; i < out->count; ++i) people[i] = out->persons[i].detection;
    others_near_ = someoneNearRegion(std::span(people.data(), out->count), *out->target, crop, whole.near_crop_sides);
  }
  remember(*out);
  return out;
}

}  // namespace aerotrack::perception
