// Targets without tags (ehc_control::TargetSelector, the scene's `targets:`): the in-process
// pipeline grasps the object the selector names from the depth cloud alone (no tag in the scene,
// no tag file), and only that one; the sequencer chooses a cloud target's grasp without the tag's
// centring or fallback; a scene whose targets do not match the sequencer fails naming the file;
// Exp-2 with library objects draws untagged objects of one half where the scene's stood.
#include "ehc_bringup/grasp_experiment.h"
#include "ehc_sim/object_library.h"
#include "ehc_sim/sim_world.h"
#include "ehc_test/errors.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <set>

using namespace ehc_bringup;

namespace {

const std::string kConfig = EHC_CONFIG_DIR;
const std::string kScene = std::string(EHC_TEST_FIXTURES_DIR) + "/scenes/tagless_two_objects.yaml";

GraspPipelineFiles taglessFiles(const std::string& scene) {
  return GraspPipelineFiles::demo(kConfig, scene, kConfig + "/demo/grasp_single_forward.yaml", {});
}

}  // namespace

TEST(CloudTargets, ThePipelineGraspsTheSecondObjectFromTheLeftWithoutATag) {
  const GraspPipelineConfig cfg = loadGraspPipelineConfig(taglessFiles(kScene));
  ASSERT_TRUE(cfg.tag_targets.empty());
  ASSERT_EQ(cfg.sequencer.objects.size(), 1u);
  ASSERT_EQ(cfg.sequencer.objects[0].target.kind, ehc_control::TargetSelectorKind::KthFromLeft);
  for (const auto& o : cfg.scene.objects) ASSERT_FALSE(o.tag.enabled) << o.name;
  const unsigned seed = 4101;
  std::printf("seed %u\n", seed);
  GraspPipeline pipe(cfg, seed);
  const int target = cfg.scene.objectIndex("right_cylinder"), other = cfg.scene.objectIndex("left_box");
  const double z0 = pipe.world().objectPose(target).translation().z();
  const Eigen::Vector3d other0 = pipe.world().objectPose(other).translation();
  double rise = 0.0, other_moved = 0.0, centre_error = 1.0;
  bool centre_checked = false;
  while (!pipe.done() && pipe.time() < 45.0) {
    const PipelineCycle& c = pipe.step();
    for (const auto& e : c.events) std::printf("t=%.2f %s\n", c.t, e.c_str());
    rise = std::max(rise, pipe.world().objectPose(target).translation().z() - z0);
    other_moved = std::max(other_moved, (pipe.world().objectPose(other).translation() - other0).norm());
    // The centre the camera watches (MPBS, TfM) is the target's cloud centre: on the target's
    // seen side, within its radius and half height of its true centre.
    if (!centre_checked && c.phase == GraspPhase::Approach) {
      const auto centre = pipe.sequencer().objectCentre();
      ASSERT_TRUE(centre);
      centre_error = (*centre - pipe.world().objectPose(target).translation()).norm();
      centre_checked = true;
    }
  }
  ASSERT_TRUE(pipe.done());
  const GraspResult& r = pipe.sequencer().results().at(0);
  std::printf("%s\n", graspResultLine(r).c_str());
  EXPECT_TRUE(r.success) << r.failed_phase << ": " << r.reason;
  EXPECT_TRUE(r.used_candidate);  // a cloud target has no tag fallback
  EXPECT_GT(r.tfm, 0.5);
  EXPECT_TRUE(centre_checked);
  EXPECT_LT(centre_error, 0.07);
  EXPECT_GT(rise, 0.08) << "the cylinder (2nd from the left) was not lifted";
  EXPECT_LT(other_moved, 0.01) << "the box was touched";
  EXPECT_EQ(pipe.counters().images, 0);  // no tag anywhere: no image rendered
}

TEST(CloudTargets, ACloudTargetsGraspNeedsACandidateAndIsNotCentredOnItsPose) {
  GraspSequencerParams p;
  p.objects.push_back({"a", ApproachDirection::Forward, {}});
  p.objects[0].target.kind = ehc_control::TargetSelectorKind::Nearest;
  p.objects[0].target.point = Eigen::Vector3d(1.5, 0, 0.8);
  GraspSequencer seq(p);
  SequencerInput in;
  in.t = 1.0;
  in.tcp = Eigen::Isometry3d::Identity();
  const Eigen::Isometry3d pose = ehc_control::cloudTargetPose(Eigen::Vector3d(1.5, 0, 0.8), Eigen::Vector3d(0.5, 0, 1.3));
  ASSERT_TRUE(seq.setObjectPose(0, 1.0, pose));
  seq.update(in);
  in.t = 1.1;
  seq.update(in);
  EXPECT_EQ(seq.phase(), GraspPhase::WaitTarget);  // no candidate: no tag fallback
  // A candidate 6 cm beside the centre (a handle): within the cloud gate, and kept where it is.
  GraspCandidate c;
  c.pose = pose;
  c.pose.translation() += 0.06 * pose.linear().col(1);
  c.width = 0.03;
  c.score = 0.9;
  seq.setGraspCandidates(1.1, {c});
  ASSERT_TRUE(seq.setObjectPose(0, 1.15, pose));
  in.t = 1.2;
  seq.update(in);
  EXPECT_EQ(seq.phase(), GraspPhase::Approach);
  in.t = 1.3;
  const SequencerOutput out = seq.update(in);
  ASSERT_TRUE(out.goal);
  // The goal is the pre-grasp of the candidate: 6 cm beside the centre, not moved onto it.
  EXPECT_NEAR((out.goal->translation() - pose.translation()).dot(pose.linear().col(1)), 0.06, 1e-9);
  // A "no target" reason reaches the failure of an object that never got a pose.
  GraspSequencerParams q = p;
  q.object_time_limit = 1.0;
  GraspSequencer none(q);
  in.t = 1.0;
  none.update(in);
  none.setNoTarget(0, "nearest to (1.5, 0, 0.8): ambiguous");
  in.t = 2.5;
  none.update(in);
  ASSERT_EQ(none.results().size(), 1u);
  EXPECT_NE(none.results()[0].reason.find("no target: nearest to (1.5, 0, 0.8): ambiguous"), std::string::npos)
      << none.results()[0].reason;
}

TEST(CloudTargets, SceneTargetsThatDoNotMatchTheSequencerNameTheFiles) {
  // Two targets for the one-object sequencer of grasp_single_forward.yaml.
  const std::string scene = ::testing::TempDir() + "/two_targets.yaml";
  {
    std::FILE* f = std::fopen(scene.c_str(), "w");
    ASSERT_TRUE(f);
    std::fputs("scene:\n  objects:\n    - {name: a, shape: box, size: [0.06, 0.06, 0.12], position: [1.5, 0, 0.76], mass: 0.1}\n"
               "  targets:\n    - {select: nearest, point: [1.5, 0, 0.76]}\n    - {select: kth_from_front, k: 1}\n",
               f);
    std::fclose(f);
  }
  const std::string e = ehc_test::errorOf([&] { loadGraspPipelineConfig(taglessFiles(scene)); });
  EXPECT_NE(e.find("two_targets.yaml"), std::string::npos) << e;
  EXPECT_NE(e.find("scene.targets"), std::string::npos) << e;
  EXPECT_NE(e.find("grasp_single_forward.yaml"), std::string::npos) << e;
}

TEST(CloudTargets, LibraryScenesPutObjectsOfOneHalfUntaggedWhereTheSceneHadItsOwn) {
  GraspExperimentParams p;
  p.config_dir = kConfig;
  p.sets = 1;
  p.library_split = "validation";
  const GraspExperiment exp(p, {"ehc"});
  const ehc_sim::ObjectLibrary library = ehc_sim::loadObjectLibrary(kConfig + "/objects/library.yaml");
  const ehc_sim::SceneConfig shipped = ehc_sim::loadSceneConfig(kConfig + "/scenes/table_three_objects.yaml");
  std::set<std::string> drawn;
  for (unsigned seed = 1000; seed < 1010; ++seed) {
    const GraspPipelineConfig c = exp.runConfig("ehc", "", seed);
    ASSERT_EQ(c.scene.objects.size(), 3u);
    ASSERT_EQ(c.scene.targets.size(), 3u);
    EXPECT_TRUE(c.tag_targets.empty());
    std::set<std::string> names;
    for (std::size_t i = 0; i < 3; ++i) {
      const auto& o = c.scene.objects[i];
      EXPECT_EQ(library.object(o.name).split, "validation") << o.name;
      EXPECT_FALSE(o.tag.enabled);
      EXPECT_EQ(c.sequencer.objects[i].name, o.name);
      EXPECT_EQ(c.sequencer.objects[i].target.kind, ehc_control::TargetSelectorKind::Nearest);
      // Where the scene's object stood (within the jitter), on its support.
      EXPECT_LT((o.position - shipped.objects[i].position).head<2>().norm(), 0.015) << o.name;
      EXPECT_NEAR(o.position.z() - o.halfExtents().z(), shipped.objects[i].position.z() - shipped.objects[i].halfExtents().z(), 1e-9);
      EXPECT_LT((c.sequencer.objects[i].target.point - o.position).norm(), c.sequencer.objects[i].target.radius);
      names.insert(o.name);
      drawn.insert(o.name);
    }
    EXPECT_EQ(names.size(), 3u) << "an object twice";
    EXPECT_EQ(exp.runConfig("ehc", "", seed).scene.summary(), c.scene.summary()) << "same seed, same scene";
  }
  EXPECT_GT(drawn.size(), 6u);  // ten seeds draw widely
  GraspExperimentParams bad = p;
  bad.library_split = "all";
  EXPECT_NE(ehc_test::errorOf([&] { GraspExperiment(bad, {"ehc"}); }).find("library_split"), std::string::npos);
}
