#pragma once
// ControlPhase and QpStatus: what a control cycle did, as typed values with ONE string map each.
// The strings are the ones /ehc/status carries (ehc_msgs/ControllerStatus PHASE_* and QP_*
// constants; test_control_status checks that both lists agree). ROS-free.

#include <ostream>
#include <string>
#include <vector>

namespace ehc_control {

enum class ControlPhase {
  Idle,        ///< IDLE: no target yet
  Tracking,    ///< TRACKING: servoing to the target (ehc, neo_e, neo_c)
  Arrived,     ///< ARRIVED: within the arrival tolerance
  TsmmBase,    ///< TSMM_BASE: tsmm stage 1, the base drives, the arm is held
  TsmmArm,     ///< TSMM_ARM: tsmm stage 2, the arm works, the base is held
  Stopped,     ///< STOPPED: stale or invalid state, controller error (zero command)
  TargetLost,  ///< TARGET_LOST: target older than watchdog.target_timeout (zero command)
  QpFailed,    ///< QP_FAILED: infeasible, non-finite or over-budget solve (zero command)
  ObstaclesStale,  ///< OBSTACLES_STALE: obstacle sensing required (watchdog.require_obstacles)
                   ///< and the obstacle list missing or older than watchdog.obstacle_timeout
                   ///< (zero command)
};

enum class QpStatus {
  Ok,      ///< OK
  Failed,  ///< QP_FAILED
  NotRun,  ///< NOT_RUN
};

std::string toString(ControlPhase phase);
std::string toString(QpStatus status);
/// Inverse of toString; throws std::invalid_argument "[ControlStatus] ..." for any other string.
ControlPhase controlPhaseFromString(const std::string& s);
QpStatus qpStatusFromString(const std::string& s);
/// Every value of the string map, in declaration order (tests, documentation).
std::vector<ControlPhase> controlPhases();
std::vector<QpStatus> qpStatuses();

inline std::ostream& operator<<(std::ostream& os, ControlPhase phase) { return os << toString(phase); }
inline std::ostream& operator<<(std::ostream& os, QpStatus status) { return os << toString(status); }

}  // namespace ehc_control
