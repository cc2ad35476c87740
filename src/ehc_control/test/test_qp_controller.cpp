// EhcQpController: closed-loop convergence for every mode from several start states (noise-free
// kinematic integration), velocity limits and finiteness, joint limits over a long random run,
// obstacle dampers keep d >= d_s, failures give a zero command with QP_FAILED.

#include "ehc_common/config_node.h"
#include "ehc_control/dual_active_set_qp.h"
#include "ehc_control/pose_servo.h"
#include "ehc_control/qp_controller.h"
#include "ehc_test/control_fixtures.h"
#include "ehc_test/test_seed.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <random>

using ehc_common::ConfigNode;

using namespace ehc_control;

namespace {

/// The RealMan without robot.yaml's per-link obstacle stop distances: these tests set
/// QpControllerParams::obstacle_stop_links themselves (the generic obstacle_stop otherwise).
RobotConfig realmanWithoutStopDistances() {
  RobotConfig c = test::realmanConfig();
  c.obstacle_stop_distances.clear();
  return c;
}

using test::approachPose;

std::shared_ptr<const EhcWeighting> weighting() {
  static auto w = std::make_shared<const EhcWeighting>(
      std::make_shared<const ReachabilityMap>(ReachabilityMap::load(test::realmanConfig().reachability_map_path)),
      EhcWeightingParams{});
  return w;
}

/// Runs the loop at 100 Hz; returns the time of arrival or -1.
double run(EhcQpController& ctrl, test::KinematicSim& sim, const Eigen::Isometry3d& target, double limit_s,
           double* min_margin = nullptr, const std::function<std::vector<ObstaclePair>(const test::KinematicSim&)>& obstacles = nullptr,
           double* min_distance = nullptr, const std::function<void(const ControllerCommand&)>& on_command = nullptr) {
  const WholeBodyModel& m = ctrl.model();
  const auto& rc = m.config();
  const Eigen::VectorXd vmax = rc.velocityLimits();
  const PoseServoParams servo;
  for (int k = 0; k < static_cast<int>(limit_s * 100); ++k) {
    const Eigen::Isometry3d tcp = m.fk(sim.base, sim.q, rc.tcp_frame);
    const Vector6d e = poseError(tcp, target);
    if (e.head<3>().norm() < 0.01 && e.tail<3>().norm() < 2.0 * M_PI / 180.0) return k * 0.01;
    std::vector<ObstaclePair> obs;
    if (obstacles) obs = obstacles(sim);
    if (min_distance)
      for (const auto& o : obs) *min_distance = std::min(*min_distance, o.distance);
    const ControllerCommand c = ctrl.step(sim.base, sim.q, target, proportionalPoseServo(tcp, target, servo), obs);
    EXPECT_TRUE(c.velocity.allFinite());
    EXPECT_TRUE((c.velocity.cwiseAbs().array() <= vmax.array() + 1e-12).all()) << c.velocity.transpose();
    EXPECT_EQ(c.qp_status, QpStatus::Ok) << c.failure;
    if (on_command) on_command(c);
    if (!c.ok) return -1;
    sim.step(m, c.velocity, 0.01);
    if (min_margin)
      *min_margin = std::min(*min_margin, std::min((sim.q - rc.arm_lower).minCoeff(), (rc.arm_upper - sim.q).minCoeff()));
  }
  return -1;
}

}  // namespace

class Convergence : public ::testing::TestWithParam<ControlMode> {};

TEST_P(Convergence, ReachesTargetsFromSeveralStarts) {
  auto model = std::make_shared<const WholeBodyModel>(realmanWithoutStopDistances());
  QpControllerParams p;
  p.mode = GetParam();
  EhcQpController ctrl(model, p, weighting());
  const std::vector<Eigen::Vector3d> starts = {{0, 0, 0}, {-0.5, 0.3, 0.8}, {0.2, -0.4, -1.2}};
  const std::vector<Eigen::Isometry3d> targets = {
      approachPose(2.0, 0.0, 0.8, Eigen::Vector3d(1, 0, -1)),     // ahead, 45 deg down
      approachPose(1.2, 1.5, 0.75, Eigen::Vector3d(0.6, 0.8, -1)), // left, 45 deg down, table height
      approachPose(-1.5, -0.5, 0.9, Eigen::Vector3d(-1, 0, 0))};  // behind, horizontal
  for (std::size_t s = 0; s < starts.size(); ++s) {
    test::KinematicSim sim{starts[s], model->config().arm_ready};
    ctrl.reset();
    const double t = run(ctrl, sim, targets[s], 30.0);
    EXPECT_GT(t, 0.0) << toString(GetParam()) << " start " << s << " did not arrive in 30 s";
  }
}

INSTANTIATE_TEST_SUITE_P(AllModes, Convergence,
                         ::testing::Values(ControlMode::Ehc, ControlMode::NeoE, ControlMode::NeoC, ControlMode::Tsmm),
                         [](const auto& info) { return toString(info.param); });

TEST(EhcQpController, JointDampersKeepJointsInsideLimitsOverALongRandomRun) {
  auto model = std::make_shared<const WholeBodyModel>(realmanWithoutStopDistances());
  EhcQpController ctrl(model, QpControllerParams{}, weighting());
  test::KinematicSim sim{Eigen::Vector3d::Zero(), model->config().arm_ready};
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double margin = 1e9;
  for (int i = 0; i < 15; ++i) {
    const Eigen::Vector3d tcp = model->fk(sim.base, sim.q, "ee_link").translation();
    const Eigen::Isometry3d target =
        approachPose(tcp.x() + 1.5 * u(rng), tcp.y() + 1.5 * u(rng), 0.65 + 0.3 * u(rng), Eigen::Vector3d(u(rng), u(rng), -1.5));
    ctrl.reset();
    run(ctrl, sim, target, 10.0, &margin);
  }
  EXPECT_GT(margin, 0.0);  // never at or beyond a limit
  RecordProperty("min_joint_limit_margin_rad", std::to_string(margin));
}

TEST(EhcQpController, ObstacleInThePathIsNeverApproachedCloserThanDs) {
  auto model = std::make_shared<const WholeBodyModel>(realmanWithoutStopDistances());
  QpControllerParams p;
  EhcQpController ctrl(model, p, weighting());
  test::KinematicSim sim{Eigen::Vector3d::Zero(), model->config().arm_ready};
  // A 10 cm sphere on the straight path of the TCP to a target 1.6 m ahead.
  const Eigen::Vector3d centre(0.9, 0.0, 0.95);
  const double radius = 0.10;
  const std::vector<std::string> links = {"ee_link", "link6", "link5", "link3", "camera_link", "gripper_base_link"};
  auto obstacles = [&](const test::KinematicSim& s) {
    std::vector<ObstaclePair> out;
    for (const auto& l : links) {
      const Eigen::Vector3d pl = model->fk(s.base, s.q, l).translation();
      const Eigen::Vector3d d = pl - centre;
      ObstaclePair o;
      o.link = l;
      o.link_point = pl;
      o.normal = d.normalized();
      o.obstacle_point = centre + radius * o.normal;
      o.distance = d.norm() - radius;
      out.push_back(o);
    }
    return out;
  };
  double min_d = 1e9;
  const double t = run(ctrl, sim, approachPose(1.6, 0.0, 0.9, Eigen::Vector3d(1, 0, -0.3)), 30.0, nullptr, obstacles, &min_d);
  EXPECT_GE(min_d, p.obstacle_stop - 0.005) << "closest approach " << min_d;
  EXPECT_LT(min_d, p.obstacle_influence);  // the obstacle really was in the way
  RecordProperty("arrival_s", std::to_string(t));
}

namespace {
/// Deepest and RMS depth inside d_s (m) of links held at d_s by a wall (the plane x = 1.0, the
/// target 15 cm behind it), with Table I's actuation noise (executed base v and w: sigma 0.05;
/// arm rates: 0.002 rad/s; white per 10 ms step, seeded) on top of the command.
struct HeldDepth {
  double worst = 0.0, rms = 0.0;
};
HeldDepth depthHeldAtTheWall(double recovery_gain, unsigned seed) {
  auto model = std::make_shared<const WholeBodyModel>(realmanWithoutStopDistances());
  QpControllerParams p;
  p.obstacle_recovery_gain = recovery_gain;
  EhcQpController ctrl(model, p, weighting());
  test::KinematicSim sim{Eigen::Vector3d::Zero(), model->config().arm_ready};
  const double wall = 1.0;
  const std::vector<std::string> links = {"ee_link", "gripper_base_link", "camera_link", "link6"};
  const Eigen::Isometry3d target = approachPose(wall + 0.15, 0.0, 0.8, Eigen::Vector3d(1, 0, -0.3));
  std::mt19937 rng(seed);
  std::normal_distribution<double> base_noise(0.0, 0.05), arm_noise(0.0, 0.002);
  HeldDepth out;
  double sum_sq = 0.0;
  int held = 0;
  for (int k = 0; k < 1000; ++k) {
    std::vector<ObstaclePair> obs;
    for (const std::string& l : links) {
      ObstaclePair o;
      o.link = l;
      o.link_point = model->fk(sim.base, sim.q, l).translation();
      o.normal = -Eigen::Vector3d::UnitX();
      o.distance = wall - o.link_point.x();
      o.obstacle_point = Eigen::Vector3d(wall, o.link_point.y(), o.link_point.z());
      obs.push_back(o);
    }
    double d_min = 1e9;
    for (const ObstaclePair& o : obs) d_min = std::min(d_min, o.distance);
    if (held > 0 || d_min < p.obstacle_stop + 0.001) {  // from the first arrival at d_s on
      const double depth = std::max(0.0, p.obstacle_stop - d_min);
      out.worst = std::max(out.worst, depth);
      sum_sq += depth * depth;
      ++held;
    }
    const Eigen::Isometry3d tcp = model->fk(sim.base, sim.q, model->config().tcp_frame);
    const ControllerCommand c = ctrl.step(sim.base, sim.q, target, proportionalPoseServo(tcp, target, PoseServoParams{}), obs);
    EXPECT_EQ(c.qp_status, QpStatus::Ok) << c.failure;
    if (!c.ok) break;
    Eigen::VectorXd v = c.velocity;
    v[0] += base_noise(rng);
    v[model->nBase() - 1] += base_noise(rng);
    for (int i = model->nBase(); i < v.size(); ++i) v[i] += arm_noise(rng);
    sim.step(*model, v, 0.01);
  }
  EXPECT_GT(held, 500) << "the wall never held a link at d_s";
  out.rms = held > 0 ? std::sqrt(sum_sq / held) : 0.0;
  return out;
}
}  // namespace

TEST(EhcQpController, LinkHeldAtItsStopDistanceByTheTaskStaysNearItUnderActuationNoise) {
  // The task pulls the hand through a wall; the dampers hold it at d_s while Table I's noise
  // pushes it in. The damper alone lets it back out at xi / (d_i - d_s) = 4/s x the depth; the
  // recovery gain (20/s) at five times that: the depth stays within 5 mm and its spread shrinks.
  const unsigned seed = ehc_test::testSeed("held at d_s under actuation noise");
  const HeldDepth damper = depthHeldAtTheWall(0.0, seed);
  const HeldDepth recovery = depthHeldAtTheWall(QpControllerParams{}.obstacle_recovery_gain, seed);
  RecordProperty("damper_alone_worst_mm", std::to_string(1000.0 * damper.worst));
  RecordProperty("recovery_worst_mm", std::to_string(1000.0 * recovery.worst));
  std::cout << "depth inside d_s: damper alone worst " << 1000.0 * damper.worst << " mm, rms " << 1000.0 * damper.rms
            << " mm; recovery " << QpControllerParams{}.obstacle_recovery_gain << "/s worst " << 1000.0 * recovery.worst
            << " mm, rms " << 1000.0 * recovery.rms << " mm" << std::endl;
  EXPECT_LE(recovery.worst, 0.005);
  EXPECT_LT(recovery.rms, 0.7 * damper.rms);
}

TEST(EhcQpController, ALinkFoundDeepInsideItsStopDistanceBacksOutInsteadOfStopping) {
  // A wall first seen 3-8 cm inside the arm base's d_s (a table's face the camera had not looked
  // at). Only the base moves that link, and the recovery gain asks 20/s x the depth, more than
  // the base's 0.5 m/s: the demand is capped at obstacle_recovery_share of what the base can do,
  // the QP stays feasible every cycle and the base backs the link out to d_s. Randomized depth,
  // wall direction and target beyond the wall (the task pulls the robot into it).
  const unsigned seed = ehc_test::testSeed("deep inside d_s");
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> depth_of(0.03, 0.08), bearing_of(-0.6, 0.6);
  auto model = std::make_shared<const WholeBodyModel>(realmanWithoutStopDistances());
  const QpControllerParams p;
  const double ds = p.obstacle_stop;
  for (int trial = 0; trial < 5; ++trial) {
    EhcQpController ctrl(model, p, weighting());
    test::KinematicSim sim{Eigen::Vector3d::Zero(), model->config().arm_ready};
    const double depth = depth_of(rng), bearing = bearing_of(rng);
    const Eigen::Vector3d into(std::cos(bearing), std::sin(bearing), 0.0);  // from the link to the wall
    const Eigen::Vector3d start = model->fk(sim.base, sim.q, "arm_base_link").translation();
    const double wall = start.dot(into) + ds - depth;  // the plane into . x = wall
    ASSERT_GT(depth * p.obstacle_recovery_gain, model->config().velocityLimits()[0]) << "the uncapped demand exceeds the base";
    const Eigen::Isometry3d target = approachPose(1.2 * into.x(), 1.2 * into.y(), 0.8, Eigen::Vector3d(into.x(), into.y(), -0.3));
    double d = 0.0;
    for (int k = 0; k < 300; ++k) {
      ObstaclePair o;
      o.link = "arm_base_link";
      o.link_point = model->fk(sim.base, sim.q, o.link).translation();
      o.normal = -into;
      o.distance = d = wall - o.link_point.dot(into);
      o.obstacle_point = o.link_point + o.distance * into;
      const Eigen::Isometry3d tcp = model->fk(sim.base, sim.q, model->config().tcp_frame);
      const ControllerCommand c = ctrl.step(sim.base, sim.q, target, proportionalPoseServo(tcp, target, PoseServoParams{}), {o});
      ASSERT_EQ(c.qp_status, QpStatus::Ok) << "seed " << seed << " trial " << trial << " depth " << depth << " cycle " << k
                                           << ": " << c.failure;
      sim.step(*model, c.velocity, 0.01);
    }
    EXPECT_GT(d, ds - 0.003) << "seed " << seed << " trial " << trial << ": backed out to d_s (depth " << depth << " m)";
    EXPECT_LT(d, ds + 0.05) << "and held there by the task";
  }
}

TEST(EhcQpController, BadInputGivesZeroCommandAndQpFailed) {
  auto model = std::make_shared<const WholeBodyModel>(realmanWithoutStopDistances());
  EhcQpController ctrl(model, QpControllerParams{}, weighting());
  const Eigen::VectorXd q = model->config().arm_ready;
  Eigen::Isometry3d target = approachPose(1, 0, 0.8, Eigen::Vector3d(0, 0, -1));
  Vector6d nu = Vector6d::Constant(0.1);
  Eigen::Isometry3d bad = target;
  bad.translation().x() = std::nan("");
  for (const ControllerCommand& c :
       {ctrl.step(Eigen::Vector3d::Zero(), q, bad, nu), ctrl.step(Eigen::Vector3d::Zero(), Eigen::VectorXd::Zero(5), target, nu),
        ctrl.step(Eigen::Vector3d(0, std::nan(""), 0), q, target, nu),
        ctrl.step(Eigen::Vector3d::Zero(), q, target, Vector6d::Constant(std::nan("")))}) {
    EXPECT_FALSE(c.ok);
    EXPECT_EQ(c.qp_status, QpStatus::Failed);
    EXPECT_FALSE(c.failure.empty());
    EXPECT_EQ(c.velocity.size(), model->nDof());
    EXPECT_TRUE(c.velocity.isZero(0.0));
  }
}

TEST(EhcQpController, PairsThatCannotAllOpenAreHeldAndATrulyInfeasibleProblemStops) {
  auto model = std::make_shared<const WholeBodyModel>(realmanWithoutStopDistances());
  EhcQpController ctrl(model, QpControllerParams{}, weighting());
  const Eigen::VectorXd q = model->config().arm_ready;
  const Eigen::Vector3d p = model->fk(Eigen::Vector3d::Zero(), q, "ee_link").translation();
  const Eigen::Isometry3d target = approachPose(1, 0, 0.8, Eigen::Vector3d(0, 0, -1));
  // The hand inside two obstacles pushing it out in opposite directions (a finger each side of
  // an object): both cannot open, so both are held: feasible, and the command approaches
  // neither (its point's velocity along the normals is zero).
  ObstaclePair a, b;
  a.link = b.link = "ee_link";
  a.link_point = b.link_point = p;
  a.normal = Eigen::Vector3d::UnitX();
  b.normal = -Eigen::Vector3d::UnitX();
  a.distance = b.distance = -0.5;
  const ControllerCommand held = ctrl.step(Eigen::Vector3d::Zero(), q, target, Vector6d::Constant(0.1), {a, b});
  ASSERT_TRUE(held.ok) << held.failure;
  EXPECT_TRUE(held.obstacles_held);
  EXPECT_EQ(held.obstacle_rows, 2);
  KinematicState state;
  model->updateKinematics(Eigen::Vector3d::Zero(), q, &state);
  Matrix6Xd J;
  model->pointJacobian(state, model->linkIndex("ee_link"), p, &J);
  EXPECT_NEAR((J.topRows<3>() * held.velocity).x(), 0.0, 1e-6) << "neither pair approached";
  // One pair alone can open: not held.
  const ControllerCommand one = ctrl.step(Eigen::Vector3d::Zero(), q, target, Vector6d::Constant(0.1), {a});
  ASSERT_TRUE(one.ok) << one.failure;
  EXPECT_FALSE(one.obstacles_held);
  // A task twist beyond the slack bound and the robot's rates: no command follows it, held or
  // not: zero command and QP_FAILED.
  const ControllerCommand c = ctrl.step(Eigen::Vector3d::Zero(), q, target, Vector6d::Constant(1000.0), {a, b});
  EXPECT_FALSE(c.ok);
  EXPECT_EQ(c.qp_status, QpStatus::Failed);
  EXPECT_TRUE(c.velocity.isZero(0.0));
}

// A solve that does not finish within max_qp_iterations active-set steps (vpQuadProg would
// loop forever on a degenerate problem: test_bounded_quad_prog replays one) stops the robot:
// zero command, QP_FAILED and the reason; the next cycle solves again (cold start).
TEST(EhcQpController, IterationLimitGivesZeroCommandAndQpFailed) {
  auto model = std::make_shared<const WholeBodyModel>(realmanWithoutStopDistances());
  const Eigen::VectorXd q = model->config().arm_ready;
  const Eigen::Isometry3d target = approachPose(1.5, 0.5, 0.8, Eigen::Vector3d(0, 0, -1));
  const Vector6d nu = (Vector6d() << 2.0, 1.0, -0.5, 0.5, 0.5, 0.5).finished();  // saturates bounds
  QpControllerParams p;
  EhcQpController normal(model, p, weighting());
  const ControllerCommand ok = normal.step(Eigen::Vector3d::Zero(), q, target, nu);
  ASSERT_TRUE(ok.ok) << ok.failure;
  p.max_qp_iterations = 1;
  EhcQpController limited(model, p, weighting());
  for (int k = 0; k < 2; ++k) {
    const ControllerCommand c = limited.step(Eigen::Vector3d::Zero(), q, target, nu);
    EXPECT_FALSE(c.ok);
    EXPECT_EQ(c.qp_status, QpStatus::Failed);
    EXPECT_NE(c.failure.find("QP iteration limit (1 active-set iterations"), std::string::npos) << c.failure;
    EXPECT_EQ(c.velocity.size(), model->nDof());
    EXPECT_TRUE(c.velocity.isZero(0.0));
  }
  p.max_qp_iterations = 0;
  EXPECT_THROW(p.validate(), std::invalid_argument);
}

TEST(QpControllerParams, ValidationAndLoading) {
  QpControllerParams p;
  p.joint_stop = 1.0;
  p.joint_influence = 0.5;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  const auto cfg = ConfigNode::loadString("controller: {mode: walk}", "test.yaml", "Test");
  try {
    loadQpControllerParams(cfg.child("controller"));
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("field 'controller.mode' must be ehc, ehc_place, neo_e, neo_c or tsmm"),
              std::string::npos)
        << e.what();
  }
  const auto ok = ConfigNode::loadFile(std::string(EHC_CONFIG_DIR) + "/control/controller.yaml", "Test");
  EXPECT_EQ(loadQpControllerParams(ok.child("controller")).mode, ControlMode::Ehc);
  EXPECT_THROW(EhcQpController(std::make_shared<const WholeBodyModel>(realmanWithoutStopDistances()), QpControllerParams{}, nullptr),
               std::invalid_argument);  // ehc needs a map
  // ehc_place: loads, needs a map too.
  const auto place = ConfigNode::loadString("controller: {mode: ehc_place}", "test.yaml", "Test");
  QpControllerParams pp = loadQpControllerParams(place.child("controller"));
  EXPECT_EQ(pp.mode, ControlMode::EhcPlace);
  try {
    EhcQpController(std::make_shared<const WholeBodyModel>(realmanWithoutStopDistances()), pp, nullptr);
    FAIL() << "ehc_place without a map accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("mode ehc_place needs a reachability map"), std::string::npos) << e.what();
  }
  // The placement's parameters: out of range fails naming the file and the field.
  const auto bad_place =
      ConfigNode::loadString("controller: {recovery: {placement_handover_sig: 1.5}}", "place.yaml", "Test");
  try {
    loadQpControllerParams(bad_place.child("controller"));
    FAIL() << "placement_handover_sig 1.5 accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("place.yaml"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("placement_handover_sig"), std::string::npos) << e.what();
  }
}

TEST(ControlMode, EveryModeNameRoundTrips) {
  for (ControlMode m : {ControlMode::Ehc, ControlMode::EhcPlace, ControlMode::NeoE, ControlMode::NeoC, ControlMode::Tsmm})
    EXPECT_EQ(controlModeFromString(toString(m)), m) << toString(m);
  EXPECT_EQ(toString(ControlMode::EhcPlace), "ehc_place");
  EXPECT_TRUE(usesWeighting(ControlMode::EhcPlace));
  EXPECT_FALSE(usesWeighting(ControlMode::NeoE));
  EXPECT_THROW(controlModeFromString("ehc_placement"), std::invalid_argument);
}

namespace {
/// A QpSolver back end for the interface test: hands every problem to DualActiveSetQp and
/// records its size, or reports every problem infeasible.
class RecordingSolver : public QpSolver {
 public:
  explicit RecordingSolver(bool infeasible) : infeasible_(infeasible) {}
  std::string name() const override { return "recording"; }
  QpSolveResult solve(const QpProblemView& p, Eigen::VectorXd* x, int max_iterations) override {
    ++solves;
    variables = static_cast<int>(p.G.rows());
    equalities = static_cast<int>(p.A.rows());
    inequalities = static_cast<int>(p.C.rows());
    if (infeasible_) return QpSolveResult::Infeasible;
    return inner_.solve(p, x, max_iterations);
  }
  int iterations() const override { return inner_.iterations(); }
  int solves = 0, variables = 0, equalities = 0, inequalities = 0;

 private:
  bool infeasible_;
  DualActiveSetQp inner_;
};
}  // namespace

// The controller reaches its QP back end only through QpSolver: made by name from
// params.qp_solver (an unknown name is an error), replaceable, and a back end's answer
// (the same problem solved by the same method gives the same command, an infeasible one a
// safe stop) is what the command is made of.
TEST(EhcQpController, SolvesThroughTheQpSolverInterface) {
  auto model = std::make_shared<const WholeBodyModel>(realmanWithoutStopDistances());
  const Eigen::VectorXd q = model->config().arm_ready;
  const Eigen::Isometry3d target = approachPose(1.5, 0.5, 0.8, Eigen::Vector3d(0, 0, -1));
  const Vector6d nu = (Vector6d() << 0.3, 0.1, -0.1, 0.1, 0.0, 0.2).finished();
  EhcQpController plain(model, QpControllerParams{}, weighting());
  EXPECT_EQ(plain.qpSolver().name(), "dual_active_set");
  const ControllerCommand expected = plain.step(Eigen::Vector3d::Zero(), q, target, nu);
  ASSERT_TRUE(expected.ok) << expected.failure;

  EhcQpController swapped(model, QpControllerParams{}, weighting());
  auto recording = std::make_unique<RecordingSolver>(false);
  RecordingSolver* seen = recording.get();
  swapped.setQpSolver(std::move(recording));
  EXPECT_EQ(swapped.qpSolver().name(), "recording");
  const ControllerCommand c = swapped.step(Eigen::Vector3d::Zero(), q, target, nu);
  ASSERT_TRUE(c.ok) << c.failure;
  EXPECT_EQ(seen->solves, 1);
  EXPECT_EQ(seen->variables, model->nDof());  // the slack is eliminated: one variable per DOF
  EXPECT_EQ(seen->equalities, 0);
  EXPECT_EQ(seen->inequalities, 2 * model->nDof() + 12);  // bounds and slack bounds, no obstacle
  EXPECT_EQ(c.velocity, expected.velocity);
  EXPECT_EQ(c.slack, expected.slack);
  EXPECT_EQ(c.qp_iterations, expected.qp_iterations);

  swapped.setQpSolver(std::make_unique<RecordingSolver>(true));
  const ControllerCommand failed = swapped.step(Eigen::Vector3d::Zero(), q, target, nu);
  EXPECT_FALSE(failed.ok);
  EXPECT_EQ(failed.qp_status, QpStatus::Failed);
  EXPECT_EQ(failed.failure, "QP infeasible");
  EXPECT_TRUE(failed.velocity.isZero(0.0));
  EXPECT_THROW(swapped.setQpSolver(nullptr), std::invalid_argument);

  QpControllerParams unknown;
  unknown.qp_solver = "qpoases";
  try {
    EhcQpController bad(model, unknown, weighting());
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "[QpControllerParams] qp_solver must be one of: dual_active_set (got 'qpoases')");
  }
  const auto cfg = ConfigNode::loadString("controller: {qp_solver: qpoases}", "test.yaml", "Test");
  try {
    loadQpControllerParams(cfg.child("controller"));
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("qp_solver must be one of: dual_active_set (got 'qpoases')"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("test.yaml"), std::string::npos) << e.what();
  }
  const auto shipped = ConfigNode::loadFile(std::string(EHC_CONFIG_DIR) + "/control/controller.yaml", "Test");
  EXPECT_EQ(loadQpControllerParams(shipped.child("controller")).qp_solver, "dual_active_set");
}

TEST(EhcQpController, PerLinkStopDistanceLetsTheHandNearTheTable) {
  // A table top 3 cm below the target TCP position. With the default d_s = 5 cm the TCP is held
  // 5 cm above it and never arrives; with d_s = 1 cm for the TCP link it arrives, and never goes
  // below 1 cm.
  auto model = std::make_shared<const WholeBodyModel>(realmanWithoutStopDistances());
  const double table_z = 0.77;
  const Eigen::Isometry3d target = approachPose(1.3, 0.2, table_z + 0.03, Eigen::Vector3d(1, 0, -0.2));
  auto table = [&](const test::KinematicSim& s) {
    const Eigen::Vector3d p = model->fk(s.base, s.q, "ee_link").translation();
    ObstaclePair o;
    o.link = "ee_link";
    o.link_point = p;
    o.obstacle_point = Eigen::Vector3d(p.x(), p.y(), table_z);
    o.normal = Eigen::Vector3d::UnitZ();
    o.distance = p.z() - table_z;
    return std::vector<ObstaclePair>{o};
  };
  QpControllerParams p;
  {
    EhcQpController ctrl(model, p, weighting());
    test::KinematicSim sim{Eigen::Vector3d::Zero(), model->config().arm_ready};
    double min_d = 1e9;
    EXPECT_LT(run(ctrl, sim, target, 15.0, nullptr, table, &min_d), 0.0);  // blocked
    EXPECT_GE(min_d, p.obstacle_stop - 0.005);
  }
  p.obstacle_stop_links["ee_link"] = 0.01;
  {
    EhcQpController ctrl(model, p, weighting());
    test::KinematicSim sim{Eigen::Vector3d::Zero(), model->config().arm_ready};
    double min_d = 1e9;
    EXPECT_GT(run(ctrl, sim, target, 30.0, nullptr, table, &min_d), 0.0);  // arrives
    EXPECT_GE(min_d, 0.01 - 0.005);
  }
  p.obstacle_stop_links["ee_link"] = 0.5;  // not below the influence distance
  EXPECT_THROW(p.validate(), std::invalid_argument);
}

TEST(EhcQpController, ManipulabilityFadeStopsNullSpaceDriftAtTheTarget) {
  // At the target (zero error, zero desired twist) the only thing that moves the robot is the
  // linear cost: with the constant manipulability term the arm keeps drifting in the null
  // space (the QP trades a little slack for manipulability); with the fade it holds still.
  auto model = std::make_shared<const WholeBodyModel>(realmanWithoutStopDistances());
  const auto& rc = model->config();
  Eigen::VectorXd q = rc.arm_ready;
  q[1] += 0.6;  // a stretched pose: large manipulability gradient
  q[2] += 0.8;
  const Eigen::Vector3d base = Eigen::Vector3d::Zero();
  const Eigen::Isometry3d here = model->fk(base, q, rc.tcp_frame);
  QpControllerParams p;
  p.posture_gain = 0.0;  // the manipulability term alone
  p.base_turn_gain = 0.0;
  EhcQpController constant(model, p, weighting());
  const ControllerCommand c0 = constant.step(base, q, here, Vector6d::Zero(), {});
  ASSERT_TRUE(c0.ok) << c0.failure;
  p.manipulability_fade_distance = 0.10;
  EhcQpController faded(model, p, weighting());
  const ControllerCommand c1 = faded.step(base, q, here, Vector6d::Zero(), {});
  ASSERT_TRUE(c1.ok) << c1.failure;
  EXPECT_GT(c0.velocity.tail(model->nArm()).norm(), 1e-3) << "no drift to remove: the test proves nothing";
  EXPECT_LT(c1.velocity.tail(model->nArm()).norm(), 0.1 * c0.velocity.tail(model->nArm()).norm())
      << "constant " << c0.velocity.transpose() << " | faded " << c1.velocity.transpose() << " slack " << c1.slack.transpose();
  // Far from the target (beyond the fade distance) both behave the same.
  Eigen::Isometry3d far = here;
  far.translation().x() += 0.3;
  const Vector6d nu = (Vector6d() << 0.3, 0, 0, 0, 0, 0).finished();
  constant.reset();
  faded.reset();
  const ControllerCommand f0 = constant.step(base, q, far, nu, {});
  const ControllerCommand f1 = faded.step(base, q, far, nu, {});
  EXPECT_LT((f0.velocity - f1.velocity).norm(), 1e-9);
  // Validation: a negative fade distance fails naming the field.
  const auto bad = ConfigNode::loadString("controller: {manipulability_fade_distance: -0.1}", "test.yaml", "Test");
  try {
    loadQpControllerParams(bad.child("controller"));
    FAIL() << "negative fade distance accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("manipulability_fade_distance"), std::string::npos) << e.what();
  }
}

TEST(EhcQpController, FarApproachFacesTheTargetAndCarriesTheArmOnlyWhileFar) {
  // A target 3.5-5 m away, 60-120 deg to the left of the heading, the TCP ahead of the base
  // (bearing ~0) and a wrist joint off its ready position, no desired twist: with the far
  // approach the base turns left towards the target and the wrist is pulled towards ready;
  // without it (the paper's TCP bearing) neither. Within far_approach.distance of the target the
  // far approach changes nothing.
  const unsigned seed = ehc_test::testSeed("EhcQpController far approach");
  RecordProperty("seed", std::to_string(seed));
  SCOPED_TRACE("seed " + std::to_string(seed));
  std::mt19937 rng(seed);
  auto model = std::make_shared<const WholeBodyModel>(realmanWithoutStopDistances());
  const auto& rc = model->config();
  std::uniform_real_distribution<double> side(60.0 * M_PI / 180.0, 120.0 * M_PI / 180.0), dist(3.5, 5.0);
  const double bearing = side(rng), d = dist(rng);
  const Eigen::Isometry3d target = test::approachPose(d * std::cos(bearing), d * std::sin(bearing), 0.7, Eigen::Vector3d(0, 0, -1));
  const Eigen::Vector3d base = Eigen::Vector3d::Zero();
  Eigen::VectorXd q = rc.arm_ready;  // TCP ahead of the base: its bearing is ~0
  const int wrist = model->nArm() - 2;
  q[wrist] += 0.5;                    // off the ready posture
  const Eigen::Isometry3d tcp = model->fk(base, q, rc.tcp_frame);
  // No desired twist: the turn and posture come from the cost terms alone (a servo's pull towards
  // the target would turn the base either way).
  const Vector6d nu = Vector6d::Zero();
  QpControllerParams on, off;
  off.far_approach.face_target = false;
  off.far_approach.posture_gain = 0.0;
  off.far_approach.orientation_release = 0.0;
  ASSERT_TRUE(on.far_approach.face_target && on.far_approach.posture_gain > 0.0);
  EXPECT_EQ(on.far_approach.fraction(2.0 * on.far_approach.distance + 0.1), 1.0);
  EXPECT_EQ(on.far_approach.fraction(on.far_approach.distance), 0.0);
  EXPECT_NEAR(on.far_approach.fraction(1.5 * on.far_approach.distance), 0.5, 1e-12);
  const int nb = model->nBase();
  for (ControlMode mode : {ControlMode::NeoC, ControlMode::NeoE, ControlMode::Ehc}) {
    SCOPED_TRACE(toString(mode));
    on.mode = off.mode = mode;
    EhcQpController with(model, on, weighting()), without(model, off, weighting());
    const ControllerCommand c1 = with.step(base, q, target, nu, {});
    const ControllerCommand c0 = without.step(base, q, target, nu, {});
    ASSERT_TRUE(c1.ok && c0.ok) << c1.failure << c0.failure;
    EXPECT_GT(c1.velocity[nb - 1], 0.2) << "the base does not turn towards the target";
    EXPECT_GT(c1.velocity[nb - 1], c0.velocity[nb - 1] + 0.1) << c1.velocity.transpose() << " | " << c0.velocity.transpose();
    EXPECT_LT(c1.velocity[nb + wrist], c0.velocity[nb + wrist] - 0.1) << "the wrist is not pulled towards ready";
    // Within far_approach.distance of the target: the same command with and without.
    Eigen::Isometry3d near = tcp;
    near.translation().x() += 0.5 * on.far_approach.distance;
    const ControllerCommand n1 = with.step(base, q, near, nu, {});
    const ControllerCommand n0 = without.step(base, q, near, nu, {});
    EXPECT_LT((n1.velocity - n0.velocity).norm(), 1e-9);
  }
  // Validation: each field is checked and named.
  for (const char* bad : {"{distance: 0}", "{posture_gain: -1}", "{orientation_release: 1.5}", "{face_target: maybe}"}) {
    const auto cfg = ConfigNode::loadString(std::string("controller: {far_approach: ") + bad + "}", "far.yaml", "Test");
    try {
      loadQpControllerParams(cfg.child("controller"));
      ADD_FAILURE() << bad << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("far.yaml"), std::string::npos) << e.what();
      const std::string field = std::string(bad).substr(1, std::string(bad).find(':') - 1);
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  }
}

TEST(EhcQpController, TenObstaclePairsClosedLoopReproducesTheRecordedCommands) {
  // Regression record: four targets in a row, ten link-obstacle pairs in every cycle (a point
  // obstacle 0.15-0.24 m from each link origin along a fixed world direction, as in
  // bench_controller), 100 Hz closed loop. The expected values are printed by this test
  // (EHC_PRINT_RECORD=1). History: recorded against the controller of commit 883b4fc (per-link
  // KDL Jacobians, vpQuadProg), met to 1e-8 by the one-pass kinematics; re-recorded when the QP
  // solver became DualActiveSetQp. Solving each cycle's QP with both showed two cycles where
  // they differ: the first of the second target (vpQuadProg returned a feasible point of cost
  // 0.287 where the optimum is -0.0019; the commands differed by 4 rad/s in one joint) and
  // one of the fourth (-0.0564 vs -0.0603); everywhere else they agreed to 1e-11. The
  // tolerance is rounding-level: a genuine change of the QP (a cost or constraint term, another
  // solution) moves these sums by far more than 1e-6. The record is met with glibc's libm on
  // its non-FMA code paths too (GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2,-FMA), so it does not
  // hang on the last bit of sin/cos.
  auto model = std::make_shared<const WholeBodyModel>(realmanWithoutStopDistances());
  const auto& rc = model->config();
  // The record is of the paper's cost terms (the controller of 883b4fc): the later base-turn
  // unwinding and joint-limit centring are switched off here, so the record keeps checking
  // that the one-pass kinematics reproduce the per-link KDL path.
  QpControllerParams paper_terms;
  paper_terms.base_turn_unwinding = false;
  paper_terms.limit_centring_gain = 0.0;
  paper_terms.far_approach.face_target = false;
  paper_terms.far_approach.posture_gain = 0.0;
  paper_terms.far_approach.orientation_release = 0.0;
  EhcQpController ctrl(model, paper_terms, weighting());
  test::KinematicSim sim{Eigen::Vector3d::Zero(), rc.arm_ready};
  const std::vector<std::string> links = {"link1", "link2", "link3", "link4", "link5",
                                          "link6", "gripper_base_link", "camera_link", "arm_base_link", "ee_link"};
  auto obstacles = [&](const test::KinematicSim& s) {
    std::vector<ObstaclePair> out;
    for (std::size_t i = 0; i < links.size(); ++i) {
      ObstaclePair o;
      o.link = links[i];
      o.link_point = model->fk(s.base, s.q, o.link).translation();
      o.normal = Eigen::Vector3d(0.3 * static_cast<double>(i) - 1.0, 1.0, 0.5).normalized();
      o.distance = 0.15 + 0.01 * static_cast<double>(i);
      o.obstacle_point = o.link_point - o.distance * o.normal;
      out.push_back(o);
    }
    return out;
  };
  const std::vector<Eigen::Isometry3d> targets = {
      test::approachPose(1.2, 0.4, 0.8, Eigen::Vector3d(1, 0, -1)), test::approachPose(0.6, 1.3, 0.7, Eigen::Vector3d(0, 1, -1)),
      test::approachPose(-0.4, 0.9, 0.9, Eigen::Vector3d(-1, 0, -0.3)), test::approachPose(0.5, -0.5, 0.75, Eigen::Vector3d(0, 0, -1))};
  int cycles = 0, rows = 0;
  Eigen::VectorXd sum_v = Eigen::VectorXd::Zero(model->nDof()), sum_abs_v = sum_v;
  auto record = [&](const ControllerCommand& c) {
    ++cycles;
    rows += c.obstacle_rows;
    sum_v += c.velocity;
    sum_abs_v += c.velocity.cwiseAbs();
  };
  std::vector<long> arrival;  // cycle of arrival per target
  for (const auto& target : targets) {
    ctrl.reset();
    arrival.push_back(std::lround(100.0 * run(ctrl, sim, target, 5.0, nullptr, obstacles, nullptr, record)));
  }
  Eigen::VectorXd state(3 + model->nArm());
  state << sim.base, sim.q;
  if (std::getenv("EHC_PRINT_RECORD")) {
    std::printf("cycles %d rows %d arrival", cycles, rows);
    for (long k : arrival) std::printf(" %ld", k);
    auto print = [](const char* name, const Eigen::VectorXd& v) {
      std::printf("\n%s", name);
      for (int i = 0; i < v.size(); ++i) std::printf(" %.17g,", v[i]);
    };
    print("sum_v", sum_v);
    print("sum_abs_v", sum_abs_v);
    print("state", state);
    std::printf("\n");
  }
  // Recorded with DualActiveSetQp (see above).
  const int expected_cycles = 1567, expected_rows = 15670;
  const std::vector<long> expected_arrival = {348, 356, 366, 497};
  Eigen::VectorXd expected_sum_v(8), expected_sum_abs_v(8), expected_state(9);
  expected_sum_v << 298.17631017200512, 518.16624992874313, 8.7937398549671126, -118.55608400875612,
      88.287504631544337, -0.014930797778809556, -93.811170378106965, -101.34617843716163;
  expected_sum_abs_v << 315.10425355347923, 518.16624992874313, 317.27102816417488, 412.11586704019868,
      432.84095069058878, 202.93122409039179, 246.98803020204605, 248.42706152087621;
  expected_state << 0.25464694645588914, -0.087957702535265817, 5.1816624992873814, 0.087937398549671544,
      -0.68556084008755924, -1.0171249536845579, -0.00014930797778991945, -1.4381117037810707,
      -1.013461784371616;
  EXPECT_EQ(cycles, expected_cycles);
  EXPECT_EQ(rows, expected_rows);
  EXPECT_EQ(arrival, expected_arrival);
  const double tol = 1e-8;
  EXPECT_LE((sum_v - expected_sum_v).cwiseAbs().maxCoeff(), tol) << sum_v.transpose();
  EXPECT_LE((sum_abs_v - expected_sum_abs_v).cwiseAbs().maxCoeff(), tol) << sum_abs_v.transpose();
  EXPECT_LE((state - expected_state).cwiseAbs().maxCoeff(), tol) << state.transpose();
}

TEST(EhcQpController, ObstacleRowsAreTheNearestPairsUpToTheBound) {
  auto model = std::make_shared<const WholeBodyModel>(realmanWithoutStopDistances());
  QpControllerParams p;
  p.mode = ControlMode::NeoC;
  p.max_obstacle_rows = 3;
  p.obstacle_stop_links["link6"] = 0.01;
  EhcQpController ctrl(model, p, nullptr);
  std::vector<ObstaclePair> pairs;
  // distance - d_s: link2 0.20, link3 0.05, link4 0.25, link5 0.35 (beyond d_i: never), link6 0.03,
  // link2 0.10.
  const std::vector<std::pair<std::string, double>> spec = {{"link2", 0.25}, {"link3", 0.10}, {"link4", 0.30},
                                                            {"link5", 0.40}, {"link6", 0.04}, {"link2", 0.15}};
  for (const auto& [link, d] : spec) {
    ObstaclePair o;
    o.link = link;
    o.distance = d;
    o.normal = Eigen::Vector3d::UnitX();
    pairs.push_back(o);
  }
  std::string bad;
  const std::vector<const ObstaclePair*> rows = ctrl.nearestObstaclePairs(pairs, &bad);
  EXPECT_EQ(bad, "");
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[0], &pairs[4]);  // link6, margin 0.03
  EXPECT_EQ(rows[1], &pairs[1]);  // link3, margin 0.05
  EXPECT_EQ(rows[2], &pairs[5]);  // link2, margin 0.10
  // 1000 pairs: still 3 rows; a bad pair anywhere is reported.
  std::vector<ObstaclePair> many(1000, pairs[1]);
  EXPECT_EQ(ctrl.nearestObstaclePairs(many, &bad).size(), 3u);
  many[999].normal.setZero();
  EXPECT_TRUE(ctrl.nearestObstaclePairs(many, &bad).empty());
  EXPECT_NE(bad.find("zero normal"), std::string::npos) << bad;
  // Parameters: a negative bound is rejected.
  p.max_obstacle_rows = -1;
  EXPECT_THROW(p.validate(), std::invalid_argument);
}
