#pragma once
// ReachExperiment: paper Exp-1 (random reaching) in-process, without a ROS master.
// The control cycle (ehc_control::ControlCycle with the proportional servo and the EHC QP)
// drives the noisy KinematicFakeRobot through sequences of target TCP poses, fed with the sim
// time; a target is reached when the TCP is within the arrival tolerance (1 cm, 2 deg) and
// failed after the time limit (30 s); the next target starts from where the last one ended.

#include "ehc_control/control_cycle.h"
#include "ehc_sim/kinematic_fake_robot.h"

#include <Eigen/Geometry>

#include <functional>
#include <ostream>
#include <memory>
#include <string>
#include <vector>

namespace ehc_bringup {

struct ReachExperimentParams {
  double control_rate = 100.0;      ///< Hz
  double time_limit = 30.0;         ///< s per target
  double distant_threshold = 0.5;   ///< m: cycles with position error above are "distant"
  double arrival_position = 0.01;   ///< m
  double arrival_orientation = 2.0 * M_PI / 180.0;  ///< rad
  ehc_sim::ActuationNoise noise;    ///< Table I; noise.enabled = false for --noise off
  ehc_control::PoseServoParams servo;
  void validate() const;            ///< throws "[ReachExperiment] ..."
};

/// Mean absolute speeds: base translation (m/s), base rotation (rad/s), arm (sum of |qd_i|).
struct SpeedMeans {
  double base_t = 0.0, base_r = 0.0, arm = 0.0;
  long cycles = 0;
};

/// Adds one commanded velocity [base twist; arm rates] (nb base DOFs) to the sums.
void accumulateSpeed(SpeedMeans& s, const Eigen::VectorXd& v, int nb);
/// The sums divided by the cycle count (unchanged without cycles).
SpeedMeans meanSpeed(const SpeedMeans& sums);

struct ReachTrial {
  std::string method;
  int set = 0, index = 0;
  bool reached = false;
  double time_s = 0.0;
  double final_position_error = 0.0, final_orientation_error = 0.0;
  long qp_failures = 0;
  double min_joint_limit_margin = 0.0;  ///< rad, smallest distance to a joint limit seen
};

struct ReachSummary {
  std::string method;
  int targets = 0, failed = 0;
  double mean_time_s = 0.0;  ///< over reached targets
  SpeedMeans distant, close;
  long qp_failures = 0;
  long cycles = 0;
  double controller_median_us = 0.0, controller_p99_us = 0.0;
  double min_joint_limit_margin = 0.0;
  double wall_time_s = 0.0;
};

class ReachExperiment {
 public:
  using Progress = std::function<void(int done, int total, const ReachSummary& so_far)>;

  ReachExperiment(std::shared_ptr<const ehc_control::WholeBodyModel> model,
                  const ehc_control::QpControllerParams& controller,
                  std::shared_ptr<const ehc_control::EhcWeighting> weighting,
                  const ReachExperimentParams& params);

  /// Runs every set from the ready pose at the origin; set s uses noise seed `seed + s`.
  ReachSummary run(const std::vector<std::vector<Eigen::Isometry3d>>& sets, unsigned seed,
                   std::vector<ReachTrial>* trials = nullptr, const Progress& progress = nullptr);

  /// Optional per-cycle trace (CSV rows: method,set,index,t,x,y,yaw,q...,pos_err,ori_err,omega,
  /// sig,base_weight,qp_status,v...). Not owned; nullptr disables it.
  void setTrace(std::ostream* trace) { trace_ = trace; }

  /// Drives `robot` to one target (at most the time limit) through `cycle` (built by run() from
  /// the constructor's arguments), accumulating speeds and the update() timings.
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
  double sim_time_ = 0.0;  ///< s, advanced by one control period per cycle
  int trace_set_ = 0, trace_index_ = 0;
};

/// Writes summary.json, table.md (paper Table II layout) and trials.csv into `dir`.
void writeReachResults(const std::string& dir, const std::vector<ReachSummary>& summaries,
                       const std::vector<ReachTrial>& trials, const std::string& notes);
std::string summaryJson(const ReachSummary& s);

}  // namespace ehc_bringup
