// `make demo` reliability, reduced: the demo scene and configuration
// (config/scenes/table_three_objects.yaml, config/demo/*) through the in-process GraspPipeline
// with three noise seeds that each failed or closed short before the issue-18 fixes:
//   1040: back timed out in GRASP, TCP held 2.9 cm above the grasp by the wrist's table stop;
//   1060: middle stalled 1.0 cm short (same cause, 27 cm behind the table edge);
//   1220: back closed 2.4 cm short ("stalled ... closing there") on nothing.
// Every object must be grasped, and every grasp must close within 1 cm of its planned pose.
#include "ehc_bringup/grasp_experiment.h"

#include <gtest/gtest.h>

using namespace ehc_bringup;

TEST(DemoReliability, ThreeSeedsGraspThreeOfThreeClosingWithinOneCentimetre) {
  GraspExperimentParams p;
  p.config_dir = EHC_CONFIG_DIR;
  p.sets = 1;
  p.jitter_xy = 0.0;  // the demo scene as shipped
  p.jitter_yaw_deg = 0.0;
  p.timing = false;
  const GraspExperiment exp(p, {"ehc"});
  for (const unsigned seed : {1040u, 1060u, 1220u}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    GraspPipeline pipe(exp.runConfig("ehc", "", seed), seed);
    ASSERT_TRUE(pipe.runUntilDone(150.0)) << "the sequencer did not finish";
    const auto& results = pipe.sequencer().results();
    ASSERT_EQ(results.size(), 3u);
    for (const GraspResult& r : results) {
      std::printf("seed %u: %s\n", seed, graspResultLine(r).c_str());
      EXPECT_TRUE(r.success) << r.name << ": " << r.failed_phase << ": " << r.reason;
      EXPECT_GE(r.close_offset, 0.0) << r.name << " never closed";
      EXPECT_LE(r.close_offset, 0.01) << r.name << " closed " << r.close_offset << " m from its grasp";
    }
    EXPECT_EQ(pipe.counters().collision_steps, 0);
  }
}
