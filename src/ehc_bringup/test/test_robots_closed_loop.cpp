// The closed loop on every shipped robot (every folder under config/robots: the RealMan RM65
// and the Kinova Gen3 7-DOF on differential bases, the KUKA iiwa 14 and the UR5e on holonomic
// bases), as ocs2 runs its closed-loop tests over robots. Everything is selected by the robot switch alone (a robot name):
//  - reduced Exp-1: the controller converges from several start states (each target of the
//    sequence protocol starts where the previous one ended; the reset protocol from the ready
//    pose) with Table I noise, and no arm joint ever leaves its limits;
//  - one Exp-2 set (the demo's table, three objects) with EHC: all three grasped, no robot-scene
//    contact, no joint-limit violation, and the perceived link-obstacle distance never below the
//    robot's smallest obstacle stop distance (minus one 5 mm tolerance).
// Seeded noise and lock-step sim time, no wall clock: the Exp-1 targets and the Exp-2 set's seed
// (noise, object placement jitter) are drawn on every run and printed (EHC_TEST_SEED=<seed>
// reruns them).

#include "ehc_bringup/grasp_experiment.h"
#include "ehc_bringup/reach_experiment.h"
#include "ehc_bringup/reach_targets.h"
#include "ehc_common/config_node.h"
#include "ehc_control/robot_config.h"
#include "ehc_test/test_seed.h"

#include <gtest/gtest.h>

#include <algorithm>

using namespace ehc_bringup;

namespace {

class RobotClosedLoop : public ::testing::TestWithParam<std::string> {};

ReachSummary runReach(const std::string& robot, ReachProtocol protocol, std::vector<ReachTrial>* trials) {
  const auto rc = ehc_control::loadRobotConfig(ehc_control::resolveRobotFile(robot));
  auto model = std::make_shared<const ehc_control::WholeBodyModel>(rc);
  const auto cfg = ehc_common::ConfigNode::loadFile(ehc_control::configDirectory() + "/control/controller.yaml", "test");
  ehc_control::QpControllerParams ctrl = ehc_control::loadQpControllerParams(cfg.child("controller"));
  ReachExperimentParams params;
  params.servo = ehc_control::loadPoseServoParams(cfg.child("servo"));
  params.protocol = protocol;
  auto weighting = std::make_shared<const ehc_control::EhcWeighting>(
      std::make_shared<const ehc_control::ReachabilityMap>(ehc_control::ReachabilityMap::load(rc.reachability_map_path)),
      ehc_control::loadEhcWeightingParams(cfg.child("weighting")));
  // Reachable as the runner and the failure classification define it: inside the joint stops.
  auto reachable = [&](const Eigen::Isometry3d& T) { return kinematicallyReachable(*model, T, ctrl.joint_stop); };
  std::vector<Eigen::Isometry3d> targets = ReachTargetGenerator{}.generate(
      6, ehc_test::testSeed(robot + " Exp-1 " + toString(protocol)), Eigen::Vector2d::Zero(), reachable);
  if (protocol == ReachProtocol::Reset) targets = relativeToPrevious(targets);
  ReachExperiment exp(model, ctrl, weighting, params);
  return exp.run({targets}, 5, trials);
}

}  // namespace

TEST_P(RobotClosedLoop, ReducedExp1ConvergesFromSeveralStartStatesWithinTheJointLimits) {
  for (const ReachProtocol protocol : {ReachProtocol::Sequence, ReachProtocol::Reset}) {
    SCOPED_TRACE(GetParam() + " protocol " + toString(protocol));
    std::vector<ReachTrial> trials;
    const ReachSummary s = runReach(GetParam(), protocol, &trials);
    RecordProperty(GetParam() + "_" + toString(protocol), summaryJson(s));
    EXPECT_EQ(s.targets, 6);
    EXPECT_EQ(s.failed, 0) << summaryJson(s);
    EXPECT_EQ(s.qp_failures, 0);
    EXPECT_GT(s.min_joint_limit_margin, 0.0);  // never at or beyond a limit
    for (const ReachTrial& t : trials) {
      EXPECT_TRUE(t.reached) << "target " << t.index << ": " << toString(t.failure);
      EXPECT_LE(t.final_position_error, 0.01);
    }
  }
}

TEST_P(RobotClosedLoop, Exp2OneSetGraspsAllThreeObjectsKeepingTheStopDistance) {
  GraspExperimentParams p;
  p.protocol = GraspProtocol::Table;
  p.config_dir = ehc_control::configDirectory();
  p.robot = GetParam();
  p.sets = 1;
  p.per_set = 1;
  p.seed = ehc_test::testSeed(GetParam() + " Exp-2 set");
  p.jobs = 1;
  const GraspExperimentResult r = GraspExperiment(p, {"ehc"}).run();
  ASSERT_EQ(r.summaries.size(), 1u);
  RecordProperty(GetParam(), graspSummaryJson(r.summaries[0]));
  EXPECT_EQ(r.summaries[0].successes, 3) << graspSummaryJson(r.summaries[0]);
  for (const GraspTrial& t : r.trials) {
    SCOPED_TRACE(GetParam() + " " + t.object);
    EXPECT_TRUE(t.success) << t.failed_phase << ": " << t.reason;
    EXPECT_EQ(t.contact_steps, 0);
    EXPECT_EQ(t.joint_limit_violations, 0);
    // Every perceived link-scene pair keeps its link's stop distance d_s (5 mm for the noise).
    if (t.tightest.found) {
      EXPECT_GE(t.tightest.margin(), -0.005) << t.tightest.link << " to " << t.tightest.body;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Robots, RobotClosedLoop, ::testing::ValuesIn(ehc_control::robotNames()),
                         [](const auto& info) { return info.param; });
