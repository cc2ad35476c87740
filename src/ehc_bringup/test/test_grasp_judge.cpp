// GraspJudge: grasps judged against a true mesh. Known grasps on a box and a cylinder (valid, too
// wide, a contact 45 deg off the closing axis, a finger into the table, closing on nothing), random
// boxes and grasps against the analytic verdict (seed printed), and the search for a valid grasp.

#include "ehc_bringup/grasp_judge.h"

#include "ehc_test/errors.h"
#include "ehc_test/test_seed.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

using ehc_bringup::GraspJudge;
using ehc_bringup::GraspJudgeParams;
using ehc_bringup::GraspVerdict;

namespace {

constexpr double kTable = 0.75;
constexpr double kDeg = M_PI / 180.0;

/// Grasp frame at `origin`: closing axis `y`, approach `z` (both unit, perpendicular).
Eigen::Isometry3d graspPose(const Eigen::Vector3d& origin, const Eigen::Vector3d& y, const Eigen::Vector3d& z) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear().col(0) = y.cross(z);
  T.linear().col(1) = y;
  T.linear().col(2) = z;
  T.translation() = origin;
  return T;
}

/// An object resting on the table, yawed by `yaw`, its body frame at its bounding-box centre.
Eigen::Isometry3d onTable(double x, double y, double half_height, double yaw = 0.0) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, y, kTable + half_height);
  return T;
}

const Eigen::Vector3d kDown(0, 0, -1);

}  // namespace

TEST(GraspJudge, VerdictNamesRoundTripAndBadParametersFail) {
  for (const GraspVerdict v : {GraspVerdict::Valid, GraspVerdict::OutsideOpening, GraspVerdict::PalmCollides})
    EXPECT_EQ(ehc_bringup::graspVerdictFromString(ehc_bringup::toString(v)), v);
  EXPECT_THROW(ehc_bringup::graspVerdictFromString("fine"), std::invalid_argument);
  GraspJudgeParams p;
  p.friction_coefficient = std::nan("");
  EXPECT_THROW(p.validate(), std::invalid_argument);
  EXPECT_THROW(GraspJudge(ehc_sim::TriangleMesh(), Eigen::Isometry3d::Identity(), kTable, {}, {}), std::invalid_argument);
}

TEST(GraspJudge, BoxGraspsFromAbove) {
  // A standing 50 x 50 x 100 mm box; top at 0.85 m.
  const GraspJudge judge(ehc_sim::boxSurface({0.05, 0.05, 0.10}), onTable(0, 0, 0.05), kTable, {}, {});
  // Top-down, closing across y, 30 mm below the top: fingertips 40 mm, palm 10 mm above the top.
  const auto good = judge.judge(graspPose({0, 0, 0.82}, Eigen::Vector3d::UnitY(), kDown));
  EXPECT_EQ(good.verdict, GraspVerdict::Valid) << toString(good.verdict);
  EXPECT_NEAR(good.width, 0.05, 1e-6);
  EXPECT_NEAR(good.contact_angle_deg[0], 0.0, 1e-3);
  EXPECT_NEAR(good.contact[1].y(), 0.025, 1e-6);
  EXPECT_NEAR(judge.closedWidth(graspPose({0, 0, 0.82}, Eigen::Vector3d::UnitY(), kDown)), 0.05, 1e-6);
  // Palm into the top: 60 mm below it.
  EXPECT_EQ(judge.judge(graspPose({0, 0, 0.79}, Eigen::Vector3d::UnitY(), kDown)).verdict, GraspVerdict::PalmCollides);
  // 20 mm off the centre along y: the -y finger's inner face (at y = -15 mm) is inside the box.
  EXPECT_EQ(judge.judge(graspPose({0, 0.02, 0.82}, Eigen::Vector3d::UnitY(), kDown)).verdict, GraspVerdict::OutsideOpening);
  // 150 mm beside the box: nothing between the fingers.
  EXPECT_EQ(judge.judge(graspPose({0, 0.15, 0.82}, Eigen::Vector3d::UnitY(), kDown)).verdict, GraspVerdict::NothingBetween);
  // Approach from below the horizon by more than 5 deg (the generator's 95 deg from straight down).
  const Eigen::Vector3d rising = Eigen::Vector3d(1, 0, std::tan(10 * kDeg)).normalized();
  EXPECT_EQ(judge.judge(graspPose({-0.01, 0, 0.80}, Eigen::Vector3d::UnitY(), rising)).verdict,
            GraspVerdict::ApproachExcluded);
  Eigen::Isometry3d nan = graspPose({0, 0, 0.82}, Eigen::Vector3d::UnitY(), kDown);
  nan.translation().x() = std::nan("");
  EXPECT_EQ(judge.judge(nan).verdict, GraspVerdict::NotFinite);
}

TEST(GraspJudge, WiderThanTheOpeningIsRejected) {
  // 90 mm across y, 40 mm across x: across y it does not fit the 70 mm opening, across x it does.
  const GraspJudge judge(ehc_sim::boxSurface({0.04, 0.09, 0.10}), onTable(0, 0, 0.05), kTable, {}, {});
  EXPECT_EQ(judge.judge(graspPose({0, 0, 0.82}, Eigen::Vector3d::UnitY(), kDown)).verdict, GraspVerdict::OutsideOpening);
  EXPECT_EQ(judge.judge(graspPose({0, 0, 0.82}, Eigen::Vector3d::UnitX(), kDown)).verdict, GraspVerdict::Valid);
}

TEST(GraspJudge, ContactNormalOutsideTheFrictionCone) {
  // A 40 mm box yawed 45 deg; the closing line along y, 5 mm off the centre, meets two faces whose
  // normals are 45 deg off it: outside the cone of mu 0.5 (26.6 deg), inside that of mu 1.2 (50.2).
  const Eigen::Isometry3d T = onTable(0, 0, 0.05, 45 * kDeg);
  const ehc_sim::TriangleMesh box = ehc_sim::boxSurface({0.04, 0.04, 0.10});
  const Eigen::Isometry3d g = graspPose({0.005, 0, 0.82}, Eigen::Vector3d::UnitY(), kDown);
  const GraspJudge strict(box, T, kTable, {}, {});
  const auto j = strict.judge(g);
  EXPECT_EQ(j.verdict, GraspVerdict::OutsideFrictionCone);
  EXPECT_NEAR(j.contact_angle_deg[0], 45.0, 1e-3);
  EXPECT_NEAR(j.contact_angle_deg[1], 45.0, 1e-3);
  GraspJudgeParams p;
  p.friction_coefficient = 1.2;
  EXPECT_EQ(GraspJudge(box, T, kTable, {}, p).judge(g).verdict, GraspVerdict::Valid);
  // Between the contacts on the closing line 2 x (28.3 - 5) mm; the pads (20 mm broad) stop at the
  // box's edge on the centre line (its 56.6 mm diagonal) if a ray of the 1 mm grid meets it.
  EXPECT_NEAR(j.width, 2 * (0.02 * std::sqrt(2.0) - 0.005), 1e-6);
  EXPECT_NEAR(strict.closedWidth(g, 0.001), 0.04 * std::sqrt(2.0), 1e-6);  // a ray on the centre line
}

TEST(GraspJudge, FingerThroughAPartOfTheObject) {
  // A 50 mm box with a 6 mm bar standing beside it, 40 mm from its centre along y (a handle): the
  // +y finger (inner face at 35 mm, 10 mm thick) comes down onto the bar.
  ehc_sim::TriangleMesh mesh = ehc_sim::boxSurface({0.05, 0.05, 0.10});
  ehc_sim::TriangleMesh bar = ehc_sim::boxSurface({0.006, 0.006, 0.10});
  for (Eigen::Vector3d& v : bar.vertices) v.y() += 0.04;
  mesh.append(bar);
  const GraspJudge judge(mesh, onTable(0, 0, 0.05), kTable, {}, {});
  EXPECT_EQ(judge.judge(graspPose({0, 0, 0.82}, Eigen::Vector3d::UnitY(), kDown)).verdict, GraspVerdict::FingerCollides);
  // Closing across x instead: the fingers at x = +-35..45 mm miss the bar; the palm (110 mm along
  // x, 60 mm along y) stays above the top.
  EXPECT_EQ(judge.judge(graspPose({0, 0, 0.82}, Eigen::Vector3d::UnitX(), kDown)).verdict, GraspVerdict::Valid);
  // The same with the pre-grasp sweep off: only the fingers at the grasp pose, still on the bar.
  GraspJudgeParams p;
  p.pregrasp_distance = 0.0;
  EXPECT_EQ(GraspJudge(mesh, onTable(0, 0, 0.05), kTable, {}, p).judge(graspPose({0, 0, 0.82}, Eigen::Vector3d::UnitY(), kDown)).verdict,
            GraspVerdict::FingerCollides);
}

TEST(GraspJudge, FingerIntoTheTable) {
  // A 20 mm high box: the closing line 5 mm above the table puts the fingertips 5 mm below it.
  const GraspJudge judge(ehc_sim::boxSurface({0.05, 0.05, 0.02}), onTable(0, 0, 0.01), kTable, {}, {});
  EXPECT_EQ(judge.judge(graspPose({0, 0, kTable + 0.005}, Eigen::Vector3d::UnitY(), kDown)).verdict, GraspVerdict::HitsTable);
  EXPECT_EQ(judge.judge(graspPose({0, 0, kTable + 0.015}, Eigen::Vector3d::UnitY(), kDown)).verdict, GraspVerdict::Valid);
}

TEST(GraspJudge, CylinderFromTheSideAndAbove) {
  // A standing 50 mm cylinder, 100 mm high (64 sides).
  const GraspJudge judge(ehc_sim::cylinderSurface(0.05, 0.10, 64), onTable(0, 0, 0.05), kTable, {}, {},
                         Eigen::Vector3d(1, 0, -1));
  const auto side = judge.judge(graspPose({0, 0, 0.80}, Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitX()));
  EXPECT_EQ(side.verdict, GraspVerdict::Valid) << toString(side.verdict);
  EXPECT_NEAR(side.width, 0.05, 0.001);
  EXPECT_EQ(judge.judge(graspPose({0, 0, 0.82}, Eigen::Vector3d::UnitY(), kDown)).verdict, GraspVerdict::Valid);
  // From behind the object as the camera sees it (approach against the view direction).
  EXPECT_EQ(judge.judge(graspPose({0, 0, 0.80}, Eigen::Vector3d::UnitY(), -Eigen::Vector3d::UnitX())).verdict,
            GraspVerdict::ApproachExcluded);
  // Side grasp 15 mm above the table: the palm (60 mm across x) reaches below the top.
  EXPECT_EQ(judge.judge(graspPose({0, 0, kTable + 0.015}, Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitX())).verdict,
            GraspVerdict::HitsTable);
}

namespace {

/// The farther contact's distance from the grasp origin: the closing line (angle alpha to the
/// box's a axis, delta along itself and eps across it from the centre) meets the faces +-a.
double reach(double a, double alpha, double delta, double eps) {
  return (a + std::abs(eps) * std::sin(alpha)) / std::cos(alpha) + std::abs(delta);
}

/// The line meets the faces +-a (not the faces +-b) and stays 1 mm inside them.
bool meetsTheAFaces(double a, double b, double alpha, double eps) {
  return std::abs(eps) / std::cos(alpha) + a * std::tan(alpha) < b - 0.001;
}

/// The verdict of a top-down grasp on a box resting on the table (yawed), its closing axis at
/// `alpha` from the box's half-extent `a` axis, `delta` off the centre along the closing axis,
/// `eps` across it, the closing line `dz` below the top; the gripper's default geometry. The line
/// meets the faces +-a (meetsTheAFaces).
GraspVerdict expectedTopDown(double a, double h, double alpha, double delta, double eps, double dz, double mu) {
  const ehc_perception::GripperGeometry g;
  const double half = 0.5 * g.max_width;
  if (dz <= 0.0 || dz >= 2 * h) return GraspVerdict::NothingBetween;  // the line above or in the table
  if (reach(a, alpha, delta, eps) > half) return GraspVerdict::OutsideOpening;
  if (alpha > std::atan(mu)) return GraspVerdict::OutsideFrictionCone;
  if (kTable + 2 * h - dz - g.finger_tip_depth < kTable) return GraspVerdict::HitsTable;
  if (dz > g.finger_length - g.finger_tip_depth) return GraspVerdict::PalmCollides;
  return GraspVerdict::Valid;
}

}  // namespace

TEST(GraspJudge, RandomBoxesAgreeWithTheGeometry) {
  const unsigned seed = ehc_test::testSeed("GraspJudge random boxes");
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::map<GraspVerdict, int> seen;
  int cases = 0;
  for (int trial = 0; cases < 400 && trial < 4000; ++trial) {
    const double a = 0.008 + 0.04 * unit(rng), b = 0.008 + 0.04 * unit(rng), h = 0.008 + 0.05 * unit(rng);
    const double yaw = 2 * M_PI * unit(rng), mu = 0.3 + 0.7 * unit(rng);
    // Angled closing lines only on boxes whose footprint the fingers (35 mm out) cannot reach.
    const double alpha = std::hypot(a, b) < 0.034 ? 40 * kDeg * unit(rng) : 0.0;
    const double delta = alpha > 0 ? 0.0 : 0.02 * (unit(rng) - 0.5), eps = 0.8 * b * (unit(rng) - 0.5);
    const double dz = -0.005 + (2 * h + 0.01) * unit(rng);
    if (!meetsTheAFaces(a, b, alpha, eps)) continue;
    // Away from every threshold by 1 mm (0.5 deg).
    if (std::abs(reach(a, alpha, delta, eps) - 0.035) < 0.001 || std::abs(dz) < 0.001 || std::abs(dz - 2 * h) < 0.001 ||
        std::abs(2 * h - dz - 0.01) < 0.001 || std::abs(dz - 0.04) < 0.001 || std::abs(alpha - std::atan(mu)) < 0.5 * kDeg)
      continue;
    const Eigen::Isometry3d T = onTable(0.3 * unit(rng), 0.3 * unit(rng), h, yaw);
    GraspJudgeParams p;
    p.friction_coefficient = mu;
    const GraspJudge judge(ehc_sim::boxSurface({2 * a, 2 * b, 2 * h}), T, kTable, {}, p);
    const Eigen::Vector3d y = T.linear() * Eigen::Vector3d(std::cos(alpha), std::sin(alpha), 0.0);
    const Eigen::Vector3d across = T.linear() * Eigen::Vector3d(-std::sin(alpha), std::cos(alpha), 0.0);
    const Eigen::Vector3d origin = T.translation() + delta * y + eps * across + Eigen::Vector3d(0, 0, h - dz);
    const GraspVerdict expected = expectedTopDown(a, h, alpha, delta, eps, dz, mu);
    const GraspVerdict got = judge.judge(graspPose(origin, y, kDown)).verdict;
    ++cases;
    ++seen[expected];
    EXPECT_EQ(toString(got), toString(expected))
        << "seed " << seed << " trial " << trial << ": box " << 2e3 * a << " x " << 2e3 * b << " x " << 2e3 * h << " mm, alpha "
        << alpha / kDeg << " deg, delta " << 1e3 * delta << " mm, eps " << 1e3 * eps << " mm, dz " << 1e3 * dz << " mm, mu " << mu;
  }
  std::printf("%d random grasps on random boxes:", cases);
  for (const auto& [v, n] : seen) std::printf(" %s %d", toString(v).c_str(), n);
  std::printf("\n");
  EXPECT_GE(cases, 300);
  EXPECT_GE(seen.size(), 6u) << "every verdict of a top-down grasp occurs";
}

TEST(GraspJudge, AValidGraspExistsOnlyWhereOneFits) {
  GraspJudgeParams p;
  p.samples = 200;
  const Eigen::Vector3d view(1, 0, -1);
  const GraspJudge small(ehc_sim::boxSurface({0.05, 0.05, 0.10}), onTable(0, 0, 0.05), kTable, {}, p, view);
  const auto e1 = small.findValidGrasp(7), e2 = small.findValidGrasp(7);
  EXPECT_TRUE(e1.exists);
  EXPECT_EQ(e1.candidates, e2.candidates) << "same seed, same search";
  EXPECT_EQ(small.judge(e1.grasp).verdict, GraspVerdict::Valid);
  // A 100 mm cube: nothing fits the 70 mm opening.
  const GraspJudge big(ehc_sim::boxSurface({0.10, 0.10, 0.10}), onTable(0, 0, 0.05), kTable, {}, p, view);
  const auto e3 = big.findValidGrasp(7);
  EXPECT_FALSE(e3.exists);
  // A 6 mm thin plate lying flat: only its 6 mm edges could be grasped, 3 mm above the table.
  const GraspJudge flat(ehc_sim::boxSurface({0.05, 0.05, 0.006}), onTable(0, 0, 0.003), kTable, {}, p, view);
  const auto e4 = flat.findValidGrasp(7);
  EXPECT_FALSE(e4.exists) << toString(e4.commonest());
  // A 26 mm rod lying on the table (axis along x): closing across it, parallel to the table, from
  // above; its closing line must be 10 mm above the table (fingertips) and its contacts within
  // 26.6 deg of horizontal, a narrow band of the surface.
  Eigen::Isometry3d lying = onTable(0, 0, 0.013);
  lying.linear() = Eigen::AngleAxisd(0.5 * M_PI, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const GraspJudge rod(ehc_sim::cylinderSurface(0.026, 0.20, 48), lying, kTable, {}, p, view);
  const auto e5 = rod.findValidGrasp(7);
  EXPECT_TRUE(e5.exists);
  std::printf("standing box: valid after %d candidates; 100 mm cube: %d judged; flat plate: %d judged, mostly %s; "
              "lying rod: valid after %d\n",
              e1.candidates, e3.candidates, e4.candidates, toString(e4.commonest()).c_str(), e5.candidates);
}

TEST(GraspJudge, TheExistenceSearchTakesOnlyGraspsItsAcceptanceTestAccepts) {
  // An acceptance test (e.g. the robot's reach) narrows the search: a random box that fits the
  // opening, only approaches tilted at least `tilt` from straight down towards a random side
  // (within 45 deg of its azimuth) accepted, then none; the search puts at most accept_checks
  // valid grasps to the test.
  const unsigned seed = ehc_test::testSeed("GraspJudge acceptance test");
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  GraspJudgeParams p;
  p.samples = 300;
  p.accept_checks = 200 + static_cast<int>(100 * u(rng));
  const Eigen::Vector3d size(0.03 + 0.03 * u(rng), 0.03 + 0.03 * u(rng), 0.06 + 0.08 * u(rng));
  const GraspJudge box(ehc_sim::boxSurface(size), onTable(0, 0, 0.5 * size.z()), kTable, {}, p, Eigen::Vector3d(1, 0, -1));
  const double tilt = (30.0 + 30.0 * u(rng)) * M_PI / 180.0, azimuth = 2.0 * M_PI * u(rng);
  const Eigen::Vector3d side(std::cos(azimuth), std::sin(azimuth), 0.0);
  int calls = 0;
  const auto tilted = [&](const Eigen::Isometry3d& g) {
    ++calls;
    EXPECT_EQ(box.judge(g).verdict, GraspVerdict::Valid) << "only valid grasps are put to the test";
    const Eigen::Vector3d z = g.linear().col(2);
    return -z.z() <= std::cos(tilt) && z.head<2>().normalized().dot(side.head<2>()) >= std::cos(M_PI / 4.0);
  };
  const ehc_bringup::GraspExistence found = box.findValidGrasp(seed, tilted);
  std::printf("seed %u: box %.3f x %.3f x %.3f, tilt >= %.0f deg towards azimuth %.0f deg: %d tested, %d refused\n", seed,
              size.x(), size.y(), size.z(), tilt * 180.0 / M_PI, azimuth * 180.0 / M_PI, calls, found.refused);
  ASSERT_TRUE(found.exists);
  EXPECT_EQ(box.judge(found.grasp).verdict, GraspVerdict::Valid);
  const Eigen::Vector3d z = found.grasp.linear().col(2);
  EXPECT_LE(-z.z(), std::cos(tilt) + 1e-9);
  EXPECT_GE(z.head<2>().normalized().dot(side.head<2>()), std::cos(M_PI / 4.0) - 1e-9);
  EXPECT_EQ(found.refused, calls - 1);
  EXPECT_TRUE(box.findValidGrasp(seed).exists) << "without a test: the first valid grasp";
  calls = 0;
  const ehc_bringup::GraspExistence none = box.findValidGrasp(seed, [&](const Eigen::Isometry3d& g) { return tilted(g) && false; });
  EXPECT_FALSE(none.exists);
  EXPECT_EQ(none.refused, p.accept_checks);
  EXPECT_EQ(calls, p.accept_checks);
  p.accept_checks = 0;
  EXPECT_NE(ehc_test::errorOf([&] { p.validate(); }).find("accept_checks"), std::string::npos);
}

TEST(GraspJudge, LibraryViewsAreTheSameInASplitAndInAll) {
  const ehc_sim::ObjectLibrary lib = ehc_sim::loadObjectLibrary(std::string(EHC_CONFIG_DIR) + "/objects/library.yaml");
  const ehc_sim::SimConfig sim = ehc_sim::loadSimConfig(std::string(EHC_CONFIG_DIR) + "/sim/bullet_sim.yaml");
  const ehc_perception::GraspGenerator generator{ehc_perception::GraspGeneratorConfig()};
  ehc_bringup::LibraryJudgeParams p;
  p.views = 1;
  p.seed = 3;
  p.judge.samples = 100;
  p.split = "validation";
  std::size_t calls = 0;
  const auto validation = ehc_bringup::judgeLibrary(lib, sim, generator, {}, p, [&](const auto&, std::size_t done, std::size_t total) {
    ++calls;
    EXPECT_EQ(done, calls);
    EXPECT_EQ(total, lib.objects.size() / 2);
  });
  p.split = "all";
  const auto all = ehc_bringup::judgeLibrary(lib, sim, generator, {}, p, nullptr);
  ASSERT_EQ(all.size(), lib.objects.size());
  ASSERT_EQ(validation.size(), lib.objects.size() / 2);
  std::vector<ehc_bringup::JudgedView> subset;
  for (const auto& v : all)
    if (v.split == "validation") subset.push_back(v);
  EXPECT_EQ(ehc_bringup::judgedViewsCsv(subset), ehc_bringup::judgedViewsCsv(validation));
  const std::string summary = ehc_bringup::judgedViewsSummary(all, "test");
  std::printf("%s", summary.c_str());
  EXPECT_NE(summary.find("| tuning | 18 |"), std::string::npos) << "18 tuning objects, one view each";
  EXPECT_NE(summary.find("| validation | 18 |"), std::string::npos);
  p.views = 0;
  EXPECT_THROW(ehc_bringup::judgeLibrary(lib, sim, generator, {}, p, nullptr), std::invalid_argument);
}
