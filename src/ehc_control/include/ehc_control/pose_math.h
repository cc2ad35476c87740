#pragma once
// Orientations as they come in messages (geometry_msgs quaternions): the one validity rule and
// the one quaternion -> yaw / rotation conversion of the stack. ROS-free.
//
// Validity rule: a quaternion is a rotation when its norm is finite and within
// kQuaternionNormTolerance of 1 (a unit quaternion after a float or text round trip passes; an
// all-zero or default-constructed one does not). Anything else is bad input: the conversions
// give NaN, which the cores reject (ControllerSupervisor, GraspSequencer), instead of a number
// the robot would move on (atan2 of a zero quaternion is 0).

#include <Eigen/Geometry>

namespace ehc_control {

/// Largest | |q| - 1 | of a quaternion taken for a rotation.
constexpr double kQuaternionNormTolerance = 1e-3;

/// The validity rule above.
bool isRotationQuaternion(const Eigen::Quaterniond& q);

/// Yaw (rad, (-pi, pi]) of the rotation `q` about the world z axis: the z angle of its
/// z-y-x Euler angles, atan2(2 (w z + x y), 1 - 2 (y^2 + z^2)). NaN unless isRotationQuaternion(q).
double yawFromQuaternion(const Eigen::Quaterniond& q);

/// The rotation matrix of `q` (normalised first). All NaN unless isRotationQuaternion(q).
Eigen::Matrix3d rotationFromQuaternion(const Eigen::Quaterniond& q);

}  // namespace ehc_control
