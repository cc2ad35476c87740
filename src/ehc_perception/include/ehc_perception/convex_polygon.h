#pragma once
// Convex polygons in the plane (ROS-free, Eigen only): the footprints of the scene's objects on
// their support (scene clustering) and the support's own footprint (the grasp choice's reach
// check). Polygons are counter-clockwise with no repeated end point.

#include <Eigen/Core>

#include <vector>

namespace ehc_perception {

/// z of (a - o) x (b - o): > 0 when o, a, b turn counter-clockwise.
double cross2d(const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b);
/// Convex hull (Andrew's monotone chain; non-finite points dropped; a point or a segment for
/// degenerate input).
std::vector<Eigen::Vector2d> convexHull2d(std::vector<Eigen::Vector2d> pts);
/// Inside or on a convex polygon of at least three vertices.
bool insideConvex(const Eigen::Vector2d& p, const std::vector<Eigen::Vector2d>& poly);
/// Distance from p to the segment a-b.
double pointSegmentDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b);
/// Distance between two convex polygons (or points, segments), 0 when they overlap; infinity
/// when either is empty.
double hullDistance(const std::vector<Eigen::Vector2d>& a, const std::vector<Eigen::Vector2d>& b);
/// Signed area (> 0 counter-clockwise).
double polygonArea(const std::vector<Eigen::Vector2d>& poly);

}  // namespace ehc_perception
