// `aerotrack dataset --out FILE.csv [--samples N] [--seed N] [--scenario NAME|FILE] [--camera keypoints|image]`:
// a calibration dataset for the localization regression (issue 6; DESIGN.md's CSV
// `torso_px,u_px,x_m,y_m`), written from the simulator, which knows where the person really is.
// Each sample is a random view of the scenario's walking person (hal/sim/calibration_views.hpp)
// at 1.5-9 m: with the keypoint camera model (MoveNet-like noise and misses), or with a rendered
// image run through the real detector (--camera image), then the torso features of the detection
// (modules/perception); views whose torso is not reliable are skipped, as the tracker would skip
// them. The truth is the person's ground point in the camera's forward-left-up frame.
#include <cstdio>
#include <random>

#include "aerotrack/hal/sim/calibration_views.hpp"
#include "aerotrack/hal/sim/keypoint_camera.hpp"
#include "aerotrack/hal/sim/scene_renderer.hpp"
#include "aerotrack/localization/localization_io.hpp"
#include "aerotrack/perception/detector.hpp"
#include "commands.hpp"
#include "paths.hpp"
#include "sim_report.hpp"

namespace aerotrack::app {
namespace {

/// What the camera reports of one view: the detection, or nothing.
class ViewObserver {
 public:
  virtual ~ViewObserver() = default;
  virtual rt::Expected<std::optional<hal::PersonDetection>> observe(const hal::sim::CalibrationView& view,
                                                                    std::mt19937_64& rng) = 0;
};

/// The simulator's keypoint camera model.
class KeypointObserver final : public ViewObserver {
 public:
  explicit KeypointObserver(const hal::sim::KeypointCameraParams& camera) : camera_(camera) {}
  rt::Expected<std::optional<hal::PersonDetection>> observe(const hal::sim::CalibrationView& view,
                                                            std::mt19937_64& rng) override {
    return hal::sim::observe(view.person.keypoints_W_m, view.T_WC, camera_, {}, rng);
  }

 private:
  hal::sim::KeypointCameraParams camera_;
};

/// A rendered image of one of the cast's people through the real detector (the most confident person).
class ImageObserver final : public ViewObserver {
 public:
  ImageObserver(hal::sim::SceneRenderer renderer, hal::sim::ObstacleWorld world, perception::Detector detector)
      : renderer_(std::move(renderer)), world_(std::move(world)), detector_(std::move(detector)) {}
  rt::Expected<std::optional<hal::PersonDetection>> observe(const hal::sim::CalibrationView& view,
                                                            std::mt19937_64& rng) override {
    // Each view shows one person of the cast, drawn at random: the fit sees every look.
    const std::size_t who = static_cast<std::size_t>(rng() % renderer_.castSize());
    renderer_.render(world_, view.T_WC, &view.person, image_, scratch_, who);
    auto out = detector_.detectFrame(image_, detector_.params().tracking_model);
    if (!out) return out.error();
    if (out->count == 0) return std::optional<hal::PersonDetection>();
    std::size_t best = 0;
    for (std::size_t i = 1; i < out->count; ++i)
      if (out->persons[i].detection.score > out->persons[best].detection.score) best = i;
    return std::optional<hal::PersonDetection>(out->persons[best].detection);
  }

 private:
  hal::sim::SceneRenderer renderer_;
  hal::sim::ObstacleWorld world_;
  perception::Detector detector_;
  cv::Mat image_;
  hal::sim::RenderScratch scratch_;
};

}  // namespace

int datasetCommand(const ParsedArgs& args) {
  const auto samples = parseInt("samples", args.valueOr("samples", "2000"), 1, 1'000'000);
  if (!samples) return failCommand("dataset", samples.error().message);
  const auto seed = parseInt("seed", args.valueOr("seed", "1"), 0, INT64_MAX);
  if (!seed) return failCommand("dataset", seed.error().message);
  const std::string camera_mode = args.valueOr("camera", "keypoints");
  if (camera_mode != "keypoints" && camera_mode != "image")
    return failCommand("dataset", "--camera: expected keypoints or image, got '" + camera_mode + "'");
  const std::string out_path = args.values.at("out");

  auto trial = loadTrial(args.valueOr("scenario", "open"), static_cast<std::uint64_t>(*seed), std::nullopt);
  if (!trial) return failCommand("dataset", trial.error().message);
  const hal::sim::ScenarioSpec& spec = trial->spec;
  auto person = hal::sim::WalkingPerson::create(spec.person, spec.path);
  if (!person) return failCommand("dataset", person.error().message);
  const hal::CameraIntrinsics& intrinsics = spec.gimbal_camera.camera.intrinsics;

  std::unique_ptr<ViewObserver> observer;
  if (camera_mode == "keypoints") {
    observer = std::make_unique<KeypointObserver>(spec.gimbal_camera.camera);
  } else {
    hal::sim::SceneRenderParams render_params;
    render_params.intrinsics = intrinsics;
    auto renderer = hal::sim::SceneRenderer::create(render_params, spec.gimbal_camera.cast);
    if (!renderer) return failCommand("dataset", renderer.error().message);
    auto world = hal::sim::ObstacleWorld::create({}, {});
    if (!world) return failCommand("dataset", world.error().message);
    perception::DetectorParams detector_params;
    detector_params.model_dir = modelDir();
    auto detector = perception::Detector::create(detector_params);
    if (!detector) return failCommand("dataset", detector.error().message);
    observer = std::make_unique<ImageObserver>(std::move(renderer.value()), std::move(world.value()),
                                               std::move(detector.value()));
  }

  hal::sim::CalibrationViewParams view_params;
  view_params.horizontal_fov_rad = 2.0 * std::atan(0.5 * intrinsics.width_px / intrinsics.fx_px);
  if (const rt::Status s = hal::sim::validate(view_params); !s) return failCommand("dataset", s.error().message);
  const perception::TorsoFeatureParams torso_params;
  std::mt19937_64 rng(static_cast<std::uint64_t>(*seed));
  std::vector<localization::LocalizationSample> out;
  std::size_t views = 0;
  // Unreliable views are skipped; bound the attempts so a camera that never sees anyone ends.
  const std::size_t max_views = 20 * static_cast<std::size_t>(*samples);
  while (out.size() < static_cast<std::size_t>(*samples) && views < max_views) {
    ++views;
    const hal::sim::CalibrationView view =
        hal::sim::sampleCalibrationView(*person, person->durationS(), view_params, rng);
    auto detection = observer->observe(view, rng);
    if (!detection) return failCommand("dataset", detection.error().message);
    if (!*detection) continue;
    const perception::TorsoFeatures f =
        perception::torsoFeatures((*detection)->keypoints, intrinsics.width_px, intrinsics.height_px, torso_params);
    if (!f.reliable) continue;
    out.push_back({f.torso_px, f.u_px, view.p_C_flu_m.x(), view.p_C_flu_m.y(), view.p_C_flu_m.z()});
  }
  if (out.size() < static_cast<std::size_t>(*samples))
    return failCommand("dataset", "only " + std::to_string(out.size()) + " of " + std::to_string(*samples) +
                                      " views gave a reliable torso in " + std::to_string(views) + " tries");
  if (const rt::Status s = localization::writeSamplesCsv(out, out_path); !s)
    return failCommand("dataset", s.error().message);
  std::printf("%s: %zu samples (%s camera, %zu views, seed %lld)\n", out_path.c_str(), out.size(), camera_mode.c_str(),
              views, static_cast<long long>(*seed));
  return 0;
}

}  // namespace aerotrack::app
