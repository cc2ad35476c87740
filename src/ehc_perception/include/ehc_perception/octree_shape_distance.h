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
// (test_obstacle_distance_field compares them on random maps and poses).
//
// Exclusion zones (OcTreeExclusion): the voxels whose centre lies in a zone are left out as if
// the query ran on the pruned copy of the map without them (every occupied voxel outside the
// zones, set one by one, then pruned), without building that copy: a leaf that straddles a zone
// is split into the blocks the copy would hold. On a map OctoMap keeps pruned (every map built
// by point-cloud insertion) this is the copy's answer, bit for bit (tested).
//
// Other geometry types go to fcl::distance (unsigned). A penetration when a signed distance is
// asked is answered as fcl::distance answers it for an octree, with a collision query's deepest
// contact, but made here: FCL asserts that query finds a contact, and a shape touching a voxel
// within GJK's tolerance (a negative distance, no collision) aborted the process; that is
// touching, distance 0. The one home of the obstacle field's distance query
// (ObstacleDistanceField::distances).

#include "ehc_perception/obstacle_distance_field.h"  // ExclusionZone

#include <fcl/geometry/octree/octree.h>
#include <fcl/narrowphase/distance_request.h>
#include <fcl/narrowphase/distance_result.h>

#include <functional>
#include <memory>
#include <vector>

namespace ehc_perception {

/// Voxels the distance query ignores.
struct OcTreeExclusion {
  const octomap::OcTree& octree;            ///< the tree the queried fcl::OcTree wraps
  const std::vector<ExclusionZone>& zones;  ///< voxels whose centre lies in one are ignored
  /// The map without those voxels, for the queries handed to fcl::distance (see above).
  std::function<const fcl::OcTree<double>&()> filtered;
};

/// The copy of `tree` without the voxels whose centre lies in one of `zones`: every occupied voxel
/// outside them set one by one (a pruned leaf voxel by voxel), then pruned. Only the occupied
/// voxels are copied (all a distance query reads).
std::shared_ptr<const octomap::OcTree> copyWithoutZones(const octomap::OcTree& tree,
                                                        const std::vector<ExclusionZone>& zones);

/// `result->min_distance` on entry is the bound: only voxels nearer than it are reported (as
/// FCL, which prunes every node farther). `exclusion`: nullptr = none.
void octreeShapeDistance(const fcl::OcTree<double>& tree, const fcl::CollisionGeometry<double>& shape,
                         const fcl::Transform3<double>& tf, const fcl::DistanceRequest<double>& request,
                         fcl::DistanceResult<double>* result, const OcTreeExclusion* exclusion = nullptr);

}  // namespace ehc_perception
