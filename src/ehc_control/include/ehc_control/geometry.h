#pragma once
// Small rotation helpers shared by the packages (ROS-free, header only).

#include <Eigen/Core>

#include <algorithm>
#include <cmath>

namespace ehc_control {

/// Angle (rad, in [0, pi]) of the rotation between two rotation matrices: acos of
/// (trace(a^T b) - 1) / 2, the cosine clamped to [-1, 1] against rounding. A NaN entry gives NaN.
inline double rotationAngle(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  const double c = std::clamp(((a.transpose() * b).trace() - 1.0) / 2.0, -1.0, 1.0);
  return std::acos(c);
}

}  // namespace ehc_control
