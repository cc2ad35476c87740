// ehc_object_library: the simulator's generated everyday objects (ehc_sim/object_library.h).
//   ehc_object_library manifest --seed S --per-kind N --out <library.yaml>
//       draws N objects of every kind with seed S and writes the manifest (parameters, bounding
//       box, mass, friction, split); config/objects/library.yaml is made this way.
//   ehc_object_library meshes [--manifest <library.yaml>] [--out <dir>]
//       writes every object's mesh (its manifest's mesh_dir by default; the build runs this).
//   ehc_object_library cloud --object <name> --out <cloud.pcd> [--manifest <library.yaml>]
//       [--distance m] [--elevation deg] [--azimuth deg] [--seed S] [--sim <bullet_sim.yaml>]
//       the object on a table, one depth cloud of the simulated camera (world frame, binary PCD);
//       the camera position, the object's pose and the point count go to stdout as JSON.
//   ehc_object_library judge [--split tuning|validation|all] [--views N] [--seed S] --out <dir>
//       [--manifest <library.yaml>] [--sim <bullet_sim.yaml>] [--config <grasp_node.yaml>]
//       [--mu 0.5] [--samples 2000]
//       every object of the split from N random views (0.5-0.7 m, 30-60 deg above the table): the
//       grasp generator's grasps judged against the true mesh (ehc_bringup/grasp_judge.h);
//       <dir>/views.csv (one row per view) and <dir>/summary.md; progress on stderr.
//   ehc_object_library segment [--split tuning|validation|all] [--views N] [--seed S] --out <dir>
//       [--objects 3] [--min-gap 0.01] [--max-gap 0.03] [--kinds bowl,mug] [--manifest <library.yaml>]
//       [--sim <bullet_sim.yaml>] [--config <grasp_node.yaml>]
//       N random scenes of library objects of the split, each seen once: the scene segmentation
//       of tagless targets against the truth (ehc_bringup/segmentation_check.h);
//       <dir>/segment.csv (one row per object in view) and <dir>/summary.md; progress on stderr.
// Exit 0: done. Exit 2: bad arguments or files.
#include "ehc_bringup/grasp_judge.h"
#include "ehc_bringup/object_view.h"
#include "ehc_bringup/segmentation_check.h"
#include "ehc_common/command_line.h"
#include "ehc_common/config_node.h"
#include "ehc_common/output_dir.h"
#include "ehc_common/json.h"
#include "ehc_control/robot_config.h"

#include <sys/stat.h>

#include <fstream>
#include <iostream>
#include <sstream>

namespace {
const char* kUsage =
    "usage: ehc_object_library manifest --seed S --per-kind N --out <library.yaml>\n"
    "       ehc_object_library meshes [--manifest <library.yaml>] [--out <dir>]\n"
    "       ehc_object_library cloud --object <name> --out <cloud.pcd> [--manifest <library.yaml>]\n"
    "                          [--distance 0.6] [--elevation 45] [--azimuth 0] [--seed 1] [--sim <bullet_sim.yaml>]\n"
    "       ehc_object_library judge --out <dir> [--split all|tuning|validation] [--views 2] [--seed 1]\n"
    "                          [--manifest <library.yaml>] [--sim <bullet_sim.yaml>] [--config <grasp_node.yaml>]\n"
    "                          [--mu 0.5] [--samples 2000]\n"
    "       ehc_object_library segment --out <dir> [--split all|tuning|validation] [--views 20] [--seed 1]\n"
    "                          [--objects 3] [--min-gap 0.01] [--max-gap 0.03] [--kinds K1,K2]\n"
    "                          [--manifest <library.yaml>] [--sim <bullet_sim.yaml>] [--config <grasp_node.yaml>]\n"
    "The default manifest is config/objects/library.yaml.\n";

std::string defaultManifest() { return ehc_control::configDirectory() + "/objects/library.yaml"; }

int manifest(int argc, char** argv) {
  const ehc_common::CommandLine cli(argc, argv, {"seed", "per-kind", "out"}, {}, 2);
  const auto seed = static_cast<unsigned>(cli.integer("seed", 1, 0, 1000000));
  const int per_kind = static_cast<int>(cli.integer("per-kind", 4, 1, 100));
  const std::string out = cli.text("out");
  const ehc_sim::ObjectLibrary lib = ehc_sim::drawObjectLibrary(seed, per_kind);
  std::ofstream f(out);
  if (!f) throw std::invalid_argument("cannot write '" + out + "'");
  f << ehc_sim::objectLibraryYaml(lib, "rosrun ehc_bringup ehc_object_library manifest --seed " + std::to_string(seed) +
                                           " --per-kind " + std::to_string(per_kind) + " --out <this file>");
  std::cerr << "ehc_object_library: " << lib.objects.size() << " objects -> " << out << "\n";
  return 0;
}

int meshes(int argc, char** argv) {
  const ehc_common::CommandLine cli(argc, argv, {"manifest", "out"}, {}, 2);
  const ehc_sim::ObjectLibrary lib = ehc_sim::loadObjectLibrary(cli.text("manifest", defaultManifest()));
  const std::string dir = cli.text("out", lib.mesh_dir);
  mkdir(dir.c_str(), 0755);
  for (const ehc_sim::LibraryObject& o : lib.objects)
    ehc_sim::writeMeshFile(ehc_sim::generateObjectMesh(o.kind, o.params, o.seed), dir + "/" + o.file);
  std::cerr << "ehc_object_library: " << lib.objects.size() << " meshes -> " << dir << "\n";
  return 0;
}

int cloud(int argc, char** argv) {
  const ehc_common::CommandLine cli(
      argc, argv, {"manifest", "object", "out", "distance", "elevation", "azimuth", "seed", "sim"}, {}, 2);
  const ehc_sim::ObjectLibrary lib = ehc_sim::loadObjectLibrary(cli.text("manifest", defaultManifest()));
  ehc_bringup::ObjectView view;
  view.distance = cli.real("distance", view.distance);
  view.elevation_deg = cli.real("elevation", view.elevation_deg);
  view.azimuth_deg = cli.real("azimuth", view.azimuth_deg);
  if (!(view.distance > 0.1 && view.distance < 5.0)) throw std::invalid_argument("--distance must be in (0.1, 5) m");
  if (!(view.elevation_deg > 0.0 && view.elevation_deg < 89.0)) throw std::invalid_argument("--elevation must be in (0, 89) deg");
  const auto seed = static_cast<unsigned>(cli.integer("seed", 1, 0, 1000000000));
  const ehc_sim::SimConfig sim = ehc_sim::loadSimConfig(cli.text("sim", ehc_control::configDirectory() + "/sim/bullet_sim.yaml"));
  const ehc_bringup::ObjectViewCloud c = ehc_bringup::objectViewCloud(lib, cli.text("object"), view, sim, seed);
  const std::string out = cli.text("out");
  ehc_perception::savePcd(out, c.points);
  ehc_common::Json j;
  j["object"] = cli.text("object");
  j["points"] = c.points.size();
  const Eigen::Vector3d eye = c.T_world_cam.translation(), p = c.T_world_object.translation();
  const Eigen::Quaterniond q(c.T_world_object.linear());
  j["camera_position"] = {ehc_common::jsonNumber(eye.x()), ehc_common::jsonNumber(eye.y()), ehc_common::jsonNumber(eye.z())};
  j["object_position"] = {ehc_common::jsonNumber(p.x()), ehc_common::jsonNumber(p.y()), ehc_common::jsonNumber(p.z())};
  j["object_orientation"] = {ehc_common::jsonNumber(q.x()), ehc_common::jsonNumber(q.y()), ehc_common::jsonNumber(q.z()),
                             ehc_common::jsonNumber(q.w())};
  j["mesh"] = c.body.mesh_file;
  j["cloud"] = out;
  std::cout << ehc_common::jsonLine(j) << "\n";
  return 0;
}
/// What the judge and segment commands share: the output folder (prepared), the object library,
/// the simulator's settings, the grasp generator and targeting of the grasp node's file, and the
/// command line for the report. Reads --split, --views and --seed into the given fields (their
/// values are the defaults).
struct LibraryRun {
  std::string dir, command;
  ehc_sim::ObjectLibrary lib;
  ehc_sim::SimConfig sim;
  ehc_perception::GraspGenerator generator;
  ehc_perception::GraspTargetingParams targeting;
  /// Writes <dir>/<csv_name> and <dir>/summary.md and says so on stderr (`views` rows).
  void write(const std::string& csv_name, const std::string& csv_text, const std::string& summary,
             std::size_t views) const {
    std::ofstream csv(dir + "/" + csv_name), md(dir + "/summary.md");
    csv << csv_text;
    md << summary;
    if (!csv || !md) throw std::invalid_argument("cannot write to '" + dir + "'");
    std::cerr << "ehc_object_library: " << views << " views -> " << dir << "/" << csv_name << ", summary.md\n";
  }
};

LibraryRun loadLibraryRun(const ehc_common::CommandLine& cli, int argc, char** argv, std::string* split, int* views,
                          unsigned* seed) {
  *split = cli.choice("split", {"all", "tuning", "validation"}, *split);
  *views = static_cast<int>(cli.integer("views", *views, 1, 1000000));
  *seed = static_cast<unsigned>(cli.integer("seed", *seed, 0, 1000000000));
  const std::string config = cli.text("config", ehc_control::configDirectory() + "/perception/grasp_node.yaml");
  const auto root = ehc_common::ConfigNode::loadFile(config, "GraspGenerator");
  std::string command = std::string("ehc_object_library ") + argv[1];
  for (int i = 2; i < argc; ++i) command += std::string(" ") + argv[i];
  LibraryRun run{cli.text("out"),
                 command,
                 ehc_sim::loadObjectLibrary(cli.text("manifest", defaultManifest())),
                 ehc_sim::loadSimConfig(cli.text("sim", ehc_control::configDirectory() + "/sim/bullet_sim.yaml")),
                 ehc_perception::GraspGenerator(ehc_perception::loadGraspGeneratorConfig(root.childOrEmpty("grasp_generator"))),
                 ehc_perception::loadGraspTargetingParams(root.childOrEmpty("node"))};
  ehc_common::prepareOutputDir(run.dir);
  return run;
}

int judge(int argc, char** argv) {
  const ehc_common::CommandLine cli(
      argc, argv, {"manifest", "split", "views", "seed", "out", "sim", "config", "mu", "samples"}, {}, 2);
  ehc_bringup::LibraryJudgeParams p;
  const LibraryRun run = loadLibraryRun(cli, argc, argv, &p.split, &p.views, &p.seed);
  p.judge.friction_coefficient = cli.real("mu", p.judge.friction_coefficient);
  p.judge.samples = static_cast<int>(cli.integer("samples", p.judge.samples, 1, 1000000));
  p.judge.max_approach_tilt_deg = p.judge.max_view_angle_deg = run.generator.config().max_approach_tilt_deg;
  p.validate();
  std::cerr << "ehc_object_library judge: seed " << p.seed << ", split " << p.split << ", " << p.views
            << " views per object, mu " << p.judge.friction_coefficient << "\n";
  const auto rows = ehc_bringup::judgeLibrary(
      run.lib, run.sim, run.generator, run.targeting, p, [](const ehc_bringup::JudgedView& v, std::size_t done, std::size_t total) {
        const ehc_bringup::ViewJudgement& j = v.judgement;
        std::cerr << "[" << done << "/" << total << "] " << v.object << " view " << v.view << ": valid grasp "
                  << (j.exists ? "exists" : "none") << ", "
                  << (j.result.grasps.empty() ? "no grasp (" + ehc_perception::toString(j.result.failure) + ")"
                                              : "best " + ehc_bringup::toString(j.best.verdict))
                  << ", top 5 valid " << j.top5_valid << "\n";
      });
  run.write("views.csv", ehc_bringup::judgedViewsCsv(rows), ehc_bringup::judgedViewsSummary(rows, run.command), rows.size());
  return 0;
}

int segment(int argc, char** argv) {
  const ehc_common::CommandLine cli(
      argc, argv, {"manifest", "split", "views", "seed", "out", "sim", "config", "objects", "min-gap", "max-gap", "kinds"}, {}, 2);
  ehc_bringup::SegmentationCheckParams p;
  const LibraryRun run = loadLibraryRun(cli, argc, argv, &p.split, &p.views, &p.seed);
  p.objects = static_cast<int>(cli.integer("objects", p.objects, 1, 10));
  p.min_gap = cli.real("min-gap", p.min_gap);
  p.max_gap = cli.real("max-gap", p.max_gap);
  std::istringstream kinds(cli.text("kinds", ""));
  for (std::string k; std::getline(kinds, k, ',');)
    if (!k.empty()) p.kinds.push_back(k);
  p.validate();
  std::cerr << "ehc_object_library segment: seed " << p.seed << ", split " << p.split << ", " << p.views << " views\n";
  const auto views = ehc_bringup::checkSegmentation(
      run.lib, run.sim, run.generator, run.targeting, p, [](const ehc_bringup::SegmentedView& v, int done, int total) {
        std::cerr << "[" << done << "/" << total << "] " << v.clusters << " cluster(s):";
        for (const auto& o : v.objects) std::cerr << " " << o.object << " " << ehc_bringup::toString(o.outcome);
        std::cerr << "\n";
      });
  run.write("segment.csv", ehc_bringup::segmentationCsv(views), ehc_bringup::segmentationSummary(views, run.command),
            views.size());
  return 0;
}
}  // namespace

int main(int argc, char** argv) {
  const std::string command = argc > 1 ? argv[1] : "";
  try {
    if (command == "manifest") return manifest(argc, argv);
    if (command == "meshes") return meshes(argc, argv);
    if (command == "cloud") return cloud(argc, argv);
    if (command == "judge") return judge(argc, argv);
    if (command == "segment") return segment(argc, argv);
    std::cerr << kUsage;
    return command == "--help" || command == "-h" ? 0 : 2;
  } catch (const std::exception& e) {
    std::cerr << "ehc_object_library: " << e.what() << "\n" << kUsage;
    return 2;
  }
}
