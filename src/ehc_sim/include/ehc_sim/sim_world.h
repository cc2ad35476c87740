#pragma once
// SimWorld: the Bullet physics world of the simulator. Built from a SceneConfig (floor plane,
// tables, dynamic objects, static obstacles) and the robot's URDF collision geometry, whose
// links are kinematic bodies following the KinematicFakeRobot (integrated, noisy joint state)
// through WholeBodyModel forward kinematics. Each control step is split into Bullet sub-steps
// with the robot interpolated between its old and new state; robot-world and self collisions
// are reported, and a ParallelGripper grasps objects its two fingers touch (a held object is
// made kinematic and follows the gripper). Deterministic: reset(seed) rebuilds the world.
// ROS-free (Bullet, Eigen, KDL via ehc_control::WholeBodyModel).

#include "ehc_control/robot_collision_model.h"
#include "ehc_control/robot_config.h"
#include "ehc_control/whole_body_model.h"
#include "ehc_sim/kinematic_fake_robot.h"
#include "ehc_sim/parallel_gripper.h"
#include "ehc_sim/scene_config.h"
#include "ehc_sim/sim_config.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <memory>
#include <set>
#include <string>
#include <vector>

namespace ehc_sim {

/// One collision found in a step (deepest point per body pair).
struct CollisionContact {
  std::string a;  ///< robot link
  std::string b;  ///< robot link (self collision), scene body or "floor"
  double distance = 0.0;  ///< m, negative = penetration
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  ///< world, on a
  bool self = false;
};

struct StepReport {
  bool robot_world_collision = false;  ///< a robot link hit the floor, a table, an obstacle, or
                                       ///< a non-gripper link hit an object
  bool self_collision = false;
  std::vector<CollisionContact> collisions;  ///< deduplicated per pair
};

/// Counters since the last reset.
struct SimCounters {
  long steps = 0;
  long collision_steps = 0;       ///< steps with a robot-world collision
  long self_collision_steps = 0;  ///< steps with a self collision
};

class SimWorld {
 public:
  /// Builds the world. The robot starts at the scene's robot_start with the arm in its ready
  /// pose. Throws std::invalid_argument "[SimWorld] ..." (or the loaders' messages) on a bad
  /// URDF / configuration.
  SimWorld(const SimConfig& cfg, const ehc_control::RobotConfig& robot, const SceneConfig& scene);
  ~SimWorld();
  SimWorld(const SimWorld&) = delete;
  SimWorld& operator=(const SimWorld&) = delete;

  /// Back to the scene's initial state (objects, robot start, ready arm, gripper), time 0,
  /// counters zero; actuation noise reseeded with `seed`.
  void reset(unsigned seed);
  /// Loads another scene and resets.
  void setScene(const SceneConfig& scene, unsigned seed);

  /// Executes one control step of cfg.fake_robot.dt: `command` = [base twist (base frame); arm rates]
  /// (KinematicFakeRobot order and checks; throws on a wrong size or NaN).
  const StepReport& step(const Eigen::VectorXd& command);
  /// Teleports the robot (tests, tools); objects are untouched. Does not advance time.
  void setRobotState(const Eigen::Vector3d& base_pose, const Eigen::VectorXd& q);
  /// The Water2 base's own API (hardware stand-in): KinematicFakeRobot::joyControlReceived.
  void baseJoyControlReceived(double linear, double angular) { robot_.joyControlReceived(linear, angular); }
  /// Open (false) / close (true) the gripper.
  void commandGripper(bool close) { gripper_.command(close); }

  // ------------------------------------------------------------------ state
  double time() const { return static_cast<double>(step_count_) * cfg_.fake_robot.dt; }
  std::int64_t timeNs() const { return step_count_ * dt_ns_; }
  std::int64_t dtNs() const { return dt_ns_; }
  long stepCount() const { return step_count_; }
  const KinematicFakeRobot& robot() const { return robot_; }
  const ehc_control::WholeBodyModel& model() const { return *model_; }
  const ehc_control::RobotCollisionModel& collisionModel() const { return *collision_model_; }
  const ParallelGripper& gripper() const { return gripper_; }
  const StepReport& lastStep() const { return report_; }
  const SimCounters& counters() const { return counters_; }
  const SimConfig& config() const { return cfg_; }
  const SceneConfig& scene() const { return scene_; }

  /// World pose of any URDF link (finger links include the current opening).
  Eigen::Isometry3d linkPose(const std::string& link) const;
  /// Pose of any URDF link relative to its URDF parent (for tf), finger opening included.
  Eigen::Isometry3d linkPoseInParent(const std::string& link) const;
  Eigen::Isometry3d cameraPose() const;  ///< camera optical frame in the world
  /// Pose of the Bullet body of a robot link with geometry (what collisions are checked on).
  Eigen::Isometry3d linkBodyPose(const std::string& link) const;

  /// Every scene body (table parts, then objects, then obstacles) and its current pose.
  const std::vector<BodyConfig>& bodies() const { return bodies_; }
  Eigen::Isometry3d bodyPose(int i) const;
  int objectBodyIndex(int object) const { return first_object_ + object; }
  /// Current pose of object `i` (scene.objects order).
  Eigen::Isometry3d objectPose(int i) const { return bodyPose(objectBodyIndex(i)); }
  /// The triangles of body `i` in its frame (what the depth camera rasterises): boxes and
  /// meshes exactly, cylinders as 96-sided prisms.
  const TriangleMesh& bodySurface(int i) const { return *surfaces_.at(static_cast<std::size_t>(i)); }
  /// Pose of the tag printed on body `i` (only if bodies()[i].tag.enabled).
  Eigen::Isometry3d tagPose(int i) const;

  /// Finds collisions of the current configuration without advancing time (tests, tools).
  StepReport checkCollisions();

 private:
  struct Impl;
  void build();
  void placeRobot(const Eigen::Vector3d& base, const Eigen::VectorXd& q);
  void syncKinematicBodies();
  void collectContacts(StepReport* report, std::set<int>* left, std::set<int>* right) const;

  SimConfig cfg_;
  ehc_control::RobotConfig robot_cfg_;
  SceneConfig scene_;
  std::unique_ptr<ehc_control::WholeBodyModel> model_;
  std::unique_ptr<ehc_control::RobotCollisionModel> collision_model_;
  std::set<ehc_control::LinkPair> ignored_pairs_;  ///< self-collision pairs never checked
  std::vector<std::string> floor_links_;           ///< links allowed to touch the floor
  KinematicFakeRobot robot_;
  ParallelGripper gripper_;
  std::vector<BodyConfig> bodies_;
  std::vector<std::shared_ptr<const TriangleMesh>> surfaces_;  ///< per body
  int first_object_ = 0;
  std::int64_t dt_ns_ = 0;
  long step_count_ = 0;
  StepReport report_;
  SimCounters counters_;
  Eigen::Isometry3d held_in_gripper_ = Eigen::Isometry3d::Identity();
  int attached_body_ = -1;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ehc_sim
