// ehc_experiment: the paper's experiments, in-process (no ROS master needed).
//   rosrun ehc_bringup ehc_experiment reach --robot robot.yaml --method ehc|neo_e|neo_c|all
//       [--sets 10] [--points 50] [--seed S] [--targets targets.csv] [--noise on|off]
//       [--base-model ideal|water2] [--protocol sequence|reset]
//       [--config controller.yaml] [--map reachability_map.bin] --out DIR
// Writes DIR/summary.json, DIR/table.md (paper Table II layout), DIR/trials.csv and
// DIR/targets.csv; progress and ETA on stderr. Errors: stderr, exit code 2.

#include "ehc_bringup/reach_experiment.h"
#include "ehc_bringup/reach_targets.h"
#include "ehc_control/command_line.h"
#include "ehc_control/config_node.h"
#include "ehc_control/control_cycle.h"

#include <chrono>
#include <fstream>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

namespace {

const char* kUsage =
    "usage: ehc_experiment reach --robot <robot.yaml> --method ehc|neo_e|neo_c|all --out DIR\n"
    "           [--sets 10] [--points 50] [--seed 1] [--targets targets.csv] [--noise on|off]\n"
    "           [--base-model ideal|water2]   (water2: the Water2 chain of ehc_sim/base_model.h with\n"
    "                                          its default parameters; the controller sees its odometry)\n"
    "           [--config controller.yaml] [--map reachability_map.bin] [--trace cycles.csv]\n"
    "           [--protocol sequence|reset]   (reset: every target from the ready pose at the origin)\n"
    "           [--all-targets]   (keep generated targets no whole-body IK solution reaches)\n";

struct Args {
  std::string command, robot, method = "ehc", out, targets_csv, config, map, trace;
  int sets = 10, points = 50;
  unsigned seed = 1;
  bool noise = true;
  ehc_sim::BaseModelType base_model = ehc_sim::BaseModelType::Ideal;
  bool all_targets = false;  ///< keep kinematically unreachable targets
  ehc_bringup::ReachProtocol protocol = ehc_bringup::ReachProtocol::Sequence;
};

Args parse(int argc, char** argv) {
  Args a;
  if (argc < 2) throw std::invalid_argument("missing command (reach)");
  a.command = argv[1];
  if (a.command != "reach") throw std::invalid_argument("unknown command '" + a.command + "' (reach)");
  const ehc_control::CommandLine cli(argc, argv,
                                     {"robot", "method", "out", "sets", "points", "seed", "targets",
                                      "config", "map", "trace", "noise", "base-model"},
                                     {"all-targets"}, /*first=*/2);
  a.robot = cli.text("robot");
  a.out = cli.text("out");
  a.method = cli.text("method", a.method);
  a.sets = static_cast<int>(cli.integer("sets", a.sets, 1, 1000000));
  a.points = static_cast<int>(cli.integer("points", a.points, 1, 1000000));
  a.seed = static_cast<unsigned>(cli.integer("seed", a.seed, 0, 4294967295L));
  a.targets_csv = cli.text("targets", "");
  a.config = cli.text("config", "");
  a.map = cli.text("map", "");
  a.trace = cli.text("trace", "");
  a.all_targets = cli.has("all-targets");
  a.noise = cli.choice("noise", {"on", "off"}, "on") == "on";
  a.base_model = ehc_sim::baseModelTypeFromString(cli.choice("base-model", {"ideal", "water2"}, "ideal"));
  return a;
}

std::string defaultConfig(const std::string& robot_yaml) {
  // config/robots/<robot>/robot.yaml -> config/control/controller.yaml
  const auto p = robot_yaml.rfind("/robots/");
  return p == std::string::npos ? std::string("config/control/controller.yaml")
                                : robot_yaml.substr(0, p) + "/control/controller.yaml";
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const Args a = parse(argc, argv);
    const auto robot_cfg = ehc_control::loadRobotConfig(a.robot);
    auto model = std::make_shared<const ehc_control::WholeBodyModel>(robot_cfg);
    const std::string cfg_path = a.config.empty() ? defaultConfig(a.robot) : a.config;
    const auto cfg = ehc_control::ConfigNode::loadFile(cfg_path, "ehc_experiment");
    ehc_control::QpControllerParams ctrl = ehc_control::loadQpControllerParams(cfg.childOrEmpty("controller"));
    const auto wparams = ehc_control::loadEhcWeightingParams(cfg.childOrEmpty("weighting"));
    // The whole controller file is validated as the controller node reads it (the experiment
    // uses the controller, weighting and proportional-servo sections); a misspelled key is an error.
    ehc_control::loadControlCycleParams(cfg);
    cfg.ignore("node");
    cfg.rejectUnknownKeys();
    ehc_bringup::ReachExperimentParams ep;
    ep.servo = ehc_control::loadPoseServoParams(cfg.childOrEmpty("servo"));
    ep.noise.enabled = a.noise;
    ep.base_model.type = a.base_model;
    ep.protocol = a.protocol;
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
      const ehc_bringup::ReachTargetGenerator gen;
      // Targets no whole-body IK solution reaches (e.g. a horizontal approach 0.3 m above the
      // floor for a 0.61 m arm on a 0.6 m base) are redrawn unless --all-targets.
      auto reachable = [&](const Eigen::Isometry3d& T) { return model->inverseKinematics(T, 1, 30); };
      for (int s = 0; s < a.sets; ++s) {
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
              << ", seed " << a.seed << ", base model " << ep.base_model.summary() << ", protocol "
              << ehc_bringup::toString(a.protocol) << ", methods:";
    for (const auto& m : methods) std::cerr << " " << m;
    std::cerr << std::endl;

    std::vector<ehc_bringup::ReachSummary> summaries;
    std::vector<ehc_bringup::ReachTrial> trials;
    for (const std::string& m : methods) {
      ctrl.mode = ehc_control::controlModeFromString(m);
      ehc_bringup::ReachExperiment exp(model, ctrl, weighting, ep);
      std::ofstream trace_file;
      if (!a.trace.empty()) {
        trace_file.open(a.trace, methods.size() > 1 && m != methods.front() ? std::ios::app : std::ios::trunc);
        if (!trace_file) throw std::invalid_argument("cannot write trace file '" + a.trace + "'");
        exp.setTrace(&trace_file);
      }
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
                        (a.targets_csv.empty() ? (a.all_targets ? std::string("unreachable targets kept")
                                                                : std::to_string(unreachable_redrawn) + " unreachable draws redrawn (whole-body IK)")
                                               : "targets from " + a.targets_csv) +
                        (a.base_model == ehc_sim::BaseModelType::Ideal
                             ? std::string()
                             : ", base model " + ep.base_model.summary() + " (the controller sees its odometry)") +
                        ". Speeds: mean |v| (m/s) / |w| (rad/s) / sum |qd_arm| (rad/s) of the commanded velocity; distant = position error > 0.5 m.";
    ehc_bringup::writeReachResults(a.out, summaries, trials, notes);
    std::vector<Eigen::Isometry3d> flat;
    for (const auto& s : run_sets) flat.insert(flat.end(), s.begin(), s.end());
    ehc_bringup::writeReachTargetsCsv(a.out + "/targets.csv", flat);
    std::cerr << "[ehc_experiment] results in " << a.out << "/ (summary.json, table.md, trials.csv, targets.csv)\n";
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "ehc_experiment: " << e.what() << "\n" << kUsage;
    return 2;
  }
}
