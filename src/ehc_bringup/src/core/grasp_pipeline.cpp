#include "ehc_bringup/grasp_pipeline.h"
#include "ehc_control/controller_node_config.h"

#include "ehc_common/config_node.h"
#include "ehc_perception/point_cloud_layout.h"
#include "ehc_perception/rate_limiter.h"
#include "ehc_sim/sim_world.h"
#include "ehc_sim/simulated_camera.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

using ehc_common::ConfigNode;

namespace ehc_bringup {

namespace {

/// Adds the wall seconds of its lifetime to `*sink` when timing is on (no clock read otherwise).
class StageTimer {
 public:
  StageTimer(bool on, double* sink) : sink_(on ? sink : nullptr) {
    if (sink_) t0_ = std::chrono::steady_clock::now();
  }
  ~StageTimer() {
    if (sink_) *sink_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
  }

 private:
  double* sink_;
  std::chrono::steady_clock::time_point t0_;
};

constexpr double kSimClockOffset = 1.0;  ///< s: ehc_sim_node's clock starts at 1 s

}  // namespace

std::string nearestSceneBody(const ehc_sim::SimWorld& world, const Eigen::Vector3d& p) {
  return ehc_sim::nearestBody(world.bodies(), [&world](int i) { return world.bodyPose(i); }, p);
}

GraspPipelineFiles GraspPipelineFiles::demo(const std::string& config_dir, const std::string& scene,
                                            const std::string& sequencer, const std::vector<std::string>& tag_objects) {
  GraspPipelineFiles f;
  f.sim = config_dir + "/sim/bullet_sim.yaml";
  f.scene = scene;
  f.controller = config_dir + "/demo/controller.yaml";
  f.sequencer = sequencer;
  for (const auto& o : tag_objects) f.tags.push_back(config_dir + "/demo/tag_" + o + ".yaml");
  f.grasp = config_dir + "/perception/grasp_node.yaml";
  f.obstacles = config_dir + "/demo/obstacle_node.yaml";
  return f;
}

GraspPipelineConfig loadGraspPipelineConfig(const GraspPipelineFiles& files) {
  GraspPipelineConfig c;
  c.sim = ehc_sim::loadSimConfig(files.sim);
  const std::string scene = files.scene.empty() ? c.sim.scene_file : files.scene;
  if (scene.empty()) throw std::invalid_argument("[GraspPipeline] no scene: the sim file names none and none was given");
  c.scene = ehc_sim::loadSceneConfig(scene);
  {
    const auto root = ConfigNode::loadFile(files.controller, "GraspPipeline");
    c.cycle = ehc_control::loadControlCycleParams(root);
    ehc_control::loadControllerNodeParams(root);  // the node's section: checked as the node reads it, unused here
    root.rejectUnknownKeys();
  }
  c.sequencer = loadGraspSequencerParams(ConfigNode::loadFile(files.sequencer, "GraspPipeline"));
  const bool all_cloud = !c.scene.targets.empty() &&
                         std::all_of(c.scene.targets.begin(), c.scene.targets.end(),
                                     [](const ehc_control::TargetSelector& s) { return s.fromCloud(); });
  if (!c.scene.targets.empty() && c.scene.targets.size() != c.sequencer.objects.size())
    throw std::invalid_argument("[GraspPipeline] " + c.scene.source_file + ": scene.targets lists " +
                                std::to_string(c.scene.targets.size()) + " target(s) for " +
                                std::to_string(c.sequencer.objects.size()) + " sequencer object(s) in " + files.sequencer);
  if (!(all_cloud && files.tags.empty()) && files.tags.size() != c.sequencer.objects.size())
    throw std::invalid_argument("[GraspPipeline] " + std::to_string(files.tags.size()) + " tag file(s) for " +
                                std::to_string(c.sequencer.objects.size()) + " sequencer object(s) in " + files.sequencer);
  for (std::size_t i = 0; i < files.tags.size(); ++i) {
    const auto root = ConfigNode::loadFile(files.tags[i], "GraspPipeline");
    const auto detector = ehc_perception::loadTagDetectorConfig(root.childOrEmpty("tag_detector"));
    if (i == 0) c.detector = detector;
    else if (detector.summary() != c.detector.summary())
      throw std::invalid_argument("[GraspPipeline] " + files.tags[i] + ": tag_detector differs from " + files.tags[0] +
                                  "'s (one detection serves every object in-process)");
    c.tag_targets.push_back(ehc_perception::loadTagTargetConfig(root.childOrEmpty("target")));
  }
  // Each object's target: the scene's `targets:` entry, else its tag file's tag.
  for (std::size_t i = 0; i < c.sequencer.objects.size(); ++i) {
    ehc_control::TargetSelector& target = c.sequencer.objects[i].target;
    if (!c.scene.targets.empty()) target = c.scene.targets[i];
    if (target.fromCloud()) continue;
    const int file_id = c.tag_targets[i].tag_id;
    if (!c.scene.targets.empty() && target.tag_id != file_id)
      throw std::invalid_argument("[GraspPipeline] " + c.scene.source_file + ": scene.targets[" + std::to_string(i) +
                                  "].tag_id " + std::to_string(target.tag_id) + " differs from " + files.tags[i] +
                                  "'s target.tag_id " + std::to_string(file_id));
    target.tag_id = file_id;
  }
  {
    const auto root = ConfigNode::loadFile(files.grasp, "GraspPipeline");
    c.targeting = ehc_perception::loadGraspTargetingParams(root.childOrEmpty("node"));
    c.generator = ehc_perception::loadGraspGeneratorConfig(root.childOrEmpty("grasp_generator"));
  }
  c.obstacles = !files.obstacles.empty();
  if (c.obstacles) {
    const auto root = ConfigNode::loadFile(files.obstacles, "GraspPipeline");
    const auto n = root.child("node");
    n.ignore("robot_config");  // in-process the obstacle field checks the simulator's robot
    c.monitor = ehc_perception::loadObstacleMonitorParams(n);
    c.obstacle_rate_hz = n.getInRange("publish_rate_hz", c.obstacle_rate_hz, 0.1, 1000.0);
    c.map = ehc_perception::loadObstacleMapConfig(root.childOrEmpty("obstacle_map"));
  }
  if (!files.robot.empty()) {
    const std::string robot = ehc_control::resolveRobotFile(files.robot);
    c.sim.fake_robot.robot_file = robot;
    c.cycle.robot_file = robot;
  } else if (c.sim.fake_robot.robot_file != c.cycle.robot_file) {
    throw std::invalid_argument("[GraspPipeline] the simulator's robot (" + c.sim.fake_robot.robot_file + ", " +
                                files.sim + ") differs from the controller's (" + c.cycle.robot_file + ", " +
                                files.controller + "); name one robot (GraspPipelineFiles::robot, --robot)");
  }
  return c;
}

std::string GraspPipelineConfig::summary() const {
  std::ostringstream os;
  os << "GraspPipeline (in-process): scene '" << scene.name << "', " << sequencer.objects.size()
     << " object(s), controller mode " << ehc_control::toString(cycle.controller.mode) << ", servo "
     << ehc_control::toString(cycle.servo_type) << (cycle.mpbs.enabled ? " + MPBS" : "") << ", image "
     << sim.camera.image_rate << " Hz, cloud " << sim.camera.cloud_rate << " Hz, "
     << targeting.summary() << ", obstacles "
     << (obstacles ? "on (" + std::to_string(obstacle_rate_hz) + " Hz)" : std::string("off"));
  return os.str();
}

PipelineCounters& PipelineCounters::add(const PipelineCounters& o) {
  cycles += o.cycles;
  images += o.images;
  clouds += o.clouds;
  tag_detections += o.tag_detections;
  grasp_runs += o.grasp_runs;
  obstacle_updates += o.obstacle_updates;
  images_without_tags += o.images_without_tags;
  tag_whole_searches += o.tag_whole_searches;
  tag_window_searches += o.tag_window_searches;
  tag_skipped_searches += o.tag_skipped_searches;
  collision_steps += o.collision_steps;
  joint_limit_violations += o.joint_limit_violations;
  wall_image += o.wall_image;
  wall_depth += o.wall_depth;
  wall_tags += o.wall_tags;
  wall_grasps += o.wall_grasps;
  wall_obstacles += o.wall_obstacles;
  wall_control += o.wall_control;
  wall_sequencer += o.wall_sequencer;
  wall_physics += o.wall_physics;
  return *this;
}

struct GraspPipeline::Clocks {
  ehc_sim::StreamClock image, cloud, obstacles;
  ehc_perception::RateLimiter grasp;
};

GraspPipeline::GraspPipeline(const GraspPipelineConfig& cfg, unsigned seed) : cfg_(cfg) {
  cfg_.sim.fake_robot.seed = seed;
  const ehc_control::RobotConfig robot = ehc_control::loadRobotConfig(cfg_.sim.fake_robot.robot_file);
  const ehc_control::PinholeCamera intrinsics = ehc_control::loadPinholeCamera(ehc_sim::simCameraFile(cfg_.sim, robot));
  intrinsics_ = intrinsics;
  attempts_.resize(cfg_.sequencer.objects.size());
  world_ = std::make_unique<ehc_sim::SimWorld>(cfg_.sim, robot, cfg_.scene);
  camera_ = std::make_unique<ehc_sim::SimulatedCamera>(intrinsics, cfg_.sim.camera, seed);
  camera_->setScene(world_->bodies(), cfg_.scene.floor_shade);
  cycle_ = std::make_unique<ehc_control::ControlCycle>(cfg_.cycle);
  sequencer_ = std::make_unique<GraspSequencer>(cfg_.sequencer);
  if (!sequencer_->setCamera(intrinsics)) throw std::invalid_argument("[GraspPipeline] invalid camera intrinsics");
  sequencer_->setObstacleNamer([this](const Eigen::Vector3d& p) { return nearestSceneBody(*world_, p); });
  if (cfg_.sequencer.reach.enabled) {
    // The grasps the robot can reach beside the support the grasp generator finds (perceive).
    const ehc_control::QpControllerParams& qp = cycle_->controller().params();
    reach_ = std::make_unique<GraspReach>(
        cycle_->model(), cfg_.sequencer.reach, [&qp](const std::string& link) { return qp.obstacleStop(link); }, qp.joint_stop);
    sequencer_->setReachability(
        [this](const Eigen::Isometry3d& grasp, const Eigen::Isometry3d& pre) { return reach_->reachable(grasp, pre); });
  }
  detector_ = std::make_unique<ehc_perception::TagDetector>(cfg_.detector, intrinsics);
  generator_ = std::make_unique<ehc_perception::GraspGenerator>(cfg_.generator);
  if (cfg_.obstacles) monitor_ = std::make_unique<ehc_perception::ObstacleMonitor>(robot, cfg_.map, cfg_.monitor);
  if (reach_ && monitor_)
    reach_->setMapDistances(
        [this](const Eigen::Vector3d& base, const Eigen::VectorXd& q, bool descent) {
          return plannedMapDistances(base, q, descent);
        },
        [this] { return plannedMapRevision(); });
  const bool perceive_tags = !cfg_.tag_targets.empty();
  clocks_ = std::make_unique<Clocks>(Clocks{ehc_sim::StreamClock(perceive_tags ? cfg_.sim.camera.image_rate : 0.0),
                                            ehc_sim::StreamClock(cfg_.sim.camera.cloud_rate),
                                            ehc_sim::StreamClock(cfg_.obstacles ? cfg_.obstacle_rate_hz : 0.0),
                                            ehc_perception::RateLimiter(cfg_.targeting.max_rate_hz)});
  arm_names_ = robot.arm_joints;
}

GraspPipeline::~GraspPipeline() = default;

double GraspPipeline::time() const { return world_->time() + kSimClockOffset; }

void GraspPipeline::perceive(double t) {
  const std::int64_t t_ns = world_->timeNs();
  const bool consumed = sequencer_->wantsPerception();
  if (clocks_->image.due(t_ns) && consumed) {
    vpImage<unsigned char> image;
    std::vector<ehc_perception::TagDetection> detections;
    const std::size_t target = std::min(sequencer_->currentObject(), cfg_.tag_targets.size() - 1);
    detector_->setWantedTags({cfg_.tag_targets[target].tag_id});  // tracking window: see TagDetector
    bool tag_in_view = false;
    {
      StageTimer timer(timing_, &counters_.wall_image);
      // An image in which no tag can be found (none seen from the front with its black square in
      // the image, SimulatedCamera::tagInView) is neither rendered nor searched; the noise stream
      // advances as if it were, so the run is the one that searched it and found nothing.
      tag_in_view = camera_->tagInView(*world_);
      if (tag_in_view) camera_->render(*world_, &image);
      else camera_->skipImage();
    }
    const Eigen::Isometry3d T_world_cam = stackView(world_->cameraPose());
    if (tag_in_view) {
      ++counters_.images;
      StageTimer timer(timing_, &counters_.wall_tags);
      detections = detector_->detect(image, T_world_cam);  // the camera pose: ambiguity prior
      counters_.tag_whole_searches = detector_->fullFrameSearches();
      counters_.tag_window_searches = detector_->windowSearches();
      counters_.tag_skipped_searches = detector_->skippedSearches();
    } else {
      ++counters_.images_without_tags;
      detector_->resetTracking();  // as a search that found nothing: the next image is searched whole
    }
    for (std::size_t i = 0; i < cfg_.tag_targets.size(); ++i) {
      Eigen::Isometry3d T_world;
      if (!ehc_perception::findTargetInWorld(detections, cfg_.tag_targets[i], T_world_cam, &T_world)) continue;
      ++counters_.tag_detections;
      sequencer_->setObjectPose(i, t, T_world);
    }
  }
  // The depth cloud is rendered only when the grasp generator or the obstacle map takes it.
  if (!clocks_->cloud.due(t_ns)) return;
  const bool want_grasps = consumed && clocks_->grasp.accept(t);
  const bool want_obstacles = monitor_ && monitor_->acceptCloud(t);
  if (!want_grasps && !want_obstacles) return;
  std::vector<Eigen::Vector3f> cam_points;
  {
    StageTimer timer(timing_, &counters_.wall_depth);
    camera_->cloud(*world_, &cam_points);
  }
  ++counters_.clouds;
  const Eigen::Isometry3d T_world_cam = stackView(world_->cameraPose());
  const ehc_perception::PointList points = ehc_perception::transformPoints(cam_points, T_world_cam);
  const std::size_t current = sequencer_->currentObject();
  if (want_grasps && current < cfg_.sequencer.objects.size() && cfg_.sequencer.objects[current].target.fromCloud()) {
    StageTimer timer(timing_, &counters_.wall_grasps);
    perceiveCloudTarget(t, points, T_world_cam, current);
  } else if (want_grasps) {
    StageTimer timer(timing_, &counters_.wall_grasps);
    const bool fresh = grasp_target_ && t - grasp_target_t_ <= cfg_.targeting.target_timeout;
    const ehc_perception::GraspResult res = ehc_perception::generateForTarget(
        *generator_, points, T_world_cam.translation(), fresh ? &*grasp_target_ : nullptr, cfg_.targeting);
    observeSupport(points, res);
    std::vector<GraspCandidate> candidates;
    for (const auto& g : res.grasps) candidates.push_back({g.pose, g.width, g.score});
    sequencer_->setGraspCandidates(t, candidates);
    recordView(t, current, candidates, res);
    ++counters_.grasp_runs;
  }
  if (want_obstacles) {
    StageTimer timer(timing_, &counters_.wall_obstacles);
    monitor_->insertCloud(t, points, T_world_cam.translation());
  }
}

void GraspPipeline::perceiveCloudTarget(double t, const ehc_perception::PointList& points,
                                        const Eigen::Isometry3d& T_world_cam, std::size_t object) {
  // Tracked: the sequencer's pose of this object (not of the one before it) is fresh.
  const bool tracked = grasp_target_ && grasp_target_object_ == object &&
                       t - grasp_target_t_ <= cfg_.targeting.target_timeout;
  const ehc_perception::CloudTargetResult r = ehc_perception::generateForCloudTarget(
      *generator_, points, T_world_cam, cfg_.sequencer.objects[object].target, tracked ? &*grasp_target_ : nullptr,
      cfg_.targeting);
  if (r.selection.selected()) {
    sequencer_->setObjectPose(object, t, ehc_control::cloudTargetPose(r.selection.centre, T_world_cam.translation(), cfg_.generator.up));
    // Its extent (the obstacle map's exclusion from the descent on): its cluster's.
    if (const auto extent = ehc_perception::cloudTargetExtent(r, T_world_cam.translation(), cfg_.generator.up))
      sequencer_->setObjectExtent(object, *extent);
  } else
    sequencer_->setNoTarget(object, r.selection.detail);
  observeSupport(points, r.grasps);
  std::vector<GraspCandidate> candidates;
  for (const auto& g : r.grasps.grasps) candidates.push_back({g.pose, g.width, g.score});
  sequencer_->setGraspCandidates(t, candidates);
  recordView(t, object, candidates, r.grasps, r.selection.status);
  ++counters_.grasp_runs;
}

void GraspPipeline::observeSupport(const ehc_perception::PointList& points, const ehc_perception::GraspResult& r) {
  if (!reach_ || !r.support_plane_found) return;
  if (const auto seen = supportFromPoints(points, r.support_plane)) reach_->observeSupport(*seen);
}

bool GraspPipeline::GivenPlansKey::same(const GivenPlansKey& o) const {
  return locked == o.locked && pose == o.pose && kept == o.kept;
}

void GraspPipeline::updateGivenPlans() {
  // The locked grasp's placement and configurations from its reachability verdict, while the
  // controller approaches it: where a stall at its pre-grasp or grasp recovers to.
  const GraspPhase phase = sequencer_->phase();
  const std::optional<GraspChoice>& choice = sequencer_->lastChoice();
  const bool locked =
      (phase == GraspPhase::PreGrasp || phase == GraspPhase::Grasp) && choice && choice->reachable.value_or(false);
  const GivenPlansKey key{locked, locked ? choice->pose.matrix() : Eigen::Matrix4d::Zero(), reach_->keptRevision()};
  if (given_key_ && given_key_->same(key)) return;
  given_key_ = key;
  const GraspReachVerdict* v = locked ? reach_->keptVerdict(choice->pose) : nullptr;
  if (v && v->reachable) cycle_->setGivenPlans({{v->base, v->q_pre}, {v->base, v->q_grasp}});
  else cycle_->setGivenPlans({});
}

std::vector<std::pair<std::string, double>> GraspPipeline::plannedMapDistances(const Eigen::Vector3d& base,
                                                                               const Eigen::VectorXd& q, bool descent) const {
  // The map with the zones the sequencer will give it in that phase (as the object is seen now).
  const ehc_perception::ObstacleDistanceField& field = monitor_->field();
  std::vector<std::pair<std::string, double>> out;
  for (const auto& d : field.distances(field.linkPoses(monitor_->model(), base, q), plannedZones(descent)))
    out.emplace_back(d.link, d.distance);
  return out;
}

std::vector<ehc_perception::ExclusionZone> GraspPipeline::plannedZones(bool descent) const {
  std::vector<ehc_perception::ExclusionZone> zones;
  for (const auto& z : sequencer_->plannedExclusions(descent ? GraspPhase::Grasp : GraspPhase::PreGrasp))
    zones.push_back({z.centre, z.radius});
  return zones;
}

std::uint64_t GraspPipeline::plannedMapRevision() {
  PlannedMapKey key{monitor_->field().revision(), plannedZones(false)};
  const std::vector<ehc_perception::ExclusionZone> descent = plannedZones(true);
  key.zones.insert(key.zones.end(), descent.begin(), descent.end());
  if (key.map != planned_key_.map || key.zones != planned_key_.zones) {
    planned_key_ = std::move(key);
    ++planned_revision_;
  }
  return planned_revision_;
}

void GraspPipeline::updateObstacles(double t) {
  if (!monitor_) return;
  StageTimer timer(timing_, &counters_.wall_obstacles);
  const ehc_sim::KinematicFakeRobot& robot = world_->robot();
  const Eigen::VectorXd& q = robot.armPositions();
  monitor_->setJointState(t, arm_names_, std::vector<double>(q.data(), q.data() + q.size()));
  monitor_->setBasePose(t, odometryPose());
  if (!clocks_->obstacles.due(world_->timeNs())) return;
  const ehc_perception::ObstacleReport r = monitor_->update(t);
  ++counters_.obstacle_updates;
  if (r.status != ehc_perception::ObstacleReport::Status::Publish) return;
  std::vector<ehc_control::ObstaclePair> pairs;
  pairs.reserve(r.distances.size());
  for (const auto& d : r.distances) {
    pairs.push_back({d.link, d.link_point, d.obstacle_point, d.normal, d.distance});
    // d_s as the controller applies it (controller.yaml + robot.yaml's obstacle_stop_distances)
    last_.obstacle_pairs.push_back({d.distance, cycle_->controller().params().obstacleStop(d.link), d.link, d.obstacle_point});
  }
  const std::string err = cycle_->setObstacles(r.stamp, pairs);
  if (!err.empty()) throw std::runtime_error("[GraspPipeline] obstacles rejected by the controller: " + err);
}

const PipelineCycle& GraspPipeline::step() {
  const double t = time();
  last_ = PipelineCycle{};
  last_.t = t;
  last_.object = sequencer_->currentObject();
  perceive(t);
  updateObstacles(t);

  // Controller (ehc_controller_node answering the state stamped t).
  ehc_control::ControlCycleOutput out;
  {
    StageTimer timer(timing_, &counters_.wall_control);
    const ehc_sim::KinematicFakeRobot& robot = world_->robot();
    const Eigen::VectorXd& q = robot.armPositions();
    std::string err = cycle_->setJointState(t, arm_names_, std::vector<double>(q.data(), q.data() + q.size()));
    if (err.empty()) err = cycle_->setBasePose(t, odometryPose());
    if (!err.empty()) throw std::runtime_error("[GraspPipeline] state rejected by the controller: " + err);
    out = cycle_->update(t);
  }

  // Sequencer (ehc_grasp_sequencer_node on the status of t): goal etc. for the next cycle.
  if (reach_) reach_->setRobotBase(odometryPose());  // its grasp choice: placements on the robot's side
  {
    StageTimer timer(timing_, &counters_.wall_sequencer);
    SequencerInput in;
    in.t = t;
    in.controller_phase = ehc_control::toString(out.status.phase);
    in.target_in_fov = out.status.target_in_fov;
    in.sig = out.status.sig;
    in.gripper_state = world_->gripper().state();
    in.grasp_succeeded = world_->gripper().graspSucceeded();
    in.motion_limit = out.status.motion_limit;
    in.tcp = stackView(world_->linkPose(cycle_->model().config().tcp_frame));
    in.camera = stackView(world_->cameraPose());
    const std::size_t results_before = sequencer_->results().size();
    const SequencerOutput s = sequencer_->update(in);
    recordAttempt(t, last_.object, results_before);
    if (s.object_pose) {
      grasp_target_ = s.object_pose->translation();
      grasp_target_t_ = t;
      grasp_target_object_ = last_.object;
    }
    if (s.goal) {
      const std::string err = cycle_->setTarget(t, *s.goal);
      if (!err.empty()) throw std::runtime_error("[GraspPipeline] goal rejected by the controller: " + err);
    }
    if (const auto c = sequencer_->objectCentre()) cycle_->setWatchedCentre(t, *c);
    if (monitor_ && (!s.exclusions.empty() || excluding_)) {
      excluding_ = !s.exclusions.empty();
      std::vector<ehc_perception::ExclusionZone> zones;
      for (const auto& z : s.exclusions) zones.push_back({z.centre, z.radius});
      const std::string err = monitor_->setExclusionZones(t, zones);
      if (!err.empty()) throw std::runtime_error("[GraspPipeline] exclusion zones rejected: " + err);
    }
    if (s.gripper_command) world_->commandGripper(*s.gripper_command);
    last_.events = s.events;
    last_.phase = sequencer_->phase();
    if (reach_) updateGivenPlans();
  }

  // Simulator step with the controller's command.
  {
    StageTimer timer(timing_, &counters_.wall_physics);
    const ehc_sim::StepReport& r = world_->step(out.velocity);
    last_.collision = r.robot_world_collision || r.self_collision;
  }
  const ehc_control::RobotConfig& rc = cycle_->model().config();
  const Eigen::VectorXd& q = world_->robot().armPositions();
  for (int i = 0; i < q.size(); ++i)
    if (q[i] < rc.arm_lower[i] || q[i] > rc.arm_upper[i]) ++last_.joint_limit_violations;
  last_.status = out.status;
  last_.command = out.velocity;
  ++counters_.cycles;
  counters_.collision_steps += last_.collision;
  counters_.joint_limit_violations += last_.joint_limit_violations;
  return last_;
}

Eigen::Vector3d GraspPipeline::odometryPose() const { return world_->robot().odometryPose(); }

Eigen::Isometry3d GraspPipeline::stackView(const Eigen::Isometry3d& T_world_frame) const {
  const ehc_sim::KinematicFakeRobot& robot = world_->robot();
  if (robot.odometryIsTruth()) return T_world_frame;  // ideal base without imprecision
  using ehc_control::WholeBodyModel;
  return WholeBodyModel::baseTransform(robot.odometryPose()) * WholeBodyModel::baseTransform(robot.basePose()).inverse() *
         T_world_frame;
}

Eigen::Isometry3d GraspPipeline::trueView(const Eigen::Isometry3d& T_stack_frame) const {
  const ehc_sim::KinematicFakeRobot& robot = world_->robot();
  if (robot.odometryIsTruth()) return T_stack_frame;
  using ehc_control::WholeBodyModel;
  return WholeBodyModel::baseTransform(robot.basePose()) * WholeBodyModel::baseTransform(robot.odometryPose()).inverse() *
         T_stack_frame;
}

ObjectViewRecord GraspPipeline::viewNow(double t, std::size_t object) const {
  ObjectViewRecord v;
  v.t = t;
  v.T_world_cam = world_->cameraPose();
  v.T_world_object = world_->objectPose(static_cast<int>(object));
  return v;
}

void GraspPipeline::recordView(double t, std::size_t object, const std::vector<GraspCandidate>& candidates,
                              const ehc_perception::GraspResult& result, ehc_control::TargetSelectionStatus target) {
  if (object >= attempts_.size() || object >= cfg_.scene.objects.size()) return;
  if (object != views_object_) views_.clear();
  views_object_ = object;
  ObjectViewRecord v = viewNow(t, object);
  v.candidates = candidates;
  v.failure = result.failure;
  v.reason = result.reason;
  v.target = target;
  views_.push_back(v);
  if (intrinsics_.projectsInside(v.T_world_cam.inverse() * v.T_world_object.translation())) attempts_[object].last_seen = v;
}

void GraspPipeline::recordAttempt(double t, std::size_t object, std::size_t results_before) {
  if (object >= attempts_.size() || object >= cfg_.scene.objects.size()) return;
  GraspAttemptRecord& a = attempts_[object];
  const bool ended = sequencer_->results().size() > results_before;
  const std::optional<GraspChoice>& locked = sequencer_->lockedGrasp();
  const std::optional<GraspChoice>* take = nullptr;
  if (locked && !a.locked) take = &locked;
  else if (ended && !a.locked && sequencer_->lastChoice()) take = &sequencer_->lastChoice();
  if (take) {
    const GraspChoice& c = **take;
    a.locked = locked.has_value();
    a.chosen = true;
    a.grasp.pose = trueView(c.pose);
    a.grasp.width = c.width;
    a.T_world_object_at_choice = world_->objectPose(static_cast<int>(object));
    a.grasp_view = ObjectViewRecord{};
    a.candidate.reset();
    if (object == views_object_)
      for (const ObjectViewRecord& v : views_)
        if (v.t == c.candidates_t) a.grasp_view = v;
    const auto k = static_cast<std::size_t>(c.candidate_index);
    if (c.from_candidate && a.grasp_view.t >= 0.0 && k < a.grasp_view.candidates.size()) {
      a.candidate = a.grasp_view.candidates[k];
      a.candidate->pose = trueView(a.candidate->pose);
    }
  }
  if (ended) a.end = viewNow(t, object);
}

bool GraspPipeline::runUntilDone(double sim_time_limit) {
  const double t_end = time() + sim_time_limit;
  while (!done() && time() < t_end) step();
  return done();
}

}  // namespace ehc_bringup
