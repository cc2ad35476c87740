#pragma once
// GraspSequencer: the per-object grasp state machine behind `make demo` (ROS-free; the node
// ehc_grasp_sequencer_node only converts messages and calls it). Issue 6 item 4.
//
// For every object in order:
//   WAIT_TARGET  until the object's perceived pose (tag target) arrives
//   APPROACH     goal = pre-grasp pose of the current best grasp (re-chosen as perception and
//                grasp candidates update); the controller drives base + arm. Ends when the TCP is
//                within approach_tolerance of the pre-grasp pose (tsmm: the controller's base
//                stage happens here)
//   PRE_GRASP    the grasp is locked in the world frame (the object is static until touched, and
//                the tag may leave the view at close range); goal = pre-grasp pose, tight tolerance
//   GRASP        goal = grasp pose; ends within grasp tolerance
//   CLOSE        gripper close command once; HOLDING -> LIFT, CLOSED_EMPTY -> failure
//   LIFT         goal = grasp pose raised by lift_height; the simulator's grasp result decides:
//                grasp_succeeded -> success, the object dropped -> failure
//   RELEASE      (after success or failure) gripper open; until open or release_timeout
//   RETREAT      goal = the TCP pose at release, backed off along the approach and raised;
//                until within retreat_tolerance or retreat_timeout; then the next object
//   DONE         all objects handled: no goal any more (the controller stops on TARGET_LOST)
// WAIT_TARGET..LIFT of one object must finish within object_time_limit (30 s), else the object
// is failed with the phase it was in. Time = sim time (s). NaN/Inf inputs are rejected
// (counted); a non-finite or decreasing time throws "[GraspSequencer] ...".
//
// TfM of an object = fraction of controller cycles from the object's start until the gripper
// closes in which the controller reported the target inside the camera image.

#include "ehc_bringup/grasp_selection.h"

#include <Eigen/Geometry>

#include <optional>
#include <string>
#include <vector>

namespace ehc_control {
class ConfigNode;
}

namespace ehc_bringup {

enum class GraspPhase { WaitTarget, Approach, PreGrasp, Grasp, Close, Lift, Release, Retreat, Done };
std::string toString(GraspPhase p);

struct GraspObjectSpec {
  std::string name;
  ApproachDirection approach = ApproachDirection::Forward;
};

struct GraspSequencerParams {
  std::vector<GraspObjectSpec> objects;
  double object_time_limit = 30.0;        ///< s, WAIT_TARGET..LIFT per object
  double perception_hold = 1.0;           ///< s: before the lock, an older object pose gives no goal
  double pose_filter_gain = 0.3;          ///< (0, 1]: weight of a new perceived pose (1 = no filter)
  double pregrasp_distance = 0.10;        ///< m, pre-grasp = grasp backed off along the approach
  double approach_position_tolerance = 0.05;      ///< m
  double approach_orientation_tolerance_deg = 15.0;
  double pregrasp_position_tolerance = 0.015;     ///< m
  double pregrasp_orientation_tolerance_deg = 5.0;
  double grasp_position_tolerance = 0.01;         ///< m
  double grasp_orientation_tolerance_deg = 4.0;
  double gripper_timeout = 3.0;           ///< s, CLOSE without HOLDING / CLOSED_EMPTY
  double lift_height = 0.15;              ///< m, above the grasp pose (> the sim's 0.10 m)
  double release_timeout = 2.0;           ///< s
  double retreat_distance = 0.12;         ///< m back along the approach
  double retreat_raise = 0.05;            ///< m up
  double retreat_tolerance = 0.04;        ///< m
  double retreat_timeout = 4.0;           ///< s
  GraspSelectionParams selection;
  void validate() const;                  ///< throws "[GraspSequencerParams] ..."
  std::string summary() const;
};
/// Reads `sequencer:` (scalars, `selection:` child) and `objects:` (list of {name, approach})
/// from the node's YAML; errors name the file and the field.
GraspSequencerParams loadGraspSequencerParams(const ehc_control::ConfigNode& root);

/// Everything the sequencer reads each cycle (one controller status).
struct SequencerInput {
  double t = 0.0;                                  ///< sim time, s
  std::optional<Eigen::Isometry3d> tcp;            ///< TCP pose in the world (tf), if known
  std::string controller_phase;                    ///< /ehc/status phase ("" if none yet)
  bool target_in_fov = false;                      ///< /ehc/status target_in_fov
  std::string gripper_state;                       ///< /sim/status: open|closing|holding|closed_empty|opening
  bool grasp_succeeded = false;                    ///< /sim/status grasp_succeeded
};

struct SequencerOutput {
  std::optional<Eigen::Isometry3d> goal;           ///< TCP goal for the controller (publish it)
  std::optional<Eigen::Isometry3d> object_pose;    ///< current object's filtered pose (grasp node)
  std::optional<bool> gripper_command;             ///< true = close, false = open (send once)
  std::vector<std::string> events;                 ///< progress lines
};

struct GraspResult {
  std::string name;
  bool success = false;
  double time_s = 0.0;            ///< object start -> lift success (or failure)
  double tfm = 0.0;               ///< [0, 1]
  long cycles = 0;                ///< cycles counted for TfM
  std::string failed_phase;       ///< "" on success
  std::string reason;             ///< "" on success
  bool used_candidate = false;    ///< grasp from perception candidates (else the tag fallback)
  std::string approach;           ///< wanted approach direction
  std::vector<std::pair<std::string, double>> phase_times;  ///< phase -> s spent
  std::vector<std::pair<std::string, long>> controller_phases;  ///< controller phase -> cycles
};

class GraspSequencer {
 public:
  explicit GraspSequencer(const GraspSequencerParams& params);  ///< validates

  /// Perceived pose of object `index` at time t (world). Returns false (and counts it) if the
  /// index is unknown or the pose is not finite / not a rotation.
  bool setObjectPose(std::size_t index, double t, const Eigen::Isometry3d& pose);
  /// Latest grasp candidates (world). Non-finite candidates are dropped (counted).
  void setGraspCandidates(double t, const std::vector<GraspCandidate>& candidates);

  /// One cycle. Throws "[GraspSequencer] ..." for a non-finite or decreasing time.
  SequencerOutput update(const SequencerInput& in);

  GraspPhase phase() const { return phase_; }
  bool done() const { return phase_ == GraspPhase::Done; }
  std::size_t currentObject() const { return current_; }
  const std::vector<GraspResult>& results() const { return results_; }
  long rejectedInputs() const { return rejected_; }
  const GraspSequencerParams& params() const { return params_; }
  /// Locked grasp of the current object (PRE_GRASP onwards).
  const std::optional<GraspChoice>& lockedGrasp() const { return locked_; }

 private:
  void startObject(double t, SequencerOutput* out);
  void enter(GraspPhase p, double t, SequencerOutput* out, const std::string& why = "");
  void finishObject(double t, bool success, const std::string& reason, const SequencerInput& in,
                    SequencerOutput* out);
  std::optional<GraspChoice> currentChoice(const SequencerInput& in) const;
  Eigen::Isometry3d preGrasp(const Eigen::Isometry3d& grasp) const;
  bool within(const SequencerInput& in, const Eigen::Isometry3d& goal, double pos, double ori_deg) const;
  std::string label() const;

  GraspSequencerParams params_;
  GraspPhase phase_ = GraspPhase::WaitTarget;
  std::size_t current_ = 0;
  bool started_ = false;
  double last_t_ = -1.0;
  double object_t0_ = 0.0, phase_t0_ = 0.0;
  // perception of the current object
  std::optional<Eigen::Isometry3d> object_pose_;
  double object_pose_t_ = -1.0;
  std::vector<GraspCandidate> candidates_;
  std::optional<GraspChoice> locked_;
  std::optional<Eigen::Isometry3d> hold_goal_;  ///< RELEASE / RETREAT goal
  Eigen::Vector3d last_approach_ = Eigen::Vector3d::UnitX();
  // bookkeeping
  GraspResult cur_;
  long fov_cycles_ = 0, tfm_cycles_ = 0;
  bool counting_tfm_ = true;
  std::string last_controller_phase_;
  std::vector<GraspResult> results_;
  long rejected_ = 0;
};

/// JSON summary: {"mode": ..., "objects": [{"name", "success", "time_s", "tfm", ...}], "successes": n,
/// "total_time_s": t}.
std::string graspResultsToJson(const std::vector<GraspResult>& results, const std::string& mode,
                               double total_time_s);
/// One human-readable line per object.
std::string graspResultLine(const GraspResult& r);

}  // namespace ehc_bringup
