#include "ehc_sim/fake_robot_config.h"

#include "ehc_common/config_node.h"
#include "ehc_control/robot_config.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <sstream>
#include <stdexcept>

using ehc_common::ConfigNode;

namespace ehc_sim {


std::int64_t FakeRobotConfig::dtNs() const { return static_cast<std::int64_t>(std::llround(dt * 1e9)); }

void FakeRobotConfig::validate() const {
  const char* o = "FakeRobotConfig";
  if (robot_file.empty()) throw std::invalid_argument("[FakeRobotConfig] sim.robot: no robot.yaml given");
  ehc_common::requireRange(o, "sim.dt", dt, 1e-4, 0.1);
  if (std::abs(dt * 1e9 - std::round(dt * 1e9)) > 1e-3)
    throw std::invalid_argument("[FakeRobotConfig] sim.dt must be a whole number of nanoseconds");
  ehc_common::requirePositive(o, "sim.state_republish_period", state_republish_period);
  ehc_common::requirePositive(o, "sim.command_timeout", command_timeout);
  ehc_common::requireRange(o, "sim.max_real_time_factor", max_real_time_factor, 0.0, 1e6);
  if (!robot_start.allFinite()) throw std::invalid_argument("[FakeRobotConfig] sim.robot_start must be finite");
  noise.validate();
  base_model.validate();
}

std::string FakeRobotConfig::summary() const {
  std::ostringstream os;
  os << "  robot " << robot_file << ", start (" << robot_start.x() << ", " << robot_start.y() << ", "
     << robot_start.z() << ")\n"
     << "  dt " << dt << " s, seed " << seed << ", mode ";
  if (free_run)
    os << "free-run (command timeout " << command_timeout << " wall s)";
  else
    os << "lock-step (unanswered state resent every " << state_republish_period << " wall s"
       << (max_real_time_factor > 0 ? ", at most " + std::to_string(max_real_time_factor) + " x real time" : "")
       << ")";
  os << ", noise " << (noise.enabled ? "on" : "off") << " (base-T " << noise.base_translation
     << ", base-R " << noise.base_rotation << ", arm " << noise.arm << ")\n"
     << "  base model " << toString(base_model.type) << ", base imprecision " << base_model.imprecision.summary()
     << "\n";
  return os.str();
}

ActuationNoise loadActuationNoise(const ConfigNode& n) {
  ActuationNoise a;
  a.enabled = n.get<bool>("enabled", a.enabled);
  a.base_translation = n.get<double>("base_translation", a.base_translation);
  a.base_rotation = n.get<double>("base_rotation", a.base_rotation);
  a.arm = n.get<double>("arm", a.arm);
  for (const auto& [key, sigma] : {std::make_pair("base_translation", a.base_translation),
                                   std::make_pair("base_rotation", a.base_rotation),
                                   std::make_pair("arm", a.arm)})
    if (sigma < 0.0 || sigma > 1.0) n.fail(key, "must be in [0, 1]");
  return a;
}

Eigen::Vector3d loadBasePose(const ConfigNode& n) {
  return Eigen::Vector3d(n.get<double>("x", 0.0), n.get<double>("y", 0.0), n.get<double>("yaw", 0.0));
}

FakeRobotConfig loadFakeRobotConfig(const ConfigNode& s) {
  // The kinematic simulator's former keys: an error naming the replacement, never ignored.
  static const std::pair<const char*, const char*> kReplaced[] = {
      {"lockstep", "was replaced by sim.free_run (free_run: false = lock-step)"},
      {"lockstep_timeout_wall",
       "was removed: lock-step never advances without an answer; an unanswered state is resent "
       "every sim.state_republish_period wall seconds"},
      {"noise_base_translation", "was replaced by sim.noise.base_translation"},
      {"noise_base_rotation", "was replaced by sim.noise.base_rotation"},
      {"noise_arm", "was replaced by sim.noise.arm"},
      {"initial_base", "was replaced by sim.robot_start: {x, y, yaw}"},
  };
  for (const auto& [key, why] : kReplaced)
    if (s.has(key)) s.fail(key, why);
  if (s.has("noise") && !s.yaml()["noise"].IsMap())
    s.fail("noise", "must be a mapping {enabled, base_translation, base_rotation, arm} "
                    "(the flag 'noise: false' is now 'noise: {enabled: false}')");

  FakeRobotConfig c;
  c.robot_file = ehc_control::robotFileField(s, "robot");  // a robot name or a robot.yaml path
  c.dt = s.get<double>("dt", c.dt);
  if (!(c.dt >= 1e-4 && c.dt <= 0.1)) s.fail("dt", "must be in [0.0001, 0.1] s");
  if (std::abs(c.dt * 1e9 - std::round(c.dt * 1e9)) > 1e-3) s.fail("dt", "must be a whole number of nanoseconds");
  const long seed = s.get<long>("seed", static_cast<long>(c.seed));
  if (seed < 0 || seed > 4294967295L) s.fail("seed", "must be in [0, 2^32)");
  c.seed = static_cast<unsigned>(seed);
  c.free_run = s.get<bool>("free_run", c.free_run);
  c.state_republish_period = s.get<double>("state_republish_period", c.state_republish_period);
  if (!(c.state_republish_period > 0)) s.fail("state_republish_period", "must be > 0 s");
  c.command_timeout = s.get<double>("command_timeout", c.command_timeout);
  if (!(c.command_timeout > 0)) s.fail("command_timeout", "must be > 0 s");
  c.max_real_time_factor = s.get<double>("max_real_time_factor", c.max_real_time_factor);
  if (!(c.max_real_time_factor >= 0 && c.max_real_time_factor <= 1e6))
    s.fail("max_real_time_factor", "must be in [0, 1e6] (0 = no pacing)");
  c.noise = loadActuationNoise(s.childOrEmpty("noise"));
  if (s.has("robot_start")) c.robot_start = loadBasePose(s.child("robot_start"));
  if (s.has("base_model")) c.base_model.type = baseModelTypeFromString(s.require<std::string>("base_model"));
  // The Water2 parameters are read (and checked) whichever model is selected, so that a file
  // can keep them next to base_model: ideal.
  if (s.has("water2")) c.base_model.water2 = loadWater2BaseParams(s.child("water2"));
  // On top of either model; level 0 (the default) = off.
  if (s.has("base_imprecision")) c.base_model.imprecision = loadBaseImprecisionParams(s.child("base_imprecision"));
  s.validate(c);
  return c;
}

FakeRobotConfig loadFakeRobotConfigFile(const std::string& path) {
  const ConfigNode root = ConfigNode::loadFile(path, "FakeRobotConfig");
  if (root.has("robot")) root.fail("robot", "was moved to sim.robot");
  FakeRobotConfig c = loadFakeRobotConfig(root.child("sim"));  // the former keys fail here, with their replacement
  root.rejectUnknownKeys();  // a Bullet simulator key, or a typo
  return c;
}

}  // namespace ehc_sim
