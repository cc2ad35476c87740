// ehc_detect_tags: AprilTag detection + pose on one image file, JSON on stdout.
//   ehc_detect_tags --image <png|pgm|jpg> --camera <camera_info yaml> --tag-size <m>
//                   [--family 36h11] [--config <yaml with a tag_detector section>]
// Prints [{"id":…, "T_cam_tag":[[4x4]], "corners":[[u,v]…], …}]. Errors: stderr, exit 2.
#include "ehc_common/command_line.h"
#include "ehc_common/config_node.h"
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
    const ehc_common::CommandLine cli(
        argc, argv, {"image", "camera", "tag-size", "family", "config"}, {"help"});
    if (cli.has("help")) {
      std::cout << kUsage;
      return 0;
    }
    const std::string image_path = cli.text("image");
    const std::string camera_path = cli.text("camera");
    TagDetectorConfig cfg;
    if (cli.has("config")) {
      const auto root = ehc_common::ConfigNode::loadFile(cli.text("config"), "TagDetector");
      cfg = loadTagDetectorConfig(root.childOrEmpty("tag_detector"));
      root.ignore("node");  // the node sections are the ROS nodes'
      root.ignore("target");
      root.rejectUnknownKeys();
    } else if (!cli.has("tag-size")) {
      throw std::invalid_argument("missing --tag-size (or --config)");
    }
    if (cli.has("tag-size")) {
      cfg.default_tag_size = cli.real("tag-size", cfg.default_tag_size);
      cfg.tag_sizes.clear();
    }
    cfg.family = cli.text("family", cfg.family);
    const ehc_control::PinholeCamera cam = ehc_control::loadPinholeCamera(camera_path);
    TagDetector detector(cfg, cam);
    const vpImage<unsigned char> image = loadGrayImage(image_path);
    std::cout << tagDetectionsToJson(detector.detect(image)) << std::endl;
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "ehc_detect_tags: error: " << e.what() << "\n" << kUsage;
    return 2;
  }
}
