// cast_appearance: how far apart the lock-on's appearance cue (perception/appearance.hpp, the torso's
// hue-saturation histogram) puts the people of the image-mode cast (hal/sim/render/person_cast.hpp).
// Each person is rendered walking towards and away from a camera 4 m away at eye height; the torso
// histogram is taken on the true projected keypoints. Prints the front-to-front distance matrix and
// each person's front-to-back distance, to set against tracker.max_appearance_distance (0.45): a
// diagnostic for issue 22 item 2 (docs/modules/localization-estimation.md), not a test.
//
//   cast_appearance
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "aerotrack/hal/sim/scene_renderer.hpp"
#include "aerotrack/hal/sim/walking_person.hpp"
#include "aerotrack/perception/appearance.hpp"

int main() {
  using namespace aerotrack;
  using namespace aerotrack::hal::sim;
  auto renderer = SceneRenderer::create({}, defaultCast());
  auto world = ObstacleWorld::create({}, {});
  if (!renderer || !world) {
    std::fprintf(stderr, "cast_appearance: %s\n", renderer ? "world" : renderer.error().message.c_str());
    return 1;
  }
  const Eigen::Isometry3d T_WC = cameraLookingAt({0.0, 0.0, 1.6}, {4.0, 0.0, 0.9});
  const hal::CameraIntrinsics& k = renderer->params().intrinsics;
  std::vector<perception::Appearance> front, back;
  cv::Mat bgr;
  RenderScratch scratch;
  for (std::size_t who = 0; who < renderer->castSize(); ++who) {
    for (const double heading : {std::numbers::pi, 0.0}) {
      const Eigen::Vector2d dir(std::cos(heading), std::sin(heading));
      const Eigen::Vector2d start = Eigen::Vector2d(4.0, 0.0) - 5.0 * dir;
      auto walker = WalkingPerson::create({}, {{start, 1.4}, {start + 10.0 * dir, 1.4}});
      const PersonState person = walker->state(5.0 / 1.4);
      renderer->render(*world, T_WC, &person, bgr, scratch, who);
      std::array<hal::Keypoint2D, hal::kNumKeypoints> keypoints{};
      for (std::size_t i = 0; i < hal::kNumKeypoints; ++i) {
        const Eigen::Vector3d p_C = T_WC.inverse() * person.keypoints_W_m[i];
        keypoints[i] = {k.cx_px + k.fx_px * p_C.x() / p_C.z(), k.cy_px + k.fy_px * p_C.y() / p_C.z(), 0.9};
      }
      (heading == 0.0 ? back : front).push_back(perception::personAppearance(bgr, keypoints));
    }
  }
  std::printf("%-22s", "front vs front");
  for (std::size_t j = 0; j < front.size(); ++j) std::printf(" %5zu", j);
  std::printf("   front vs own back\n");
  for (std::size_t i = 0; i < front.size(); ++i) {
    std::printf("%zu %-20s", i, renderer->sprite(i).name().c_str());
    for (std::size_t j = 0; j < front.size(); ++j)
      std::printf(" %5.2f", perception::appearanceDistance(front[i], front[j]));
    std::printf("   %5.2f\n", perception::appearanceDistance(front[i], back[i]));
  }
  return 0;
}
