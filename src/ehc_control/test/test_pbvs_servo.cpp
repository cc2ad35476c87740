// PbvsServo (ViSP eye-in-hand PBVS): the camera twist computed by vpServo is converted into the
// TCP twist with the camera mount of the URDF. Proven (1) against the analytic rigid-body twist
// transform, (2) by integrating the TCP twist: the TCP converges to the desired pose and the
// camera origin travels on the straight line the cdMc PBVS law prescribes (a wrong mount
// transform bends it), plus the adaptive gain, the saturation and the roll unwinding.

#include "ehc_common/config_node.h"
#include "ehc_control/pbvs_servo.h"
#include "ehc_test/control_fixtures.h"

#include <gtest/gtest.h>

#include <random>

using ehc_common::ConfigNode;

namespace ehc_control {
namespace {

using test::realmanTcpToCamera;

Eigen::Isometry3d randomPose(std::mt19937& rng, double extent) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(u(rng), u(rng), u(rng), u(rng)).normalized().toRotationMatrix();
  T.translation() << extent * u(rng), extent * u(rng), extent * u(rng);
  return T;
}

/// Euler step of a world-frame twist [v; w] taken at the TCP origin.
void integrate(Eigen::Isometry3d& T, const Vector6d& nu, double dt) {
  T.translation() += nu.head<3>() * dt;
  const double w = nu.tail<3>().norm();
  if (w > 0) T.linear() = Eigen::AngleAxisd(w * dt, nu.tail<3>() / w).toRotationMatrix() * T.linear();
}

double angleBetween(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(Eigen::Matrix3d(a.transpose() * b)).angle();
}

PbvsServoParams unsaturated() {
  PbvsServoParams p;
  p.max_linear = 100.0;
  p.max_angular = 100.0;
  return p;
}

TEST(PbvsServo, CameraMountIsTheUrdfOne) {
  const Eigen::Isometry3d eTc = realmanTcpToCamera();
  // URDF: camera 0.07 m along the flange x, 0.03 m along the flange z; TCP 0.12 m along the
  // flange z; optical axis = approach axis (TCP z).
  EXPECT_TRUE(eTc.translation().isApprox(Eigen::Vector3d(0.07, 0.0, -0.09), 1e-9)) << eTc.translation().transpose();
  EXPECT_GT(eTc.linear().col(2).dot(Eigen::Vector3d::UnitZ()), 1.0 - 1e-9);
}

TEST(PbvsServo, TcpTwistIsTheAnalyticTransformOfTheCameraTwist) {
  const Eigen::Isometry3d eTc = realmanTcpToCamera();
  PbvsServo servo(eTc, unsaturated());
  std::mt19937 rng(7);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Isometry3d tcp = randomPose(rng, 2.0), desired = randomPose(rng, 2.0);
    const Vector6d nu = servo.twist(tcp, desired);
    ASSERT_DOUBLE_EQ(servo.scale(), 1.0);
    const Vector6d vc = servo.cameraTwist();
    // Rigid body: w is the same vector; the TCP point's velocity is the camera point's plus
    // w x (p_tcp - p_cam).
    const Eigen::Matrix3d R_wc = tcp.linear() * eTc.linear();
    const Eigen::Vector3d w = R_wc * vc.tail<3>();
    const Eigen::Vector3d p_cam = tcp * eTc.translation();
    const Eigen::Vector3d v = R_wc * vc.head<3>() + w.cross(tcp.translation() - p_cam);
    EXPECT_LT((nu.head<3>() - v).norm(), 1e-9 * (1.0 + v.norm())) << i;
    EXPECT_LT((nu.tail<3>() - w).norm(), 1e-9 * (1.0 + w.norm())) << i;
  }
}

TEST(PbvsServo, CameraTwistIsThePbvsLawWithTheAdaptiveGain) {
  const Eigen::Isometry3d eTc = realmanTcpToCamera();
  PbvsServoParams p = unsaturated();
  PbvsServo servo(eTc, p);
  std::mt19937 rng(11);
  for (int i = 0; i < 50; ++i) {
    const Eigen::Isometry3d tcp = randomPose(rng, 1.0), desired = randomPose(rng, 1.0);
    servo.twist(tcp, desired);
    const Eigen::Isometry3d cdMc = (desired * eTc).inverse() * (tcp * eTc);
    const Eigen::AngleAxisd tu(cdMc.linear());
    // vpServo: lambda(|e1|_inf) of vpAdaptiveGain, e1 = L^+ (s - s*) = [cdRc^T cd_t_c; theta u].
    const double x = std::max((cdMc.linear().transpose() * cdMc.translation()).cwiseAbs().maxCoeff(),
                              (tu.angle() * tu.axis()).cwiseAbs().maxCoeff());
    const double a = p.gain_at_zero - p.gain_at_infinity;
    const double lambda = a * std::exp(-p.slope_at_zero * x / a) + p.gain_at_infinity;
    EXPECT_NEAR(servo.gain(), lambda, 1e-9);
    // PBVS (cdMc): v_c = -lambda cdRc^T cd_t_c, w_c = -lambda theta u.
    const Eigen::Vector3d v = -lambda * cdMc.linear().transpose() * cdMc.translation();
    const Eigen::Vector3d w = -lambda * tu.angle() * tu.axis();
    EXPECT_LT((servo.cameraTwist().head<3>() - v).norm(), 1e-9) << i;
    EXPECT_LT((servo.cameraTwist().tail<3>() - w).norm(), 1e-9) << i;
  }
  // The gain is lambda_0 at zero error and tends to lambda_inf far away.
  const Eigen::Isometry3d I = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d far = I;
  far.translation() << 50.0, 0.0, 0.0;
  servo.twist(I, I);
  EXPECT_NEAR(servo.gain(), p.gain_at_zero, 1e-12);
  servo.twist(I, far);
  EXPECT_NEAR(servo.gain(), p.gain_at_infinity, 1e-9);
}

TEST(PbvsServo, IntegratedTwistConvergesWithTheCameraOnAStraightLine) {
  const Eigen::Isometry3d eTc = realmanTcpToCamera();
  std::mt19937 rng(5);
  for (int trial = 0; trial < 10; ++trial) {
    PbvsServo servo(eTc, PbvsServoParams{});
    Eigen::Isometry3d tcp = randomPose(rng, 1.0);
    Eigen::Isometry3d desired = tcp;
    desired.translation() += Eigen::Vector3d(0.6, -0.4, 0.3);
    desired.linear() = Eigen::AngleAxisd(1.2, Eigen::Vector3d(1, 2, -1).normalized()).toRotationMatrix() * tcp.linear();
    const Eigen::Vector3d c0 = (tcp * eTc).translation(), c1 = (desired * eTc).translation();
    const Eigen::Vector3d dir = (c1 - c0).normalized();
    double max_off_line = 0.0, max_overshoot = 0.0;
    const double dt = 0.002;
    for (int k = 0; k < 10000; ++k) {
      integrate(tcp, servo.twist(tcp, desired), dt);
      const Eigen::Vector3d c = (tcp * eTc).translation() - c0;
      max_off_line = std::max(max_off_line, (c - c.dot(dir) * dir).norm());
      max_overshoot = std::max(max_overshoot, c.dot(dir) - (c1 - c0).norm());
    }
    EXPECT_LT((tcp.translation() - desired.translation()).norm(), 1e-4) << trial;
    EXPECT_LT(angleBetween(tcp.linear(), desired.linear()), 1e-4) << trial;
    EXPECT_LT(max_off_line, 1e-3) << trial;  // Euler error only; ~0.1 m if the mount is ignored
    EXPECT_LT(max_overshoot, 1e-6) << trial;
  }
}

TEST(PbvsServo, TreatingTheCameraTwistAsTheTcpTwistWouldBendTheLine) {
  // Guards the line test above: the same integration with the camera twist applied to the TCP
  // as if it were the TCP's (mount ignored) leaves the line by centimetres.
  const Eigen::Isometry3d eTc = realmanTcpToCamera();
  PbvsServo servo(eTc, PbvsServoParams{});
  Eigen::Isometry3d tcp = Eigen::Isometry3d::Identity(), desired = Eigen::Isometry3d::Identity();
  desired.translation() << 0.6, -0.4, 0.3;
  desired.linear() = Eigen::AngleAxisd(1.2, Eigen::Vector3d(1, 2, -1).normalized()).toRotationMatrix();
  const Eigen::Vector3d c0 = (tcp * eTc).translation(), dir = ((desired * eTc).translation() - c0).normalized();
  double max_off_line = 0.0;
  for (int k = 0; k < 5000; ++k) {
    servo.twist(tcp, desired);
    const Eigen::Matrix3d R_wc = tcp.linear() * eTc.linear();
    Vector6d wrong;
    wrong << R_wc * servo.cameraTwist().head<3>(), R_wc * servo.cameraTwist().tail<3>();
    integrate(tcp, wrong, 0.002);
    const Eigen::Vector3d c = (tcp * eTc).translation() - c0;
    max_off_line = std::max(max_off_line, (c - c.dot(dir) * dir).norm());
  }
  EXPECT_GT(max_off_line, 0.01);
}

TEST(PbvsServo, SaturationKeepsTheTwistDirection) {
  PbvsServoParams p;
  p.max_linear = 0.3;
  p.max_angular = 0.5;
  PbvsServo servo(realmanTcpToCamera(), p);
  PbvsServo free(realmanTcpToCamera(), unsaturated());
  std::mt19937 rng(3);
  for (int i = 0; i < 100; ++i) {
    const Eigen::Isometry3d tcp = randomPose(rng, 3.0), desired = randomPose(rng, 3.0);
    const Vector6d nu = servo.twist(tcp, desired), ref = free.twist(tcp, desired);
    EXPECT_LE(nu.head<3>().norm(), p.max_linear + 1e-12);
    EXPECT_LE(nu.tail<3>().norm(), p.max_angular + 1e-12);
    EXPECT_LT((nu - servo.scale() * ref).norm(), 1e-9);
    EXPECT_GT(servo.scale(), 0.0);
    EXPECT_LE(servo.scale(), 1.0);
  }
}

TEST(PbvsServo, RollUnwindingTurnsTheLongWayNearTheRollLimit) {
  const Eigen::Isometry3d eTc = realmanTcpToCamera();
  PbvsServo servo(eTc, PbvsServoParams{});
  const Eigen::Isometry3d tcp = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d desired = tcp;
  desired.linear() = Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();  // +1 rad roll
  RollJoint roll;
  roll.lower = -2.0 * M_PI;
  roll.upper = 2.0 * M_PI;
  roll.q = 2.0 * M_PI - 0.5;  // +1 rad would pass the upper limit (margin 0.3)
  const double w_short = servo.twist(tcp, desired).tail<3>().dot(tcp.linear().col(2));
  const double w_long = servo.twist(tcp, desired, &roll).tail<3>().dot(tcp.linear().col(2));
  EXPECT_GT(w_short, 0.0);
  EXPECT_LT(w_long, 0.0);
  // Far from the limit the roll joint changes nothing.
  roll.q = 0.0;
  const Vector6d a = servo.twist(tcp, desired), b = servo.twist(tcp, desired, &roll);
  EXPECT_LT((a - b).norm(), 1e-12);
  // Closed loop with the roll joint following the TCP roll: converges without passing the limit.
  roll.q = 2.0 * M_PI - 0.5;
  Eigen::Isometry3d T = tcp;
  double q_max = roll.q;
  for (int k = 0; k < 8000; ++k) {
    const Vector6d nu = servo.twist(T, desired, &roll);
    roll.q += nu.tail<3>().dot(T.linear().col(2)) * 0.002;
    q_max = std::max(q_max, roll.q);
    integrate(T, nu, 0.002);
  }
  EXPECT_LT(angleBetween(T.linear(), desired.linear()), 1e-3);
  EXPECT_LE(q_max, 2.0 * M_PI - 0.5 + 1e-9);
  EXPECT_NEAR(roll.q, 2.0 * M_PI - 0.5 + 1.0 - 2.0 * M_PI, 1e-3);
}

TEST(PbvsServo, BadParametersAndInputsThrowWithTheClassName) {
  PbvsServoParams p;
  p.gain_at_infinity = 3.0;  // > gain_at_zero
  try {
    PbvsServo(Eigen::Isometry3d::Identity(), p);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("[PbvsServoParams]"), std::string::npos) << e.what();
  }
  Eigen::Isometry3d skew = Eigen::Isometry3d::Identity();
  skew.linear()(0, 1) = 0.5;
  EXPECT_THROW(PbvsServo(skew, PbvsServoParams{}), std::invalid_argument);
  PbvsServo servo(Eigen::Isometry3d::Identity(), PbvsServoParams{});
  Eigen::Isometry3d nan = Eigen::Isometry3d::Identity();
  nan.translation().x() = std::nan("");
  EXPECT_THROW(servo.twist(nan, Eigen::Isometry3d::Identity()), std::invalid_argument);
  const ConfigNode bad = ConfigNode::loadString("gain_at_zero: -1\n", "servo.yaml", "ControllerNode");
  EXPECT_THROW(loadPbvsServoParams(bad), std::invalid_argument);
  const ConfigNode good = ConfigNode::loadString("gain_at_zero: 3\ngain_at_infinity: 1\nslope_at_zero: 5\nmax_linear: 1\n",
                                                 "servo.yaml", "ControllerNode");
  const PbvsServoParams q = loadPbvsServoParams(good);
  EXPECT_EQ(q.gain_at_zero, 3.0);
  EXPECT_EQ(q.gain_at_infinity, 1.0);
  EXPECT_EQ(q.slope_at_zero, 5.0);
  EXPECT_EQ(q.max_linear, 1.0);
}

}  // namespace
}  // namespace ehc_control
