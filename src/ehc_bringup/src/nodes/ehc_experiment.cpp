// ehc_experiment: the paper's experiments, in-process (no ROS master needed).
//   rosrun ehc_bringup ehc_experiment reach --robot robot.yaml --method ehc|ehc_place|neo_e|neo_c|all
//       [--sets 10] [--points 50] [--seed S] [--targets targets.csv] [--noise on|off]
//       [--base-model ideal|water2] [--base-imprecision LEVEL] [--protocol sequence|reset]
//       [--config controller.yaml] [--map reachability_map.bin] --out DIR
// Writes DIR/summary.json, DIR/table.md (paper Table II layout), DIR/trials.csv and
// DIR/targets.csv; progress and ETA on stderr. Errors: stderr, exit code 2.
//   rosrun ehc_bringup ehc_experiment grasp --method tsmm|neo_c|neo_e|ehc|ehc_place|all [--sets 15] [--seed S]
//       [--scene scene.yaml] [--jobs N] [--config-dir config] [--base-imprecision LEVEL] --out DIR  (paper Exp-2)
//   rosrun ehc_bringup ehc_experiment poses --method neo_nompbs|ehc_nompbs|ehc|all [--sets 15]
//       [--per-set 5] [--seed S] [--scene ...] [--jobs N] --out DIR             (paper Exp-3)
// The grasping pipeline in-process (ehc_bringup::GraspPipeline, GraspExperiment): DIR/table.md
// (paper Table III / IV beside the measured figures), trials.csv, summary.json, trace.csv.

#include "ehc_bringup/grasp_experiment.h"
#include "ehc_bringup/reach_experiment.h"
#include "ehc_bringup/reach_targets.h"
#include "ehc_common/command_line.h"
#include "ehc_common/config_node.h"
#include "ehc_common/output_dir.h"
#include "ehc_common/stop_signal.h"
#include "ehc_control/control_cycle.h"
#include "ehc_control/controller_node_config.h"

#include <chrono>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

namespace {

const char* kUsage =
    "usage: ehc_experiment reach --robot <name|robot.yaml> --method ehc|ehc_place|neo_e|neo_c|all --out DIR\n"
    "           [--sets 10] [--points 50] [--seed 1] [--targets targets.csv] [--noise on|off]\n"
    "           [--base-model ideal|water2]   (water2: the Water2 chain of ehc_sim/base_model.h with\n"
    "                                          its default parameters; the controller sees its odometry)\n"
    "           [--base-imprecision LEVEL]   (>= 0, default 0 = off: wheel slip and scale error, minimum speed,\n"
    "                                         command latency, odometry drift, localisation jumps on top of the\n"
    "                                         base model, every magnitude x LEVEL; ehc_sim::BaseImprecisionParams)\n"
    "           [--config controller.yaml] [--map reachability_map.bin] [--trace cycles.csv]\n"
    "           [--protocol sequence|reset]   (reset: every target from the ready pose at the origin)\n"
    "           [--first-set K]   (number of the first set: runs sets K..K+sets-1; set k's targets and noise\n"
    "                              depend only on the seed and k, so one set of a run reruns alone)\n"
    "           [--all-targets]   (keep generated targets no whole-body IK solution reaches)\n"
    "           [--generator paper|any]   (target distribution: paper = 1.5-4 m apart, approach within +-45 deg\n"
    "                                      of the travel direction; any = 0-7 m apart, approach from any direction)\n"
    "           [--min-distance m] [--max-distance m] [--min-height m] [--max-height m] [--max-tilt deg]\n"
    "           [--azimuth-spread deg] [--tilt-sampling uniform|sphere]   (override the generator's fields)\n"
    "       ehc_experiment grasp --method tsmm|neo_c|neo_e|ehc|ehc_place|all --out DIR [--robot <name|robot.yaml>] [--sets 15] [--seed 1]\n"
    "           [--scene scene.yaml] [--jobs 1] [--config-dir config] [--jitter-xy 0.01] [--jitter-yaw 3]\n"
    "           [--base-model ideal|water2]   (default: the sim file's, ideal; water2: the stack sees the bridge's /odom)\n"
    "           [--base-imprecision LEVEL]   (default: the sim file's, 0 = off)\n"
    "           [--object-time-limit s]   (per object, WAIT_TARGET..LIFT; default: the sequencer file's, 30 s)\n"
    "           [--library validation|tuning]   (everyday objects: per run the scene's objects replaced by library objects\n"
    "                                            of that half, untagged, each the target nearest its place)\n"
    "       ehc_experiment poses --method neo_nompbs|ehc_nompbs|ehc|all --out DIR [--robot <name|robot.yaml>] [--sets 15] [--per-set 5]\n"
    "           [--seed 1] [--scene scene.yaml] [--jobs 1] [--config-dir config] [--jitter-xy 0.01] [--jitter-yaw 3]\n"
    "           [--base-model ideal|water2] [--base-imprecision LEVEL] [--object-time-limit s]\n";

struct Args {
  std::string command, robot, method = "ehc", out, targets_csv, config, map, trace;
  int sets = 10, points = 50, first_set = 0;
  unsigned seed = 1;
  bool noise = true;
  ehc_sim::BaseModelType base_model = ehc_sim::BaseModelType::Ideal;
  double base_imprecision = 0.0;  ///< level, 0 = off
  bool all_targets = false;  ///< keep kinematically unreachable targets
  ehc_bringup::ReachProtocol protocol = ehc_bringup::ReachProtocol::Sequence;
  ehc_bringup::ReachTargetGenerator generator;
};

/// --base-imprecision: a level in [0, 100] (BaseImprecisionParams::level); `fallback` if not given.
double baseImprecisionLevel(const ehc_common::CommandLine& cli, double fallback) {
  const double level = cli.real("base-imprecision", fallback);
  if (!(level >= 0.0 && level <= 100.0))
    throw std::invalid_argument("[CommandLine] --base-imprecision: must be in [0, 100] (0 = off), got " +
                                std::to_string(level));
  return level;
}

/// --generator preset, then the field overrides.
ehc_bringup::ReachTargetGenerator generatorFromCli(const ehc_common::CommandLine& cli) {
  auto g = ehc_bringup::ReachTargetGenerator::preset(cli.choice("generator", ehc_bringup::ReachTargetGenerator::presetNames(), "paper"));
  g.min_distance = cli.real("min-distance", g.min_distance);
  g.max_distance = cli.real("max-distance", g.max_distance);
  g.min_height = cli.real("min-height", g.min_height);
  g.max_height = cli.real("max-height", g.max_height);
  g.max_tilt_deg = cli.real("max-tilt", g.max_tilt_deg);
  g.tilt_azimuth_spread_deg = cli.real("azimuth-spread", g.tilt_azimuth_spread_deg);
  if (cli.has("tilt-sampling"))
    g.tilt_sampling = ehc_bringup::tiltSamplingFromString(cli.choice("tilt-sampling", {"uniform", "sphere"}, "uniform"));
  g.validate();
  return g;
}

Args parse(int argc, char** argv) {
  Args a;
  if (argc < 2) throw std::invalid_argument("missing command (reach)");
  a.command = argv[1];
  if (a.command != "reach") throw std::invalid_argument("unknown command '" + a.command + "' (reach, grasp, poses)");
  const ehc_common::CommandLine cli(argc, argv,
                                     {"robot", "method", "out", "sets", "points", "seed", "targets",
                                      "config", "map", "trace", "noise", "base-model", "base-imprecision", "protocol", "generator",
                                      "min-distance", "max-distance", "min-height", "max-height", "max-tilt",
                                      "azimuth-spread", "tilt-sampling", "first-set"},
                                     {"all-targets"}, /*first=*/2);
  a.robot = ehc_control::resolveRobotFile(cli.text("robot"));  // a robot name or a robot.yaml
  a.out = cli.text("out");
  a.method = cli.text("method", a.method);
  a.sets = static_cast<int>(cli.integer("sets", a.sets, 1, 1000000));
  a.points = static_cast<int>(cli.integer("points", a.points, 1, 1000000));
  a.first_set = static_cast<int>(cli.integer("first-set", a.first_set, 0, 1000000));
  a.seed = static_cast<unsigned>(cli.integer("seed", a.seed, 0, 4294967295L));
  a.targets_csv = cli.text("targets", "");
  a.config = cli.text("config", "");
  a.map = cli.text("map", "");
  a.trace = cli.text("trace", "");
  a.all_targets = cli.has("all-targets");
  a.noise = cli.choice("noise", {"on", "off"}, "on") == "on";
  a.base_model = ehc_sim::baseModelTypeFromString(cli.choice("base-model", {"ideal", "water2"}, "ideal"));
  a.base_imprecision = baseImprecisionLevel(cli, a.base_imprecision);
  a.protocol = ehc_bringup::reachProtocolFromString(cli.choice("protocol", {"sequence", "reset"}, "sequence"));
  a.generator = generatorFromCli(cli);
  return a;
}

/// After the results are written: 0, or after a stop signal a note and 128 + the signal.
int interrupted(int done, int planned, const char* what) {
  if (!ehc_common::stopRequested()) return 0;
  std::cerr << "[ehc_experiment] interrupted (signal " << ehc_common::stopSignal() << "): partial results of " << done
            << " of " << planned << " " << what << " written (summary.json: \"partial\": true)\n";
  return ehc_common::stopExitCode();
}

/// The stack's controller.yaml (absolute: works from any working directory).
std::string defaultConfig() { return ehc_control::configDirectory() + "/control/controller.yaml"; }

/// `grasp` (Exp-2) and `poses` (Exp-3).
int runGrasp(int argc, char** argv) {
  const std::string command = argv[1];
  ehc_bringup::GraspExperimentParams p;
  p.protocol = command == "grasp" ? ehc_bringup::GraspProtocol::Table : ehc_bringup::GraspProtocol::Poses;
  std::vector<std::string> options = {"robot", "method", "out", "sets", "seed", "scene", "jobs", "config-dir",
                                      "jitter-xy", "jitter-yaw", "base-model", "base-imprecision", "object-time-limit"};
  if (p.protocol == ehc_bringup::GraspProtocol::Poses) options.push_back("per-set");
  if (p.protocol == ehc_bringup::GraspProtocol::Table) options.push_back("library");
  const ehc_common::CommandLine cli(argc, argv, options, {}, /*first=*/2);
  const std::string method = cli.text("method", "all");
  const std::string out = cli.text("out");
  ehc_common::prepareOutputDir(out);  // before any work
  p.sets = static_cast<int>(cli.integer("sets", p.sets, 1, 100000));
  if (p.protocol == ehc_bringup::GraspProtocol::Poses)
    p.per_set = static_cast<int>(cli.integer("per-set", p.per_set, 1, 100000));
  p.seed = static_cast<unsigned>(cli.integer("seed", p.seed, 0, 4294967295L));
  p.scene = cli.text("scene", p.scene);
  p.jobs = static_cast<int>(cli.integer("jobs", p.jobs, 1, 64));
  p.config_dir = cli.text("config-dir", ehc_control::configDirectory());
  p.robot = cli.text("robot", "");
  p.jitter_xy = cli.real("jitter-xy", p.jitter_xy);
  p.jitter_yaw_deg = cli.real("jitter-yaw", p.jitter_yaw_deg);
  if (p.protocol == ehc_bringup::GraspProtocol::Table) p.per_set = 1;
  if (cli.has("object-time-limit")) p.object_time_limit = cli.real("object-time-limit", 30.0);
  if (p.protocol == ehc_bringup::GraspProtocol::Table && cli.has("library"))
    p.library_split = cli.choice("library", {"validation", "tuning"}, "validation");
  if (cli.has("base-model"))
    p.base_model = ehc_sim::baseModelTypeFromString(cli.choice("base-model", {"ideal", "water2"}, "ideal"));
  if (cli.has("base-imprecision")) p.base_imprecision = baseImprecisionLevel(cli, 0.0);
  const std::vector<std::string> methods = ehc_bringup::graspMethodNames(p.protocol, method);
  const ehc_bringup::GraspExperiment exp(p, methods);
  std::cerr << "[ehc_experiment] " << command << ": " << p.sets << " set(s)"
            << (p.protocol == ehc_bringup::GraspProtocol::Poses ? " x " + std::to_string(p.per_set) + " per approach" : "")
            << ", seed " << p.seed << ", jobs " << p.jobs << ", methods:";
  for (const auto& m : methods) std::cerr << " " << m;
  const ehc_bringup::GraspPipelineConfig first =
      exp.runConfig(methods.front(), p.protocol == ehc_bringup::GraspProtocol::Table ? "" : "forward", 0);
  const ehc_sim::BaseModelConfig& base = first.sim.fake_robot.base_model;
  std::cerr << "\n  " << first.summary()
            << std::endl;
  const auto t0 = std::chrono::steady_clock::now();
  auto progress = [&](int done, int total, const std::string& text) {
    const double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::fprintf(stderr, "[ehc_experiment] %4d/%d  %s  elapsed %.0f s  ETA %.0f s\n", done, total, text.c_str(), el,
                 el * (total - done) / std::max(1, done));
  };
  const ehc_bringup::GraspExperimentResult res = exp.run(progress);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::ostringstream notes;
  notes << std::fixed << std::setprecision(1)
        << (p.protocol == ehc_bringup::GraspProtocol::Table
                ? "Exp-2 protocol: config/scenes/table_three_objects.yaml, start pose of the scene, front, middle, back in sequence "
                  "(config/demo/grasp_sequencer.yaml, 30 s per object). "
                : "Exp-3 protocol: config/scenes/single_object.yaml, forward / downward / sideways grasps "
                  "(config/demo/grasp_single_<approach>.yaml), each from the start pose; TfM = GraspSequencer's window "
                  "(object centre in the image from its first perceived pose until sig(w) >= tfm_handover_sig or the "
                  "pre-grasp switch). ")
        << (p.library_split.empty() ? std::string()
                                    : "Objects: per run, library objects of the " + p.library_split +
                                          " half (config/objects/library.yaml) drawn from the run seed, placed where the scene's "
                                          "objects stand with a random yaw, untagged; each object's target is the object nearest "
                                          "its place (within " + std::to_string(p.library_radius) + " m), from the depth cloud. ")
        << p.sets << " set(s)" << (p.protocol == ehc_bringup::GraspProtocol::Poses ? " x " + std::to_string(p.per_set) + " per approach" : "")
        << ", seed " << p.seed << ": run seed = seed*1000 + set*10 + index (Table I actuation noise, camera noise) and a "
        << "jitter of every object's placement, uniform +-" << p.jitter_xy * 100.0 << " cm in x and y and +-"
        << p.jitter_yaw_deg << " deg in yaw, drawn from the run seed. Methods: tsmm / neo_c / neo_e / neo_nompbs / "
        << "ehc_nompbs with plain PBVS (MPBS off), ehc with MPBS. tsmm as the paper (section IV-D): the base drives "
        << "(arm held) until the TCP is d = 0.2 m (controller tsmm_switch_distance, horizontal) from the perceived "
        << "object centre, stops (base command exactly 0 from then on), and the arm alone goes to the pre-grasp and "
        << "grasps; unlike the paper, the 30 s limit per object applies to tsmm too. Time = mean over successful grasps of the sequencer's "
        << "object time (object start -> lift success). Speeds: mean |v| (m/s) / |w| (rad/s) / sum |qd_arm| (rad/s) of "
        << "the commanded velocity while an object is worked on (QP solved); distant = controller position error > "
        << p.distant_threshold << " m. Base model: "
        << base.summary()
        << (base.type == ehc_sim::BaseModelType::Water2
                ? " (the stack sees the bridge's /odom estimate: controller, perception, sequencer)" : "")
        << (base.imprecision.enabled() ? " (the stack sees the imprecise odometry)" : ", base imprecision off (level 0)")
        << ". In-process pipeline (no ROS transport latency), "
        << res.sim_time_s << " s of sim time in " << wall << " s wall with " << p.jobs << " job(s) (real-time factor "
        << res.sim_time_s / std::max(1e-9, wall) << "; wall figures depend on the machine's load).";
  if (res.partial())
    notes << " PARTIAL: interrupted (signal " << ehc_common::stopSignal() << ") after " << res.runs_done << " of "
          << res.runs_planned << " runs; the figures are those of the completed runs.";
  ehc_bringup::writeGraspResults(out, p, res, notes.str());
  for (const auto& s : res.summaries) std::cout << ehc_bringup::graspSummaryJson(s) << std::endl;
  std::cerr << "[ehc_experiment] pipeline stage cost: " << ehc_bringup::pipelineStageCosts(res.counters, res.sim_time_s)
            << std::endl;
  std::cerr << "[ehc_experiment] results in " << out << "/ (table.md, trials.csv, summary.json, trace.csv)\n";
  return interrupted(res.runs_done, res.runs_planned, "runs");
}

}  // namespace

int main(int argc, char** argv) {
  ehc_common::installStopSignals();  // SIGINT / SIGTERM: partial results, exit 130 / 143
  try {
    if (argc >= 2 && (std::string(argv[1]) == "grasp" || std::string(argv[1]) == "poses")) return runGrasp(argc, argv);
    const Args a = parse(argc, argv);
    ehc_common::prepareOutputDir(a.out);  // before any work
    const auto robot_cfg = ehc_control::loadRobotConfig(a.robot);
    auto model = std::make_shared<const ehc_control::WholeBodyModel>(robot_cfg);
    const std::string cfg_path = a.config.empty() ? defaultConfig() : a.config;
    const auto cfg = ehc_common::ConfigNode::loadFile(cfg_path, "ehc_experiment");
    ehc_control::QpControllerParams ctrl = ehc_control::loadQpControllerParams(cfg.childOrEmpty("controller"));
    const auto wparams = ehc_control::loadEhcWeightingParams(cfg.childOrEmpty("weighting"));
    // The whole controller file is validated as the controller node reads it (the experiment
    // uses the controller, weighting, proportional-servo and motion_limit sections); a misspelled
    // key is an error.
    const ehc_control::ControlCycleParams cycle_cfg = ehc_control::loadControlCycleParams(cfg);
    ehc_control::loadControllerNodeParams(cfg);  // the node's section: checked as the node reads it
    cfg.rejectUnknownKeys();
    ehc_bringup::ReachExperimentParams ep;
    ep.motion_limit = cycle_cfg.motion_limit;
    ep.servo = ehc_control::loadPoseServoParams(cfg.childOrEmpty("servo"));
    ep.noise.enabled = a.noise;
    ep.base_model.type = a.base_model;
    ep.base_model.imprecision.level = a.base_imprecision;
    ep.protocol = a.protocol;
    ep.first_set = a.first_set;
    ep.arrival_position = ctrl.arrival_position;
    ep.arrival_orientation = ctrl.arrival_orientation;

    const std::string map_path = a.map.empty() ? robot_cfg.reachability_map_path : a.map;
    if (map_path.empty()) throw std::invalid_argument("no reachability map: give --map or robot.reachability_map");
    auto map = std::make_shared<ehc_control::ReachabilityMap>(ehc_control::ReachabilityMap::load(map_path));
    map->checkCompatible(robot_cfg);
    auto weighting = std::make_shared<const ehc_control::EhcWeighting>(map, wparams);

    std::vector<std::vector<Eigen::Isometry3d>> sets;
    int unreachable_redrawn = 0;
    if (!a.targets_csv.empty()) {
      const auto all = ehc_bringup::readReachTargetsCsv(a.targets_csv);
      for (std::size_t i = 0; i < all.size(); i += static_cast<std::size_t>(a.points))
        sets.emplace_back(all.begin() + static_cast<long>(i),
                          all.begin() + static_cast<long>(std::min(all.size(), i + static_cast<std::size_t>(a.points))));
    } else {
      const ehc_bringup::ReachTargetGenerator& gen = a.generator;
      // Targets no whole-body IK solution reaches (e.g. a horizontal approach 0.3 m above the
      // floor for a 0.61 m arm on a 0.6 m base), or only with a joint inside the controller's
      // joint stop, are redrawn unless --all-targets.
      auto reachable = [&](const Eigen::Isometry3d& T) { return ehc_bringup::kinematicallyReachable(*model, T, ctrl.joint_stop); };
      for (int s = a.first_set; s < a.first_set + a.sets; ++s) {
        int rejected = 0;
        sets.push_back(gen.generate(a.points, a.seed * 1000u + static_cast<unsigned>(s), Eigen::Vector2d::Zero(),
                                    a.all_targets ? std::function<bool(const Eigen::Isometry3d&)>() : reachable, &rejected));
        unreachable_redrawn += rejected;
      }
    }
    // The reset protocol runs the same approaches, each from the origin.
    std::vector<std::vector<Eigen::Isometry3d>> run_sets = sets;
    if (a.protocol == ehc_bringup::ReachProtocol::Reset)
      for (auto& set : run_sets) set = ehc_bringup::relativeToPrevious(set);
    std::vector<std::string> methods;
    if (a.method == "all") methods = {"neo_c", "neo_e", "ehc"};
    else methods = {a.method};

    std::cerr << robot_cfg.summary() << map->summary() << "\n" << ctrl.summary() << "\n"
              << "[ehc_experiment] " << sets.size() << " sets, noise " << (a.noise ? "on" : "off")
              << ", seed " << a.seed << ", " << (a.targets_csv.empty() ? a.generator.summary() : "targets from " + a.targets_csv) << ", base model " << ep.base_model.summary() << ", protocol "
              << ehc_bringup::toString(a.protocol) << ", methods:";
    for (const auto& m : methods) std::cerr << " " << m;
    std::cerr << std::endl;

    std::vector<ehc_bringup::ReachSummary> summaries;
    std::vector<ehc_bringup::ReachTrial> trials;
    std::ofstream events(a.out + "/events.log");
    for (const std::string& m : methods) {
      ctrl.mode = ehc_control::controlModeFromString(m);
      ehc_bringup::ReachExperiment exp(model, ctrl, weighting, ep);
      std::ofstream trace_file;
      if (!a.trace.empty()) {
        trace_file.open(a.trace, methods.size() > 1 && m != methods.front() ? std::ios::app : std::ios::trunc);
        if (!trace_file) throw std::invalid_argument("cannot write trace file '" + a.trace + "'");
        exp.setTrace(&trace_file);
      }
      exp.setEvents(&events);
      const auto t0 = std::chrono::steady_clock::now();
      double last = -1.0;
      auto progress = [&](int done, int total, const ehc_bringup::ReachSummary& s) {
        const double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        if (done != total && el - last < 2.0) return;
        last = el;
        const double eta = el * (total - done) / std::max(1, done);
        std::fprintf(stderr, "[ehc_experiment] %-6s %4d/%d targets  failed %3d  mean %.2f s  elapsed %.0f s  ETA %.0f s\n",
                     m.c_str(), done, total, s.failed, s.mean_time_s, el, eta);
      };
      summaries.push_back(exp.run(run_sets, a.seed, &trials, progress));
      std::cout << ehc_bringup::summaryJson(summaries.back()) << std::endl;
    }
    std::string notes = "Exp-1 (random reaching), " + std::to_string(summaries[0].targets) +
                        " targets, protocol " + ehc_bringup::toString(a.protocol) + ", noise " + (a.noise ? "on (Table I)" : "off") + ", seed " +
                        std::to_string(a.seed) + ", " +
                        (a.targets_csv.empty() ? a.generator.summary() + ", " : std::string()) +
                        (a.targets_csv.empty() ? (a.all_targets ? std::string("unreachable targets kept")
                                                                : std::to_string(unreachable_redrawn) + " unreachable draws redrawn (whole-body IK with every joint " + std::to_string(ctrl.joint_stop).substr(0, 4) + " rad inside its limits)")
                                               : "targets from " + a.targets_csv) +
                        (a.base_model == ehc_sim::BaseModelType::Ideal && a.base_imprecision == 0.0
                             ? std::string()
                             : ", base model " + ep.base_model.summary() + " (the controller sees its odometry)") +
                        ". Speeds: mean |v| (m/s) / |w| (rad/s) / sum |qd_arm| (rad/s) of the commanded velocity; distant = position error > 0.5 m." +
                        (ehc_common::stopRequested() ? " PARTIAL: interrupted; the figures are those of the targets run." : "");
    ehc_bringup::writeReachResults(a.out, summaries, trials, notes);
    std::vector<Eigen::Isometry3d> flat;
    for (const auto& s : run_sets) flat.insert(flat.end(), s.begin(), s.end());
    ehc_bringup::writeReachTargetsCsv(a.out + "/targets.csv", flat);
    std::cerr << "[ehc_experiment] results in " << a.out << "/ (summary.json, table.md, trials.csv, targets.csv, events.log)\n";
    return interrupted(static_cast<int>(trials.size()), summaries[0].targets_planned * static_cast<int>(methods.size()),
                       "targets (over the methods)");
  } catch (const std::exception& e) {
    std::cerr << "ehc_experiment: " << e.what() << "\n" << kUsage;
    return 2;
  }
}
