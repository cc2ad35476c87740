// The one quaternion -> yaw / rotation conversion (pose_math.h): random yaws round-trip through
// a quaternion; a tilted rotation gives the yaw of its z-y-x Euler angles; a non-unit (beyond
// kQuaternionNormTolerance), all-zero or non-finite quaternion is rejected (NaN), a unit one
// off by float rounding is not.

#include "ehc_control/pose_math.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace ehc_control {
namespace {

Eigen::Quaterniond yawQuaternion(double yaw) { return Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ())); }

TEST(PoseMath, RandomYawsRoundTrip) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-M_PI, M_PI);
  for (int i = 0; i < 1000; ++i) {
    const double yaw = u(rng);
    EXPECT_NEAR(yawFromQuaternion(yawQuaternion(yaw)), yaw, 1e-12) << yaw;
    // -q is the same rotation.
    const Eigen::Quaterniond q = yawQuaternion(yaw);
    EXPECT_NEAR(yawFromQuaternion(Eigen::Quaterniond(-q.w(), -q.x(), -q.y(), -q.z())), yaw, 1e-12) << yaw;
  }
}

TEST(PoseMath, YawOfATiltedRotationIsItsZyxEulerYaw) {
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(-0.3, Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  EXPECT_NEAR(yawFromQuaternion(Eigen::Quaterniond(R)), 0.7, 1e-12);
  EXPECT_NEAR(yawFromQuaternion(Eigen::Quaterniond(R)), std::atan2(R(1, 0), R(0, 0)), 1e-12);
}

TEST(PoseMath, NonUnitAndNonFiniteQuaternionsAreRejected) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (const Eigen::Quaterniond& q : {Eigen::Quaterniond(0, 0, 0, 0), Eigen::Quaterniond(2, 0, 0, 0),
                                      Eigen::Quaterniond(1.0 + 2 * kQuaternionNormTolerance, 0, 0, 0),
                                      Eigen::Quaterniond(0.5, 0.5, 0.5, 0.0), Eigen::Quaterniond(nan, 0, 0, 1),
                                      Eigen::Quaterniond(0, 0, inf, 0)}) {
    EXPECT_FALSE(isRotationQuaternion(q)) << q.coeffs().transpose();
    EXPECT_TRUE(std::isnan(yawFromQuaternion(q))) << q.coeffs().transpose();
    EXPECT_TRUE(rotationFromQuaternion(q).array().isNaN().all()) << q.coeffs().transpose();
  }
}

TEST(PoseMath, AUnitQuaternionOffByRoundingIsARotation) {
  const Eigen::Quaterniond q = yawQuaternion(1.2);
  const Eigen::Quaterniond f(static_cast<float>(q.w()), 0.0, 0.0, static_cast<float>(q.z()));  // a float message
  const Eigen::Quaterniond scaled(q.coeffs() * (1.0 + 0.5 * kQuaternionNormTolerance));
  for (const Eigen::Quaterniond& p : {f, scaled}) {
    EXPECT_TRUE(isRotationQuaternion(p));
    EXPECT_NEAR(yawFromQuaternion(p), 1.2, 1e-3);
    const Eigen::Matrix3d R = rotationFromQuaternion(p);
    EXPECT_NEAR((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-12);  // normalised
    EXPECT_NEAR(R.determinant(), 1.0, 1e-12);
  }
  EXPECT_TRUE(rotationFromQuaternion(q).isApprox(q.toRotationMatrix(), 1e-15));
}

}  // namespace
}  // namespace ehc_control
