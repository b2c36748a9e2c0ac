// Tests of the localization models (paper Sect. IV-B, Eq. 1, and the pinhole model): recovery of
// known parameters from noise-free synthetic data, fitted from scratch; robustness to gross
// outliers; fit errors; the held-out evaluation.
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "aerotrack/localization/localization_eval.hpp"
#include "aerotrack/localization/localization_model.hpp"

namespace aerotrack::localization {
namespace {

hal::CameraIntrinsics testIntrinsics() {
  hal::CameraIntrinsics k;
  k.width_px = 640;
  k.height_px = 480;
  k.fx_px = 460.0;
  k.fy_px = 455.0;
  k.cx_px = 322.0;
  k.cy_px = 240.0;
  return k;
}

LocalizationParams truePaper() {
  LocalizationParams p;
  p.model = LocalizationModel::kPaper;
  p.paper = {12.0, -0.03, 3.0, -0.004, 1.2, -0.003, -0.4, 0.0005, 0.3};
  p.z_m = -1.1;
  return p;
}

LocalizationParams truePinhole() {
  LocalizationParams p;
  p.model = LocalizationModel::kPinhole;
  const hal::CameraIntrinsics k = testIntrinsics();
  p.pinhole = {k.fx_px, k.fy_px, k.cx_px, 0.52, 0.15, -40.0, 0.04, -0.05};
  p.z_m = -0.8;
  return p;
}

/// Samples from `truth` on a torso range of 20-200 px and the image width, plus noise (metres).
std::vector<LocalizationSample> synthesize(const LocalizationParams& truth, std::size_t count, double noise_m,
                                           unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> torso(20.0, 200.0);
  std::uniform_real_distribution<double> u(0.0, 640.0);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<LocalizationSample> samples;
  for (std::size_t i = 0; i < count; ++i) {
    LocalizationSample s;
    s.torso_px = torso(rng);
    s.u_px = u(rng);
    const Eigen::Vector3d p_C = predict(truth, s.torso_px, s.u_px);
    s.x_m = p_C.x() + noise_m * noise(rng);
    s.y_m = p_C.y() + noise_m * noise(rng);
    s.z_m = p_C.z();
    samples.push_back(s);
  }
  return samples;
}

void expectRelativelyNear(double actual, double expected, double relative, const char* name) {
  EXPECT_NEAR(actual, expected, relative * std::max(1e-3, std::abs(expected))) << name;
}

TEST(PaperModel, GivenNoiseFreeSamplesWhenFittedFromScratchThenRecoversTheParameters) {
  // Given samples of the paper's Eq. (1) with known parameters, no noise.
  const LocalizationParams truth = truePaper();
  const auto samples = synthesize(truth, 300, 0.0, 1);
  // When fitted from scratch.
  const auto fitted = fit(LocalizationModel::kPaper, samples, testIntrinsics());
  ASSERT_TRUE(fitted) << fitted.error().message;
  // Then every parameter is recovered.
  const PaperModelParams& p = fitted->paper;
  const PaperModelParams& t = truth.paper;
  expectRelativelyNear(p.l1_m, t.l1_m, 1e-4, "l1_m");
  expectRelativelyNear(p.k1_per_px, t.k1_per_px, 1e-4, "k1_per_px");
  expectRelativelyNear(p.l2_m, t.l2_m, 1e-4, "l2_m");
  expectRelativelyNear(p.k2_per_px, t.k2_per_px, 1e-4, "k2_per_px");
  expectRelativelyNear(p.l3, t.l3, 1e-4, "l3");
  expectRelativelyNear(p.k3_per_px, t.k3_per_px, 1e-4, "k3_per_px");
  expectRelativelyNear(p.l4, t.l4, 1e-4, "l4");
  expectRelativelyNear(p.k4_per_px, t.k4_per_px, 1e-4, "k4_per_px");
  expectRelativelyNear(p.b_m, t.b_m, 1e-4, "b_m");
  EXPECT_NEAR(fitted->z_m, truth.z_m, 1e-12);
  EXPECT_LT(fitted->fit_mean_error_m, 1e-6);
  EXPECT_EQ(fitted->fit_samples, 300u);
  std::printf("[ figures  ] paper model, noise-free: fit mean error %.3g m\n", fitted->fit_mean_error_m);
}

TEST(PinholeModel, GivenNoiseFreeSamplesWhenFittedFromScratchThenRecoversTheParameters) {
  const LocalizationParams truth = truePinhole();
  const auto samples = synthesize(truth, 200, 0.0, 2);
  const auto fitted = fit(LocalizationModel::kPinhole, samples, testIntrinsics());
  ASSERT_TRUE(fitted) << fitted.error().message;
  const PinholeModelParams& p = fitted->pinhole;
  const PinholeModelParams& t = truth.pinhole;
  EXPECT_EQ(p.fx_px, t.fx_px);
  EXPECT_EQ(p.fy_px, t.fy_px);
  EXPECT_EQ(p.cx_px, t.cx_px);
  EXPECT_NEAR(p.torso_m, t.torso_m, 1e-9);
  EXPECT_NEAR(p.x_offset_m, t.x_offset_m, 1e-8);
  EXPECT_NEAR(p.x_inv_sq_m_px2, t.x_inv_sq_m_px2, 1e-5);
  EXPECT_NEAR(p.y_scale_correction, t.y_scale_correction, 1e-9);
  EXPECT_NEAR(p.y_offset_m, t.y_offset_m, 1e-9);
  EXPECT_NEAR(fitted->z_m, truth.z_m, 1e-12);
}

TEST(PinholeModel, GivenAPersonRightOfTheImageCentreThenYIsNegative) {
  LocalizationParams p = truePinhole();
  p.pinhole.y_offset_m = 0.0;
  p.pinhole.x_offset_m = 0.0;
  p.pinhole.x_inv_sq_m_px2 = 0.0;
  p.pinhole.y_scale_correction = 0.0;
  const Eigen::Vector3d p_C = predict(p, 100.0, p.pinhole.cx_px + 46.0);  // 0.1 rad right
  EXPECT_NEAR(p_C.x(), 455.0 * 0.52 / 100.0, 1e-12);
  EXPECT_NEAR(p_C.y(), -p_C.x() * 0.1, 1e-12);
}

TEST(LocalizationFit, GivenAFewGrossOutliersWhenFittedThenTheRobustLossIgnoresThem) {
  for (const LocalizationModel model : {LocalizationModel::kPaper, LocalizationModel::kPinhole}) {
    // Given 300 noisy samples (0.05 m) of which 6 are gross outliers (a wrong person, 3-6 m off).
    const LocalizationParams truth = model == LocalizationModel::kPaper ? truePaper() : truePinhole();
    auto samples = synthesize(truth, 300, 0.05, 3);
    for (std::size_t i = 0; i < 6; ++i) {
      samples[i * 50].x_m += 3.0 + static_cast<double>(i) * 0.5;
      samples[i * 50 + 7].y_m -= 4.0;
    }
    // When fitted.
    const auto fitted = fit(model, samples, testIntrinsics());
    ASSERT_TRUE(fitted) << fitted.error().message;
    // Then predictions on clean data are as good as the noise allows.
    const auto clean = synthesize(truth, 500, 0.0, 4);
    const auto evaluation = evaluate(*fitted, clean);
    ASSERT_TRUE(evaluation);
    EXPECT_LT(evaluation->mean_error_m, 0.03) << toString(model);
    EXPECT_LT(evaluation->max_error_m, 0.15) << toString(model);
    std::printf("[ figures  ] %s model, 12 gross outliers in 300: clean-data mean %.4f m, max %.4f m\n",
                std::string(toString(model)).c_str(), evaluation->mean_error_m, evaluation->max_error_m);
  }
}

TEST(LocalizationFit, GivenPinholeLikeDataWhenThePaperModelIsFittedThenItApproximatesIt) {
  // Given data from pinhole geometry with 0.1 m noise (the shape the paper's regression meets).
  const auto train = synthesize(truePinhole(), 800, 0.1, 5);
  const auto test = synthesize(truePinhole(), 800, 0.0, 6);
  for (const LocalizationModel model : {LocalizationModel::kPaper, LocalizationModel::kPinhole}) {
    const auto fitted = fit(model, train, testIntrinsics());
    ASSERT_TRUE(fitted) << fitted.error().message;
    const auto evaluation = evaluate(*fitted, test);
    ASSERT_TRUE(evaluation);
    EXPECT_LT(evaluation->mean_error_m, 0.1) << toString(model);
    std::printf("[ figures  ] %s model on pinhole-like data: mean %.4f m, p95 %.4f m, max %.4f m\n",
                std::string(toString(model)).c_str(), evaluation->mean_error_m, evaluation->p95_error_m,
                evaluation->max_error_m);
  }
}

TEST(LocalizationFit, GivenTooFewOrInvalidSamplesThenAnError) {
  const auto samples = synthesize(truePaper(), 5, 0.0, 7);
  const auto few = fit(LocalizationModel::kPaper, samples, testIntrinsics());
  ASSERT_FALSE(few);
  EXPECT_NE(few.error().message.find("at least 12 samples"), std::string::npos) << few.error().message;
  auto bad = synthesize(truePinhole(), 20, 0.0, 8);
  bad[3].torso_px = 0.0;
  const auto zero = fit(LocalizationModel::kPinhole, bad, testIntrinsics());
  ASSERT_FALSE(zero);
  EXPECT_NE(zero.error().message.find("sample 3"), std::string::npos) << zero.error().message;
  hal::CameraIntrinsics no_focal = testIntrinsics();
  no_focal.fx_px = 0.0;
  EXPECT_FALSE(fit(LocalizationModel::kPinhole, synthesize(truePinhole(), 20, 0.0, 9), no_focal));
}

TEST(LocalizationFit, GivenRowsThatDoNotVaryThenTheFitRefusesThem) {
  // 500 identical rows fitted with 0.000 m error (issue 23 item 7): any curve passes through one point.
  const std::vector<LocalizationSample> same(500, synthesize(truePinhole(), 1, 0.0, 11)[0]);
  for (const LocalizationModel model : {LocalizationModel::kPaper, LocalizationModel::kPinhole}) {
    const auto fitted = fit(model, same, testIntrinsics());
    ASSERT_FALSE(fitted) << toString(model);
    EXPECT_NE(fitted.error().message.find("the samples do not vary: 1 distinct torso length(s), need at least 5"),
              std::string::npos)
        << fitted.error().message;
  }
}

TEST(LocalizationFit, GivenDataNoModelCanExplainThenConvergenceFailureIsAnError) {
  // Given one iteration only: Ceres cannot converge, and the fit says so.
  FitOptions options;
  options.max_iterations = 1;
  const auto fitted = fit(LocalizationModel::kPaper, synthesize(truePaper(), 100, 0.2, 10), testIntrinsics(), options);
  ASSERT_FALSE(fitted);
  EXPECT_NE(fitted.error().message.find("did not converge"), std::string::npos) << fitted.error().message;
}

TEST(LocalizationEvaluate, GivenKnownErrorsThenTheSummaryAndTheDistanceTable) {
  // Given a model predicting x = 1 m everywhere and samples at 1.5, 2.5, 2.6, 4.2 m ahead.
  LocalizationParams params;
  params.model = LocalizationModel::kPinhole;
  params.pinhole = {100.0, 100.0, 50.0, 0.0, 1.0, 0.0, 0.0, 0.0};
  std::vector<LocalizationSample> samples = {
      {10.0, 50.0, 1.5, 0.0}, {10.0, 50.0, 2.5, 0.0}, {10.0, 50.0, 2.6, 0.0}, {10.0, 50.0, 4.2, 0.0}};
  // When evaluated.
  const auto e = evaluate(params, samples);
  ASSERT_TRUE(e);
  // Then errors 0.5, 1.5, 1.6, 3.2.
  EXPECT_EQ(e->model, "pinhole");
  EXPECT_EQ(e->samples, 4u);
  EXPECT_NEAR(e->mean_error_m, (0.5 + 1.5 + 1.6 + 3.2) / 4.0, 1e-12);
  EXPECT_NEAR(e->median_error_m, 1.55, 1e-12);
  EXPECT_NEAR(e->max_error_m, 3.2, 1e-12);
  EXPECT_NEAR(e->p95_error_m, 1.6 + 0.85 * (3.2 - 1.6), 1e-12);
  ASSERT_EQ(e->by_distance.size(), 3u);
  EXPECT_EQ(e->by_distance[0].from_m, 1.0);
  EXPECT_EQ(e->by_distance[1].from_m, 2.0);
  EXPECT_EQ(e->by_distance[1].samples, 2u);
  EXPECT_NEAR(e->by_distance[1].mean_error_m, 1.55, 1e-12);
  EXPECT_EQ(e->by_distance[2].from_m, 4.0);
  EXPECT_EQ(e->by_distance[2].to_m, 5.0);
  EXPECT_FALSE(evaluate(params, std::vector<LocalizationSample>{}));
}

TEST(LocalizationNoise, GivenResidualsGrowingWithDistance_WhenFitted_ThenTheNoiseLineIsRecovered) {
  // Each axis off by N(0, (0.05 + 0.04 x)^2) around the true model: fitNoise on the true parameters recovers the
  // line from the residuals' medians.
  const LocalizationParams truth = truePinhole();
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> torso(20.0, 200.0);
  std::uniform_real_distribution<double> u(0.0, 640.0);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<LocalizationSample> samples;
  for (int i = 0; i < 8000; ++i) {
    LocalizationSample s;
    s.torso_px = torso(rng);
    s.u_px = u(rng);
    const Eigen::Vector3d p_C = predict(truth, s.torso_px, s.u_px);
    const double sigma_m = 0.05 + 0.04 * p_C.x();
    s.x_m = p_C.x() + sigma_m * normal(rng);
    s.y_m = p_C.y() + sigma_m * normal(rng);
    samples.push_back(s);
  }
  LocalizationParams fitted = truth;
  fitNoise(fitted, samples);
  EXPECT_NEAR(fitted.noise_std_per_m, 0.04, 0.004);
  EXPECT_NEAR(fitted.noise_std_m, 0.05, 0.02);
  // Constant noise: the slope near 0, the intercept the noise. fit() measures it on its own residuals.
  const auto constant = fit(LocalizationModel::kPinhole, synthesize(truth, 2000, 0.2, 9), testIntrinsics());
  ASSERT_TRUE(constant.has_value()) << constant.error().message;
  EXPECT_NEAR(constant->noise_std_m + 5.0 * constant->noise_std_per_m, 0.2, 0.03);
  // No samples: not measured.
  LocalizationParams none = truth;
  fitNoise(none, {});
  EXPECT_EQ(none.noise_std_m, 0.0);
  EXPECT_EQ(none.noise_std_per_m, 0.0);
}

TEST(LocalizationModelNames, ParseAndPrint) {
  EXPECT_EQ(toString(LocalizationModel::kPaper), "paper");
  ASSERT_TRUE(parseLocalizationModel("pinhole"));
  EXPECT_EQ(*parseLocalizationModel("pinhole"), LocalizationModel::kPinhole);
  const auto bad = parseLocalizationModel("linear");
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.error().message, "expected paper or pinhole, got 'linear'");
}

}  // namespace
}  // namespace aerotrack::localization
