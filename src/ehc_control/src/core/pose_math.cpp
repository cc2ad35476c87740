#include "ehc_control/pose_math.h"

#include <cmath>
#include <limits>

namespace ehc_control {

bool isRotationQuaternion(const Eigen::Quaterniond& q) {
  const double n = q.norm();
  return std::isfinite(n) && std::abs(n - 1.0) <= kQuaternionNormTolerance;
}

double yawFromQuaternion(const Eigen::Quaterniond& q) {
  if (!isRotationQuaternion(q)) return std::numeric_limits<double>::quiet_NaN();
  return std::atan2(2.0 * (q.w() * q.z() + q.x() * q.y()), 1.0 - 2.0 * (q.y() * q.y() + q.z() * q.z()));
}

Eigen::Matrix3d rotationFromQuaternion(const Eigen::Quaterniond& q) {
  if (!isRotationQuaternion(q)) return Eigen::Matrix3d::Constant(std::numeric_limits<double>::quiet_NaN());
  return q.normalized().toRotationMatrix();
}

bool isValidPose(const Eigen::Isometry3d& T) {
  if (!T.matrix().allFinite()) return false;
  const Eigen::Matrix3d R = T.linear();
  return (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-6 &&
         std::abs(R.determinant() - 1.0) < 1e-6;
}

}  // namespace ehc_control
