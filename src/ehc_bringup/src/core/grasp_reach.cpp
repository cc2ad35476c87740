#include "ehc_bringup/grasp_reach.h"

#include "ehc_common/config_node.h"
#include "ehc_control/reach_recovery.h"
#include "ehc_perception/convex_polygon.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <random>
#include <sstream>
#include <stdexcept>

namespace ehc_bringup {

using ehc_control::CollisionShape;
using ehc_control::WholeBodyModel;

namespace {
constexpr double kDistanceStep = 0.05;  ///< m: placement distances along a bearing
/// Newton-Raphson steps per IK solve (converging solves take a few tens).
constexpr int kIterations = 100;
/// Arm IK seeds besides the ready posture.
constexpr int kRandomSeeds = 3;
}  // namespace

void GraspReachParams::validate() const {
  auto check = [](bool ok, const std::string& what) {
    if (!ok) throw std::invalid_argument("[GraspReachParams] " + what);
  };
  check(bearings >= 3 && bearings <= 72, "bearings must be in [3, 72]");
  check(ik_attempts >= 1 && ik_attempts <= 100, "ik_attempts must be in [1, 100]");
  check(std::isfinite(clearance) && clearance >= 0.0 && clearance <= 0.2, "clearance must be in [0, 0.2] m");
  check(std::isfinite(grasp_support_exclusion) && grasp_support_exclusion >= 0.0 && grasp_support_exclusion <= 1.0,
        "grasp_support_exclusion must be in [0, 1] m");
}

std::string GraspReachParams::summary() const {
  std::ostringstream os;
  if (!enabled) return "reach: off (grasps chosen by score alone)";
  os << "reach: " << bearings << " bearings, " << ik_attempts << " placements tried, clearance " << clearance
     << " m beyond the stop distances, at the grasp links within " << grasp_support_exclusion
     << " m of it not checked";
  return os.str();
}

GraspReachParams loadGraspReachParams(const ehc_common::ConfigNode& node) {
  GraspReachParams p;
  p.enabled = node.get("enabled", p.enabled);
  p.bearings = node.get("bearings", p.bearings);
  p.ik_attempts = node.get("ik_attempts", p.ik_attempts);
  p.clearance = node.get("clearance", p.clearance);
  p.grasp_support_exclusion = node.get("grasp_support_exclusion", p.grasp_support_exclusion);
  node.validate(p);
  return p;
}

namespace {
/// Half extents of the world-axis-aligned box round a shape at world pose `T`.
Eigen::Vector3d shapeHalfExtents(const CollisionShape& s, const Eigen::Matrix3d& R) {
  Eigen::Vector3d h = Eigen::Vector3d::Zero();
  switch (s.type) {
    case CollisionShape::Type::Box: h = R.cwiseAbs() * s.halfExtents(); break;
    case CollisionShape::Type::Cylinder: {
      const Eigen::Vector3d a = R.col(2);
      for (int k = 0; k < 3; ++k)
        h[k] = std::abs(a[k]) * 0.5 * s.size.y() + s.size.x() * std::sqrt(std::max(0.0, 1.0 - a[k] * a[k]));
      break;
    }
    case CollisionShape::Type::Sphere: h = s.halfExtents(); break;
  }
  return h;
}
}  // namespace

bool SupportSurface::valid() const {
  if (!std::isfinite(height) || footprint.size() < 3) return false;
  for (const auto& c : footprint)
    if (!c.allFinite()) return false;
  return ehc_perception::polygonArea(footprint) > 0.5e-9;
}

std::optional<SupportSurface> supportFromPoints(const std::vector<Eigen::Vector3f>& points, const Eigen::Vector4d& plane,
                                                double tolerance, std::size_t max_points) {
  const Eigen::Vector3d n = plane.head<3>();
  if (!plane.allFinite() || n.norm() < 1e-9 || n.normalized().z() < std::cos(30.0 * M_PI / 180.0) || max_points == 0)
    return std::nullopt;
  const double scale = 1.0 / n.norm();
  const std::size_t stride = std::max<std::size_t>(1, points.size() / max_points);
  std::vector<Eigen::Vector2d> xy;
  double z = 0.0;
  for (std::size_t i = 0; i < points.size(); i += stride) {
    const Eigen::Vector3d p = points[i].cast<double>();
    if (!p.allFinite() || std::abs((n.dot(p) + plane.w()) * scale) > tolerance) continue;
    xy.push_back(p.head<2>());
    z += p.z();
  }
  if (xy.size() < 3) return std::nullopt;
  SupportSurface s;
  s.height = z / static_cast<double>(xy.size());
  s.footprint = ehc_perception::convexHull2d(std::move(xy));
  if (!s.valid()) return std::nullopt;
  return s;
}

SupportSurface mergedSupport(const std::optional<SupportSurface>& previous, const SupportSurface& seen,
                             double height_tolerance) {
  if (!previous || !previous->valid() || std::abs(previous->height - seen.height) > height_tolerance) return seen;
  std::vector<Eigen::Vector2d> all = previous->footprint;
  all.insert(all.end(), seen.footprint.begin(), seen.footprint.end());
  SupportSurface s;
  s.height = seen.height;
  s.footprint = ehc_perception::convexHull2d(std::move(all));
  return s;
}

bool wayKeepsClear(const std::vector<Eigen::Vector2d>& footprint, const Eigen::Vector2d& from, const Eigen::Vector2d& to,
                   double corridor) {
  const double ends = std::min({ehc_perception::hullDistance(footprint, {from}),
                                ehc_perception::hullDistance(footprint, {to}), std::max(corridor, 0.0)});
  // A seen footprint's outline is the hull of noisy points: along an edge it wanders by about a
  // centimetre, which a way parallel to it must not fail on.
  constexpr double kOutlineTolerance = 0.02;
  const double way = ehc_perception::hullDistance(footprint, {from, to});
  return way > 0.0 && way >= ends - kOutlineTolerance;
}

double supportDistance(const SupportSurface& support, const Eigen::Vector3d& centre, const Eigen::Vector3d& half_extents) {
  const double dxy = std::max(0.0, ehc_perception::hullDistance(support.footprint, {centre.head<2>()}) - half_extents.head<2>().norm());
  const double lo = centre.z() - half_extents.z(), hi = centre.z() + half_extents.z();
  const double dz = support.height < lo ? lo - support.height : support.height > hi ? support.height - hi : 0.0;
  return std::hypot(dxy, dz);
}

// ---------------------------------------------------------------- GraspReach

GraspReach::GraspReach(const WholeBodyModel& model, const GraspReachParams& params,
                       const std::function<double(const std::string&)>& stop_distance, double joint_stop)
    : model_(model), params_(params), joint_stop_(joint_stop) {
  params_.validate();
  const ehc_control::RobotConfig& rc = model_.config();
  if (!std::isfinite(joint_stop) || joint_stop < 0.0 || ((rc.arm_upper - rc.arm_lower).array() <= 2.0 * joint_stop).any())
    throw std::invalid_argument("[GraspReach] joint_stop must be >= 0 and leave every joint a range");
  const ehc_control::RobotCollisionModel collision(model_.calibratedUrdfXml(), rc.arm_joints, rc.checked_links);
  // A link moves with the arm when its pose in the base frame changes between two configurations.
  const Eigen::VectorXd q0 = rc.arm_ready;
  const Eigen::VectorXd q1 = rc.arm_ready + 0.3 * Eigen::VectorXd::Ones(rc.nArm());
  for (const ehc_control::RobotLinkGeometry& g : collision.links()) {
    Link l;
    l.index = model_.linkIndex(g.name);
    l.name = g.name;
    l.shapes = g.shapes;
    l.finger = collision.fingerOffset(g.name, std::nullopt);
    const double stop = stop_distance(g.name);
    if (!std::isfinite(stop) || stop < 0.0) throw std::invalid_argument("[GraspReach] stop distance of '" + g.name + "' must be >= 0");
    l.stop = stop + params_.clearance;
    l.moves = !model_.linkPoseInBase(q0, g.name).isApprox(model_.linkPoseInBase(q1, g.name), 1e-9);
    links_.push_back(std::move(l));
  }
  model_.updateKinematics(Eigen::Vector3d::Zero(), rc.arm_ready, &state_);
  for (const Link& l : links_) {
    if (l.moves) continue;
    const Eigen::Isometry3d T = state_.linkPose(l.index) * l.finger;
    for (const CollisionShape& s : l.shapes) {
      const Eigen::Isometry3d W = T * s.origin;
      corridor_ = std::max(corridor_, W.translation().head<2>().norm() +
                                          shapeHalfExtents(s, W.linear()).head<2>().norm() + l.stop);
    }
  }
  const Eigen::Vector3d tcp = model_.linkPoseInBase(rc.arm_ready, rc.tcp_frame).translation();
  ready_bearing_ = ehc_control::readyTcpBearing(model_);
  arm_base_ = model_.linkPoseInBase(rc.arm_ready, rc.arm_base_frame).translation();
  ready_distance_ = (tcp - arm_base_).norm();
  // The arm's reach: the farthest sampled TCP from the arm base (deterministic sample).
  std::mt19937 rng(7);
  reach_ = 0.0;
  for (int s = 0; s < 400; ++s) {
    Eigen::VectorXd q(rc.nArm());
    for (int i = 0; i < rc.nArm(); ++i) q[i] = std::uniform_real_distribution<double>(rc.arm_lower[i], rc.arm_upper[i])(rng);
    reach_ = std::max(reach_, (model_.linkPoseInBase(q, rc.tcp_frame).translation() - arm_base_).norm());
  }
  reach_ *= 1.05;
  // IK seeds: the ready posture and a few fixed random configurations (deterministic).
  seeds_.push_back(rc.arm_ready);
  for (int s = 0; s < kRandomSeeds; ++s) {
    Eigen::VectorXd q(rc.nArm());
    for (int i = 0; i < rc.nArm(); ++i)
      q[i] = std::uniform_real_distribution<double>(rc.arm_lower[i] + joint_stop, rc.arm_upper[i] - joint_stop)(rng);
    seeds_.push_back(q);
  }
}

GraspReach::~GraspReach() = default;

void GraspReach::setSupport(const std::optional<SupportSurface>& support) {
  if (support && !support->valid()) throw std::invalid_argument("[GraspReach] invalid support surface");
  support_ = support;
  kept_.clear();
  ++kept_revision_;
}

bool GraspReach::observeSupport(const SupportSurface& seen) {
  if (!seen.valid()) return false;
  const SupportSurface merged = mergedSupport(support_, seen);
  if (support_ && std::abs(merged.height - support_->height) <= 0.005 &&
      std::all_of(merged.footprint.begin(), merged.footprint.end(),
                  [&](const Eigen::Vector2d& c) { return ehc_perception::hullDistance(support_->footprint, {c}) <= 0.01; }))
    return false;
  setSupport(merged);
  return true;
}

std::optional<std::pair<std::string, double>> GraspReach::blocked(const Eigen::Vector3d& base, const Eigen::VectorXd& q,
                                                                  bool base_links_only, const Eigen::Vector2d& excluded,
                                                                  double exclusion) const {
  model_.updateKinematics(base, q, &state_);
  std::optional<std::pair<std::string, double>> worst;
  for (const Link& l : links_) {
    if (base_links_only && l.moves) continue;
    const Eigen::Isometry3d T = state_.linkPose(l.index) * l.finger;
    for (const CollisionShape& s : l.shapes) {
      const Eigen::Isometry3d W = T * s.origin;
      if (exclusion > 0.0 && (W.translation().head<2>() - excluded).norm() < exclusion) continue;
      const double d = supportDistance(*support_, W.translation(), shapeHalfExtents(s, W.linear()));
      if (d < l.stop && (!worst || d - l.stop < worst->second)) worst = std::make_pair(l.name, d);
    }
  }
  return worst;
}

std::vector<Eigen::Vector3d> GraspReach::placements(const Eigen::Vector3d& target) const {
  struct Placement {
    Eigen::Vector3d base;
    double misfit;  ///< m: |arm base to target - the ready TCP's distance from the arm base|
  };
  std::vector<Placement> out;
  const Eigen::VectorXd& ready = model_.config().arm_ready;
  for (int i = 0; i < params_.bearings; ++i) {
    const double a = 2.0 * M_PI * i / params_.bearings;
    for (double d = 0.0;; d += kDistanceStep) {
      const Eigen::Vector3d base = ehc_control::placementFacing(target.head<2>(), a, d, ready_bearing_);
      const double arm = (WholeBodyModel::baseTransform(base) * arm_base_ - target).norm();
      if (arm > reach_) break;
      if (onTheWay(base) && !blocked(base, ready, true, Eigen::Vector2d::Zero(), 0.0))
        out.push_back({base, std::abs(arm - ready_distance_)});
    }
  }
  // The arm base at the ready TCP's distance from the target first (the IK starts at the ready posture).
  std::stable_sort(out.begin(), out.end(), [](const Placement& x, const Placement& y) { return x.misfit < y.misfit; });
  std::vector<Eigen::Vector3d> bases;
  for (std::size_t i = 0; i < out.size() && static_cast<int>(i) < params_.ik_attempts; ++i) bases.push_back(out[i].base);
  return bases;
}

GraspReachVerdict GraspReach::judge(const Eigen::Isometry3d& grasp, const Eigen::Isometry3d& pre_grasp) const {
  GraspReachVerdict v;
  if (!support_) {
    v.reachable = true;
    return v;
  }
  const std::vector<Eigen::Vector3d> bases = placements(pre_grasp.translation());
  if (bases.empty()) v.reason = "no base placement within the arm's reach beside the support on the robot's side";
  // The reason kept: the last configuration found and why it fails, else the missing IK solution.
  for (const Eigen::Vector3d& b : bases)
    for (const Eigen::VectorXd& seed : seeds_) {
      Eigen::VectorXd q_pre;
      if (!model_.armInverseKinematicsFrom(pre_grasp, b, seed, &q_pre, joint_stop_, kIterations)) {
        if (v.reason.empty()) v.reason = "no arm configuration of the pre-grasp";
        continue;
      }
      if (settle(grasp, b, q_pre, &v)) return v;
    }
  // No placement's arm reaches it: the whole body from each (the base free to move to where the
  // arm reaches the pre-grasp's orientation, e.g. a top-down grasp the ready posture's bearing
  // does not suit), the base where it ends kept clear of the support.
  for (const Eigen::Vector3d& b : bases) {
    Eigen::Vector3d b_pre;
    Eigen::VectorXd q_pre;
    if (!model_.inverseKinematicsFrom(pre_grasp, b, seeds_.front(), &b_pre, &q_pre, joint_stop_)) continue;
    if (!onTheWay(b_pre) || blocked(b_pre, q_pre, true, Eigen::Vector2d::Zero(), 0.0)) continue;
    if (settle(grasp, b_pre, q_pre, &v)) return v;
  }
  return v;
}

bool GraspReach::settle(const Eigen::Isometry3d& grasp, const Eigen::Vector3d& base,
                        const Eigen::VectorXd& q_pre, GraspReachVerdict* v) const {
  std::ostringstream why;
  why << std::fixed << std::setprecision(3);
  if (const auto hit = blocked(base, q_pre, false, Eigen::Vector2d::Zero(), 0.0)) {
    why << hit->first << " " << hit->second << " m from the support at the pre-grasp";
    v->reason = why.str();
    return false;
  }
  Eigen::VectorXd q_grasp;
  if (!model_.armInverseKinematicsFrom(grasp, base, q_pre, &q_grasp, joint_stop_, kIterations)) {
    v->reason = "no arm configuration of the grasp from the pre-grasp's";
    return false;
  }
  if (const auto hit = blocked(base, q_grasp, false, grasp.translation().head<2>(), params_.grasp_support_exclusion)) {
    why << hit->first << " " << hit->second << " m from the support at the grasp";
    v->reason = why.str();
    return false;
  }
  const std::string map = descentBlocked(base, q_pre, q_grasp);
  if (!map.empty()) {
    v->reason = map;
    return false;
  }
  v->reachable = true;
  v->base = base;
  v->q_pre = q_pre;
  v->q_grasp = q_grasp;
  v->reason.clear();
  return true;
}

std::optional<std::pair<std::string, double>> GraspReach::mapBlocked(const Eigen::Vector3d& base, const Eigen::VectorXd& q,
                                                                     bool descent) const {
  if (!map_) return std::nullopt;
  std::optional<std::pair<std::string, double>> worst;
  for (const auto& [name, d] : map_(base, q, descent)) {
    const auto l = std::find_if(links_.begin(), links_.end(), [&](const Link& k) { return k.name == name; });
    if (l == links_.end() || d >= l->stop) continue;
    if (!worst || d - l->stop < worst->second) worst = std::make_pair(name, d);
  }
  return worst;
}

bool GraspReach::onTheWay(const Eigen::Vector3d& placement) const {
  if (!robot_base_ || !support_) return true;
  return wayKeepsClear(support_->footprint, robot_base_->head<2>(), placement.head<2>(), corridor_);
}

std::string GraspReach::descentBlocked(const Eigen::Vector3d& base, const Eigen::VectorXd& q_pre,
                                       const Eigen::VectorXd& q_grasp) const {
  struct Check {
    Eigen::VectorXd q;
    bool descent;
    const char* where;
  };
  const Check checks[] = {{q_pre, false, "the pre-grasp"},
                          {0.5 * (q_pre + q_grasp), true, "halfway down"},
                          {q_grasp, true, "the grasp"}};
  for (const Check& c : checks)
    if (const auto hit = mapBlocked(base, c.q, c.descent)) {
      std::ostringstream why;
      why << std::fixed << std::setprecision(3) << hit->first << " " << hit->second << " m from an obstacle at "
          << c.where;
      return why.str();
    }
  return "";
}

namespace {
/// Whether two grasp poses share a kept verdict (within 5 mm and 2 deg).
bool sameGrasp(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  const Eigen::AngleAxisd d(Eigen::Matrix3d(a.linear().transpose() * b.linear()));
  return (a.translation() - b.translation()).norm() <= 0.005 && std::abs(d.angle()) <= 2.0 * M_PI / 180.0;
}
}  // namespace

const GraspReachVerdict* GraspReach::keptVerdict(const Eigen::Isometry3d& grasp) const {
  for (const Kept& k : kept_)
    if (sameGrasp(k.grasp, grasp)) return &k.verdict;
  return nullptr;
}

bool GraspReach::reachable(const Eigen::Isometry3d& grasp, const Eigen::Isometry3d& pre_grasp) {
  if (!params_.enabled || !support_) return true;
  const std::optional<std::uint64_t> revision =
      map_revision_ ? std::optional<std::uint64_t>(map_revision_()) : std::nullopt;
  for (auto k = kept_.begin(); k != kept_.end(); ++k) {
    if (!sameGrasp(k->grasp, grasp)) continue;
    const GraspReachVerdict& v = k->verdict;
    if (!v.reachable) return false;
    if (onTheWay(v.base) &&
        ((revision && k->clear_at == revision) || descentBlocked(v.base, v.q_pre, v.q_grasp).empty())) {
      k->clear_at = revision;
      return true;
    }
    kept_.erase(k);  // the map grew into its configurations, or the robot is across the support: judged anew
    break;
  }
  ++judgements_;
  const GraspReachVerdict v = judge(grasp, pre_grasp);
  if (kept_.size() >= 256) kept_.clear();
  kept_.push_back({grasp, v, v.reachable ? revision : std::nullopt});
  ++kept_revision_;  // also counts an erase above
  return v.reachable;
}

}  // namespace ehc_bringup
