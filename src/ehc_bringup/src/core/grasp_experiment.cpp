#include "ehc_bringup/grasp_experiment.h"

#include "ehc_common/config_node.h"
#include "ehc_common/output_dir.h"
#include "ehc_common/stop_signal.h"
#include "ehc_common/text_format.h"
#include "ehc_sim/sim_world.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <map>
#include <mutex>
#include <random>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace ehc_bringup {

namespace {

/// The paper's figures of one table (config/paper/figures.yaml): method -> field -> text.
using PaperTable = std::map<std::string, std::map<std::string, std::string>>;

PaperTable loadPaperTable(const std::string& config_dir, const std::string& table) {
  const auto root = ehc_common::ConfigNode::loadFile(config_dir + "/paper/figures.yaml", "GraspExperiment");
  root.ignore("table2");
  for (const char* t : {"table3", "table4"})
    if (t != table) root.ignore(t);
  PaperTable out;
  const auto t = root.child(table);
  for (const std::string& method : t.keys()) {
    const auto row = t.child(method);
    for (const std::string& field : row.keys()) out[method][field] = row.require<std::string>(field);
  }
  root.rejectUnknownKeys();
  return out;
}

/// The paper's `field` for `method` ("" when the paper has no such row).
std::string paperCell(const PaperTable& paper, const std::string& method, const std::string& field) {
  const auto row = paper.find(method);
  if (row == paper.end()) return "";
  const auto cell = row->second.find(field);
  return cell == row->second.end() ? "" : cell->second;
}

/// The sequencer's result of one object into its trial.
void takeResult(const GraspResult& r, GraspTrial* t) {
  t->success = r.success;
  t->time_s = r.time_s;
  t->tfm = r.tfm;
  t->tfm_until_switch = r.tfm_until_switch;
  t->controller_tfm = r.controller_tfm;
  t->failed_phase = r.failed_phase;
  t->reason = r.reason;
  t->cause = toString(r.cause);
  t->stall_cause = r.stallCause();
  if (r.timed_out) {
    t->stall_joint = r.stall.joint;
    t->stall_link = r.stall.link;
    t->stall_body = r.stall_body;
    t->stall_detail = r.stallDetail();
  }
  t->close_offset = r.close_offset;
}

[[noreturn]] void bad(const std::string& what) { throw std::invalid_argument("[GraspExperiment] " + what); }

const char* kApproaches[] = {"forward", "downward", "sideways"};

}  // namespace

GraspMethod graspMethod(const std::string& name) {
  using ehc_control::ControlMode;
  if (name == "tsmm") return {name, ControlMode::Tsmm, false};
  if (name == "neo_c") return {name, ControlMode::NeoC, false};
  if (name == "neo_e") return {name, ControlMode::NeoE, false};
  if (name == "ehc") return {name, ControlMode::Ehc, true};
  if (name == "ehc_place") return {name, ControlMode::EhcPlace, true};
  if (name == "neo_nompbs") return {name, ControlMode::NeoE, false};
  if (name == "ehc_nompbs") return {name, ControlMode::Ehc, false};
  bad("unknown method '" + name + "' (tsmm, neo_c, neo_e, ehc, ehc_place, neo_nompbs, ehc_nompbs)");
}

std::vector<std::string> graspMethodNames(GraspProtocol protocol, const std::string& method) {
  const std::vector<std::string> all = protocol == GraspProtocol::Table
                                           ? std::vector<std::string>{"tsmm", "neo_c", "neo_e", "ehc"}
                                           : std::vector<std::string>{"neo_nompbs", "ehc_nompbs", "ehc"};
  if (method == "all") return all;
  // ehc's own placement mode (not one of the paper's methods, so not in "all").
  if (method == "ehc_place" && protocol == GraspProtocol::Table) return {method};
  if (std::find(all.begin(), all.end(), method) == all.end()) {
    std::string list;
    for (const auto& m : all) list += (list.empty() ? "" : "|") + m;
    bad("method '" + method + "' is not one of this protocol's: " + list + "|all");
  }
  return {method};
}

void GraspExperimentParams::validate() const {
  if (sets < 1) bad("sets must be >= 1");
  if (per_set < 1) bad("per_set must be >= 1");
  if (jobs < 1) bad("jobs must be >= 1");
  if (!(jitter_xy >= 0.0 && jitter_xy <= 0.05)) bad("jitter_xy must be in [0, 0.05] m");
  if (!(jitter_yaw_deg >= 0.0 && jitter_yaw_deg <= 15.0)) bad("jitter_yaw_deg must be in [0, 15] deg");
  if (!(distant_threshold > 0.0)) bad("distant_threshold must be > 0");
  if (!(trace_period > 0.0)) bad("trace_period must be > 0");
  if (object_time_limit && !(*object_time_limit > 0.0 && *object_time_limit <= 3600.0))
    bad("object_time_limit must be in (0, 3600] s");
  if (base_imprecision && !(*base_imprecision >= 0.0 && *base_imprecision <= 100.0))
    bad("base_imprecision must be in [0, 100]");
  if (!library_split.empty() && library_split != "validation" && library_split != "tuning")
    bad("library_split must be validation, tuning or empty (is '" + library_split + "')");
  if (!library_split.empty() && protocol != GraspProtocol::Table) bad("library objects are an Exp-2 (table) option");
  if (!(library_radius > 0.0 && library_radius <= 1.0)) bad("library_radius must be in (0, 1] m");
}

struct GraspExperiment::RunOutput {
  std::vector<GraspTrial> trials;
  std::vector<GraspTraceSample> trace;
  SpeedMeans distant, close;  ///< sums
  PipelineCounters counters;
  double sim_time_s = 0.0;
  bool complete = false;  ///< false: stopped by a stop signal before its end (not counted)
};

GraspExperiment::GraspExperiment(const GraspExperimentParams& params, std::vector<std::string> methods)
    : params_(params), methods_(std::move(methods)) {
  params_.validate();
  if (methods_.empty()) bad("no method");
  for (const auto& m : methods_) graspMethod(m);
  const std::string& dir = params_.config_dir;
  if (params_.protocol == GraspProtocol::Table) {
    const std::string scene = params_.scene.empty() ? dir + "/scenes/table_three_objects.yaml" : params_.scene;
    GraspPipelineFiles files = GraspPipelineFiles::demo(dir, scene, dir + "/demo/grasp_sequencer.yaml", {"front", "middle", "back"});
    files.robot = params_.robot;
    base_[""] = loadGraspPipelineConfig(files);
    if (!params_.library_split.empty()) library_ = ehc_sim::loadObjectLibrary(dir + "/objects/library.yaml");
  } else {
    const std::string scene = params_.scene.empty() ? dir + "/scenes/single_object.yaml" : params_.scene;
    for (const char* a : kApproaches) {
      GraspPipelineFiles files =
          GraspPipelineFiles::demo(dir, scene, dir + "/demo/grasp_single_" + std::string(a) + ".yaml", {"target"});
      files.robot = params_.robot;
      base_[a] = loadGraspPipelineConfig(files);
    }
  }
}

GraspPipelineConfig GraspExperiment::runConfig(const std::string& method, const std::string& approach,
                                               unsigned seed) const {
  const auto it = base_.find(approach);
  if (it == base_.end()) bad("no configuration for approach '" + approach + "'");
  GraspPipelineConfig c = it->second;
  const GraspMethod m = graspMethod(method);
  c.cycle.controller.mode = m.mode;
  c.cycle.mpbs.enabled = m.mpbs;
  if (params_.base_model) c.sim.fake_robot.base_model.type = *params_.base_model;
  if (params_.base_imprecision) c.sim.fake_robot.base_model.imprecision.level = *params_.base_imprecision;
  if (params_.object_time_limit) c.sequencer.object_time_limit = *params_.object_time_limit;
  if (library_) placeLibraryObjects(&c, *library_, params_.library_split, params_.library_radius, seed);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (auto& o : c.scene.objects) {
    o.position.x() += params_.jitter_xy * u(rng);
    o.position.y() += params_.jitter_xy * u(rng);
    o.rpy.z() += params_.jitter_yaw_deg * M_PI / 180.0 * u(rng);
  }
  c.scene.validate();
  return c;
}

void placeLibraryObjects(GraspPipelineConfig* cfg, const ehc_sim::ObjectLibrary& library, const std::string& split,
                         double radius, unsigned seed) {
  std::vector<const ehc_sim::LibraryObject*> half;
  for (const auto& o : library.objects)
    if (o.split == split) half.push_back(&o);
  std::vector<ehc_sim::BodyConfig>& objects = cfg->scene.objects;
  if (half.size() < objects.size())
    bad("the library's " + split + " half has " + std::to_string(half.size()) + " object(s), the scene " +
        std::to_string(objects.size()));
  // The run's own stream (the jitter after this draws from the run seed itself).
  std::mt19937 rng(seed ^ 0x9e3779b9u);
  std::uniform_real_distribution<double> yaw(-M_PI, M_PI);
  const auto footprint = [](const ehc_sim::LibraryObject& o) { return 0.5 * std::hypot(o.size.x(), o.size.y()); };
  for (int attempt = 0;; ++attempt) {
    if (attempt == 1000) bad("no draw of " + split + " library objects fits the scene's places");
    std::shuffle(half.begin(), half.end(), rng);
    bool fits = true;  // bounding circles apart (any yaw)
    for (std::size_t i = 0; i < objects.size() && fits; ++i)
      for (std::size_t j = 0; j < i && fits; ++j)
        fits = (objects[i].position - objects[j].position).head<2>().norm() > footprint(*half[i]) + footprint(*half[j]) + 0.01;
    if (fits) break;
  }
  cfg->scene.targets.clear();
  cfg->tag_targets.clear();
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const double support = objects[i].position.z() - objects[i].halfExtents().z();
    ehc_sim::BodyConfig b = ehc_sim::libraryBody(library, half[i]->name);
    b.position = Eigen::Vector3d(objects[i].position.x(), objects[i].position.y(), support + 0.5 * b.size.z());
    b.rpy = Eigen::Vector3d(0.0, 0.0, yaw(rng));
    objects[i] = b;
    ehc_control::TargetSelector t;
    t.kind = ehc_control::TargetSelectorKind::Nearest;
    t.point = b.position;
    t.radius = radius;
    cfg->scene.targets.push_back(t);
    if (i < cfg->sequencer.objects.size()) {
      cfg->sequencer.objects[i].name = b.name;
      cfg->sequencer.objects[i].target = t;
    }
  }
  cfg->scene.validate();
}

std::string AttemptJudgement::reason(bool success) const {
  if (!judged) return "";
  if (valid_exists) {
    if (success) return "grasped";
    if (attempted) return verdict == GraspVerdict::Valid ? "valid_grasp_failed" : "invalid_grasp:" + toString(verdict);
    return chosen ? "not_locked:" + toString(verdict) : "no_grasp_chosen";
  }
  if (success) return "grasped_where_none";
  if (attempted) return "attempted_where_none:" + toString(verdict);
  return "none_exists:" + (search_candidates > 0 ? toString(search_verdict) : std::string("wider_than_opening"));
}

std::optional<SupportSurface> tableTopUnder(const ehc_sim::SceneConfig& scene, const Eigen::Vector2d& xy) {
  const ehc_sim::TableConfig* top = nullptr;
  for (const ehc_sim::TableConfig& t : scene.tables) {
    const Eigen::Vector2d local = Eigen::Rotation2Dd(-t.yaw) * (xy - t.center);
    if (std::abs(local.x()) <= 0.5 * t.size.x() && std::abs(local.y()) <= 0.5 * t.size.y() && (!top || t.height > top->height))
      top = &t;
  }
  if (!top) return std::nullopt;
  SupportSurface s;
  s.height = top->height;
  const Eigen::Rotation2Dd R(top->yaw);
  for (const Eigen::Vector2d& corner : {Eigen::Vector2d(-1, -1), Eigen::Vector2d(1, -1), Eigen::Vector2d(1, 1), Eigen::Vector2d(-1, 1)})
    s.footprint.push_back(top->center + R * (0.5 * corner.cwiseProduct(top->size)));
  return s;
}

AttemptJudgement judgeAttempt(const GraspAttemptRecord& record, const ehc_sim::TriangleMesh& mesh, const ehc_sim::SceneConfig& scene,
                              const ehc_perception::GripperGeometry& gripper, const GraspJudgeParams& params, unsigned seed,
                              const GraspReachable& reachable) {
  AttemptJudgement j;
  const ObjectViewRecord* view = nullptr;
  if (record.chosen && record.grasp_view.t >= 0.0) view = &record.grasp_view, j.view = "grasp";
  else if (record.last_seen.t >= 0.0) view = &record.last_seen, j.view = "last_seen";
  else if (record.end.t >= 0.0) view = &record.end, j.view = "end";
  if (!view) return j;
  j.judged = true;
  j.generator_failure = view->failure;
  j.generator_reason = view->reason;
  j.target = view->target;
  j.chosen = record.chosen;
  j.attempted = record.locked;
  const Eigen::Isometry3d object = record.chosen ? record.T_world_object_at_choice : view->T_world_object;
  const std::optional<SupportSurface> top = tableTopUnder(scene, object.translation().head<2>());
  const GraspJudge judge(mesh, object, top ? top->height : 0.0, gripper, params,
                         view->T_world_object.translation() - view->T_world_cam.translation());
  if (record.chosen) j.verdict = judge.judge(record.grasp.pose).verdict;
  j.has_candidate = record.candidate.has_value();
  if (j.has_candidate) j.candidate_verdict = judge.judge(record.candidate->pose).verdict;
  j.valid_exists = j.chosen && j.verdict == GraspVerdict::Valid;
  j.reachable_exists = j.valid_exists && reachable && reachable(record.grasp.pose);
  // One search answers both: the first valid grasp it meets (accepted or refused by the reach
  // test) is the one the plain search stops at.
  if (!j.valid_exists || (reachable && !j.reachable_exists)) {
    const GraspExistence e = judge.findValidGrasp(seed, reachable);
    if (!j.valid_exists) {
      j.valid_exists = e.exists || e.refused > 0;
      j.search_verdict = j.valid_exists ? GraspVerdict::Valid : e.commonest();
      j.search_candidates = e.candidates;
    }
    j.reachable_exists = reachable && e.exists;
    j.reach_refused = e.refused;
  }
  j.reach_judged = j.valid_exists && reachable;
  return j;
}

std::string noGraspCause(const AttemptJudgement& j) {
  using ehc_control::TargetSelectionStatus;
  if (j.target != TargetSelectionStatus::NotCloudTarget && j.target != TargetSelectionStatus::Selected)
    return "no_target:" + ehc_control::toString(j.target);
  return ehc_perception::toString(j.generator_failure);
}

void JudgeCounts::add(const GraspTrial& t) {
  const AttemptJudgement& j = t.judge;
  if (!j.judged) return;
  ++objects;
  ++reasons[j.reason(t.success)];
  if (j.valid_exists && !t.success && !j.chosen) ++no_grasp_failures[noGraspCause(j)];
  attempted += j.attempted;
  attempted_invalid += j.attempted && !j.attemptValid();
  if (j.valid_exists) {
    ++valid_exists;
    grasped_where_exists += t.success;
    reach_judged += j.reach_judged;
    reachable_exists += j.reachable_exists;
    grasped_where_reachable += j.reachable_exists && t.success;
  } else {
    attempted_where_none += j.attempted;
    grasped_where_none += t.success;
  }
}

namespace {

/// Every object's attempt of a finished run judged (trials in sequencer order, as the scene's
/// objects): the run seed and the object's index seed its existence search. The reach test:
/// GraspReach (the sequencer's reach parameters, the controller's stop distances) with the true
/// top of the table under the object as its support and the robot's start as its base (the
/// ways to the placements from the robot's side), the grasp or its half-turn about the approach
/// (a parallel-jaw grasp is symmetric) with its pre-grasp; the obstacle map is not consulted.
void judgeTrials(const GraspPipelineConfig& cfg, const GraspPipeline& pipe, unsigned run_seed, std::vector<GraspTrial>* trials) {
  GraspJudgeParams params;  // mu 0.5
  params.pregrasp_distance = cfg.sequencer.pregrasp_distance;
  params.max_approach_tilt_deg = params.max_view_angle_deg = cfg.generator.max_approach_tilt_deg;
  const ehc_control::QpControllerParams& qp = pipe.cycle().controller().params();
  GraspReach reach(pipe.cycle().model(), cfg.sequencer.reach, [&qp](const std::string& link) { return qp.obstacleStop(link); },
                   qp.joint_stop);
  reach.setRobotBase(cfg.scene.robot_start);
  const auto reachable = [&](const Eigen::Isometry3d& grasp) {
    Eigen::Isometry3d turned = grasp;
    turned.linear() = halfTurned(grasp.linear());
    for (const Eigen::Isometry3d& g : {grasp, turned})
      if (reach.judge(g, backedOff(g, cfg.sequencer.pregrasp_distance)).reachable) return true;
    return false;
  };
  const std::vector<GraspAttemptRecord>& records = pipe.attempts();
  for (std::size_t i = 0; i < trials->size() && i < records.size() && i < cfg.scene.objects.size(); ++i) {
    std::seed_seq seq{run_seed, static_cast<unsigned>(i)};
    std::mt19937 rng(seq);
    const ehc_sim::TriangleMesh& mesh = pipe.world().bodySurface(pipe.world().objectBodyIndex(static_cast<int>(i)));
    reach.setSupport(tableTopUnder(cfg.scene, cfg.scene.objects[i].position.head<2>()));
    (*trials)[i].judge = judgeAttempt(records[i], mesh, cfg.scene, cfg.generator.gripper, params, static_cast<unsigned>(rng()),
                                      reachable);
  }
}

}  // namespace

GraspExperiment::RunOutput GraspExperiment::runOne(const RunSpec& spec) const {
  const GraspPipelineConfig cfg = runConfig(spec.method, spec.approach, spec.seed);
  GraspPipeline pipe(cfg, spec.seed);
  pipe.setTiming(params_.timing);
  RunOutput out;
  const int nb = pipe.cycle().model().nBase();
  const std::size_t n_objects = cfg.sequencer.objects.size();
  std::vector<long> contacts(n_objects, 0), limits(n_objects, 0);
  std::vector<ObstacleExtreme> nearest(n_objects), tightest(n_objects), grasped(n_objects);
  std::vector<double> t0(n_objects, -1.0);
  std::vector<double> next_sample(n_objects, 0.0);
  const Eigen::Vector3d unset = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  std::vector<Eigen::Vector3d> lock_centre(n_objects, unset), close_centre(n_objects, unset);
  std::vector<double> lock_axis_error(n_objects, unset.x());
  GraspPhase previous_phase = GraspPhase::WaitTarget;
  const std::string tcp_frame = pipe.cycle().model().config().tcp_frame;
  std::vector<Eigen::Vector3d> object_start;
  for (std::size_t i = 0; i < n_objects; ++i) object_start.push_back(pipe.world().objectPose(static_cast<int>(i)).translation());
  // Per object: WAIT_TARGET .. LIFT (30 s each) + release + retreat, with margin.
  const double limit = static_cast<double>(n_objects) *
                       (cfg.sequencer.object_time_limit + cfg.sequencer.release_timeout +
                        cfg.sequencer.retreat_timeout + cfg.sequencer.gripper_timeout + 2.0);
  const double t_end = pipe.time() + limit;
  while (!pipe.done() && pipe.time() < t_end) {
    if (ehc_common::stopRequested()) return out;  // incomplete: dropped by run()
    const PipelineCycle& c = pipe.step();
    const std::size_t k = std::min(c.object, n_objects - 1);
    contacts[k] += c.collision;
    limits[k] += c.joint_limit_violations;
    for (const ObstaclePairRecord& r : c.obstacle_pairs) {
      ObstacleExtreme e;
      e.found = true;
      e.distance = r.distance;
      e.stop = r.stop;
      e.link = r.link;
      e.body = nearestSceneBody(pipe.world(), r.obstacle_point);
      e.phase = toString(c.phase);
      if (e.body == cfg.sequencer.objects[k].name && c.phase >= GraspPhase::PreGrasp && c.phase <= GraspPhase::Lift) {
        grasped[k].take(e, false);
      } else {
        nearest[k].take(e, false);
        tightest[k].take(e, true);
      }
    }
    // Ground truth at the lock and at the close (GraspTrial::lock_centre_in_grasp / close_centre_in_tcp).
    if (c.phase != previous_phase && k < n_objects) {
      const Eigen::Vector3d centre = pipe.world().objectPose(static_cast<int>(k)).translation();
      if (c.phase == GraspPhase::PreGrasp && pipe.sequencer().lockedGrasp()) {
        const Eigen::Isometry3d& grasp = pipe.sequencer().lockedGrasp()->pose;
        lock_centre[k] = grasp.inverse() * centre;
        const Eigen::Vector3d closing = pipe.world().objectPose(static_cast<int>(k)).linear().transpose() * grasp.linear().col(1);
        lock_axis_error[k] = std::acos(std::min(1.0, closing.cwiseAbs().maxCoeff())) * 180.0 / M_PI;
      }
      if (c.phase == GraspPhase::Close) close_centre[k] = pipe.world().linkPose(tcp_frame).inverse() * centre;
    }
    previous_phase = c.phase;
    const bool working = c.phase != GraspPhase::Place && c.phase != GraspPhase::Release && c.phase != GraspPhase::Retreat &&
                         c.phase != GraspPhase::Done;
    if (t0[k] < 0.0) t0[k] = c.t;
    if (working && c.status.qp_status == ehc_control::QpStatus::Ok)
      accumulateSpeed(c.status.position_error > params_.distant_threshold ? out.distant : out.close, c.command, nb);
    if (working && c.t - t0[k] >= next_sample[k] - 1e-9) {
      next_sample[k] += params_.trace_period;
      GraspTraceSample s;
      s.method = spec.method;
      s.set = spec.set;
      s.index = spec.index;
      s.object = cfg.sequencer.objects[k].name;
      s.t = c.t - t0[k];
      const Eigen::Isometry3d tcp = pipe.world().linkPose(tcp_frame);
      const Eigen::Vector3d object = pipe.world().objectPose(static_cast<int>(k)).translation();
      s.distance = (tcp.translation() - object).norm();
      s.phase = toString(c.phase);
      if (pipe.sequencer().lockedGrasp()) s.tcp_in_grasp = pipe.sequencer().lockedGrasp()->pose.inverse() * tcp.translation();
      s.object_moved = (object - object_start[k]).norm();
      const CommandSpeeds speeds = commandSpeeds(c.command, nb);
      s.base_speed = speeds.base_t;
      s.base_turn = speeds.base_r;
      s.arm_speed = speeds.arm;
      out.trace.push_back(s);
    }
  }
  const auto& results = pipe.sequencer().results();
  for (std::size_t i = 0; i < n_objects; ++i) {
    GraspTrial t;
    t.method = spec.method;
    t.set = spec.set;
    t.index = spec.index;
    t.seed = spec.seed;
    t.object = cfg.sequencer.objects[i].name;
    t.approach = toString(cfg.sequencer.objects[i].approach);
    if (i < results.size()) {
      takeResult(results[i], &t);
    } else {
      t.failed_phase = toString(pipe.sequencer().phase());
      t.reason = "run ended (sim time limit " + std::to_string(limit) + " s) before this object was handled";
    }
    t.contact_steps = contacts[i];
    t.joint_limit_violations = limits[i];
    t.nearest = nearest[i];
    t.tightest = tightest[i];
    t.grasped = grasped[i];
    t.lock_centre_in_grasp = lock_centre[i];
    t.close_centre_in_tcp = close_centre[i];
    t.lock_closing_axis_error_deg = lock_axis_error[i];
    out.trials.push_back(t);
  }
  if (library_) judgeTrials(cfg, pipe, spec.seed, &out.trials);
  out.counters = pipe.counters();
  out.sim_time_s = pipe.time() - 1.0;
  out.complete = true;
  return out;
}

GraspExperimentResult GraspExperiment::run(const Progress& progress) const {
  std::vector<RunSpec> specs;
  for (const auto& m : methods_)
    for (int s = 0; s < params_.sets; ++s) {
      if (params_.protocol == GraspProtocol::Table) {
        specs.push_back({m, "", s, 0, params_.seed * 1000u + static_cast<unsigned>(s) * 10u});
      } else {
        for (int k = 0; k < params_.per_set; ++k)
          for (const char* a : kApproaches)
            specs.push_back({m, a, s, k, params_.seed * 1000u + static_cast<unsigned>(s) * 10u + static_cast<unsigned>(k)});
      }
    }
  std::vector<RunOutput> outputs(specs.size());
  std::vector<double> wall(specs.size(), 0.0);
  std::atomic<std::size_t> next{0};
  std::mutex mutex;
  int done = 0;
  std::exception_ptr error;
  auto worker = [&] {
    for (;;) {
      const std::size_t i = next++;
      if (i >= specs.size() || ehc_common::stopRequested()) return;
      try {
        const auto w0 = std::chrono::steady_clock::now();
        outputs[i] = runOne(specs[i]);
        wall[i] = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
      } catch (...) {
        std::lock_guard<std::mutex> lock(mutex);
        if (!error) error = std::current_exception();
        next = specs.size();
        return;
      }
      std::lock_guard<std::mutex> lock(mutex);
      if (!outputs[i].complete) return;  // stopped
      ++done;
      if (progress) {
        int ok = 0;
        for (const auto& t : outputs[i].trials) ok += t.success;
        std::ostringstream os;
        os << specs[i].method << " set " << specs[i].set
           << (specs[i].approach.empty() ? "" : " " + specs[i].approach + " #" + std::to_string(specs[i].index))
           << ": " << ok << "/" << outputs[i].trials.size() << " grasped, sim " << std::fixed << std::setprecision(1)
           << outputs[i].sim_time_s << " s in " << wall[i] << " s wall";
        progress(done, static_cast<int>(specs.size()), os.str());
      }
    }
  };
  const int jobs = std::min<int>(params_.jobs, static_cast<int>(specs.size()));
  std::vector<std::thread> threads;
  for (int j = 1; j < jobs; ++j) threads.emplace_back(worker);
  worker();
  for (auto& t : threads) t.join();
  if (error) std::rethrow_exception(error);

  // Assemble in spec order: the result does not depend on the job count.
  GraspExperimentResult res;
  res.runs_planned = static_cast<int>(specs.size());
  res.runs_done = done;
  for (const auto& m : methods_) {
    GraspMethodSummary s;
    s.method = m;
    const ehc_sim::BaseModelConfig& base = runConfig(m, base_.begin()->first, 0).sim.fake_robot.base_model;
    s.base_model = ehc_sim::toString(base.type);
    s.base_imprecision = base.imprecision.level;
    SpeedMeans distant, close;
    double time_sum = 0.0;
    std::map<std::string, std::pair<double, int>> tfm;
    for (std::size_t i = 0; i < specs.size(); ++i) {
      if (specs[i].method != m || !outputs[i].complete) continue;
      const RunOutput& o = outputs[i];
      for (const auto& t : o.trials) {
        ++s.grasps;
        if (t.success) {
          ++s.successes;
          time_sum += t.time_s;
        }
        auto& e = tfm[t.approach];
        e.first += t.tfm;
        ++e.second;
        s.contact_steps += t.contact_steps;
        s.joint_limit_violations += t.joint_limit_violations;
        if (!t.stall_cause.empty()) ++s.stall_causes[t.stall_cause];
        s.judge.add(t);
        s.nearest.take(t.nearest, false);
        s.tightest.take(t.tightest, true);
        s.grasped.take(t.grasped, false);
        res.trials.push_back(t);
      }
      for (SpeedMeans* p : {&distant, &close}) {
        const SpeedMeans& add = p == &distant ? o.distant : o.close;
        p->base_t += add.base_t;
        p->base_r += add.base_r;
        p->arm += add.arm;
        p->cycles += add.cycles;
      }
      res.trace.insert(res.trace.end(), o.trace.begin(), o.trace.end());
      s.sim_time_s += o.sim_time_s;
      s.wall_time_s += wall[i];
      res.counters.add(o.counters);
    }
    for (auto& e : tfm) e.second.first /= std::max(1, e.second.second);
    s.tfm = tfm;
    s.mean_time_s = s.successes ? time_sum / s.successes : 0.0;
    s.distant = meanSpeed(distant);
    s.close = meanSpeed(close);
    res.sim_time_s += s.sim_time_s;
    res.summaries.push_back(s);
  }
  return res;
}

std::string pipelineStageCosts(const PipelineCounters& c, double sim_time_s) {
  using ehc_common::jsonNumber;
  const double per = sim_time_s > 0.0 ? 1.0 / sim_time_s : 0.0;
  const double total = c.wall_image + c.wall_depth + c.wall_tags + c.wall_grasps + c.wall_obstacles + c.wall_control +
                       c.wall_sequencer + c.wall_physics;
  ehc_common::Json j;
  j["sim_time_s"] = jsonNumber(sim_time_s);
  j["cycles"] = c.cycles;
  j["images"] = c.images;
  j["images_without_tags"] = c.images_without_tags;
  j["tag_searches"] = {{"whole", c.tag_whole_searches}, {"window", c.tag_window_searches},
                       {"skipped", c.tag_skipped_searches}};
  j["clouds"] = c.clouds;
  j["grasp_runs"] = c.grasp_runs;
  j["obstacle_updates"] = c.obstacle_updates;
  j["wall_s_per_sim_s"] = {{"image", jsonNumber(c.wall_image * per)},         {"depth", jsonNumber(c.wall_depth * per)},
                           {"tags", jsonNumber(c.wall_tags * per)},           {"grasps", jsonNumber(c.wall_grasps * per)},
                           {"obstacles", jsonNumber(c.wall_obstacles * per)}, {"control", jsonNumber(c.wall_control * per)},
                           {"sequencer", jsonNumber(c.wall_sequencer * per)}, {"physics", jsonNumber(c.wall_physics * per)},
                           {"total", jsonNumber(total * per)}};
  return ehc_common::jsonLine(j);
}

namespace {
ehc_common::Json obstacleJson(const ObstacleExtreme& e) {
  using ehc_common::jsonNumber;
  if (!e.found)
    return {{"distance", nullptr}, {"stop", nullptr}, {"margin", nullptr}, {"link", ""}, {"body", ""}, {"phase", ""}};
  return {{"distance", jsonNumber(e.distance)}, {"stop", jsonNumber(e.stop)}, {"margin", jsonNumber(e.margin())},
          {"link", e.link}, {"body", e.body}, {"phase", e.phase}};
}
/// ",value" for a finite value, "," (an empty CSV field) for NaN (not measured).
void writeFiniteField(std::ostream& f, double v) {
  f << ",";
  if (std::isfinite(v)) f << v;
}
}  // namespace

ehc_common::Json graspSummaryJsonValue(const GraspMethodSummary& s) {
  using ehc_common::jsonNumber;
  const GraspMethod m = graspMethod(s.method);
  ehc_common::Json j;
  j["method"] = s.method;
  j["mode"] = ehc_control::toString(m.mode);
  j["mpbs"] = m.mpbs;
  j["base_model"] = s.base_model;
  j["base_imprecision"] = jsonNumber(s.base_imprecision);
  j["grasps"] = s.grasps;
  j["successes"] = s.successes;
  j["success_rate"] = jsonNumber(s.grasps ? 100.0 * s.successes / s.grasps : 0.0);
  j["mean_time_s"] = jsonNumber(s.mean_time_s);
  j["distant"] = speedJson(s.distant);
  j["close"] = speedJson(s.close);
  ehc_common::Json& tfm = j["tfm"] = ehc_common::Json::object();
  for (const auto& e : s.tfm) tfm[e.first] = jsonNumber(100.0 * e.second.first);
  j["contact_steps"] = s.contact_steps;
  j["joint_limit_violations"] = s.joint_limit_violations;
  ehc_common::Json& stalls = j["stall_causes"] = ehc_common::Json::object();
  for (const auto& [cause, n] : s.stall_causes) stalls[cause] = n;
  if (s.judge.objects > 0) {
    const JudgeCounts& c = s.judge;
    j["judge"] = {{"objects", c.objects},
                  {"valid_exists", c.valid_exists},
                  {"grasped_where_exists", c.grasped_where_exists},
                  {"grasped_where_exists_rate", c.valid_exists ? jsonNumber(100.0 * c.grasped_where_exists / c.valid_exists) : ehc_common::Json()},
                  {"reach_judged", c.reach_judged},
                  {"reachable_exists", c.reachable_exists},
                  {"grasped_where_reachable", c.grasped_where_reachable},
                  {"attempted", c.attempted},
                  {"attempted_invalid", c.attempted_invalid},
                  {"attempted_where_none", c.attempted_where_none},
                  {"grasped_where_none", c.grasped_where_none},
                  {"reasons", c.reasons},
                  {"no_grasp_failures", c.no_grasp_failures}};
  }
  j["min_obstacle"] = obstacleJson(s.nearest);
  j["min_obstacle_margin"] = obstacleJson(s.tightest);
  j["min_grasped_object"] = obstacleJson(s.grasped);
  j["sim_time_s"] = jsonNumber(s.sim_time_s);
  return j;
}

std::string graspSummaryJson(const GraspMethodSummary& s) { return ehc_common::jsonLine(graspSummaryJsonValue(s)); }

namespace {

std::ofstream openResultFile(const std::string& dir, const std::string& name) {
  std::ofstream f(dir + "/" + name);
  if (!f) throw std::runtime_error("[GraspExperiment] cannot write " + dir + "/" + name);
  return f;
}

void writeSummaryJson(const std::string& dir, const GraspExperimentParams& params, const GraspExperimentResult& result) {
  using ehc_common::jsonNumber;
  ehc_common::Json j;
  j["protocol"] = params.protocol == GraspProtocol::Table ? "grasp" : "poses";
  j["sets"] = params.sets;
  j["per_set"] = params.per_set;
  j["seed"] = params.seed;
  j["jitter_xy"] = jsonNumber(params.jitter_xy);
  j["jitter_yaw_deg"] = jsonNumber(params.jitter_yaw_deg);
  if (!result.summaries.empty()) {  // every method runs on the same base
    j["base_model"] = result.summaries.front().base_model;
    j["base_imprecision"] = jsonNumber(result.summaries.front().base_imprecision);
  }
  j["sim_time_s"] = jsonNumber(result.sim_time_s);
  // Interrupted (SIGINT / SIGTERM): the completed runs only.
  j["partial"] = result.partial();
  j["runs_done"] = result.runs_done;
  j["runs_planned"] = result.runs_planned;
  j["methods"] = ehc_common::Json::array();
  for (const GraspMethodSummary& m : result.summaries) j["methods"].push_back(graspSummaryJsonValue(m));
  openResultFile(dir, "summary.json") << ehc_common::jsonLine(j) << "\n";
}

double percent(int a, int b) { return b ? 100.0 * a / b : 0.0; }

/// Table III (Exp-2) rows beside the paper's.
void writeTable3(std::ostream& f, const GraspExperimentResult& result, const PaperTable& paper) {
  f << "Table III (Exp-2): sequentially grasping three objects. Measured (in-process sim) | paper (real robot)\n\n"
    << "| Method | Time(s) | Distant(Base-T/Base-R/Arm) | Close(Base-T/Base-R/Arm) | Success Rate (%) "
       "| paper Time(s) | paper Distant | paper Close | paper Success (%) |\n|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& s : result.summaries) {
    f << "| " << s.method << " | " << std::setprecision(2) << s.mean_time_s << " | " << std::setprecision(3)
      << s.distant.base_t << "/" << s.distant.base_r << "/" << s.distant.arm << " | " << s.close.base_t << "/"
      << s.close.base_r << "/" << s.close.arm << " | " << std::setprecision(1) << percent(s.successes, s.grasps)
      << " (" << s.successes << "/" << s.grasps << ") | " << paperCell(paper, s.method, "time") << " | "
      << paperCell(paper, s.method, "distant") << " | " << paperCell(paper, s.method, "close") << " | "
      << paperCell(paper, s.method, "success") << " |\n";
  }
}

/// Table IV (Exp-3) rows beside the paper's.
void writeTable4(std::ostream& f, const GraspExperimentResult& result, const PaperTable& paper) {
  f << "Table IV (Exp-3): grasping one object with different poses, TfM (%). Measured (in-process sim) | paper\n\n"
    << "| Method | Forward | Downward | Sideways | Success (%) | paper Forward | paper Downward | paper Sideways |\n"
       "|---|---|---|---|---|---|---|---|\n";
  for (const auto& s : result.summaries) {
    f << "| " << s.method;
    for (const char* a : kApproaches) {
      const auto it = s.tfm.find(a);
      f << " | " << std::setprecision(1) << (it == s.tfm.end() ? 0.0 : 100.0 * it->second.first);
    }
    f << " | " << percent(s.successes, s.grasps) << " (" << s.successes << "/" << s.grasps << ") | "
      << paperCell(paper, s.method, "forward") << " | " << paperCell(paper, s.method, "downward") << " | "
      << paperCell(paper, s.method, "sideways") << " |\n";
  }
}

/// Everyday objects: the judged grasps per method (JudgeCounts), when any was judged.
void writeJudgeTable(std::ostream& f, const GraspExperimentResult& result) {
  bool any = false;
  for (const auto& s : result.summaries) any = any || s.judge.objects > 0;
  if (!any) return;
  f << "\nEveryday objects judged against their true meshes (ehc_bringup/grasp_judge.h: approach, contacts on the closing "
       "line inside the opening, friction cone mu 0.5, fingers and palm swept in). A valid grasp exists where the grasp the "
       "sequencer chose is valid or the search on the mesh finds one, from the camera pose of the view the grasp came from "
       "(without one: the last view with the object in the image). Bar: grasped and lifted >= 90 % where one exists, no "
       "grasp attempted where none exists. Reachable: one of the valid grasps is one the robot reaches from its side of the "
       "table with every link clear of the top (GraspReach on the true table top; neighbours not considered).\n\n"
    << "| Method | objects | a valid grasp exists | grasped and lifted among them | ... a reachable one | grasped and "
       "lifted among those | attempted where none exists | attempted (judged invalid) | lifted where none exists |\n"
       "|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& s : result.summaries) {
    const JudgeCounts& c = s.judge;
    f << "| " << s.method << " | " << c.objects << " | " << c.valid_exists << " | " << c.grasped_where_exists << " ("
      << std::setprecision(1) << percent(c.grasped_where_exists, c.valid_exists) << " %) | " << c.reachable_exists
      << " | " << c.grasped_where_reachable << " (" << percent(c.grasped_where_reachable, c.reachable_exists) << " %) | "
      << c.attempted_where_none << " | " << c.attempted << " (" << c.attempted_invalid << ") | " << c.grasped_where_none
      << " |\n";
  }
}

/// An obstacle extreme for the safety table: d (or the margin d - d_s) in mm, where, when.
std::string obstacleCell(const ObstacleExtreme& d, bool margin) {
  std::ostringstream os;
  if (!d.found) return std::string("none within the influence distance");
  os << std::fixed << std::setprecision(1);
  if (margin) os << d.margin() * 1000.0 << " (" << d.link << " - " << d.body << ", " << d.phase << "; d "
                 << d.distance * 1000.0 << ", d_s " << d.stop * 1000.0 << ")";
  else os << d.distance * 1000.0 << " (" << d.link << " - " << d.body << ", " << d.phase << ")";
  return os.str();
}

/// The safety table (contacts, joint limits, perceived obstacle distances) and its notes.
void writeSafetyTable(std::ostream& f, const GraspExperimentResult& result, const std::string& notes) {
  f << "\nSafety (not in the paper; contacts and violations must be zero, every perceived distance at "
       "least its link's stop distance d_s):\n\n"
    << "| Method | sim steps with robot-scene contact (Bullet) | joint-limit violations "
       "| min perceived robot-obstacle distance d, mm (link - nearest scene body, phase) "
       "| min margin d - d_s, mm (link - body, phase; d, d_s) | object being grasped, PRE_GRASP on: min d, mm "
       "| sim time (s) |\n"
       "|---|---|---|---|---|---|---|\n";
  for (const auto& s : result.summaries)
    f << "| " << s.method << " | " << s.contact_steps << " | " << s.joint_limit_violations << " | "
      << obstacleCell(s.nearest, false) << " | " << obstacleCell(s.tightest, true) << " | "
      << obstacleCell(s.grasped, false) << " | " << std::setprecision(1) << s.sim_time_s << " |\n";
  f << "\nPerceived distances are those the controller received (ehc_obstacle_node's: octomap of the depth "
       "clouds, robot points filtered, the grasped object's extent and its support excluded from the descent to the end of the "
       "retreat); the scene body is the ground-truth body nearest to the perceived obstacle point. The object "
       "being grasped is scene until the grasp is locked; from PRE_GRASP on the hand must come close to it (the "
       "controller still keeps its dampers until GRASP, d_s 10 mm for the fingers), so its pairs are listed "
       "apart.\n";
  if (!notes.empty()) f << "\n" << notes << "\n";
}

void writeTableMd(const std::string& dir, const GraspExperimentParams& params, const GraspExperimentResult& result,
                  const std::string& notes) {
  std::ofstream f = openResultFile(dir, "table.md");
  f << std::fixed;
  if (params.protocol == GraspProtocol::Table) {
    writeTable3(f, result, loadPaperTable(params.config_dir, "table3"));
    writeJudgeTable(f, result);
  } else {
    writeTable4(f, result, loadPaperTable(params.config_dir, "table4"));
  }
  writeSafetyTable(f, result, notes);
}

/// A CSV value of an obstacle extreme; empty: no pair within the influence distance (a distance
/// <= 0 is a penetration).
std::string obstacleCsvValue(const ObstacleExtreme& e, double v) {
  std::ostringstream os;
  if (e.found) os << v;
  return os.str();
}

void writeTrialsCsv(const std::string& dir, const GraspExperimentResult& result) {
  std::ofstream f = openResultFile(dir, "trials.csv");
  f << "method,set,index,seed,object,approach,success,time_s,tfm,tfm_until_switch,controller_tfm,failed_phase,"
       "reason,stall_cause,stall_joint,stall_link,stall_body,stall_detail,close_offset_m,contact_steps,joint_limit_violations,min_obstacle_distance_m,min_obstacle_link,min_obstacle_body,"
       "min_obstacle_phase,min_margin_m,min_margin_link,min_margin_body,min_margin_phase,min_grasped_object_m,"
       "min_grasped_object_link,min_grasped_object_phase,lock_centre_in_grasp_x_m,lock_centre_in_grasp_y_m,"
       "lock_centre_in_grasp_z_m,close_centre_in_tcp_x_m,close_centre_in_tcp_y_m,close_centre_in_tcp_z_m,"
       "lock_closing_axis_error_deg,cause,judge_view,valid_exists,valid_reachable_exists,attempted,attempt_valid,grasp_verdict,candidate_verdict,judge_reason,"
       "target_selection,generator_failure,generator_reason\n";
  for (const auto& t : result.trials) {
    f << t.method << "," << t.set << "," << t.index << "," << t.seed << "," << t.object << "," << t.approach << ","
      << (t.success ? 1 : 0) << "," << t.time_s << "," << t.tfm << "," << t.tfm_until_switch << ","
      << t.controller_tfm << "," << t.failed_phase << "," << ehc_common::csvField(t.reason) << "," << t.stall_cause << ","
      << t.stall_joint << "," << t.stall_link << "," << t.stall_body << "," << ehc_common::csvField(t.stall_detail) << "," << t.close_offset << "," << t.contact_steps << ","
      << t.joint_limit_violations << "," << obstacleCsvValue(t.nearest, t.nearest.distance) << "," << t.nearest.link << ","
      << t.nearest.body << "," << t.nearest.phase << "," << obstacleCsvValue(t.tightest, t.tightest.margin()) << ","
      << t.tightest.link << "," << t.tightest.body << "," << t.tightest.phase << ","
      << obstacleCsvValue(t.grasped, t.grasped.distance) << ","
      << t.grasped.link << "," << t.grasped.phase;
    for (int a = 0; a < 3; ++a) writeFiniteField(f, t.lock_centre_in_grasp[a]);
    for (int a = 0; a < 3; ++a) writeFiniteField(f, t.close_centre_in_tcp[a]);
    writeFiniteField(f, t.lock_closing_axis_error_deg);
    f << "," << t.cause;
    const AttemptJudgement& j = t.judge;
    if (j.judged)
      f << "," << j.view << "," << j.valid_exists << "," << (j.reach_judged ? (j.reachable_exists ? "1" : "0") : "") << ","
        << j.attempted << "," << j.attemptValid() << ","
        << (j.chosen ? toString(j.verdict) : "") << "," << (j.has_candidate ? toString(j.candidate_verdict) : "") << ","
        << j.reason(t.success) << "," << ehc_control::toString(j.target) << ","
        << ehc_perception::toString(j.generator_failure) << "," << ehc_common::csvField(j.generator_reason);
    else
      f << ",,,,,,,,,,,";
    f << "\n";
  }
}

void writeTraceCsv(const std::string& dir, const GraspExperimentResult& result) {
  std::ofstream f = openResultFile(dir, "trace.csv");
  f << "method,set,index,object,t,distance,base_speed,base_turn,arm_speed,phase,tcp_in_grasp_x,tcp_in_grasp_y,"
       "tcp_in_grasp_z,object_moved\n"
    << std::setprecision(5);
  for (const auto& s : result.trace) {
    f << s.method << "," << s.set << "," << s.index << "," << s.object << "," << s.t << "," << s.distance << ","
      << s.base_speed << "," << s.base_turn << "," << s.arm_speed << "," << s.phase;
    for (int a = 0; a < 3; ++a) writeFiniteField(f, s.tcp_in_grasp[a]);
    f << "," << s.object_moved << "\n";
  }
}

}  // namespace

void writeGraspResults(const std::string& dir, const GraspExperimentParams& params,
                       const GraspExperimentResult& result, const std::string& notes) {
  ehc_common::prepareOutputDir(dir);
  writeSummaryJson(dir, params, result);
  writeTableMd(dir, params, result, notes);
  writeTrialsCsv(dir, result);
  writeTraceCsv(dir, result);
}

}  // namespace ehc_bringup
