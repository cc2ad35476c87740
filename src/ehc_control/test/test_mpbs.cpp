// MPBS (paper eq. 14): T* = sig T_grasp (+) (1 - sig) T_monitor on SE(3).
// sig = 1 gives the grasp pose; sig = 0 puts the target centre on the camera's optical axis;
// every interpolated rotation is a rotation; T* is continuous in sig and along the approach;
// MPBS off serves the grasp pose. Last, a whole-body closed loop (ControlCycle: model + EHC QP +
// MPBS, no ROS) shows the point of it: with MPBS the camera keeps the target in view while the robot
// approaches a downward grasp, without MPBS it loses it for part of the approach.

#include "ehc_common/config_node.h"
#include "ehc_control/control_cycle.h"
#include "ehc_control/mpbs.h"
#include "ehc_test/control_fixtures.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <random>

namespace ehc_control {
namespace {

using test::realmanTcpToCamera;

Eigen::Matrix3d randomRotation(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  return Eigen::Quaterniond(u(rng), u(rng), u(rng), u(rng)).normalized().toRotationMatrix();
}

Eigen::Isometry3d randomPose(std::mt19937& rng, double extent) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = randomRotation(rng);
  T.translation() << extent * u(rng), extent * u(rng), extent * u(rng);
  return T;
}

double angleBetween(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(Eigen::Matrix3d(a.transpose() * b)).angle();
}

void expectRotation(const Eigen::Matrix3d& R) {
  EXPECT_LT((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), 1e-12);
  EXPECT_NEAR(R.determinant(), 1.0, 1e-12);
}

TEST(Mpbs, SigOneIsTheGraspPose) {
  const Eigen::Isometry3d eTc = realmanTcpToCamera();
  std::mt19937 rng(1);
  for (int i = 0; i < 100; ++i) {
    const Eigen::Isometry3d grasp = randomPose(rng, 2.0);
    const Eigen::Vector3d tcp = grasp.translation() + Eigen::Vector3d(1.5, -0.5, 0.4);
    const Eigen::Isometry3d monitor = monitoringPose(tcp, grasp, grasp.translation(), eTc, 0.15);
    const Eigen::Isometry3d T = mpbsDesiredPose(1.0, grasp, monitor);
    EXPECT_TRUE(T.matrix().isApprox(grasp.matrix(), 1e-12)) << i;
    EXPECT_TRUE(monitor.translation().isApprox(grasp.translation(), 1e-15));  // same position
  }
}

TEST(Mpbs, SigZeroPutsTheTargetCentreOnTheOpticalAxis) {
  const Eigen::Isometry3d eTc = realmanTcpToCamera();
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> dist(0.31, 4.0);
  for (int i = 0; i < 500; ++i) {
    const Eigen::Isometry3d grasp = randomPose(rng, 2.0);
    const Eigen::Vector3d centre = grasp * Eigen::Vector3d(0.0, 0.0, 0.03);
    const Eigen::Vector3d tcp = centre + dist(rng) * randomRotation(rng).col(0);
    const Eigen::Isometry3d T = mpbsDesiredPose(0.0, grasp, monitoringPose(tcp, grasp, centre, eTc, 0.15));
    expectRotation(T.linear());
    // The camera where the TCP is now, with the monitoring orientation.
    Eigen::Isometry3d tcp_pose = T;
    tcp_pose.translation() = tcp;
    const Eigen::Vector3d p = (tcp_pose * eTc).inverse() * centre;
    EXPECT_GT(p.z(), 0.0) << i;
    EXPECT_LT(p.head<2>().norm(), 1e-9 * p.z()) << i << ": " << p.transpose();
  }
}

TEST(Mpbs, MonitoringOrientationIsTheGraspOneTurnedTheLeast) {
  // The look-at constraint leaves the roll about the line of sight free; the chosen one is the
  // closest to the grasp orientation, so no look-at orientation is closer.
  const Eigen::Isometry3d eTc = realmanTcpToCamera();
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> roll(-M_PI, M_PI);
  for (int i = 0; i < 100; ++i) {
    const Eigen::Isometry3d grasp = randomPose(rng, 1.0);
    const Eigen::Vector3d tcp = grasp.translation() + 2.0 * randomRotation(rng).col(0);
    const Eigen::Isometry3d m = monitoringPose(tcp, grasp, grasp.translation(), eTc, 0.15);
    const double best = angleBetween(m.linear(), grasp.linear());
    const Eigen::Vector3d los = (grasp.translation() - tcp).normalized();
    for (int k = 0; k < 20; ++k) {  // other look-at orientations: rolled about the line of sight
      const Eigen::Matrix3d other = Eigen::AngleAxisd(roll(rng), los).toRotationMatrix() * m.linear();
      EXPECT_GE(angleBetween(other, grasp.linear()), best - 1e-9);
    }
  }
}

TEST(Mpbs, InterpolatedPosesAreValidAndGeodesic) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> s01(0.0, 1.0);
  for (int i = 0; i < 1000; ++i) {
    const Eigen::Isometry3d a = randomPose(rng, 2.0), b = randomPose(rng, 2.0);
    const double s = s01(rng);
    const Eigen::Isometry3d T = interpolatePose(a, b, s);
    expectRotation(T.linear());
    EXPECT_TRUE(T.translation().isApprox((1 - s) * a.translation() + s * b.translation(), 1e-12));
    // On the shorter geodesic: angle(a, T) = s angle(a, b), angle(T, b) = (1 - s) angle(a, b).
    const double ab = angleBetween(a.linear(), b.linear());
    EXPECT_NEAR(angleBetween(a.linear(), T.linear()), s * ab, 1e-9);
    EXPECT_NEAR(angleBetween(T.linear(), b.linear()), (1 - s) * ab, 1e-9);
  }
  // Clamped outside [0, 1]; never a matrix average (which would not be a rotation here).
  const Eigen::Isometry3d a = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d b = a;
  b.linear() = Eigen::AngleAxisd(M_PI - 0.01, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  expectRotation(interpolatePose(a, b, 0.5).linear());
  EXPECT_TRUE(interpolatePose(a, b, -1.0).isApprox(a));
  EXPECT_TRUE(interpolatePose(a, b, 2.0).isApprox(b));
  Eigen::Isometry3d nan = a;
  nan.translation().x() = std::nan("");
  EXPECT_THROW(interpolatePose(a, nan, 0.5), std::invalid_argument);
}

TEST(Mpbs, DesiredPoseIsContinuousInSigAndAlongTheApproach) {
  const Eigen::Isometry3d eTc = realmanTcpToCamera();
  std::mt19937 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Isometry3d grasp = randomPose(rng, 1.0);
    const Eigen::Vector3d start = grasp.translation() + 3.0 * randomRotation(rng).col(0);
    const Eigen::Isometry3d monitor = monitoringPose(start, grasp, grasp.translation(), eTc, 0.15);
    const double total = angleBetween(monitor.linear(), grasp.linear());
    Eigen::Isometry3d prev = mpbsDesiredPose(0.0, grasp, monitor);
    const double ds = 1e-3;
    for (double s = ds; s <= 1.0 + 1e-12; s += ds) {  // Lipschitz in sig with the geodesic length
      const Eigen::Isometry3d T = mpbsDesiredPose(s, grasp, monitor);
      EXPECT_LE(angleBetween(prev.linear(), T.linear()), total * ds + 1e-9);
      prev = T;
    }
    // Along a straight approach from 3 m to 0 m the monitoring pose moves continuously (no roll
    // flips) and ends at the grasp orientation.
    Eigen::Isometry3d last = monitor;
    for (int k = 1; k <= 3000; ++k) {
      const Eigen::Vector3d p = start + (grasp.translation() - start) * (k / 3000.0);
      const Eigen::Isometry3d m = monitoringPose(p, grasp, grasp.translation(), eTc, 0.15);
      EXPECT_LT(angleBetween(last.linear(), m.linear()), 0.05) << trial << " step " << k;
      last = m;
    }
    EXPECT_LT(angleBetween(last.linear(), grasp.linear()), 1e-12);
  }
}

TEST(Mpbs, ServoFollowsTheBlendAndOffMeansTheGraspPose) {
  const Eigen::Isometry3d eTc = realmanTcpToCamera();
  MpbsParams on;
  MpbsParams off;
  off.enabled = false;
  MpbsServo with(eTc, PbvsServoParams{}, on), without(eTc, PbvsServoParams{}, off);
  PbvsServo plain(eTc, PbvsServoParams{});
  Eigen::Isometry3d grasp = Eigen::Isometry3d::Identity();
  grasp.translation() << 2.0, 0.0, 0.6;
  grasp.linear() = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY()).toRotationMatrix();  // downward
  Eigen::Isometry3d tcp = Eigen::Isometry3d::Identity();
  tcp.translation() << 0.0, 0.0, 1.0;
  tcp.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix();  // looking forward
  for (double sig : {0.0, 0.3, 0.7, 1.0}) {
    const MpbsOutput a = with.compute(tcp, grasp, sig), b = without.compute(tcp, grasp, sig);
    EXPECT_TRUE(a.desired.isApprox(interpolatePose(a.monitor, grasp, sig), 1e-12));
    EXPECT_TRUE(b.desired.isApprox(grasp, 1e-12));
    EXPECT_LT((b.twist - plain.twist(tcp, grasp)).norm(), 1e-12);
  }
  // Far away (sig = 0) the camera is turned towards the target: it ends up looking at it.
  const MpbsOutput far = with.compute(tcp, grasp, 0.0);
  Eigen::Isometry3d look = far.desired;
  look.translation() = tcp.translation();
  const Eigen::Vector3d p = (look * eTc).inverse() * grasp.translation();
  EXPECT_GT(p.z(), 0.0);
  EXPECT_LT(p.head<2>().norm(), 1e-9);
  // Within min_monitor_distance the grasp orientation is served whatever sig.
  Eigen::Isometry3d near = grasp;
  near.translation().z() += 0.1;
  EXPECT_TRUE(with.compute(near, grasp, 0.0).desired.isApprox(grasp, 1e-12));
  // Bad configuration: the monitoring distance must exceed the camera's offset from the TCP.
  MpbsParams tiny;
  tiny.min_monitor_distance = 0.05;
  EXPECT_THROW(MpbsServo(eTc, PbvsServoParams{}, tiny), std::invalid_argument);
  EXPECT_THROW(loadMpbsParams(ehc_common::ConfigNode::loadString("target_centre: [1, 2]\n", "c.yaml", "ControllerNode")),
               std::invalid_argument);
  const MpbsParams loaded = loadMpbsParams(
      ehc_common::ConfigNode::loadString("enabled: false\nmin_monitor_distance: 0.2\ntarget_centre: [0, 0, 0.03]\n", "c.yaml", "X"));
  EXPECT_FALSE(loaded.enabled);
  EXPECT_EQ(loaded.min_monitor_distance, 0.2);
  EXPECT_EQ(loaded.target_centre.z(), 0.03);
}

// ------------------------------------------------------------------ whole-body closed loop

struct LoopResult {
  bool arrived = false;
  double time_s = 0.0, tfm = 0.0;
  double tfm_monitoring = 0.0;  ///< over the cycles with sig(omega) < 0.5 (T* closer to T_monitor)
};

/// Kinematic closed loop at 100 Hz through the control cycle: RealMan robot (differential
/// base), EHC QP, PBVS with or without MPBS, TfM from the cycle's status.
LoopResult runLoop(bool mpbs, const Eigen::Isometry3d& grasp, double time_limit) {
  ControlCycleParams p;
  p.robot_file = test::realmanYaml();
  p.servo_type = ServoType::Pbvs;
  p.mpbs.enabled = mpbs;
  p.tracking.camera_file = std::string(EHC_CONFIG_DIR) + "/robots/realman_rm65_water2/camera.yaml";
  p.watchdog.require_obstacles = false;  // no obstacle lists here
  ControlCycle cycle(p);
  const RobotConfig& rc = cycle.model().config();
  test::KinematicSim sim{Eigen::Vector3d::Zero(), rc.arm_ready};
  LoopResult r;
  long monitoring_cycles = 0, monitoring_in_view = 0;
  const double dt = 0.01;
  for (int k = 0; k < static_cast<int>(time_limit / dt); ++k) {
    const double t = k * dt;
    EXPECT_EQ(cycle.setJointState(t, rc.arm_joints, std::vector<double>(sim.q.data(), sim.q.data() + sim.q.size())), "");
    EXPECT_EQ(cycle.setBasePose(t, sim.base), "");
    EXPECT_EQ(cycle.setTarget(t, grasp), "");
    const ControlCycleOutput out = cycle.update(t);
    const ControlCycleStatus& s = out.status;
    if (s.sig < 0.5) {
      ++monitoring_cycles;
      monitoring_in_view += s.target_in_fov;
    }
    if (std::getenv("EHC_TRACE") && mpbs && k % 20 == 0)
      std::printf("t %.2f in_view %d |p| %.3f rot %.3f sig %.3f base %.2f %.2f %.2f\n", t, s.target_in_fov,
                  s.position_error, s.orientation_error, s.sig, sim.base.x(), sim.base.y(), sim.base.z());
    EXPECT_EQ(s.qp_status, QpStatus::Ok) << s.phase << ": " << s.reason;
    if (s.phase == ControlPhase::Arrived) {
      r.arrived = true;
      r.time_s = t;
      break;
    }
    sim.step(cycle.model(), out.velocity, dt);
  }
  r.tfm = cycle.tracker().tfm();
  r.tfm_monitoring = monitoring_cycles > 0 ? static_cast<double>(monitoring_in_view) / static_cast<double>(monitoring_cycles) : 0.0;
  return r;
}

TEST(Mpbs, WholeBodyLoopKeepsTheTargetInViewAndStillGrasps) {
  // The object of config/scenes/single_object.yaml (1.5 m ahead, centre 0.76 m high) and one
  // 2.5 m ahead and 0.5 m to the left; forward, downward and sideways grasps (paper Exp-3).
  // MPBS watches the target while the base leads (sig < 0.5, T* closer to T_monitor); when
  // the arm takes over (sig -> 1, about 0.25 m from the target here) T* turns to the grasp
  // orientation and the target centre, soon between the fingers and closer than the camera
  // (9 cm behind the TCP, 7 cm off-axis) can see, leaves the image: overall TfM < 1 also with
  // MPBS. Without MPBS the camera turns away early for downward and sideways grasps.
  const char* names[] = {"forward", "downward", "sideways"};
  for (const Eigen::Vector3d& position : {Eigen::Vector3d(1.5, 0.0, 0.76), Eigen::Vector3d(2.5, 0.5, 0.76)}) {
    for (int orientation = 0; orientation < 3; ++orientation) {
      Eigen::Isometry3d grasp = Eigen::Isometry3d::Identity();
      grasp.translation() = position;
      if (orientation == 0)  // approach +x
        grasp.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix();
      else if (orientation == 1)  // approach -z
        grasp.linear() = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()).toRotationMatrix();
      else  // approach +y
        grasp.linear() = Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitX()).toRotationMatrix();
      const LoopResult with = runLoop(true, grasp, 30.0), without = runLoop(false, grasp, 30.0);
      SCOPED_TRACE(std::string(names[orientation]) + " at x " + std::to_string(position.x()));
      std::printf("[ MPBS loop ] %-8s x %.1f: MPBS arrived %d in %5.2f s, TfM %.3f (sig < 0.5: %.3f); "
                  "PBVS arrived %d in %5.2f s, TfM %.3f (sig < 0.5: %.3f)\n",
                  names[orientation], position.x(), with.arrived, with.time_s, with.tfm, with.tfm_monitoring,
                  without.arrived, without.time_s, without.tfm, without.tfm_monitoring);
      EXPECT_TRUE(with.arrived);
      EXPECT_TRUE(without.arrived);
      EXPECT_GE(with.tfm_monitoring, 0.95);
      if (orientation > 0) {
        EXPECT_GT(with.tfm, without.tfm);
      }
    }
  }
}

}  // namespace
}  // namespace ehc_control
