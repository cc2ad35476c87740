#include "ehc_control/robot_config.h"

#include "ehc_control/config_node.h"

#include <cmath>
#include <set>
#include <sstream>
#include <stdexcept>

namespace ehc_control {

namespace {
const char* kOwner = "RobotConfig";

[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument(std::string("[") + kOwner + "] " + what);
}
}  // namespace

std::string toString(BaseType t) {
  return t == BaseType::Holonomic ? "holonomic" : "differential";
}

BaseType baseTypeFromString(const std::string& s) {
  if (s == "holonomic") return BaseType::Holonomic;
  if (s == "differential") return BaseType::Differential;
  fail("base type must be 'holonomic' or 'differential' (got '" + s + "')");
}

Eigen::VectorXd RobotConfig::velocityLimits() const {
  Eigen::VectorXd v(nBase() + nArm());
  if (base_type == BaseType::Holonomic)
    v.head(3) << max_linear_velocity, max_linear_velocity, max_angular_velocity;
  else
    v.head(2) << max_linear_velocity, max_angular_velocity;
  v.tail(nArm()) = arm_velocity;
  return v;
}

void RobotConfig::validate() const {
  if (urdf_path.empty()) fail("robot.urdf: no URDF file given");
  requireRange(kOwner, "robot.base.max_linear_velocity", max_linear_velocity, 1e-3, 5.0);
  requireRange(kOwner, "robot.base.max_angular_velocity", max_angular_velocity, 1e-3, 10.0);
  const int n = nArm();
  if (n < 1 || n > 7) fail("robot.arm.joints: need 1..7 arm joints (have " + std::to_string(n) + ")");
  std::set<std::string> unique(arm_joints.begin(), arm_joints.end());
  if (static_cast<int>(unique.size()) != n) fail("robot.arm.joints: joint names must be unique");
  auto sized = [&](const Eigen::VectorXd& v, const char* field) {
    if (v.size() != n)
      fail(std::string(field) + ": must have one value per arm joint (" + std::to_string(n) +
           "), has " + std::to_string(v.size()));
    if (!v.allFinite()) fail(std::string(field) + ": values must be finite");
  };
  sized(arm_lower, "robot.arm.lower");
  sized(arm_upper, "robot.arm.upper");
  sized(arm_velocity, "robot.arm.velocity");
  sized(arm_ready, "robot.arm.ready");
  for (int i = 0; i < n; ++i) {
    const std::string j = arm_joints[static_cast<std::size_t>(i)];
    if (!(arm_lower[i] < arm_upper[i])) fail("robot.arm: lower >= upper for joint " + j);
    if (!(arm_velocity[i] > 0.0)) fail("robot.arm.velocity: must be > 0 for joint " + j);
    if (arm_ready[i] < arm_lower[i] || arm_ready[i] > arm_upper[i])
      fail("robot.arm.ready: joint " + j + " ready position is outside its limits");
  }
  std::set<std::string> frames{world_frame, base_frame, arm_base_frame, tcp_frame, camera_frame};
  if (frames.count("")) fail("robot.frames: frame names must not be empty");
  if (world_frame == base_frame) fail("robot.frames: world and base frame must differ");
}

std::string RobotConfig::summary() const {
  std::ostringstream os;
  os << "robot '" << name << "' (" << (source_file.empty() ? "built in code" : source_file) << ")\n"
     << "  urdf: " << urdf_path << "\n"
     << "  reachability map: " << (reachability_map_path.empty() ? "(none)" : reachability_map_path) << "\n"
     << "  frames: world=" << world_frame << " base=" << base_frame
     << " arm_base=" << arm_base_frame << " tcp=" << tcp_frame << " camera=" << camera_frame
     << "\n"
     << "  base: " << toString(base_type) << ", |v| <= " << max_linear_velocity
     << " m/s, |w| <= " << max_angular_velocity << " rad/s\n"
     << "  arm: " << nArm() << " joints\n";
  for (int i = 0; i < nArm(); ++i)
    os << "    " << arm_joints[static_cast<std::size_t>(i)] << ": [" << arm_lower[i] << ", "
       << arm_upper[i] << "] rad, |qd| <= " << arm_velocity[i] << " rad/s, ready " << arm_ready[i]
       << "\n";
  for (const auto& c : calibration)
    os << "  calibration " << c.joint << ": xyz [" << c.xyz.transpose() << "] rpy ["
       << c.rpy.transpose() << "]\n";
  return os.str();
}

RobotConfig loadRobotConfig(const std::string& path) {
  const ConfigNode root = ConfigNode::loadFile(path, kOwner);
  const ConfigNode r = root.child("robot");
  RobotConfig c;
  c.source_file = path;
  c.name = r.get<std::string>("name", c.name);
  c.urdf_path = r.resolvePath(r.require<std::string>("urdf"));
  if (r.has("reachability_map"))
    c.reachability_map_path = r.resolvePath(r.require<std::string>("reachability_map"));

  const ConfigNode f = r.childOrEmpty("frames");
  c.world_frame = f.get<std::string>("world", c.world_frame);
  c.base_frame = f.get<std::string>("base", c.base_frame);
  c.arm_base_frame = f.get<std::string>("arm_base", c.arm_base_frame);
  c.tcp_frame = f.get<std::string>("tcp", c.tcp_frame);
  c.camera_frame = f.get<std::string>("camera_optical", c.camera_frame);

  const ConfigNode b = r.child("base");
  const std::string type = b.require<std::string>("type");
  if (type != "holonomic" && type != "differential")
    b.fail("type", "must be 'holonomic' or 'differential' (got '" + type + "')");
  c.base_type = baseTypeFromString(type);
  c.max_linear_velocity = b.get<double>("max_linear_velocity", c.max_linear_velocity);
  c.max_angular_velocity = b.get<double>("max_angular_velocity", c.max_angular_velocity);

  const ConfigNode a = r.child("arm");
  c.arm_joints = a.getStrings("joints", {});
  if (c.arm_joints.empty()) a.fail("joints", "must list the arm joints");
  const int n = c.nArm();
  c.arm_lower = a.requireVector("lower", n);
  c.arm_upper = a.requireVector("upper", n);
  c.arm_velocity = a.requireVector("velocity", n);
  c.arm_ready = a.getVector("ready", 0.5 * (c.arm_lower + c.arm_upper), n);

  const ConfigNode cal = r.childOrEmpty("calibration");
  for (const char* key : {"tcp", "camera"}) {
    if (!cal.has(key)) continue;
    const ConfigNode e = cal.child(key);
    FrameOverride o;
    o.joint = e.require<std::string>("joint");
    o.xyz = e.requireVector("xyz", 3);
    o.rpy = e.requireVector("rpy", 3);
    c.calibration.push_back(o);
  }
  root.rejectUnknownKeys();
  root.validate(c);  // errors name the file
  return c;
}

}  // namespace ehc_control
