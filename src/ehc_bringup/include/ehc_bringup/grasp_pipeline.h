#pragma once
// GraspPipeline: the grasping pipeline of `make demo` in-process, without a ROS master
// (docs/DESIGN.md, simulation). The cores the nodes wrap, stepped in lock-step on sim time:
//
//   SimWorld (Bullet)            ehc_sim_node
//   SimulatedCamera              ehc_sim_node: image / depth cloud when due (StreamClock), only
//                                what perception consumes: the image and the grasps only while
//                                GraspSequencer::wantsPerception() (until the grasp is locked),
//                                the image only if a tag can be found in it (tagInView: one
//                                seen from the front, its black square in the image),
//                                the cloud only when the grasp generator or the obstacle map
//                                takes it (their rate limits)
//   TagDetector + findTargetInWorld   ehc_tag_node (one detection per image serves every object)
//   GraspGenerator + generateForTarget ehc_grasp_node (RateLimiter at max_rate_hz; target = the
//                                sequencer's object pose); for a target without a tag
//                                (the scene's `targets:`) generateForCloudTarget, whose
//                                object centre is also the object's pose (the tag node's part)
//   ObstacleMonitor              ehc_obstacle_node (insert rate, exclusions, distances at its
//                                publish rate)
//   GraspSequencer               ehc_grasp_sequencer_node; its grasp choice judged by GraspReach
//                                against the support plane of the grasp generator's views
//   ControlCycle                 ehc_controller_node
//
// One cycle at sim time t (= world time + 1 s, as ehc_sim_node's clock): sensors due at t ->
// perception -> obstacle distances -> ControlCycle::update(t) -> GraspSequencer::update (goal,
// watched centre, exclusions, gripper for the next cycle) -> SimWorld::step(command). No wall
// clock anywhere: the same configuration and seed give the same run, bit for bit. Perception has
// no transport latency here (the ROS path delivers an image's pose a few ms of wall time later,
// usually before the next state): see the ROS-agreement notes in the experiment's table.

#include "ehc_bringup/grasp_reach.h"
#include "ehc_bringup/grasp_sequencer.h"
#include "ehc_control/control_cycle.h"
#include "ehc_perception/grasp_generator.h"
#include "ehc_perception/obstacle_monitor.h"
#include "ehc_perception/tag_detector.h"
#include "ehc_sim/scene_config.h"
#include "ehc_sim/sim_config.h"

#include <Eigen/Core>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace ehc_sim {
class SimWorld;
class SimulatedCamera;
}  // namespace ehc_sim

namespace ehc_bringup {

/// The files the pipeline reads: those demo.sh gives its nodes (paths as given, relative to the
/// working directory or absolute).
struct GraspPipelineFiles {
  std::string sim;                ///< bullet_sim.yaml (ehc_sim_node)
  std::string scene;              ///< scene YAML; "" = the sim file's
  std::string controller;         ///< controller.yaml (ehc_controller_node)
  std::string sequencer;          ///< grasp_sequencer.yaml (objects, in order)
  std::vector<std::string> tags;  ///< one tag node file per sequencer object (detector + target); none when the scene's `targets:` has no tag target
  std::string grasp;              ///< grasp_node.yaml (generator + targeting)
  std::string obstacles;          ///< obstacle_node.yaml; "" = no obstacle distances (OBSTACLES=0)
  /// The robot (a name or a robot.yaml, ehc_control::resolveRobotFile) for the simulator, the
  /// controller and the obstacle field, as _robot:= does for the nodes; "" = the files' own
  /// (which must then name the same robot).
  std::string robot;
  /// The demo's files under `config_dir` (config/): sim/bullet_sim.yaml, demo/controller.yaml,
  /// demo/<sequencer>, demo/tag_<object>.yaml, perception/grasp_node.yaml, demo/obstacle_node.yaml.
  static GraspPipelineFiles demo(const std::string& config_dir, const std::string& scene,
                                 const std::string& sequencer, const std::vector<std::string>& tag_objects);
};

struct GraspPipelineConfig {
  ehc_sim::SimConfig sim;
  ehc_sim::SceneConfig scene;
  ehc_control::ControlCycleParams cycle;
  GraspSequencerParams sequencer;
  ehc_perception::TagDetectorConfig detector;              ///< the tag nodes' (identical) detector
  std::vector<ehc_perception::TagTargetConfig> tag_targets; ///< per sequencer object
  ehc_perception::GraspGeneratorConfig generator;
  ehc_perception::GraspTargetingParams targeting;
  bool obstacles = true;
  ehc_perception::ObstacleMonitorParams monitor;
  ehc_perception::ObstacleMapConfig map;
  double obstacle_rate_hz = 50.0;  ///< ehc_obstacle_node's publish_rate_hz
  std::string summary() const;
};
/// Loads every file with the nodes' loaders (unknown keys: errors, as in the nodes). Throws
/// std::invalid_argument naming the file and field.
GraspPipelineConfig loadGraspPipelineConfig(const GraspPipelineFiles& files);

/// Name of the scene body (table part, object, obstacle) or "floor" nearest to `p` (world), at
/// the bodies' current poses (ehc_sim::nearestBody; ground truth: names a perceived obstacle
/// point for the safety table and a stall held by an obstacle).
std::string nearestSceneBody(const ehc_sim::SimWorld& world, const Eigen::Vector3d& p);

/// One perceived link-obstacle pair as the controller received it (safety metrics).
struct ObstaclePairRecord {
  double distance = -1.0;  ///< m; -1: no pair this cycle
  double stop = 0.0;       ///< m, d_s of the link
  std::string link;
  Eigen::Vector3d obstacle_point = Eigen::Vector3d::Zero();  ///< world
  double margin() const { return distance - stop; }
};

/// What one cycle did (for metrics and traces).
struct PipelineCycle {
  double t = 0.0;                        ///< sim time of the state, s
  std::size_t object = 0;                ///< sequencer's current object (before the update)
  GraspPhase phase = GraspPhase::WaitTarget;  ///< sequencer phase after the update
  ehc_control::ControlCycleStatus status;
  Eigen::VectorXd command;               ///< [base twist; arm rates] sent to the sim
  /// The link-obstacle pairs the controller received this cycle (empty: none), with each link's
  /// stop distance d_s (controller obstacle_stop[_links]).
  std::vector<ObstaclePairRecord> obstacle_pairs;
  bool collision = false;                ///< the sim step found a robot-world or self collision
  int joint_limit_violations = 0;        ///< arm joints outside their limits after the step
  std::vector<std::string> events;       ///< the sequencer's progress lines of this cycle
};

/// Ground truth of one depth view taken for a sequencer object's grasps (world frame): what the
/// grasp judge needs to say whether a valid grasp existed in it.
struct ObjectViewRecord {
  double t = -1.0;  ///< s, sim time of the view's depth cloud; -1: none
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();     ///< the true camera pose
  Eigen::Isometry3d T_world_object = Eigen::Isometry3d::Identity();  ///< the object's true pose
  std::vector<GraspCandidate> candidates;  ///< the grasp generator's in this view (the stack's world frame)
  /// The grasp generator's outcome in this view: why it gave no grasp (None: it gave some) and
  /// its reason line (GraspResult::failure / reason).
  ehc_perception::GraspFailure failure = ehc_perception::GraspFailure::None;
  std::string reason;
  /// A target without a tag: what the cloud's target selection gave in this view (NotCloudTarget
  /// for a tag target).
  ehc_control::TargetSelectionStatus target = ehc_control::TargetSelectionStatus::NotCloudTarget;
};

/// What one sequencer object's attempt committed to, recorded for the grasp judge
/// (GraspExperiment judges it after the run; the control loop only copies these). Ground truth,
/// world frame: the grasp is the stack's, moved into the true world (the same pose when the
/// odometry is the truth, see GraspPipeline::stackView).
struct GraspAttemptRecord {
  /// A grasp was locked (PRE_GRASP): the grasp the sequencer committed to and went for.
  bool locked = false;
  /// A grasp was chosen: the locked one, else the last one chosen before the object ended (the
  /// robot drove to its pre-grasp and the object failed before the lock).
  bool chosen = false;
  GraspCandidate grasp;           ///< that grasp: pose (true world) and width (score unset)
  /// The generator's candidate it was chosen from, as generated (true world): before the
  /// selection turned it onto the wanted approach or centred it (GraspSelectionParams).
  std::optional<GraspCandidate> candidate;
  ObjectViewRecord grasp_view;    ///< the view its candidate set came from (GraspChoice::candidates_t)
  Eigen::Isometry3d T_world_object_at_choice = Eigen::Isometry3d::Identity();  ///< at the lock (else at the end)
  /// The last depth view taken for the object's grasps in which its true centre projected into
  /// the image (t -1: none).
  ObjectViewRecord last_seen;
  ObjectViewRecord end;           ///< camera and object when the object's attempt ended (t -1: never)
};

/// Work done so far (counts, and wall seconds per stage for `make bench`).
struct PipelineCounters {
  long cycles = 0, images = 0, clouds = 0, tag_detections = 0, grasp_runs = 0, obstacle_updates = 0;
  long images_without_tags = 0;  ///< images due but not rendered: no tag to find (SimulatedCamera::tagInView)
  /// TagDetector: images searched whole / in a window / not searched (no wanted tag can be in view)
  long tag_whole_searches = 0, tag_window_searches = 0, tag_skipped_searches = 0;
  long collision_steps = 0, joint_limit_violations = 0;
  double wall_image = 0.0, wall_depth = 0.0, wall_tags = 0.0, wall_grasps = 0.0, wall_obstacles = 0.0,
         wall_control = 0.0, wall_sequencer = 0.0, wall_physics = 0.0;
  PipelineCounters& add(const PipelineCounters& o);  ///< adds another run's counts and times
};

class GraspPipeline {
 public:
  /// Builds the world (scene of `cfg`, noise seed `seed`) and every core.
  GraspPipeline(const GraspPipelineConfig& cfg, unsigned seed);
  ~GraspPipeline();
  GraspPipeline(const GraspPipeline&) = delete;
  GraspPipeline& operator=(const GraspPipeline&) = delete;

  /// One lock-step cycle (see the header comment).
  const PipelineCycle& step();
  /// Steps until the sequencer is done or `sim_time_limit` s of sim time have passed; returns
  /// whether it is done.
  bool runUntilDone(double sim_time_limit);

  bool done() const { return sequencer_->done(); }
  double time() const;  ///< sim time of the current state, s
  const GraspSequencer& sequencer() const { return *sequencer_; }
  const ehc_sim::SimWorld& world() const { return *world_; }
  const ehc_control::ControlCycle& cycle() const { return *cycle_; }
  const PipelineCounters& counters() const { return counters_; }
  const PipelineCycle& last() const { return last_; }
  /// Per sequencer object: the grasp it committed to and the views it came from (for the judge).
  const std::vector<GraspAttemptRecord>& attempts() const { return attempts_; }
  /// Measure wall time per stage (counters().wall_*); off by default (no clock reads).
  void setTiming(bool on) { timing_ = on; }

 private:
  void perceive(double t);
  void updateObstacles(double t);
  /// The stack's view of a world pose of a robot frame: what tf gives the nodes. Ideal base
  /// without imprecision: the true pose (unchanged, bit for bit). Otherwise (water2: the
  /// bridge's estimate; base imprecision: the drifting odometry) /odom is not the truth, so every
  /// robot frame the nodes look up (camera, TCP) is the true one moved by the odometry error:
  /// odom_T_base(estimate) * base_T_frame(true). Perception then puts a tag or a cloud where the
  /// odometry says the camera was, as on the robot.
  Eigen::Isometry3d stackView(const Eigen::Isometry3d& T_world_frame) const;
  /// The base pose the nodes get from /odom (x, y, yaw).
  Eigen::Vector3d odometryPose() const;
  /// stackView's inverse: a pose the stack gives (its world frame) in the true world.
  Eigen::Isometry3d trueView(const Eigen::Isometry3d& T_stack_frame) const;
  /// Ground truth now: the true camera pose and object `object`'s true pose, stamped t.
  ObjectViewRecord viewNow(double t, std::size_t object) const;
  /// A depth view taken for object `object`'s grasps (stamped t) and the candidates the generator
  /// found in it (with the generator's outcome and the cloud target's selection): kept until the object changes,
  /// and its last_seen when the object's centre projects into the image.
  void recordView(double t, std::size_t object, const std::vector<GraspCandidate>& candidates,
                  const ehc_perception::GraspResult& result,
                  ehc_control::TargetSelectionStatus target = ehc_control::TargetSelectionStatus::NotCloudTarget);
  /// After the sequencer's update of `object`: its grasp record when it locks a grasp or ends.
  void recordAttempt(double t, std::size_t object, std::size_t results_before);

  GraspPipelineConfig cfg_;
  std::unique_ptr<ehc_sim::SimWorld> world_;
  std::unique_ptr<ehc_sim::SimulatedCamera> camera_;
  std::unique_ptr<ehc_control::ControlCycle> cycle_;
  std::unique_ptr<GraspSequencer> sequencer_;
  std::unique_ptr<ehc_perception::TagDetector> detector_;
  std::unique_ptr<ehc_perception::GraspGenerator> generator_;
  std::unique_ptr<ehc_perception::ObstacleMonitor> monitor_;
  /// The sequencer's reachability judgement (sequencer.reach.enabled), its support from the
  /// grasp generator's support plane in each cloud (observeSupport).
  std::unique_ptr<GraspReach> reach_;
  void observeSupport(const ehc_perception::PointList& points, const ehc_perception::GraspResult& r);
  /// GraspReach's view of the obstacle map: the checked links' distances with the robot at
  /// (base, q), the map with the exclusions the sequencer plans before (`descent` false) or
  /// during the descent.
  std::vector<std::pair<std::string, double>> plannedMapDistances(const Eigen::Vector3d& base, const Eigen::VectorXd& q,
                                                                  bool descent) const;
  /// Hands the controller's stall recovery (ControlCycle::setGivenPlans) the locked grasp's
  /// pre-grasp and grasp configurations at its placement from GraspReach's verdict while the
  /// sequencer is in PRE_GRASP or GRASP, none otherwise; only when the lock, the locked pose or
  /// GraspReach's kept verdicts (GraspReach::keptRevision) have changed since the last time.
  void updateGivenPlans();
  struct GivenPlansKey {
    bool locked = false;
    Eigen::Matrix4d pose = Eigen::Matrix4d::Zero();  ///< the locked grasp's (locked)
    std::uint64_t kept = 0;                          ///< GraspReach::keptRevision
    bool same(const GivenPlansKey& o) const;
  };
  std::optional<GivenPlansKey> given_key_;
  /// Its revision: changes with the map's (ObstacleDistanceField::revision) and whenever the
  /// planned exclusions move.
  std::uint64_t plannedMapRevision();
  struct PlannedMapKey {
    std::uint64_t map = 0;
    std::vector<ehc_perception::ExclusionZone> zones;  ///< before, then during the descent
  };
  PlannedMapKey planned_key_;
  std::uint64_t planned_revision_ = 0;
  /// The exclusion zones the sequencer plans before (`descent` false) or during the descent.
  std::vector<ehc_perception::ExclusionZone> plannedZones(bool descent) const;
  struct Clocks;
  std::unique_ptr<Clocks> clocks_;
  std::optional<Eigen::Vector3d> grasp_target_;  ///< the sequencer's object pose (grasp node target)
  double grasp_target_t_ = -1.0;
  std::size_t grasp_target_object_ = 0;  ///< the sequencer object grasp_target_ belongs to
  /// The grasp node's work on a cloud for a cloud target (ehc_control::TargetSelector): the
  /// target's pose (ehc_control::cloudTargetPose of its cloud centre) or why there is none, and
  /// its candidates, to the sequencer.
  void perceiveCloudTarget(double t, const ehc_perception::PointList& points, const Eigen::Isometry3d& T_world_cam,
                           std::size_t object);
  bool excluding_ = false;
  std::vector<std::string> arm_names_;
  PipelineCycle last_;
  PipelineCounters counters_;
  ehc_control::PinholeCamera intrinsics_;
  std::vector<GraspAttemptRecord> attempts_;
  std::vector<ObjectViewRecord> views_;  ///< the current object's grasp views (recordView)
  std::size_t views_object_ = 0;
  bool timing_ = false;
};

}  // namespace ehc_bringup
