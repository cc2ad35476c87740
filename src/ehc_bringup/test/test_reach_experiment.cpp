// ReachExperiment (Exp-1 in-process): determinism, safety over a run, and the DMCG property:
// on the same targets, once the target is within the arm's reach EHC's base moves clearly less
// than NEO(e)'s (the arm takes over).

#include "ehc_bringup/reach_experiment.h"
#include "ehc_bringup/reach_targets.h"
#include "ehc_control/config_node.h"

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
  const auto cfg = ehc_control::ConfigNode::loadFile(std::string(EHC_CONFIG_DIR) + "/control/controller.yaml", "test");
  s.ctrl = ehc_control::loadQpControllerParams(cfg.child("controller"));
  s.params.servo = ehc_control::loadPoseServoParams(cfg.child("servo"));
  s.weighting = std::make_shared<const ehc_control::EhcWeighting>(
      std::make_shared<const ehc_control::ReachabilityMap>(ehc_control::ReachabilityMap::load(rc.reachability_map_path)),
      ehc_control::loadEhcWeightingParams(cfg.child("weighting")));
  auto reachable = [&](const Eigen::Isometry3d& T) { return s.model->inverseKinematics(T, 1, 30); };
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
  // Margin: both base speeds at least 15 % lower (measured on this seeded set: 28 % and 26 %;
  // the paper's Table II shows 8 % and 25 %).
  EXPECT_LT(ehc.close.base_t, 0.85 * neo.close.base_t);
  EXPECT_LT(ehc.close.base_r, 0.85 * neo.close.base_r);
}
