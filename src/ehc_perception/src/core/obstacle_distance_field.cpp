#include "ehc_perception/obstacle_distance_field.h"

#include "ehc_common/config_node.h"
#include "ehc_control/fcl_geometry.h"
#include "ehc_control/whole_body_model.h"
#include "ehc_perception/octree_shape_distance.h"

#include <fcl/geometry/octree/octree.h>
#include <fcl/narrowphase/distance.h>
#include <octomap/OcTree.h>

#include <cmath>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>

using ehc_common::requireRange;

namespace ehc_perception {

using ehc_control::CollisionShape;

namespace {
const char* kOwner = "ObstacleDistanceField";

[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument(std::string("[ObstacleDistanceField] ") + what);
}
}  // namespace

// ------------------------------------------------------------------------------ config

void ObstacleMapConfig::validate() const {
  requireRange(kOwner, "resolution", resolution, 0.005, 0.2);
  requireRange(kOwner, "max_range", max_range, 0.1, 50.0);
  requireRange(kOwner, "prob_hit", prob_hit, 0.5001, 0.9999);
  requireRange(kOwner, "prob_miss", prob_miss, 0.0001, 0.4999);
  requireRange(kOwner, "clamp_min", clamp_min, 0.0001, 0.4999);
  requireRange(kOwner, "clamp_max", clamp_max, 0.5001, 0.9999);
  requireRange(kOwner, "occupancy_threshold", occupancy_threshold, clamp_min,
                            clamp_max);
  requireRange(kOwner, "min_height", min_height, -10.0, 10.0);
  requireRange(kOwner, "self_filter_padding", self_filter_padding, 0.0, 0.5);
  requireRange(kOwner, "influence_distance", influence_distance, resolution, 5.0);
}

std::string ObstacleMapConfig::summary() const {
  std::ostringstream os;
  os << "obstacle map: OctoMap resolution " << resolution << " m, max range " << max_range
     << " m, hit/miss " << prob_hit << "/" << prob_miss << ", clamp [" << clamp_min << ", "
     << clamp_max << "], threshold " << occupancy_threshold << ", min height " << min_height
     << " m, self filter " << self_filter_padding << " m, influence " << influence_distance
     << " m, " << (links.empty() ? std::string("the robot's checked links") : std::to_string(links.size()) + " links");
  return os.str();
}

ObstacleMapConfig loadObstacleMapConfig(const ehc_common::ConfigNode& n) {
  ObstacleMapConfig c;
  c.resolution = n.get("resolution", c.resolution);
  c.max_range = n.get("max_range", c.max_range);
  c.prob_hit = n.get("prob_hit", c.prob_hit);
  c.prob_miss = n.get("prob_miss", c.prob_miss);
  c.clamp_min = n.get("clamp_min", c.clamp_min);
  c.clamp_max = n.get("clamp_max", c.clamp_max);
  c.occupancy_threshold = n.get("occupancy_threshold", c.occupancy_threshold);
  c.min_height = n.get("min_height", c.min_height);
  c.self_filter_padding = n.get("self_filter_padding", c.self_filter_padding);
  c.influence_distance = n.get("influence_distance", c.influence_distance);
  if (n.has("links"))  // robot-specific: lives in robot.yaml now
    n.fail("links", "names robot links: move it to the robot's robot.yaml as robot.collision.checked_links");
  n.validate(c);
  return c;
}

// ------------------------------------------------------------------------------ field


namespace {
/// m: the seeded bound sits this far above the distance to the remembered voxel, well above
/// the tolerance of FCL's GJK (1e-6), so that the voxel itself passes the bound.
constexpr double kSeedMargin = 1e-4;
}  // namespace

struct ObstacleDistanceField::Impl {
  std::shared_ptr<octomap::OcTree> tree;
  std::shared_ptr<fcl::OcTree<double>> fcl_tree;
  std::vector<std::shared_ptr<fcl::CollisionGeometry<double>>> geoms;  // per shape
  struct ShapeIndex {
    std::size_t link, shape;  // robot.links()[link].shapes[shape]
  };
  std::vector<ShapeIndex> shapes;  // every shape of every link, in order
  /// Per shape: a voxel inside the obstacle its last query found (the queries follow the robot
  /// at the publish rate, so that voxel is near the next answer). See seedBound.
  std::vector<std::optional<octomap::OcTreeKey>> last_voxel;
  // The exclusion zones the queries use (active_zones): the zones given, taken over when the map
  // changed or a zone moved (see zonesMoved); the queries leave out the voxels in them
  // (OcTreeExclusion) and only FCL's fallbacks read the map's copy without them (filtered).
  std::vector<ExclusionZone> active_zones;
  bool zones_taken = false;  ///< active_zones were taken at least once
  bool map_changed = true;   ///< since active_zones were taken
  std::uint64_t revision = 0;  ///< counts the map's changes (ObstacleDistanceField::revision)
  void changed() {
    map_changed = true;
    ++revision;
  }
  std::shared_ptr<fcl::OcTree<double>> filtered_tree;  ///< built from active_zones when first asked
  bool filtered_stale = true;

  /// A zone carried by the hand is re-sent every control cycle with sub-millimetre motion; the
  /// queries keep the zones they have unless the map changed, or a zone moved or grew by a
  /// quarter voxel since they were taken (or the count changed).
  bool zonesMoved(const std::vector<ExclusionZone>& zones) const {
    if (zones.size() != active_zones.size()) return true;
    const double tol = 0.25 * tree->getResolution();
    for (std::size_t i = 0; i < zones.size(); ++i)
      if ((zones[i].centre - active_zones[i].centre).norm() >= tol ||
          std::abs(zones[i].radius - active_zones[i].radius) >= tol)
        return true;
    return false;
  }
  /// The zones the queries use given the field's `zones` (empty: none).
  const std::vector<ExclusionZone>& activeZones(const std::vector<ExclusionZone>& zones) {
    if (zones.empty()) return zones;
    if (map_changed || !zones_taken || zonesMoved(zones)) {
      active_zones = zones;
      zones_taken = true;
      map_changed = false;
      filtered_stale = true;
    }
    return active_zones;
  }

  void reset(const ObstacleMapConfig& c) {
    tree = std::make_shared<octomap::OcTree>(c.resolution);
    tree->setProbHit(c.prob_hit);
    tree->setProbMiss(c.prob_miss);
    tree->setClampingThresMin(c.clamp_min);
    tree->setClampingThresMax(c.clamp_max);
    tree->setOccupancyThres(c.occupancy_threshold);
    // FCL reads the occupancy threshold from the tree at construction.
    fcl_tree = std::make_shared<fcl::OcTree<double>>(
        std::static_pointer_cast<const octomap::OcTree>(tree));
    changed();
  }

  /// An upper bound on the distance of shape `i` (posed at `tf`) to the obstacles of `octree`:
  /// its distance to the voxel its last query ended at, if that is still occupied (+inf
  /// otherwise). FCL's octree traversal prunes every node farther than its starting bound, so
  /// starting from this bound instead of the influence distance visits far fewer voxels and finds
  /// the same minimum (every voxel nearer than the bound is still visited).
  double seedBound(std::size_t i, const std::vector<ExclusionZone>& zones, const fcl::Transform3<double>& tf) const {
    const octomap::OcTree& octree = *tree;
    if (!last_voxel[i]) return std::numeric_limits<double>::infinity();
    const octomap::OcTreeNode* node = octree.search(*last_voxel[i]);
    if (!node || !octree.isNodeOccupied(node)) return std::numeric_limits<double>::infinity();
    const octomap::point3d c = octree.keyToCoord(*last_voxel[i]);
    if (ExclusionZone::inAny(zones, Eigen::Vector3d(c.x(), c.y(), c.z()))) return std::numeric_limits<double>::infinity();
    const double r = octree.getResolution();
    const fcl::Box<double> voxel(r, r, r);
    fcl::Transform3<double> at = fcl::Transform3<double>::Identity();
    at.translation() = Eigen::Vector3d(c.x(), c.y(), c.z());
    fcl::DistanceRequest<double> req;
    fcl::DistanceResult<double> res;
    fcl::distance(&voxel, at, geoms[i].get(), tf, req, res);
    return res.min_distance > 0.0 ? res.min_distance : std::numeric_limits<double>::infinity();
  }

  /// Remembers the voxel behind obstacle point `p` (on the voxel's face, `normal` pointing away
  /// from it) for seedBound.
  void rememberVoxel(std::size_t i, const Eigen::Vector3d& p, const Eigen::Vector3d& normal) {
    const Eigen::Vector3d inside = p - 0.25 * tree->getResolution() * normal;
    octomap::OcTreeKey key;
    if (tree->coordToKeyChecked(inside.x(), inside.y(), inside.z(), key)) last_voxel[i] = key;
    else last_voxel[i].reset();
  }

  /// The map without the voxels whose centre lies in an active zone (fcl::distance's fallbacks,
  /// octreeShapeDistance), rebuilt when the active zones were taken anew.
  const fcl::OcTree<double>& filteredTree() {
    if (filtered_stale || !filtered_tree) {
      const std::shared_ptr<const octomap::OcTree> copy = copyWithoutZones(*tree, active_zones);
      filtered_tree = std::make_shared<fcl::OcTree<double>>(copy);
      filtered_stale = false;
    }
    return *filtered_tree;
  }
};

ObstacleDistanceField::ObstacleDistanceField(const ObstacleMapConfig& config,
                                             const ehc_control::RobotCollisionModel& robot)
    : config_(config), robot_(robot), impl_(std::make_unique<Impl>()) {
  config_.validate();
  impl_->reset(config_);
  for (std::size_t li = 0; li < robot_.links().size(); ++li)
    for (std::size_t si = 0; si < robot_.links()[li].shapes.size(); ++si) {
      const CollisionShape& s = robot_.links()[li].shapes[si];
      impl_->geoms.push_back(ehc_control::makeFclGeometry(s));
      impl_->shapes.push_back({li, si});
    }
  impl_->last_voxel.resize(impl_->shapes.size());
}

ObstacleDistanceField::~ObstacleDistanceField() = default;
ObstacleDistanceField::ObstacleDistanceField(ObstacleDistanceField&&) noexcept = default;
ObstacleDistanceField& ObstacleDistanceField::operator=(ObstacleDistanceField&&) noexcept = default;

void ObstacleDistanceField::clear() { impl_->reset(config_); }

void ObstacleDistanceField::setExclusionZones(const std::vector<ExclusionZone>& zones) {
  for (const ExclusionZone& z : zones) {
    if (!z.centre.allFinite()) fail("exclusion zone centre is not finite");
    if (!(z.radius >= 0.0 && z.radius <= ExclusionZone::kMaxRadius))
      fail("exclusion zone radius " + std::to_string(z.radius) + " m is outside [0, " +
           std::to_string(ExclusionZone::kMaxRadius) + "]");
  }
  zones_ = zones;  // the queries take them when they have moved (Impl::activeZones)
}

ObstacleDistanceField::InsertStats ObstacleDistanceField::insertCloud(
    const PointList& points, const Eigen::Vector3d& origin,
    const std::vector<Eigen::Isometry3d>* link_poses) {
  if (!origin.allFinite()) fail("sensor origin is not finite");
  if (link_poses && link_poses->size() != robot_.links().size())
    fail("expected " + std::to_string(robot_.links().size()) + " link poses, got " +
         std::to_string(link_poses->size()));
  InsertStats st;
  st.input = static_cast<int>(points.size());
  // Robot shapes in the world frame, with bounding spheres for a quick reject.
  struct Posed {
    const CollisionShape* s;
    Eigen::Isometry3d link_inv;
    Eigen::Vector3d centre;
    double radius;
  };
  std::vector<Posed> posed;
  if (link_poses) {
    for (const Impl::ShapeIndex& k : impl_->shapes) {
      const ehc_control::RobotLinkGeometry& link = robot_.links()[k.link];
      const CollisionShape& s = link.shapes[k.shape];
      const Eigen::Isometry3d& Tl = (*link_poses)[k.link];
      if (!Tl.matrix().allFinite()) fail("link pose of '" + link.name + "' is not finite");
      posed.push_back({&s, Tl.inverse(), Tl * s.origin.translation(),
                       s.boundingRadius() + config_.self_filter_padding});
    }
  }
  octomap::Pointcloud pc;
  pc.reserve(points.size());
  for (const Eigen::Vector3f& pf : points) {
    if (!pf.allFinite()) {
      ++st.non_finite;
      continue;
    }
    const Eigen::Vector3d p = pf.cast<double>();
    if (p.z() < config_.min_height) {
      ++st.below_min_height;
      continue;
    }
    bool own = false;
    for (const Posed& ps : posed) {
      if ((p - ps.centre).squaredNorm() > ps.radius * ps.radius) continue;
      if (ps.s->contains(ps.link_inv * p, config_.self_filter_padding)) {
        own = true;
        break;
      }
    }
    if (own) {
      ++st.robot;
      continue;
    }
    pc.push_back(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
  }
  st.inserted = static_cast<int>(pc.size());
  if (!pc.size()) return st;
  impl_->changed();
  impl_->tree->insertPointCloud(
      pc, octomap::point3d(static_cast<float>(origin.x()), static_cast<float>(origin.y()),
                           static_cast<float>(origin.z())),
      config_.max_range, /*lazy_eval=*/false, /*discretize=*/true);
  return st;
}

void ObstacleDistanceField::addOccupiedBox(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  if (!lo.allFinite() || !hi.allFinite() || (hi - lo).minCoeff() < 0.0)
    fail("addOccupiedBox: box must be finite with max >= min");
  const double r = config_.resolution;
  auto first = [r](double v) { return (std::ceil(v / r - 0.5) + 0.5) * r; };  // first centre >= v
  for (double x = first(lo.x()); x <= hi.x(); x += r)
    for (double y = first(lo.y()); y <= hi.y(); y += r)
      for (double z = first(lo.z()); z <= hi.z(); z += r)
        impl_->tree->updateNode(static_cast<float>(x), static_cast<float>(y),
                                static_cast<float>(z), true, /*lazy_eval=*/true);
  impl_->tree->updateInnerOccupancy();
  impl_->changed();
}

std::uint64_t ObstacleDistanceField::revision() const { return impl_->revision; }

ObstacleDistanceField::Cell ObstacleDistanceField::cell(const Eigen::Vector3d& p) const {
  const octomap::OcTreeNode* n = impl_->tree->search(p.x(), p.y(), p.z());
  if (!n) return Cell::Unknown;
  return impl_->tree->isNodeOccupied(n) ? Cell::Occupied : Cell::Free;
}

std::size_t ObstacleDistanceField::occupiedLeafCount() const {
  std::size_t n = 0;
  for (auto it = impl_->tree->begin_leafs(), end = impl_->tree->end_leafs(); it != end; ++it)
    if (impl_->tree->isNodeOccupied(*it)) ++n;
  return n;
}

std::vector<LinkObstacleDistance> ObstacleDistanceField::distances(
    const std::vector<Eigen::Isometry3d>& link_poses) const {
  const std::vector<ExclusionZone>& zones = impl_->activeZones(zones_);
  const OcTreeExclusion exclusion{*impl_->tree, zones, [this]() -> const fcl::OcTree<double>& { return impl_->filteredTree(); }};
  return query(link_poses, zones.empty() ? nullptr : &exclusion, true);
}

std::vector<LinkObstacleDistance> ObstacleDistanceField::distances(const std::vector<Eigen::Isometry3d>& link_poses,
                                                                   const std::vector<ExclusionZone>& zones) const {
  for (const ExclusionZone& z : zones)
    if (!z.centre.allFinite() || !std::isfinite(z.radius) || z.radius < 0.0 || z.radius > ExclusionZone::kMaxRadius)
      fail("exclusion zone: non-finite centre or radius outside [0, " + std::to_string(ExclusionZone::kMaxRadius) + "] m");
  std::shared_ptr<fcl::OcTree<double>> filtered;  // FCL's fallbacks only: built when first asked
  const OcTreeExclusion exclusion{*impl_->tree, zones, [&]() -> const fcl::OcTree<double>& {
                                    if (!filtered) filtered = std::make_shared<fcl::OcTree<double>>(copyWithoutZones(*impl_->tree, zones));
                                    return *filtered;
                                  }};
  return query(link_poses, zones.empty() ? nullptr : &exclusion, false);
}

std::vector<LinkObstacleDistance> ObstacleDistanceField::query(const std::vector<Eigen::Isometry3d>& link_poses,
                                                               const OcTreeExclusion* excluding, bool seeded_queries) const {
  if (link_poses.size() != robot_.links().size())
    fail("expected " + std::to_string(robot_.links().size()) + " link poses, got " +
         std::to_string(link_poses.size()));
  std::vector<LinkObstacleDistance> best(robot_.links().size());
  std::vector<bool> found(robot_.links().size(), false);
  if (impl_->tree->size() == 0) return {};

  fcl::DistanceRequest<double> req;
  req.enable_nearest_points = true;
  // The robot's own configuration: a penetration's depth (FCL's collision query). A planned one
  // may lie deep in the map, where that query can disagree with GJK (FCL asserts): unsigned, a
  // penetration then reads <= 0, all a planning check needs.
  req.enable_signed_distance = seeded_queries;
  static const std::vector<ExclusionZone> kNone;
  const std::vector<ExclusionZone>& zones = excluding ? excluding->zones : kNone;
  for (std::size_t i = 0; i < impl_->shapes.size(); ++i) {
    const std::size_t li = impl_->shapes[i].link;
    const ehc_control::RobotLinkGeometry& link = robot_.links()[li];
    const CollisionShape& s = link.shapes[impl_->shapes[i].shape];
    const Eigen::Isometry3d& Tl = link_poses[li];
    if (!Tl.matrix().allFinite()) fail("link pose of '" + link.name + "' is not finite");
    const Eigen::Isometry3d Ts = Tl * s.origin;
    fcl::Transform3<double> tf;
    tf.linear() = Ts.linear();
    tf.translation() = Ts.translation();
    fcl::DistanceResult<double> res;
    // Start from the influence distance: the octree traversal prunes every voxel farther. Nearer
    // still: just above the distance to the voxel the last query found (seedBound).
    const double start = found[li] ? std::min(best[li].distance, config_.influence_distance)
                                   : config_.influence_distance;
    const double seeded = seeded_queries ? std::min(start, impl_->seedBound(i, zones, tf) + kSeedMargin) : start;
    res.min_distance = seeded;
    octreeShapeDistance(*impl_->fcl_tree, *impl_->geoms[i], tf, req, &res, excluding);
    if (!(res.min_distance < seeded) && seeded < start) {  // GJK's tolerance: ask again unseeded
      res = fcl::DistanceResult<double>();
      res.min_distance = start;
      octreeShapeDistance(*impl_->fcl_tree, *impl_->geoms[i], tf, req, &res, excluding);
    }
    if (!(res.min_distance < start)) {
      if (seeded_queries) impl_->last_voxel[i].reset();
      continue;
    }
    LinkObstacleDistance d;
    d.link = link.name;
    d.distance = res.min_distance;
    d.obstacle_point = res.nearest_points[0];
    d.link_point = res.nearest_points[1];
    Eigen::Vector3d nrm = d.link_point - d.obstacle_point;
    if (d.distance <= 0.0 || nrm.norm() < 1e-9) nrm = Ts.translation() - d.obstacle_point;
    if (nrm.norm() < 1e-9) nrm = Eigen::Vector3d::UnitZ();
    d.normal = nrm.normalized();
    if (seeded_queries) {
      if (d.distance > 0.0) impl_->rememberVoxel(i, d.obstacle_point, d.normal);
      else impl_->last_voxel[i].reset();
    }
    best[li] = d;
    found[li] = true;
  }
  std::vector<LinkObstacleDistance> out;
  for (std::size_t l = 0; l < best.size(); ++l)
    if (found[l]) out.push_back(best[l]);
  return out;
}

std::vector<Eigen::Isometry3d> ObstacleDistanceField::linkPoses(
    const ehc_control::WholeBodyModel& model, const Eigen::Vector3d& base_pose,
    const Eigen::VectorXd& q, std::optional<double> finger_opening) const {
  const Eigen::Isometry3d Twb = ehc_control::WholeBodyModel::baseTransform(base_pose);
  std::vector<Eigen::Isometry3d> out;
  out.reserve(robot_.links().size());
  for (std::size_t i = 0; i < robot_.links().size(); ++i) {
    const std::string& l = robot_.links()[i].name;
    if (!model.hasLink(l)) fail("link '" + l + "' is not in the whole-body model");
    out.push_back(Twb * model.linkPoseInBase(q, l) * robot_.fingerOffset(l, finger_opening));
  }
  return out;
}

std::string ObstacleDistanceField::summary() const {
  return robot_.summary() + "; gripper fingers posed at their upper limit (fully open) unless an opening is given";
}

void ObstacleDistanceField::writeBinary(const std::string& path) const {
  if (!impl_->tree->writeBinary(path))
    throw std::runtime_error("[ObstacleDistanceField] cannot write '" + path + "'");
}

}  // namespace ehc_perception
