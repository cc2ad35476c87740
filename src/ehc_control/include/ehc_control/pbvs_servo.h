#pragma once
// PbvsServo: eye-in-hand position-based visual servo with ViSP (DESIGN.md section 8).
// The task is the camera's: vpServo EYEINHAND_CAMERA with the features vpFeatureTranslation
// (cdMc) and vpFeatureThetaU (cdRc) of the current camera frame c in the desired camera frame
// cd, and an adaptive gain (vpAdaptiveGain). The desired camera pose is the desired TCP pose
// composed with the camera mount (tcp_T_camera, from the URDF): w_T_cd = w_T_e* e_T_c.
// The camera twist v_c = [v; w] (camera frame, at the camera origin) that ViSP computes is
// converted to the TCP twist the QP tracks: nu_e(TCP frame) = eVc v_c (vpVelocityTwistMatrix of
// e_T_c), then rotated into the world: nu_e = [w_R_e v_e; w_R_e w_e].
// With cdMc features the camera origin moves on a straight line to its desired position and
// the rotation follows the geodesic; the output is scaled as a whole (direction kept) to the
// linear / angular limits. ROS-free. Not thread-safe; not copyable (vpServo keeps pointers to
// the features), movable.

#include "ehc_control/pose_servo.h"
#include "ehc_control/qp_controller.h"

#include <Eigen/Geometry>

#include <memory>
#include <string>

namespace ehc_common {
class ConfigNode;
}  // namespace ehc_common

namespace ehc_control {

struct PbvsServoParams {
  /// vpAdaptiveGain lambda(x) = (l0 - linf) exp(-l0' x / (l0 - linf)) + linf, with (as vpServo
  /// does) x = |L^+ e|_inf = max(|cdRc^T cd_t_c|_inf in m, |theta u|_inf in rad).
  double gain_at_zero = 2.0;      ///< l0, 1/s: gain close to the desired pose
  double gain_at_infinity = 0.5;  ///< linf, 1/s: gain far from it
  double slope_at_zero = 4.0;     ///< l0', 1/s
  double max_linear = 2.0;        ///< m/s, |v| of the TCP twist (whole twist scaled down)
  double max_angular = 2.0;       ///< rad/s, |w| of the TCP twist (whole twist scaled down)
  bool unwind_roll = true;        ///< roll the long way round when the short way passes the roll joint's limit
  void validate() const;          ///< throws "[PbvsServoParams] ..."
  std::string summary() const;
};
/// Reads the `servo` section (shared fields max_linear, max_angular, unwind_roll).
PbvsServoParams loadPbvsServoParams(const ehc_common::ConfigNode& node);

class PbvsServo {
 public:
  /// tcp_T_camera: pose of the camera optical frame in the TCP frame (rigid on the hand).
  PbvsServo(const Eigen::Isometry3d& tcp_T_camera, const PbvsServoParams& params);
  ~PbvsServo();
  PbvsServo(PbvsServo&&) noexcept;
  PbvsServo& operator=(PbvsServo&&) noexcept;

  /// TCP twist [v; w] (world frame, at the TCP origin) driving the TCP from `tcp` to `desired`
  /// (both world poses). With `roll` (and unwind_roll), the rotation about the TCP z axis takes
  /// the direction that keeps the roll joint inside its range. Throws on non-finite input.
  Vector6d twist(const Eigen::Isometry3d& tcp, const Eigen::Isometry3d& desired,
                 const RollJoint* roll = nullptr);

  /// Of the last twist(): camera twist [v; w] in the camera frame as computed by vpServo
  /// (before scaling), the adaptive gain used, the task error |e| and the scale applied (<= 1).
  const Vector6d& cameraTwist() const { return camera_twist_; }
  double gain() const { return gain_; }
  double errorNorm() const { return error_norm_; }
  double scale() const { return scale_; }

  const PbvsServoParams& params() const { return params_; }
  const Eigen::Isometry3d& tcpToCamera() const { return tcp_T_camera_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  PbvsServoParams params_;
  Eigen::Isometry3d tcp_T_camera_;
  Vector6d camera_twist_ = Vector6d::Zero();
  double gain_ = 0.0, error_norm_ = 0.0, scale_ = 1.0;
};

}  // namespace ehc_control
