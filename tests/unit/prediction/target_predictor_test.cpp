// Tests of the Bezier target prediction (issue 7, item 1) on synthetic walks fed at 30 Hz with
// white noise of 0.05 m per horizontal axis (about the target estimator's filtered error): a
// straight walk at 1.5 m/s, a constant-rate turn (1.5 m/s on a 4 m radius) and a stop, each
// extrapolated 1.5 s ahead from every frame after the window filled, several seeds. The stated
// errors at 1.5 s ahead (horizontal, metres), checked below:
//   straight: mean <= 0.12, 95th percentile <= 0.20      (measured 0.08 / 0.16)
//   turn:     mean <= 1.10, 95th percentile <= 1.25      (measured 1.02 / 1.14)
//   stop:     standing >= 1 s: mean <= 0.10, p95 <= 0.20 (measured 0.09 / 0.17)
// The turn is the weak case: a straight line along the true velocity would be off by 0.63 m; the
// acceleration regulariser (needed for the straight-walk figure: lambda = 1e-3 s^3 doubles its
// error) straightens the fitted curve over the window, so its end direction lags the turn. While
// braking the prediction overshoots (about 1.6 m mean), printed but not bounded.
// Also: the velocity and acceleration bounds at every hodograph control point (and so on the
// curve), dropouts (keeps extrapolating, data age grows, refused past max_data_age_s), the
// refusals (too few estimates, out of order) and the config section.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "aerotrack/prediction/target_predictor.hpp"
#include "support/require.hpp"

namespace aerotrack::prediction {
namespace {

constexpr double kRateHz = 30.0;
constexpr double kNoiseM = 0.05;
constexpr double kHorizonS = 1.5;

using Path = std::function<Eigen::Vector3d(double t_s)>;

Eigen::Vector3d straight(double t_s) {
  const Eigen::Vector3d direction(std::cos(0.5), std::sin(0.5), 0.0);
  return Eigen::Vector3d(10.0, -20.0, 0.9) + 1.5 * t_s * direction;
}

Eigen::Vector3d turning(double t_s) {
  constexpr double kSpeed = 1.5, kRadius = 4.0;
  const double angle = kSpeed / kRadius * t_s;
  return Eigen::Vector3d(kRadius * std::sin(angle), kRadius * (1.0 - std::cos(angle)), 0.9);
}

constexpr double kWalkS = 4.0;
constexpr double kBrakeMps2 = 1.5;
Eigen::Vector3d stopping(double t_s) {
  constexpr double kSpeed = 1.5;
  if (t_s < kWalkS) return Eigen::Vector3d(kSpeed * t_s, 0.0, 0.9);
  const double tb = std::min(t_s - kWalkS, kSpeed / kBrakeMps2);
  return Eigen::Vector3d(kSpeed * kWalkS + kSpeed * tb - 0.5 * kBrakeMps2 * tb * tb, 0.0, 0.9);
}

rt::TimeNs stampOf(int k) {
  return rt::secondsToNs(static_cast<double>(k) / kRateHz);
}

struct Errors {
  double mean_m = 0.0;
  double p95_m = 0.0;
  double max_m = 0.0;
  int predictions = 0;
};

Errors summarise(std::vector<double> errors) {
  Errors e;
  if (errors.empty()) return e;
  std::sort(errors.begin(), errors.end());
  for (const double v : errors) e.mean_m += v;
  e.mean_m /= static_cast<double>(errors.size());
  e.p95_m = errors[static_cast<std::size_t>(0.95 * static_cast<double>(errors.size() - 1))];
  e.max_m = errors.back();
  e.predictions = static_cast<int>(errors.size());
  return e;
}

/// Feeds `path` from t = 0 to duration_s; from each frame at or after first_eval_s predicts 1.5 s
/// ahead and records the horizontal error against the truth.
Errors run(const Path& path, double duration_s, double first_eval_s, const TargetPredictorParams& params = {}) {
  std::vector<double> errors;
  for (unsigned seed = 1; seed <= 5; ++seed) {
    TargetPredictor predictor = aerotrack::test::require(TargetPredictor::create(params), "TargetPredictor::create");
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> noise(0.0, kNoiseM);
    const int frames = static_cast<int>(duration_s * kRateHz);
    for (int k = 0; k <= frames; ++k) {
      const double t_s = static_cast<double>(k) / kRateHz;
      EXPECT_TRUE(predictor.add(stampOf(k), path(t_s) + Eigen::Vector3d(noise(rng), noise(rng), 0.0)));
      if (t_s < first_eval_s) continue;
      const auto prediction = predictor.predict(stampOf(k));
      EXPECT_TRUE(prediction) << prediction.error().message;
      if (!prediction) continue;
      const rt::TimeNs future_ns = stampOf(k) + rt::secondsToNs(kHorizonS);
      errors.push_back((prediction->position(future_ns) - path(t_s + kHorizonS)).head<2>().norm());
    }
  }
  return summarise(errors);
}

void print(const char* name, const Errors& e) {
  std::printf("%-9s 1.5 s ahead over %d predictions: mean %.3f m, p95 %.3f m, max %.3f m\n", name, e.predictions,
              e.mean_m, e.p95_m, e.max_m);
}

TEST(TargetPredictor, GivenAStraightWalkThenExtrapolatedWithinTwentyCentimetres) {
  const Errors e = run(straight, 8.0, 2.0);
  print("straight", e);
  EXPECT_LE(e.mean_m, 0.12);
  EXPECT_LE(e.p95_m, 0.20);
}

TEST(TargetPredictor, GivenAConstantRateTurnThenExtrapolatedAlongTheTurn) {
  const Errors e = run(turning, 10.0, 2.0);
  print("turn", e);
  EXPECT_LE(e.mean_m, 1.10);
  EXPECT_LE(e.p95_m, 1.25);
}

TEST(TargetPredictor, GivenAStopThenThePredictionStandsStill) {
  const Errors standing = run(stopping, 8.0, kWalkS + 1.0 + 1.0);  // standing since 5 s; from 6 s
  print("stop", standing);
  EXPECT_LE(standing.mean_m, 0.10);
  EXPECT_LE(standing.p95_m, 0.20);
  const Errors braking = run(stopping, kWalkS + 1.0, kWalkS);  // while braking: reported, not bounded
  print("braking", braking);
}

TEST(TargetPredictor, GivenTightBoundsThenEveryHodographControlPointRespectsThem) {
  TargetPredictorParams params;
  params.max_speed_mps = 0.8;  // below the walk's 1.5 m/s along x
  params.max_accel_mps2 = 0.3;
  params.fit_z = true;
  auto predictor = TargetPredictor::create(params);
  ASSERT_TRUE(predictor);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, kNoiseM);
  int checked = 0;
  for (int k = 0; k <= 240; ++k) {
    const double t_s = static_cast<double>(k) / kRateHz;
    ASSERT_TRUE(predictor->add(stampOf(k), turning(t_s) + Eigen::Vector3d(noise(rng), noise(rng), noise(rng))));
    if (k < 30) continue;
    const auto prediction = predictor->predict(stampOf(k));
    ASSERT_TRUE(prediction) << prediction.error().message;
    constexpr double kSlack = 1e-7;
    for (int i = 0; i < prediction->degree; ++i) {
      EXPECT_LE(prediction->velocityControlPoint(i).cwiseAbs().maxCoeff(), params.max_speed_mps + kSlack);
    }
    for (int i = 0; i + 1 < prediction->degree; ++i) {
      EXPECT_LE(prediction->accelerationControlPoint(i).cwiseAbs().maxCoeff(), params.max_accel_mps2 + kSlack);
    }
    // The convex hull property: then the bound holds along the curve too.
    for (int j = 0; j <= 50; ++j) {
      const rt::TimeNs t_ns = prediction->start_ns + (prediction->end_ns - prediction->start_ns) * j / 50;
      EXPECT_LE(prediction->velocity(t_ns).cwiseAbs().maxCoeff(), params.max_speed_mps + kSlack);
      EXPECT_LE(prediction->acceleration(t_ns).cwiseAbs().maxCoeff(), params.max_accel_mps2 + kSlack);
    }
    ++checked;
  }
  EXPECT_EQ(checked, 211);
}

TEST(TargetPredictor, GivenPinToNewestThenTheCurvePassesThroughTheNewestEstimate) {
  TargetPredictorParams params;
  params.pin_to_newest = true;
  auto predictor = TargetPredictor::create(params);
  ASSERT_TRUE(predictor);
  std::mt19937_64 rng(9);
  std::normal_distribution<double> noise(0.0, kNoiseM);
  Eigen::Vector3d newest;
  for (int k = 0; k <= 60; ++k) {
    newest = straight(static_cast<double>(k) / kRateHz) + Eigen::Vector3d(noise(rng), noise(rng), 0.0);
    ASSERT_TRUE(predictor->add(stampOf(k), newest));
  }
  const auto prediction = predictor->predict(stampOf(60));
  ASSERT_TRUE(prediction) << prediction.error().message;
  EXPECT_LT((prediction->position(stampOf(60)) - newest).head<2>().norm(), 1e-9);
}

TEST(TargetPredictor, GivenARunnerWhoBrakesWhenTheVelocityIsPinnedThenTheCurveHasTheEstimatesVelocity) {
  // 4 m/s along x, then braking at 3 m/s^2 from 1 s (issue 21: the fit lags a braking runner). Positions
  // noisy as estimates are, velocities exact (standing in for the Kalman filter's). 0.8 s into the braking
  // the runner is at 1.6 m/s.
  const auto x_at = [](double t_s) {
    const double braking_s = std::clamp(t_s - 1.0, 0.0, 4.0 / 3.0);
    return 4.0 * std::min(t_s, 1.0) + 4.0 * braking_s - 1.5 * braking_s * braking_s;
  };
  const auto v_at = [](double t_s) { return std::max(0.0, 4.0 - 3.0 * std::max(0.0, t_s - 1.0)); };
  const auto velocityAtNewest = [&](bool pinned, double weight = 0.0) {
    TargetPredictorParams params;
    params.max_speed_mps = 6.0;
    params.pin_velocity_to_newest = pinned;
    params.newest_velocity_weight = weight;
    auto predictor = aerotrack::test::require(TargetPredictor::create(params), "predictor");
    std::mt19937_64 rng(4);
    std::normal_distribution<double> noise(0.0, kNoiseM);
    const int last = static_cast<int>(1.8 * kRateHz);
    for (int k = 0; k <= last; ++k) {
      const double t_s = k / kRateHz;
      EXPECT_TRUE(predictor.add(stampOf(k), Eigen::Vector3d(x_at(t_s) + noise(rng), noise(rng), 0.0),
                                Eigen::Vector3d(v_at(t_s), 0.0, 0.0)));
    }
    const auto prediction = aerotrack::test::require(predictor.predict(stampOf(last)), "prediction");
    return prediction.velocity(stampOf(last)).x();
  };
  const double truth_mps = v_at(1.8);
  EXPECT_NEAR(velocityAtNewest(true), truth_mps, 1e-6);
  const double lag_mps = velocityAtNewest(false) - truth_mps;
  std::printf("braking runner at %.2f m/s: the unpinned fit reads %.2f m/s more\n", truth_mps, lag_mps);
  EXPECT_GT(lag_mps, 0.3) << "the lag the pin removes";
  // The soft pull lies between, closer to the estimate as its weight grows.
  const double soft_mps = velocityAtNewest(false, 0.2) - truth_mps;
  const double softer_mps = velocityAtNewest(false, 0.02) - truth_mps;
  EXPECT_GT(soft_mps, 0.0);
  EXPECT_LT(soft_mps, softer_mps);
  EXPECT_LT(softer_mps, lag_mps);
}

TEST(TargetPredictor, GivenADropoutThenKeepsExtrapolatingWithAGrowingDataAge) {
  TargetPredictorParams params;
  auto predictor = TargetPredictor::create(params);
  ASSERT_TRUE(predictor);
  std::mt19937_64 rng(2);
  std::normal_distribution<double> noise(0.0, kNoiseM);
  constexpr int kLastFrame = 90;  // data until 3 s, then nothing
  for (int k = 0; k <= kLastFrame; ++k) {
    ASSERT_TRUE(predictor->add(stampOf(k), straight(k / kRateHz) + Eigen::Vector3d(noise(rng), noise(rng), 0.0)));
  }
  double previous_age_s = -1.0;
  for (const double gap_s : {0.0, 0.5, 1.0, 2.0}) {
    const rt::TimeNs now_ns = stampOf(kLastFrame) + rt::secondsToNs(gap_s);
    const auto prediction = predictor->predict(now_ns);
    ASSERT_TRUE(prediction) << prediction.error().message;
    EXPECT_NEAR(prediction->dataAgeS(), gap_s, 1e-9);
    EXPECT_GT(prediction->dataAgeS(), previous_age_s);
    previous_age_s = prediction->dataAgeS();
    EXPECT_EQ(prediction->end_ns, now_ns + rt::secondsToNs(kHorizonS));
    // The straight walk goes on: the extrapolation stays on it (error grows with the gap).
    const double t_s = kLastFrame / kRateHz + gap_s + kHorizonS;
    const double error_m = (prediction->position(now_ns + rt::secondsToNs(kHorizonS)) - straight(t_s)).head<2>().norm();
    std::printf("dropout %.1f s: error 1.5 s ahead %.3f m\n", gap_s, error_m);
    EXPECT_LT(error_m, 0.15 + 0.15 * gap_s);
  }
  const auto too_old = predictor->predict(stampOf(kLastFrame) + rt::secondsToNs(params.max_data_age_s + 0.1));
  ASSERT_FALSE(too_old);
  EXPECT_NE(too_old.error().message.find("old"), std::string::npos);
}

TEST(TargetPredictor, GivenTooFewOrDisorderedEstimatesThenRefused) {
  auto predictor = TargetPredictor::create({});
  ASSERT_TRUE(predictor);
  EXPECT_FALSE(predictor->predict(0));
  ASSERT_TRUE(predictor->add(stampOf(0), Eigen::Vector3d::Zero()));
  EXPECT_FALSE(predictor->add(stampOf(0), Eigen::Vector3d::Zero()));  // not newer
  EXPECT_FALSE(predictor->add(stampOf(1), Eigen::Vector3d(std::nan(""), 0.0, 0.0)));
  const auto few = predictor->predict(stampOf(1));
  ASSERT_FALSE(few);
  EXPECT_NE(few.error().message.find("1 estimates in the window, need 5"), std::string::npos);
  // The window: after 3 s of data only the last 1.5 s is kept (at 30 Hz: 46 estimates).
  for (int k = 1; k <= 90; ++k) ASSERT_TRUE(predictor->add(stampOf(k), Eigen::Vector3d::Zero()));
  EXPECT_EQ(predictor->sampleCount(), 46u);
}

TEST(TargetPredictorParams, GivenAConfigSectionThenEveryKeyIsRequiredAndChecked) {
  const std::string good =
      "prediction:\n  bezier_degree: 5\n  window_s: 1.5\n  horizon_s: 1.5\n  weight_half_life_s: 0.5\n"
      "  accel_energy_weight_s3: 0.01\n  max_speed_mps: 3.0\n  max_accel_mps2: 3.0\n  fit_z: false\n"
      "  pin_to_newest: false\n  pin_velocity_to_newest: false\n  newest_velocity_weight: 0.0\n  min_samples: 5\n  "
      "max_data_age_s: 3.0\n  max_samples: 128\n"
      "  qp_max_iterations: 100\n";
  const auto parse = [](const std::string& text) {
    const rt::ConfigNode root = aerotrack::test::require(rt::ConfigNode::fromString(text, "cfg.yaml"), "cfg.yaml");
    return rt::parseConfig<TargetPredictorParams>(
        [&root] { return parseTargetPredictorParams(root.child("prediction")); });
  };
  const auto params = parse(good);
  ASSERT_TRUE(params) << params.error().message;
  EXPECT_EQ(params->bezier_degree, 5);
  EXPECT_EQ(params->max_samples, 128);
  EXPECT_TRUE(validate(*params));
  const auto unknown = parse(good + "  horizon_ms: 3\n");
  ASSERT_FALSE(unknown);
  EXPECT_NE(unknown.error().message.find("prediction.horizon_ms: unknown key"), std::string::npos);
  std::string missing = good;
  missing.erase(missing.find("  fit_z"), std::string("  fit_z: false\n").size());
  ASSERT_FALSE(parse(missing));
  EXPECT_NE(parse(missing).error().message.find("prediction.fit_z"), std::string::npos);
  std::string out_of_range = good;
  out_of_range.replace(out_of_range.find("bezier_degree: 5"), 16, "bezier_degree: 12");
  ASSERT_FALSE(parse(out_of_range));
  TargetPredictorParams bad;
  bad.max_samples = 3;  // below min_samples
  EXPECT_FALSE(TargetPredictor::create(bad));
}

}  // namespace
}  // namespace aerotrack::prediction
