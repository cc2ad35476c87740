#pragma once
// MPBS: monitoring-position-based servoing (paper section III-C, eq. 14; DESIGN.md section 8).
//
//   T* = sig(omega) T_grasp (+) (1 - sig(omega)) T_monitor
//
// interpolated on SE(3): translation lerp, rotation slerp (never a matrix average).
// T_monitor has the grasp position and the orientation that makes the camera look at the
// target centre from where the TCP is now: among all such orientations, the one closest to the
// grasp orientation (the grasp orientation turned by the smallest rotation that puts the
// target on the optical axis), so the roll is the grasp's and changes continuously. Far from
// the target (sig -> 0) the servo turns the camera towards it; close (sig -> 1) the TCP takes
// the grasp orientation. With MPBS disabled T* = T_grasp (plain PBVS, the ablation).
// ROS-free.

#include "ehc_control/pbvs_servo.h"

#include <Eigen/Geometry>

#include <string>

namespace ehc_common {
class ConfigNode;
}  // namespace ehc_common

namespace ehc_control {

struct MpbsParams {
  bool enabled = true;                ///< false: plain PBVS to the grasp pose
  /// m: when the target centre is closer to the TCP than this the camera cannot usefully look
  /// at it; T_monitor fades (slerp) from the look-at orientation at 2x this distance to the
  /// grasp orientation at 1x. Must exceed the camera's offset from the TCP.
  double min_monitor_distance = 0.15;
  /// Target centre (what the camera watches and TfM counts) in the target (grasp) frame.
  Eigen::Vector3d target_centre = Eigen::Vector3d::Zero();
  void validate() const;              ///< throws "[MpbsParams] ..."
  std::string summary() const;
};
MpbsParams loadMpbsParams(const ehc_common::ConfigNode& node);

/// SE(3) interpolation: translation (1 - s) a.t + s b.t, rotation slerp(a.R, b.R, s) along the
/// shorter arc. s is clamped to [0, 1]. Throws "[Mpbs] ..." on non-finite input.
Eigen::Isometry3d interpolatePose(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, double s);

/// T_monitor: position of `grasp`, orientation closest to the grasp's whose camera optical axis
/// (z of tcp_T_camera) passes through `target_centre` when the TCP is at `tcp_position`.
/// Within min_monitor_distance of the target the grasp orientation (see MpbsParams).
Eigen::Isometry3d monitoringPose(const Eigen::Vector3d& tcp_position, const Eigen::Isometry3d& grasp,
                                 const Eigen::Vector3d& target_centre, const Eigen::Isometry3d& tcp_T_camera,
                                 double min_monitor_distance);

/// Eq. 14: interpolatePose(T_monitor, T_grasp, sig).
Eigen::Isometry3d mpbsDesiredPose(double sig, const Eigen::Isometry3d& grasp, const Eigen::Isometry3d& monitor);

struct MpbsOutput {
  Vector6d twist = Vector6d::Zero();                       ///< TCP twist [v; w], world
  Eigen::Isometry3d desired = Eigen::Isometry3d::Identity();  ///< T* served this cycle
  Eigen::Isometry3d monitor = Eigen::Isometry3d::Identity();  ///< T_monitor (= grasp when disabled)
  double sig = 1.0;                                         ///< blend used (1 when disabled)
};

/// PBVS (ViSP) towards the MPBS desired pose.
class MpbsServo {
 public:
  MpbsServo(const Eigen::Isometry3d& tcp_T_camera, const PbvsServoParams& pbvs, const MpbsParams& mpbs);

  /// One cycle: TCP pose, target (grasp) pose, sig(omega) of this cycle, optional roll joint,
  /// optional target centre (world; default targetCentre(grasp)) for when the goal is not at
  /// the object, e.g. a pre-grasp pose.
  MpbsOutput compute(const Eigen::Isometry3d& tcp, const Eigen::Isometry3d& grasp, double sig,
                     const RollJoint* roll = nullptr, const Eigen::Vector3d* centre = nullptr);
  /// World position of the target centre for a target pose.
  Eigen::Vector3d targetCentre(const Eigen::Isometry3d& target) const { return target * params_.target_centre; }

  const MpbsParams& params() const { return params_; }
  PbvsServo& pbvs() { return pbvs_; }

 private:
  PbvsServo pbvs_;
  MpbsParams params_;
};

}  // namespace ehc_control
