// WristFlip: flip triples found on the RealMan (joint4..joint6) and the 7-DOF test arm, the
// flipped configuration keeps the TCP pose, and in closed loop the QP with the flip reaches a
// target whose orientation needs joint4 beyond its limit on the current branch, where the QP
// alone stays pinned (the Exp-1 trap).

#include "ehc_control/pose_servo.h"
#include "ehc_control/qp_controller.h"
#include "ehc_control/wrist_flip.h"
#include "ehc_test/control_fixtures.h"

#include <gtest/gtest.h>

using namespace ehc_control;

namespace {

std::string arm7Yaml() { return std::string(EHC_TEST_FIXTURES_DIR) + "/robots/arm7_differential/robot.yaml"; }

struct LoopResult {
  double arrival_s = -1.0;  ///< -1: not within the limit
  int flip_cycles = 0;
  int flips_started = 0;
  double min_margin = 1e9;  ///< rad, to any arm joint limit
};

/// 100 Hz closed loop, noise-free, until arrival (1 cm, 2 deg) or `limit_s`.
LoopResult run(EhcQpController& ctrl, test::KinematicSim& sim, const Eigen::Isometry3d& target, double limit_s) {
  const WholeBodyModel& m = ctrl.model();
  const RobotConfig& rc = m.config();
  LoopResult r;
  for (int k = 0; k < static_cast<int>(limit_s * 100); ++k) {
    const Eigen::Isometry3d tcp = m.fk(sim.base, sim.q, rc.tcp_frame);
    const Vector6d e = poseError(tcp, target);
    if (e.head<3>().norm() < 0.01 && e.tail<3>().norm() < 2.0 * M_PI / 180.0) {
      r.arrival_s = k * 0.01;
      return r;
    }
    const ControllerCommand c = ctrl.step(sim.base, sim.q, target, proportionalPoseServo(tcp, target, PoseServoParams{}));
    EXPECT_EQ(c.qp_status, QpStatus::Ok) << c.failure;
    EXPECT_TRUE((c.velocity.cwiseAbs().array() <= rc.velocityLimits().array() + 1e-12).all());
    if (!c.ok) return r;
    r.flip_cycles += c.wrist_flip;
    r.flips_started += !c.event.empty();
    sim.step(m, c.velocity, 0.01);
    r.min_margin = std::min(r.min_margin, std::min((sim.q - rc.arm_lower).minCoeff(), (rc.arm_upper - sim.q).minCoeff()));
  }
  return r;
}

}  // namespace

TEST(WristFlip, FindsTheSphericalWristTriples) {
  const WholeBodyModel realman(test::realmanConfig());
  EXPECT_EQ(findFlipTriples(realman), std::vector<int>({3}));  // joint4, joint5, joint6
  // iiwa kinematics: every roll-bend-roll triple (shoulder, elbow, wrist).
  const WholeBodyModel arm7(loadRobotConfig(arm7Yaml()));
  EXPECT_EQ(findFlipTriples(arm7), std::vector<int>({0, 2, 4}));
}

TEST(WristFlip, FlippedConfigurationKeepsTheTcpPoseAndGainsMargin) {
  const RobotConfig rc = test::realmanConfig();
  const WholeBodyModel model(rc);
  const WristFlip flip(model, WristFlipParams{});
  std::mt19937 rng(3);
  for (int trial = 0; trial < 50; ++trial) {
    Eigen::VectorXd q = test::randomArm(rc, rng, 0.1);
    q[3] = (trial % 2 ? 1.0 : -1.0) * (rc.arm_upper[3] - 0.2);  // joint4 0.2 rad from a limit
    double after = 0.0;
    const Eigen::Vector3d g = flip.flipped(q, 3, &after);
    Eigen::VectorXd f = q;
    f.segment<3>(3) = g;
    EXPECT_TRUE(model.linkPoseInBase(q, rc.tcp_frame).isApprox(model.linkPoseInBase(f, rc.tcp_frame), 1e-9));
    EXPECT_NEAR(std::abs(g[0]), M_PI - (rc.arm_upper[3] - 0.2), 1e-12);  // joint4 near the middle
    EXPECT_NEAR(g[1], -q[4], 1e-12);
    EXPECT_GE(after, std::min(q[4] - rc.arm_lower[4], rc.arm_upper[4] - q[4]) - 1e-12);
    EXPECT_TRUE((f.array() >= rc.arm_lower.array()).all() && (f.array() <= rc.arm_upper.array()).all());
  }
}

TEST(WristFlip, ParamsValidateAndOffFindsNothing) {
  WristFlipParams p;
  EXPECT_NO_THROW(p.validate());
  p.speed = 0.0;
  EXPECT_NE(test::errorOf([&] { p.validate(); }).find("[WristFlipParams]"), std::string::npos);
  WristFlipParams off;
  off.margin = 0.0;
  const WholeBodyModel model(test::realmanConfig());
  EXPECT_TRUE(WristFlip(model, off).triples().empty());
  EXPECT_EQ(off.summary(), "wrist flip: off");
}

TEST(WristFlip, ClosedLoopEscapesTheForearmRollTrapThatPinsTheQpAlone) {
  // A trapped state of Exp-1 (seed 1, set 0, target 46, ehc, sequence protocol, 6 s into the
  // trial, before this escape existed): joint4 pinned 0.1 rad from its upper limit, the TCP
  // 9 cm and 4 deg from the target; the QP alone stayed there for the remaining 24 s.
  auto model = std::make_shared<const WholeBodyModel>(test::realmanConfig());
  const RobotConfig& rc = model->config();
  auto weighting = std::make_shared<const EhcWeighting>(
      std::make_shared<const ReachabilityMap>(ReachabilityMap::load(rc.reachability_map_path)), EhcWeightingParams{});
  const Eigen::Vector3d base0(-13.9384, -2.28438, -1.12904);
  Eigen::VectorXd q0(6);
  q0 << 0.10756, -0.622439, -1.69422, 3.00521, 0.38587, -2.07912;
  Eigen::Isometry3d target = Eigen::Isometry3d::Identity();
  target.translation() << -13.76077788, -2.789582649, 0.6865048606;
  target.linear() = Eigen::Quaterniond(-0.0006379327063, -0.5467659214, 0.8089216713, -0.216084127).normalized().toRotationMatrix();

  QpControllerParams p;  // defaults: mode ehc, flip on
  QpControllerParams no_flip = p;
  no_flip.wrist_flip.margin = 0.0;
  {
    EhcQpController ctrl(model, no_flip, weighting);
    test::KinematicSim sim{base0, q0};
    const LoopResult r = run(ctrl, sim, target, 15.0);
    EXPECT_LT(r.arrival_s, 0.0) << "the QP alone reached it: the scenario no longer shows the trap";
    EXPECT_EQ(r.flip_cycles, 0);
    EXPECT_LT(rc.arm_upper[3] - sim.q[3], 0.15);  // joint4 still pinned at its limit
  }
  {
    EhcQpController ctrl(model, p, weighting);
    test::KinematicSim sim{base0, q0};
    const LoopResult r = run(ctrl, sim, target, 15.0);
    EXPECT_GT(r.arrival_s, 0.0);
    EXPECT_EQ(r.flips_started, 1);
    EXPECT_GT(r.flip_cycles, 0);
    EXPECT_GT(r.min_margin, p.joint_stop - 1e-3);
    EXPECT_LT(std::abs(sim.q[3]), 1.0);  // arrived on the other wrist branch
    EXPECT_EQ(ctrl.wristFlip().flips(), 1);
    std::printf("arrived in %.2f s, %d flip cycles\n", r.arrival_s, r.flip_cycles);
  }
}
