#pragma once
// ParallelGripper: state machine of a two-finger parallel-jaw gripper. The fingers move at a
// fixed speed; while closing, an object touched by both fingers is grasped (held) and the
// fingers stop; closing to the end without such an object is a failed grasp. A held object
// lifted by `lift_height` above where it was grasped is a successful grasp. Opening releases
// it. Pure logic: SimWorld moves the finger bodies and reports the finger contacts. ROS-free.

#include "ehc_control/gripper_state.h"
#include "ehc_sim/sim_config.h"

#include <set>
#include <string>

namespace ehc_sim {

/// The gripper states and their strings (/sim/status gripper_state) are ehc_control's, which the
/// grasp sequencer reads too.
using ehc_control::GripperState;

class ParallelGripper {
 public:
  /// `max_opening`: travel of each finger (m), from the URDF finger joint limit.
  ParallelGripper(const GripperConfig& cfg, double max_opening);

  /// Fully open (or closed if !start_open), nothing held, counters zero.
  void reset();
  /// close = true starts closing (from any state but Holding); false starts opening and
  /// releases a held object.
  void command(bool close);
  /// Moves the fingers for dt seconds (not while holding).
  void advance(double dt);
  /// Objects each finger touches now. While closing, an object touched by both fingers is
  /// grasped; returns true if a grasp started in this call.
  bool onFingerContacts(const std::set<int>& left, const std::set<int>& right);
  /// Height of the held object (world z). Declares success once lifted by lift_height.
  void onHeldObjectHeight(double z);

  GripperState state() const { return state_; }
  /// Travel of each finger from closed (m): 0 = closed, maxOpening() = fully open.
  double opening() const { return opening_; }
  double maxOpening() const { return max_opening_; }
  int heldObject() const { return held_; }  ///< -1 if none
  /// True from the moment the held object was lifted by lift_height until the next close.
  bool graspSucceeded() const { return succeeded_; }
  double graspHeight() const { return grasp_z_; }
  long graspsStarted() const { return grasps_; }
  long graspSuccesses() const { return successes_; }
  long graspFailures() const { return failures_; }  ///< closed on nothing

 private:
  GripperConfig cfg_;
  double max_opening_;
  GripperState state_ = GripperState::Open;
  double opening_ = 0.0;
  int held_ = -1;
  bool succeeded_ = false;
  double grasp_z_ = 0.0;
  bool have_grasp_z_ = false;
  long grasps_ = 0, successes_ = 0, failures_ = 0;
};

}  // namespace ehc_sim
