#pragma once
// Joint-limit centring: a cost term of the EHC QP that keeps arm joints out of their
// velocity-damper zone before a damper pins them (the "joint-limit trap" of Exp-1: a joint held
// at joint_stop by its damper while the task pulls it further, the base unable to take over).
//
// Potential per joint and limit side, with margin m to the limit, influence rho and stop s:
//   u = clamp((rho - m) / (rho - s), 0, 1)   (0 at the influence border, 1 at the stop)
//   V = gain (rho - s) (u^3 / 3)              (C^1 at the border, gradient gain at the stop)
// dV/dq pushes the joint away from the limit, growing quadratically as it nears it. Added to
// the QP's linear cost (C_arm += dV/dq), minimising C^T qd moves q down the potential; the
// task (slack weight 1/|e|) outweighs it near arrival, the base takes over where it can.
// ROS-free.

#include <Eigen/Core>

namespace ehc_control {

struct JointLimitCentring {
  double gain = 0.0;       ///< dV/dq at the stop (cost units of C); 0 = off
  double influence = 0.9;  ///< rad: margin below which the potential is active
  double stop = 0.1;       ///< rad: margin at which it reaches `gain`

  /// V(q) for arm positions q within [lower, upper] (a margin beyond the stop counts as the stop).
  double potential(const Eigen::VectorXd& q, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper) const;
  /// dV/dq (size of q).
  Eigen::VectorXd gradient(const Eigen::VectorXd& q, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper) const;
  /// out += dV/dq, in place (the QP's cost vector; no allocation in the control cycle).
  void addGradient(const Eigen::VectorXd& q, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                   Eigen::Ref<Eigen::VectorXd> out) const;
};

}  // namespace ehc_control
