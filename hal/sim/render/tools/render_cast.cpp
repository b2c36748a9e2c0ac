// render_cast: a contact sheet of the image-mode cast (person_cast.hpp) so a person can check the
// cut-outs and the part warps by eye: one row per person; columns: the photo's cut-out with its
// part labels tinted, then the person walking towards a camera 4 m away at eye height (two gait
// phases), walking away (two phases), and walking across the image. Prints each person's parts'
// pixel counts and the mean time to draw a 640 x 480 frame with them. A developer tool, not part of
// the product.
//
//   render_cast OUT.png [CAST.yaml]
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "aerotrack/hal/sim/cast_file.hpp"
#include "aerotrack/hal/sim/scene_renderer.hpp"
#include "aerotrack/hal/sim/walking_person.hpp"

namespace {

using namespace aerotrack::hal::sim;

/// The person mid-walk at about (4, 0), heading `heading_rad`, `phase_s` into their stride.
PersonState walkingAt(double heading_rad, double phase_s) {
  const Eigen::Vector2d dir(std::cos(heading_rad), std::sin(heading_rad));
  const Eigen::Vector2d start = Eigen::Vector2d(4.0, 0.0) - 5.0 * dir;
  auto walker = WalkingPerson::create({}, {{start, 1.4}, {start + 10.0 * dir, 1.4}});
  return walker->state(5.0 / 1.4 + phase_s);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: render_cast OUT.png [CAST.yaml]\n");
    return 1;
  }
  PersonCastSpec cast = defaultCast();
  if (argc > 2) {
    auto loaded = loadCastFile(argv[2]);
    if (!loaded) {
      std::fprintf(stderr, "render_cast: %s\n", loaded.error().message.c_str());
      return 1;
    }
    cast = std::move(loaded.value());
  }
  auto renderer = SceneRenderer::create({}, cast);
  if (!renderer) {
    std::fprintf(stderr, "render_cast: %s\n", renderer.error().message.c_str());
    return 1;
  }
  const auto world = ObstacleWorld::create({}, {});
  const Eigen::Isometry3d T_WC = cameraLookingAt({0.0, 0.0, 1.6}, {4.0, 0.0, 0.9});
  constexpr double kPi = 3.14159265358979;
  const std::array<std::pair<double, double>, 5> poses = {
      {{kPi, 0.0}, {kPi, 0.28}, {0.0, 0.0}, {0.0, 0.28}, {kPi / 2.0, 0.14}}};
  const cv::Rect window(240, 100, 160, 300);
  std::vector<cv::Mat> rows;
  cv::Mat frame;
  RenderScratch scratch;
  for (std::size_t who = 0; who < renderer->castSize(); ++who) {
    const PersonSprite& sprite = renderer->sprite(who);
    // The cut-out with its parts tinted, scaled to the window's height.
    cv::Mat cut(sprite.levels()[0].size(), CV_8UC3);
    const std::array<cv::Vec3b, kPartCount> tint = {{{60, 60, 200},
                                                     {200, 200, 200},
                                                     {200, 60, 60},
                                                     {255, 150, 150},
                                                     {60, 200, 60},
                                                     {150, 255, 150},
                                                     {200, 60, 200},
                                                     {255, 150, 255},
                                                     {60, 200, 200},
                                                     {150, 255, 255}}};
    for (int v = 0; v < cut.rows; ++v) {
      for (int u = 0; u < cut.cols; ++u) {
        const cv::Vec4f c = sprite.levels()[0].at<cv::Vec4f>(v, u);
        const std::uint8_t label = sprite.labels()[0].at<std::uint8_t>(v, u);
        cv::Vec3b& px = cut.at<cv::Vec3b>(v, u);
        for (int ch = 0; ch < 3; ++ch) {
          const float shown = 255.0F * c[ch] + (1.0F - c[3]) * 255.0F;
          const float t = label == kNoPart ? 0.0F : 0.35F;
          px[ch] = static_cast<std::uint8_t>((1.0F - t) * shown +
                                             t * (label == kNoPart ? 0.0F : static_cast<float>(tint[label][ch])));
        }
      }
    }
    const double s = static_cast<double>(window.height) / cut.rows;
    cv::resize(cut, cut, cv::Size(), s, s, cv::INTER_CUBIC);
    cv::Mat row = cut;
    double ms = 0.0;
    for (const auto& [heading, phase] : poses) {
      const PersonState person = walkingAt(heading, phase);
      const auto begin = std::chrono::steady_clock::now();
      renderer->render(*world, T_WC, &person, frame, scratch, who);
      ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count();
      cv::hconcat(row, frame(window), row);
    }
    rows.push_back(row);
    std::printf("%-22s %s, %d px opaque, parts:", sprite.name().c_str(), toString(sprite.view()),
                sprite.opaquePixels());
    for (const int n : sprite.partPixels()) std::printf(" %d", n);
    std::printf("; %.2f ms a frame\n", ms / poses.size());
  }
  int width = 0;
  for (const cv::Mat& r : rows) width = std::max(width, r.cols);
  for (cv::Mat& r : rows) cv::copyMakeBorder(r, r, 0, 0, 0, width - r.cols, cv::BORDER_CONSTANT, cv::Scalar::all(255));
  cv::Mat sheet;
  cv::vconcat(rows, sheet);
  cv::imwrite(argv[1], sheet);
  return 0;
}
