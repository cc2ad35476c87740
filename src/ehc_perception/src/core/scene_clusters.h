#pragma once
// The object clusters of a scene cloud (GraspGenerator::segmentScene, after the support plane is
// removed). Internal to ehc_perception_core (PCL types).
//
// 1. Connectivity: two points above the support are connected when closer than the larger of
//    their connection distances; a point's is cluster_tolerance, or, with a viewpoint,
//    cluster_spacing_factor x the cloud's angular point pitch x its range from the viewpoint
//    if that is larger (a far surface is sampled more sparsely; the pitch is the median over the
//    cloud of nearest-neighbour distance / range, so it needs no camera model).
// 2. Footprints: the connected parts are projected onto the support plane; two parts whose
//    footprints' convex hulls overlap or are within footprint_merge_gap are one object (a bowl's
//    near and far walls, whose floor the support removal takes; a part cut off by an occluding
//    edge), unless the joined footprint would be wider than max_object_extent. The merge gap
//    stays below the distance between neighbouring objects, whose footprints never overlap.
// 3. Parts of at least min_cluster_points points, largest first, at most max_objects.

#include "ehc_perception/convex_polygon.h"
#include "ehc_perception/grasp_generator.h"

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <vector>

namespace ehc_perception {
namespace detail {

/// Indices into `above` per object, largest first. `all`: every point of the view (the pitch's
/// sample); `viewpoint` may be null (fixed cluster_tolerance); `up`: the support's normal.
std::vector<std::vector<int>> clusterObjects(const pcl::PointCloud<pcl::PointXYZ>& above,
                                             const pcl::PointCloud<pcl::PointXYZ>& all,
                                             const Eigen::Vector3d* viewpoint, const Eigen::Vector3d& up,
                                             const GraspGeneratorConfig& cfg);

/// The cloud's angular point pitch seen from `viewpoint` (rad): the median over (at most 2000
/// evenly chosen) points of the distance to the nearest other point / the range; 0 for fewer
/// than two points.
double angularPitch(const pcl::PointCloud<pcl::PointXYZ>& cloud, const Eigen::Vector3d& viewpoint);


}  // namespace detail
}  // namespace ehc_perception
