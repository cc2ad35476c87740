#include "ehc_perception/octree_shape_distance.h"

#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/cylinder.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/geometry/shape/utility.h>
#include <fcl/math/bv/utility.h>
#include <fcl/narrowphase/detail/gjk_solver_libccd.h>
#include <fcl/narrowphase/distance.h>

#include <algorithm>
#include <cmath>

namespace ehc_perception {

namespace {
/// Distance from point `q` (the shape's frame) to the shape; 0 inside.
double pointDistance(const fcl::Box<double>& b, const Eigen::Vector3d& q) {
  return (q.cwiseAbs() - 0.5 * b.side).cwiseMax(0.0).norm();
}
double pointDistance(const fcl::Cylinder<double>& c, const Eigen::Vector3d& q) {
  return Eigen::Vector2d(std::max(0.0, q.head<2>().norm() - c.radius), std::max(0.0, std::abs(q.z()) - 0.5 * c.lz))
      .norm();
}
double pointDistance(const fcl::Sphere<double>& s, const Eigen::Vector3d& q) {
  return std::max(0.0, q.norm() - s.radius);
}

/// m: a node is pruned only when its lower bound exceeds the current minimum by this much. GJK
/// reports the distance of a point of the Minkowski difference, never below the true distance
/// (FCL's tolerance is 1e-6), so such a node's voxels could not lower the minimum.
constexpr double kPruneMargin = 1e-5;

/// octreeShapeDistance for one shape type (see the header).
template <class Shape>
class PrunedOcTreeDistance {
 public:
  PrunedOcTreeDistance(const fcl::OcTree<double>& tree, const Shape& shape, const fcl::Transform3<double>& tf,
                       const fcl::DistanceRequest<double>& request, fcl::DistanceResult<double>* result)
      : tree_(tree), shape_(shape), tf_(tf), tf_inv_(tf.inverse()), result_(result) {
    solver_.distance_tolerance = request.distance_tolerance;  // as fcl::distance sets up its solver
    fcl::computeBV(shape_, tf_, aabb_);
  }
  void run() {
    if (result_->min_distance <= 0.0 || !tree_.getRoot()) return;  // DistanceRequest::isSatisfied
    recurse(tree_.getRoot(), tree_.getRootBV());
  }

 private:
  using Node = fcl::OcTree<double>::OcTreeNode;
  /// True when the search is over (a penetration found), as FCL's.
  bool recurse(const Node* node, const fcl::AABB<double>& bv) {
    if (!tree_.nodeHasChildren(node)) {
      if (!tree_.isNodeOccupied(node)) return false;
      fcl::Box<double> box;
      fcl::Transform3<double> box_tf;
      fcl::constructBox(bv, I(), box, box_tf);
      double dist = 0.0;
      Eigen::Vector3d p1 = Eigen::Vector3d::Zero(), p2 = Eigen::Vector3d::Zero();
      solver_.shapeDistance(box, box_tf, shape_, tf_, &dist, &p1, &p2);
      result_->update(dist, &tree_, &shape_, static_cast<int>(node - tree_.getRoot()),
                      fcl::DistanceResult<double>::NONE, p1, p2);
      return result_->min_distance <= 0.0;
    }
    if (!tree_.isNodeOccupied(node)) return false;
    for (unsigned i = 0; i < 8; ++i) {
      if (!tree_.nodeChildExists(node, i)) continue;
      fcl::AABB<double> child_bv, loose;
      fcl::computeChildBV(bv, i, child_bv);
      fcl::convertBV(child_bv, I(), loose);
      if (!(loose.distance(aabb_) < result_->min_distance)) continue;  // FCL's test
      const double lower = pointDistance(shape_, tf_inv_ * child_bv.center()) - 0.5 * (child_bv.max_ - child_bv.min_).norm();
      if (lower >= result_->min_distance + kPruneMargin) continue;
      if (recurse(tree_.getNodeChild(node, i), child_bv)) return true;
    }
    return false;
  }
  static const fcl::Transform3<double>& I() {
    static const fcl::Transform3<double> identity = fcl::Transform3<double>::Identity();
    return identity;
  }

  const fcl::OcTree<double>& tree_;
  const Shape& shape_;
  const fcl::Transform3<double> tf_, tf_inv_;
  fcl::DistanceResult<double>* result_;
  fcl::detail::GJKSolver_libccd<double> solver_;
  fcl::AABB<double> aabb_;
};

}  // namespace

void octreeShapeDistance(const fcl::OcTree<double>& tree, const fcl::CollisionGeometry<double>& g,
                         const fcl::Transform3<double>& tf, const fcl::DistanceRequest<double>& request,
                         fcl::DistanceResult<double>* result) {
  const fcl::DistanceResult<double> start = *result;
  switch (g.getNodeType()) {
    case fcl::GEOM_BOX:
      PrunedOcTreeDistance(tree, static_cast<const fcl::Box<double>&>(g), tf, request, result).run();
      break;
    case fcl::GEOM_CYLINDER:
      PrunedOcTreeDistance(tree, static_cast<const fcl::Cylinder<double>&>(g), tf, request, result).run();
      break;
    case fcl::GEOM_SPHERE:
      PrunedOcTreeDistance(tree, static_cast<const fcl::Sphere<double>&>(g), tf, request, result).run();
      break;
    default: fcl::distance(&tree, fcl::Transform3<double>::Identity(), &g, tf, request, *result); return;
  }
  // A penetration with a signed distance asked: fcl::distance then replaces the GJK answer by the
  // deepest contact of a collision query; it is rare, so it is asked of FCL from the start.
  if (request.enable_signed_distance && result->min_distance < 0.0) {
    *result = start;
    fcl::distance(&tree, fcl::Transform3<double>::Identity(), &g, tf, request, *result);
  }
}

}  // namespace ehc_perception
