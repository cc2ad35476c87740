#pragma once
// ReachExperiment: paper Exp-1 (random reaching) in-process, without a ROS master.
// The control cycle (ehc_control::ControlCycle with the proportional servo and the EHC QP)
// drives the noisy KinematicFakeRobot through sequences of target TCP poses, fed with the sim
// time; a target is reached when the TCP is within the arrival tolerance (1 cm, 2 deg) and
// failed after the time limit (30 s); the next target starts from where the last one ended.

#include "ehc_common/json.h"
#include "ehc_control/control_cycle.h"
#include "ehc_sim/kinematic_fake_robot.h"

#include <Eigen/Geometry>

#include <functional>
#include <map>
#include <ostream>
#include <memory>
#include <string>
#include <vector>

namespace ehc_bringup {

/// How the targets of a set follow each other: back to back (each starts where the last one
/// ended), or each from the ready pose at the origin (the NEO reference protocol).
enum class ReachProtocol { Sequence, Reset };
std::string toString(ReachProtocol p);
ReachProtocol reachProtocolFromString(const std::string& s);  ///< throws "[ReachExperiment] ..."

/// Why a target was not reached within the time limit (classified at the end of the trial,
/// first match in this order).
enum class ReachFailure {
  None,                ///< reached
  Unreachable,         ///< no whole-body IK solution (kinematically unreachable)
  Converging,          ///< the error still fell over the last progress window: out of time
  RollWinding,         ///< the TCP roll joint is pinned at a limit (wound up)
  JointLimit,          ///< another arm joint is pinned at a limit (ReachTrial::failure_joint)
  Singular,            ///< arm manipulability below motion_limit.singular_manipulability
  BaseStuck,           ///< TCP beyond the arm's reach and the base does not move
  Stalled,             ///< none of the above: a local minimum away from limits and singularities
};
std::string toString(ReachFailure f);
ReachFailure reachFailureFromString(const std::string& s);  ///< throws "[ReachExperiment] ..."
std::vector<ReachFailure> reachFailures();                  ///< every value, in order

struct ReachExperimentParams {
  double control_rate = 100.0;      ///< Hz
  double time_limit = 30.0;         ///< s per target
  double distant_threshold = 0.5;   ///< m: cycles with position error above are "distant"
  double arrival_position = 0.01;   ///< m
  double arrival_orientation = 2.0 * M_PI / 180.0;  ///< rad
  ehc_sim::ActuationNoise noise;    ///< Table I; noise.enabled = false for --noise off
  /// ideal (--base-model ideal) | water2, and the base imprecision on top (--base-imprecision:
  /// imprecision.level): the controller is fed the base model's odometry
  /// (KinematicFakeRobot::odometryPose); arrival is judged on the true pose.
  ehc_sim::BaseModelConfig base_model;
  ehc_control::PoseServoParams servo;
  ReachProtocol protocol = ReachProtocol::Sequence;
  /// Number of the first set: set k (k = first_set, first_set + 1, ...) has noise seed
  /// `seed + k`, so that one set of a larger run can be rerun alone (--first-set K --sets 1).
  int first_set = 0;
  // Failure classification (ReachFailure) of a target not reached in time:
  double progress_window = 3.0;        ///< s: the error is compared with its value this long before
  double progress_position = 0.005;    ///< m: a smaller drop over the window is no progress
  double progress_orientation = 1.0 * M_PI / 180.0;  ///< rad: idem
  // Pinned joints and singularity: the controller's motion-limit tests (MotionLimitMonitor:
  // joint_stop + recovery.pinned_margin, motion_limit.singular_manipulability).
  ehc_control::MotionLimitParams motion_limit;  ///< controller.yaml's motion_limit section
  double base_reach = 0.8;             ///< m: position error beyond which only the base can help
  double base_stuck_distance = 0.02;   ///< m: base travel over the window below which it is stuck
  void validate() const;            ///< throws "[ReachExperiment] ..."
};

/// The runner's definition of a kinematically reachable target: a whole-body IK solution (30
/// seeded attempts) with every arm joint at least `joint_stop` from its limits, the closest the
/// controller's joint dampers let a joint come (QpControllerParams::joint_stop). Targets
/// reachable only inside that last stretch of a joint's range are redrawn by the generator
/// and classified ReachFailure::Unreachable.
bool kinematicallyReachable(const ehc_control::WholeBodyModel& model, const Eigen::Isometry3d& target, double joint_stop);

/// Mean absolute speeds: base translation (m/s), base rotation (rad/s), arm (sum of |qd_i|).
struct SpeedMeans {
  double base_t = 0.0, base_r = 0.0, arm = 0.0;
  long cycles = 0;
};

/// The absolute speeds of one commanded velocity [base twist; arm rates] (nb base DOFs): the
/// experiments' one definition (SpeedMeans, the Exp-3 trace's GraspTraceSample).
struct CommandSpeeds {
  double base_t = 0.0;  ///< m/s, |base translation|
  double base_r = 0.0;  ///< rad/s, |base rotation|
  double arm = 0.0;     ///< rad/s, sum of |qd_i|
};
CommandSpeeds commandSpeeds(const Eigen::VectorXd& v, int nb);
/// Adds one commanded velocity [base twist; arm rates] (nb base DOFs) to the sums.
void accumulateSpeed(SpeedMeans& s, const Eigen::VectorXd& v, int nb);
/// The sums divided by the cycle count (unchanged without cycles).
SpeedMeans meanSpeed(const SpeedMeans& sums);
/// {"base_t", "base_r", "arm", "cycles"} of mean speeds, the project's JSON number format.
ehc_common::Json speedJson(const SpeedMeans& m);

struct ReachTrial {
  std::string method;
  int set = 0, index = 0;
  bool reached = false;
  double time_s = 0.0;
  double final_position_error = 0.0, final_orientation_error = 0.0;
  long qp_failures = 0;
  double min_joint_limit_margin = 0.0;  ///< rad, smallest distance to a joint limit seen
  ReachFailure failure = ReachFailure::None;
  std::string failure_joint;            ///< the pinned joint (RollWinding, JointLimit), else ""
  int recoveries = 0;                   ///< joint-limit stall recoveries started (ReachRecovery)
};

struct ReachSummary {
  std::string method;
  std::string base_model;          ///< ideal | water2 (ReachExperimentParams::base_model)
  double base_imprecision = 0.0;   ///< its base imprecision level (0 = off)
  int targets = 0, failed = 0;
  double mean_time_s = 0.0;  ///< over reached targets
  SpeedMeans distant, close;
  long qp_failures = 0;
  long recoveries = 0;                           ///< stall recoveries started, all targets
  long cycles = 0;
  double controller_median_us = 0.0, controller_p99_us = 0.0;
  double min_joint_limit_margin = 0.0;
  double wall_time_s = 0.0;
  std::map<ReachFailure, int> failures;          ///< count per cause (failed targets only)
  std::map<std::string, int> pinned_joints;      ///< count per joint (RollWinding, JointLimit)
  int targets_planned = 0;  ///< targets given to run(); `targets` were run
  bool partial = false;     ///< a stop signal ended the run early (ehc_common::stopRequested)
};

class ReachExperiment {
 public:
  using Progress = std::function<void(int done, int total, const ReachSummary& so_far)>;

  ReachExperiment(std::shared_ptr<const ehc_control::WholeBodyModel> model,
                  const ehc_control::QpControllerParams& controller,
                  std::shared_ptr<const ehc_control::EhcWeighting> weighting,
                  const ReachExperimentParams& params);

  /// Runs every set from the ready pose at the origin; set s (numbered from params.first_set)
  /// uses noise seed `seed + s`. A stop signal (ehc_common::stopRequested) ends it before the
  /// next target (ReachSummary::partial). With
  /// ReachProtocol::Reset every target starts from the ready pose at the origin, and targets
  /// are taken relative to the previous one (relativeToPrevious, reach_targets.h) by the caller.
  ReachSummary run(const std::vector<std::vector<Eigen::Isometry3d>>& sets, unsigned seed,
                   std::vector<ReachTrial>* trials = nullptr, const Progress& progress = nullptr);

  /// Optional per-cycle trace (CSV rows: method,set,index,t,x,y,yaw,q...,pos_err,ori_err,omega,
  /// sig,base_weight,qp_status,v...). Not owned; nullptr disables it.
  void setTrace(std::ostream* trace) { trace_ = trace; }
  /// Optional log of the controller's events (a stall recovery planned, moved, given up; a
  /// wrist flip), one line each: "<method> set S target I t T s: <event>". Not owned.
  void setEvents(std::ostream* events) { events_ = events; }

  /// Drives `robot` to one target (at most the time limit) through `cycle` (built by run() from
  /// the constructor's arguments), accumulating speeds and the update() timings.
  /// Classifies a failed trial from the state at its end (`base`, `q`), the target, and the
  /// position/orientation error and base position one progress window earlier.
  void classifyFailure(ReachTrial& t, const Eigen::Vector3d& base, const Eigen::VectorXd& q,
                       const Eigen::Isometry3d& target, double position_error_before,
                       double orientation_error_before, const Eigen::Vector3d& base_before) const;

  ReachTrial reach(ehc_sim::KinematicFakeRobot& robot, ehc_control::ControlCycle& cycle,
                   const Eigen::Isometry3d& target, SpeedMeans& distant, SpeedMeans& close,
                   std::vector<double>& step_us);

 private:
  std::shared_ptr<const ehc_control::WholeBodyModel> model_;
  ehc_control::QpControllerParams controller_;
  std::shared_ptr<const ehc_control::EhcWeighting> weighting_;
  ReachExperimentParams params_;
  ehc_control::ControlCycleParams cycle_params_;
  std::ostream* trace_ = nullptr;
  std::ostream* events_ = nullptr;
  double sim_time_ = 0.0;  ///< s, advanced by one control period per cycle
  int trace_set_ = 0, trace_index_ = 0;
  int roll_joint_ = -1;             ///< findRollJoint
  /// The controller's pinned-joint and singularity tests (the cause of a stall, MotionLimit).
  std::unique_ptr<ehc_control::MotionLimitMonitor> limits_;
};

/// Writes summary.json, table.md (paper Table II layout) and trials.csv into `dir`.
void writeReachResults(const std::string& dir, const std::vector<ReachSummary>& summaries,
                       const std::vector<ReachTrial>& trials, const std::string& notes);
/// One method's summary as JSON (summary.json, the runner's stdout), the project's number format.
ehc_common::Json summaryJsonValue(const ReachSummary& s);
std::string summaryJson(const ReachSummary& s);

}  // namespace ehc_bringup
