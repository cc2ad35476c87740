#include "ehc_perception/object_extent.h"

#include "ehc_control/pose_math.h"

#include <algorithm>
#include <cmath>

namespace ehc_perception {

bool ObjectExtent::valid() const {
  return ehc_control::isValidPose(pose) && half_extents.allFinite() && half_extents.minCoeff() >= 0.0 &&
         half_extents.maxCoeff() < 1.0;
}

double ObjectExtent::distance(const Eigen::Vector3d& p) const {
  const Eigen::Vector3d q = (pose.linear().transpose() * (p - pose.translation())).cwiseAbs() - half_extents;
  return q.cwiseMax(0.0).norm();
}

bool ObjectExtent::holds(const ObjectExtent& other, double tolerance) const {
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d u((k & 1) ? 1.0 : -1.0, (k & 2) ? 1.0 : -1.0, (k & 4) ? 1.0 : -1.0);
    if (distance(other.pose * u.cwiseProduct(other.half_extents)) > tolerance) return false;
  }
  return true;
}

std::optional<ObjectExtent> clusterExtent(const std::vector<Eigen::Vector3f>& points, const Eigen::Vector3d& viewpoint,
                                          const Eigen::Vector3d& up_in, const std::optional<double>& support_height) {
  if (points.size() < 3 || !up_in.allFinite() || up_in.norm() < 1e-9 || !viewpoint.allFinite()) return std::nullopt;
  const Eigen::Vector3d up = up_in.normalized();
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& pf : points) centroid += pf.cast<double>();
  centroid /= static_cast<double>(points.size());
  Eigen::Vector3d x = centroid - viewpoint;  // the view's direction, across `up`
  x -= x.dot(up) * up;
  if (x.norm() < 1e-6) x = up.unitOrthogonal();  // seen from straight above: any
  x.normalize();
  Eigen::Matrix3d R;
  R << x, up.cross(x), up;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e30), hi = Eigen::Vector3d::Constant(-1e30);
  for (const auto& pf : points) {
    const Eigen::Vector3d q = R.transpose() * pf.cast<double>();
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  hi.x() = std::max(hi.x(), lo.x() + (hi.y() - lo.y()));  // the hidden far side
  if (support_height && std::isfinite(*support_height)) lo.z() = std::min(lo.z(), *support_height);
  ObjectExtent e;
  e.pose.linear() = R;
  e.pose.translation() = R * (0.5 * (lo + hi));
  e.half_extents = 0.5 * (hi - lo);
  if (!e.valid()) return std::nullopt;
  return e;
}

}  // namespace ehc_perception
