// Speed of the image-mode gimbal camera (hal/sim/render): one 640 x 480 frame of the forest, of
// sharp_turn and of the crowd (the target and every bystander, each an articulated person of the
// cast), seen from 2.5 m behind the person as the follower flies, on one core. Target (issue 22):
// <= 5 ms a frame. Skipped when the cast's photos (Debian package opencv-doc) are missing.
#include <benchmark/benchmark.h>

#include <cmath>
#include <string>
#include <vector>

#include "aerotrack/hal/sim/scenario.hpp"
#include "aerotrack/hal/sim/scene_renderer.hpp"

namespace {

using namespace aerotrack::hal::sim;

void BM_RenderFrame(benchmark::State& state, const std::string& scenario) {
  auto spec = loadScenarioSpec(AEROTRACK_SOURCE_DIR "/config/scenarios/" + scenario + ".yaml");
  if (!spec) {
    state.SkipWithError(spec.error().message.c_str());
    return;
  }
  auto trial = instantiate(*spec, 1);
  auto world = ObstacleWorld::create(trial->spec.boxes, trial->spec.cylinders);
  auto walker = WalkingPerson::create(trial->spec.person, trial->spec.path);
  auto renderer = SceneRenderer::create({}, trial->spec.gimbal_camera.cast);
  if (!trial || !world || !walker || !renderer) {
    state.SkipWithError(renderer ? "scenario" : renderer.error().message.c_str());
    return;
  }
  std::vector<WalkingPerson> bystanders;
  for (const Bystander& b : trial->bystanders.people) {
    auto walker_b = WalkingPerson::create(b.params, b.path);
    if (walker_b) bystanders.push_back(std::move(walker_b.value()));
  }
  const std::size_t cast_size = renderer->castSize();
  cv::Mat bgr;
  RenderScratch scratch;
  std::vector<PersonState> states(bystanders.size() + 1);
  std::vector<RenderedPerson> everyone(bystanders.size() + 1);
  double t_s = 2.0;
  for (auto _ : state) {
    // The person walks on; the camera 2.5 m behind them at 1.5 m, looking at their hips.
    const PersonState person = walker->state(t_s);
    t_s = std::fmod(t_s + 0.5, walker->durationS());
    const Eigen::Vector3d forward(std::cos(person.heading_rad), std::sin(person.heading_rad), 0.0);
    const Eigen::Vector3d eye = person.p_W_m - 2.5 * forward + Eigen::Vector3d(0, 0, 1.5);
    const Eigen::Isometry3d T_WC = cameraLookingAt(eye, person.p_W_m + Eigen::Vector3d(0, 0, 0.9));
    states[0] = person;
    for (std::size_t i = 0; i < bystanders.size(); ++i) states[i + 1] = bystanders[i].state(t_s);
    for (std::size_t i = 0; i < states.size(); ++i)
      everyone[i] = RenderedPerson{&states[i], castPersonFor(i, false, 0, cast_size)};
    renderer->render(*world, T_WC, everyone, bgr, scratch);
    benchmark::DoNotOptimize(bgr.data);
  }
}

BENCHMARK_CAPTURE(BM_RenderFrame, forest, "forest")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_RenderFrame, sharp_turn, "sharp_turn")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_RenderFrame, crowd, "crowd")->Unit(benchmark::kMillisecond);

}  // namespace
