#pragma once
// JSON output of the perception CLIs (ehc_detect_tags, ehc_grasps).

#include "ehc_perception/grasp_generator.h"
#include "ehc_perception/tag_detector.h"

#include <string>
#include <vector>

namespace ehc_perception {

/// [{"id":…, "tag_size":…, "T_cam_tag":[[4x4]], "corners":[[u,v]x4], "reprojection_error":…}]
std::string tagDetectionsToJson(const std::vector<TagDetection>& detections);
/// [{"position":[x,y,z], "orientation":[qx,qy,qz,qw], "width":w, "score":s, …}] (given order)
std::string graspsToJson(const std::vector<Grasp>& grasps);

}  // namespace ehc_perception
