#include "ehc_control/control_status.h"

#include "ehc_common/enum_names.h"

namespace ehc_control {

namespace {

// The one string map of each enum.
constexpr ehc_common::EnumNames<ControlPhase, 9> kPhaseNames = {{
    {ControlPhase::Idle, "IDLE"},
    {ControlPhase::Tracking, "TRACKING"},
    {ControlPhase::Arrived, "ARRIVED"},
    {ControlPhase::TsmmBase, "TSMM_BASE"},
    {ControlPhase::TsmmArm, "TSMM_ARM"},
    {ControlPhase::Stopped, "STOPPED"},
    {ControlPhase::TargetLost, "TARGET_LOST"},
    {ControlPhase::QpFailed, "QP_FAILED"},
    {ControlPhase::ObstaclesStale, "OBSTACLES_STALE"},
}};
constexpr ehc_common::EnumNames<QpStatus, 3> kQpStatusNames = {{
    {QpStatus::Ok, "OK"},
    {QpStatus::Failed, "QP_FAILED"},
    {QpStatus::NotRun, "NOT_RUN"},
}};
const char* kOwner = "ControlStatus";

}  // namespace

std::string toString(ControlPhase phase) { return ehc_common::enumName(kPhaseNames, phase, kOwner); }
std::string toString(QpStatus status) { return ehc_common::enumName(kQpStatusNames, status, kOwner); }
ControlPhase controlPhaseFromString(const std::string& s) { return ehc_common::enumValue(kPhaseNames, s, kOwner, "control phase"); }
QpStatus qpStatusFromString(const std::string& s) { return ehc_common::enumValue(kQpStatusNames, s, kOwner, "QP status"); }
std::vector<ControlPhase> controlPhases() { return ehc_common::enumValues(kPhaseNames); }
std::vector<QpStatus> qpStatuses() { return ehc_common::enumValues(kQpStatusNames); }

}  // namespace ehc_control
