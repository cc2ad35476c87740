#include "ehc_control/pose_servo.h"

#include "ehc_control/config_node.h"
#include "ehc_control/qp_controller.h"

namespace ehc_control {

void PoseServoParams::validate() const {
  requireRange("PoseServoParams", "gain", gain, 1e-3, 100.0);
  requireRange("PoseServoParams", "rotation_gain_ratio", rotation_gain_ratio, 1e-3, 100.0);
  requireRange("PoseServoParams", "max_linear", max_linear, 1e-3, 100.0);
  requireRange("PoseServoParams", "max_angular", max_angular, 1e-3, 100.0);
}

PoseServoParams loadPoseServoParams(const ConfigNode& n) {
  PoseServoParams p;
  p.gain = n.get("gain", p.gain);
  p.rotation_gain_ratio = n.get("rotation_gain_ratio", p.rotation_gain_ratio);
  p.max_linear = n.get("max_linear", p.max_linear);
  p.max_angular = n.get("max_angular", p.max_angular);
  p.validate();
  return p;
}

Vector6d proportionalPoseServo(const Eigen::Isometry3d& tcp, const Eigen::Isometry3d& target,
                               const PoseServoParams& p) {
  Vector6d nu = poseError(tcp, target);
  nu.head<3>() *= p.gain;
  nu.tail<3>() *= p.gain * p.rotation_gain_ratio;
  const double v = nu.head<3>().norm(), w = nu.tail<3>().norm();
  if (v > p.max_linear) nu.head<3>() *= p.max_linear / v;
  if (w > p.max_angular) nu.tail<3>() *= p.max_angular / w;
  return nu;
}

}  // namespace ehc_control
