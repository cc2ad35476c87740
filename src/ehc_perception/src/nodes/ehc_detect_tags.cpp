// ehc_detect_tags: AprilTag detection + pose on one image file, JSON on stdout.
//   ehc_detect_tags --image <png|pgm|jpg> --camera <camera_info yaml> --tag-size <m>
//                   [--family 36h11] [--config <yaml with a tag_detector section>]
// Prints [{"id":…, "T_cam_tag":[[4x4]], "corners":[[u,v]…], …}]. Errors: stderr, exit 2.
#include "cli_args.h"
#include "ehc_control/config_node.h"
#include "ehc_perception/perception_json.h"
#include "ehc_perception/tag_detector.h"

#include <iostream>

namespace {
const char* kUsage =
    "usage: ehc_detect_tags --image <png|pgm|jpg> --camera <camera_info.yaml> --tag-size <m>\n"
    "                       [--family 36h11|25h9|16h5] [--config <file.yaml>]\n"
    "Prints a JSON list [{\"id\":..., \"T_cam_tag\":[[4x4]], \"corners\":[[u,v],...]}].\n";
}

int main(int argc, char** argv) {
  using namespace ehc_perception;
  try {
    const auto args = cli::parseArgs(argc, argv, {"help"});
    if (args.count("help")) {
      std::cout << kUsage;
      return 0;
    }
    for (const char* k : {"image", "camera"})
      if (!args.count(k)) throw std::invalid_argument(std::string("missing --") + k);
    TagDetectorConfig cfg;
    if (args.count("config")) {
      const auto root = ehc_control::ConfigNode::loadFile(args.at("config"), "TagDetector");
      cfg = loadTagDetectorConfig(root.childOrEmpty("tag_detector"));
      root.ignore("node");  // the node sections are the ROS nodes'
      root.ignore("target");
      root.rejectUnknownKeys();
    } else if (!args.count("tag-size")) {
      throw std::invalid_argument("missing --tag-size (or --config)");
    }
    if (args.count("tag-size")) {
      cfg.default_tag_size = cli::parseDouble("tag-size", args.at("tag-size"));
      cfg.tag_sizes.clear();
    }
    if (args.count("family")) cfg.family = args.at("family");
    const ehc_control::PinholeCamera cam = ehc_control::loadPinholeCamera(args.at("camera"));
    TagDetector detector(cfg, cam);
    const vpImage<unsigned char> image = loadGrayImage(args.at("image"));
    std::cout << tagDetectionsToJson(detector.detect(image)) << std::endl;
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "ehc_detect_tags: error: " << e.what() << "\n" << kUsage;
    return 2;
  }
}
