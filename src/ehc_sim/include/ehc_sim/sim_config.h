#pragma once
// SimConfig: parameters of the Bullet simulator — the settings every fake robot shares
// (FakeRobotConfig: robot, time step, seed, lock-step / free-run, actuation noise) plus
// collision checking, gripper and simulated camera (intrinsics: ehc_control::PinholeCamera from
// loadPinholeCamera(camera_file)) — loaded from a YAML file (top-level key
// `sim`) with one loader per struct. Paths inside the file are resolved against its folder.
// The robot starts at the scene's robot_start (sim.robot_start is an error here). ROS-free.

#include "ehc_sim/fake_robot_config.h"

#include "ehc_control/robot_config.h"
#include "ehc_control/self_collision.h"

#include <Eigen/Core>

#include <string>
#include <utility>
#include <vector>

namespace ehc_common {
class ConfigNode;
}  // namespace ehc_common

namespace ehc_sim {

/// Collision checking. The robot-specific parts live in robot.yaml (ehc_control::RobotConfig):
/// robot.collision.floor_links (links allowed to touch the floor; default the URDF root) and the
/// self-collision pairs never checked (ehc_control::selfCollisionIgnorePairs: adjacent, always
/// in contact, robot.collision.ignore_pairs).
struct CollisionConfig {
  double tolerance = 0.001;  ///< m; a contact deeper than this is a collision
  ehc_control::SelfCollisionSampling self_collision;  ///< sim.collision.self_collision_samples / _seed
  void validate() const;
};

struct GripperConfig {
  double speed = 0.05;              ///< m/s per finger (URDF finger joint velocity)
  double contact_tolerance = 0.002; ///< m; a finger this close to an object touches it
  double lift_height = 0.10;        ///< m; a held object lifted this far = grasp success
  bool start_open = true;
  void validate() const;
};

/// How the simulated depth is disturbed. `gaussian`: Gaussian noise along the ray with sigma =
/// base + quadratic z^2, every sample kept. `stereo`: the D400 family's active-stereo error model
/// (Intel, "Tuning depth cameras for best performance" / "Depth camera performance", RealSense
/// D400 white papers: depth RMS error = z^2 * subpixel / (focal_px * baseline)), with D435
/// figures: subpixel 0.08 (the white papers' typical value on a well-textured scene), baseline
/// 50 mm, focal length 0.5 * 848 px / tan(87 deg / 2) = 447 px (depth stream at 848 x 480, 87 deg
/// horizontal field of view: D400 data sheet); plus flying pixels at depth edges and holes at
/// grazing angles, whose figures are ASSUMPTIONS (no measured source): a sample next to a depth
/// edge (a grid neighbour whose depth is off this sample's
/// surface plane by more than edge_jump) takes, with probability flying_pixels, a depth drawn
/// uniformly between its own and that neighbour's; a surface seen at more than grazing_angle from its normal
/// gives no depth with a probability rising linearly from 0 there to 1 at 90 deg.
enum class DepthNoiseModel { Gaussian, Stereo };
std::string toString(DepthNoiseModel m);
DepthNoiseModel depthNoiseModelFromString(const std::string& name);

struct DepthNoiseConfig {
  DepthNoiseModel model = DepthNoiseModel::Gaussian;
  double base = 0.001;        ///< gaussian: m, sigma at any range
  double quadratic = 0.002;   ///< gaussian: m / m^2, sigma += quadratic z^2
  double subpixel = 0.08;     ///< stereo: disparity RMS error, pixels
  double baseline = 0.050;    ///< stereo: m
  double focal_px = 447.0;    ///< stereo: focal length of the depth stream, pixels
  double flying_pixels = 0.3; ///< stereo: probability of a flying pixel at a depth edge (ASSUMPTION)
  double edge_jump = 0.02;    ///< stereo: m, a neighbour this far off the sample's plane is across an edge (ASSUMPTION)
  double grazing_angle = 75.0;  ///< stereo: deg from the normal where holes start (ASSUMPTION)
  /// Depth noise sigma (m) at depth z (m).
  double sigma(double z) const;
  void validate() const;
  std::string summary() const;
};

struct SimulatedCameraConfig {
  double image_rate = 15.0;   ///< Hz (sim time); 0 = never
  double cloud_rate = 15.0;   ///< Hz (sim time); 0 = never
  int ray_cols = 80;          ///< depth grid (sub-sampled image grid)
  int ray_rows = 60;
  double min_range = 0.10;    ///< m (D435 minimum depth)
  double max_range = 6.0;     ///< m
  DepthNoiseConfig depth_noise;
  double image_noise = 2.0;   ///< grey levels, Gaussian pixel noise sigma (0 = none)
  int background = 110;       ///< grey level where no surface is hit (floor colour if < 0: scene's)
  int tag_pixels_per_cell = 12;  ///< texture resolution of the AprilTag patterns
  void validate() const;
};

struct SimConfig {
  std::string source_file;
  FakeRobotConfig fake_robot;  ///< robot file, dt, seed, stepping policy, noise
  std::string camera_file;  ///< camera_info YAML of the colour stream; "" = robot.yaml's robot.camera_info
  std::string scene_file;   ///< default scene (the node's _scene overrides it)
  double max_physics_substep = 0.005;  ///< s; Bullet steps ceil(dt / this) times per step
  CollisionConfig collision;
  GripperConfig gripper;
  SimulatedCameraConfig camera;

  void validate() const;    ///< throws "[SimConfig] ..."
  std::string summary() const;
  /// Number of Bullet sub-steps per control step.
  int substeps() const;
};

/// The camera_info YAML the simulated camera uses: sim.camera_info if given, else robot.yaml's
/// robot.camera_info. Throws "[SimConfig] ..." when neither names one.
std::string simCameraFile(const SimConfig& sim, const ehc_control::RobotConfig& robot);

SimConfig loadSimConfig(const std::string& path);
SimConfig loadSimConfigString(const std::string& text, const std::string& origin);

CollisionConfig loadCollisionConfig(const ehc_common::ConfigNode& n);
GripperConfig loadGripperConfig(const ehc_common::ConfigNode& n);
SimulatedCameraConfig loadSimulatedCameraConfig(const ehc_common::ConfigNode& n);
DepthNoiseConfig loadDepthNoiseConfig(const ehc_common::ConfigNode& n);

}  // namespace ehc_sim
