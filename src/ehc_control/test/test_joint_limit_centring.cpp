// Joint-limit centring (the QP cost term against joint-limit traps) and the unwound bearing of
// the base-turn term.

#include "ehc_control/joint_limit_centring.h"
#include "ehc_control/qp_controller.h"
#include "ehc_control/robot_config.h"

#include <gtest/gtest.h>

#include <random>

using namespace ehc_control;

namespace {
const Eigen::VectorXd kLower = (Eigen::VectorXd(3) << -3.0, -2.0, -6.0).finished();
const Eigen::VectorXd kUpper = (Eigen::VectorXd(3) << 3.0, 2.0, 6.0).finished();
}  // namespace

TEST(JointLimitCentring, GradientMatchesThePotentialNumerically) {
  const JointLimitCentring c{0.7, 0.9, 0.1};
  std::mt19937 rng(5);
  int active = 0;
  for (int trial = 0; trial < 200; ++trial) {
    // Positions anywhere between the stops, many of them inside the influence zone.
    Eigen::VectorXd q(3);
    for (int i = 0; i < 3; ++i)
      q[i] = std::uniform_real_distribution<double>(kLower[i] + 0.1 + 1e-4, kUpper[i] - 0.1 - 1e-4)(rng);
    if (trial % 2 == 0) q[trial % 3] = kUpper[trial % 3] - std::uniform_real_distribution<double>(0.11, 0.89)(rng);
    const Eigen::VectorXd g = c.gradient(q, kLower, kUpper);
    for (int i = 0; i < 3; ++i) {
      const double h = 1e-6;
      Eigen::VectorXd qp = q, qm = q;
      qp[i] += h;
      qm[i] -= h;
      const double numeric = (c.potential(qp, kLower, kUpper) - c.potential(qm, kLower, kUpper)) / (2 * h);
      EXPECT_NEAR(g[i], numeric, 1e-6) << "joint " << i << " at " << q[i];
      active += g[i] != 0.0;
    }
  }
  EXPECT_GT(active, 50);  // the check covered the active zone
}

TEST(JointLimitCentring, ZeroOutsideTheInfluenceGainAtTheStopPushingAway) {
  const JointLimitCentring c{0.5, 0.9, 0.1};
  Eigen::VectorXd q = Eigen::VectorXd::Zero(3);
  EXPECT_TRUE(c.gradient(q, kLower, kUpper).isZero());
  EXPECT_EQ(c.potential(q, kLower, kUpper), 0.0);
  q << -3.0 + 0.1, 2.0 - 0.1, 6.0 - 0.5;
  const Eigen::VectorXd g = c.gradient(q, kLower, kUpper);
  // Minimising C^T qd with C = g moves each joint along -g: away from its limit.
  EXPECT_NEAR(g[0], -0.5, 1e-12);  // at the lower stop: push up
  EXPECT_NEAR(g[1], 0.5, 1e-12);   // at the upper stop: push down
  EXPECT_NEAR(g[2], 0.5 * 0.25, 1e-12);  // halfway through the zone: u = 0.5, gain u^2
  // Beyond the stop the push keeps its full size.
  q[0] = -3.0 + 0.05;
  EXPECT_NEAR(c.gradient(q, kLower, kUpper)[0], -0.5, 1e-12);
  // Off: nothing.
  EXPECT_TRUE((JointLimitCentring{0.0, 0.9, 0.1}.gradient(q, kLower, kUpper).isZero()));
}

TEST(BaseTurnBearing, TakesTheBranchOfTheYawJointWinding) {
  // Arm forward: the plain bearing.
  EXPECT_DOUBLE_EQ(unwoundBearing(0.3, 0.0), 0.3);
  EXPECT_DOUBLE_EQ(unwoundBearing(-3.0, 0.0), -3.0);
  // Yaw joint wound to -3 rad (TCP behind, atan2 just across the cut at +3.05): the base must
  // turn the negative way, which unwinds the joint, not the short positive way into its limit.
  EXPECT_NEAR(unwoundBearing(3.05, -3.0), 3.05 - 2 * M_PI, 1e-12);
  EXPECT_NEAR(unwoundBearing(-3.05, 3.0), -3.05 + 2 * M_PI, 1e-12);
}

TEST(BaseTurnBearing, FindsTheRealManYawJoint) {
  const WholeBodyModel model(loadRobotConfig(std::string(EHC_CONFIG_DIR) + "/robots/realman_rm65_water2/robot.yaml"));
  EXPECT_EQ(armYawJoint(model), 0);
}
