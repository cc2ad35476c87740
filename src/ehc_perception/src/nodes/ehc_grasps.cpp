// ehc_grasps: grasp candidates for a PCD cloud, JSON list sorted by score.
//   ehc_grasps --cloud <file.pcd> [--viewpoint x,y,z] [--top K] [--up x,y,z]
//              [--mode scene|object] [--config <yaml with a grasp_generator section>]
//              --out grasps.json
// Exit 0: grasps written. Exit 3: no grasp ("[]" written, reason on stderr).
// Exit 2: bad arguments, unreadable cloud or config.
#include "cli_args.h"
#include "ehc_control/config_node.h"
#include "ehc_perception/grasp_generator.h"
#include "ehc_perception/perception_json.h"

#include <fstream>
#include <iostream>

namespace {
const char* kUsage =
    "usage: ehc_grasps --cloud <file.pcd> --out <grasps.json> [--viewpoint x,y,z] [--top K]\n"
    "                  [--up x,y,z] [--mode scene|object] [--config <file.yaml>]\n"
    "Writes [{\"position\":[x,y,z], \"orientation\":[qx,qy,qz,qw], \"width\":w, \"score\":s}]\n"
    "best first (grasp frame: z = approach, y = finger closing). Exit 3 if no grasp.\n";
}

int main(int argc, char** argv) {
  using namespace ehc_perception;
  try {
    const auto args = cli::parseArgs(argc, argv, {"help"});
    if (args.count("help")) {
      std::cout << kUsage;
      return 0;
    }
    for (const char* k : {"cloud", "out"})
      if (!args.count(k)) throw std::invalid_argument(std::string("missing --") + k);
    GraspGeneratorConfig cfg;
    if (args.count("config")) {
      const auto root = ehc_control::ConfigNode::loadFile(args.at("config"), "GraspGenerator");
      cfg = loadGraspGeneratorConfig(root.childOrEmpty("grasp_generator"));
      root.ignore("node");  // the node sections are the ROS nodes'
      root.ignore("target");
      root.rejectUnknownKeys();
    }
    if (args.count("top")) {
      const double k = cli::parseDouble("top", args.at("top"));
      if (k < 1 || k != static_cast<int>(k)) throw std::invalid_argument("--top must be >= 1");
      cfg.top_k = static_cast<int>(k);
    }
    if (args.count("up")) cfg.up = cli::parseVector3("up", args.at("up"));
    const Eigen::Vector3d viewpoint = args.count("viewpoint")
                                          ? cli::parseVector3("viewpoint", args.at("viewpoint"))
                                          : Eigen::Vector3d::Zero();
    const std::string mode = args.count("mode") ? args.at("mode") : "scene";
    if (mode != "scene" && mode != "object")
      throw std::invalid_argument("--mode must be scene or object");
    const GraspGenerator gen(cfg);
    const PointList cloud = loadPcd(args.at("cloud"));
    const GraspResult res = mode == "scene" ? gen.generateFromScene(cloud, viewpoint)
                                            : gen.generate(cloud, viewpoint);
    std::ofstream out(args.at("out"));
    if (!out) throw std::invalid_argument("cannot write '" + args.at("out") + "'");
    out << graspsToJson(res.grasps) << "\n";
    out.close();
    std::cerr << "ehc_grasps: " << res.input_points << " points, " << res.objects
              << " object(s), support plane " << (res.support_plane_found ? "yes" : "no") << ", "
              << res.grasps.size() << " grasp(s) -> " << args.at("out") << "\n";
    if (res.grasps.empty()) {
      std::cerr << "ehc_grasps: no grasp: " << res.reason << "\n";
      return 3;
    }
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "ehc_grasps: error: " << e.what() << "\n" << kUsage;
    return 2;
  }
}
