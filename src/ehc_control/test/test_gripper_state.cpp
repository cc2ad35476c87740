// GripperState: one string map (the strings /sim/status gripper_state carries): every value
// round-trips through its string, the strings are distinct, and an unknown string is an error
// that names the class and lists the known states.

#include "ehc_control/gripper_state.h"

#include <gtest/gtest.h>

#include <set>
#include <stdexcept>
#include <string>

namespace ehc_control {
namespace {

TEST(GripperState, EveryStateRoundTripsThroughItsString) {
  std::set<std::string> names;
  for (const GripperState s : gripperStates()) {
    EXPECT_EQ(gripperStateFromString(toString(s)), s);
    names.insert(toString(s));
  }
  EXPECT_EQ(gripperStates().size(), 5u);
  EXPECT_EQ(names.size(), gripperStates().size());
}

TEST(GripperState, TheStringsAreTheSimulatorStatusStrings) {
  EXPECT_EQ(toString(GripperState::Open), "open");
  EXPECT_EQ(toString(GripperState::Closing), "closing");
  EXPECT_EQ(toString(GripperState::Holding), "holding");
  EXPECT_EQ(toString(GripperState::ClosedEmpty), "closed_empty");
  EXPECT_EQ(toString(GripperState::Opening), "opening");
}

TEST(GripperState, AnUnknownNameIsAnErrorListingTheKnownOnes) {
  for (const std::string bad : {"", "Holding", "held", "open "}) {
    try {
      gripperStateFromString(bad);
      ADD_FAILURE() << "'" << bad << "' accepted";
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind("[GripperState] unknown gripper state '" + bad + "'", 0), 0u) << what;
      EXPECT_NE(what.find("'closed_empty'"), std::string::npos) << what;
    }
  }
}

}  // namespace
}  // namespace ehc_control
