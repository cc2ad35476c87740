// ReachExperiment (Exp-1 in-process): determinism, safety over a run, and the DMCG property:
// on the same targets, once the target is within the arm's reach EHC's base moves clearly less
// than NEO(e)'s (the arm takes over).

#include "ehc_bringup/reach_experiment.h"
#include "ehc_bringup/reach_targets.h"
#include "ehc_common/config_node.h"

#include <gtest/gtest.h>

using namespace ehc_bringup;

namespace {

struct ExpSetup {
  std::shared_ptr<const ehc_control::WholeBodyModel> model;
  std::shared_ptr<const ehc_control::EhcWeighting> weighting;
  ehc_control::QpControllerParams ctrl;
  ReachExperimentParams params;
  std::vector<std::vector<Eigen::Isometry3d>> sets;
};

ExpSetup makeSetup(int points, int n_sets = 1) {
  ExpSetup s;
  const auto rc = ehc_control::loadRobotConfig(std::string(EHC_CONFIG_DIR) + "/robots/realman_rm65_water2/robot.yaml");
  s.model = std::make_shared<const ehc_control::WholeBodyModel>(rc);
  const auto cfg = ehc_common::ConfigNode::loadFile(std::string(EHC_CONFIG_DIR) + "/control/controller.yaml", "test");
  s.ctrl = ehc_control::loadQpControllerParams(cfg.child("controller"));
  s.params.servo = ehc_control::loadPoseServoParams(cfg.child("servo"));
  s.weighting = std::make_shared<const ehc_control::EhcWeighting>(
      std::make_shared<const ehc_control::ReachabilityMap>(ehc_control::ReachabilityMap::load(rc.reachability_map_path)),
      ehc_control::loadEhcWeightingParams(cfg.child("weighting")));
  auto reachable = [&](const Eigen::Isometry3d& T) { return kinematicallyReachable(*s.model, T, s.ctrl.joint_stop); };
  for (int k = 0; k < n_sets; ++k)
    s.sets.push_back(ReachTargetGenerator{}.generate(points, 3000 + static_cast<unsigned>(k), Eigen::Vector2d::Zero(), reachable));
  return s;
}

ReachSummary run(ExpSetup& s, ehc_control::ControlMode mode, std::vector<ReachTrial>* trials = nullptr) {
  auto c = s.ctrl;
  c.mode = mode;
  ReachExperiment e(s.model, c, s.weighting, s.params);
  return e.run(s.sets, 3, trials);
}

}  // namespace

TEST(ReachExperiment, DeterministicPerSeedAndSafe) {
  ExpSetup s = makeSetup(8);
  std::vector<ReachTrial> trials;
  const ReachSummary a = run(s, ehc_control::ControlMode::Ehc, &trials);
  const ReachSummary b = run(s, ehc_control::ControlMode::Ehc);
  EXPECT_EQ(summaryJson(a).substr(0, summaryJson(a).find("controller_step")),
            summaryJson(b).substr(0, summaryJson(b).find("controller_step")));
  EXPECT_EQ(a.targets, 8);
  EXPECT_EQ(a.qp_failures, 0);
  EXPECT_GT(a.min_joint_limit_margin, 0.0);  // the dampers kept every joint inside its limits
  EXPECT_LE(a.failed, 2);
  for (const auto& t : trials)
    if (t.reached) {
      EXPECT_LT(t.final_position_error, 0.01);
      EXPECT_LT(t.final_orientation_error, 2.0 * M_PI / 180.0);
    }
}

TEST(ReachExperiment, EhcPlaceReachesMostTargetsFromItsPlacements) {
  // ehc_place closed loop (the placement's move, then ehc) on the same targets as above.
  ExpSetup s = makeSetup(8);
  std::vector<ReachTrial> trials;
  const ReachSummary r = run(s, ehc_control::ControlMode::EhcPlace, &trials);
  std::printf("ehc_place: %d of %d failed, mean %.2f s (targets seed 3000, noise seed 3)\n", r.failed, r.targets,
              r.mean_time_s);
  EXPECT_EQ(r.method, "ehc_place");
  EXPECT_EQ(r.targets, 8);
  EXPECT_LE(r.failed, 1);
  EXPECT_EQ(r.qp_failures, 0);
  EXPECT_GT(r.min_joint_limit_margin, 0.0);
  for (const auto& t : trials)
    if (t.reached) {
      EXPECT_LT(t.final_position_error, 0.01);
      EXPECT_LT(t.final_orientation_error, 2.0 * M_PI / 180.0);
    }
}

TEST(ReachExperiment, ReachesMostTargetsWithTheBaseImprecisionAtLevelOne) {
  // The controller runs on the imprecise odometry (latency, minimum speed, drift, localisation
  // jumps); arrival is judged on the true pose. Same targets as above.
  ExpSetup s = makeSetup(8);
  s.params.base_model.imprecision.level = 1.0;
  std::vector<ReachTrial> trials;
  const ReachSummary r = run(s, ehc_control::ControlMode::Ehc, &trials);
  std::printf("base imprecision level 1: %d of %d failed, mean %.2f s (targets seed 3000, noise seed 3)\n", r.failed,
              r.targets, r.mean_time_s);
  EXPECT_EQ(r.base_imprecision, 1.0);
  EXPECT_NE(summaryJson(r).find("\"base_imprecision\":1"), std::string::npos) << summaryJson(r);
  EXPECT_EQ(r.targets, 8);
  EXPECT_LE(r.failed, 3);
  EXPECT_EQ(r.qp_failures, 0);
  for (const auto& t : trials)
    if (t.reached) {
      EXPECT_LT(t.final_position_error, 0.01);  // the true TCP
    }
}

TEST(ReachExperiment, DmcgEhcBaseMovesLessThanNeoEOnceTheArmCanReach) {
  // Close = position error below 0.5 m (DESIGN section 10), where EHC's sig(omega) rises to 1.
  // 100 targets: fewer make the close-phase means too noisy to compare.
  ExpSetup s = makeSetup(50, 2);
  const ReachSummary ehc = run(s, ehc_control::ControlMode::Ehc);
  const ReachSummary neo = run(s, ehc_control::ControlMode::NeoE);
  RecordProperty("ehc_close_base_t", std::to_string(ehc.close.base_t));
  RecordProperty("neo_e_close_base_t", std::to_string(neo.close.base_t));
  RecordProperty("ehc_close_base_r", std::to_string(ehc.close.base_r));
  RecordProperty("neo_e_close_base_r", std::to_string(neo.close.base_r));
  std::printf("close (< 0.5 m) base speeds: ehc %.4f m/s %.4f rad/s, neo_e %.4f m/s %.4f rad/s\n",
              ehc.close.base_t, ehc.close.base_r, neo.close.base_t, neo.close.base_r);
  // Margin: base translation at least 5 % lower, rotation at least 15 % lower (measured on this
  // seeded set: 10 % and 22 %; the paper's Table II shows 8 % and 25 %). Until the base-turn
  // term was unwound at the +-pi jump of atan2 (controller.base_turn_unwinding, every method),
  // NEO(e)'s base sometimes turned the wrong way near the target and the translation margin
  // measured 28 %: part of that was the jump, not EHC's weighting.
  EXPECT_LT(ehc.close.base_t, 0.95 * neo.close.base_t);
  EXPECT_LT(ehc.close.base_r, 0.85 * neo.close.base_r);
}

namespace {
/// The first `points` targets of set 0 of `ehc_experiment reach --seed 1` (generator seed 1000,
/// unreachable draws redrawn), run with noise seed 1 as that command runs them.
std::vector<std::vector<Eigen::Isometry3d>> experimentSet0(const ExpSetup& s, int points) {
  auto reachable = [&](const Eigen::Isometry3d& T) { return kinematicallyReachable(*s.model, T, s.ctrl.joint_stop); };
  return {ReachTargetGenerator{}.generate(points, 1000, Eigen::Vector2d::Zero(), reachable)};
}
ReachSummary runSet0(const ExpSetup& s, ehc_control::QpControllerParams c, ehc_control::ControlMode mode,
                     const std::vector<std::vector<Eigen::Isometry3d>>& sets, std::vector<ReachTrial>* trials,
                     ReachProtocol protocol = ReachProtocol::Sequence) {
  c.mode = mode;
  ReachExperimentParams p = s.params;
  p.protocol = protocol;
  ReachExperiment e(s.model, c, s.weighting, p);
  return e.run(sets, 1, trials);
}
void expectCausesAccountedFor(const ReachSummary& s, const std::vector<ReachTrial>& trials) {
  int counted = 0;
  for (const auto& [cause, n] : s.failures) {
    EXPECT_NE(cause, ReachFailure::None);
    counted += n;
  }
  EXPECT_EQ(counted, s.failed) << s.method;
  for (const ReachTrial& t : trials) {
    if (t.method != s.method) continue;
    EXPECT_EQ(t.reached, t.failure == ReachFailure::None) << s.method << " target " << t.index;
    const bool pinned = t.failure == ReachFailure::JointLimit || t.failure == ReachFailure::RollWinding;
    EXPECT_EQ(pinned, !t.failure_joint.empty()) << s.method << " target " << t.index;
  }
}
}  // namespace

TEST(ReachExperiment, FailureCausesHaveOneStringMap) {
  for (const ReachFailure f : reachFailures()) EXPECT_EQ(reachFailureFromString(toString(f)), f);
  EXPECT_EQ(reachProtocolFromString("reset"), ReachProtocol::Reset);
  EXPECT_EQ(toString(ReachProtocol::Sequence), "sequence");
  EXPECT_THROW(reachFailureFromString("bad luck"), std::invalid_argument);
  EXPECT_THROW(reachProtocolFromString("random"), std::invalid_argument);
}

TEST(ReachExperiment, NoJointLimitTrapsBackToBackEveryMethod) {
  // Reduced Exp-1 (20 targets back to back, noise on). Before the unwound base-turn bearing
  // and the joint-limit centring, NEO(c) left joint1 pinned at its limit on two of these
  // targets (every later target inherits the posture); with them every method reaches at
  // least 19 of 20, and every failure, before or after, carries a cause.
  ExpSetup s = makeSetup(1);
  const auto sets = experimentSet0(s, 20);
  ehc_control::QpControllerParams before = s.ctrl;
  before.base_turn_unwinding = false;
  before.limit_centring_gain = 0.0;
  before.recovery.enabled = false;  // the stall recovery would rescue these targets too
  before.far_approach.face_target = false;  // and so would the far approach
  before.far_approach.posture_gain = 0.0;
  before.far_approach.orientation_release = 0.0;
  std::vector<ReachTrial> trials_before;
  const ReachSummary b = runSet0(s, before, ehc_control::ControlMode::NeoC, sets, &trials_before);
  EXPECT_GE(b.failed, 2);
  EXPECT_GE(b.pinned_joints.count("joint1"), 1u);
  expectCausesAccountedFor(b, trials_before);

  ASSERT_GT(s.ctrl.limit_centring_gain, 0.0);  // controller.yaml switches it on
  ASSERT_TRUE(s.ctrl.base_turn_unwinding);
  for (const auto mode : {ehc_control::ControlMode::Ehc, ehc_control::ControlMode::NeoE, ehc_control::ControlMode::NeoC}) {
    std::vector<ReachTrial> trials;
    const ReachSummary a = runSet0(s, s.ctrl, mode, sets, &trials);
    std::printf("%s: %d of %d failed, mean %.2f s\n", a.method.c_str(), a.failed, a.targets, a.mean_time_s);
    EXPECT_LE(a.failed, 1) << a.method;
    expectCausesAccountedFor(a, trials);
  }
}

TEST(ReachExperiment, WristFlipRemovesTheForearmRollTrapBackToBack) {
  // The first 47 targets of `ehc_experiment reach --seed 1` back to back, noise on. Without
  // the wrist flip, EHC ends target 46 with joint4 pinned 0.1 rad from its limit, 9 cm short
  // (the sequence-protocol trap: without the flip 23-33 of 500 failed per method, mostly this);
  // with it every method reaches all 47, and the flip costs EHC no mean time.
  ExpSetup s = makeSetup(1);
  const auto sets = experimentSet0(s, 47);
  ehc_control::QpControllerParams no_flip = s.ctrl;
  no_flip.wrist_flip.margin = 0.0;
  no_flip.recovery.enabled = false;  // the stall recovery would rescue this target too
  no_flip.far_approach.face_target = false;  // and so would the far approach
  no_flip.far_approach.posture_gain = 0.0;
  no_flip.far_approach.orientation_release = 0.0;
  std::vector<ReachTrial> trials_before;
  const ReachSummary b = runSet0(s, no_flip, ehc_control::ControlMode::Ehc, sets, &trials_before);
  ASSERT_EQ(trials_before.size(), 47u);
  EXPECT_FALSE(trials_before[46].reached);
  EXPECT_EQ(trials_before[46].failure, ReachFailure::JointLimit);
  EXPECT_EQ(trials_before[46].failure_joint, "joint4");
  expectCausesAccountedFor(b, trials_before);

  ASSERT_GT(s.ctrl.wrist_flip.margin, 0.0);  // controller.yaml switches it on
  for (const auto mode : {ehc_control::ControlMode::Ehc, ehc_control::ControlMode::NeoE, ehc_control::ControlMode::NeoC}) {
    std::vector<ReachTrial> trials;
    const ReachSummary a = runSet0(s, s.ctrl, mode, sets, &trials);
    std::printf("%s: %d of %d failed, mean %.2f s (no flip, ehc: %d failed, mean %.2f s)\n", a.method.c_str(), a.failed,
                a.targets, a.mean_time_s, b.failed, b.mean_time_s);
    EXPECT_EQ(a.failed, 0) << a.method;
    EXPECT_EQ(a.qp_failures, 0) << a.method;
    if (mode == ehc_control::ControlMode::Ehc) {
      EXPECT_LE(a.mean_time_s, b.mean_time_s + 0.1);
    }
  }
}

TEST(ReachExperiment, ResetProtocolStartsEveryTargetFromTheReadyPose) {
  ExpSetup s = makeSetup(1);
  const auto sets = std::vector<std::vector<Eigen::Isometry3d>>{relativeToPrevious(experimentSet0(s, 4)[0])};
  std::vector<ReachTrial> trials;
  const ReachSummary r = runSet0(s, s.ctrl, ehc_control::ControlMode::NeoE, sets, &trials, ReachProtocol::Reset);
  EXPECT_EQ(r.targets, 4);
  // Every target is 1.5-4 m from the origin, where the robot starts each time.
  for (const auto& t : sets[0]) {
    EXPECT_GE(t.translation().head<2>().norm(), 1.5 - 1e-9);
    EXPECT_LE(t.translation().head<2>().norm(), 4.0 + 1e-9);
  }
  expectCausesAccountedFor(r, trials);
}

TEST(ReachExperiment, RunsOnTheSevenDofTestArm) {
  // The controller and the failure bookkeeping on a redundant (7-DOF) arm on the differential
  // base: test/fixtures/robots/arm7_differential (iiwa 14 kinematics).
  const auto rc = ehc_control::loadRobotConfig(std::string(EHC_TEST_FIXTURES_DIR) + "/robots/arm7_differential/robot.yaml");
  ExpSetup s = makeSetup(1);
  s.model = std::make_shared<const ehc_control::WholeBodyModel>(rc);
  const auto cfg = ehc_common::ConfigNode::loadFile(std::string(EHC_CONFIG_DIR) + "/control/controller.yaml", "test");
  auto map = std::make_shared<const ehc_control::ReachabilityMap>(ehc_control::ReachabilityMap::load(rc.reachability_map_path));
  map->checkCompatible(rc);
  s.weighting = std::make_shared<const ehc_control::EhcWeighting>(map, ehc_control::loadEhcWeightingParams(cfg.child("weighting")));
  EXPECT_EQ(ehc_control::armYawJoint(*s.model), 0);
  const auto sets = experimentSet0(s, 5);
  std::vector<ReachTrial> trials;
  const ReachSummary r = runSet0(s, s.ctrl, ehc_control::ControlMode::Ehc, sets, &trials);
  std::printf("7-DOF ehc: %d of %d failed, mean %.2f s\n", r.failed, r.targets, r.mean_time_s);
  EXPECT_EQ(r.targets, 5);
  EXPECT_EQ(r.qp_failures, 0);
  EXPECT_GT(r.min_joint_limit_margin, 0.0);
  EXPECT_LE(r.failed, 2);
  expectCausesAccountedFor(r, trials);
}

// Joint-limit stalls and their recovery (ReachRecovery). Two targets approached from the side
// (the `any` generator): from the ready pose without recovery, the QP pins the wrist bend
// (joint5) or the forearm roll (joint4) and settles a few cm short for good; with the recovery,
// whole-body IK finds a configuration with wide joint margins and the robot reaches the target.
TEST(ReachExperiment, AJointLimitStallIsRecoveredThroughWholeBodyIk) {
  ExpSetup s = makeSetup(1);
  auto pose = [](double x, double y, double z, double qx, double qy, double qz, double qw) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::Quaterniond(qw, qx, qy, qz).normalized().toRotationMatrix();
    T.translation() << x, y, z;
    return T;
  };
  s.sets = {{pose(-0.01073739308, -0.2371418818, 0.698047065, -0.2357319204, -0.4545359977, 0.8384985393, 0.1864073179)},
            {pose(-1.71836345, 0.28998997, 0.5336868357, -0.7470270042, -0.04410559814, -0.3843337259, 0.5406412289)}};
  s.params.noise.enabled = false;
  // The far approach carries the arm to set 1's target (behind the robot) without the stall;
  // this test is about the recovery from it, so both runs go without the far approach.
  s.ctrl.far_approach.face_target = false;
  s.ctrl.far_approach.posture_gain = 0.0;
  s.ctrl.far_approach.orientation_release = 0.0;
  for (const bool recovery : {false, true}) {
    s.ctrl.recovery.enabled = recovery;
    std::vector<ReachTrial> trials;
    const ReachSummary sum = run(s, ehc_control::ControlMode::Ehc, &trials);
    ASSERT_EQ(trials.size(), 2u);
    for (const ReachTrial& t : trials) {
      if (recovery) {
        EXPECT_TRUE(t.reached) << "set " << t.set << ": " << toString(t.failure) << " " << t.failure_joint << ", "
                               << t.final_position_error << " m short";
        EXPECT_GT(t.min_joint_limit_margin, 0.0);
      } else {
        EXPECT_FALSE(t.reached) << "set " << t.set << " (the stall this test is about no longer occurs)";
        EXPECT_EQ(t.failure, ReachFailure::JointLimit) << "set " << t.set;
      }
    }
    EXPECT_EQ(sum.qp_failures, 0);
  }
}
