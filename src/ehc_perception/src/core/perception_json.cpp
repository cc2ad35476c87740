#include "ehc_perception/perception_json.h"

#include "ehc_common/json.h"

namespace ehc_perception {

using ehc_common::Json;
using ehc_common::jsonNumber;

std::string tagDetectionsToJson(const std::vector<TagDetection>& dets) {
  Json out = Json::array();
  for (const TagDetection& d : dets) {
    Json j;
    j["id"] = d.id;
    j["tag_size"] = jsonNumber(d.tag_size);
    const Eigen::Matrix4d M = d.T_cam_tag.matrix();
    Json T = Json::array();
    for (int r = 0; r < 4; ++r) {
      Json row = Json::array();
      for (int c = 0; c < 4; ++c) row.push_back(jsonNumber(M(r, c)));
      T.push_back(row);
    }
    j["T_cam_tag"] = T;
    Json corners = Json::array();
    for (std::size_t k = 0; k < 4; ++k)
      corners.push_back({jsonNumber(d.corners[k].x()), jsonNumber(d.corners[k].y())});
    j["corners"] = corners;
    j["reprojection_error"] = jsonNumber(d.reprojection_error);
    out.push_back(j);
  }
  return ehc_common::jsonLine(out);
}

std::string graspsToJson(const std::vector<Grasp>& grasps) {
  Json out = Json::array();
  for (const Grasp& g : grasps) {
    const Eigen::Vector3d p = g.pose.translation();
    const Eigen::Quaterniond q(g.pose.linear());
    Json j;
    j["position"] = {jsonNumber(p.x()), jsonNumber(p.y()), jsonNumber(p.z())};
    j["orientation"] = {jsonNumber(q.x()), jsonNumber(q.y()), jsonNumber(q.z()), jsonNumber(q.w())};
    j["width"] = jsonNumber(g.width);
    j["score"] = jsonNumber(g.score);
    j["object"] = g.object;
    j["antipodal"] = jsonNumber(g.antipodal);
    j["centroid_weight"] = jsonNumber(g.centroid_weight);
    j["pca_weight"] = jsonNumber(g.pca_weight);
    out.push_back(j);
  }
  return ehc_common::jsonLine(out);
}

}  // namespace ehc_perception
