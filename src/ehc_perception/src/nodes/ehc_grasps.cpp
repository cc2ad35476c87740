// ehc_grasps: grasp candidates for a PCD cloud, JSON list sorted by score.
//   ehc_grasps --cloud <file.pcd> [--viewpoint x,y,z] [--top K] [--up x,y,z]
//              [--mode scene|object] [--config <yaml with a grasp_generator section>]
//              --out grasps.json
// Exit 0: grasps written. Exit 3: no grasp ("[]" written, reason on stderr).
// Exit 2: bad arguments, unreadable cloud or config.
#include "ehc_common/command_line.h"
#include "ehc_common/config_node.h"
#include "ehc_perception/grasp_generator.h"
#include "ehc_perception/perception_json.h"

#include <fstream>
#include <iostream>

namespace {
const char* kUsage =
    "usage: ehc_grasps --cloud <file.pcd> --out <grasps.json> [--viewpoint x,y,z] [--top K]\n"
    "                  [--up x,y,z] [--mode scene|object] [--config <file.yaml>]\n"
    "Writes [{\"position\":[x,y,z], \"orientation\":[qx,qy,qz,qw], \"width\":w, \"score\":s}]\n"
    "best first (grasp frame: z = approach, y = finger closing). Exit 3 if no grasp.\n"
    "--viewpoint: the camera's origin in the cloud's frame (without it, no hidden-volume check).\n";
}

int main(int argc, char** argv) {
  using namespace ehc_perception;
  try {
    const ehc_common::CommandLine cli(
        argc, argv, {"cloud", "out", "viewpoint", "top", "up", "mode", "config"}, {"help"});
    if (cli.has("help")) {
      std::cout << kUsage;
      return 0;
    }
    const std::string cloud_path = cli.text("cloud");
    const std::string out_path = cli.text("out");
    GraspGeneratorConfig cfg;
    if (cli.has("config")) {
      const auto root = ehc_common::ConfigNode::loadFile(cli.text("config"), "GraspGenerator");
      cfg = loadGraspGeneratorConfig(root.childOrEmpty("grasp_generator"));
      root.ignore("node");  // the node sections are the ROS nodes'
      root.ignore("target");
      root.rejectUnknownKeys();
    }
    cfg.top_k = static_cast<int>(cli.integer("top", cfg.top_k, 1, 1000000));
    cfg.up = cli.vector3("up", cfg.up);
    // Without the camera's origin the volume its view hides is not known.
    if (!cli.has("viewpoint")) cfg.hidden_volume_check = false;
    const Eigen::Vector3d viewpoint = cli.vector3("viewpoint", Eigen::Vector3d::Zero());
    const std::string mode = cli.choice("mode", {"scene", "object"}, "scene");
    const GraspGenerator gen(cfg);
    const PointList cloud = loadPcd(cloud_path);
    const GraspResult res = mode == "scene" ? gen.generateFromScene(cloud, viewpoint)
                                            : gen.generate(cloud, viewpoint);
    std::ofstream out(out_path);
    if (!out) throw std::invalid_argument("cannot write '" + out_path + "'");
    out << graspsToJson(res.grasps) << "\n";
    out.close();
    std::cerr << "ehc_grasps: " << res.input_points << " points, " << res.objects
              << " object(s), support plane " << (res.support_plane_found ? "yes" : "no") << ", "
              << res.grasps.size() << " grasp(s) -> " << out_path << "\n";
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
