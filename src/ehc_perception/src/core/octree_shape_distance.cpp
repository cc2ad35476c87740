#include "ehc_perception/octree_shape_distance.h"

#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/cylinder.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/geometry/shape/utility.h>
#include <fcl/math/bv/utility.h>
#include <fcl/narrowphase/detail/gjk_solver_libccd.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/distance.h>

#include <octomap/OcTree.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace ehc_perception {

namespace {
/// Calls f(centre, edge, log-odds) for every occupied leaf of `t` (a pruned one included), and
/// does not descend into free subtrees: the map's inner nodes hold their children's maximum
/// (insertions update them), so a free inner node has no occupied voxel below it. The map is
/// mostly free space the rays cleared; a leaf iterator would visit all of it.
template <class F>
void forEachOccupiedLeaf(const octomap::OcTree& t, F&& f) {
  struct Item {
    const octomap::OcTreeNode* node;
    octomap::OcTreeKey key;
    unsigned depth;
  };
  if (!t.getRoot()) return;
  const auto centre = static_cast<octomap::key_type>(1u << (t.getTreeDepth() - 1));
  std::vector<Item> stack{{t.getRoot(), octomap::OcTreeKey(centre, centre, centre), 0}};
  while (!stack.empty()) {
    const Item it = stack.back();
    stack.pop_back();
    if (!t.isNodeOccupied(it.node)) continue;
    if (!t.nodeHasChildren(it.node)) {
      f(t.keyToCoord(it.key, it.depth), t.getNodeSize(it.depth), it.node->getLogOdds());
      continue;
    }
    const auto offset = static_cast<octomap::key_type>(centre >> (it.depth + 1));
    for (unsigned i = 0; i < 8; ++i) {
      if (!t.nodeChildExists(it.node, i)) continue;
      octomap::OcTreeKey child;
      octomap::computeChildKey(i, offset, it.key, child);
      stack.push_back({t.getNodeChild(it.node, i), child, it.depth + 1});
    }
  }
}

/// Calls f(i, j, k, centre) for every voxel of the leaf centred at `c` with edge `size` (i, j, k:
/// along x, y, z from the low corner). The one computation of a voxel's centre from its leaf.
template <class F>
void forEachVoxelOfLeaf(const octomap::point3d& c, double size, double res, F&& f) {
  const int n = std::max(1, static_cast<int>(std::lround(size / res)));
  const double first = -0.5 * (n - 1) * res;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k)
        f(i, j, k, Eigen::Vector3d(c.x() + first + i * res, c.y() + first + j * res, c.z() + first + k * res));
}

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
                       const fcl::DistanceRequest<double>& request, fcl::DistanceResult<double>* result,
                       const OcTreeExclusion* exclusion)
      : tree_(tree), shape_(shape), tf_(tf), tf_inv_(tf.inverse()), result_(result), ex_(exclusion) {
    solver_.distance_tolerance = request.distance_tolerance;  // as fcl::distance sets up its solver
    fcl::computeBV(shape_, tf_, aabb_);
  }
  void run() {
    if (result_->min_distance <= 0.0 || !tree_.getRoot()) return;  // DistanceRequest::isSatisfied
    const auto c = static_cast<octomap::key_type>(ex_ ? 1u << (ex_->octree.getTreeDepth() - 1) : 0u);
    recurse(tree_.getRoot(), tree_.getRootBV(), octomap::OcTreeKey(c, c, c), 0);
  }

 private:
  using Node = fcl::OcTree<double>::OcTreeNode;
  /// True when the search is over (a penetration found), as FCL's. `key`, `depth`: the node's
  /// (kept only with an exclusion).
  bool recurse(const Node* node, const fcl::AABB<double>& bv, const octomap::OcTreeKey& key, unsigned depth) {
    if (!tree_.nodeHasChildren(node)) {
      if (!tree_.isNodeOccupied(node)) return false;
      index_ = static_cast<int>(node - tree_.getRoot());
      if (ex_ && nearZone(key, depth)) return splitLeaf(bv, key, depth);
      return leaf(bv);
    }
    if (!tree_.isNodeOccupied(node)) return false;
    for (unsigned i = 0; i < 8; ++i) {
      // A free child (most of a map the rays cleared) holds no occupied voxel: FCL tests its
      // bounds and returns from it at once.
      if (!tree_.nodeChildExists(node, i) || !tree_.isNodeOccupied(tree_.getNodeChild(node, i))) continue;
      fcl::AABB<double> child_bv;
      fcl::computeChildBV(bv, i, child_bv);
      if (!admits(child_bv)) continue;
      octomap::OcTreeKey child_key = key;
      if (ex_) {
        const auto half = static_cast<octomap::key_type>(1u << (ex_->octree.getTreeDepth() - 1));
        octomap::computeChildKey(i, static_cast<octomap::key_type>(half >> (depth + 1)), key, child_key);
      }
      if (recurse(tree_.getNodeChild(node, i), child_bv, child_key, depth + 1)) return true;
    }
    return false;
  }
  /// Ours (usually the tighter, so first), then FCL's test (the shape's AABB against a cube around
  /// the node's bounding sphere): a node is entered only if both admit it.
  bool admits(const fcl::AABB<double>& bv) const {
    const double lower = pointDistance(shape_, tf_inv_ * bv.center()) - 0.5 * (bv.max_ - bv.min_).norm();
    if (!(lower < result_->min_distance + kPruneMargin)) return false;
    fcl::AABB<double> loose;
    fcl::convertBV(bv, I(), loose);
    return loose.distance(aabb_) < result_->min_distance;
  }
  /// An occupied voxel (or block of voxels) of the map: GJK and the result's update, as FCL.
  bool leaf(const fcl::AABB<double>& bv) {
    fcl::Box<double> box;
    fcl::Transform3<double> box_tf;
    fcl::constructBox(bv, I(), box, box_tf);
    double dist = 0.0;
    Eigen::Vector3d p1 = Eigen::Vector3d::Zero(), p2 = Eigen::Vector3d::Zero();
    solver_.shapeDistance(box, box_tf, shape_, tf_, &dist, &p1, &p2);
    result_->update(dist, &tree_, &shape_, index_, fcl::DistanceResult<double>::NONE, p1, p2);
    return result_->min_distance <= 0.0;
  }
  /// False if no voxel centre of the leaf (key, depth) can lie in a zone.
  bool nearZone(const octomap::OcTreeKey& key, unsigned depth) const {
    const octomap::point3d c = ex_->octree.keyToCoord(key, depth);
    const double reach = 0.5 * std::sqrt(3.0) * ex_->octree.getNodeSize(depth) + 1e-6;
    for (const ExclusionZone& z : ex_->zones)
      if ((Eigen::Vector3d(c.x(), c.y(), c.z()) - z.centre).norm() <= z.radius + reach) return true;
    return false;
  }
  /// A leaf that may straddle a zone: its voxels, each kept or excluded by its centre (computed as
  /// the copy of the map computes it), in the blocks the pruned copy would hold.
  bool splitLeaf(const fcl::AABB<double>& bv, const octomap::OcTreeKey& key, unsigned depth) {
    const octomap::OcTree& t = ex_->octree;
    const double size = t.getNodeSize(depth);
    n_ = std::max(1, static_cast<int>(std::lround(size / t.getResolution())));
    kept_.assign(static_cast<std::size_t>(n_ * n_ * n_), 0);
    forEachVoxelOfLeaf(t.keyToCoord(key, depth), size, t.getResolution(), [&](int i, int j, int k, const Eigen::Vector3d& p) {
      kept_[static_cast<std::size_t>((i * n_ + j) * n_ + k)] = !ExclusionZone::inAny(ex_->zones, p);
    });
    return block(bv, 0, 0, 0, n_);
  }
  /// Voxels [i, i + m) x [j, j + m) x [k, k + m) of the split leaf, as the copy holds them: one
  /// leaf if all are kept, nothing if none is, else its eight octants in FCL's child order.
  bool block(const fcl::AABB<double>& bv, int i, int j, int k, int m) {
    const int kept = keptIn(i, j, k, m);
    if (kept == 0) return false;
    if (kept == m * m * m) return leaf(bv);
    const int h = m / 2;
    for (unsigned o = 0; o < 8; ++o) {
      const int ci = i + ((o & 1) ? h : 0), cj = j + ((o & 2) ? h : 0), ck = k + ((o & 4) ? h : 0);
      if (keptIn(ci, cj, ck, h) == 0) continue;  // the copy has no such node
      fcl::AABB<double> child_bv;
      fcl::computeChildBV(bv, o, child_bv);
      if (!admits(child_bv)) continue;
      if (block(child_bv, ci, cj, ck, h)) return true;
    }
    return false;
  }
  int keptIn(int i, int j, int k, int m) const {
    int n = 0;
    for (int a = i; a < i + m; ++a)
      for (int b = j; b < j + m; ++b)
        for (int c = k; c < k + m; ++c) n += kept_[static_cast<std::size_t>((a * n_ + b) * n_ + c)];
    return n;
  }
  static const fcl::Transform3<double>& I() {
    static const fcl::Transform3<double> identity = fcl::Transform3<double>::Identity();
    return identity;
  }

  const fcl::OcTree<double>& tree_;
  const Shape& shape_;
  const fcl::Transform3<double> tf_, tf_inv_;
  fcl::DistanceResult<double>* result_;
  const OcTreeExclusion* ex_;
  fcl::detail::GJKSolver_libccd<double> solver_;
  fcl::AABB<double> aabb_;
  int index_ = 0;           ///< the leaf being tested (FCL's result index)
  int n_ = 0;               ///< voxels per edge of the split leaf
  std::vector<char> kept_;  ///< per voxel of the split leaf: outside every zone
};

}  // namespace

std::shared_ptr<const octomap::OcTree> copyWithoutZones(const octomap::OcTree& tree,
                                                        const std::vector<ExclusionZone>& zones) {
  auto copy = std::make_shared<octomap::OcTree>(tree.getResolution());
  copy->setOccupancyThres(tree.getOccupancyThres());
  copy->setClampingThresMin(tree.getClampingThresMin());
  copy->setClampingThresMax(tree.getClampingThresMax());
  forEachOccupiedLeaf(tree, [&](const octomap::point3d& c, double size, float value) {
    forEachVoxelOfLeaf(c, size, tree.getResolution(), [&](int, int, int, const Eigen::Vector3d& p) {
      if (!ExclusionZone::inAny(zones, p)) copy->setNodeValue(p.x(), p.y(), p.z(), value, /*lazy_eval=*/true);
    });
  });
  copy->updateInnerOccupancy();
  copy->prune();
  return copy;
}

namespace {
/// A penetration's signed distance as fcl::distance answers it for an octree (its workaround for
/// non-primitive shapes: the deepest contact of a collision query), without its assertion that
/// the collision query finds one. libfcl 0.7 is built with assertions, and a shape touching a
/// voxel within GJK's tolerance can have a negative distance and no collision: the process
/// aborted. No contact: touching (0); the distance query's nearest points stay.
void penetration(const fcl::OcTree<double>& tree, const fcl::CollisionGeometry<double>& g,
                 const fcl::Transform3<double>& tf, const fcl::DistanceRequest<double>& request,
                 fcl::DistanceResult<double>* result) {
  fcl::CollisionRequest<double> creq;
  creq.enable_contact = true;
  fcl::CollisionResult<double> cres;
  fcl::detail::GJKSolver_libccd<double> solver;  // as fcl::distance sets up the solver it collides with
  solver.distance_tolerance = request.distance_tolerance;
  fcl::collide(&tree, fcl::Transform3<double>::Identity(), &g, tf, &solver, creq, cres);
  std::size_t index = cres.numContacts();
  double depth = std::numeric_limits<double>::min();  // as FCL: a contact of depth 0 is no penetration
  for (std::size_t i = 0; i < cres.numContacts(); ++i)
    if (depth < cres.getContact(i).penetration_depth) {
      depth = cres.getContact(i).penetration_depth;
      index = i;
    }
  if (index == cres.numContacts()) {
    result->min_distance = 0.0;
    return;
  }
  result->min_distance = -depth;
  if (request.enable_nearest_points) result->nearest_points[0] = result->nearest_points[1] = cres.getContact(index).pos;
}
}  // namespace

void octreeShapeDistance(const fcl::OcTree<double>& tree, const fcl::CollisionGeometry<double>& g,
                         const fcl::Transform3<double>& tf, const fcl::DistanceRequest<double>& request,
                         fcl::DistanceResult<double>* result, const OcTreeExclusion* exclusion) {
  const fcl::OcTree<double>& map = exclusion ? exclusion->filtered() : tree;
  switch (g.getNodeType()) {
    case fcl::GEOM_BOX:
      PrunedOcTreeDistance(tree, static_cast<const fcl::Box<double>&>(g), tf, request, result, exclusion).run();
      break;
    case fcl::GEOM_CYLINDER:
      PrunedOcTreeDistance(tree, static_cast<const fcl::Cylinder<double>&>(g), tf, request, result, exclusion).run();
      break;
    case fcl::GEOM_SPHERE:
      PrunedOcTreeDistance(tree, static_cast<const fcl::Sphere<double>&>(g), tf, request, result, exclusion).run();
      break;
    default: {
      fcl::DistanceRequest<double> unsigned_request = request;
      unsigned_request.enable_signed_distance = false;
      fcl::distance(&map, fcl::Transform3<double>::Identity(), &g, tf, unsigned_request, *result);
      if (request.enable_signed_distance && result->min_distance <= 0.0) penetration(map, g, tf, request, result);
      return;
    }
  }
  // A penetration with a signed distance asked: the deepest contact of a collision query, as
  // fcl::distance answers it (rare).
  if (request.enable_signed_distance && result->min_distance < 0.0) penetration(map, g, tf, request, result);
}

}  // namespace ehc_perception
