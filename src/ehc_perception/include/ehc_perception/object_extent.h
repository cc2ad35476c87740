#pragma once
// ObjectExtent: an object's box in the world, and the box of an object cluster seen in one view
// (clusterExtent). The grasp sequencer leaves this box (grown by a margin) out of the obstacle
// map while the hand touches the object; a tag object's box comes from its configured size, a
// target without a tag's from its cluster (the in-process pipeline and ehc_grasp_node alike,
// cloudTargetExtent in grasp_generator.h). ROS-free, Eigen only.

#include <Eigen/Geometry>

#include <optional>
#include <vector>

namespace ehc_perception {

/// An object's extent: a box (world) with its centre and axes in `pose`.
struct ObjectExtent {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  Eigen::Vector3d half_extents = Eigen::Vector3d::Zero();  ///< m, >= 0
  bool valid() const;  ///< finite, a rotation, half extents >= 0 and below 1 m
  double distance(const Eigen::Vector3d& p) const;  ///< m from p to the box (0 inside)
  /// Whether every corner of `other` lies within `tolerance` (m) of this box.
  bool holds(const ObjectExtent& other, double tolerance) const;
};

/// Extent of an object cluster (world points, one view from `viewpoint`) standing on a support
/// with normal `up`: a box with one axis along `up` from the lowest to the highest point
/// (`support_height`: down to the support, height along `up` of the support plane, when given),
/// one along the view's horizontal direction to the points' centroid and one across it. The
/// view hides the far side: the box reaches back from the nearest point at least as far as the
/// points spread across the view (a round or square body is as deep as it is wide), farther if
/// the points do. nullopt for fewer than 3 points.
std::optional<ObjectExtent> clusterExtent(const std::vector<Eigen::Vector3f>& points, const Eigen::Vector3d& viewpoint,
                                          const Eigen::Vector3d& up, const std::optional<double>& support_height);

}  // namespace ehc_perception
