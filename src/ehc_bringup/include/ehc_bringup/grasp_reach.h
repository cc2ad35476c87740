#pragma once
// GraspReach: can the robot reach a grasp and its pre-grasp standing beside the support the
// object stands on, with every link clear of it? Judged by whole-body kinematics (ROS-free,
// any robot: the links, their stop distances and the arm come from the robot's model).
//
// The support (SupportSurface): a horizontal surface, its height and the convex footprint of
// the support plane's points seen so far (supportFromPoints, mergedSupport), world frame. A
// link shape keeps its stop distance from it as the controller's obstacle dampers keep it from
// the obstacle map's voxels: the distance of the shape's bounding box (its horizontal part a
// circle) to the footprint at the support's height (supportDistance).
//
// A grasp is reachable when, from one of the base placements, the arm alone reaches the
// pre-grasp (from the ready posture) and then the grasp (from the pre-grasp's configuration:
// the straight descent) within the joint limits shrunk by the controller's joint stop, and in
// both configurations every checked link (robot.collision.checked_links) is at least its stop
// distance plus `clearance` from the support. At the grasp, the links within
// grasp_support_exclusion of the grasp position (horizontally) are not checked: the fingers
// touch the support and from GRASP on the obstacle map leaves it out there (the sequencer's
// support cap, obstacle_exclusion_support_reach).
// Placements: `bearings` directions round the pre-grasp, evenly spaced, the base facing it so
// that the ready pose's TCP points at it, every 5 cm outwards while the arm base is within the
// arm's reach (sampled farthest TCP distance) of it; those where the links that do not move
// with the arm keep their stop distance from the support. The ik_attempts whose arm base is
// nearest the ready TCP's distance from the arm base are tried, each with the arm IK from the
// ready posture and from 3 fixed random configurations; when none reaches the pre-grasp, the
// whole body's IK from each placement (the base free, where it ends kept clear of the support:
// a top-down grasp near the support's edge wants another bearing than the ready posture's). A
// differential base reaches any of them (the judgement is kinematic; the controller's approach
// may end elsewhere, at the support's edge beside the placement, and then its stall recovery
// moves to the kept verdict's configuration: keptVerdict, ControlCycle::setGivenPlans) as long
// as the way there does not cross the support: the controller is reactive and does not
// drive round a table. With the robot's base pose (setRobotBase), only placements whose
// straight way from the robot's base keeps off the support's footprint are tried (a grasp
// from the far side of a table is unreachable for a robot on its near side), and by as much as
// its ends do, up to the base's corridor (wayKeepsClear): the base sweeps its own radius plus
// its stop distance, and a way that grazes a corner of the footprint takes it into the legs
// standing under that corner (or into a corner the views have not shown yet).
// With the obstacle map (setMapDistances: the map the controller's dampers read), the pre-grasp's
// configuration, the grasp's and the one halfway down the descent must also keep every checked
// link at its stop distance from the map's obstacles: the neighbours beside the target, and the
// target itself where the map still holds it (before the descent). The controller stops a link
// there and the approach stalls; another candidate or another placement may pass.
// Verdicts are kept per grasp pose (within 5 mm and 2 deg) until the support changes: the
// choice runs whenever candidates or the object's pose update. The map grows while the robot
// drives: a kept reachable verdict's configurations are checked against it again (a few distance
// queries) when the map's revision (setMapDistances) has changed since they were last found
// clear, or at every call without one, and the grasp judged anew when one is blocked.

#include "ehc_control/robot_collision_model.h"
#include "ehc_control/whole_body_model.h"

#include <Eigen/Geometry>

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace ehc_common {
class ConfigNode;
}  // namespace ehc_common

namespace ehc_bringup {

struct GraspReachParams {
  /// false: grasps are not judged (the choice by score alone).
  bool enabled = true;
  int bearings = 12;          ///< base placement directions round the grasp
  int ik_attempts = 6;        ///< placements tried per grasp (arm IK of the pre-grasp), [1, 100]
  /// m beyond each link's obstacle stop distance.
  double clearance = 0.0;
  /// m: at the grasp, links within this of the grasp position (horizontally) are not checked.
  double grasp_support_exclusion = 0.20;
  void validate() const;  ///< throws "[GraspReachParams] ..."
  std::string summary() const;
};
/// The `reach` mapping (keys above; absent keys keep their defaults, unknown keys are errors).
GraspReachParams loadGraspReachParams(const ehc_common::ConfigNode& node);

/// A horizontal support surface (world): its height and its footprint, a convex polygon
/// (counter-clockwise, at least 3 corners).
struct SupportSurface {
  double height = 0.0;
  std::vector<Eigen::Vector2d> footprint;
  bool valid() const;  ///< finite, at least 3 corners, non-zero area
};


/// The support of a plane n.p + d = 0 (n up, world z up within 30 deg) in a cloud (world): the
/// points within `tolerance` of it, their convex footprint and mean height; at most
/// `max_points` of them read (an even stride). nullopt when fewer than 3 or a degenerate hull.
std::optional<SupportSurface> supportFromPoints(const std::vector<Eigen::Vector3f>& points, const Eigen::Vector4d& plane,
                                                double tolerance = 0.01, std::size_t max_points = 20000);

/// `seen` and the support seen before, `previous`, one surface when their heights are within
/// `height_tolerance` (the hull of both footprints, `seen`'s height); else `seen`.
SupportSurface mergedSupport(const std::optional<SupportSurface>& previous, const SupportSurface& seen,
                             double height_tolerance = 0.02);

/// Distance (m) of an axis-aligned box (centre, half extents; its horizontal part taken as the
/// circle round its horizontal rectangle) to the support's footprint at the support's height.
double supportDistance(const SupportSurface& support, const Eigen::Vector3d& centre, const Eigen::Vector3d& half_extents);

/// Whether the straight way from `from` to `to` keeps off a footprint (convex polygon) by at
/// least the clearance it has at its ends, or `corridor` (m) where both ends have more, less
/// 2 cm (the outline of a seen footprint wanders by about that): it does not cut a corner.
/// An end on or inside the footprint: false.
bool wayKeepsClear(const std::vector<Eigen::Vector2d>& footprint, const Eigen::Vector2d& from, const Eigen::Vector2d& to,
                   double corridor);

/// What GraspReach found for one grasp.
struct GraspReachVerdict {
  bool reachable = false;
  Eigen::Vector3d base = Eigen::Vector3d::Zero();  ///< the placement that reaches it (reachable)
  Eigen::VectorXd q_pre, q_grasp;  ///< the arm at the pre-grasp and at the grasp (reachable)
  std::string reason;  ///< the last placement's failure (unreachable), e.g. "link4 0.012 m from the support at the pre-grasp"
};

class GraspReach {
 public:
  /// `stop_distance(link)`: the controller's obstacle stop distance of a link; `joint_stop`
  /// (rad): its closest approach to a joint limit. Throws std::invalid_argument
  /// "[GraspReach] ..." for bad parameters (validate) or a joint stop that leaves a joint no range.
  GraspReach(const ehc_control::WholeBodyModel& model, const GraspReachParams& params,
             const std::function<double(const std::string&)>& stop_distance, double joint_stop);
  ~GraspReach();

  /// The checked links' distances (m) to the obstacle map with the robot at (base, q), the map
  /// as the controller sees it before the descent (`descent` false) or during it (true: the
  /// target and the support round it left out, GraspSequencer::plannedExclusions): (link,
  /// distance) pairs; a link without an obstacle within the map's influence left out.
  using MapDistances = std::function<std::vector<std::pair<std::string, double>>(
      const Eigen::Vector3d& base, const Eigen::VectorXd& q, bool descent)>;
  /// A number that changes whenever what `distances` reads does (the map or its planned
  /// exclusions): a kept verdict is checked again only when it has changed.
  using MapRevision = std::function<std::uint64_t()>;
  /// The obstacle map the configurations are checked against (none: the support only), and its
  /// revision (none: kept verdicts are checked at every call).
  void setMapDistances(MapDistances distances, MapRevision revision = {}) {
    map_ = std::move(distances);
    map_revision_ = std::move(revision);
  }

  /// Where the robot's base is now (x, y, yaw; world): placements are tried only where the way
  /// from it keeps off the support (see the top of this file). nullopt (the default): any.
  void setRobotBase(const std::optional<Eigen::Vector3d>& base) { robot_base_ = base; }

  /// The support the grasps stand on; a new one forgets the verdicts.
  void setSupport(const std::optional<SupportSurface>& support);
  const std::optional<SupportSurface>& support() const { return support_; }
  /// A support seen in one view: merged into the current one (mergedSupport); setSupport only
  /// when that moves the footprint by more than 1 cm or the height by more than 5 mm (the
  /// verdicts are kept otherwise). Returns whether it did.
  bool observeSupport(const SupportSurface& seen);
  /// The judgement (see the top of this file). Without a support every grasp is reachable.
  GraspReachVerdict judge(const Eigen::Isometry3d& grasp, const Eigen::Isometry3d& pre_grasp) const;
  /// judge()'s verdict, kept per grasp pose (see the top of this file).
  bool reachable(const Eigen::Isometry3d& grasp, const Eigen::Isometry3d& pre_grasp);
  /// The verdict kept for a grasp pose (within 5 mm and 2 deg; see the top of this file), if any:
  /// its placement and configurations, e.g. for the controller to move to when the approach
  /// stalls (ReachRecovery::setGivenPlans). Valid until the next call of a non-const member.
  const GraspReachVerdict* keptVerdict(const Eigen::Isometry3d& grasp) const;
  /// A number that changes whenever a kept verdict is added, dropped or forgotten: what
  /// keptVerdict returns for a pose stays the same while it does not.
  std::uint64_t keptRevision() const { return kept_revision_; }
  /// Verdicts computed (judge() calls through reachable(); not the ones kept).
  long judgements() const { return judgements_; }
  const GraspReachParams& params() const { return params_; }

 private:
  struct Link {
    int index = -1;  ///< WholeBodyModel::linkIndex
    std::string name;
    std::vector<ehc_control::CollisionShape> shapes;
    Eigen::Isometry3d finger = Eigen::Isometry3d::Identity();  ///< fingers fully open
    double stop = 0.0;       ///< stop distance + clearance
    bool moves = true;       ///< moves with the arm joints
  };
  /// The link of `links_` nearest the support closer than its stop (name and distance), if any;
  /// links within `exclusion` of `excluded` (horizontally) skipped.
  std::optional<std::pair<std::string, double>> blocked(const Eigen::Vector3d& base, const Eigen::VectorXd& q,
                                                        bool base_links_only, const Eigen::Vector2d& excluded,
                                                        double exclusion) const;
  /// The link of links_ nearest the obstacle map closer than its stop (name and distance), if
  /// any (see setMapDistances); nullopt without a map.
  std::optional<std::pair<std::string, double>> mapBlocked(const Eigen::Vector3d& base, const Eigen::VectorXd& q,
                                                           bool descent) const;
  /// mapBlocked at the pre-grasp, halfway down the descent and at the grasp of a verdict;
  /// the reason when one is blocked (empty: clear).
  std::string descentBlocked(const Eigen::Vector3d& base, const Eigen::VectorXd& q_pre,
                             const Eigen::VectorXd& q_grasp) const;
  /// The rest of judge() with the pre-grasp solved at (base, q_pre): its clearance, the grasp
  /// from it (the arm alone) and its clearance; true and `v` filled when reachable, else
  /// v->reason set.
  bool settle(const Eigen::Isometry3d& grasp, const Eigen::Vector3d& base,
              const Eigen::VectorXd& q_pre, GraspReachVerdict* v) const;
  /// Base placements for a target position, in the order tried (see the top of this file).
  std::vector<Eigen::Vector3d> placements(const Eigen::Vector3d& target) const;

  const ehc_control::WholeBodyModel& model_;
  GraspReachParams params_;
  double joint_stop_ = 0.0;
  std::vector<Link> links_;
  double ready_bearing_ = 0.0;  ///< the ready pose's TCP bearing in the base frame
  Eigen::Vector3d arm_base_ = Eigen::Vector3d::Zero();  ///< the arm base in the base frame
  double ready_distance_ = 0.5;  ///< m: the ready TCP's distance from the arm base
  std::vector<Eigen::VectorXd> seeds_;  ///< arm IK seeds: the ready posture, then fixed random ones
  double reach_ = 1.0;  ///< m: the farthest TCP distance from the arm base (sampled)
  /// m: the base's corridor, the farthest horizontal reach of the links that do not move with
  /// the arm from the base's origin plus their stop distance
  double corridor_ = 0.0;
  std::optional<SupportSurface> support_;
  /// Whether the straight way from the robot's base to `placement` keeps off the support's
  /// footprint (true without a robot base or a support).
  bool onTheWay(const Eigen::Vector3d& placement) const;

  MapDistances map_;
  MapRevision map_revision_;
  std::optional<Eigen::Vector3d> robot_base_;
  struct Kept {
    Eigen::Isometry3d grasp;
    GraspReachVerdict verdict;
    std::optional<std::uint64_t> clear_at;  ///< the map revision its configurations were found clear at
  };
  std::vector<Kept> kept_;
  std::uint64_t kept_revision_ = 0;
  long judgements_ = 0;
  mutable ehc_control::KinematicState state_;
};

}  // namespace ehc_bringup
