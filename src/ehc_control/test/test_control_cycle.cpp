// ControlCycle (the one control cycle): closed-loop convergence through update() with each servo
// (proportional, PBVS, PBVS + MPBS); the watchdog (stale state -> STOPPED, no target -> IDLE,
// old target -> TARGET_LOST, a fresh one resumes) with zero commands; rejected inputs; TfM
// bookkeeping with the watched centre; a new target restarts the QP (TSMM stage); parameter
// loading from the shipped controller.yaml and the configuration checks. Required
// obstacles (OBSTACLES_STALE), no command from a state that went stale during the solve (fake
// clock), bounded obstacle rows (200 / 1000 pairs), the solve-time budget.

#include "ehc_common/config_node.h"
#include "ehc_control/control_cycle.h"
#include "ehc_test/control_fixtures.h"
#include "ehc_test/test_seed.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

using ehc_common::ConfigNode;

namespace ehc_control {
namespace {

using test::approachPose;

const std::string kConfigDir = EHC_CONFIG_DIR;

ControlCycleParams cycleParams(ServoType servo = ServoType::Proportional, bool mpbs = false) {
  ControlCycleParams p;
  p.robot_file = test::realmanYaml();
  p.servo_type = servo;
  p.mpbs.enabled = mpbs;
  p.tracking.camera_file = kConfigDir + "/robots/realman_rm65_water2/camera.yaml";
  p.watchdog.require_obstacles = false;  // no obstacle lists in these loops (said in every status)
  return p;
}

/// The cycle closed over a noise-free kinematic robot at 100 Hz; inputs stamped with sim time.
struct Loop {
  explicit Loop(const ControlCycleParams& p) : cycle(p) { sim.q = cycle.model().config().arm_ready; }

  void feedState(double t) {
    const RobotConfig& rc = cycle.model().config();
    ASSERT_EQ(cycle.setJointState(t, rc.arm_joints, std::vector<double>(sim.q.data(), sim.q.data() + sim.q.size())), "");
    ASSERT_EQ(cycle.setBasePose(t, sim.base), "");
  }
  /// One cycle at t = k dt: state (and the target, if given) stamped t, update, integrate
  /// (`move` false: the robot ignores the command, e.g. a blocked base).
  ControlCycleOutput step(const Eigen::Isometry3d* target = nullptr, bool move = true) {
    const double t = k * dt;
    feedState(t);
    if (target) {
      EXPECT_EQ(cycle.setTarget(t, *target), "");
    }
    ControlCycleOutput out = cycle.update(t);
    if (move) sim.step(cycle.model(), out.velocity, dt);
    ++k;
    return out;
  }
  double now() const { return k * dt; }

  ControlCycle cycle;
  test::KinematicSim sim;
  long k = 0;
  const double dt = 0.01;
};

bool isZero(const Eigen::VectorXd& v) { return v.size() > 0 && (v.array() == 0.0).all(); }

// ------------------------------------------------------------------ closed loop

struct ServoCase {
  const char* name;
  ServoType type;
  bool mpbs;
};

class ClosedLoop : public ::testing::TestWithParam<ServoCase> {};

TEST_P(ClosedLoop, ConvergesToTheTargetThroughUpdate) {
  Loop loop(cycleParams(GetParam().type, GetParam().mpbs));
  const Eigen::VectorXd vmax = loop.cycle.model().config().velocityLimits();
  const Eigen::Isometry3d target = approachPose(1.5, 0.3, 0.8, Eigen::Vector3d(1, 0, -1));
  ControlCycleStatus last;
  bool arrived = false;
  for (int i = 0; i < 3000 && !arrived; ++i) {
    const ControlCycleOutput out = loop.step(&target);
    last = out.status;
    ASSERT_TRUE(out.velocity.allFinite());
    EXPECT_TRUE((out.velocity.cwiseAbs().array() <= vmax.array() + 1e-12).all()) << out.velocity.transpose();
    ASSERT_EQ(last.qp_status, QpStatus::Ok) << last.phase << ": " << last.reason;
    EXPECT_EQ(last.mode, ControlMode::Ehc);
    EXPECT_TRUE(last.reason.empty()) << last.reason;
    EXPECT_GE(last.sig, 0.0);
    EXPECT_LE(last.sig, 1.0);
    arrived = last.phase == ControlPhase::Arrived;
    if (!arrived) {
      EXPECT_EQ(last.phase, ControlPhase::Tracking);
    }
  }
  ASSERT_TRUE(arrived) << GetParam().name << ": position error " << last.position_error << " after "
                       << loop.now() << " s";
  EXPECT_LT(last.position_error, 0.01);
  EXPECT_LT(last.orientation_error, 2.0 * M_PI / 180.0);
  EXPECT_GT(last.tfm, 0.0);  // TfM counted every cycle
  EXPECT_EQ(loop.cycle.tracker().cycles(), loop.k);
  const std::string& tcp = loop.cycle.model().config().tcp_frame;
  const Vector6d e = poseError(loop.cycle.model().fk(loop.sim.base, loop.sim.q, tcp), target);
  EXPECT_LT(e.head<3>().norm(), 0.012);  // one more integrated step past the arrival check
}

INSTANTIATE_TEST_SUITE_P(EveryServo, ClosedLoop,
                         ::testing::Values(ServoCase{"proportional", ServoType::Proportional, false},
                                           ServoCase{"pbvs", ServoType::Pbvs, false},
                                           ServoCase{"mpbs", ServoType::Pbvs, true}),
                         [](const auto& info) { return std::string(info.param.name); });

// ------------------------------------------------------------------ far approach

// A target metres away, 70-150 deg off the base's heading, with an approach direction turned
// anywhere around the vertical, from an arm posture left by an earlier target (the ready posture
// with every joint moved by up to 1 rad): every mode, through update() with the shipped servo
// (PBVS + MPBS), reaches it in 30 s, and while the TCP is beyond twice far_approach.distance no
// arm joint comes within joint_stop + recovery.pinned_margin of a limit and no stall recovery
// starts (the far approach carries the arm in its ready posture and the base faces the target;
// with the TCP's bearing alone a differential base drove past such targets with joint2 pinned,
// and stalled metres away: 17 of 39 seeds failed so). The base then arrives facing the target
// with the hand up to 3 rad from the grasp orientation; without recovery.free_stalls the QP
// settled 0.2-0.3 m short in a limit cycle with every joint free on 6 of 40 seeds.
TEST(ControlCycle, FarTargetOffTheHeadingIsReachedWithoutPinnedJointsByEveryMode) {
  const unsigned seed = ehc_test::testSeed("ControlCycle far approach");
  RecordProperty("seed", std::to_string(seed));
  SCOPED_TRACE("seed " + std::to_string(seed));
  std::mt19937 rng(seed);
  ControlCycleParams p = loadControlCycleParams(ConfigNode::loadFile(kConfigDir + "/control/controller.yaml", "ControllerNode"));
  p.watchdog.require_obstacles = false;
  const FarApproachParams& far = p.controller.far_approach;
  const double pinned = p.controller.joint_stop + p.controller.recovery.pinned_margin;
  std::uniform_real_distribution<double> off(70.0 * M_PI / 180.0, 150.0 * M_PI / 180.0), dist(3.0, 5.0),
      height(0.5, 0.9), azimuth(-M_PI, M_PI), tilt(0.0, 0.8), coin(0.0, 1.0);
  for (int trial = 0; trial < 3; ++trial) {
    const Loop probe(p);
    const WholeBodyModel& model = probe.cycle.model();
    const RobotConfig& rc = model.config();
    Eigen::Isometry3d target;
    do {  // a target whole-body IK reaches inside the joint stops
      const double bearing = (coin(rng) < 0.5 ? -1.0 : 1.0) * off(rng), d = dist(rng), a = azimuth(rng), t = tilt(rng);
      target = approachPose(d * std::cos(bearing), d * std::sin(bearing), height(rng),
                            Eigen::Vector3d(std::cos(a) * std::cos(t), std::sin(a) * std::cos(t), -std::sin(t)));
    } while (!model.inverseKinematics(target, seed, 30, nullptr, nullptr, p.controller.joint_stop));
    Eigen::VectorXd start = rc.arm_ready;  // a posture left by an earlier target: ready, joints moved by up to 1 rad
    std::uniform_real_distribution<double> shift(-1.0, 1.0);
    for (int j = 0; j < model.nArm(); ++j)
      start[j] = std::clamp(start[j] + shift(rng), rc.arm_lower[j] + 0.3, rc.arm_upper[j] - 0.3);
    for (ControlMode mode : {ControlMode::NeoC, ControlMode::NeoE, ControlMode::Ehc}) {
      SCOPED_TRACE("trial " + std::to_string(trial) + ", mode " + toString(mode) + ", target at [" +
                   std::to_string(target.translation().x()) + ", " + std::to_string(target.translation().y()) + "]");
      p.controller.mode = mode;
      Loop loop(p);
      loop.sim.q = start;
      ControlCycleStatus last;
      bool arrived = false, far_recovery = false;
      double far_margin = 1e9;
      for (int i = 0; i < 3000 && !arrived; ++i) {
        last = loop.step(&target).status;
        ASSERT_EQ(last.qp_status, QpStatus::Ok) << last.reason;
        const bool is_far = last.position_error > 2.0 * far.distance;
        far_recovery = far_recovery || (is_far && last.recovering);
        if (is_far && loop.now() > 2.0)  // after leaving the start posture
          for (int j = 0; j < model.nArm(); ++j)
            far_margin = std::min({far_margin, loop.sim.q[j] - rc.arm_lower[j], rc.arm_upper[j] - loop.sim.q[j]});
        arrived = last.phase == ControlPhase::Arrived;
      }
      EXPECT_TRUE(arrived) << "position error " << last.position_error << " m, orientation error "
                           << last.orientation_error << " rad after " << loop.now() << " s";
      EXPECT_FALSE(far_recovery) << "a stall recovery started while the target was far";
      EXPECT_GT(far_margin, pinned) << "an arm joint came to its stop while the target was far";
    }
  }
}

// ------------------------------------------------------------------ watchdog

TEST(ControlCycle, NoStateIsStoppedAndNoTargetIsIdleWithZeroCommands) {
  Loop loop(cycleParams());
  ControlCycleOutput out = loop.cycle.update(0.0);
  EXPECT_EQ(out.status.phase, ControlPhase::Stopped);
  EXPECT_NE(out.status.reason.find("no joint state"), std::string::npos) << out.status.reason;
  EXPECT_TRUE(isZero(out.velocity));
  EXPECT_EQ(out.velocity.size(), loop.cycle.model().nDof());
  loop.feedState(0.0);
  out = loop.cycle.update(0.0);
  EXPECT_EQ(out.status.phase, ControlPhase::Idle);
  EXPECT_EQ(out.status.reason, "no target");
  EXPECT_EQ(out.status.qp_status, QpStatus::NotRun);
  EXPECT_EQ(out.status.target_age, -1.0);
  EXPECT_FALSE(out.status.controller_error);
  EXPECT_TRUE(isZero(out.velocity));
  EXPECT_EQ(loop.cycle.tracker().cycles(), 0);  // TfM counts only with a target
}

TEST(ControlCycle, StaleJointStateStopsWithZeroCommand) {
  Loop loop(cycleParams());
  const Eigen::Isometry3d target = approachPose(1.5, 0.0, 0.8, Eigen::Vector3d(1, 0, -1));
  for (int i = 0; i < 10; ++i) EXPECT_EQ(loop.step(&target).status.phase, ControlPhase::Tracking);
  // Odometry and the target keep arriving, the joint state does not (state_timeout 0.2 s).
  const double t = loop.now() + 0.3;
  ASSERT_EQ(loop.cycle.setBasePose(t, loop.sim.base), "");
  ASSERT_EQ(loop.cycle.setTarget(t, target), "");
  const ControlCycleOutput out = loop.cycle.update(t);
  EXPECT_EQ(out.status.phase, ControlPhase::Stopped);
  EXPECT_NE(out.status.reason.find("joint state is"), std::string::npos) << out.status.reason;
  EXPECT_EQ(out.status.qp_status, QpStatus::NotRun);
  EXPECT_TRUE(isZero(out.velocity));
  // A fresh joint state resumes.
  loop.feedState(t);
  EXPECT_EQ(loop.cycle.update(t).status.phase, ControlPhase::Tracking);
}

/// `n` link-obstacle pairs within the influence distance around the arm, deterministic.
std::vector<ObstaclePair> manyPairs(const ControlCycle& cycle, int n) {
  const std::vector<std::string> links = {"link2", "link3", "link4", "link5", "link6"};
  std::vector<ObstaclePair> pairs;
  for (int i = 0; i < n; ++i) {
    ObstaclePair o;
    o.link = links[static_cast<std::size_t>(i) % links.size()];
    const double a = 0.37 * i;
    o.normal = Eigen::Vector3d(std::cos(a), std::sin(a), 0.3).normalized();
    o.link_point = cycle.model().fk(Eigen::Vector3d::Zero(), cycle.model().config().arm_ready, o.link).translation();
    o.distance = 0.10 + 0.15 * ((i * 7919) % 1000) / 1000.0;  // 0.10 .. 0.25 m, all < d_i 0.3
    o.obstacle_point = o.link_point - o.distance * o.normal;
    pairs.push_back(o);
  }
  return pairs;
}

TEST(ControlCycle, RequiredObstaclesMissingOrStaleStopWithObstaclesStale) {
  ControlCycleParams p = cycleParams();
  p.watchdog = SupervisorParams();  // the default: obstacle sensing required (safe unless a config says otherwise)
  ASSERT_TRUE(p.watchdog.require_obstacles);
  // A configuration that does not mention it requires it too.
  EXPECT_TRUE(loadControlCycleParams(ConfigNode::loadString("controller: {mode: ehc}\n", "/cfg/c.yaml", "Test"))
                  .watchdog.require_obstacles);
  Loop loop(p);
  const Eigen::Isometry3d target = approachPose(1.5, 0.0, 0.8, Eigen::Vector3d(1, 0, -1));
  // No obstacle list yet: stopped (not tracking blind), and the status says why.
  ControlCycleOutput out = loop.step(&target);
  EXPECT_EQ(out.status.phase, ControlPhase::ObstaclesStale);
  EXPECT_NE(out.status.reason.find("no obstacle list"), std::string::npos) << out.status.reason;
  EXPECT_TRUE(isZero(out.velocity));
  EXPECT_EQ(out.status.obstacles_age, -1.0);
  EXPECT_TRUE(out.status.obstacles_required);
  // A fresh list (empty: nothing near) lets it track.
  const double t_list = loop.now();
  ASSERT_EQ(loop.cycle.setObstacles(t_list, {}), "");
  out = loop.step(&target);
  EXPECT_EQ(out.status.phase, ControlPhase::Tracking) << out.status.reason;
  EXPECT_FALSE(isZero(out.velocity));
  // The obstacle node stalls or dies: state and target keep coming, the list ages past
  // obstacle_timeout (0.5 s) -> stopped with zero commands.
  ControlCycleOutput last;
  while (loop.now() - t_list <= p.watchdog.obstacle_timeout) {
    last = loop.step(&target);
    EXPECT_EQ(last.status.phase, ControlPhase::Tracking);
  }
  // The first zero command comes within one cycle after the list turned obstacle_timeout old.
  EXPECT_LE(loop.now() - t_list, p.watchdog.obstacle_timeout + loop.dt + 1e-9);
  out = loop.step(&target);
  EXPECT_EQ(out.status.phase, ControlPhase::ObstaclesStale);
  EXPECT_NE(out.status.reason.find("obstacle list is"), std::string::npos) << out.status.reason;
  EXPECT_GT(out.status.obstacles_age, p.watchdog.obstacle_timeout);
  EXPECT_TRUE(isZero(out.velocity));
  // A fresh list resumes.
  ASSERT_EQ(loop.cycle.setObstacles(loop.now(), {}), "");
  EXPECT_EQ(loop.step(&target).status.phase, ControlPhase::Tracking);
  // Not required (a config says so): the same stale list is dropped and the cycle tracks, and
  // every status says that obstacle sensing is off.
  Loop optional(cycleParams());
  ASSERT_EQ(optional.cycle.setObstacles(0.0, {}), "");
  for (int i = 0; i < 80; ++i) {
    const ControlCycleOutput o = optional.step(&target);
    EXPECT_EQ(o.status.phase, ControlPhase::Tracking);
    EXPECT_FALSE(o.status.obstacles_required);
  }
  EXPECT_FALSE(optional.cycle.stopped(optional.now(), "test").status.obstacles_required);
}

TEST(ControlCycle, ACommandIsNeverComputedFromAStateOlderThanTheStateTimeout) {
  Loop loop(cycleParams());
  const Eigen::Isometry3d target = approachPose(1.5, 0.0, 0.8, Eigen::Vector3d(1, 0, -1));
  // A fake clock: the solve "takes" `solve` seconds.
  double solve = 0.001;
  double started = 0.0;
  loop.cycle.setClock([&] { return started + solve; });
  started = loop.now();
  ControlCycleOutput out = loop.step(&target);
  EXPECT_EQ(out.status.phase, ControlPhase::Tracking) << out.status.reason;
  EXPECT_FALSE(isZero(out.velocity));
  // State stamped at the cycle start, fresh when the cycle starts (0.15 s < 0.2 s) but 0.35 s
  // old when the solve ends: the command is not sent (before: sent, from a 0.35 s old state).
  const double t_state = loop.now();
  loop.feedState(t_state);
  ASSERT_EQ(loop.cycle.setTarget(t_state + 0.15, target), "");
  started = t_state + 0.15;
  solve = 0.2;
  out = loop.cycle.update(started);
  EXPECT_EQ(out.status.phase, ControlPhase::Stopped);
  EXPECT_NE(out.status.reason.find("after the"), std::string::npos) << out.status.reason;
  EXPECT_NE(out.status.reason.find("joint state is"), std::string::npos) << out.status.reason;
  EXPECT_TRUE(isZero(out.velocity));
  EXPECT_NEAR(out.status.state_age, 0.35, 1e-9);  // the true age, at the end of the cycle
  // A quick solve with the same inputs is sent.
  solve = 0.01;
  out = loop.cycle.update(started);
  EXPECT_EQ(out.status.phase, ControlPhase::Tracking) << out.status.reason;
  EXPECT_FALSE(isZero(out.velocity));
  EXPECT_NEAR(out.status.state_age, 0.15, 1e-9);
}

TEST(ControlCycle, ObstacleRowsAreBoundedWhateverTheListLength) {
  ControlCycleParams p = cycleParams();
  p.controller.max_obstacle_rows = 12;
  Loop loop(p);
  const Eigen::Isometry3d target = approachPose(1.5, 0.0, 0.8, Eigen::Vector3d(1, 0, -1));
  for (int n : {200, 1000}) {
    ASSERT_EQ(loop.cycle.setObstacles(loop.now(), manyPairs(loop.cycle, n)), "");
    const ControlCycleOutput out = loop.step(&target);
    EXPECT_EQ(out.status.obstacle_rows, 12) << n << " pairs";
    EXPECT_TRUE(out.velocity.allFinite());
    EXPECT_NE(out.status.qp_status, QpStatus::NotRun);
  }
}

TEST(ControlCycle, ASolveOverItsTimeBudgetGivesAZeroCommandAndSaysWhy) {
  ControlCycleParams p = cycleParams();
  p.watchdog.max_solve_time = 0.05;
  Loop loop(p);
  const Eigen::Isometry3d target = approachPose(1.5, 0.0, 0.8, Eigen::Vector3d(1, 0, -1));
  // A fake clock: this cycle "takes" 60 ms (the state stays fresh: 0.06 s < 0.2 s).
  double started = loop.now();
  loop.cycle.setClock([&] { return started + 0.06; });
  const ControlCycleOutput out = loop.step(&target);
  EXPECT_EQ(out.status.phase, ControlPhase::QpFailed);
  EXPECT_EQ(out.status.qp_status, QpStatus::Failed);
  EXPECT_NE(out.status.reason.find("max_solve_time"), std::string::npos) << out.status.reason;
  EXPECT_TRUE(isZero(out.velocity));
  // 40 ms: within the budget, sent.
  started = loop.now();
  loop.cycle.setClock([&] { return started + 0.04; });
  const ControlCycleOutput ok = loop.step(&target);
  EXPECT_EQ(ok.status.phase, ControlPhase::Tracking) << ok.status.reason;
  EXPECT_FALSE(isZero(ok.velocity));
}

TEST(ControlCycle, StoppedIsAZeroCommandWithTheInputAges) {
  Loop loop(cycleParams());
  const Eigen::Isometry3d target = approachPose(1.5, 0.0, 0.8, Eigen::Vector3d(1, 0, -1));
  loop.step(&target);
  const ControlCycleOutput out = loop.cycle.stopped(0.5, "watchdog");
  EXPECT_EQ(out.status.phase, ControlPhase::Stopped);
  EXPECT_EQ(out.status.reason, "watchdog");
  EXPECT_TRUE(isZero(out.velocity));
  EXPECT_NEAR(out.status.state_age, 0.5, 1e-12);
  EXPECT_NEAR(out.status.target_age, 0.5, 1e-12);
}

TEST(ControlCycle, OldTargetIsLostWithZeroCommandsAndAFreshOneResumes) {
  ControlCycleParams p = cycleParams();
  p.watchdog.target_timeout = 0.25;
  Loop loop(p);
  const Eigen::Isometry3d target = approachPose(1.5, 0.0, 0.8, Eigen::Vector3d(1, 0, -1));
  ControlCycleOutput out = loop.step(&target);
  EXPECT_EQ(out.status.phase, ControlPhase::Tracking);
  EXPECT_FALSE(isZero(out.velocity));
  // The last good pose is served while younger than the timeout ...
  for (int i = 0; i < 24; ++i) {
    out = loop.step();
    EXPECT_EQ(out.status.phase, ControlPhase::Tracking) << loop.now();
    EXPECT_FALSE(isZero(out.velocity));
  }
  EXPECT_NEAR(out.status.target_age, 0.24, 1e-9);
  loop.step();  // age 0.25: the boundary
  // ... then TARGET_LOST, zero commands, every cycle; TfM keeps counting.
  const long tfm_cycles = loop.cycle.tracker().cycles();
  for (int i = 0; i < 20; ++i) {
    out = loop.step();
    EXPECT_EQ(out.status.phase, ControlPhase::TargetLost);
    EXPECT_NE(out.status.reason.find("target is"), std::string::npos) << out.status.reason;
    EXPECT_EQ(out.status.qp_status, QpStatus::NotRun);
    EXPECT_TRUE(isZero(out.velocity));
  }
  EXPECT_EQ(loop.cycle.tracker().cycles(), tfm_cycles + 20);
  EXPECT_NEAR(out.status.target_age, 0.45, 1e-9);
  // A fresh pose resumes.
  out = loop.step(&target);
  EXPECT_EQ(out.status.phase, ControlPhase::Tracking);
  EXPECT_EQ(out.status.qp_status, QpStatus::Ok);
  EXPECT_NEAR(out.status.target_age, 0.0, 1e-12);
  EXPECT_FALSE(isZero(out.velocity));
}

TEST(ControlCycle, InvalidInputsAreRejectedAndTheLastGoodOnesKept) {
  Loop loop(cycleParams());
  const RobotConfig& rc = loop.cycle.model().config();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> q(rc.arm_ready.data(), rc.arm_ready.data() + rc.nArm());
  q[2] = nan;
  EXPECT_NE(loop.cycle.setJointState(0.0, rc.arm_joints, q), "");
  EXPECT_NE(loop.cycle.setJointState(0.0, {"joint1"}, {0.0}), "");  // lacks arm joints
  EXPECT_NE(loop.cycle.setBasePose(0.0, Eigen::Vector3d(nan, 0, 0)), "");
  ControlCycleOutput out = loop.cycle.update(0.0);
  EXPECT_EQ(out.status.phase, ControlPhase::Stopped);  // nothing accepted yet
  EXPECT_TRUE(isZero(out.velocity));
  const Eigen::Isometry3d target = approachPose(1.5, 0.0, 0.8, Eigen::Vector3d(1, 0, -1));
  out = loop.step(&target);
  ASSERT_EQ(out.status.phase, ControlPhase::Tracking);
  // A NaN joint state later is rejected; the cycle runs on the last good state.
  EXPECT_NE(loop.cycle.setJointState(loop.now(), rc.arm_joints, q), "");
  EXPECT_TRUE(loop.cycle.supervisor().q().allFinite());
  Eigen::Isometry3d bad = target;
  bad.linear() *= 2.0;  // not a rotation
  EXPECT_NE(loop.cycle.setTarget(loop.now(), bad), "");
  EXPECT_NE(loop.cycle.setWatchedCentre(loop.now(), Eigen::Vector3d(0, nan, 0)), "");
  ObstaclePair o;
  o.link = "link6";
  o.normal.setZero();
  EXPECT_NE(loop.cycle.setObstacles(loop.now(), {o}), "");
  EXPECT_TRUE(loop.cycle.supervisor().target().isApprox(target));
  EXPECT_EQ(loop.cycle.supervisor().rejected(), 6);  // the centre is checked by the cycle
}

// ------------------------------------------------------------------ TfM, watched centre, new target

TEST(ControlCycle, TfmCountsInViewCyclesAndRestartsForANewTargetCentre) {
  Loop loop(cycleParams());
  // In front of the camera (ready pose looks ahead and slightly down).
  const Eigen::Isometry3d ahead = approachPose(1.5, 0.0, 0.6, Eigen::Vector3d(1, 0, -1));
  ControlCycleOutput out = loop.step(&ahead);
  EXPECT_NE(out.event.find("TfM restarts"), std::string::npos) << out.event;
  EXPECT_TRUE(out.status.target_in_fov);
  for (int i = 0; i < 9; ++i) {
    out = loop.step(&ahead);
    EXPECT_TRUE(out.event.empty()) << out.event;  // same target: no restart
  }
  EXPECT_EQ(loop.cycle.tracker().cycles(), 10);
  EXPECT_EQ(out.status.tfm, 1.0);
  // The camera watches another point (e.g. the object behind a pre-grasp goal): behind the
  // robot it is not in view; TfM restarts for it.
  ASSERT_EQ(loop.cycle.setWatchedCentre(loop.now(), Eigen::Vector3d(-2.0, 0.0, 0.6)), "");
  out = loop.step(&ahead);
  EXPECT_NE(out.event.find("TfM restarts"), std::string::npos);
  EXPECT_FALSE(out.status.target_in_fov);
  EXPECT_EQ(out.status.tfm, 0.0);
  EXPECT_TRUE(loop.cycle.watchedCentre(loop.now()).isApprox(Eigen::Vector3d(-2.0, 0.0, 0.6)));
  // Not refreshed for longer than centre_timeout (1 s): the target's own centre again.
  while (loop.now() < 2.5) loop.step(&ahead);
  EXPECT_TRUE(loop.cycle.watchedCentre(loop.now()).isApprox(ahead.translation()));
  EXPECT_TRUE(loop.cycle.tracker().centre().isApprox(ahead.translation()));
  EXPECT_GT(loop.cycle.tracker().tfm(), 0.0);
}

TEST(ControlCycle, ANewTargetRestartsTheQp) {
  // tsmm keeps its stage (base first, then arm) per target: a new target starts with the base.
  ControlCycleParams p = cycleParams();
  p.controller.mode = ControlMode::Tsmm;
  Loop loop(p);
  const Eigen::Isometry3d first = approachPose(1.2, 0.0, 0.8, Eigen::Vector3d(1, 0, -1));
  ControlCycleOutput out = loop.step(&first);
  EXPECT_EQ(out.status.phase, ControlPhase::TsmmBase);
  EXPECT_EQ(out.status.mode, ControlMode::Tsmm);
  for (int i = 0; i < 3000 && out.status.phase == ControlPhase::TsmmBase; ++i) out = loop.step(&first);
  ASSERT_EQ(out.status.phase, ControlPhase::TsmmArm);
  // The same pose again (every cycle, as the node receives it): the arm stage continues.
  for (int i = 0; i < 5; ++i) EXPECT_EQ(loop.step(&first).status.phase, ControlPhase::TsmmArm);
  // A different target 1 m further: the stage was reset, the base drives again (without the
  // reset the arm stage would go on: it is only left for a new target).
  Eigen::Isometry3d second = first;
  second.translation().x() += 1.0;
  out = loop.step(&second);
  EXPECT_EQ(out.status.phase, ControlPhase::TsmmBase);
  for (int i = 0; i < 3000 && out.status.phase == ControlPhase::TsmmBase; ++i) out = loop.step(&second);
  EXPECT_EQ(out.status.phase, ControlPhase::TsmmArm);
}

// ------------------------------------------------------------------ motion limits (a stall's cause)

/// The TCP's own pose: a target that asks for no motion.
Eigen::Isometry3d tcpPose(const Loop& loop) {
  return loop.cycle.model().fk(loop.sim.base, loop.sim.q, loop.cycle.model().config().tcp_frame);
}

TEST(ControlCycle, MotionLimitNamesTheJointPinnedAtItsStop) {
  const unsigned seed = ehc_test::testSeed("ControlCycle pinned joint");
  RecordProperty("seed", std::to_string(seed));
  SCOPED_TRACE("seed " + std::to_string(seed));
  std::mt19937 rng(seed);
  Loop loop(cycleParams());
  const RobotConfig& rc = loop.cycle.model().config();
  const QpControllerParams& qp = loop.cycle.controller().params();
  const double pinned = qp.joint_stop + qp.recovery.pinned_margin;  // one definition: ReachRecovery's
  ASSERT_LT(pinnedJoint(rc, rc.arm_ready, pinned), 0) << "the ready pose has a pinned joint";
  std::uniform_int_distribution<int> joint(0, rc.nArm() - 1);
  std::uniform_real_distribution<double> inside(0.0, 0.99 * pinned);
  for (int trial = 0; trial < 20; ++trial) {
    const int j = joint(rng);
    const bool upper = rng() % 2 == 0;
    const double margin = inside(rng);
    SCOPED_TRACE(rc.arm_joints[static_cast<std::size_t>(j)] + (upper ? " upper " : " lower ") + std::to_string(margin));
    auto at = [&](double m) {
      loop.sim.q = rc.arm_ready;
      loop.sim.q[j] = upper ? rc.arm_upper[j] - m : rc.arm_lower[j] + m;
      const Eigen::Isometry3d target = tcpPose(loop);
      return loop.step(&target, false).status.motion_limit;
    };
    const MotionLimitReport held = at(margin);
    EXPECT_EQ(held.limit, MotionLimit::JointLimit);
    EXPECT_EQ(held.joint, rc.arm_joints[static_cast<std::size_t>(j)]);
    EXPECT_NEAR(held.value, margin, 1e-9);
    EXPECT_NE(held.detail().find(held.joint), std::string::npos) << held.detail();
    // Beyond the pinned margin the joint is free.
    EXPECT_NE(at(pinned + 0.02).limit, MotionLimit::JointLimit);
  }
}

TEST(ControlCycle, MotionLimitNamesTheLinkObstaclePairHeldAtItsStopDistance) {
  Loop loop(cycleParams());
  const Eigen::Isometry3d target = tcpPose(loop);
  std::vector<ObstaclePair> pairs = manyPairs(loop.cycle, 10);  // 0.10-0.25 m: all beyond d_s + margin
  ASSERT_EQ(loop.cycle.setObstacles(loop.now(), pairs), "");
  EXPECT_EQ(loop.step(&target).status.motion_limit.limit, MotionLimit::None);
  // One pair at its link's stop distance (+ 4 mm, within motion_limit.obstacle_margin): named.
  const QpControllerParams& qp = loop.cycle.controller().params();
  ObstaclePair& held = pairs[3];
  held.distance = qp.obstacleStop(held.link) + 0.004;
  held.obstacle_point = held.link_point - held.distance * held.normal;
  ASSERT_EQ(loop.cycle.setObstacles(loop.now(), pairs), "");
  MotionLimitReport r = loop.step(&target).status.motion_limit;
  EXPECT_EQ(r.limit, MotionLimit::Obstacle);
  EXPECT_EQ(r.link, held.link);
  EXPECT_TRUE(r.obstacle_point.isApprox(held.obstacle_point)) << r.obstacle_point.transpose();
  EXPECT_NEAR(r.value, 0.004, 1e-9);
  // A finger closer to its own (smaller) stop distance is the tighter pair: d_s per link.
  ObstaclePair finger = held;
  finger.link = "left_finger_link";
  finger.distance = qp.obstacleStop(finger.link) + 0.001;
  ASSERT_LT(finger.distance, held.distance);
  pairs.push_back(finger);
  ASSERT_EQ(loop.cycle.setObstacles(loop.now(), pairs), "");
  r = loop.step(&target).status.motion_limit;
  EXPECT_EQ(r.link, "left_finger_link");
  EXPECT_NE(r.detail().find("left_finger_link"), std::string::npos) << r.detail();
}

TEST(ControlCycle, MotionLimitNamesATargetOutOfViewForTargetUnseenTime) {
  Loop loop(cycleParams());
  const Eigen::Isometry3d target = tcpPose(loop);
  const double unseen = loop.cycle.params().motion_limit.target_unseen_time;
  const double t0 = loop.now();
  ControlCycleOutput out;
  while (loop.now() - t0 < unseen + 0.5) {
    ASSERT_EQ(loop.cycle.setWatchedCentre(loop.now(), Eigen::Vector3d(-2.0, 0.0, 0.6)), "");  // behind the robot
    const double t = loop.now();
    out = loop.step(&target);
    ASSERT_FALSE(out.status.target_in_fov);
    if (t - t0 < unseen - 1e-9) {
      EXPECT_NE(out.status.motion_limit.limit, MotionLimit::TargetNotSeen) << "t " << t;
    }
  }
  EXPECT_EQ(out.status.motion_limit.limit, MotionLimit::TargetNotSeen);
  EXPECT_GE(out.status.motion_limit.value, unseen);
  // In view again: no longer.
  ASSERT_EQ(loop.cycle.setWatchedCentre(loop.now(), Eigen::Vector3d(1.5, 0.0, 0.6)), "");
  out = loop.step(&target);
  ASSERT_TRUE(out.status.target_in_fov);
  EXPECT_NE(out.status.motion_limit.limit, MotionLimit::TargetNotSeen);
}

TEST(ControlCycle, MotionLimitNamesABaseThatIsCommandedButDoesNotMove) {
  Loop loop(cycleParams());
  const Eigen::Isometry3d far = approachPose(2.5, 0.0, 0.8, Eigen::Vector3d(1, 0, -1));  // the base must drive
  const double window = loop.cycle.params().motion_limit.base_window;
  ControlCycleOutput out;
  // The base does not follow its command (blocked, a stalled drive).
  while (loop.now() < window + 0.2) {
    const double t = loop.now();
    out = loop.step(&far, false);
    EXPECT_GT(std::abs(out.velocity[0]), loop.cycle.params().motion_limit.base_command) << "t " << t;
    if (t < window - 1e-9) {
      EXPECT_NE(out.status.motion_limit.limit, MotionLimit::BaseNotMoving) << "t " << t;
    }
  }
  EXPECT_EQ(out.status.motion_limit.limit, MotionLimit::BaseNotMoving);
  EXPECT_LT(out.status.motion_limit.value, 1e-12);
  // It drives: within a few cycles no longer.
  for (int i = 0; i < 5; ++i) out = loop.step(&far);
  EXPECT_EQ(out.status.motion_limit.limit, MotionLimit::None);
}

TEST(ControlCycle, MotionLimitNamesASingularArmAndASaturatedSlackInTheirOrder) {
  const ControlCycle cycle(cycleParams());
  const WholeBodyModel& model = cycle.model();
  const QpControllerParams& qp = cycle.controller().params();
  MotionLimitMonitor m(model, qp, MotionLimitParams{});
  MotionLimitMonitor::Cycle c;
  c.q = model.config().arm_ready;
  c.has_target = true;
  c.target_in_fov = true;
  EXPECT_EQ(m.update(c).limit, MotionLimit::None);
  // The arm stretched straight (every joint at 0): singular.
  c.q = Eigen::VectorXd::Zero(model.nArm());
  ASSERT_LT(m.manipulabilityRatio(c.q), MotionLimitParams{}.singular_manipulability);
  MotionLimitReport r = m.update(c);
  EXPECT_EQ(r.limit, MotionLimit::Singular);
  EXPECT_LT(r.value, MotionLimitParams{}.singular_manipulability);
  // A task slack at its bound.
  c.q = model.config().arm_ready;
  Vector6d slack = Vector6d::Zero();
  slack[4] = -0.97 * qp.slack_bound;
  c.slack = &slack;
  r = m.update(c);
  EXPECT_EQ(r.limit, MotionLimit::SlackSaturated);
  EXPECT_NEAR(r.value, 0.97, 1e-12);
  // A pinned joint comes first (the order of MotionLimit).
  c.q[0] = model.config().arm_upper[0] - qp.joint_stop;
  EXPECT_EQ(m.update(c).limit, MotionLimit::JointLimit);
  for (MotionLimit l : motionLimits()) EXPECT_EQ(motionLimitFromString(toString(l)), l);
}

// ------------------------------------------------------------------ parameters

TEST(ControlCycle, LoadsTheShippedControllerYamlAndChecksTheConfiguration) {
  const ConfigNode cfg = ConfigNode::loadFile(kConfigDir + "/control/controller.yaml", "ControllerNode");
  const ControlCycleParams p = loadControlCycleParams(cfg);
  EXPECT_EQ(p.servo_type, ServoType::Pbvs);
  EXPECT_TRUE(p.mpbs.enabled);
  EXPECT_EQ(p.centre_timeout, 1.0);
  EXPECT_EQ(p.watchdog.target_timeout, 0.2);
  EXPECT_EQ(p.controller.mode, ControlMode::Ehc);
  EXPECT_NE(p.robot_file.find("robots/realman_rm65_water2/robot.yaml"), std::string::npos) << p.robot_file;
  EXPECT_TRUE(p.tracking.camera_file.empty());  // robot-specific: robot.yaml's robot.camera_info
  const ControlCycle cycle(p);
  EXPECT_NE(cycle.params().tracking.camera_file.find("realman_rm65_water2/camera.yaml"), std::string::npos);
  // Per-link stop distances come from robot.yaml (controller.yaml names no link).
  EXPECT_EQ(cycle.controller().params().obstacleStop("ee_link"), 0.01);
  EXPECT_EQ(cycle.controller().params().obstacleStop("link2"), p.controller.obstacle_stop);
  EXPECT_TRUE(cycle.controller().hasWeighting());
  EXPECT_GE(cycle.rollJointIndex(), 0);
  const Eigen::VectorXd& ready = cycle.model().config().arm_ready;
  const std::optional<RollJoint> roll = cycle.rollJointAt(ready);
  ASSERT_TRUE(roll.has_value());
  EXPECT_EQ(roll->q, ready[cycle.rollJointIndex()]);
  const std::string summary = cycle.summary();
  for (const char* part : {"servo: pbvs", "mpbs: on", "roll joint joint6", "centre timeout 1 s", "watchdog: state 0.2 s"})
    EXPECT_NE(summary.find(part), std::string::npos) << part << " not in\n" << summary;

  // Every shipped controller.yaml (demo and real robot extend this one) builds a cycle.
  for (const char* file : {"/demo/controller.yaml", "/realman/controller.yaml"}) {
    SCOPED_TRACE(file);
    const ControlCycleParams other = loadControlCycleParams(ConfigNode::loadFile(kConfigDir + file, "ControllerNode"));
    EXPECT_EQ(other.servo_type, ServoType::Pbvs);
    EXPECT_NO_THROW(ControlCycle{other});
  }

  auto load = [](const std::string& yaml) {
    return loadControlCycleParams(ConfigNode::loadString(yaml, "/cfg/controller.yaml", "ControllerNode"));
  };
  EXPECT_EQ(load("servo: {type: proportional}\n").servo_type, ServoType::Proportional);
  EXPECT_EQ(load("{}\n").robot_file, resolveRobotFile("realman_rm65_water2"));
  EXPECT_EQ(load("robot: my/robot.yaml\n").robot_file, "/cfg/my/robot.yaml");  // a path: relative to the file
  EXPECT_EQ(load("robot: kuka_iiwa14_kmr\n").robot_file, robotsDirectory() + "/kuka_iiwa14_kmr/robot.yaml");
  for (const char* bad : {"robot: no_such_robot\n", "controller: {obstacle_stop_links: {ee_link: 0.01}}\n"}) {
    try {
      load(bad);
      ADD_FAILURE() << bad << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("/cfg/controller.yaml"), std::string::npos) << e.what();
    }
  }
  try {
    load("servo: {type: visp}\n");
    ADD_FAILURE() << "bad servo type accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("servo.type"), std::string::npos) << e.what();
  }
  EXPECT_THROW(load("tracking: {centre_timeout: 0}\n"), std::invalid_argument);
  EXPECT_THROW(load("watchdog: {target_timeout: -1}\n"), std::invalid_argument);
  EXPECT_EQ(load("motion_limit: {base_window: 2.5}\n").motion_limit.base_window, 2.5);
  try {
    load("motion_limit: {base_window: 0}\n");
    ADD_FAILURE() << "base_window 0 accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("base_window"), std::string::npos) << e.what();
  }
  {  // an unknown key of the section: the node's check (rejectUnknownKeys) names it
    const ConfigNode root = ConfigNode::loadString("motion_limit: {stall_time: 1}\n", "/cfg/controller.yaml", "ControllerNode");
    loadControlCycleParams(root);
    try {
      root.rejectUnknownKeys();
      ADD_FAILURE() << "motion_limit.stall_time accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("stall_time"), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(servoTypeFromString("PBVS"), std::invalid_argument);
  EXPECT_EQ(servoTypeFromString(toString(ServoType::Pbvs)), ServoType::Pbvs);

  // MPBS needs sig(omega), i.e. a reachability map.
  RobotConfig no_map = test::realmanConfig();
  no_map.reachability_map_path.clear();
  auto model = std::make_shared<const WholeBodyModel>(no_map);
  ControlCycleParams mpbs = cycleParams(ServoType::Pbvs, true);
  mpbs.controller.mode = ControlMode::NeoC;
  try {
    ControlCycle(model, nullptr, mpbs);
    ADD_FAILURE() << "MPBS without a map accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("[ControlCycle] mpbs.enabled needs"), std::string::npos) << e.what();
  }
  mpbs.mpbs.enabled = false;
  EXPECT_NO_THROW(ControlCycle(model, nullptr, mpbs));
  mpbs.controller.mode = ControlMode::Ehc;  // ehc needs the map too
  EXPECT_THROW(ControlCycle(model, nullptr, mpbs), std::invalid_argument);
}

}  // namespace
}  // namespace ehc_control
