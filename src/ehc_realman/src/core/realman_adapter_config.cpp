#include "ehc_realman/realman_adapter_config.h"

#include "ehc_common/config_node.h"
#include "ehc_control/robot_config.h"

#include <sstream>
#include <stdexcept>

namespace ehc_realman {

namespace {
const char* kOwner = "RmArmAdapterConfig";
}

void RmArmAdapterConfig::validate() const {
  limits.validate();
  stream.validate();
  gripper.validate();
  ehc_common::requireRange(kOwner, "status_rate_hz", status_rate_hz, 0.1, 100.0);
}

std::string RmArmAdapterConfig::summary() const {
  std::ostringstream os;
  os << "rm_arm_adapter (" << (source_file.empty() ? "built in code" : source_file) << ")\n"
     << "  robot: " << robot_file << "\n"
     << "  stream: " << stream.rate_hz << " Hz, step <= " << stream.max_step_deg
     << " deg/frame, driver speed <= " << stream.driver_max_speed_deg << " deg/s, speed scale "
     << stream.speed_scale << ", command timeout " << stream.command_timeout << " s, hold "
     << stream.hold_duration << " s, state timeout " << stream.state_timeout
     << " s, tracking error <= " << stream.max_tracking_error << " rad, limit margin "
     << stream.limit_margin << " rad\n"
     << "  gripper: max opening " << gripper.max_opening << " m, open " << gripper.open_position
     << ", close " << gripper.close_position << ", pick speed " << gripper.pick_speed
     << " force " << gripper.pick_force << "\n"
     << "  status: " << status_rate_hz << " Hz\n";
  return os.str();
}

RmArmAdapterConfig loadRmArmAdapterConfig(const std::string& path) {
  const auto root = ehc_common::ConfigNode::loadFile(path, kOwner);
  const auto a = root.child("rm_arm_adapter");
  RmArmAdapterConfig c;
  c.source_file = path;
  c.robot_file = a.requirePath("robot");
  const ehc_control::RobotConfig robot = ehc_control::loadRobotConfig(c.robot_file);
  c.limits.names = robot.arm_joints;
  c.limits.lower = robot.arm_lower;
  c.limits.upper = robot.arm_upper;
  c.limits.velocity = robot.arm_velocity;

  const auto s = a.childOrEmpty("stream");
  c.stream.rate_hz = s.get<double>("rate_hz", c.stream.rate_hz);
  c.stream.max_step_deg = s.get<double>("max_step_deg", c.stream.max_step_deg);
  c.stream.driver_max_speed_deg = s.get<double>("driver_max_speed_deg", c.stream.driver_max_speed_deg);
  c.stream.speed_scale = s.get<double>("speed_scale", c.stream.speed_scale);
  c.stream.command_timeout = s.get<double>("command_timeout", c.stream.command_timeout);
  c.stream.hold_duration = s.get<double>("hold_duration", c.stream.hold_duration);
  c.stream.state_timeout = s.get<double>("state_timeout", c.stream.state_timeout);
  c.stream.max_tracking_error = s.get<double>("max_tracking_error", c.stream.max_tracking_error);
  c.stream.limit_margin = s.get<double>("limit_margin", c.stream.limit_margin);

  const auto g = a.childOrEmpty("gripper");
  auto u16 = [&](const char* key, std::uint16_t fallback) {
    const int v = g.get<int>(key, fallback);
    if (v < 1 || v > 1000) g.fail(key, "must be in 1..1000 (got " + std::to_string(v) + ")");
    return static_cast<std::uint16_t>(v);
  };
  c.gripper.max_opening = g.get<double>("max_opening", c.gripper.max_opening);
  c.gripper.open_position = u16("open_position", c.gripper.open_position);
  c.gripper.close_position = u16("close_position", c.gripper.close_position);
  c.gripper.pick_speed = u16("pick_speed", c.gripper.pick_speed);
  c.gripper.pick_force = u16("pick_force", c.gripper.pick_force);
  c.status_rate_hz = a.get<double>("status_rate_hz", c.status_rate_hz);
  root.rejectUnknownKeys();
  root.validate(c);  // errors name the file
  return c;
}

}  // namespace ehc_realman
