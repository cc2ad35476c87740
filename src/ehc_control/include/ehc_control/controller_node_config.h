#pragma once
// The `node:` section of controller.yaml: how ehc_controller_node runs its cycle (on each joint
// state in lock-step, or on a timer) and its wall-clock watchdog. The rest of the file is
// ControlCycleParams (control_cycle.h). ROS-free, unit-tested.

#include <string>

namespace ehc_common {
class ConfigNode;
}  // namespace ehc_common

namespace ehc_control {

/// What starts a control cycle.
enum class CycleTrigger {
  State,  ///< "state": each joint state once odometry of the same stamp is in (lock-step simulator)
  Timer,  ///< "timer": a timer at `rate` (real robot)
};
std::string toString(CycleTrigger trigger);
/// "state" | "timer"; throws std::invalid_argument "[ControllerNodeParams] ..." otherwise.
CycleTrigger cycleTriggerFromString(const std::string& s);

struct ControllerNodeParams {
  CycleTrigger trigger = CycleTrigger::State;  ///< node.trigger: state | timer
  double rate = 100.0;                         ///< Hz, node.rate: the timer trigger's, [1, 1000]
  /// wall s, node.wall_timeout, [0.01, 10]: no control cycle for this long on the wall clock
  /// while ROS time stands still as long -> zeros (STOPPED). Catches what the ROS-time
  /// watchdogs cannot: ROS time standing still (sim time of a dead simulator).
  double wall_timeout = 0.5;
  void validate() const;        ///< throws "[ControllerNodeParams] ..."
  std::string summary() const;  ///< "trigger timer at 50 Hz, wall-clock watchdog 0.5 s"
};

/// Reads the `node:` section of controller.yaml (`root`; absent: the defaults) and validates
/// it; errors name the file and the field. Keys it does not know stay unread, so the caller's
/// rejectUnknownKeys() on `root` reports them.
ControllerNodeParams loadControllerNodeParams(const ehc_common::ConfigNode& root);

}  // namespace ehc_control
