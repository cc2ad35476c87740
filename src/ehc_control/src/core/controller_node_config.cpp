#include "ehc_control/controller_node_config.h"

#include "ehc_common/config_node.h"
#include "ehc_common/enum_names.h"

#include <sstream>
#include <stdexcept>
#include <string>

namespace ehc_control {

namespace {
constexpr ehc_common::EnumNames<CycleTrigger, 2> kTriggerNames = {{{CycleTrigger::State, "state"}, {CycleTrigger::Timer, "timer"}}};
const char* kOwner = "ControllerNodeParams";
}  // namespace

std::string toString(CycleTrigger trigger) { return ehc_common::enumName(kTriggerNames, trigger, kOwner); }
CycleTrigger cycleTriggerFromString(const std::string& s) { return ehc_common::enumValue(kTriggerNames, s, kOwner, "trigger"); }

void ControllerNodeParams::validate() const {
  ehc_common::requireRange(kOwner, "node.rate", rate, 1.0, 1000.0);
  ehc_common::requireRange(kOwner, "node.wall_timeout", wall_timeout, 0.01, 10.0);
}

std::string ControllerNodeParams::summary() const {
  std::string s = "trigger " + toString(trigger);
  if (trigger == CycleTrigger::Timer) s += " at " + std::to_string(rate) + " Hz";
  std::ostringstream os;
  os << s << ", wall-clock watchdog " << wall_timeout << " s";
  return os.str();
}

ControllerNodeParams loadControllerNodeParams(const ehc_common::ConfigNode& root) {
  const ehc_common::ConfigNode n = root.childOrEmpty("node");
  ControllerNodeParams p;
  const std::string trigger = n.get<std::string>("trigger", toString(p.trigger));
  try {
    p.trigger = cycleTriggerFromString(trigger);
  } catch (const std::invalid_argument&) {
    n.fail("trigger", "must be 'state' or 'timer'");
  }
  p.rate = n.get("rate", p.rate);
  p.wall_timeout = n.get("wall_timeout", p.wall_timeout);
  n.validate(p);
  return p;
}

}  // namespace ehc_control
