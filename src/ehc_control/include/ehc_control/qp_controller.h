#pragma once
// EhcQpController: the whole-body QP of DESIGN.md section 6 (paper eq. 6-13), solved through the
// QpSolver interface (qp_solver.h; by default DualActiveSetQp, the Goldfarb-Idnani dual active
// set of dual_active_set_qp.h) with an iteration limit, after eliminating the slack
// delta = nu_e - J_e qd (see step()).
//
//   x = [qd_base; qd_arm; delta]            (delta in R^6: slack of the end-effector task)
//   min 1/2 x^T Q x + C^T x
//   s.t. [J_e  I_6] x = nu_e                 (J_e: 6 x n whole-body Jacobian of the TCP, world)
//        A_in x <= b_in                      (joint-position and obstacle velocity dampers)
//        x- <= x <= x+                       (velocity limits, slack bound)
//   Q = blkdiag(w_base I, w_arm I, 1/max(|e|, e_min) I_6)
//   C = [0 .. -k_eps b (w_z column); -k_m J_m + (k_p + f k_p,far) (q - q_ready) + dV_lim/dq; 0]
//   b: bearing in the base frame of TCP + f (target - TCP), f the far fraction (the TCP's near
//      the target, the target's far from it; FarApproachParams), on the 2 pi branch nearest the winding of
//      the arm's yaw joint (q_yaw - q_yaw,ready), so that turning towards the TCP unwinds it;
//      with the TCP over the shoulder (> 90 deg from the yaw joint's direction) on the previous
//      cycle's branch (no 2 pi flips from noise at the branch border)
//   V_lim: joint-limit centring potential (JointLimitCentring)
//
// Modes (one parameter): ehc  w_base = w_min + (w_max - w_min) sig(omega)
//                        ehc_place  ehc, and the base's goal chosen per target by inverse
//                              reachability (ReachRecovery's placement, reach_recovery.h,
//                              run by ControlCycle): while sig(omega) is below the hand-over
//                              level the QP tracks the drive to that base pose, then ehc
//                        neo_e w_base = w_arm / |e|        (NEO: base weight 1/|e|)
//                        neo_c w_base = constant
//                        tsmm  base only (arm held) until the TCP is within d of the target
//                              horizontally, then arm only (base held, command exactly 0) for
//                              as long as the target stays within d (horizontally) of where it
//                              was at the switch: the base stands at its grasping position
//                              while the goal moves (pre-grasp, grasp, lift, perception updates);
//                              a target farther away drives the base again (paper: TSMM).
// A failed, infeasible, non-finite or over-iteration-limit solve gives a zero command and qp_status QP_FAILED (the
// time budget: ControlCycle, watchdog.max_solve_time); the command never contains NaN/Inf and
// never exceeds a velocity limit. The obstacle rows are bounded (max_obstacle_rows, nearest pairs first). ROS-free.

#include "ehc_control/control_status.h"
#include "ehc_control/ehc_weighting.h"
#include "ehc_control/qp_solver.h"
#include "ehc_control/reach_recovery.h"
#include "ehc_control/whole_body_model.h"
#include "ehc_control/wrist_flip.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace ehc_common {
class ConfigNode;
}  // namespace ehc_common

namespace ehc_control {

using Vector6d = Eigen::Matrix<double, 6, 1>;

enum class ControlMode { Ehc, EhcPlace, NeoE, NeoC, Tsmm };
std::string toString(ControlMode m);
/// The modes whose base weight is sig(omega) (ehc, ehc_place): they need an EhcWeighting.
inline bool usesWeighting(ControlMode m) { return m == ControlMode::Ehc || m == ControlMode::EhcPlace; }
ControlMode controlModeFromString(const std::string& s);  ///< throws std::invalid_argument

/// The far approach (every mode; section `far_approach`): while the TCP is farther than
/// `distance` from the target, a far fraction f = clamp(|e_p| / distance - 1, 0, 1) (0 within
/// `distance`, 1 beyond twice it) leads the base and carries the arm:
///  - face_target: the turn term's bearing is that of TCP + f (target - TCP): the target's while
///    far, the TCP's (paper, NEO) within `distance`. The TCP bearing says where to go only while
///    the arm reaches towards the target; a folded or pinned arm holds the TCP near the base's
///    axis, and a differential base then drives past a target lying metres to its side.
///  - posture_gain: k_p + f posture_gain pulls the arm towards its ready posture, so that it is
///    carried comfortably while the base drives instead of stretching towards the target (the
///    base cannot keep pace with the TCP task far away) into joint stops it later arrives from.
/// The ramp is in the TCP's distance, not sig(omega): omega, measured along e from the arm base,
/// stays ~0 when the TCP has passed a target that lies behind or below it.
struct FarApproachParams {
  double distance = 1.0;       ///< m: the far fraction is 0 within this TCP-target distance, 1 beyond twice it
  bool face_target = true;     ///< the turn term faces the target while far (false: the TCP always)
  double posture_gain = 0.05;  ///< added to posture_gain times the far fraction; 0 = off
  /// The TCP orientation rows of the task are weighed by 1 - f orientation_release: 0 keeps the
  /// servo's orientation (MPBS: looking at the target) while far, 1 leaves it to the posture.
  double orientation_release = 0.8;
  /// The far fraction for a TCP-target distance (m).
  double fraction(double position_error) const {
    return std::clamp(position_error / distance - 1.0, 0.0, 1.0);
  }
  void validate() const;       ///< throws "[FarApproachParams] ..."
  std::string summary() const;
};

struct QpControllerParams {
  ControlMode mode = ControlMode::Ehc;
  double arm_weight = 0.01;            ///< w_arm (NEO's lambda)
  double ehc_base_weight_min = 0.001;  ///< ehc: base weight at sig = 0 (far)
  double ehc_base_weight_max = 1.0;    ///< ehc: base weight at sig = 1 (close)
  double neo_c_base_weight = 0.01;     ///< neo_c: constant base weight
  double min_error = 0.01;             ///< |e| floor in 1/|e| terms (slack and neo_e)
  double slack_bound = 10.0;           ///< |delta_i| bound
  double base_turn_gain = 0.5;         ///< k_eps: turn the base toward the TCP
  /// Take the TCP bearing of the turn term on the branch of the arm yaw joint's winding
  /// (unwoundBearing); false: plain atan2 (paper, NEO), which near +-pi turns the base the way
  /// that winds the yaw joint further into its limit.
  bool base_turn_unwinding = true;
  double manipulability_gain = 1.0;    ///< k_m: weight of -J_m in C
  /// m; > 0: k_m fades linearly to 0 as the TCP comes within this distance of the target.
  /// Near a stretched pose the manipulability gradient is large and, with the 1/|e| slack
  /// weight shrinking the task's pull, can hold the TCP a few cm short of the target (grasping
  /// far over a table). 0 (default, the paper's formulation): constant k_m.
  double manipulability_fade_distance = 0.0;
  /// Auxiliary task in C (paper: "C incorporates manipulability maximisation and auxiliary
  /// performance tasks"): a weak pull of the arm towards its ready posture,
  /// C_arm += k_p (q - q_ready), which keeps the joints away from their limits.
  double posture_gain = 0.001;
  /// Joint-limit centring (JointLimitCentring, joint_limit_centring.h): C_arm += dV/dq of a
  /// potential that is 0 at joint_influence and has slope limit_centring_gain at joint_stop,
  /// so that joints leave the damper zone while the task (or the base) allows it, instead of
  /// being pinned there by their damper. 0 = off.
  double limit_centring_gain = 0.1;
  /// Section `far_approach`: how the robot travels while the target is metres away (FarApproach).
  FarApproachParams far_approach;
  /// Section `wrist_flip`: the joint-limit escape above the QP (WristFlip, wrist_flip.h): a
  /// spherical-wrist roll joint nearing its limit moves to the other wrist branch (same TCP
  /// pose) while the base and the other joints keep the TCP position task.
  WristFlipParams wrist_flip;
  /// Section `recovery`: the joint-limit stall recovery of the control cycle (ReachRecovery,
  /// reach_recovery.h): after a stall with a joint pinned, a whole-body configuration with wide
  /// joint margins from IK, tracked through this QP as a reference velocity (step()'s `reference`).
  ReachRecoveryParams recovery;
  double joint_influence = 0.9;        ///< rad: joint damper becomes active
  double joint_stop = 0.1;             ///< rad: closest allowed approach to a joint limit
  double joint_damper_gain = 1.0;      ///< xi of the joint dampers, 1/s
  double obstacle_influence = 0.3;     ///< m: d_i
  double obstacle_stop = 0.05;         ///< m: d_s (= S of the paper)
  /// Per-link d_s overriding obstacle_stop, e.g. the hand links, which must come close to the
  /// support surface of the object they grasp (each must stay below obstacle_influence).
  /// Robot-specific, so not read from controller.yaml: EhcQpController adds robot.yaml's
  /// robot.obstacle_stop_distances (entries set here win); a link the URDF lacks is an error.
  std::map<std::string, double> obstacle_stop_links;
  double obstacleStop(const std::string& link) const {
    const auto it = obstacle_stop_links.find(link);
    return it == obstacle_stop_links.end() ? obstacle_stop : it->second;
  }
  double obstacle_damper_gain = 1.0;   ///< xi of the obstacle dampers, 1/s
  /// 1/s: a pair closer than its d_s must open at least at this rate x (d_s - d), or at the
  /// damper's own xi (d_s - d) / (d_i - d_s) if that is faster. The damper alone lets a link
  /// held at d_s (the damper active, the task pulling the link on) back out at only 3.7/s x the
  /// depth (xi 1, d_i - d_s 0.27 m), while actuation noise (Table I's base noise moves a wrist
  /// link by about 7 cm/s per 10 ms step) keeps pushing it in: a link held at d_s then sits
  /// inside it by a few mm (a random walk pulled back at the recovery rate: its spread falls
  /// with the square root of the rate). 0 = the damper alone.
  double obstacle_recovery_gain = 20.0;
  /// (0, 1]: a pair's demanded opening rate (recovery or damper) is at most this share of the
  /// fastest its DOFs can open it within their velocity bounds. A link found deep inside d_s
  /// (an obstacle first seen there: a table's face the camera had not looked at) asked more
  /// than the robot can do: the QP was infeasible, the command zero, and so the next cycle's,
  /// for good. The share below 1 leaves the other rows and the task room.
  double obstacle_recovery_share = 0.5;
  /// At most this many obstacle damper rows per QP: of the pairs within obstacle_influence,
  /// the nearest (smallest distance - d_s) are kept, the rest dropped for this cycle. Bounds
  /// the build (one link Jacobian per row) and the solve whatever the obstacle node sends.
  int max_obstacle_rows = 24;
  /// At most this many active-set iterations (constraint additions and removals) per solve
  /// (DualActiveSetQp): a degenerate problem could make an active-set method revisit active
  /// sets (ViSP's vpQuadProg, used before, cycled forever on one); at the limit the cycle fails
  /// safely (zero command, QP_FAILED). Normal solves take 0 to about 15.
  int max_qp_iterations = 200;
  /// QP back end, by name (makeQpSolver, qp_solver.h): "dual_active_set" (DualActiveSetQp).
  std::string qp_solver = "dual_active_set";
  double tsmm_switch_distance = 0.2;   ///< m: tsmm switches to the arm stage here
  double arrival_position = 0.01;      ///< m
  double arrival_orientation = 2.0 * M_PI / 180.0;  ///< rad
  void validate() const;               ///< throws "[QpControllerParams] ..."
  std::string summary() const;
};
QpControllerParams loadQpControllerParams(const ehc_common::ConfigNode& node);

/// One link-obstacle closest-point pair (world frame). normal: unit, obstacle -> link.
struct ObstaclePair {
  std::string link;
  Eigen::Vector3d link_point = Eigen::Vector3d::Zero();
  Eigen::Vector3d obstacle_point = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double distance = 0.0;
};

/// What one QP step measured and chose (reported per cycle in /ehc/status).
struct QpStepFigures {
  double position_error = 0.0;        ///< m
  double orientation_error = 0.0;     ///< rad
  double error_norm = 0.0;            ///< sum |[dp; theta u]| (NEO's e_t)
  double omega = 0.0;
  double sig = 0.0;                   ///< sig(omega)
  double base_weight = 0.0;
  double solve_time_us = 0.0;         ///< QP build + solve
  int qp_iterations = 0;              ///< active-set steps of the solve (<= max_qp_iterations)
  int obstacle_rows = 0;
};

struct ControllerCommand : QpStepFigures {
  Eigen::VectorXd velocity;  ///< [base twist; arm rates]; all zero unless ok
  Vector6d slack = Vector6d::Zero();
  /// The arm's manipulability at the step's state (from the step's TCP Jacobian); < 0 when the
  /// step stopped before its kinematics (bad input).
  double manipulability = -1.0;
  bool ok = false;
  QpStatus qp_status = QpStatus::NotRun;        ///< Ok | Failed after step()
  ControlPhase phase = ControlPhase::Tracking;  ///< Tracking | Arrived | TsmmBase | TsmmArm
  std::string failure;                          ///< reason when qp_status == QpStatus::Failed
  int joint_damper_rows = 0;
  bool wrist_flip = false;                      ///< the arm's wrist rates were prescribed (WristFlip)
  bool recovering = false;                      ///< a stall recovery's reference was tracked (ControlCycle)
  /// Infeasible with the pairs inside d_s opening (two of them on opposite sides of the hand,
  /// or one against a joint damper): solved again with those pairs held, none approaching.
  bool obstacles_held = false;
  std::string event;                            ///< log-worthy, e.g. a wrist flip started; else ""
};

/// Index of the arm joint whose axis is the base's vertical axis at the ready pose (the arm's
/// yaw, e.g. joint1 of the RM65-B), -1 if none.
int armYawJoint(const WholeBodyModel& model);
/// `bearing` (rad) shifted by multiples of 2 pi into (winding - pi, winding + pi]: the branch
/// of the TCP bearing that continues the arm yaw joint's winding.
double unwoundBearing(double bearing, double winding);

/// Pose error of the TCP to the target: [t* - t; theta u of R* R^T], world frame.
Vector6d poseError(const Eigen::Isometry3d& tcp, const Eigen::Isometry3d& target);

class EhcQpController {
 public:
  /// `weighting` is required for mode ehc (and reported for the others when given).
  EhcQpController(std::shared_ptr<const WholeBodyModel> model, const QpControllerParams& params,
                  std::shared_ptr<const EhcWeighting> weighting);
  ~EhcQpController();

  /// One control cycle: state (base pose x, y, yaw; arm q), target TCP pose (world), desired
  /// TCP twist nu_e (world, [v; w]) and the obstacle pairs. Never throws for bad numbers:
  /// returns a zero command with qp_status QP_FAILED and the reason.
  /// `weight`: sig(omega) of this cycle if the caller already evaluated it (weight(), e.g. for
  /// MPBS), else it is evaluated here.
  /// `reference` (size nDof, [base twist; arm rates]): a whole-body velocity to track instead
  /// of the servo (ReachRecovery): the task becomes nu_e = J reference and the linear cost
  /// -h o reference (h: the cost diagonal), so the optimum is the reference itself wherever the
  /// bounds, joint dampers and obstacle dampers allow it; no wrist flip starts meanwhile.
  ControllerCommand step(const Eigen::Vector3d& base_pose, const Eigen::VectorXd& q,
                         const Eigen::Isometry3d& target, const Vector6d& nu_e,
                         const std::vector<ObstaclePair>& obstacles = {},
                         const EhcWeight* weight = nullptr, const Eigen::VectorXd* reference = nullptr);

  /// The EHC weighting of a TCP position towards a target position (both world frame) for the
  /// base pose, exactly as step() evaluates it. Throws "[EhcQpController] ..." without a
  /// weighting (hasWeighting()) or for non-finite input.
  EhcWeight weight(const Eigen::Vector3d& base_pose, const Eigen::Vector3d& tcp_world,
                   const Eigen::Vector3d& target_world) const;
  bool hasWeighting() const { return static_cast<bool>(weighting_); }

  /// New target. The QP keeps nothing between cycles (each solve starts from the unconstrained
  /// minimum); the TSMM stage follows the target in step() (see above).
  void reset();
  const QpControllerParams& params() const { return params_; }
  void setMode(ControlMode m);
  const WholeBodyModel& model() const { return *model_; }
  const WristFlip& wristFlip() const { return *flip_; }
  /// The QP back end (made from params().qp_solver).
  const QpSolver& qpSolver() const;
  /// Replaces the QP back end (e.g. a packaged solver, or a test double); throws
  /// std::invalid_argument "[EhcQpController] ..." for a null solver.
  void setQpSolver(std::unique_ptr<QpSolver> solver);

  /// The obstacle pairs step() turns into rows: those within obstacle_influence, nearest
  /// (distance - d_s) first, at most max_obstacle_rows. A non-finite, zero-normal or
  /// unknown-link pair sets `bad_pair` (the reason) and returns none.
  std::vector<const ObstaclePair*> nearestObstaclePairs(const std::vector<ObstaclePair>& obstacles,
                                                        std::string* bad_pair) const;
  /// The same into a caller-owned list (step() reuses one: no allocation per cycle). `ranked`
  /// holds (distance - d_s, pair) of the chosen pairs, nearest first.
  void nearestObstaclePairs(const std::vector<ObstaclePair>& obstacles,
                            std::vector<std::pair<double, const ObstaclePair*>>* ranked, std::string* bad_pair) const;

 private:
  /// The QP solver and every per-cycle matrix (qp_controller.cpp).
  struct Workspace;
  /// DOF groups a mode holds out of the QP this cycle (tsmm stages).
  struct HeldGroups {
    bool base = false, arm = false;
  };
  ControllerCommand fail(ControllerCommand c, const std::string& why) const;
  // The stages of step(), in order; a std::string result is the failure ("" = none).
  /// One FK pass: TCP pose (returned), whole-body Jacobian, manipulability and its gradient.
  Eigen::Isometry3d updateKinematics(const Eigen::Vector3d& base_pose, const Eigen::VectorXd& q,
                                     double* manipulability);
  /// omega and sig(omega) of this cycle (given, evaluated, or none without a weighting).
  void reportWeighting(const Eigen::Vector3d& base_pose, const Eigen::Isometry3d& T_tcp,
                       const Eigen::Isometry3d& target, const EhcWeight* weight, ControllerCommand* out) const;
  /// The mode's base weight and held groups (tsmm stage switch), and the arrival phase.
  HeldGroups applyMode(const Vector6d& e, const Eigen::Isometry3d& target, double e_floor, ControllerCommand* out);
  /// The turn term's bearing in the base frame: of the TCP, led towards the target far from it
  /// (far_approach.face_target; `target_in_base`: the target position in the base frame, `far`
  /// the far fraction), unwound (base_turn_unwinding).
  double turnBearing(const Eigen::VectorXd& q, const Eigen::Vector3d& target_in_base, double far);
  /// Cost diagonal h and linear term c of [qd; delta].
  void buildCost(const Eigen::VectorXd& q, const Eigen::Vector3d& target_in_base, double e_floor,
                 const ControllerCommand& out, const Eigen::VectorXd* reference);
  /// Velocity and slack bounds, the held variables, the joint dampers as tightened bounds.
  std::string buildBounds(const Eigen::VectorXd& q, const HeldGroups& held, ControllerCommand* out);
  /// Obstacle damper rows (nearest pairs first, parallel rows merged).
  std::string buildObstacleRows(const std::vector<ObstaclePair>& obstacles, ControllerCommand* out);
  /// WristFlip: prescribes the wrist triple's rates (held) when a flip runs; true then.
  bool applyWristFlip(const Eigen::VectorXd& q, const HeldGroups& held, bool may_run, ControllerCommand* out);
  /// The free DOFs, the task rows over them and the QP's cost G, g (slack eliminated).
  /// `orientation_scale` weighs the orientation rows (1: the task; 0: released to the slack,
  /// tsmm base stage and wrist flip; between: the far approach).
  void buildTaskAndCost(const Vector6d& nu_e, double orientation_scale);
  /// The QP's inequality rows C, d (bounds, slack bounds, obstacle dampers); returns their count.
  int buildInequalities();
  /// Builds the inequalities and solves; when infeasible with obstacle rows demanding an opening,
  /// holds those rows (no approach: the zero command is feasible for them) and solves again
  /// (out->obstacles_held). Throws std::invalid_argument for a cost that is not positive definite.
  QpSolveResult solveQp(ControllerCommand* out);
  /// The command from the QP solution: held values, slack, bounds check and clamp.
  std::string assembleCommand(ControllerCommand* out);

  std::shared_ptr<const WholeBodyModel> model_;
  QpControllerParams params_;
  std::shared_ptr<const EhcWeighting> weighting_;
  Eigen::Isometry3d base_T_arm_;
  Eigen::VectorXd vmax_;
  bool tsmm_arm_stage_ = false;
  /// Arm joint turning about the base's vertical axis (e.g. joint1), -1 if none: the base-turn
  /// term takes the TCP bearing on the branch of this joint's winding (see step()).
  int yaw_joint_ = -1;
  double last_bearing_ = 0.0;  ///< the turn term's unwound TCP bearing of the previous step
  bool have_bearing_ = false;
  Eigen::Vector3d tsmm_stage_target_ = Eigen::Vector3d::Zero();  ///< target position at the arm-stage switch
  std::unique_ptr<Workspace> ws_;
  std::unique_ptr<WristFlip> flip_;
};

}  // namespace ehc_control
