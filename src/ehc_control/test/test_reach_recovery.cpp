// ReachRecovery's far stalls: an approach that makes no progress farther than twice the ready
// pose's reach from the target brings the arm back to ready while the base drives to where the
// ready TCP is over the target, on random targets in every direction (seed printed); far plans
// have their own attempt count, so the near (joint-limit) recoveries stay available.

#include "ehc_control/qp_controller.h"
#include "ehc_control/reach_recovery.h"
#include "ehc_test/control_fixtures.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <random>

using namespace ehc_control;

namespace {

constexpr double kDt = 0.02;  // s, the recovery's cycle here

/// The TCP of (base, q): the recovery sees it; a stalled approach keeps it in place.
Eigen::Isometry3d tcpOf(const WholeBodyModel& m, const Eigen::Vector3d& base, const Eigen::VectorXd& q) {
  return m.fk(base, q, m.config().tcp_frame);
}

}  // namespace

TEST(ReachRecovery, AFarStallDrivesTheBaseToTheTargetWithTheArmAtReady) {
  const WholeBodyModel model(test::realmanConfig());
  const RobotConfig& rc = model.config();
  const QpControllerParams qp;
  const char* given = std::getenv("EHC_TEST_SEED");  // reruns a printed seed
  const unsigned seed = given ? static_cast<unsigned>(std::stoul(given)) : std::random_device{}();
  std::cout << "[ReachRecovery test] seed " << seed << std::endl;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI), dist(3.0, 7.0), height(0.3, 1.0);
  for (int trial = 0; trial < 10; ++trial) {
    SCOPED_TRACE("trial " + std::to_string(trial) + ", seed " + std::to_string(seed));
    ReachRecovery rec(model, qp.recovery, qp.joint_stop, qp.joint_influence);
    test::KinematicSim sim;
    sim.base = test::randomBase(rng);
    sim.q = test::randomArm(rc, rng, 0.3);
    Eigen::Vector3d& base = sim.base;
    Eigen::VectorXd& q = sim.q;
    const double a = angle(rng), d = dist(rng);
    const Eigen::Vector3d approach(std::cos(angle(rng)), std::sin(angle(rng)), 0.5 - height(rng));
    const Eigen::Isometry3d target =
        test::approachPose(base.x() + d * std::cos(a), base.y() + d * std::sin(a), height(rng), approach.normalized());
    // A stalled approach: the state does not change; the recovery must start after stall_window.
    const Eigen::VectorXd* ref = nullptr;
    double t = 0.0;
    for (; t < qp.recovery.stall_window + 0.1 && !ref; t += kDt)
      ref = rec.update(t, base, q, tcpOf(model, base, q), target);
    ASSERT_NE(ref, nullptr) << "no recovery after the stall window";
    EXPECT_NE(rec.event().find("far attempt 1"), std::string::npos) << rec.event();
    EXPECT_EQ(rec.attempts(), 0) << "a far plan must not use a near attempt";
    EXPECT_TRUE(rec.goalArm().isApprox(rc.arm_ready));
    // The goal: the ready TCP over the target.
    const Eigen::Vector3d ready_tcp = tcpOf(model, rec.goalBase(), rc.arm_ready).translation();
    EXPECT_LT((ready_tcp.head<2>() - target.translation().head<2>()).norm(), 1e-6);
    // Closed loop on the reference: the move ends at that goal, within its tolerances.
    const double start = t;
    while (ref && t < start + 60.0) {  // the move ends by itself (arrival or its time limit)
      sim.step(model, *ref, kDt);
      if (std::getenv("EHC_TRACE") && std::fmod(t, 1.0) < kDt)
        std::cout << "t " << t << " base " << base.transpose() << " goal " << rec.goalBase().transpose()
                  << " ref " << ref->head(2).transpose() << "\n";
      t += kDt;
      ref = rec.update(t, base, q, tcpOf(model, base, q), target);
    }
    EXPECT_EQ(ref, nullptr) << "the move did not end";
    EXPECT_EQ(rec.event(), "recovery configuration reached");
    const Eigen::Vector3d tcp = tcpOf(model, base, q).translation();
    EXPECT_LT((tcp.head<2>() - target.translation().head<2>()).norm(), qp.recovery.position_tolerance + 0.05)
        << "the ready TCP did not arrive over the target";
    EXPECT_LT((q - rc.arm_ready).cwiseAbs().maxCoeff(), qp.recovery.joint_tolerance);
  }
}

TEST(ReachRecovery, AFarStallWithTheArmAtReadyStartsNothing) {
  const WholeBodyModel model(test::realmanConfig());
  const QpControllerParams qp;
  ReachRecovery rec(model, qp.recovery, qp.joint_stop, qp.joint_influence);
  const Eigen::Vector3d base = Eigen::Vector3d::Zero();
  const Eigen::VectorXd q = model.config().arm_ready;
  const Eigen::Isometry3d target = test::approachPose(5.0, 0.0, 0.7, Eigen::Vector3d(1.0, 0.0, 0.0));
  for (double t = 0.0; t < 3.0 * qp.recovery.stall_window; t += kDt)
    EXPECT_EQ(rec.update(t, base, q, tcpOf(model, base, q), target), nullptr) << "t " << t;
}
