#pragma once
// What ehc_grasp_sequencer_node records of a run (make demo): the per-cycle trace (trace.csv, one
// row per controller status; demo_report.py plots it) and the JSON summary file
// (graspResultsToJson). The in-process experiments write their own tables (writeGraspResults,
// grasp_experiment.h). ROS-free.

#include "ehc_bringup/grasp_sequencer.h"

#include <fstream>
#include <string>
#include <vector>

namespace ehc_bringup {

/// One row of trace.csv: the sequencer's state after a cycle and what the controller and the
/// robot did.
struct GraspTraceRow {
  double t = 0.0;                  ///< s, the status's time
  std::string object;              ///< the object being grasped
  GraspPhase phase = GraspPhase::WaitTarget;  ///< the sequencer's phase after the update
  std::string controller_phase;    ///< /ehc/status phase
  double error_norm = 0.0, position_error = 0.0, sig_omega = 0.0;  ///< /ehc/status
  double base_speed = 0.0;         ///< m/s, measured (odometry twist)
  double base_turn = 0.0;          ///< rad/s, |measured yaw rate|
  double arm_speed = 0.0;          ///< rad/s, measured (jointStateArmSpeed)
  bool target_in_fov = false;      ///< /ehc/status
  unsigned long obstacle_rows = 0; ///< /ehc/status
  std::string qp_status;           ///< /ehc/status
};

/// trace.csv: a header line, then one line per row (t with 3 decimals, the figures with 5).
class GraspTraceWriter {
 public:
  static constexpr const char* kHeader =
      "t,object,phase,controller_phase,error_norm,position_error,sig_omega,base_speed,base_turn_rate,"
      "arm_speed,target_in_fov,obstacle_rows,qp_status";
  /// Creates `path` and writes the header. Throws std::runtime_error "[GraspTraceWriter] cannot
  /// write the trace file <path>".
  explicit GraspTraceWriter(const std::string& path);
  void write(const GraspTraceRow& row);
  void flush() { file_.flush(); }

 private:
  std::ofstream file_;
};

/// Writes the run's JSON summary (graspResultsToJson) and a newline to `path`; false if the
/// file cannot be written.
bool writeGraspSummaryFile(const std::string& path, const std::string& json);

/// The trace's arm speed from a joint state: the Euclidean norm of the rates of the robot's arm
/// joints (`arm_joints`, RobotConfig::arm_joints), picked by name with the one joint-state
/// parser (ehc_control::armPositionsFromJointState: any order, other joints such as the
/// fingers ignored). NaN if an arm joint or its rate is missing or not finite. Not the
/// experiments' arm speed (SpeedMeans, GraspTraceSample: the sum of |commanded rates|).
double jointStateArmSpeed(const std::vector<std::string>& arm_joints, const std::vector<std::string>& names,
                          const std::vector<double>& velocities);

}  // namespace ehc_bringup
