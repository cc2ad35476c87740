#include "ehc_bringup/reach_targets.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

using namespace ehc_bringup;

TEST(ReachTargets, GeneratorFollowsTheProtocolAndIsSeeded) {
  const ReachTargetGenerator g;
  const auto a = g.generate(500, 11), b = g.generate(500, 11), c = g.generate(500, 12);
  ASSERT_EQ(a.size(), 500u);
  Eigen::Vector2d prev = Eigen::Vector2d::Zero();
  double max_tilt = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_TRUE(a[i].isApprox(b[i]));
    const Eigen::Vector2d xy = a[i].translation().head<2>();
    const double d = (xy - prev).norm();
    EXPECT_GE(d, 1.5 - 1e-9);
    EXPECT_LE(d, 4.0 + 1e-9);
    EXPECT_GE(a[i].translation().z(), 0.3);
    EXPECT_LE(a[i].translation().z(), 1.0);
    // Approach axis (z) between straight down and horizontal.
    const double tilt = std::acos(std::clamp(-a[i].linear().col(2).z(), -1.0, 1.0));
    EXPECT_LE(tilt, M_PI / 2 + 1e-9);
    max_tilt = std::max(max_tilt, tilt);
    EXPECT_NEAR(a[i].linear().determinant(), 1.0, 1e-12);
    // The approach axis leans along the travel direction (within the 45 deg spread).
    const Eigen::Vector2d zh = a[i].linear().col(2).head<2>();
    if (zh.norm() > 1e-6) {
      EXPECT_GE(zh.normalized().dot((xy - prev).normalized()), std::cos(M_PI / 4) - 1e-9);
    }
    prev = xy;
  }
  EXPECT_GT(max_tilt, 80.0 * M_PI / 180.0);  // the whole tilt range is used
  EXPECT_FALSE(a[0].isApprox(c[0]));
}

TEST(ReachTargets, AnyPresetApproachesFromEverySideAndDistance) {
  const ReachTargetGenerator g = ReachTargetGenerator::preset("any");
  const auto a = g.generate(4000, 21);
  Eigen::Vector2d prev = Eigen::Vector2d::Zero();
  int below_horizontal = 0, against_travel = 0, near = 0, far = 0;
  Eigen::Vector3d mean_axis = Eigen::Vector3d::Zero();
  for (const Eigen::Isometry3d& t : a) {
    const Eigen::Vector2d xy = t.translation().head<2>();
    const double d = (xy - prev).norm();
    EXPECT_LE(d, 7.0 + 1e-9);
    near += d < 1.0;
    far += d > 6.0;
    const Eigen::Vector3d axis = t.linear().col(2);
    mean_axis += axis;
    below_horizontal += axis.z() > 0.1;  // approached from below
    if (axis.head<2>().norm() > 0.3 && d > 1e-3) against_travel += axis.head<2>().normalized().dot((xy - prev) / d) < -0.7;
    prev = xy;
  }
  // Uniform over the sphere: as many approach axes point up as down, every azimuth relative to
  // the travel direction occurs, and the distances cover [0, 7] m.
  EXPECT_LT((mean_axis / a.size()).norm(), 0.05);
  EXPECT_GT(below_horizontal, 1600);
  EXPECT_GT(against_travel, 300);
  EXPECT_GT(near, 300);
  EXPECT_GT(far, 300);
}

TEST(ReachTargets, PaperPresetIsTheDefaultAndUnknownPresetsAreErrors) {
  const auto p = ReachTargetGenerator::preset("paper");
  const ReachTargetGenerator d;
  EXPECT_EQ(p.summary(), d.summary());
  const auto a = p.generate(20, 5), b = d.generate(20, 5);
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_TRUE(a[i].isApprox(b[i]));
  try {
    ReachTargetGenerator::preset("everywhere");
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("[ReachTargetGenerator] unknown generator 'everywhere'"), std::string::npos) << e.what();
  }
  EXPECT_THROW(tiltSamplingFromString("cone"), std::invalid_argument);
  ReachTargetGenerator bad = d;
  bad.max_tilt_deg = 190.0;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

TEST(ReachTargets, CsvRoundTrip) {
  const auto t = ReachTargetGenerator{}.generate(20, 3);
  writeReachTargetsCsv("/tmp/ehc_targets.csv", t);
  const auto r = readReachTargetsCsv("/tmp/ehc_targets.csv");
  ASSERT_EQ(r.size(), t.size());
  for (std::size_t i = 0; i < t.size(); ++i) EXPECT_TRUE(r[i].isApprox(t[i], 1e-8));
}

TEST(ReachTargets, MalformedCsvNamesTheLine) {
  std::ofstream("/tmp/ehc_bad_targets.csv") << "x y z qx qy qz qw\n1 2 0.5 0 0 0 1\n1 2 0.5 0 0 1\n";
  try {
    readReachTargetsCsv("/tmp/ehc_bad_targets.csv");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("ehc_bad_targets.csv:3: expected 7 values"), std::string::npos)
        << e.what();
  }
  std::ofstream("/tmp/ehc_bad_targets.csv") << "1 2 0.5 0 0 0 2\n";
  EXPECT_THROW(readReachTargetsCsv("/tmp/ehc_bad_targets.csv"), std::invalid_argument);
  std::ofstream("/tmp/ehc_bad_targets.csv") << "1 2 nan 0 0 0 1\n";
  EXPECT_THROW(readReachTargetsCsv("/tmp/ehc_bad_targets.csv"), std::invalid_argument);
  EXPECT_THROW(readReachTargetsCsv("/nonexistent.csv"), std::invalid_argument);
}

TEST(ReachTargets, ReachabilityFilterRedrawsRejectedTargets) {
  const ReachTargetGenerator g;
  int rejected = 0;
  // Accept only targets above 0.6 m: every accepted one satisfies it, some were redrawn.
  const auto t = g.generate(100, 9, Eigen::Vector2d::Zero(),
                            [](const Eigen::Isometry3d& T) { return T.translation().z() > 0.6; }, &rejected);
  ASSERT_EQ(t.size(), 100u);
  for (const auto& T : t) EXPECT_GT(T.translation().z(), 0.6);
  EXPECT_GT(rejected, 20);
  EXPECT_THROW(g.generate(1, 9, Eigen::Vector2d::Zero(), [](const Eigen::Isometry3d&) { return false; }),
               std::invalid_argument);
}

TEST(ReachTargets, RelativeToPreviousKeepsEachApproachFromTheStart) {
  const auto seq = ReachTargetGenerator{}.generate(6, 9);
  const auto rel = relativeToPrevious(seq);
  ASSERT_EQ(rel.size(), seq.size());
  Eigen::Vector2d prev = Eigen::Vector2d::Zero();
  for (std::size_t i = 0; i < seq.size(); ++i) {
    EXPECT_TRUE(rel[i].translation().head<2>().isApprox(seq[i].translation().head<2>() - prev, 1e-12));
    EXPECT_DOUBLE_EQ(rel[i].translation().z(), seq[i].translation().z());
    EXPECT_TRUE(rel[i].linear().isApprox(seq[i].linear(), 1e-15));
    prev = seq[i].translation().head<2>();
  }
}
