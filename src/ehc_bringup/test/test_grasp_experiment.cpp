// GraspExperiment / GraspPipeline: one set of every method of Exp-2 and Exp-3 runs
// in-process to the end and reports every grasp; the same seed gives bit-identical results
// (one set run twice, summaries and trials compared as text); a different seed jitters the
// objects. No ROS master, no wall clock in the pipeline.
#include "ehc_bringup/grasp_experiment.h"
#include "ehc_sim/sim_world.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <sstream>

using namespace ehc_bringup;

namespace {

GraspExperimentParams params(GraspProtocol protocol) {
  GraspExperimentParams p;
  p.protocol = protocol;
  p.config_dir = EHC_CONFIG_DIR;
  p.sets = 1;
  p.per_set = 1;
  p.seed = 7;
  p.jobs = 2;
  return p;
}

std::string trialsText(const GraspExperimentResult& r) {
  std::ostringstream os;
  os.precision(17);
  for (const auto& t : r.trials)
    os << t.method << " " << t.object << " " << t.success << " " << t.time_s << " " << t.tfm << " " << t.failed_phase
       << " " << t.reason << " " << t.contact_steps << " " << t.nearest.distance << " " << t.nearest.link << " " << t.nearest.body << " "
       << t.nearest.phase << " " << t.tightest.margin() << " " << t.tightest.link << " " << t.grasped.distance << "\n";
  return os.str();
}

std::string summariesText(const GraspExperimentResult& r) {
  std::string s;
  for (const auto& m : r.summaries) s += graspSummaryJson(m) + "\n";
  return s;
}

std::string readFile(const std::string& path) {
  std::ifstream f(path);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

}  // namespace

TEST(GraspExperiment, MethodNamesPerProtocol) {
  EXPECT_EQ(graspMethodNames(GraspProtocol::Table, "all"), (std::vector<std::string>{"tsmm", "neo_c", "neo_e", "ehc"}));
  EXPECT_EQ(graspMethodNames(GraspProtocol::Poses, "all"), (std::vector<std::string>{"neo_nompbs", "ehc_nompbs", "ehc"}));
  EXPECT_THROW(graspMethodNames(GraspProtocol::Poses, "tsmm"), std::invalid_argument);
  EXPECT_FALSE(graspMethod("ehc_nompbs").mpbs);
  EXPECT_TRUE(graspMethod("ehc").mpbs);
  // ehc's placement mode: Exp-2 only, by name (not one of the paper's methods in "all").
  EXPECT_EQ(graspMethodNames(GraspProtocol::Table, "ehc_place"), (std::vector<std::string>{"ehc_place"}));
  EXPECT_THROW(graspMethodNames(GraspProtocol::Poses, "ehc_place"), std::invalid_argument);
  EXPECT_EQ(graspMethod("ehc_place").mode, ehc_control::ControlMode::EhcPlace);
  EXPECT_TRUE(graspMethod("ehc_place").mpbs);
}

TEST(GraspExperiment, APenetratingPairIsTheWorstCaseNotNone) {
  // A perceived distance <= 0 (the link inside an occupied voxel) once read as "no pair" and
  // was left out of the safety table's minima.
  auto pair = [](double d, double stop) {
    ObstacleExtreme e;
    e.found = true;
    e.distance = d;
    e.stop = stop;
    return e;
  };
  ObstacleExtreme nearest, tightest;
  EXPECT_FALSE(nearest.found);
  for (const ObstacleExtreme& e : {pair(0.004, 0.010), pair(-0.007, 0.015), pair(0.030, 0.050), ObstacleExtreme{}}) {
    nearest.take(e, false);
    tightest.take(e, true);
  }
  ASSERT_TRUE(nearest.found);
  EXPECT_DOUBLE_EQ(nearest.distance, -0.007);
  EXPECT_DOUBLE_EQ(tightest.margin(), -0.022);
  EXPECT_NE(graspSummaryJson([&] {
              GraspMethodSummary s;
              s.method = "ehc";
              s.tightest = tightest;
              return s;
            }()).find("\"margin\":-0.022"),
            std::string::npos);
}

TEST(GraspExperiment, SetsJitterTheObjectsBySeed) {
  const GraspExperiment exp(params(GraspProtocol::Table), {"ehc"});
  const auto a = exp.runConfig("ehc", "", 7000), b = exp.runConfig("ehc", "", 7000), c = exp.runConfig("ehc", "", 7010);
  ASSERT_EQ(a.scene.objects.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(a.scene.objects[i].position, b.scene.objects[i].position);
    EXPECT_NE(a.scene.objects[i].position, c.scene.objects[i].position);
    EXPECT_LE((a.scene.objects[i].position - c.scene.objects[i].position).head<2>().cwiseAbs().maxCoeff(), 0.02 + 1e-12);
  }
}

TEST(GraspExperiment, TsmmStopsTheBaseWithTheTcpDFromTheObjectThenTheArmAloneGrasps) {
  // Paper section IV-D: the base drives until the TCP is d = 0.2 m from the object (horizontally,
  // ground truth here; the controller measures it to the perceived object centre), stops, and
  // the arm grasps alone: the base command is exactly zero in the whole arm stage.
  const GraspExperiment exp(params(GraspProtocol::Table), {"tsmm"});
  const GraspPipelineConfig cfg = exp.runConfig("tsmm", "", 7000);
  const double d = cfg.cycle.controller.tsmm_switch_distance;
  ASSERT_EQ(d, 0.2);
  GraspPipeline pipe(cfg, 7000);
  const int nb = pipe.cycle().model().nBase();
  const std::string tcp = pipe.cycle().model().config().tcp_frame;
  bool arm_stage = false;
  int switches = 0;
  long arm_cycles = 0;
  while (pipe.sequencer().results().empty() && pipe.time() < 40.0) {
    const PipelineCycle& c = pipe.step();
    if (c.status.phase == ehc_control::ControlPhase::TsmmBase) arm_stage = false;
    if (c.status.phase == ehc_control::ControlPhase::TsmmArm && !arm_stage) {
      arm_stage = true;
      ++switches;
      const Eigen::Vector3d object = pipe.world().objectPose(0).translation();
      const double horizontal = (pipe.world().linkPose(tcp).translation() - object).head<2>().norm();
      RecordProperty("tcp_object_horizontal_at_switch", std::to_string(horizontal));
      // d from the object, within the perception error of its centre (the pre-grasp, which
      // the switch used to be measured to, is 0.1 m before the object: ~0.3 m).
      EXPECT_NEAR(horizontal, d, 0.03);
    }
    if (arm_stage) {
      ++arm_cycles;
      for (int i = 0; i < nb; ++i) ASSERT_EQ(c.command[i], 0.0) << "t " << c.t << " base DOF " << i;
    }
  }
  ASSERT_EQ(pipe.sequencer().results().size(), 1u);
  EXPECT_TRUE(pipe.sequencer().results()[0].success) << pipe.sequencer().results()[0].reason;
  EXPECT_EQ(switches, 1);  // one base stage, one arm stage: the base never drives again
  EXPECT_GT(arm_cycles, 100);
}

TEST(GraspExperiment, TheWater2BaseGraspsThroughItsOdometryEstimate) {
  // --base-model water2: the simulated Water2 chain moves the base, and the stack (controller,
  // perception, sequencer) sees the bridge's /odom estimate, which lags and drifts from the true
  // pose; the front object is still grasped.
  GraspExperimentParams p = params(GraspProtocol::Table);
  p.base_model = ehc_sim::BaseModelType::Water2;
  const GraspExperiment exp(p, {"ehc"});
  const GraspPipelineConfig cfg = exp.runConfig("ehc", "", 7000);
  ASSERT_EQ(cfg.sim.fake_robot.base_model.type, ehc_sim::BaseModelType::Water2);
  GraspPipeline pipe(cfg, 7000);
  ASSERT_NE(pipe.world().robot().water2(), nullptr);
  double worst = 0.0;
  while (pipe.sequencer().results().empty() && pipe.time() < 40.0) {
    pipe.step();
    const auto& robot = pipe.world().robot();
    worst = std::max(worst, (robot.odometryPose().head<2>() - robot.basePose().head<2>()).norm());
  }
  RecordProperty("worst_odometry_error_m", std::to_string(worst));
  EXPECT_GT(worst, 1e-3) << "the stack ran on the true pose, not on the odometry estimate";
  ASSERT_EQ(pipe.sequencer().results().size(), 1u);
  EXPECT_TRUE(pipe.sequencer().results()[0].success) << pipe.sequencer().results()[0].reason;
  EXPECT_EQ(pipe.counters().collision_steps, 0);
}

TEST(GraspExperiment, TheBaseImprecisionLevelReachesTheSimulatorAndTheStackSeesItsOdometry) {
  GraspExperimentParams p = params(GraspProtocol::Table);
  p.base_imprecision = 1.0;
  const GraspExperiment exp(p, {"ehc"});
  const GraspPipelineConfig cfg = exp.runConfig("ehc", "", 7000);
  ASSERT_EQ(cfg.sim.fake_robot.base_model.imprecision.level, 1.0);
  GraspPipeline pipe(cfg, 7000);
  ASSERT_NE(pipe.world().robot().imprecision(), nullptr);
  EXPECT_FALSE(pipe.world().robot().odometryIsTruth());
  p.base_imprecision = -0.5;
  EXPECT_THROW(GraspExperiment(p, {"ehc"}), std::invalid_argument);
}

TEST(GraspExperiment, Exp2OneSetOfEveryMethodAndTheSameSeedGivesTheSameResult) {
  const GraspExperimentParams p = params(GraspProtocol::Table);
  const GraspExperiment exp(p, graspMethodNames(GraspProtocol::Table, "all"));
  int progress_calls = 0;
  const GraspExperimentResult r = exp.run([&](int, int, const std::string&) { ++progress_calls; });
  EXPECT_EQ(progress_calls, 4);
  ASSERT_EQ(r.summaries.size(), 4u);
  ASSERT_EQ(r.trials.size(), 12u);  // 4 methods x 3 objects, every one reported
  for (const auto& t : r.trials) {
    EXPECT_TRUE(t.success || !t.failed_phase.empty()) << t.method << " " << t.object;
    EXPECT_EQ(t.joint_limit_violations, 0) << t.method << " " << t.object;
  }
  for (const auto& s : r.summaries) RecordProperty(s.method, graspSummaryJson(s));
  EXPECT_GT(r.counters.tag_detections, 0);
  EXPECT_GT(r.counters.grasp_runs, 0);
  EXPECT_GT(r.counters.obstacle_updates, 0);

  // The same set of one method again, alone and on one job: bit-identical.
  GraspExperimentParams once = p;
  once.jobs = 1;
  const GraspExperimentResult again = GraspExperiment(once, {"ehc"}).run();
  GraspExperimentResult ehc_only;
  ehc_only.summaries = {r.summaries.back()};
  for (const auto& t : r.trials)
    if (t.method == "ehc") ehc_only.trials.push_back(t);
  ehc_only.summaries.back().wall_time_s = 0.0;
  EXPECT_EQ(summariesText(again), summariesText(ehc_only));
  EXPECT_EQ(trialsText(again), trialsText(ehc_only));

  const std::string dir = ::testing::TempDir() + "/ehc_exp2_test";
  writeGraspResults(dir, p, r, "test");
  const std::string table = readFile(dir + "/table.md");
  EXPECT_NE(table.find("| tsmm |"), std::string::npos) << table;
  EXPECT_NE(table.find("95.6"), std::string::npos) << table;  // the paper's EHC figure beside
  EXPECT_NE(readFile(dir + "/trials.csv").find("ehc,0,0,7000,back,"), std::string::npos);
  EXPECT_NE(readFile(dir + "/summary.json").find("\"method\":\"neo_e\""), std::string::npos);
}

TEST(GraspExperiment, Exp3OneSetOfEveryMethodReportsTfmPerApproach) {
  const GraspExperimentParams p = params(GraspProtocol::Poses);
  const GraspExperiment exp(p, graspMethodNames(GraspProtocol::Poses, "all"));
  const GraspExperimentResult r = exp.run();
  ASSERT_EQ(r.summaries.size(), 3u);
  ASSERT_EQ(r.trials.size(), 9u);  // 3 methods x 3 approaches x 1
  for (const auto& s : r.summaries) {
    RecordProperty(s.method, graspSummaryJson(s));
    EXPECT_EQ(s.tfm.size(), 3u) << s.method;
    for (const auto& e : s.tfm) {
      EXPECT_GE(e.second.first, 0.0);
      EXPECT_LE(e.second.first, 1.0);
    }
  }
  for (const auto& t : r.trials) {
    EXPECT_EQ(t.joint_limit_violations, 0) << t.method << " " << t.approach;
    // The object being grasped is listed apart from PRE_GRASP on (the hand must come close).
    if (t.nearest.body == t.object) {
      EXPECT_TRUE(t.nearest.phase == "WAIT_TARGET" || t.nearest.phase == "APPROACH") << t.nearest.phase;
    }
    if (t.grasped.found) {
      EXPECT_NE(t.grasped.link, "") << t.method;
    }
  }
}

TEST(GraspExperiment, AnObjectsTimeLimitNamesTheStallsCauseInTheResultLineTrialsAndSummary) {
  // A bench across the way (test/fixtures/scenes/blocked_single_object.yaml): the camera sees the
  // object over it, the obstacle dampers stop the base at it. A grasp that runs out of time says
  // why: the link and the scene body held at the stop distance (or another MotionLimit), never
  // only "time limit".
  GraspExperimentParams p = params(GraspProtocol::Poses);
  p.scene = std::string(EHC_TEST_FIXTURES_DIR) + "/scenes/blocked_single_object.yaml";
  p.object_time_limit = 8.0;
  const GraspExperimentResult r = GraspExperiment(p, {"ehc"}).run();
  ASSERT_EQ(r.trials.size(), 3u);
  int timed_out = 0, bench = 0;
  for (const auto& t : r.trials) {
    SCOPED_TRACE(t.approach + ": " + t.reason);
    RecordProperty(t.approach, t.success ? std::string("grasped") : t.reason);
    if (t.success || t.reason.rfind("time limit", 0) != 0) {
      EXPECT_EQ(t.stall_cause, "");
      continue;
    }
    ++timed_out;
    EXPECT_NO_THROW(ehc_control::motionLimitFromString(t.stall_cause));
    EXPECT_NE(t.reason.find("stall: " + t.stall_cause), std::string::npos);
    EXPECT_FALSE(t.stall_detail.empty());
    if (t.stall_cause == "joint_limit") {
      EXPECT_FALSE(t.stall_joint.empty());
    }
    if (t.stall_cause == "obstacle") {
      EXPECT_FALSE(t.stall_link.empty());
      EXPECT_FALSE(t.stall_body.empty());
      if (t.stall_body == "bench") ++bench;
    }
  }
  EXPECT_GE(timed_out, 1);
  EXPECT_GE(bench, 1) << "no stall named the bench that blocks the way";
  ASSERT_EQ(r.summaries.size(), 1u);
  int counted = 0;
  for (const auto& [cause, n] : r.summaries[0].stall_causes) counted += n;
  EXPECT_EQ(counted, timed_out);

  const std::string dir = ::testing::TempDir() + "/ehc_stall_test";
  writeGraspResults(dir, p, r, "test");
  const std::string trials = readFile(dir + "/trials.csv");
  EXPECT_NE(trials.find(",stall_cause,stall_joint,stall_link,stall_body,stall_detail,"), std::string::npos);
  EXPECT_NE(trials.find(",obstacle,,base_link,bench,"), std::string::npos) << trials;
  const std::string summary = readFile(dir + "/summary.json");
  EXPECT_NE(summary.find("\"stall_causes\":{"), std::string::npos) << summary;
  EXPECT_NE(summary.find("\"obstacle\":"), std::string::npos) << summary;
}
