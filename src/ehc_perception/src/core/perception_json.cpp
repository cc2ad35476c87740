#include "ehc_perception/perception_json.h"

#include <cstdio>
#include <sstream>

namespace ehc_perception {

namespace {
std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.9g", v);
  return buf;
}
}  // namespace

std::string tagDetectionsToJson(const std::vector<TagDetection>& dets) {
  std::ostringstream os;
  os << "[";
  for (std::size_t i = 0; i < dets.size(); ++i) {
    const TagDetection& d = dets[i];
    os << (i ? "," : "") << "{\"id\":" << d.id << ",\"tag_size\":" << num(d.tag_size)
       << ",\"T_cam_tag\":[";
    const Eigen::Matrix4d M = d.T_cam_tag.matrix();
    for (int r = 0; r < 4; ++r) {
      os << (r ? "," : "") << "[";
      for (int c = 0; c < 4; ++c) os << (c ? "," : "") << num(M(r, c));
      os << "]";
    }
    os << "],\"corners\":[";
    for (std::size_t k = 0; k < 4; ++k)
      os << (k ? "," : "") << "[" << num(d.corners[k].x()) << "," << num(d.corners[k].y()) << "]";
    os << "],\"reprojection_error\":" << num(d.reprojection_error) << "}";
  }
  os << "]";
  return os.str();
}

std::string graspsToJson(const std::vector<Grasp>& grasps) {
  std::ostringstream os;
  os << "[";
  for (std::size_t i = 0; i < grasps.size(); ++i) {
    const Grasp& g = grasps[i];
    const Eigen::Vector3d p = g.pose.translation();
    const Eigen::Quaterniond q(g.pose.linear());
    os << (i ? ",\n " : "") << "{\"position\":[" << num(p.x()) << "," << num(p.y()) << ","
       << num(p.z()) << "],\"orientation\":[" << num(q.x()) << "," << num(q.y()) << ","
       << num(q.z()) << "," << num(q.w()) << "],\"width\":" << num(g.width)
       << ",\"score\":" << num(g.score) << ",\"object\":" << g.object
       << ",\"antipodal\":" << num(g.antipodal) << ",\"centroid_weight\":"
       << num(g.centroid_weight) << ",\"pca_weight\":" << num(g.pca_weight) << "}";
  }
  os << "]";
  return os.str();
}

}  // namespace ehc_perception
