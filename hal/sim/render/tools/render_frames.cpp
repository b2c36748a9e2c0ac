// render_frames: flies a scenario with the truth-fed baseline follower (as `aerotrack sim` does in
// keypoint mode) and writes what the image-mode gimbal camera would see at a few instants as PNGs,
// with the projected keypoints and torso drawn in a second copy and a third view from 9 m behind the
// person (where obstacles come between), so a person can look at the renderer's output. A developer tool, not part of
// the product.
//
//   render_frames SCENARIO.yaml OUT_DIR [SEED] [FRAMES]
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "aerotrack/hal/sim/baseline_follower.hpp"
#include "aerotrack/hal/sim/scene_renderer.hpp"
#include "aerotrack/hal/sim/simulation.hpp"

int main(int argc, char** argv) {
  using namespace aerotrack;
  if (argc < 3) {
    std::fprintf(stderr, "usage: render_frames SCENARIO.yaml OUT_DIR [SEED] [FRAMES]\n");
    return 1;
  }
  const std::string out_dir = argv[2];
  const std::uint64_t seed = argc > 3 ? std::strtoull(argv[3], nullptr, 10) : 1;
  const int frames = argc > 4 ? std::atoi(argv[4]) : 6;
  auto spec = hal::sim::loadScenarioSpec(argv[1]);
  if (!spec) {
    std::fprintf(stderr, "render_frames: %s\n", spec.error().message.c_str());
    return 1;
  }
  auto trial = hal::sim::instantiate(*spec, seed);
  if (!trial) {
    std::fprintf(stderr, "render_frames: %s\n", trial.error().message.c_str());
    return 1;
  }
  hal::sim::SimulationOptions options;
  options.render_depth = false;
  auto sim = hal::sim::Simulation::create(*trial, options, 0);
  if (!sim) {
    std::fprintf(stderr, "render_frames: %s\n", sim.error().message.c_str());
    return 1;
  }
  hal::sim::SceneRenderParams params;
  params.intrinsics = trial->spec.gimbal_camera.camera.intrinsics;
  auto renderer = hal::sim::SceneRenderer::create(params, trial->spec.gimbal_camera.cast);
  if (!renderer) {
    std::fprintf(stderr, "render_frames: %s\n", renderer.error().message.c_str());
    return 1;
  }
  hal::sim::BaselineFollower follower({}, trial->spec.drone.start_m, trial->spec.drone.start_yaw_rad);
  const double start_s = trial->spec.person_start_delay_s;
  const double span_s = trial->duration_s - start_s - 1.0;
  cv::Mat bgr;
  hal::sim::RenderScratch scratch;
  int frame = 0;
  double render_ms_total = 0.0;
  for (rt::TimeNs t = 0; frame < frames; t += 5'000'000) {  // 200 Hz
    (*sim)->step(t);
    const auto command = follower.update(*(*sim)->truthOut().read(), t);
    (*sim)->setpointInbox().write(command.setpoint);
    (*sim)->gimbalInbox().write(command.gimbal);
    while ((*sim)->detectionsOut().try_pop()) {
    }
    const double due_s = start_s + span_s * (frame + 0.5) / frames;
    if (rt::nsToSeconds(t) < due_s) continue;
    const auto& truth = (*sim)->truth();
    const Eigen::Isometry3d T_WC = (*sim)->cameraPose(truth.drone, truth.gimbal_angle_rad);
    const hal::sim::PersonState person = (*sim)->personAt(t);
    // Everyone: the target and the bystanders, each wearing their person of the cast.
    std::vector<hal::sim::PersonState> states;
    for (std::size_t id = 0; id < (*sim)->personCount(); ++id) states.push_back((*sim)->personStateAt(id, t));
    std::vector<hal::sim::RenderedPerson> everyone;
    const std::size_t target = trial->spec.gimbal_camera.target_person;
    for (std::size_t id = 0; id < states.size(); ++id) {
      const hal::sim::Bystander* b = id == 0 ? nullptr : &trial->bystanders.people[id - 1];
      const bool look_alike = b != nullptr && b->look_alike;
      everyone.push_back({&states[id], hal::sim::castPersonFor(id, look_alike, target, renderer->castSize()),
                          b != nullptr && !look_alike && renderer->castSize() == 1,
                          b != nullptr ? hal::sim::clothingBgr(b->clothing) : Eigen::Vector3f::Ones()});
    }
    const auto begin = std::chrono::steady_clock::now();
    renderer->render((*sim)->obstacles(), T_WC, everyone, bgr, scratch);
    render_ms_total += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count();
    char name[64];
    std::snprintf(name, sizeof(name), "/frame_%02d.png", frame);
    cv::imwrite(out_dir + name, bgr);
    // A copy with the projected keypoints (green) and the sprite's torso placement (red).
    const hal::sim::SpritePlacement pl = renderer->placeSprite(person, T_WC, target);
    const auto uv = [&](const Eigen::Vector3d& p_W) {
      const auto q = hal::sim::project(T_WC.inverse() * p_W, params.intrinsics);
      return q ? cv::Point(static_cast<int>(q->x()), static_cast<int>(q->y())) : cv::Point(-100, -100);
    };
    for (const auto& p_W : person.keypoints_W_m) cv::circle(bgr, uv(p_W), 2, cv::Scalar(0, 255, 0), -1);
    if (pl.visible) {
      cv::line(bgr, cv::Point(static_cast<int>(pl.neck_px.x()), static_cast<int>(pl.neck_px.y())),
               cv::Point(static_cast<int>(pl.mid_hip_px.x()), static_cast<int>(pl.mid_hip_px.y())),
               cv::Scalar(0, 0, 255), 1);
    }
    std::snprintf(name, sizeof(name), "/frame_%02d_keypoints.png", frame);
    cv::imwrite(out_dir + name, bgr);
    // A third view from 9 m behind the person at 1.6 m, where obstacles come between (occlusion).
    {
      const Eigen::Vector3d forward(std::cos(person.heading_rad), std::sin(person.heading_rad), 0.0);
      const Eigen::Vector3d eye = person.p_W_m - 9.0 * forward + Eigen::Vector3d(0.0, 0.0, 1.6);
      const Eigen::Isometry3d T_far = hal::sim::cameraLookingAt(eye, person.p_W_m + Eigen::Vector3d(0.0, 0.0, 0.9));
      renderer->render((*sim)->obstacles(), T_far, everyone, bgr, scratch);
      std::snprintf(name, sizeof(name), "/frame_%02d_far.png", frame);
      cv::imwrite(out_dir + name, bgr);
    }
    std::printf("frame %d at %.2f s: person %s, torso %.1f px, depth %.2f m\n", frame, rt::nsToSeconds(t),
                pl.visible ? "in front" : "behind", (pl.mid_hip_px - pl.neck_px).norm(), pl.depth_m);
    ++frame;
  }
  std::printf("mean render time %.2f ms (%d frames, %d x %d)\n", render_ms_total / frames, frames,
              params.intrinsics.width_px, params.intrinsics.height_px);
  return 0;
}
