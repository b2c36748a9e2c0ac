// Tests of the image-mode renderer (hal/sim/render/scene_renderer.hpp): every body part of every person
// of the cast lands on its projected bone, arms and legs move with the gait, a person walking away
// shows their back, obstacles hide people pixel by pixel, nothing behind the camera is drawn,
// rendering is deterministic, and a missing or corrupt photo is an error at construction.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "../../../support/require.hpp"
#include "aerotrack/hal/sim/scene_renderer.hpp"

namespace aerotrack::hal::sim {
namespace {

using K = CocoKeypoint;

// A person standing at (x, 0) facing -x, towards a camera on the -x side.
PersonState standingAt(double x_m) {
  const WalkingPerson walker = aerotrack::test::require(
      WalkingPerson::create({}, {{{x_m, 0.0}, 1.0}, {{x_m - 1.0, 0.0}, 1.0}}), "WalkingPerson::create");
  return walker.state(-1.0);
}

ObstacleWorld world(std::vector<Box> boxes, std::vector<Cylinder> cylinders = {}) {
  return aerotrack::test::require(ObstacleWorld::create(std::move(boxes), std::move(cylinders)),
                                  "ObstacleWorld::create");
}

Eigen::Vector2d projected(const Eigen::Vector3d& p_W, const Eigen::Isometry3d& T_WC, const CameraIntrinsics& k) {
  return *project(T_WC.inverse() * p_W, k);
}

Eigen::Vector3d mid(const PersonState& p, K a, K b) {
  return 0.5 * (p.keypoints_W_m[index(a)] + p.keypoints_W_m[index(b)]);
}

// Pixels that differ between two images by more than threshold (sum over B, G, R).
cv::Mat changed(const cv::Mat& a, const cv::Mat& b, float threshold = 0.0F) {
  cv::Mat diff;
  cv::absdiff(a, b, diff);
  cv::Mat sum;
  cv::transform(diff, sum, cv::Matx13f(1, 1, 1));
  return sum > static_cast<double>(threshold);
}

bool castInstalled() {
  for (const PersonSpriteSpec& p : defaultCast().people) {
    if (!std::filesystem::exists(p.image_path)) return false;
  }
  return true;
}

// A person walking at 1.4 m/s through (x, 0) heading `heading_rad`, `phase_s` after passing it.
PersonState walkingThrough(double x_m, double heading_rad, double phase_s) {
  const Eigen::Vector2d dir(std::cos(heading_rad), std::sin(heading_rad));
  const Eigen::Vector2d start = Eigen::Vector2d(x_m, 0.0) - 5.0 * dir;
  const WalkingPerson walker = aerotrack::test::require(
      WalkingPerson::create({}, {{start, 1.4}, {start + 10.0 * dir, 1.4}}), "WalkingPerson::create");
  return walker.state(5.0 / 1.4 + phase_s);
}

Eigen::Vector2d applied(const Eigen::Matrix3d& H, const Eigen::Vector2d& p) {
  const Eigen::Vector3d q = H * Eigen::Vector3d(p.x(), p.y(), 1.0);
  return q.head<2>() / q.z();
}

class SceneRendererTest : public testing::Test {
 protected:
  // One renderer for the suite: loading segments the photo (a fraction of a second).
  static void SetUpTestSuite() {
    if (!castInstalled()) return;
    auto created = SceneRenderer::create({}, defaultCast());
    if (created) shared_ = std::make_unique<SceneRenderer>(std::move(created.value()));
  }
  static void TearDownTestSuite() { shared_.reset(); }

  void SetUp() override {
    if (!castInstalled()) GTEST_SKIP() << "opencv-doc's sample data is missing: install the Debian package opencv-doc";
    ASSERT_NE(shared_, nullptr) << "the default cast did not load";
    renderer_ = shared_.get();
  }

  cv::Mat render(const ObstacleWorld& w, const Eigen::Isometry3d& T_WC, const PersonState* person) {
    cv::Mat bgr;
    renderer_->render(w, T_WC, person, bgr, scratch_);
    return bgr;
  }

  static inline std::unique_ptr<SceneRenderer> shared_;
  const SceneRenderer* renderer_ = nullptr;
  RenderScratch scratch_;
};

TEST_F(SceneRendererTest, SpriteTorsoAndMidHipMatchTheProjectedKeypoints) {
  // Given a person 4 m in front of a camera at 1.5 m, seen slightly from the side and rolled by 5 deg
  const PersonState person = standingAt(4.0);
  Eigen::Isometry3d T_WC = cameraLookingAt({0.0, 0.7, 1.5}, {4.0, 0.0, 1.0});
  T_WC.linear() = T_WC.linear() * Eigen::AngleAxisd(0.087, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const CameraIntrinsics& k = renderer_->params().intrinsics;
  // (the midpoints of the projected joints, as the detector reports them)
  const auto mid_px = [&](K a, K b) -> Eigen::Vector2d {
    return 0.5 *
           (projected(person.keypoints_W_m[index(a)], T_WC, k) + projected(person.keypoints_W_m[index(b)], T_WC, k));
  };
  const Eigen::Vector2d neck = mid_px(K::kLeftShoulder, K::kRightShoulder);
  const Eigen::Vector2d hip = mid_px(K::kLeftHip, K::kRightHip);

  // When the sprite is placed and the scene rendered with and without the person
  const SpritePlacement placement = renderer_->placeSprite(person, T_WC);
  const ObstacleWorld empty = world({});
  const cv::Mat mask = changed(render(empty, T_WC, &person), render(empty, T_WC, nullptr));

  // Then the sprite's own torso maps onto the projected one: same mid-hip, same length and direction
  ASSERT_TRUE(placement.visible);
  EXPECT_LT((placement.mid_hip_px - hip).norm(), 1e-9);
  EXPECT_LT((placement.neck_px - neck).norm(), 1e-9);
  const PersonSprite& sprite = renderer_->sprite();
  const Eigen::Matrix3d& H_torso = placement.parts[static_cast<std::size_t>(BodyPart::kTorso)].H_sprite_image;
  EXPECT_LT((applied(H_torso, neck) - sprite.neckPx()).norm(), 1e-6);
  EXPECT_LT((applied(H_torso, hip) - sprite.midHipPx()).norm(), 1e-6);
  // ... and the drawn person covers the mid-hip and the neck, within the placement's bounds, with
  // their feet near the projected ground point under the pelvis.
  const auto covered = [&](const Eigen::Vector2d& p) {
    int hits = 0;  // any pixel within 2 px
    for (int dv = -2; dv <= 2; ++dv)
      for (int du = -2; du <= 2; ++du)
        hits += mask.at<std::uint8_t>(static_cast<int>(p.y()) + dv, static_cast<int>(p.x()) + du) > 0;
    return hits > 0;
  };
  EXPECT_TRUE(covered(hip));
  EXPECT_TRUE(covered(neck));
  const cv::Rect drawn = cv::boundingRect(mask);
  EXPECT_GE(drawn.x, placement.bounds_px[0] - 2.0);
  EXPECT_LE(drawn.x + drawn.width, placement.bounds_px[2] + 2.0);
  EXPECT_GE(drawn.y, placement.bounds_px[1] - 2.0);
  EXPECT_LE(drawn.y + drawn.height, placement.bounds_px[3] + 2.0);
  const Eigen::Vector2d ground = projected(person.p_W_m, T_WC, k);
  EXPECT_NEAR(drawn.y + drawn.height, ground.y(), 6.0);
  // The drawn height agrees with the person's: head top to soles ~ stature H = 1.75 m at ~4 m.
  const double expected_height_px = k.fy_px * 1.75 / 4.2;
  EXPECT_NEAR(drawn.height, expected_height_px, 0.15 * expected_height_px);
}

TEST_F(SceneRendererTest, AnObstacleBetweenCameraAndPersonHidesTheirPixels) {
  // Given a person 5 m away and a pole between them and the camera covering the left half of the body
  const PersonState person = standingAt(5.0);
  const Eigen::Isometry3d T_WC = cameraLookingAt({0.0, 0.0, 1.2}, {5.0, 0.0, 1.0});
  const ObstacleWorld pole = world({Box{{2.4, -0.05, 0.0}, {2.6, 0.4, 3.0}}});
  const ObstacleWorld empty = world({});

  // When the scene is rendered with and without the person, with and without the pole
  const cv::Mat with_pole = changed(render(pole, T_WC, &person), render(pole, T_WC, nullptr));
  const cv::Mat pole_pixels = scratch_.depth_m < std::numeric_limits<double>::infinity();
  const cv::Mat without_pole = changed(render(empty, T_WC, &person), render(empty, T_WC, nullptr));

  // Then no pixel of the pole shows the person, though the person is there behind it, and the
  // person's other half is still drawn
  ASSERT_GT(cv::countNonZero(pole_pixels), 1000);
  EXPECT_EQ(cv::countNonZero(with_pole & pole_pixels), 0);
  EXPECT_GT(cv::countNonZero(without_pole & pole_pixels), 300);
  EXPECT_GT(cv::countNonZero(with_pole), 300);
  EXPECT_EQ(cv::countNonZero(with_pole & ~without_pole), 0);

  // ... and a pole behind the person hides nothing of them
  const ObstacleWorld behind = world({Box{{7.0, -0.5, 0.0}, {7.2, 0.5, 3.0}}});
  const cv::Mat with_behind = changed(render(behind, T_WC, &person), render(behind, T_WC, nullptr));
  // (the faint edge pixels of the sprite may round to the background's colour on one of the two)
  const cv::Mat clearly_person = changed(render(empty, T_WC, &person), render(empty, T_WC, nullptr), 30.0F);
  EXPECT_GT(cv::countNonZero(clearly_person), 1000);
  // (an opaque pixel of the photo may happen to have the pole's very colour)
  EXPECT_LE(cv::countNonZero(clearly_person & ~with_behind), 5);
}

TEST_F(SceneRendererTest, NothingBehindTheCameraIsDrawn) {
  // Given a camera looking along +x, and a wall, a tree and a person all behind it (x < 0)
  const Eigen::Isometry3d T_WC = cameraLookingAt({0.0, 0.0, 1.5}, {10.0, 0.0, 1.0});
  const PersonState person = standingAt(-3.0);
  const ObstacleWorld behind =
      world({Box{{-4.0, -5.0, 0.0}, {-3.8, 5.0, 4.0}}}, {Cylinder{{-2.0, 1.0}, 0.3, 0.0, 6.0}});

  // When rendered, then the image is the empty world's
  const cv::Mat scene = render(behind, T_WC, &person);
  const cv::Mat empty = render(world({}), T_WC, nullptr);
  EXPECT_EQ(cv::countNonZero(changed(scene, empty)), 0);
  EXPECT_FALSE(renderer_->placeSprite(person, T_WC).visible);
}

TEST_F(SceneRendererTest, TheDepthBufferHoldsTheNearestObstacleOnEveryPixelsRay) {
  // Given a random forest with a building, seen from the ground, from above the tree tops (their caps),
  // rolled and pitched, and from inside a trunk's footprint (the general path)
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> x(2.0, 30.0), y(-10.0, 10.0), r(0.1, 0.5), top(1.0, 9.0);
  std::vector<Cylinder> trees;
  for (int i = 0; i < 60; ++i) trees.push_back(Cylinder{{x(rng), y(rng)}, r(rng), 0.0, top(rng)});
  trees.push_back(Cylinder{{0.0, 0.0}, 0.6, 0.0, 1.0});  // a stump the last camera stands over
  const ObstacleWorld forest = world({Box{{12.0, -2.0, 0.0}, {15.0, 2.0, 3.0}}}, trees);
  const std::vector<Eigen::Isometry3d> cameras = {
      cameraLookingAt({0.0, 0.5, 1.5}, {10.0, 0.0, 1.0}), cameraLookingAt({-2.0, 0.0, 12.0}, {15.0, 0.0, 0.0}),
      cameraLookingAt({1.0, -8.0, 2.0}, {20.0, 6.0, 4.0}) * Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()),
      cameraLookingAt({0.2, 0.1, 2.5}, {12.0, 3.0, 0.5})};
  const CameraIntrinsics& k = renderer_->params().intrinsics;
  const double max_range = renderer_->params().max_range_m;
  for (const Eigen::Isometry3d& T_WC : cameras) {
    // When rendered
    (void)render(forest, T_WC, nullptr);

    // Then each pixel's depth is the first hit of its ray (double precision, every obstacle tried: the
    // slow, obvious reference of the single-precision vectorised pass), up to float rounding; a few
    // pixels grazing a silhouette may differ
    int differing = 0;
    for (int v = 0; v < k.height_px; v += 2) {
      for (int u = 0; u < k.width_px; u += 2) {
        const Eigen::Vector3d d_W =
            T_WC.linear() * Eigen::Vector3d((u + 0.5 - k.cx_px) / k.fx_px, (v + 0.5 - k.cy_px) / k.fy_px, 1.0);
        const Ray ray(T_WC.translation(), d_W);
        double nearest = std::numeric_limits<double>::infinity();
        for (const Box& b : forest.boxes())
          if (const auto t = firstHit(b, ray, max_range); t && *t >= 0.05) nearest = std::min(nearest, *t);
        for (const Cylinder& c : forest.cylinders())
          if (const auto t = firstHit(c, ray, max_range); t && *t >= 0.05) nearest = std::min(nearest, *t);
        const auto rendered = static_cast<double>(scratch_.depth_m.at<float>(v, u));
        const bool same = std::isinf(nearest) ? std::isinf(rendered) : std::abs(rendered - nearest) <= 1e-3 * nearest;
        differing += same ? 0 : 1;
      }
    }
    EXPECT_LE(differing, k.width_px * k.height_px / 4 / 1000) << "camera at " << T_WC.translation().transpose();
  }
}

TEST_F(SceneRendererTest, RenderingIsDeterministic) {
  // Given a forest scene
  std::vector<Cylinder> trees;
  for (int i = 0; i < 30; ++i) trees.push_back(Cylinder{{3.0 + 0.9 * i, -6.0 + 0.43 * i}, 0.25, 0.0, 8.0});
  const ObstacleWorld forest = world({Box{{10.0, 3.0, 0.0}, {14.0, 9.0, 4.0}}}, std::move(trees));
  const PersonState person = standingAt(6.0);
  const Eigen::Isometry3d T_WC = cameraLookingAt({0.0, 0.5, 1.6}, {6.0, 0.0, 1.0});

  // When it is rendered twice by one renderer and once by a second one built from the same photo
  const cv::Mat first = render(forest, T_WC, &person);
  const cv::Mat second = render(forest, T_WC, &person);
  auto other = SceneRenderer::create({}, defaultCast());
  ASSERT_TRUE(other.has_value());
  cv::Mat third;
  RenderScratch scratch;
  other->render(forest, T_WC, &person, third, scratch);

  // Then the three images are identical, bit for bit
  EXPECT_EQ(cv::countNonZero(changed(first, second)), 0);
  EXPECT_EQ(cv::countNonZero(changed(first, third)), 0);
}

TEST_F(SceneRendererTest, EveryPartOfEveryPersonLandsOnItsProjectedBone) {
  // Given each person of the cast walking towards, away from and across a camera 5 m away
  const Eigen::Isometry3d T_WC = cameraLookingAt({0.0, 0.3, 1.6}, {5.0, 0.0, 0.9});
  const CameraIntrinsics& k = renderer_->params().intrinsics;
  const ObstacleWorld empty = world({});
  const cv::Mat background = render(empty, T_WC, nullptr);
  ASSERT_GE(renderer_->castSize(), 6U);
  for (std::size_t who = 0; who < renderer_->castSize(); ++who) {
    for (const double heading : {M_PI, 0.0, M_PI / 2.0}) {
      const PersonState person = walkingThrough(5.0, heading, 0.2);
      // When placed and drawn
      const SpritePlacement pl = renderer_->placeSprite(person, T_WC, who);
      cv::Mat bgr;
      renderer_->render(empty, T_WC, &person, bgr, scratch_, who);
      const cv::Mat drawn = changed(bgr, background, 30.0F);
      ASSERT_TRUE(pl.visible);
      // Then each limb's map takes its projected joints onto the photo's joints of that limb
      const PersonSprite& sprite = renderer_->sprite(who);
      std::array<Eigen::Vector2d, kNumKeypoints> kp_px{};
      for (std::size_t i = 0; i < kNumKeypoints; ++i) kp_px[i] = projected(person.keypoints_W_m[i], T_WC, k);
      for (std::size_t p = 0; p < kPartCount; ++p) {
        const auto ends_i = bodyPartEnds(static_cast<BodyPart>(p), kp_px);
        const auto ends_s = bodyPartEnds(static_cast<BodyPart>(p), sprite.keypointsPx());
        const Eigen::Matrix3d& H = pl.parts[p].H_sprite_image;
        EXPECT_LT((applied(H, ends_i[0]) - ends_s[0]).norm(), 1e-6) << sprite.name() << " part " << p;
        // (a limb pointing at the camera keeps a minimum length: the far end may fall short)
        if ((ends_i[1] - ends_i[0]).norm() > 0.3 * pl.scale * (ends_s[1] - ends_s[0]).norm()) {
          EXPECT_LT((applied(H, ends_i[1]) - ends_s[1]).norm(), 1e-6) << sprite.name() << " part " << p;
        }
      }
      // ... and the person is drawn at the projected neck, hips, knees and ankles (within 3 px)
      for (const K joint : {K::kLeftHip, K::kRightHip, K::kLeftKnee, K::kRightKnee, K::kLeftAnkle, K::kRightAnkle}) {
        const Eigen::Vector2d p = kp_px[index(joint)];
        const cv::Rect near(static_cast<int>(p.x()) - 3, static_cast<int>(p.y()) - 3, 7, 7);
        EXPECT_GT(cv::countNonZero(drawn(near)), 0)
            << sprite.name() << " joint " << index(joint) << " heading " << heading;
      }
    }
  }
}

TEST_F(SceneRendererTest, ArmsAndLegsMoveWithTheGait) {
  // Given a person walking across the image, at two instants a quarter stride apart
  const Eigen::Isometry3d T_WC = cameraLookingAt({0.0, 0.0, 1.5}, {5.0, 0.0, 0.9});
  const ObstacleWorld empty = world({});
  const cv::Mat background = render(empty, T_WC, nullptr);
  const PersonState early = walkingThrough(5.0, M_PI / 2.0, 0.0);
  PersonState later = walkingThrough(5.0, M_PI / 2.0, 0.14);
  // (the same place, so only the limbs differ)
  const Eigen::Vector3d shift = early.p_W_m - later.p_W_m;
  later.p_W_m += shift;
  for (auto& p : later.keypoints_W_m) p += shift;

  // When both are drawn
  const cv::Mat a = changed(render(empty, T_WC, &early), background, 30.0F);
  const cv::Mat b = changed(render(empty, T_WC, &later), background, 30.0F);

  // Then the silhouettes differ below the hips (the legs swung) and much less above them
  const CameraIntrinsics& k = renderer_->params().intrinsics;
  const int hip_v = static_cast<int>(projected(mid(early, K::kLeftHip, K::kRightHip), T_WC, k).y());
  const cv::Mat moved = a ^ b;
  const int below = cv::countNonZero(moved.rowRange(hip_v, moved.rows));
  const int torso_rows = cv::countNonZero(a.rowRange(0, hip_v));
  EXPECT_GT(below, 150);
  EXPECT_GT(below, cv::countNonZero(moved.rowRange(0, hip_v)));
  EXPECT_GT(torso_rows, 300);
}

TEST_F(SceneRendererTest, APersonWalkingAwayShowsTheirBack) {
  const Eigen::Isometry3d T_WC = cameraLookingAt({0.0, 0.0, 1.6}, {5.0, 0.0, 0.9});
  const PersonState towards = walkingThrough(5.0, M_PI, 0.0);
  const PersonState away = walkingThrough(5.0, 0.0, 0.0);
  for (std::size_t who = 0; who < renderer_->castSize(); ++who) {
    const bool front_photo = renderer_->sprite(who).view() == PersonView::kFront;
    // A front photo is drawn as it is for someone walking towards the camera, mirrored with hair over
    // the face for someone walking away; a back photo the other way round
    const SpritePlacement t = renderer_->placeSprite(towards, T_WC, who);
    const SpritePlacement a = renderer_->placeSprite(away, T_WC, who);
    EXPECT_EQ(t.mirrored, !front_photo) << renderer_->sprite(who).name();
    EXPECT_EQ(a.mirrored, front_photo) << renderer_->sprite(who).name();
    EXPECT_FALSE(t.hair_over_face);
    EXPECT_EQ(a.hair_over_face, front_photo);
  }
  // The cast has both: people photographed from the front and from behind
  int backs = 0;
  for (std::size_t who = 0; who < renderer_->castSize(); ++who)
    backs += renderer_->sprite(who).view() == PersonView::kBack;
  EXPECT_GE(backs, 2);
  EXPECT_GE(static_cast<int>(renderer_->castSize()) - backs, 2);
}

TEST(SceneRendererErrors, AMissingPhotoIsAnErrorNamingIt) {
  // Given a sprite spec whose photo does not exist
  PersonCastSpec cast = defaultCast();
  cast.people[2].image_path = "/nonexistent/person.png";

  // When a renderer is created, then it fails with a message naming the file
  const auto renderer = SceneRenderer::create({}, cast);
  ASSERT_FALSE(renderer.has_value());
  EXPECT_NE(renderer.error().message.find("/nonexistent/person.png"), std::string::npos) << renderer.error().message;
}

TEST(SceneRendererErrors, ACorruptPhotoIsAnError) {
  // Given a "PNG" file holding garbage
  const std::string path = testing::TempDir() + "/corrupt_sprite.png";
  {
    std::ofstream out(path, std::ios::binary);
    out << "\x89PNG\r\n\x1a\n this is not really an image";
  }
  PersonCastSpec cast;
  cast.people.push_back(PersonSpriteSpec{});
  cast.people[0].image_path = path;

  // When a renderer is created, then it fails with a message naming the file, without crashing
  const auto renderer = SceneRenderer::create({}, cast);
  ASSERT_FALSE(renderer.has_value());
  EXPECT_NE(renderer.error().message.find(path), std::string::npos) << renderer.error().message;
  std::remove(path.c_str());
}

TEST(SceneRendererErrors, BadSpritesAndCastsAreOneLineErrorsNamingThePersonAndKey) {
  const auto message = [](const rt::Status& status) { return status ? std::string() : status.error().message; };
  PersonSpriteSpec outside;
  outside.keypoints_px[9] = {500.0, 100.0};  // a wrist outside the crop
  EXPECT_NE(message(validate(outside)).find("basketball1_standing: keypoints_px: keypoint 9"), std::string::npos)
      << message(validate(outside));
  PersonSpriteSpec turned;
  turned.view = PersonView::kBack;  // the shoulders say front
  EXPECT_NE(message(validate(turned)).find("view"), std::string::npos);
  PersonSpriteSpec upside_down;
  std::swap(upside_down.keypoints_px[5], upside_down.keypoints_px[11]);
  std::swap(upside_down.keypoints_px[6], upside_down.keypoints_px[12]);
  EXPECT_NE(message(validate(upside_down)).find("neck above the mid-hip"), std::string::npos);
  EXPECT_NE(message(validate(PersonCastSpec{})).find("the cast is empty"), std::string::npos);
  PersonCastSpec twice;
  twice.people = {PersonSpriteSpec{}, PersonSpriteSpec{}};
  EXPECT_NE(message(validate(twice)).find("given twice"), std::string::npos);
  for (const std::string& m : {message(validate(outside)), message(validate(PersonCastSpec{}))})
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
  SceneRenderParams params;
  params.intrinsics.distortion[0] = 0.1;
  EXPECT_FALSE(validate(params).has_value());
}

TEST(SceneRendererErrors, AVideoFramePastTheEndIsAnErrorNamingTheFrame) {
  PersonCastSpec cast = defaultCast();
  if (!std::filesystem::exists(cast.people[1].image_path)) GTEST_SKIP() << "opencv-doc is missing";
  cast.people.resize(2);
  cast.people[1].frame = 5000;  // vtest.avi has 795
  const auto loaded = loadCast(cast);
  ASSERT_FALSE(loaded.has_value());
  EXPECT_NE(loaded.error().message.find("frame 5000 is past the video's end (795 frames)"), std::string::npos)
      << loaded.error().message;
}

TEST(SceneRendererErrors, ADirectoryOrSpecialFileIsNotAPhoto) {
  PersonCastSpec cast;
  cast.people.push_back(PersonSpriteSpec{});
  cast.people[0].image_path = testing::TempDir();
  auto loaded = loadCast(cast);
  ASSERT_FALSE(loaded.has_value());
  EXPECT_NE(loaded.error().message.find("is a directory"), std::string::npos) << loaded.error().message;
  cast.people[0].image_path = "/dev/zero";
  loaded = loadCast(cast);
  ASSERT_FALSE(loaded.has_value());
  EXPECT_NE(loaded.error().message.find("/dev/zero: not a regular file"), std::string::npos) << loaded.error().message;
}

}  // namespace
}  // namespace aerotrack::hal::sim
