#include "ehc_control/pose_servo.h"

#include "ehc_common/config_node.h"
#include "ehc_control/qp_controller.h"
#include "ehc_control/whole_body_model.h"

using ehc_common::requireRange;

namespace ehc_control {

void PoseServoParams::validate() const {
  requireRange("PoseServoParams", "gain", gain, 1e-3, 100.0);
  requireRange("PoseServoParams", "rotation_gain_ratio", rotation_gain_ratio, 1e-3, 100.0);
  requireRange("PoseServoParams", "max_linear", max_linear, 1e-3, 100.0);
  requireRange("PoseServoParams", "max_angular", max_angular, 1e-3, 100.0);
}

PoseServoParams loadPoseServoParams(const ehc_common::ConfigNode& n) {
  PoseServoParams p;
  p.gain = n.get("gain", p.gain);
  p.rotation_gain_ratio = n.get("rotation_gain_ratio", p.rotation_gain_ratio);
  p.max_linear = n.get("max_linear", p.max_linear);
  p.max_angular = n.get("max_angular", p.max_angular);
  p.unwind_roll = n.get("unwind_roll", p.unwind_roll);
  n.validate(p);  // errors name the file and the section
  return p;
}

namespace {

/// Swing-twist split of the rotation error R* R^T about the TCP z axis (R_err = R_swing R_twist)
/// and the twist direction that keeps the roll joint inside its range: psi_cmd = psi, or psi
/// -/+ 2 pi (the long way round) when the short way would pass the joint's limit.
struct RollSplit {
  Eigen::Vector3d axis;      ///< TCP z axis, world
  Eigen::Quaterniond swing;  ///< rotation error without the twist about `axis`
  double psi = 0.0;          ///< twist angle in (-pi, pi]
  double psi_cmd = 0.0;      ///< twist to command
};

RollSplit splitRoll(const Eigen::Isometry3d& tcp, const Eigen::Isometry3d& target, const RollJoint& roll) {
  RollSplit r;
  r.axis = tcp.linear().col(2);
  Eigen::Quaterniond qe(Eigen::Matrix3d(target.linear() * tcp.linear().transpose()));
  if (qe.w() < 0) qe.coeffs() *= -1.0;
  r.psi = 2.0 * std::atan2(qe.vec().dot(r.axis), qe.w());
  const double lo = roll.lower + roll.margin, hi = roll.upper - roll.margin;
  r.psi_cmd = r.psi;
  if (roll.q + r.psi > hi && roll.q + r.psi - 2.0 * M_PI >= lo) r.psi_cmd = r.psi - 2.0 * M_PI;
  else if (roll.q + r.psi < lo && roll.q + r.psi + 2.0 * M_PI <= hi) r.psi_cmd = r.psi + 2.0 * M_PI;
  r.swing = qe * Eigen::Quaterniond(Eigen::AngleAxisd(r.psi, r.axis)).inverse();
  return r;
}

}  // namespace

int findRollJoint(const WholeBodyModel& model) {
  const RobotConfig& rc = model.config();
  const Matrix6Xd J = model.armJacobian(rc.arm_ready, rc.tcp_frame);
  const Eigen::Vector3d z = model.linkPoseInBase(rc.arm_ready, rc.tcp_frame).linear().col(2);
  for (int i = model.nArm() - 1; i >= 0; --i) {
    const Eigen::Vector3d axis = J.block<3, 1>(3, i);
    if (axis.norm() > 0.5 && axis.normalized().dot(z) > 1.0 - 1e-6 && J.block<3, 1>(0, i).norm() < 1e-6) return i;
  }
  return -1;
}

Vector6d proportionalPoseServo(const Eigen::Isometry3d& tcp, const Eigen::Isometry3d& target,
                               const PoseServoParams& p, const RollJoint* roll) {
  Vector6d nu = poseError(tcp, target);
  if (roll && p.unwind_roll) {
    const RollSplit r = splitRoll(tcp, target, *roll);
    if (r.psi_cmd != r.psi) {
      const Eigen::AngleAxisd swing(r.swing);
      nu.tail<3>() = swing.axis() * swing.angle() + r.psi_cmd * r.axis;
    }
  }
  nu.head<3>() *= p.gain;
  nu.tail<3>() *= p.gain * p.rotation_gain_ratio;
  const double v = nu.head<3>().norm(), w = nu.tail<3>().norm();
  if (v > p.max_linear) nu.head<3>() *= p.max_linear / v;
  if (w > p.max_angular) nu.tail<3>() *= p.max_angular / w;
  return nu;
}

Eigen::Isometry3d rollUnwoundTarget(const Eigen::Isometry3d& tcp, const Eigen::Isometry3d& target,
                                    const RollJoint& roll) {
  const RollSplit r = splitRoll(tcp, target, roll);
  if (r.psi_cmd == r.psi) return target;
  Eigen::Isometry3d waypoint = target;
  waypoint.linear() =
      (r.swing * Eigen::Quaterniond(Eigen::AngleAxisd(0.5 * r.psi_cmd, r.axis))).toRotationMatrix() * tcp.linear();
  return waypoint;
}

}  // namespace ehc_control
