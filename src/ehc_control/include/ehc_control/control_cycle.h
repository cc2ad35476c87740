#pragma once
// ControlCycle: THE control cycle of EHC-MM (DESIGN.md sections 6-9), ROS-free. One object owns
// the whole-body model, the EHC QP (EhcQpController), the servo (proportional NEO p_servo, or
// ViSP PBVS with or without MPBS), the TargetTracker (TfM), the ControllerSupervisor (input
// validation and freshness watchdog), the roll joint and the watched target centre. Callers
// (ehc_controller_node, the Exp-1 runner, tests, benches) feed it inputs stamped with their
// time (sim or ROS seconds) and call update(now) once per cycle:
//
//   watchdog decision -> TfM bookkeeping -> sig(omega) -> servo -> QP step -> status (with the
//   cycle's motion limit, MotionLimitMonitor)
//
// The command is never NaN/Inf and all zeros unless the QP ran and succeeded. Core errors
// inside the cycle stop the robot (STOPPED, reason "controller error: ...") instead of throwing.

#include "ehc_control/control_status.h"
#include "ehc_control/controller_supervisor.h"
#include "ehc_control/ehc_weighting.h"
#include "ehc_control/motion_limit.h"
#include "ehc_control/mpbs.h"
#include "ehc_control/pose_servo.h"
#include "ehc_control/qp_controller.h"
#include "ehc_control/reach_recovery.h"
#include "ehc_control/target_tracker.h"
#include "ehc_control/whole_body_model.h"

#include <Eigen/Geometry>

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace ehc_common {
class ConfigNode;
}  // namespace ehc_common

namespace ehc_control {

enum class ServoType { Proportional, Pbvs };
std::string toString(ServoType type);
ServoType servoTypeFromString(const std::string& s);  ///< throws "[ControlCycle] ..."

/// Every section of controller.yaml the cycle uses (defaults in each struct's header).
struct ControlCycleParams {
  std::string robot_file;                   ///< robot.yaml (resolved path): key `robot`
  QpControllerParams controller;            ///< section `controller`
  EhcWeightingParams weighting;             ///< section `weighting`
  ServoType servo_type = ServoType::Proportional;  ///< `servo.type`: proportional | pbvs
  PoseServoParams servo;                    ///< section `servo` (proportional law)
  PbvsServoParams pbvs;                     ///< section `servo` (pbvs law)
  MpbsParams mpbs;                          ///< section `mpbs` (with servo pbvs)
  TargetTrackerParams tracking;             ///< section `tracking`
  double centre_timeout = 1.0;              ///< s, `tracking.centre_timeout`: older watched centres are ignored
  SupervisorParams watchdog;                ///< section `watchdog`
  MotionLimitParams motion_limit;           ///< section `motion_limit`
  void validate() const;                    ///< throws "[ControlCycleParams] ..." (and the sections' own)
};
/// Reads the whole controller.yaml (`root`); `robot` defaults to the RealMan robot.yaml next to
/// it and is resolved against the file's folder. Unknown sections (e.g. `node`) are ignored.
ControlCycleParams loadControlCycleParams(const ehc_common::ConfigNode& root);

/// What one cycle did: the fields of /ehc/status (without header). The QP step's figures
/// (errors, omega, sig, base weight, solve time, obstacle rows) are 0 unless the QP ran.
struct ControlCycleStatus : QpStepFigures {
  ControlPhase phase = ControlPhase::Idle;
  std::string reason;                     ///< why the command is zero (watchdog, QP failure, error), else ""
  QpStatus qp_status = QpStatus::NotRun;
  ControlMode mode = ControlMode::Ehc;
  bool target_in_fov = false;             ///< target centre in the image this cycle
  double tfm = 0.0;                       ///< TfM since the target (centre) was set
  double target_age = -1.0;               ///< s since the last good target pose; -1: none
  double state_age = -1.0;                ///< s since the older of joint state / odometry; -1: none
  double obstacles_age = -1.0;            ///< s since the last good obstacle list; -1: none
  /// watchdog.require_obstacles: false = obstacle sensing off (the QP runs without obstacle
  /// dampers whenever no fresh list is in), said in every status, never silently.
  bool obstacles_required = true;
  bool controller_error = false;          ///< a core error (exception) stopped this cycle
  bool wrist_flip = false;                ///< the QP step prescribed a wrist flip (WristFlip)
  bool recovering = false;                ///< the QP tracked a stall recovery's reference (ReachRecovery)
  /// What holds the robot back this cycle (MotionLimitMonitor; none without joint state and odometry).
  MotionLimitReport motion_limit;
};

struct ControlCycleOutput {
  Eigen::VectorXd velocity;  ///< [base twist (x, [y,] yaw); arm joint rates]; zeros unless the QP ran OK
  ControlCycleStatus status;
  std::string event;         ///< log-worthy, e.g. "new target centre [...]: TfM restarts"; "" if none
};

class ControlCycle {
 public:
  /// Loads params.robot_file, its reachability map (if robot.yaml names one; checked against
  /// the robot) and the tracking camera. Throws std::invalid_argument on a bad configuration.
  explicit ControlCycle(const ControlCycleParams& params);
  /// With a model and an EHC weighting (nullptr: none) built by the caller.
  ControlCycle(std::shared_ptr<const WholeBodyModel> model, std::shared_ptr<const EhcWeighting> weighting,
               const ControlCycleParams& params);

  // Inputs, stamped with their time t (s). Each returns "" if accepted, else why it was
  // rejected (the last good value is kept).
  /// Arm joint positions by name (other names are ignored).
  std::string setJointState(double t, const std::vector<std::string>& names, const std::vector<double>& positions);
  /// Base pose (x, y, yaw) in the world frame.
  std::string setBasePose(double t, const Eigen::Vector3d& base_pose);
  /// Target TCP pose (world). One that differs from the last accepted one starts a new
  /// approach (EhcQpController::reset; the TSMM stage follows the target).
  std::string setTarget(double t, const Eigen::Isometry3d& target);
  /// The point the camera watches and TfM counts (world), when it is not the target's centre
  /// (e.g. the object while the target is a pre-grasp pose). Used while younger than
  /// centre_timeout, else the target's centre (MpbsParams::target_centre) is watched.
  std::string setWatchedCentre(double t, const Eigen::Vector3d& centre);
  /// Link-obstacle pairs (world); used while younger than watchdog.obstacle_timeout.
  std::string setObstacles(double t, const std::vector<ObstaclePair>& obstacles);
  /// Whole-body configurations planned clear of the obstacles for the targets to come (e.g. a
  /// grasp's pre-grasp and grasp): a stall at a target one of them reaches moves there
  /// (ReachRecovery::setGivenPlans, which throws for a malformed plan); empty: none.
  void setGivenPlans(std::vector<ReachRecovery::GivenPlan> plans) { recovery_->setGivenPlans(std::move(plans)); }

  /// One control cycle at time `now`. With a clock (setClock), the cycle's duration and the
  /// watchdog are checked again at the clock's time after the QP solve: a cycle longer than
  /// watchdog.max_solve_time gives zeros and QP_FAILED; a command computed from a state, target
  /// or obstacle list that went stale during the cycle is replaced by zeros (phase and reason
  /// of that check, prefixed "after the ... s cycle").
  ControlCycleOutput update(double now);
  /// The time source of the after-solve check (the node: ROS time; tests: a fake clock). An
  /// empty function: no after-solve check (time stands still during a cycle, e.g. lock-step).
  using Clock = std::function<double()>;
  void setClock(Clock clock) { clock_ = std::move(clock); }
  /// A zero command with phase STOPPED, `reason`, and the inputs' ages at `now`: what the
  /// node's watchdog publishes when no cycle ran (e.g. lock-step without state).
  ControlCycleOutput stopped(double now, const std::string& reason) const;

  /// Multi-line start-up summary of the robot, map, controller, servo, roll joint, tracking and
  /// watchdog.
  std::string summary() const;

  // The parts, for logging and for benchmarks that time them one by one.
  const ControlCycleParams& params() const { return params_; }
  const WholeBodyModel& model() const { return *model_; }
  const std::shared_ptr<const WholeBodyModel>& modelPtr() const { return model_; }
  const EhcQpController& controller() const { return *controller_; }
  MpbsServo& mpbsServo() { return *mpbs_; }
  const TargetTracker& tracker() const { return *tracker_; }
  const ControllerSupervisor& supervisor() const { return *supervisor_; }
  const MotionLimitMonitor& motionLimits() const { return *limits_; }
  /// Index of the arm joint that rolls the TCP (findRollJoint), -1 if none.
  int rollJointIndex() const { return roll_index_; }
  /// That joint at arm configuration q, for the servo's roll unwinding (none without one).
  std::optional<RollJoint> rollJointAt(const Eigen::VectorXd& q) const;
  /// Pose of the camera optical frame in the TCP frame (URDF, at the ready pose).
  const Eigen::Isometry3d& tcpToCamera() const { return tcp_T_camera_; }
  /// The point the camera watches at `now`: the watched centre while fresh, else the target's.
  Eigen::Vector3d watchedCentre(double now) const;

 private:
  /// Loads the weighting of the model's reachability map.
  ControlCycle(const std::shared_ptr<const WholeBodyModel>& model, const ControlCycleParams& params);
  /// Zero command, mode and input ages at `now` (phase Idle, no reason).
  ControlCycleOutput zeroOutput(double now) const;
  /// Servo + QP for the supervisor's current state and target.
  ControllerCommand step(double now);
  /// The cycle's motion limit into out->status (after the command is final).
  void reportMotionLimit(double now, const Vector6d* slack, double manipulability, ControlCycleOutput* out);

  ControlCycleParams params_;
  std::shared_ptr<const WholeBodyModel> model_;
  std::shared_ptr<const EhcWeighting> weighting_;  ///< nullptr: no reachability map
  std::unique_ptr<EhcQpController> controller_;
  std::unique_ptr<ReachRecovery> recovery_;
  std::unique_ptr<ControllerSupervisor> supervisor_;
  std::unique_ptr<MotionLimitMonitor> limits_;
  /// The last cycle's motion limit was an obstacle (a link held at its stop distance): not a free stall.
  bool obstacle_held_ = false;
  std::unique_ptr<MpbsServo> mpbs_;
  std::unique_ptr<TargetTracker> tracker_;
  Eigen::Isometry3d tcp_T_camera_ = Eigen::Isometry3d::Identity();
  int roll_index_ = -1;
  bool have_target_ = false;
  Eigen::Isometry3d last_target_ = Eigen::Isometry3d::Identity();
  Eigen::Vector3d centre_ = Eigen::Vector3d::Zero();
  std::optional<double> t_centre_;
  Clock clock_;
};

}  // namespace ehc_control
