#pragma once
// ReachRecovery: the way out of a joint-limit stall, from whole-body inverse kinematics. ROS-free.
//
// The trap (Exp-1 traces, targets approached from any side, every method): the QP follows the
// local gradient of the pose task; the arm takes the orientation the short way and a joint
// (the RM65's wrist bend most often) ends at its stop. What is left of the error then needs a
// motion the remaining joints cannot make without moving the pinned one, e.g. a sideways shift
// of a differential base, which it can only make by driving forwards and backwards while
// turning. No single reactive step does that: the command settles at a few mm/s, the TCP 1-30
// cm short, with or without actuation noise. Linear secondary terms towards an IK posture
// (tried) only add equilibria. Yet with a mobile base, every target that whole-body IK reaches
// inside the joint stops can be reached with wide joint margins: the base can stand elsewhere.
//
// ReachRecovery watches the approach and, when it stalls with a joint pinned, looks further:
//   detect   no progress (position_progress, orientation_progress; with a joint pinned near
//            the target also pinned_progress_fraction of the error: traces, RealMan `any`, two
//            joints at their stops, the base turning, the error crept from 20 to 7 cm over 11 s,
//            its time constant ~10 s against the servo's 0.7 s, above 5 mm per 2 s until the
//            time limit was near) for stall_window s, not
//            arrived, and an arm joint within pinned_margin of its joint stop or the target
//            farther than twice the ready pose's reach (the base is not bringing the arm there),
//            or (free_stalls) near the target with every joint free and no link held at an
//            obstacle: the pose task's own equilibrium, or with a given plan of the target
//            (setGivenPlans) any near stall, also one with a link held at an obstacle. Traces (far approach, targets 70-150 deg
//            off the heading, RealMan): the base arrives facing the target with the hand 2.3-3
//            rad from the grasp orientation; the QP then settles 0.2-0.3 m short in a limit
//            cycle of period 4 cycles (base yaw rate +-0.4 rad/s, the wrist +-1.3 rad/s, every
//            joint 0.9 rad or more from its limit), the 1/|e| slack weight low with the
//            orientation error large, the manipulability and turn terms holding the arm. The
//            plan below puts the base on the target's other side;
//   plan     far from the target (beyond twice the ready pose's reach) the arm unwinds to its
//            ready posture while the base drives to where the ready TCP is over the target
//            (readyOver; traces: far stalls came from a base turned to rotate the hand, the
//            arm in its dampers' zone, unable to absorb the turn back; from ready the base
//            turns and drives at once); near it with a given plan of the target
//            (setGivenPlans: a configuration planned clear of the obstacles, e.g. the grasp
//            choice's reach check beside a table), that plan (traces, Exp-2 back-slot objects: a
//            differential base arrives at the table edge 30 cm beside the placement the grasp
//            needs, a link held at the table, and no reactive step shifts it sideways); else
//            near it, whole-body IK (WholeBodyModel::inverseKinematicsFrom) from `starts` starts, a few
//            per cycle: the current configuration, the current base with the ready posture,
//            then base placements around the target, the ready TCP over it; the solution with
//            the best min(margin, joint_influence) - travel_weight x travel is taken (a joint
//            whose range spans more than a turn at its widest equivalent, widestTurn). Any
//            solution will do, even one near a stop: it is a configuration of the target
//            itself inside the stops, which the stalled pose task was not finding;
//            (IK steps leave out a joint at its bound that they would push beyond it, so that
//            a target whose configurations all have a joint at its stop converges from the
//            stalled configuration next to it); when no start converges, WholeBodyModel::inverseKinematics from 30 random seeds
//            (the check that admits Exp-1's targets; one longer cycle, once per stall);
//   move     a whole-body reference velocity towards that configuration (b*, q*), tracked
//            through the QP (EhcQpController::step's `reference`: joint dampers, obstacle
//            dampers and velocity limits still apply): arm joint_gain (q* - q); base a
//            pose-stabilising law (differential: the polar law of Astolfi, forwards or
//            backwards; holonomic: proportional);
//   finish   a near move at the tolerances of (b*, q*) with the TCP still off the target: once,
//            the arm's configuration of the target from the base where it stands (IK, base
//            held), tracked by the arm alone; where there is none (a target whose every
//            configuration has a joint at its stop: a base a few cm off b* leaves the arm
//            none), the whole-body one with the base moving as it can without manoeuvres
//            (differential: straight along its heading while turning; holonomic: freely),
//            until the TCP is on the target or within a tenth of the tolerances of it;
//   resume   within the tolerances of (b*, q*), where the TCP is on the target, or after
//            move_timeout (a far move: plus its travel at the base's speed limit); the pose
//            task takes over again. At most max_attempts near and
//            max_attempts far plans per target.
// Every method gets it (it acts only after a stall, when the method has failed to make
// progress), so comparisons between methods stay fair and nothing costs time when no stall occurs.
//
// Placement (mode ehc_place only; update() given this cycle's EHC weight): the same plan and
// move, started at once for every new target instead of after a stall, from starts ranked by
// inverse reachability: base poses on rings around the target (placement_bearings bearings,
// radii of 0.4-1.0 times the farthest horizontal reach of r_td from the arm base, headings that
// put the ready TCP's bearing on the target and +-0.3 rad beside it), each scored by the map's R
// of the target in the arm base frame at that pose; per bearing the best (R, then a differential
// base's travel: distance and turns), bearings in order of their best R. IK from
// each with the base held at it (the arm alone: the pose keeps its R), then from the best ones
// again with the base free. Of the solutions one with a joint margin of placement_margin wins
// over one without (traces: a base under the target, r_td all round, left the arm folded near
// its stops), then one whose target voxel is in the map's high-reachability set r_td, then the
// least travel (margins beyond placement_margin count no more). The move hands over to the pose task
// (EHC's sig(omega) split) when sig reaches placement_handover_sig, at its goal, or at its
// time limit (move_timeout plus the travel at the base's speed limit). Not an attempt.

#include "ehc_control/ehc_weighting.h"
#include "ehc_control/whole_body_model.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace ehc_common {
class ConfigNode;
}  // namespace ehc_common

namespace ehc_control {

struct ReachRecoveryParams {
  bool enabled = true;
  double stall_window = 2.0;                         ///< s without progress
  double position_progress = 0.005;                  ///< m: a smaller drop of the error is no progress
  double orientation_progress = 1.0 * M_PI / 180.0;  ///< rad
  /// Near the target with a joint pinned, a drop smaller than this fraction of the error is no
  /// progress either (a creep into the trap's equilibrium; 0 = the absolute thresholds alone).
  double pinned_progress_fraction = 0.25;
  double pinned_margin = 0.05;                       ///< rad beyond the joint stop: a joint this close is pinned
  int starts = 24;                                   ///< IK starts per plan
  int starts_per_cycle = 2;                          ///< IK solves per control cycle while planning
  double travel_weight = 0.2;                        ///< rad of margin per m of base travel when choosing
  double joint_gain = 1.0;                           ///< 1/s
  double base_gain = 1.0;                            ///< 1/s: k_rho (differential), position gain (holonomic)
  double heading_gain = 3.0;                         ///< 1/s: k_alpha (differential), yaw gain (holonomic)
  double final_heading_gain = -1.5;                  ///< 1/s: k_beta (differential), < 0
  /// The move ends this close to (b*, q*): the pose task, whose target (b*, q*) reaches, finishes.
  double position_tolerance = 0.05;                  ///< m
  double yaw_tolerance = 8.0 * M_PI / 180.0;         ///< rad
  double joint_tolerance = 0.1;                      ///< rad
  double move_timeout = 10.0;                        ///< s
  int max_attempts = 2;                              ///< per target
  /// Near stalls with every joint free (and no link held at an obstacle) plan too.
  bool free_stalls = true;
  /// Placement (ehc_place): bearings around the target of the candidate base poses.
  int placement_bearings = 16;
  /// Placement: the move hands over to the pose task once sig(omega) reaches this (1: only at its goal).
  double placement_handover_sig = 0.9;
  /// Placement: rad of joint margin that is enough; among the placements with it, the least travel.
  double placement_margin = 0.3;
  void validate() const;                             ///< throws "[ReachRecoveryParams] ..."
  std::string summary() const;
};
/// Section `recovery` of the controller section (defaults for absent keys).
ReachRecoveryParams loadReachRecoveryParams(const ehc_common::ConfigNode& node);

/// The bearing (rad) of the ready posture's TCP in the base frame.
double readyTcpBearing(const WholeBodyModel& model);
/// The base pose (x, y, yaw) `radius` from `target` at `angle` (world, seen from the target),
/// turned so that the ready posture's TCP, at `ready_bearing` in the base frame, points at the
/// target: the placements of ReachRecovery and of the grasp choice's reach check.
Eigen::Vector3d placementFacing(const Eigen::Vector2d& target, double angle, double radius, double ready_bearing);

class ReachRecovery {
 public:
  enum class State { Watching, Planning, Moving };

  /// `joint_stop`: the controller's joint stop (IK solutions keep it, pins are measured from it);
  /// `joint_influence`: margins beyond it count no more when choosing.
  ReachRecovery(const WholeBodyModel& model, const ReachRecoveryParams& params, double joint_stop,
                double joint_influence);

  /// Per control cycle at time `now` (s), before the QP: the state, the TCP pose and the target.
  /// Returns the whole-body reference velocity while moving (size nDof), else nullptr.
  /// `place`: this cycle's EHC weight in mode ehc_place (a new target starts a placement, see
  /// the top of this file; needs setPlacementMap()), nullptr otherwise. `obstacle_held`: a
  /// link is held at its obstacle stop distance (MotionLimit::Obstacle): not a free stall.
  const Eigen::VectorXd* update(double now, const Eigen::Vector3d& base_pose, const Eigen::VectorXd& q,
                                const Eigen::Isometry3d& tcp, const Eigen::Isometry3d& target,
                                const EhcWeight* place = nullptr, bool obstacle_held = false);
  /// A new approach: forgets the progress history and the attempts.
  void reset();
  /// The reachability map and its r_td threshold (the EHC weighting) of the placements.
  void setPlacementMap(std::shared_ptr<const EhcWeighting> weighting);
  /// The map's R of the target position in the arm base frame with the base at `base_pose`
  /// (needs setPlacementMap(); throws "[ReachRecovery] ..." otherwise).
  double placementReachability(const Eigen::Isometry3d& target, const Eigen::Vector3d& base_pose) const;
  /// The ranked placement starts for a target seen from `base_pose` (see the top of this file).
  std::vector<Eigen::Vector3d> placementStarts(const Eigen::Isometry3d& target, const Eigen::Vector3d& base_pose) const;
  /// True while a placement (not a stall recovery) is planned or moved to.
  bool placing() const { return place_ && state_ != State::Watching; }
  /// A whole-body configuration (base pose x, y, yaw; arm) known to keep every link clear of
  /// the obstacles, e.g. the one a grasp's reachability check planned for its pre-grasp.
  struct GivenPlan {
    Eigen::Vector3d base = Eigen::Vector3d::Zero();
    Eigen::VectorXd q;
  };
  /// Given plans (none: the default): a near stall at a target one of them reaches (its TCP
  /// within 1 cm and 2 deg of it), also one with a link held at an obstacle, moves to that
  /// configuration instead of planning (see the top of this file). Throws
  /// "[ReachRecovery] ..." for a plan whose arm has the wrong size or is not finite.
  void setGivenPlans(std::vector<GivenPlan> plans);

  State state() const { return state_; }
  int attempts() const { return attempts_; }
  /// "" or what the last update() started or ended (log-worthy).
  const std::string& event() const { return event_; }
  /// The configuration the last plan chose.
  const Eigen::Vector3d& goalBase() const { return goal_base_; }
  const Eigen::VectorXd& goalArm() const { return goal_q_; }
  /// Smallest distance of an arm joint to its limit (rad).
  double margin(const Eigen::VectorXd& q) const;
  /// q with every joint whose range spans more than a turn (a continuous joint given limits
  /// of +-2 pi, a UR joint) moved by whole turns to the equivalent, inside the stops, with the
  /// widest limit margin: the same pose of every link, the most room to move.
  Eigen::VectorXd widestTurn(const Eigen::VectorXd& q) const;

 private:
  void startWatching(double now, double position_error, double orientation_error);
  bool stalled(double now, double position_error, double orientation_error, const Eigen::VectorXd& q,
               bool obstacle_held);
  void startPlanning(const Eigen::Vector3d& base_pose, const Eigen::VectorXd& q, bool far);
  /// The given plan that reaches `target` (setGivenPlans), if any.
  const GivenPlan* givenPlan(const Eigen::Isometry3d& target) const;
  /// A placement plan for target_ (ehc_place): startPlanning from the ranked placement starts.
  void startPlacement(const Eigen::Vector3d& base_pose, const Eigen::VectorXd& q);
  /// The base pose, on the line from `base` to the target, at which the ready pose's TCP is
  /// over the target (facing it as the ready TCP's bearing says).
  Eigen::Vector3d readyOver(const Eigen::Isometry3d& target, const Eigen::Vector3d& base) const;
  void plan(const Eigen::Isometry3d& target);
  /// How the base may move in solve(): freely (x, y, yaw); held (the arm alone); straight along
  /// its heading at the start while turning (what a differential base does without manoeuvres).
  enum class BaseMotion { Free, Held, Straight };
  /// Whole-body IK of `target` from (base, q) with joint-limit avoidance (see the .cpp); true
  /// and the solution in (base, q) when it converges.
  bool solve(const Eigen::Isometry3d& target, Eigen::Vector3d* base, Eigen::VectorXd* q,
             BaseMotion motion = BaseMotion::Free) const;
  void start(int k, const Eigen::Isometry3d& target, Eigen::Vector3d* base, Eigen::VectorXd* q) const;
  void reference(const Eigen::Vector3d& base_pose, const Eigen::VectorXd& q);
  /// Within `scale` x the tolerances of (b*, q*) (an arm-only finish: its joints alone).
  bool atGoal(const Eigen::Vector3d& base_pose, const Eigen::VectorXd& q, double scale = 1.0) const;
  /// At a near move's goal with the TCP still off the target: the goal becomes the arm's IK
  /// configuration from the current base (base held), or where there is none, the whole-body
  /// one with the base moving as it can without manoeuvres (BaseMotion::Straight for a
  /// differential base, Free for a holonomic one); once per move; true then.
  bool finish(const Eigen::Vector3d& base_pose, const Eigen::VectorXd& q, double position_error,
              double orientation_error);

  const WholeBodyModel& model_;
  ReachRecoveryParams params_;
  double joint_stop_ = 0.0, joint_influence_ = 0.0;
  double reach_ = 0.5, ready_bearing_ = 0.0;  ///< the ready pose's TCP in the base frame (horizontal)
  Eigen::Isometry3d T_base_arm_ready_ = Eigen::Isometry3d::Identity();  ///< the arm base at the ready pose
  Eigen::VectorXd vmax_;
  State state_ = State::Watching;
  Eigen::Isometry3d target_ = Eigen::Isometry3d::Identity();
  bool have_target_ = false;
  double best_position_ = 0.0, best_orientation_ = 0.0, progress_t_ = 0.0;
  int attempts_ = 0;      ///< near stalls of this target
  int far_attempts_ = 0;  ///< far stalls of this target (their own count: a far unwind is not a near plan)
  bool far_ = false;      ///< the current plan is a far one
  bool finishing_ = false;  ///< the current near move finishes from where it stands (finish)
  bool finish_base_ = false;  ///< ... with the base moving too
  bool place_ = false;    ///< the current plan is a placement (ehc_place)
  bool given_ = false;    ///< the current plan is a given one (setGivenPlans)
  std::vector<GivenPlan> given_plans_;
  std::vector<Eigen::Isometry3d> given_tcp_;  ///< each given plan's TCP pose (setGivenPlans)
  std::shared_ptr<const EhcWeighting> placement_map_;
  std::vector<Eigen::Vector3d> place_starts_;  ///< the current placement's IK starts
  double goal_reach_ = 0.0;                    ///< the map's R of the target at the chosen placement
  double place_reach_ = 0.5;  ///< m: the farthest horizontal reach of r_td from the arm base (the rings' scale)
  // Planning
  Eigen::Vector3d plan_base_ = Eigen::Vector3d::Zero();
  Eigen::VectorXd plan_q_;
  double plan_margin_ = 0.0;
  int next_start_ = 0;
  int solutions_ = 0;  ///< IK solutions found by the current plan
  bool have_goal_ = false;
  double goal_score_ = 0.0;
  Eigen::Vector3d goal_base_ = Eigen::Vector3d::Zero();
  Eigen::VectorXd goal_q_;
  double goal_margin_ = 0.0;
  // Moving
  double move_t_ = 0.0;
  double move_limit_ = 0.0;  ///< s: move_timeout, plus the travel time of a far move
  Eigen::VectorXd reference_;
  std::string event_;
};

}  // namespace ehc_control
