// ControlPhase / QpStatus / MotionLimit: one string map each, and exactly the values /ehc/status declares
// (ehc_msgs/ControllerStatus PHASE_*, QP_* and LIMIT_*): every enum value's string is a message constant
// and every message constant is an enum value's string. Round trip; unknown strings throw.

#include "ehc_control/control_status.h"
#include "ehc_control/motion_limit.h"
#include "ehc_msgs/ControllerStatus.h"

#include <gtest/gtest.h>

#include <set>
#include <stdexcept>
#include <string>

namespace ehc_control {
namespace {

using Msg = ehc_msgs::ControllerStatus;

/// Both ways: each value's string is one of `msg` and parses back to the value; each of `msg`
/// names a value; no two values share a string.
template <class E, class FromString>
void expectSameStrings(const std::vector<E>& values, const std::set<std::string>& msg, FromString fromString) {
  std::set<std::string> core;
  for (E v : values) {
    const std::string s = toString(v);
    EXPECT_EQ(msg.count(s), 1u) << s << " is not a ControllerStatus constant";
    EXPECT_EQ(fromString(s), v) << s;
    core.insert(s);
  }
  for (const std::string& s : msg) {
    EXPECT_EQ(core.count(s), 1u) << "ControllerStatus constant '" << s << "' is not an enum value's string";
    if (core.count(s)) {
      EXPECT_EQ(toString(fromString(s)), s);
    }
  }
  EXPECT_EQ(core.size(), values.size());
}

TEST(ControlStatus, PhaseStringsAreTheMessageConstants) {
  expectSameStrings(controlPhases(),
                    {Msg::PHASE_IDLE, Msg::PHASE_TRACKING, Msg::PHASE_ARRIVED, Msg::PHASE_TSMM_BASE,
                     Msg::PHASE_TSMM_ARM, Msg::PHASE_STOPPED, Msg::PHASE_TARGET_LOST, Msg::PHASE_QP_FAILED,
                     Msg::PHASE_OBSTACLES_STALE},
                    controlPhaseFromString);
  EXPECT_EQ(controlPhases().size(), 9u);
  // Value by value.
  EXPECT_EQ(toString(ControlPhase::Idle), Msg::PHASE_IDLE);
  EXPECT_EQ(toString(ControlPhase::Tracking), Msg::PHASE_TRACKING);
  EXPECT_EQ(toString(ControlPhase::Arrived), Msg::PHASE_ARRIVED);
  EXPECT_EQ(toString(ControlPhase::TsmmBase), Msg::PHASE_TSMM_BASE);
  EXPECT_EQ(toString(ControlPhase::TsmmArm), Msg::PHASE_TSMM_ARM);
  EXPECT_EQ(toString(ControlPhase::Stopped), Msg::PHASE_STOPPED);
  EXPECT_EQ(toString(ControlPhase::TargetLost), Msg::PHASE_TARGET_LOST);
  EXPECT_EQ(toString(ControlPhase::QpFailed), Msg::PHASE_QP_FAILED);
  EXPECT_EQ(toString(ControlPhase::ObstaclesStale), Msg::PHASE_OBSTACLES_STALE);
}

TEST(ControlStatus, MotionLimitStringsAreTheMessageConstants) {
  expectSameStrings(motionLimits(),
                    {Msg::LIMIT_NONE, Msg::LIMIT_JOINT_LIMIT, Msg::LIMIT_OBSTACLE, Msg::LIMIT_SINGULAR,
                     Msg::LIMIT_SLACK_SATURATED, Msg::LIMIT_BASE_NOT_MOVING, Msg::LIMIT_TARGET_NOT_SEEN},
                    motionLimitFromString);
  EXPECT_EQ(motionLimits().size(), 7u);
  EXPECT_THROW(motionLimitFromString("stalled"), std::invalid_argument);
}

TEST(ControlStatus, QpStatusStringsAreTheMessageConstants) {
  expectSameStrings(qpStatuses(), {Msg::QP_OK, Msg::QP_FAILED, Msg::QP_NOT_RUN}, qpStatusFromString);
  EXPECT_EQ(qpStatuses().size(), 3u);
  EXPECT_EQ(toString(QpStatus::Ok), Msg::QP_OK);
  EXPECT_EQ(toString(QpStatus::Failed), Msg::QP_FAILED);
  EXPECT_EQ(toString(QpStatus::NotRun), Msg::QP_NOT_RUN);
}

TEST(ControlStatus, UnknownStringsThrowWithThePrefix) {
  for (const std::string bad : {"", "idle", "TRACKING ", "OK"}) {
    try {
      controlPhaseFromString(bad);
      ADD_FAILURE() << "'" << bad << "' accepted as a phase";
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()).rfind("[ControlStatus] ", 0), 0u) << e.what();
    }
  }
  EXPECT_THROW(qpStatusFromString("ok"), std::invalid_argument);
  EXPECT_THROW(qpStatusFromString("TRACKING"), std::invalid_argument);
}

}  // namespace
}  // namespace ehc_control
