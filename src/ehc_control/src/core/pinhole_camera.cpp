#include "ehc_control/pinhole_camera.h"

#include "ehc_control/config_node.h"

#include <sstream>

namespace ehc_control {

void PinholeCamera::validate() const {
  if (width <= 0 || height <= 0)
    throw std::invalid_argument("[PinholeCamera] image size must be positive (got " + std::to_string(width) + " x " +
                                std::to_string(height) + ")");
  requireRange("PinholeCamera", "fx", fx, 1e-3, 1e6);
  requireRange("PinholeCamera", "fy", fy, 1e-3, 1e6);
  requireRange("PinholeCamera", "cx", cx, -1e6, 1e6);
  requireRange("PinholeCamera", "cy", cy, -1e6, 1e6);
  requireRange("PinholeCamera", "min_depth", min_depth, 0.0, 10.0);
}

bool PinholeCamera::projectsInside(const Eigen::Vector3d& p, Eigen::Vector2d* uv) const {
  if (!p.allFinite() || !(p.z() > min_depth)) return false;
  const double u = cx + fx * p.x() / p.z(), v = cy + fy * p.y() / p.z();
  if (uv) *uv << u, v;
  return u >= 0.0 && u < width && v >= 0.0 && v < height;
}

std::string PinholeCamera::summary() const {
  std::ostringstream os;
  os << "camera " << width << "x" << height << " fx " << fx << " fy " << fy << " cx " << cx << " cy " << cy;
  return os.str();
}

CameraInfoFile readCameraInfo(const ConfigNode& n) {
  CameraInfoFile f;
  f.camera_name = n.get<std::string>("camera_name", "");
  f.width = n.require<int>("image_width");
  f.height = n.require<int>("image_height");
  f.K = n.child("camera_matrix").requireVector("data", 9);
  return f;
}

PinholeCamera loadPinholeCamera(const std::string& path) {
  const CameraInfoFile f = readCameraInfo(ConfigNode::loadFile(path, "PinholeCamera"));
  PinholeCamera c;
  c.width = f.width;
  c.height = f.height;
  c.fx = f.fx();
  c.cx = f.cx();
  c.fy = f.fy();
  c.cy = f.cy();
  try {
    c.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("[PinholeCamera] " + path + ": " + std::string(e.what()).substr(16));
  }
  return c;
}

}  // namespace ehc_control
