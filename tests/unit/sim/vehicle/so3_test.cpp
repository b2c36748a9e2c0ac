// The SO(3) helpers (hal/sim/so3.hpp) against Eigen's angle-axis rotations, each other, and finite
// differences of the exponential map.
#include <gtest/gtest.h>

#include <cmath>

#include <Eigen/Geometry>

#include "aerotrack/hal/sim/so3.hpp"

namespace aerotrack::hal::sim {
namespace {

double orthonormalityError(const Eigen::Matrix3d& R) {
  return (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
}

Eigen::Matrix3d angleAxis(const Eigen::Vector3d& phi) {
  const double angle = phi.norm();
  if (angle == 0.0) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, phi / angle).toRotationMatrix();
}

TEST(So3, GivenRotationVectorsWhenExponentiatedThenMatchEigenAngleAxis) {
  // Tolerance 1e-14: both are exact up to rounding.
  for (const Eigen::Vector3d& phi :
       {Eigen::Vector3d(0.3, -0.2, 0.1), Eigen::Vector3d(2.0, 1.0, -2.5), Eigen::Vector3d(1e-9, -2e-9, 3e-9),
        Eigen::Vector3d(0.0, 0.0, M_PI), Eigen::Vector3d(1e-4, 0.0, 0.0)}) {
    const Eigen::Matrix3d R = so3::expMap(phi);
    EXPECT_LT((R - angleAxis(phi)).cwiseAbs().maxCoeff(), 1e-14) << phi.transpose();
    EXPECT_LT(orthonormalityError(R), 1e-14);
  }
}

TEST(So3, GivenRotationVectorWhenExponentiatedThenDerivativeMatchesFiniteDifference) {
  // d/dt exp(t [phi]x) = exp(t [phi]x) [phi]x; central difference h = 1e-5, error O(h^2): tolerance 1e-8.
  const Eigen::Vector3d phi(0.7, -1.1, 0.4);
  const double t = 0.8;
  const double h = 1e-5;
  const Eigen::Matrix3d numeric = (so3::expMap((t + h) * phi) - so3::expMap((t - h) * phi)) / (2.0 * h);
  const Eigen::Matrix3d analytic = so3::expMap(t * phi) * so3::hat(phi);
  EXPECT_LT((numeric - analytic).cwiseAbs().maxCoeff(), 1e-8);
}

TEST(So3, GivenRotationWhenLoggedThenExpOfLogIsTheRotation) {
  // Tolerance 1e-12 on the rotation vector away from pi, 1e-7 next to pi (the axis comes from a
  // square-root-like conditioning there).
  for (const Eigen::Vector3d& phi : {Eigen::Vector3d(0.3, -0.2, 0.1), Eigen::Vector3d(1e-9, 2e-9, 0.0),
                                     Eigen::Vector3d(Eigen::Vector3d(-1.0, 2.0, 0.5).normalized() * 3.0)}) {
    EXPECT_LT((so3::logMap(so3::expMap(phi)) - phi).norm(), 1e-12) << phi.transpose();
  }
  const Eigen::Vector3d near_pi = Eigen::Vector3d(1.0, -2.0, 0.5).normalized() * (M_PI - 1e-9);
  const Eigen::Vector3d log_near_pi = so3::logMap(so3::expMap(near_pi));
  EXPECT_LT((so3::expMap(log_near_pi) - so3::expMap(near_pi)).cwiseAbs().maxCoeff(), 1e-7);
  EXPECT_NEAR(log_near_pi.norm(), M_PI - 1e-9, 1e-7);
}

TEST(So3, GivenDriftedMatrixWhenReorthonormalizedThenOrthonormalAndClose) {
  // A rotation perturbed by 1e-8: the result is orthonormal to 1e-15 and within 1e-7 of the input.
  Eigen::Matrix3d R = so3::expMap(Eigen::Vector3d(0.4, 1.2, -0.7));
  Eigen::Matrix3d drift;
  drift << 1, -2, 3, 0.5, 1, -1, 2, 0, -3;
  R += 1e-8 * drift;
  const Eigen::Matrix3d fixed = so3::reorthonormalize(R);
  EXPECT_LT(orthonormalityError(fixed), 1e-15);
  EXPECT_GT(fixed.determinant(), 0.0);
  EXPECT_LT((fixed - R).cwiseAbs().maxCoeff(), 1e-7);
}

}  // namespace
}  // namespace aerotrack::hal::sim
