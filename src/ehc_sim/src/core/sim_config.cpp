#include "ehc_sim/sim_config.h"

#include "ehc_common/config_node.h"
#include "ehc_common/enum_names.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

using ehc_common::ConfigNode;
using ehc_common::requireRange;

namespace ehc_sim {


void CollisionConfig::validate() const {
  requireRange("CollisionConfig", "sim.collision.tolerance", tolerance, 0.0, 0.05);
  self_collision.validate();
}

void GripperConfig::validate() const {
  requireRange("GripperConfig", "sim.gripper.speed", speed, 1e-3, 1.0);
  requireRange("GripperConfig", "sim.gripper.contact_tolerance", contact_tolerance, 0.0, 0.01);
  requireRange("GripperConfig", "sim.gripper.lift_height", lift_height, 0.005, 1.0);
}

void SimulatedCameraConfig::validate() const {
  const char* o = "SimulatedCameraConfig";
  requireRange(o, "sim.camera.image_rate", image_rate, 0.0, 200.0);
  requireRange(o, "sim.camera.cloud_rate", cloud_rate, 0.0, 200.0);
  requireRange(o, "sim.camera.ray_cols", ray_cols, 2, 1280);
  requireRange(o, "sim.camera.ray_rows", ray_rows, 2, 960);
  requireRange(o, "sim.camera.min_range", min_range, 0.0, 10.0);
  requireRange(o, "sim.camera.max_range", max_range, 0.1, 100.0);
  if (!(min_range < max_range))
    throw std::invalid_argument("[SimulatedCameraConfig] sim.camera.min_range must be < max_range");
  depth_noise.validate();
  requireRange(o, "sim.camera.image_noise", image_noise, 0.0, 50.0);
  requireRange(o, "sim.camera.background", background, -1, 255);
  requireRange(o, "sim.camera.tag_pixels_per_cell", tag_pixels_per_cell, 1, 64);
}

namespace {
constexpr ehc_common::EnumNames<DepthNoiseModel, 2> kDepthNoiseModelNames = {
    {{DepthNoiseModel::Gaussian, "gaussian"}, {DepthNoiseModel::Stereo, "stereo"}}};
}  // namespace

std::string toString(DepthNoiseModel m) { return ehc_common::enumName(kDepthNoiseModelNames, m, "DepthNoiseConfig"); }

DepthNoiseModel depthNoiseModelFromString(const std::string& name) {
  return ehc_common::enumValue(kDepthNoiseModelNames, name, "DepthNoiseConfig", "depth noise model");
}

double DepthNoiseConfig::sigma(double z) const {
  if (model == DepthNoiseModel::Gaussian) return base + quadratic * z * z;
  return z * z * subpixel / (focal_px * baseline);
}

void DepthNoiseConfig::validate() const {
  const char* o = "DepthNoiseConfig";
  requireRange(o, "sim.camera.depth_noise.base", base, 0.0, 0.1);
  requireRange(o, "sim.camera.depth_noise.quadratic", quadratic, 0.0, 0.1);
  requireRange(o, "sim.camera.depth_noise.subpixel", subpixel, 0.0, 2.0);
  requireRange(o, "sim.camera.depth_noise.baseline", baseline, 0.005, 1.0);
  requireRange(o, "sim.camera.depth_noise.focal_px", focal_px, 10.0, 1e5);
  requireRange(o, "sim.camera.depth_noise.flying_pixels", flying_pixels, 0.0, 1.0);
  requireRange(o, "sim.camera.depth_noise.edge_jump", edge_jump, 0.001, 1.0);
  requireRange(o, "sim.camera.depth_noise.grazing_angle", grazing_angle, 0.0, 90.0);
}

std::string DepthNoiseConfig::summary() const {
  std::ostringstream os;
  if (model == DepthNoiseModel::Gaussian) {
    os << "gaussian, sigma " << base << " + " << quadratic << " z^2 m";
  } else {
    os << "stereo, sigma z^2 * " << subpixel << " / (" << focal_px << " px * " << baseline << " m) = "
       << sigma(1.0) * 1000.0 << " mm at 1 m, flying pixels " << flying_pixels << " at jumps > " << edge_jump
       << " m, holes beyond " << grazing_angle << " deg";
  }
  return os.str();
}

DepthNoiseConfig loadDepthNoiseConfig(const ConfigNode& n) {
  DepthNoiseConfig d;
  if (n.has("model")) {
    try {
      d.model = depthNoiseModelFromString(n.require<std::string>("model"));
    } catch (const std::invalid_argument& e) {
      n.fail("model", e.what());
    }
  }
  d.base = n.get<double>("base", d.base);
  d.quadratic = n.get<double>("quadratic", d.quadratic);
  d.subpixel = n.get<double>("subpixel", d.subpixel);
  d.baseline = n.get<double>("baseline", d.baseline);
  d.focal_px = n.get<double>("focal_px", d.focal_px);
  d.flying_pixels = n.get<double>("flying_pixels", d.flying_pixels);
  d.edge_jump = n.get<double>("edge_jump", d.edge_jump);
  d.grazing_angle = n.get<double>("grazing_angle", d.grazing_angle);
  n.validate(d);
  return d;
}

void SimConfig::validate() const {
  const char* o = "SimConfig";
  fake_robot.validate();
  requireRange(o, "sim.max_physics_substep", max_physics_substep, 1e-4, 0.02);
  collision.validate();
  gripper.validate();
  camera.validate();
}

int SimConfig::substeps() const {
  return std::max(1, static_cast<int>(std::ceil(fake_robot.dt / max_physics_substep - 1e-9)));
}

std::string SimConfig::summary() const {
  std::ostringstream os;
  os << "sim config " << source_file << "\n"
     << fake_robot.summary()
     << "  camera " << camera_file << ", scene " << scene_file << ", " << substeps()
     << " Bullet sub-steps per step\n"
     << "  collision tolerance " << collision.tolerance << " m, self-collision pairs from "
     << collision.self_collision.samples << " samples (seed " << collision.self_collision.seed << ")\n"
     << "  gripper speed " << gripper.speed << " m/s, lift " << gripper.lift_height << " m\n"
     << "  camera image " << camera.image_rate << " Hz, cloud " << camera.cloud_rate << " Hz ("
     << camera.ray_cols << "x" << camera.ray_rows << " rays, " << camera.min_range << ".."
     << camera.max_range << " m, depth noise " << camera.depth_noise.summary() << ")\n";
  return os.str();
}

std::string simCameraFile(const SimConfig& sim, const ehc_control::RobotConfig& robot) {
  const std::string& f = sim.camera_file.empty() ? robot.camera_info_path : sim.camera_file;
  if (f.empty())
    throw std::invalid_argument("[SimConfig] no camera intrinsics: robot.yaml " + robot.source_file +
                                " names no robot.camera_info and sim.camera_info is not set");
  return f;
}

CollisionConfig loadCollisionConfig(const ConfigNode& n) {
  CollisionConfig c;
  c.tolerance = n.get<double>("tolerance", c.tolerance);
  if (c.tolerance < 0.0 || c.tolerance > 0.05) n.fail("tolerance", "must be in [0, 0.05] m");
  for (const char* key : {"floor_links", "ignore_pairs"})  // robot-specific: live in robot.yaml now
    if (n.has(key))
      n.fail(key, std::string("names robot links: move it to the robot's robot.yaml as robot.collision.") + key);
  c.self_collision.samples = n.get<int>("self_collision_samples", c.self_collision.samples);
  c.self_collision.seed = static_cast<unsigned>(n.get<int>("self_collision_seed", static_cast<int>(c.self_collision.seed)));
  return c;
}

GripperConfig loadGripperConfig(const ConfigNode& n) {
  GripperConfig g;
  g.speed = n.get<double>("speed", g.speed);
  if (!(g.speed > 0.0 && g.speed <= 1.0)) n.fail("speed", "must be in (0, 1] m/s");
  g.contact_tolerance = n.get<double>("contact_tolerance", g.contact_tolerance);
  if (g.contact_tolerance < 0.0 || g.contact_tolerance > 0.01)
    n.fail("contact_tolerance", "must be in [0, 0.01] m");
  g.lift_height = n.get<double>("lift_height", g.lift_height);
  if (!(g.lift_height >= 0.005 && g.lift_height <= 1.0)) n.fail("lift_height", "must be in [0.005, 1] m");
  g.start_open = n.get<bool>("start_open", g.start_open);
  return g;
}

SimulatedCameraConfig loadSimulatedCameraConfig(const ConfigNode& n) {
  SimulatedCameraConfig c;
  c.image_rate = n.get<double>("image_rate", c.image_rate);
  c.cloud_rate = n.get<double>("cloud_rate", c.cloud_rate);
  if (n.has("ray_grid")) {
    const Eigen::VectorXd g = n.requireVector("ray_grid", 2);
    if (g[0] < 2 || g[1] < 2 || g[0] != std::floor(g[0]) || g[1] != std::floor(g[1]))
      n.fail("ray_grid", "must be two whole numbers >= 2: [columns, rows]");
    c.ray_cols = static_cast<int>(g[0]);
    c.ray_rows = static_cast<int>(g[1]);
  }
  c.min_range = n.get<double>("min_range", c.min_range);
  c.max_range = n.get<double>("max_range", c.max_range);
  c.depth_noise = loadDepthNoiseConfig(n.childOrEmpty("depth_noise"));
  c.image_noise = n.get<double>("image_noise", c.image_noise);
  c.background = n.get<int>("background", c.background);
  c.tag_pixels_per_cell = n.get<int>("tag_pixels_per_cell", c.tag_pixels_per_cell);
  if (c.image_rate < 0 || c.image_rate > 200) n.fail("image_rate", "must be in [0, 200] Hz");
  if (c.cloud_rate < 0 || c.cloud_rate > 200) n.fail("cloud_rate", "must be in [0, 200] Hz");
  if (!(c.min_range >= 0 && c.min_range < c.max_range))
    n.fail("min_range", "must be >= 0 and smaller than max_range");
  if (c.max_range > 100) n.fail("max_range", "must be <= 100 m");
  if (c.image_noise < 0 || c.image_noise > 50) n.fail("image_noise", "must be in [0, 50]");
  if (c.background < -1 || c.background > 255) n.fail("background", "must be -1 (floor shade) or 0..255");
  if (c.tag_pixels_per_cell < 1 || c.tag_pixels_per_cell > 64)
    n.fail("tag_pixels_per_cell", "must be in [1, 64]");
  return c;
}

namespace {
SimConfig loadSim(const ConfigNode& root) {
  const ConfigNode s = root.child("sim");
  SimConfig c;
  c.source_file = root.file();
  c.fake_robot = loadFakeRobotConfig(s);
  if (s.has("robot_start"))
    s.fail("robot_start", "is not used by the Bullet simulator: the robot starts at the scene's "
                          "robot_start");
  c.camera_file = s.getPath("camera_info", c.camera_file);
  c.scene_file = s.getPath("scene", c.scene_file);
  c.max_physics_substep = s.get<double>("max_physics_substep", c.max_physics_substep);
  if (!(c.max_physics_substep >= 1e-4 && c.max_physics_substep <= 0.02))
    s.fail("max_physics_substep", "must be in [0.0001, 0.02] s");
  c.collision = loadCollisionConfig(s.childOrEmpty("collision"));
  c.gripper = loadGripperConfig(s.childOrEmpty("gripper"));
  c.camera = loadSimulatedCameraConfig(s.childOrEmpty("camera"));
  root.validate(c);
  root.rejectUnknownKeys();
  return c;
}
}  // namespace

SimConfig loadSimConfig(const std::string& path) {
  return loadSim(ConfigNode::loadFile(path, "SimConfig"));
}

SimConfig loadSimConfigString(const std::string& text, const std::string& origin) {
  return loadSim(ConfigNode::loadString(text, origin, "SimConfig"));
}

}  // namespace ehc_sim
