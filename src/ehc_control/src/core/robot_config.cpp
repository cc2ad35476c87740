#include "ehc_control/robot_config.h"

#include "ehc_common/config_node.h"
#include "ehc_common/enum_names.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <set>
#include <sstream>
#include <stdexcept>

using ehc_common::ConfigNode;
using ehc_common::requireRange;

namespace ehc_control {

namespace {
const char* kOwner = "RobotConfig";

[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument(std::string("[") + kOwner + "] " + what);
}
}  // namespace

namespace {
constexpr ehc_common::EnumNames<BaseType, 2> kBaseTypeNames = {
    {{BaseType::Holonomic, "holonomic"}, {BaseType::Differential, "differential"}}};
}  // namespace

std::string toString(BaseType t) { return ehc_common::enumName(kBaseTypeNames, t, kOwner); }

BaseType baseTypeFromString(const std::string& s) {
  return ehc_common::enumValue(kBaseTypeNames, s, kOwner, "base type");
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
  for (const auto& [link, d] : obstacle_stop_distances)
    requireRange(kOwner, "robot.obstacle_stop_distances." + link, d, 0.0, 1.0);
  for (const auto& [a, b] : ignore_pairs)
    if (a.empty() || b.empty() || a == b)
      fail("robot.collision.ignore_pairs: a pair needs two different link names");
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
  os << "  camera intrinsics: " << (camera_info_path.empty() ? "(defaults)" : camera_info_path) << "\n"
     << "  checked links: ";
  if (checked_links.empty()) os << "(every link with collision geometry)";
  for (std::size_t i = 0; i < checked_links.size(); ++i) os << (i ? ", " : "") << checked_links[i];
  os << "\n  floor links: ";
  if (floor_links.empty()) os << "(the URDF root)";
  for (std::size_t i = 0; i < floor_links.size(); ++i) os << (i ? ", " : "") << floor_links[i];
  os << "\n  extra self-collision pairs ignored: " << ignore_pairs.size();
  for (const auto& [a, b] : ignore_pairs) os << " [" << a << ", " << b << "]";
  os << "\n  obstacle stop distances:";
  if (obstacle_stop_distances.empty()) os << " (controller default for every link)";
  for (const auto& [link, d] : obstacle_stop_distances) os << " " << link << " " << d << " m";
  os << "\n";
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
  c.urdf_path = r.requirePath("urdf");
  if (r.has("reachability_map"))
    c.reachability_map_path = r.requirePath("reachability_map");

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
  if (c.arm_joints.size() != 6 && c.arm_joints.size() != 7)
    a.fail("joints", "must list the 6 or 7 arm joints in command order (has " +
                         std::to_string(c.arm_joints.size()) + "); other arms are not supported");
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
    o.key = key;
    o.joint = e.require<std::string>("joint");
    o.xyz = e.requireVector("xyz", 3);
    o.rpy = e.requireVector("rpy", 3);
    c.calibration.push_back(o);
  }
  c.camera_info_path = r.getPath("camera_info", c.camera_info_path);
  const ConfigNode col = r.childOrEmpty("collision");
  c.checked_links = col.getStrings("checked_links", {});
  c.floor_links = col.getStrings("floor_links", {});
  for (std::size_t i = 0; i < col.listSize("ignore_pairs"); ++i) {  // [link_a, link_b] lists
    const YAML::Node p = col.yaml()["ignore_pairs"][i];
    if (!p.IsSequence() || p.size() != 2 || !p[0].IsScalar() || !p[1].IsScalar())
      col.fail("ignore_pairs", "must be a list of [link_a, link_b] pairs");
    c.ignore_pairs.emplace_back(p[0].as<std::string>(), p[1].as<std::string>());
  }
  col.ignore("ignore_pairs");
  const ConfigNode stop = r.childOrEmpty("obstacle_stop_distances");
  for (const std::string& link : stop.keys()) c.obstacle_stop_distances[link] = stop.require<double>(link);
  root.rejectUnknownKeys();
  root.validate(c);  // errors name the file
  return c;
}

std::string configDirectory() {
  if (const char* env = std::getenv("EHC_CONFIG_DIR"); env && *env) return env;
#ifdef EHC_CONFIG_DIR
  return EHC_CONFIG_DIR;
#else
  return "config";
#endif
}

std::string robotsDirectory() {
  if (const char* env = std::getenv("EHC_ROBOTS_DIR"); env && *env) return env;
  return configDirectory() + "/robots";
}

std::vector<std::string> robotSearchPath() {
  std::vector<std::string> dirs{robotsDirectory()};
  const std::string shipped = configDirectory() + "/robots";
  if (dirs.front() != shipped) dirs.push_back(shipped);
  return dirs;
}

namespace {
bool isRobotName(const std::string& s) {
  return !s.empty() && s.find('/') == std::string::npos && !(s.size() >= 5 && s.compare(s.size() - 5, 5, ".yaml") == 0);
}
}  // namespace

std::string robotFileField(const ConfigNode& node, const std::string& key) {
  const std::string value = node.require<std::string>(key);
  if (!isRobotName(value)) return node.requirePath(key);
  try {
    return resolveRobotFile(value);
  } catch (const std::invalid_argument& e) {
    node.fail(key, e.what());
  }
}

std::vector<std::string> robotNames(const std::string& dir) {
  namespace fs = std::filesystem;
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (fs::is_regular_file(e.path() / "robot.yaml")) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

std::string resolveRobotFile(const std::string& name_or_path) {
  namespace fs = std::filesystem;
  const std::string& s = name_or_path;
  if (!s.empty() && !isRobotName(s)) return s;
  if (s.empty()) fail("no robot given (a robot name such as realman_rm65_water2, or a robot.yaml path)");
  const std::vector<std::string> dirs = robotSearchPath();
  for (const std::string& dir : dirs) {
    const fs::path file = fs::path(dir) / s / "robot.yaml";
    if (fs::is_regular_file(file)) return file.string();
  }
  std::string where;
  for (const std::string& dir : dirs) {
    std::string known;
    for (const std::string& n : robotNames(dir)) known += (known.empty() ? "" : ", ") + n;
    where += (where.empty() ? "" : "; ") + std::string("robots in ") + dir + ": " + (known.empty() ? "none" : known);
  }
  fail("unknown robot '" + s + "': no " + s + "/robot.yaml (" + where + "); give a robot name or a path to a robot.yaml");
}

}  // namespace ehc_control
