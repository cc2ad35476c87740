// KinematicFakeRobot: exact integration without noise, noise statistics, saturation, joint
// limits, determinism per seed, bad commands rejected.

#include "ehc_sim/kinematic_fake_robot.h"

#include <gtest/gtest.h>

#include <cmath>

using ehc_control::BaseType;
using ehc_sim::ActuationNoise;
using ehc_sim::KinematicFakeRobot;

namespace {
ehc_control::RobotConfig robot(BaseType t = BaseType::Differential) {
  auto c = ehc_control::loadRobotConfig(std::string(EHC_CONFIG_DIR) +
                                        "/robots/realman_rm65_water2/robot.yaml");
  c.base_type = t;
  return c;
}
ActuationNoise off() {
  ActuationNoise n;
  n.enabled = false;
  return n;
}
}  // namespace

TEST(KinematicFakeRobot, UnicycleDrivesAnArcExactly) {
  KinematicFakeRobot r(robot(), off(), 1);
  Eigen::VectorXd cmd = Eigen::VectorXd::Zero(8);
  cmd[0] = 0.3;  // m/s
  cmd[1] = 0.5;  // rad/s
  for (int i = 0; i < 200; ++i) r.step(cmd, 0.01);  // 2 s
  // Circle of radius v/w = 0.6 m, heading 1 rad.
  const double R = 0.6, th = 1.0;
  EXPECT_NEAR(r.basePose().x(), R * std::sin(th), 1e-9);
  EXPECT_NEAR(r.basePose().y(), R * (1 - std::cos(th)), 1e-9);
  EXPECT_NEAR(r.basePose().z(), th, 1e-12);
  EXPECT_NEAR(r.time(), 2.0, 1e-12);
}

TEST(KinematicFakeRobot, HolonomicMovesSideways) {
  KinematicFakeRobot r(robot(BaseType::Holonomic), off(), 1);
  r.reset(Eigen::Vector3d(0, 0, M_PI / 2), r.robot().arm_ready, 1);
  Eigen::VectorXd cmd = Eigen::VectorXd::Zero(9);
  cmd[1] = 0.2;  // v_y in the base frame = -x in the world when yaw = 90 deg
  for (int i = 0; i < 100; ++i) r.step(cmd, 0.01);
  EXPECT_NEAR(r.basePose().x(), -0.2, 1e-9);
  EXPECT_NEAR(r.basePose().y(), 0.0, 1e-9);
}

TEST(KinematicFakeRobot, SaturatesAndClampsAtLimits) {
  KinematicFakeRobot r(robot(), off(), 1);
  Eigen::VectorXd cmd = Eigen::VectorXd::Zero(8);
  cmd[0] = 2.0;   // above 0.5 m/s
  cmd[2] = 10.0;  // joint1 above 3.14 rad/s
  r.step(cmd, 0.1);
  EXPECT_NEAR(r.basePose().x(), 0.05, 1e-12);
  EXPECT_NEAR(r.executedVelocity()[2], 3.14, 1e-9);
  EXPECT_EQ(r.saturatedCommands(), 1);
  for (int i = 0; i < 100; ++i) r.step(cmd, 0.1);
  EXPECT_DOUBLE_EQ(r.armPositions()[0], r.robot().arm_upper[0]);
  EXPECT_GT(r.jointLimitClamps(), 0);
  EXPECT_NEAR(r.executedVelocity()[2], 0.0, 1e-12);  // pinned at the limit
}

TEST(KinematicFakeRobot, NoiseHasTheConfiguredSigmaAndIsSeeded) {
  ActuationNoise n;  // Table I defaults
  KinematicFakeRobot a(robot(), n, 7), b(robot(), n, 7), c(robot(), n, 8);
  Eigen::VectorXd cmd = Eigen::VectorXd::Constant(8, 0.1);
  double sum = 0, sum2 = 0, asum2 = 0;
  const int steps = 20000;
  for (int i = 0; i < steps; ++i) {
    if (i % 100 == 0) cmd = -cmd;  // stay away from the joint limits
    a.step(cmd, 0.01);
    b.step(cmd, 0.01);
    c.step(cmd, 0.01);
    const double e = a.executedVelocity()[0] - cmd[0];
    sum += e;
    sum2 += e * e;
    const double ea = a.executedVelocity()[3] - cmd[3];
    asum2 += ea * ea;
    ASSERT_EQ(a.executedVelocity(), b.executedVelocity());  // same seed, same noise
  }
  EXPECT_NEAR(sum / steps, 0.0, 0.003);
  EXPECT_NEAR(std::sqrt(sum2 / steps), 0.05, 0.003);
  EXPECT_NEAR(std::sqrt(asum2 / steps), 0.002, 0.0002);
  EXPECT_NE(a.basePose(), c.basePose());  // other seed, other trajectory
}

TEST(KinematicFakeRobot, ZeroCommandHoldsStill) {
  KinematicFakeRobot r(robot(), ActuationNoise{}, 3);
  const Eigen::VectorXd q0 = r.armPositions();
  for (int i = 0; i < 100; ++i) r.step(Eigen::VectorXd::Zero(8), 0.01);
  EXPECT_EQ(r.basePose(), Eigen::Vector3d::Zero());
  EXPECT_EQ(r.armPositions(), q0);
}

TEST(KinematicFakeRobot, BaseDeadbandStandsStillWhileTheArmMoves) {
  KinematicFakeRobot r(robot(), ActuationNoise{}, 5);
  Eigen::VectorXd cmd = Eigen::VectorXd::Zero(8);
  cmd[0] = 0.004;   // below the 5 mm/s deadband
  cmd[1] = 0.009;   // below the 0.01 rad/s deadband
  cmd[3] = 0.05;    // the arm moves
  const Eigen::VectorXd q0 = r.armPositions();
  for (int i = 0; i < 200; ++i) r.step(cmd, 0.01);
  EXPECT_EQ(r.basePose(), Eigen::Vector3d::Zero());   // no creep, no noise
  EXPECT_NEAR(r.armPositions()[1] - q0[1], 0.1, 0.01);  // arm moved (with its small noise)
  cmd[0] = 0.006;  // above the deadband: the base moves, with noise
  for (int i = 0; i < 200; ++i) r.step(cmd, 0.01);
  EXPECT_GT(r.basePose().head<2>().norm(), 0.0);
}

TEST(KinematicFakeRobot, RejectsBadCommands) {
  KinematicFakeRobot r(robot(), off(), 1);
  EXPECT_THROW(r.step(Eigen::VectorXd::Zero(7), 0.01), std::invalid_argument);
  Eigen::VectorXd nan = Eigen::VectorXd::Zero(8);
  nan[4] = std::nan("");
  EXPECT_THROW(r.step(nan, 0.01), std::invalid_argument);
  EXPECT_THROW(r.step(Eigen::VectorXd::Zero(8), 0.0), std::invalid_argument);
  EXPECT_EQ(r.basePose(), Eigen::Vector3d::Zero());  // state untouched
  ActuationNoise bad;
  bad.arm = -1;
  EXPECT_THROW(KinematicFakeRobot(robot(), bad, 1), std::invalid_argument);
}
