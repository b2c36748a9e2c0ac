// The camera-view term (camera_view.hpp, issue 21): the person's torso in the 1-DOF gimbal camera's
// vertical field of view. Its activation against the slow, obvious geometry of a pitched body (a point at
// elevation e seen from a body pitched nose-down by theta appears at e + theta on the optical axis), and its
// gradients against central differences.
#include "aerotrack/planning/camera_view.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>
#include <random>

namespace aerotrack::planning {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// The acceleration that tilts the thrust (body z) by theta towards +x with no vertical acceleration.
Eigen::Vector3d pitchAcceleration(double theta_rad) {
  return Eigen::Vector3d(kGravityMps2 * std::tan(theta_rad), 0.0, 0.0);
}

double viewCost(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& h, double half_m,
                double sin_limit, CameraViewGradient* gradient = nullptr) {
  double cost = 0.0;
  CameraViewGradient g;
  addCameraViewTerm(p, a, h, half_m, sin_limit, 1.0, cost, g);
  if (gradient != nullptr) *gradient = g;
  return cost;
}

TEST(CameraView, IsActiveExactlyWhenATorsoEndLeavesTheTiltedFieldOfView) {
  const double limit_rad = 35.0 * kDeg;
  const Eigen::Vector3d drone(0.0, 0.0, 1.5);
  for (const double distance_m : {1.0, 1.5, 2.5, 4.0}) {
    for (const double pitch_deg : {-30.0, -20.0, -10.0, 0.0, 10.0, 20.0, 30.0}) {
      const Eigen::Vector3d centre(distance_m, 0.0, 1.1);  // torso centre 1.1 m high, half length 0.25 m
      // The slow way: each torso end's elevation plus the pitch (nose down by theta looks down by theta).
      const double hips_rad = std::atan2(0.85 - 1.5, distance_m) + pitch_deg * kDeg;
      const double shoulders_rad = std::atan2(1.35 - 1.5, distance_m) + pitch_deg * kDeg;
      const bool outside = hips_rad < -limit_rad || shoulders_rad > limit_rad;
      const double cost = viewCost(drone, pitchAcceleration(pitch_deg * kDeg), centre, 0.25, std::sin(limit_rad));
      EXPECT_EQ(cost > 0.0, outside) << distance_m << " m, pitch " << pitch_deg << " deg";
    }
  }
  // Braking (nose up 26 deg) with the person 1.5 m ahead: the hips leave the bottom of the image.
  EXPECT_GT(viewCost(drone, pitchAcceleration(-26.0 * kDeg), Eigen::Vector3d(1.5, 0.0, 1.1), 0.25, std::sin(limit_rad)),
            0.0);
}

TEST(CameraView, GradientsMatchCentralDifferences) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int checked = 0;
  for (int trial = 0; trial < 200 && checked < 40; ++trial) {
    const Eigen::Vector3d p(u(rng), u(rng), 1.5 + 0.5 * u(rng));
    const Eigen::Vector3d a(6.0 * u(rng), 6.0 * u(rng), 3.0 * u(rng));
    const Eigen::Vector3d h(1.5 + u(rng), u(rng), 1.1 + 0.2 * u(rng));
    const double sin_limit = std::sin(25.0 * kDeg);
    CameraViewGradient g;
    if (!(viewCost(p, a, h, 0.25, sin_limit, &g) > 1e-9)) continue;
    ++checked;
    const auto check = [&](const Eigen::Vector3d& analytic, const std::function<double(const Eigen::Vector3d&)>& f,
                           const Eigen::Vector3d& x, const char* name) {
      for (int k = 0; k < 3; ++k) {
        const double step = 1e-6;
        Eigen::Vector3d plus = x;
        Eigen::Vector3d minus = x;
        plus(k) += step;
        minus(k) -= step;
        const double fd = (f(plus) - f(minus)) / (2.0 * step);
        EXPECT_NEAR(analytic(k), fd, 1e-5 * std::max(1.0, std::abs(fd))) << name << " axis " << k << " trial " << trial;
      }
    };
    check(
        g.p, [&](const Eigen::Vector3d& x) { return viewCost(x, a, h, 0.25, sin_limit); }, p, "d/dp");
    check(
        g.a, [&](const Eigen::Vector3d& x) { return viewCost(p, x, h, 0.25, sin_limit); }, a, "d/da");
    check(
        g.person, [&](const Eigen::Vector3d& x) { return viewCost(p, a, x, 0.25, sin_limit); }, h, "d/dperson");
  }
  EXPECT_GE(checked, 20) << "the term must be active at enough test points";
}

TEST(CameraView, DegenerateGeometryAddsNothing) {
  double cost = 0.0;
  CameraViewGradient g;
  // Free fall (no thrust direction) and a person at the camera.
  EXPECT_FALSE(addCameraViewTerm(Eigen::Vector3d(0, 0, 1.5), Eigen::Vector3d(0, 0, -kGravityMps2),
                                 Eigen::Vector3d(1, 0, 1.1), 0.25, 0.5, 1.0, cost, g));
  EXPECT_FALSE(addCameraViewTerm(Eigen::Vector3d(0, 0, 1.1), Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, 1.1), 0.0,
                                 0.5, 1.0, cost, g));
  EXPECT_EQ(cost, 0.0);
  EXPECT_TRUE(g.p.isZero() && g.a.isZero() && g.person.isZero());
}

}  // namespace
}  // namespace aerotrack::planning
