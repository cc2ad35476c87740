#include "ehc_perception/camera_intrinsics.h"

#include "ehc_control/config_node.h"
#include "ehc_control/pinhole_camera.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace ehc_perception {

namespace {
const char* kOwner = "CameraIntrinsics";
}

void CameraIntrinsics::validate() const {
  ehc_control::requireRange(kOwner, "image_width", width, 1, 10000);
  ehc_control::requireRange(kOwner, "image_height", height, 1, 10000);
  ehc_control::requirePositive(kOwner, "fx", fx);
  ehc_control::requirePositive(kOwner, "fy", fy);
  ehc_control::requireRange(kOwner, "cx", cx, 0.0, width);
  ehc_control::requireRange(kOwner, "cy", cy, 0.0, height);
  if (!distortion.allFinite())
    throw std::invalid_argument("[CameraIntrinsics] distortion coefficients must be finite");
}

bool CameraIntrinsics::project(const Eigen::Vector3d& p, Eigen::Vector2d* uv) const {
  if (!p.allFinite() || p.z() <= 1e-9) return false;
  const Eigen::Vector2d px(fx * p.x() / p.z() + cx, fy * p.y() / p.z() + cy);
  if (uv) *uv = px;
  return px.x() >= 0.0 && px.x() < width && px.y() >= 0.0 && px.y() < height;
}

std::string CameraIntrinsics::summary() const {
  std::ostringstream os;
  os << "camera '" << name << "': " << width << "x" << height << ", fx " << fx << " fy " << fy
     << " cx " << cx << " cy " << cy << ", " << distortion_model;
  return os.str();
}

CameraIntrinsics loadCameraIntrinsics(const std::string& path) {
  const auto root = ehc_control::ConfigNode::loadFile(path, kOwner);
  const ehc_control::CameraInfoFile f = ehc_control::readCameraInfo(root);
  CameraIntrinsics c;
  if (!f.camera_name.empty()) c.name = f.camera_name;
  c.width = f.width;
  c.height = f.height;
  c.fx = f.fx();
  c.fy = f.fy();
  c.cx = f.cx();
  c.cy = f.cy();
  if (!f.isPinholeMatrix()) root.fail("camera_matrix", "must be [fx 0 cx; 0 fy cy; 0 0 1]");
  c.distortion_model = root.get<std::string>("distortion_model", c.distortion_model);
  if (root.has("distortion_coefficients"))
    c.distortion = root.child("distortion_coefficients").requireVector("data");
  try {
    c.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string(e.what()) + " (in " + path + ")");
  }
  return c;
}

}  // namespace ehc_perception
