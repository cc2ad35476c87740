#pragma once
// octreeShapeDistance: the distance between an OctoMap octree (FCL's wrapper) and a box,
// cylinder or sphere, as fcl::distance(tree, identity, shape, tf, request, result) computes it
// (FCL 0.7, OcTreeSolver::OcTreeShapeDistanceRecurse: the same nodes in the same order, the same
// AABB test, the same GJK call per occupied voxel, the same result update), with one more prune:
// a node whose centre lies farther from the shape than its half diagonal plus the current
// minimum holds no nearer voxel and is not entered. FCL's own test compares the shape's world
// AABB with a cube around the node's bounding sphere: for a slanted arm link it admits many
// voxels that GJK then rejects one by one. GJK's distance is never below the true one, so the
// skipped voxels could not have lowered the minimum: the result is FCL's, bit for bit
// (test_obstacle_distance_field compares them on random maps and poses). The one home of the
// obstacle field's distance query (ObstacleDistanceField::distances). Other geometry types go to
// fcl::distance unchanged, and so does a penetration when a signed distance is asked (FCL then
// answers with a collision query's deepest contact).

#include <fcl/geometry/octree/octree.h>
#include <fcl/narrowphase/distance_request.h>
#include <fcl/narrowphase/distance_result.h>

namespace ehc_perception {

/// `result->min_distance` on entry is the bound: only voxels nearer than it are reported (as
/// FCL, which prunes every node farther).
void octreeShapeDistance(const fcl::OcTree<double>& tree, const fcl::CollisionGeometry<double>& shape,
                         const fcl::Transform3<double>& tf, const fcl::DistanceRequest<double>& request,
                         fcl::DistanceResult<double>* result);

}  // namespace ehc_perception
