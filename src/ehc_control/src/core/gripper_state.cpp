#include "ehc_control/gripper_state.h"

#include "ehc_common/enum_names.h"

namespace ehc_control {

namespace {

// The one string map of the gripper state.
constexpr ehc_common::EnumNames<GripperState, 5> kGripperStateNames = {{
    {GripperState::Open, "open"},
    {GripperState::Closing, "closing"},
    {GripperState::Holding, "holding"},
    {GripperState::ClosedEmpty, "closed_empty"},
    {GripperState::Opening, "opening"},
}};
const char* kOwner = "GripperState";

}  // namespace

std::string toString(GripperState state) { return ehc_common::enumName(kGripperStateNames, state, kOwner); }
GripperState gripperStateFromString(const std::string& s) {
  return ehc_common::enumValue(kGripperStateNames, s, kOwner, "gripper state");
}
std::vector<GripperState> gripperStates() { return ehc_common::enumValues(kGripperStateNames); }

}  // namespace ehc_control
