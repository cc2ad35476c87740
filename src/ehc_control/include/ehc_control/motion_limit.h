#pragma once
// MotionLimit: what holds the robot back in a control cycle, so that every stall has a named
// cause. ROS-free. One enum with one string map (the strings /ehc/status carries, ehc_msgs/
// ControllerStatus LIMIT_*), computed each cycle by MotionLimitMonitor from the controller's
// inputs and command; the first that holds, in this order:
//
//   joint_limit      an arm joint within recovery.pinned_margin of its joint stop (which joint)
//   obstacle         a robot link within obstacle_margin of its stop distance d_s from an
//                    obstacle (which link, and where the obstacle point is)
//   singular         arm manipulability below singular_manipulability x the ready pose's
//   slack_saturated  a component of the task slack at slack_fraction of its bound
//   base_not_moving  the base commanded (base_command) for base_window s and travelled less than
//                    base_travel (m, or rad of turn)
//   target_not_seen  the watched target centre outside the camera image for target_unseen_time s
//   none             none of these: nothing holds the robot back
//
// A cycle's limit says what limits motion now; when an approach ends without arriving (Exp-1's
// time limit, an object's time limit in the grasping pipeline), the last cycle's limit is the
// stall's cause. The same joint and singularity tests classify Exp-1's failures (ReachExperiment).

#include "ehc_control/qp_controller.h"
#include "ehc_control/whole_body_model.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <ostream>
#include <string>
#include <vector>

namespace ehc_common {
class ConfigNode;
}  // namespace ehc_common

namespace ehc_control {

enum class MotionLimit { None, JointLimit, Obstacle, Singular, SlackSaturated, BaseNotMoving, TargetNotSeen };
std::string toString(MotionLimit limit);
/// Inverse of toString; throws std::invalid_argument "[MotionLimit] ..." for any other string.
MotionLimit motionLimitFromString(const std::string& s);
std::vector<MotionLimit> motionLimits();  ///< every value, in the order above
inline std::ostream& operator<<(std::ostream& os, MotionLimit l) { return os << toString(l); }

/// Section `motion_limit` of controller.yaml (the joint test uses controller.joint_stop and
/// controller.recovery.pinned_margin: one definition of a pinned joint).
struct MotionLimitParams {
  double obstacle_margin = 0.01;         ///< m beyond a link's d_s: a pair this close is held
  double singular_manipulability = 0.01; ///< fraction of the ready pose's manipulability
  double slack_fraction = 0.95;          ///< of controller.slack_bound: a slack this large is saturated
  double base_window = 1.0;              ///< s of base command without base motion
  double base_command = 0.02;            ///< m/s (rad/s turning): a smaller base command is none
  double base_travel = 0.01;             ///< m (rad turning): less motion over base_window is none
  double target_unseen_time = 2.0;       ///< s with the target centre out of the image
  void validate() const;                 ///< throws "[MotionLimitParams] ..."
  std::string summary() const;
};
MotionLimitParams loadMotionLimitParams(const ehc_common::ConfigNode& node);

/// A cycle's limit and what it names.
struct MotionLimitReport {
  MotionLimit limit = MotionLimit::None;
  std::string joint;   ///< joint_limit: the pinned arm joint
  std::string link;    ///< obstacle: the robot link held at its stop distance
  Eigen::Vector3d obstacle_point = Eigen::Vector3d::Zero();  ///< obstacle: closest obstacle point (world)
  /// joint_limit: rad to the joint's limit; obstacle: m, distance - d_s; singular: manipulability
  /// ratio to the ready pose's; slack_saturated: |slack| / bound; base_not_moving: m (rad) travelled;
  /// target_not_seen: s out of the image. 0 for none.
  double value = 0.0;
  /// One line: "joint5 0.12 rad from its limit", "link6 at d_s + 0.004 m from the obstacle at
  /// (1.20, 0.30, 0.72)", ...; "" for none.
  std::string detail() const;
};

/// Index of the arm joint nearest its limit if within `margin` (rad) of it, else -1.
int pinnedJoint(const RobotConfig& rc, const Eigen::VectorXd& q, double margin);

class MotionLimitMonitor {
 public:
  /// `controller`: joint_stop, recovery.pinned_margin, the links' stop distances, slack_bound.
  MotionLimitMonitor(const WholeBodyModel& model, const QpControllerParams& controller, const MotionLimitParams& params);

  /// What one cycle saw and commanded.
  struct Cycle {
    double t = 0.0;                                  ///< s
    Eigen::Vector3d base_pose = Eigen::Vector3d::Zero();  ///< x, y, yaw
    Eigen::VectorXd q;                               ///< arm joints
    Eigen::VectorXd command;                         ///< [base twist; arm rates]; empty: none
    const Vector6d* slack = nullptr;                 ///< the QP's task slack, if it ran
    /// The arm's manipulability at q, if the controller computed it (< 0: computed here).
    double manipulability = -1.0;
    const std::vector<ObstaclePair>* obstacles = nullptr;  ///< pairs the controller used
    bool has_target = false;
    bool target_in_fov = false;
  };
  /// The cycle's limit. The base and target-visibility histories are kept across targets (the
  /// grasping pipeline moves its goal every cycle): they measure time, not approaches.
  MotionLimitReport update(const Cycle& c);

  // The state-only tests (also Exp-1's failure classification).
  /// The pinned arm joint (pinnedJoint with joint_stop + recovery.pinned_margin), -1 if none.
  int pinned(const Eigen::VectorXd& q) const;
  /// Manipulability of q over the ready pose's.
  double manipulabilityRatio(const Eigen::VectorXd& q) const;
  bool singular(const Eigen::VectorXd& q) const { return manipulabilityRatio(q) < params_.singular_manipulability; }
  const MotionLimitParams& params() const { return params_; }

 private:
  bool obstacleLimit(const std::vector<ObstaclePair>& pairs, MotionLimitReport* r) const;
  /// Updates the base history; true when the base was commanded for base_window s and moved
  /// less than base_travel (`moved`: how much).
  bool baseHeld(const Cycle& c, double* moved);

  const WholeBodyModel& model_;
  QpControllerParams controller_;
  MotionLimitParams params_;
  double ready_manipulability_ = 1.0;
  // base_not_moving: where and when the base last moved (or was not commanded)
  bool have_anchor_ = false;
  Eigen::Vector3d anchor_pose_ = Eigen::Vector3d::Zero();
  double anchor_t_ = 0.0;
  // target_not_seen: when the target was last in the image (or the approach began)
  bool have_seen_ = false;
  double seen_t_ = 0.0;
};

}  // namespace ehc_control
