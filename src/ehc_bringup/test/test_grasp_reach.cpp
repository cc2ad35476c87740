// GraspReach and the grasp choice that uses it: the support's footprint from a cloud, the
// distance of a link box to it, the reachability of a grasp beside a table on every shipped
// robot (near the edge yes, in the middle of a wide table no, without a support yes; the kept
// verdict's configurations on the pre-grasp and the grasp), and
// chooseGrasp: an unreachable higher-scored candidate loses to a reachable one (fixed and
// randomized cases, seed printed); the configurations checked against an obstacle map (the
// object left out during the descent, a neighbour at the pre-grasp blocking, a kept verdict
// checked again as the map grows); the way to a placement does not cut a corner of the
// support (randomized, seed printed); bad parameters are rejected.

#include "ehc_bringup/grasp_reach.h"
#include "ehc_bringup/grasp_selection.h"
#include "ehc_common/config_node.h"
#include "ehc_control/qp_controller.h"
#include "ehc_control/robot_collision_model.h"
#include "ehc_control/robot_config.h"
#include "ehc_perception/obstacle_distance_field.h"
#include "ehc_test/errors.h"
#include "ehc_test/test_seed.h"

#include <gtest/gtest.h>

#include <chrono>
#include <functional>
#include <random>

using namespace ehc_bringup;
using ehc_test::errorOf;

namespace {

/// A table top (world): centre, size (x, y), height; its footprint counter-clockwise.
SupportSurface table(const Eigen::Vector2d& centre, const Eigen::Vector2d& size, double height) {
  SupportSurface s;
  s.height = height;
  const Eigen::Vector2d h = 0.5 * size;
  s.footprint = {centre + Eigen::Vector2d(-h.x(), -h.y()), centre + Eigen::Vector2d(h.x(), -h.y()),
                 centre + Eigen::Vector2d(h.x(), h.y()), centre + Eigen::Vector2d(-h.x(), h.y())};
  return s;
}

/// TCP pose with approach (z) `z` at `p`, the closing axis (y) horizontal.
Eigen::Isometry3d graspAt(const Eigen::Vector3d& p, const Eigen::Vector3d& z) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  const Eigen::Vector3d a = z.normalized();
  Eigen::Vector3d y = a.cross(Eigen::Vector3d::UnitZ());
  if (y.norm() < 1e-6) y = Eigen::Vector3d::UnitY();
  y.normalize();
  T.linear().col(0) = y.cross(a);
  T.linear().col(1) = y;
  T.linear().col(2) = a;
  T.translation() = p;
  return T;
}

/// The pre-grasp 10 cm back along the approach (the sequencer's default pregrasp_distance).
Eigen::Isometry3d preGraspOf(const Eigen::Isometry3d& g) { return backedOff(g, 0.10); }

/// One robot's model and its controller's stop distances and joint stop (config/control/controller.yaml).
struct Robot {
  ehc_control::RobotConfig rc;
  std::unique_ptr<ehc_control::WholeBodyModel> model;
  ehc_control::QpControllerParams ctrl;
  explicit Robot(const std::string& name) : rc(ehc_control::loadRobotConfig(ehc_control::resolveRobotFile(name))) {
    model = std::make_unique<ehc_control::WholeBodyModel>(rc);
    const auto cfg = ehc_common::ConfigNode::loadFile(ehc_control::configDirectory() + "/control/controller.yaml", "test");
    ctrl = ehc_control::loadQpControllerParams(cfg.child("controller"));
    for (const auto& kv : rc.obstacle_stop_distances) ctrl.obstacle_stop_links.insert(kv);
  }
  GraspReach reach(const GraspReachParams& p = {}) const {
    const ehc_control::QpControllerParams& c = ctrl;
    return GraspReach(*model, p, [&c](const std::string& l) { return c.obstacleStop(l); }, ctrl.joint_stop);
  }
};

/// The ready posture's TCP pose with the base at the origin, its pre-grasp, and a table top 25 cm
/// below it whose near edge lies 5 cm beyond it (away from the robot): the robot stands where
/// the ready posture puts it, so the grasp is reachable on every robot.
struct ReadyGrasp {
  Eigen::Isometry3d grasp, pre;
  double height;  ///< of the table top
  SupportSurface table_top;
};
ReadyGrasp readyGrasp(const Robot& robot) {
  ReadyGrasp r;
  r.grasp = robot.model->fk(Eigen::Vector3d::Zero(), robot.rc.arm_ready, robot.rc.tcp_frame);
  r.pre = preGraspOf(r.grasp);
  r.height = r.grasp.translation().z() - 0.25;
  r.table_top = table(r.grasp.translation().head<2>() + Eigen::Vector2d(0.05 + 0.4, 0.0), Eigen::Vector2d(0.8, 1.2), r.height);
  return r;
}

/// An obstacle field for a robot's checked links (the controller's map, empty) and GraspReach's
/// view of it: the links' distances with `zones(descent)` left out, each call counted in `queries`.
struct MapView {
  ehc_control::RobotCollisionModel collision;
  ehc_perception::ObstacleDistanceField field;
  int queries = 0;
  explicit MapView(const Robot& robot)
      : collision(robot.model->calibratedUrdfXml(), robot.rc.arm_joints, robot.rc.checked_links),
        field(ehc_perception::ObstacleMapConfig{}, collision) {}
  GraspReach::MapDistances distances(const Robot& robot,
                                     std::function<std::vector<ehc_perception::ExclusionZone>(bool)> zones) {
    return [this, &robot, zones](const Eigen::Vector3d& base, const Eigen::VectorXd& q, bool descent) {
      ++queries;
      std::vector<std::pair<std::string, double>> out;
      for (const auto& d : field.distances(field.linkPoses(*robot.model, base, q), zones(descent)))
        out.emplace_back(d.link, d.distance);
      return out;
    };
  }
};

/// A robot standing where its ready posture reaches the ready grasp, GraspReach with that grasp's
/// table top as its support, and an empty obstacle map (MapView): the obstacle map tests' setting.
struct ReachBesideTable {
  Robot robot;
  GraspReach reach;
  ReadyGrasp ready;
  MapView map;
  explicit ReachBesideTable(const std::string& name)
      : robot(name), reach(robot.reach()), ready(readyGrasp(robot)), map(robot) {
    reach.setSupport(ready.table_top);
  }
};

}  // namespace

TEST(SupportSurface, FootprintOfTheSupportPlanesPointsInARandomCloud) {
  const unsigned seed = ehc_test::testSeed("support footprint");
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Eigen::Vector2d c(1.5 + 0.5 * u(rng), 0.3 * u(rng)), size(0.5 + 0.3 * (u(rng) + 1.0), 0.6 + 0.4 * (u(rng) + 1.0));
  const double h = 0.7 + 0.05 * u(rng);
  std::vector<Eigen::Vector3f> cloud;
  for (int i = 0; i < 4000; ++i)  // the top, 2 mm noise
    cloud.emplace_back(Eigen::Vector3d(c.x() + 0.5 * size.x() * u(rng), c.y() + 0.5 * size.y() * u(rng), h + 0.002 * u(rng)).cast<float>());
  for (int i = 0; i < 1000; ++i)  // an object on it and the floor beside it: not the support
    cloud.emplace_back(Eigen::Vector3d(c.x() + 0.05 * u(rng), c.y() + 0.05 * u(rng), h + 0.03 + 0.1 * (u(rng) + 1.0)).cast<float>());
  for (int i = 0; i < 1000; ++i)
    cloud.emplace_back(Eigen::Vector3d(c.x() + 2.0 * u(rng), c.y() + 2.0 * u(rng), 0.0).cast<float>());
  const auto s = supportFromPoints(cloud, Eigen::Vector4d(0, 0, 1, -h));
  ASSERT_TRUE(s);
  EXPECT_TRUE(s->valid());
  EXPECT_NEAR(s->height, h, 0.002);
  const SupportSurface truth = table(c, size, h);
  for (const Eigen::Vector2d& corner : s->footprint)  // every corner on or inside the true top
    EXPECT_LT(supportDistance(truth, Eigen::Vector3d(corner.x(), corner.y(), h), Eigen::Vector3d::Zero()), 1e-6);
  for (const Eigen::Vector2d& corner : truth.footprint)  // and the true corners within 5 cm of it
    EXPECT_LT(supportDistance(*s, Eigen::Vector3d(corner.x(), corner.y(), h), Eigen::Vector3d::Zero()), 0.05);
  // A second view of the other half merges into one footprint; one at another height replaces it.
  const SupportSurface other = table(c + Eigen::Vector2d(0.5 * size.x(), 0.0), size, h + 0.01);
  const SupportSurface merged = mergedSupport(*s, other);
  const double hm = merged.height;
  EXPECT_LT(supportDistance(merged, Eigen::Vector3d(c.x() - 0.45 * size.x(), c.y(), hm), Eigen::Vector3d::Zero()), 1e-6);
  EXPECT_LT(supportDistance(merged, Eigen::Vector3d(c.x() + 0.95 * size.x(), c.y(), hm), Eigen::Vector3d::Zero()), 1e-6);
  const SupportSurface shelf = table(c, size, h + 0.3);
  EXPECT_NEAR(mergedSupport(*s, shelf).height, h + 0.3, 1e-12);
  EXPECT_FALSE(supportFromPoints(cloud, Eigen::Vector4d(1, 0, 0, 0))) << "a vertical plane is no support";
}

TEST(SupportSurface, DistanceOfABoxToTheTop) {
  const SupportSurface s = table(Eigen::Vector2d(1.9, 0.0), Eigen::Vector2d(0.8, 1.2), 0.75);
  const Eigen::Vector3d half(0.05, 0.05, 0.05);
  EXPECT_NEAR(supportDistance(s, Eigen::Vector3d(1.9, 0.0, 0.85), half), 0.05, 1e-12) << "above the top";
  EXPECT_NEAR(supportDistance(s, Eigen::Vector3d(1.9, 0.0, 0.60), half), 0.10, 1e-12) << "under the top";
  EXPECT_NEAR(supportDistance(s, Eigen::Vector3d(1.9, 0.0, 0.75), half), 0.0, 1e-12) << "through it";
  const double r = half.head<2>().norm();
  EXPECT_NEAR(supportDistance(s, Eigen::Vector3d(1.5 - r - 0.03, 0.0, 0.75), half), 0.03, 1e-12) << "beside the edge";
  EXPECT_NEAR(supportDistance(s, Eigen::Vector3d(1.5 - r - 0.03, 0.0, 0.75 + 0.05 + 0.04), half), 0.05, 1e-12);
}

TEST(SupportSurface, AWayKeepsItsEndsClearanceUpToTheCorridorItDoesNotCutACorner) {
  // Random rectangles (size, rotation, place). A way tangent to a corner, c outside it, between
  // points beside its two adjacent sides (0.2-0.6 m out): refused while the corridor and the
  // ends' clearance exceed c by more than the outline tolerance (2 cm), taken with a corridor
  // below c. A way parallel to a side, both ends equally far out: taken, whatever the corridor
  // (also 1 cm off parallel). Ends inside, or a way across the top: refused.
  const unsigned seed = ehc_test::testSeed("way round a corner");
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const double L = 0.4 + u(rng), W = 0.4 + u(rng), a = 2.0 * M_PI * u(rng);
    const Eigen::Rotation2Dd R(a);
    const Eigen::Vector2d o(3.0 * u(rng) - 1.5, 3.0 * u(rng) - 1.5);
    const auto world = [&](double x, double y) { return Eigen::Vector2d(o + R * Eigen::Vector2d(x, y)); };
    const std::vector<Eigen::Vector2d> fp = {world(0, 0), world(L, 0), world(L, W), world(0, W)};
    const double c = 0.005 + 0.045 * u(rng), corridor = 0.2 + 0.3 * u(rng);
    const double k1 = 0.3 + 0.5 * u(rng), k2 = 0.3 + 0.5 * u(rng);
    // Tangent at P, c out along the corner's diagonal; the ends beside the sides x = 0 and y = 0.
    const Eigen::Vector2d P = -c * Eigen::Vector2d(1, 1).normalized(), t = Eigen::Vector2d(1, -1).normalized();
    const Eigen::Vector2d from = world((P - k1 * t).x(), (P - k1 * t).y()), to = world((P + k2 * t).x(), (P + k2 * t).y());
    EXPECT_FALSE(wayKeepsClear(fp, from, to, corridor)) << "seed " << seed << " trial " << trial << ": cuts the corner";
    EXPECT_TRUE(wayKeepsClear(fp, from, to, 0.5 * c)) << "seed " << seed << " trial " << trial << ": corridor below c";
    const double d = 0.05 + 0.55 * u(rng), x1 = L * u(rng), x2 = L * u(rng);
    EXPECT_TRUE(wayKeepsClear(fp, world(x1, -d), world(x2, -d), corridor)) << "seed " << seed << " trial " << trial;
    EXPECT_TRUE(wayKeepsClear(fp, world(x1, -d), world(x2, -d - 0.01), corridor)) << "seed " << seed << " trial " << trial;
    EXPECT_FALSE(wayKeepsClear(fp, world(0.5 * L, 0.5 * W), world(x2, -d), corridor)) << "an end on the top";
    EXPECT_FALSE(wayKeepsClear(fp, world(0.5 * L, -d), world(0.5 * L, W + d), 0.0)) << "across the top";
  }
}

TEST(GraspReach, RejectsBadParameters) {
  const auto bad = [](auto change) {
    GraspReachParams p;
    change(p);
    return errorOf([&] { p.validate(); });
  };
  EXPECT_NE(bad([](GraspReachParams& p) { p.bearings = 2; }).find("[GraspReachParams] bearings"), std::string::npos);
  EXPECT_NE(bad([](GraspReachParams& p) { p.ik_attempts = 0; }).find("ik_attempts"), std::string::npos);
  EXPECT_NE(bad([](GraspReachParams& p) { p.bearings = 73; }).find("bearings"), std::string::npos);
  EXPECT_NE(bad([](GraspReachParams& p) { p.clearance = -0.01; }).find("clearance"), std::string::npos);
  EXPECT_NE(bad([](GraspReachParams& p) { p.clearance = std::nan(""); }).find("clearance"), std::string::npos);
  EXPECT_NE(bad([](GraspReachParams& p) { p.grasp_support_exclusion = 2.0; }).find("grasp_support_exclusion"), std::string::npos);
  EXPECT_EQ(bad([](GraspReachParams&) {}), "");
  GraspSelectionParams sel;
  sel.reach_checks = -1;
  EXPECT_NE(errorOf([&] { sel.validate(); }).find("reach_checks"), std::string::npos);
  sel.reach_checks = 51;
  EXPECT_NE(errorOf([&] { sel.validate(); }).find("reach_checks"), std::string::npos);

  const Robot robot("realman_rm65_water2");
  const auto stop = [](const std::string&) { return 0.05; };
  EXPECT_NE(errorOf([&] { GraspReach(*robot.model, GraspReachParams{}, stop, std::nan("")); }).find("[GraspReach] joint_stop"),
            std::string::npos);
  EXPECT_NE(errorOf([&] { GraspReach(*robot.model, GraspReachParams{}, stop, 10.0); }).find("[GraspReach] joint_stop"),
            std::string::npos);
  EXPECT_NE(errorOf([&] { GraspReach(*robot.model, GraspReachParams{}, [](const std::string&) { return -1.0; }, 0.1); })
                .find("[GraspReach] stop distance"),
            std::string::npos);
  GraspReach reach = robot.reach();
  SupportSurface flat = table(Eigen::Vector2d(1.9, 0.0), Eigen::Vector2d(0.8, 0.0), 0.75);
  EXPECT_NE(errorOf([&] { reach.setSupport(flat); }).find("[GraspReach] invalid support"), std::string::npos);
}

class GraspReachRobots : public ::testing::TestWithParam<std::string> {};

TEST_P(GraspReachRobots, ReadyPoseBesideATableYesInTheMiddleOfAWideTableNo) {
  // The ready-pose grasp beside a table (readyGrasp): reachable on every robot. The same grasp in the
  // middle of a 3 m table (1.5 m from every edge): the base cannot stand under the top, and no
  // robot's arm reaches 1.5 m; without a support every grasp is reachable.
  const Robot robot(GetParam());
  GraspReach reach = robot.reach();
  const auto [g, pre, h, top] = readyGrasp(robot);
  reach.setSupport(top);
  const GraspReachVerdict v = reach.judge(g, pre);
  EXPECT_TRUE(v.reachable) << v.reason;
  // The kept verdict: its configurations put the TCP on the pre-grasp and on the grasp (the
  // controller's stall recovery takes them for the targets they reach).
  EXPECT_EQ(reach.keptVerdict(g), nullptr);
  ASSERT_TRUE(reach.reachable(g, pre));
  const GraspReachVerdict* kept = reach.keptVerdict(g);
  ASSERT_NE(kept, nullptr);
  const auto tcpError = [&](const Eigen::VectorXd& q, const Eigen::Isometry3d& T) {
    const Eigen::Isometry3d tcp = robot.model->fk(kept->base, q, robot.rc.tcp_frame);
    return (tcp.translation() - T.translation()).norm() + Eigen::AngleAxisd(tcp.linear().transpose() * T.linear()).angle();
  };
  EXPECT_LT(tcpError(kept->q_pre, pre), 0.005);
  EXPECT_LT(tcpError(kept->q_grasp, g), 0.005);
  Eigen::Isometry3d elsewhere = g;
  elsewhere.translation().z() += 0.01;
  EXPECT_EQ(reach.keptVerdict(elsewhere), nullptr);
  reach.setSupport(table(g.translation().head<2>(), Eigen::Vector2d(3.0, 3.0), h));
  const GraspReachVerdict w = reach.judge(g, pre);
  EXPECT_FALSE(w.reachable);
  EXPECT_FALSE(w.reason.empty());
  reach.setSupport(std::nullopt);
  EXPECT_TRUE(reach.reachable(g, pre));
}

INSTANTIATE_TEST_SUITE_P(EveryRobot, GraspReachRobots, ::testing::ValuesIn(ehc_control::robotNames()),
                         [](const ::testing::TestParamInfo<std::string>& i) { return i.param; });

TEST(GraspReach, OfTwoQualifyingCandidatesTheUnreachableHigherScoredOneLoses) {
  // The demo's table (near edge 1.5 m), the object 35 cm in from the edge: from above the
  // RealMan's shoulder and elbow would have to reach over the top within their stop distances;
  // from the side (horizontal, from the robot) the hand reaches farther.
  const Robot robot("realman_rm65_water2");
  GraspReach reach = robot.reach();
  reach.setSupport(table(Eigen::Vector2d(1.9, 0.0), Eigen::Vector2d(0.8, 1.2), 0.75));
  const Eigen::Vector3d centre(1.85, 0.0, 0.82);
  const GraspCandidate top{graspAt(centre, -Eigen::Vector3d::UnitZ()), 0.05, 0.9};
  const GraspCandidate side{graspAt(centre, Eigen::Vector3d::UnitX()), 0.05, 0.5};
  const GraspReachVerdict vt = reach.judge(top.pose, preGraspOf(top.pose));
  const GraspReachVerdict vs = reach.judge(side.pose, preGraspOf(side.pose));
  EXPECT_FALSE(vt.reachable) << "from above";
  EXPECT_TRUE(vs.reachable) << vs.reason;
  std::cout << "from above: " << vt.reason << std::endl;
  GraspSelectionParams p;
  p.centre_from_tag = p.closing_axis_from_tag = false;
  const Eigen::Isometry3d tag = graspAt(centre, Eigen::Vector3d::UnitX());
  const GraspReachable judge = [&](const Eigen::Isometry3d& g) { return reach.reachable(g, preGraspOf(g)); };
  const auto t0 = std::chrono::steady_clock::now();
  const auto c = chooseGrasp({top, side}, ApproachDirection::Any, tag, tag.linear(), p, judge);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_TRUE(c);
  EXPECT_EQ(c->candidate_index, 1) << "the reachable one";
  EXPECT_EQ(c->reachable, std::optional<bool>(true));
  const long judged = reach.judgements();
  const auto again = chooseGrasp({top, side}, ApproachDirection::Any, tag, tag.linear(), p, judge);
  ASSERT_TRUE(again);
  EXPECT_EQ(again->candidate_index, 1) << "the same choice";
  EXPECT_EQ(reach.judgements(), judged) << "the verdicts are kept";
  std::cout << "first choice of two candidates: " << ms << " ms (" << judged << " judgements)" << std::endl;
  // Without the judgement, or with the top one the only candidate: by score, as before.
  EXPECT_EQ(chooseGrasp({top, side}, ApproachDirection::Any, tag, tag.linear(), p)->candidate_index, 0);
  const auto only = chooseGrasp({top}, ApproachDirection::Any, tag, tag.linear(), p, judge);
  ASSERT_TRUE(only);
  EXPECT_EQ(only->candidate_index, 0);
  EXPECT_EQ(only->reachable, std::optional<bool>(false));
  // Without a support (none perceived yet) every grasp is reachable: the score wins.
  reach.setSupport(std::nullopt);
  const auto unknown = chooseGrasp({top, side}, ApproachDirection::Any, tag, tag.linear(), p, judge);
  ASSERT_TRUE(unknown);
  EXPECT_EQ(unknown->candidate_index, 0);
  EXPECT_EQ(unknown->reachable, std::optional<bool>(true));
}

TEST(GraspReach, ARimInTheTablesMiddleIsReachedTiltedTowardsTheRobotNotStraightDown) {
  // The demo's table (0.75 m high, near edge 1.5 m) and a bowl's rim 4 cm above its top at the
  // side of a bowl in the middle and at the back slot (27 and 43 cm in from the edge): the
  // RealMan's shoulder is mounted below the top, so straight down the wrist would have to reach
  // past the edge farther than the arm is long; the same wall grasp tilted 45 deg about its
  // closing axis (GraspGeneratorConfig::wall_tilt_deg), the wrist back towards the robot, is
  // reached from the robot's side.
  const Robot robot("realman_rm65_water2");
  GraspReach reach = robot.reach();
  reach.setSupport(table(Eigen::Vector2d(1.9, 0.0), Eigen::Vector2d(0.8, 1.2), 0.75));
  reach.setRobotBase(Eigen::Vector3d::Zero());
  const double tilt = 45.0 * M_PI / 180.0;
  for (const double x : {1.77, 1.93}) {
    SCOPED_TRACE("rim at x " + std::to_string(x));
    const Eigen::Vector3d rim(x, 0.06, 0.79);
    const Eigen::Isometry3d down = graspAt(rim, -Eigen::Vector3d::UnitZ());
    const Eigen::Isometry3d tilted = graspAt(rim, Eigen::Vector3d(std::sin(tilt), 0.0, -std::cos(tilt)));
    EXPECT_NEAR(std::abs(down.linear().col(1).dot(tilted.linear().col(1))), 1.0, 1e-9) << "one closing axis";
    const GraspReachVerdict vd = reach.judge(down, preGraspOf(down));
    const GraspReachVerdict vt = reach.judge(tilted, preGraspOf(tilted));
    EXPECT_FALSE(vd.reachable) << "straight down";
    EXPECT_TRUE(vt.reachable) << vt.reason;
    std::cout << "rim at x " << x << ": straight down: " << vd.reason << "; tilted: base " << vt.base.transpose()
              << std::endl;
  }
}

TEST(GraspSelection, ReachabilityComesBeforeScoreRandomized) {
  // Random candidate sets round a tag target and a random verdict per candidate: the choice is
  // the best-scored reachable one among the reach_checks best-scored qualifying ones, else the
  // best-scored one (reachable false).
  const unsigned seed = ehc_test::testSeed("reachability before score");
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Eigen::Isometry3d tag = graspAt(Eigen::Vector3d(1.8, 0.1, 0.8), Eigen::Vector3d::UnitX());
  for (int trial = 0; trial < 200; ++trial) {
    GraspSelectionParams p;
    p.reach_checks = 1 + static_cast<int>(u(rng) * 8);
    std::vector<GraspCandidate> cands;
    std::vector<bool> ok;
    const int n = 1 + static_cast<int>(u(rng) * 10);
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d z = Eigen::Vector3d(1.0, 0.3 * (u(rng) - 0.5), 0.3 * (u(rng) - 0.5)).normalized();
      cands.push_back({graspAt(tag.translation() + 0.02 * Eigen::Vector3d(u(rng), u(rng), u(rng)), z), 0.05, u(rng)});
      ok.push_back(u(rng) < 0.4);
    }
    // The grasps are judged best score first (the contract): the k-th question is the k-th
    // best candidate's, and its verdict is ok[] of that candidate.
    std::vector<std::size_t> order(cands.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return cands[a].score > cands[b].score; });
    std::size_t asked = 0;
    const GraspReachable judge = [&](const Eigen::Isometry3d&) { return static_cast<bool>(ok[order[asked++]]); };
    const auto c = chooseGrasp(cands, ApproachDirection::Forward, tag, tag.linear(), p, judge);
    ASSERT_TRUE(c);
    int expect = static_cast<int>(order[0]);
    bool reachable = false;
    for (std::size_t k = 0; k < order.size() && static_cast<int>(k) < p.reach_checks; ++k)
      if (ok[order[k]]) {
        expect = static_cast<int>(order[k]);
        reachable = true;
        break;
      }
    EXPECT_EQ(c->candidate_index, expect) << "trial " << trial;
    EXPECT_EQ(c->reachable, std::optional<bool>(reachable)) << "trial " << trial;
    EXPECT_LE(asked, static_cast<std::size_t>(p.reach_checks)) << "at most reach_checks judged";
  }
}

TEST_P(GraspReachRobots, ObstacleMapBlocksThePreGraspNotTheObjectDuringTheDescent) {
  // The ready-pose grasp beside a table (reachable), judged against an obstacle map (the
  // controller's ObstacleDistanceField): an object standing at the grasp blocks nothing while the
  // descent leaves it out (the sequencer's exclusion), everything when it does not; a neighbour
  // where the open fingers are at the pre-grasp blocks every placement; one 0.8 m aside, none.
  // A kept verdict is checked against the map again: the neighbour added later un-reaches it.
  ReachBesideTable s(GetParam());
  auto& [robot, reach, ready, map] = s;
  const Eigen::Isometry3d &g = ready.grasp, &pre = ready.pre;
  ehc_perception::ObstacleDistanceField& field = map.field;
  std::vector<ehc_perception::ExclusionZone> descent_zones;
  reach.setMapDistances(map.distances(robot, [&](bool descent) {
    return descent ? descent_zones : std::vector<ehc_perception::ExclusionZone>{};
  }));
  ASSERT_TRUE(reach.reachable(g, pre)) << reach.judge(g, pre).reason;
  EXPECT_EQ(reach.judgements(), 1);
  // The object: a 10 cm cube round the grasp (the open fingers inside it; 4 cm from the
  // fingertips at the pre-grasp, 10 cm back).
  const Eigen::Vector3d c = g.translation();
  field.addOccupiedBox(c - Eigen::Vector3d::Constant(0.05), c + Eigen::Vector3d::Constant(0.05));
  const GraspReachVerdict unexcluded = reach.judge(g, pre);
  EXPECT_FALSE(unexcluded.reachable);
  EXPECT_NE(unexcluded.reason.find("from an obstacle"), std::string::npos) << unexcluded.reason;
  descent_zones = {{c, 0.1}};
  const GraspReachVerdict excluded = reach.judge(g, pre);
  EXPECT_TRUE(excluded.reachable) << excluded.reason;
  EXPECT_EQ(excluded.q_pre.size(), robot.rc.nArm());
  // A neighbour 0.8 m aside: still reachable.
  const Eigen::Vector3d aside = c + Eigen::Vector3d(0.0, 0.8, 0.0);
  field.addOccupiedBox(aside - Eigen::Vector3d::Constant(0.03), aside + Eigen::Vector3d::Constant(0.03));
  EXPECT_TRUE(reach.judge(g, pre).reachable);
  EXPECT_TRUE(reach.reachable(g, pre)) << "kept, still clear";
  EXPECT_EQ(reach.judgements(), 1);
  // A neighbour where the open fingers are at the pre-grasp (whatever the placement, the TCP is there).
  const Eigen::Vector3d p = pre.translation();
  field.addOccupiedBox(p - Eigen::Vector3d::Constant(0.05), p + Eigen::Vector3d::Constant(0.05));
  const GraspReachVerdict blocked = reach.judge(g, pre);
  EXPECT_FALSE(blocked.reachable);
  EXPECT_NE(blocked.reason.find("at the pre-grasp"), std::string::npos) << blocked.reason;
  EXPECT_FALSE(reach.reachable(g, pre)) << "the kept verdict is checked against the grown map";
  EXPECT_EQ(reach.judgements(), 2);
}

TEST_P(GraspReachRobots, AKeptVerdictIsCheckedAgainstTheMapOnlyWhenItsRevisionMoves) {
  // With the map's revision (the obstacle field's), a kept reachable verdict costs no distance
  // query while the map is unchanged; once the revision moves its three configurations are
  // checked again: a neighbour 0.8 m aside keeps it, one at the pre-grasp un-reaches it.
  ReachBesideTable s(GetParam());
  auto& [robot, reach, ready, map] = s;
  const Eigen::Isometry3d &g = ready.grasp, &pre = ready.pre;
  ehc_perception::ObstacleDistanceField& field = map.field;
  const int& queries = map.queries;
  reach.setMapDistances(map.distances(robot, [](bool) { return std::vector<ehc_perception::ExclusionZone>{}; }),
                        [&] { return field.revision(); });
  ASSERT_TRUE(reach.reachable(g, pre)) << reach.judge(g, pre).reason;
  const int judged = queries;
  EXPECT_GE(judged, 3) << "the judgement checks the pre-grasp, halfway down and the grasp";
  for (int i = 0; i < 5; ++i) EXPECT_TRUE(reach.reachable(g, pre));
  EXPECT_EQ(queries, judged) << "the map unchanged: the kept verdict stands without a query";
  const Eigen::Vector3d aside = g.translation() + Eigen::Vector3d(0.0, 0.8, 0.0);
  field.addOccupiedBox(aside - Eigen::Vector3d::Constant(0.03), aside + Eigen::Vector3d::Constant(0.03));
  EXPECT_TRUE(reach.reachable(g, pre));
  EXPECT_EQ(queries, judged + 3) << "the map moved: checked again";
  EXPECT_TRUE(reach.reachable(g, pre));
  EXPECT_EQ(queries, judged + 3);
  EXPECT_EQ(reach.judgements(), 1);
  const Eigen::Vector3d p = pre.translation();
  field.addOccupiedBox(p - Eigen::Vector3d::Constant(0.05), p + Eigen::Vector3d::Constant(0.05));
  EXPECT_FALSE(reach.reachable(g, pre)) << "the kept verdict is checked against the grown map";
  EXPECT_EQ(reach.judgements(), 2);
}

TEST_P(GraspReachRobots, OnlyPlacementsOnTheRobotsSideOfTheSupportCount) {
  // The ready-pose grasp beside a table: reachable with the robot where the ready posture puts
  // it; with the robot beyond the table's far side every placement that reaches it lies across
  // the table (the controller does not drive round it): unreachable, and a kept verdict follows.
  const Robot robot(GetParam());
  GraspReach reach = robot.reach();
  const auto [g, pre, h, top] = readyGrasp(robot);
  reach.setSupport(top);
  reach.setRobotBase(Eigen::Vector3d::Zero());
  ASSERT_TRUE(reach.reachable(g, pre)) << reach.judge(g, pre).reason;
  const Eigen::Vector3d beyond(g.translation().x() + 0.45 + 0.4 + 0.8, g.translation().y(), M_PI);
  reach.setRobotBase(beyond);
  const GraspReachVerdict v = reach.judge(g, pre);
  EXPECT_FALSE(v.reachable);
  std::cout << GetParam() << " from beyond the table: " << v.reason << std::endl;
  EXPECT_FALSE(reach.reachable(g, pre)) << "the kept verdict's placement is across the table";
  EXPECT_EQ(reach.judgements(), 2);
  reach.setRobotBase(std::nullopt);
  EXPECT_TRUE(reach.judge(g, pre).reachable) << "without the robot's pose: any placement";
}
