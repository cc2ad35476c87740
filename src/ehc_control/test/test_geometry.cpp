// Rotation helpers (geometry.h). rotationAngle is the one formula behind the grasp generator's
// non-maximum suppression and the grasp sequencer's orientation checks; the two formulas those
// used before (written out below) give the same bits on rotations.
#include "ehc_control/pose_math.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

using ehc_control::rotationAngle;

namespace {

/// The grasp sequencer's former formula.
double halvedThenClamped(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  const double c = std::clamp(((a.transpose() * b).trace() - 1.0) / 2.0, -1.0, 1.0);
  return std::acos(c);
}

/// The grasp generator's former formula.
double scaledThenMinMax(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  const double c = 0.5 * ((a.transpose() * b).trace() - 1.0);
  return std::acos(std::max(-1.0, std::min(1.0, c)));
}

Eigen::Matrix3d randomRotation(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized().toRotationMatrix();
}

}  // namespace

TEST(RotationAngle, IsTheAngleOfTheRelativeRotation) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> angle(0.0, M_PI);
  for (int i = 0; i < 1000; ++i) {
    const Eigen::Matrix3d a = randomRotation(rng);
    const double th = angle(rng);
    const Eigen::Vector3d axis = randomRotation(rng).col(0);
    const Eigen::Matrix3d b = a * Eigen::AngleAxisd(th, axis).toRotationMatrix();
    EXPECT_NEAR(rotationAngle(a, b), th, 1e-6) << "trial " << i;
    EXPECT_NEAR(rotationAngle(b, a), th, 1e-6) << "trial " << i;
  }
  const Eigen::Matrix3d r = randomRotation(rng);
  EXPECT_EQ(rotationAngle(r, r), rotationAngle(r, r));
  EXPECT_LT(rotationAngle(r, r), 1e-7);
  const Eigen::Matrix3d half_turn = r * Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  EXPECT_NEAR(rotationAngle(r, half_turn), M_PI, 1e-7);
}

TEST(RotationAngle, AgreesBitForBitWithBothFormerFormulas) {
  // Random pairs, pairs close to each other and close to a half turn apart (where the cosine
  // is clamped), and the generator's half-turn-flipped products.
  std::mt19937 rng(11);
  std::normal_distribution<double> tiny(0.0, 1e-7);
  const Eigen::Matrix3d flip = Eigen::Vector3d(-1, -1, 1).asDiagonal();
  int compared = 0;
  for (int i = 0; i < 20000; ++i) {
    const Eigen::Matrix3d a = randomRotation(rng);
    Eigen::Matrix3d b;
    switch (i % 4) {
      case 0: b = randomRotation(rng); break;
      case 1: b = a * Eigen::AngleAxisd(tiny(rng), randomRotation(rng).col(0)).toRotationMatrix(); break;
      case 2: b = a * Eigen::AngleAxisd(M_PI + tiny(rng), randomRotation(rng).col(0)).toRotationMatrix(); break;
      default: b = a * flip; break;
    }
    const double angle = rotationAngle(a, b);
    ASSERT_EQ(angle, halvedThenClamped(a, b)) << "trial " << i;
    ASSERT_EQ(angle, scaledThenMinMax(a, b)) << "trial " << i;
    ASSERT_NEAR(angle, scaledThenMinMax(a, b), 1e-12) << "trial " << i;
    ++compared;
  }
  EXPECT_EQ(compared, 20000);
}

TEST(RotationAngle, NotANumberInNotANumberOut) {
  // The one input where the former formulas differed: min/max turned a NaN cosine into 1
  // (angle 0), the clamp keeps it NaN. Neither caller passes NaN (both check their rotations).
  Eigen::Matrix3d bad = Eigen::Matrix3d::Identity();
  bad(0, 0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(std::isnan(rotationAngle(bad, Eigen::Matrix3d::Identity())));
  EXPECT_EQ(scaledThenMinMax(bad, Eigen::Matrix3d::Identity()), 0.0);
}
