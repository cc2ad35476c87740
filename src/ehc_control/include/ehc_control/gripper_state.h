#pragma once
// GripperState: the state of a two-finger gripper as the simulator reports it (ehc_sim's
// ParallelGripper; /sim/status gripper_state) and the grasp sequencer reads it, with ONE string
// map (the strings /sim/status carries). Messages keep the string; nodes convert at their
// boundary with gripperStateFromString. ROS-free.

#include <ostream>
#include <string>
#include <vector>

namespace ehc_control {

enum class GripperState {
  Open,         ///< "open": fully open
  Closing,      ///< "closing": closing, nothing grasped yet
  Holding,      ///< "holding": both fingers on an object, fingers stopped
  ClosedEmpty,  ///< "closed_empty": closed to the end on nothing (a failed grasp)
  Opening,      ///< "opening": opening (a held object was released)
};

std::string toString(GripperState state);
/// Inverse of toString; throws std::invalid_argument "[GripperState] unknown gripper state 's'
/// (expected one of ...)" for any other string.
GripperState gripperStateFromString(const std::string& s);
/// Every value of the string map, in declaration order (tests, documentation).
std::vector<GripperState> gripperStates();

inline std::ostream& operator<<(std::ostream& os, GripperState state) { return os << toString(state); }

}  // namespace ehc_control
