#pragma once
// The rotation helpers of the stack (ROS-free): orientations as they come in messages
// (geometry_msgs quaternions) with the one validity rule and the one quaternion -> yaw / rotation
// conversion, and the angle between two rotations.
//
// Validity rule: a quaternion is a rotation when its norm is finite and within
// kQuaternionNormTolerance of 1 (a unit quaternion after a float or text round trip passes; an
// all-zero or default-constructed one does not). Anything else is bad input: the conversions
// give NaN, which the cores reject (ControllerSupervisor, GraspSequencer), instead of a number
// the robot would move on (atan2 of a zero quaternion is 0).

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace ehc_control {

/// Largest | |q| - 1 | of a quaternion taken for a rotation.
constexpr double kQuaternionNormTolerance = 1e-3;

/// The validity rule above.
bool isRotationQuaternion(const Eigen::Quaterniond& q);

/// True if every entry of T is finite and its rotation part is a rotation (orthonormal, det +1,
/// within 1e-6).
bool isValidPose(const Eigen::Isometry3d& T);

/// Yaw (rad, (-pi, pi]) of the rotation `q` about the world z axis: the z angle of its
/// z-y-x Euler angles, atan2(2 (w z + x y), 1 - 2 (y^2 + z^2)). NaN unless isRotationQuaternion(q).
double yawFromQuaternion(const Eigen::Quaterniond& q);

/// The rotation matrix of `q` (normalised first). All NaN unless isRotationQuaternion(q).
Eigen::Matrix3d rotationFromQuaternion(const Eigen::Quaterniond& q);

/// Pose of a camera optical frame (z forward, x right, y down) at `eye` looking at `target`, its
/// x axis horizontal (not defined when looking straight up or down).
inline Eigen::Isometry3d lookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  const Eigen::Vector3d z = (target - eye).normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
  T.linear().col(0) = x;
  T.linear().col(1) = z.cross(x);
  T.linear().col(2) = z;
  T.translation() = eye;
  return T;
}

/// Angle (rad, in [0, pi]) of the rotation between two rotation matrices: acos of
/// (trace(a^T b) - 1) / 2, the cosine clamped to [-1, 1] against rounding. A NaN entry gives NaN.
inline double rotationAngle(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  const double c = std::clamp(((a.transpose() * b).trace() - 1.0) / 2.0, -1.0, 1.0);
  return std::acos(c);
}

}  // namespace ehc_control
