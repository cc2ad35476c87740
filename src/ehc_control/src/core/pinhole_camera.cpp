#include "ehc_control/pinhole_camera.h"

#include "ehc_common/config_node.h"

#include <sstream>

using ehc_common::ConfigNode;
using ehc_common::requireRange;

namespace ehc_control {

namespace {
const char* kOwner = "PinholeCamera";
}

void PinholeCamera::validate() const {
  requireRange(kOwner, "image_width", width, 1, 10000);
  requireRange(kOwner, "image_height", height, 1, 10000);
  requireRange(kOwner, "fx", fx, 1e-3, 1e6);
  requireRange(kOwner, "fy", fy, 1e-3, 1e6);
  requireRange(kOwner, "cx", cx, 0.0, width);
  requireRange(kOwner, "cy", cy, 0.0, height);
  if (!distortion.allFinite()) throw std::invalid_argument("[PinholeCamera] distortion coefficients must be finite");
  requireRange(kOwner, "min_depth", min_depth, 0.0, 10.0);
}

Eigen::Vector2d PinholeCamera::pixel(const Eigen::Vector3d& p) const {
  return Eigen::Vector2d(cx + fx * p.x() / p.z(), cy + fy * p.y() / p.z());
}

bool PinholeCamera::projectsInside(const Eigen::Vector3d& p, Eigen::Vector2d* uv) const {
  if (!p.allFinite() || !(p.z() > min_depth)) return false;
  const Eigen::Vector2d px = pixel(p);
  if (uv) *uv = px;
  return px.x() >= 0.0 && px.x() < width && px.y() >= 0.0 && px.y() < height;
}

std::string PinholeCamera::summary() const {
  std::ostringstream os;
  os << "camera '" << name << "': " << width << "x" << height << ", fx " << fx << " fy " << fy << " cx " << cx
     << " cy " << cy << ", " << distortion_model << " (" << distortion.size() << " coefficients)";
  return os.str();
}

PinholeCamera PinholeCamera::fromCameraInfo(const std::string& name, int width, int height,
                                            const Eigen::Matrix<double, 9, 1>& K,
                                            const std::string& distortion_model, const Eigen::VectorXd& D) {
  PinholeCamera c;
  c.name = name;
  c.width = width;
  c.height = height;
  c.fx = K[0];
  c.cx = K[2];
  c.fy = K[4];
  c.cy = K[5];
  c.distortion_model = distortion_model;
  c.distortion = D;
  return c;
}

namespace {
/// A camera_info matrix section {rows, cols, data}: rows and cols (when given) must be `rows` x
/// `cols` (cols < 0: any), data rows * cols finite numbers.
Eigen::VectorXd matrixData(const ConfigNode& root, const std::string& key, int rows, int cols) {
  const ConfigNode m = root.child(key);
  if (m.has("rows") && m.require<int>("rows") != rows) m.fail("rows", "must be " + std::to_string(rows));
  const int c = m.has("cols") ? m.require<int>("cols") : cols;
  if (cols >= 0 && c != cols) m.fail("cols", "must be " + std::to_string(cols));
  if (c < 0) return m.requireVector("data");
  return m.requireVector("data", rows * c);
}
}  // namespace

PinholeCamera loadPinholeCamera(const std::string& path) {
  const ConfigNode root = ConfigNode::loadFile(path, kOwner);
  const PinholeCamera defaults;
  const int width = root.require<int>("image_width");
  const int height = root.require<int>("image_height");
  const ConfigNode matrix = root.child("camera_matrix");
  const Eigen::Matrix<double, 9, 1> K = matrixData(root, "camera_matrix", 3, 3);
  // Not used (no rectification), but a malformed one is an error, not a silent pass.
  if (root.has("rectification_matrix")) matrixData(root, "rectification_matrix", 3, 3);
  if (root.has("projection_matrix")) matrixData(root, "projection_matrix", 3, 4);
  if (!(K[1] == 0.0 && K[3] == 0.0 && K[6] == 0.0 && K[7] == 0.0 && K[8] == 1.0))
    matrix.fail("data", "must be [fx 0 cx 0 fy cy 0 0 1] (no skew)");
  const Eigen::VectorXd D = root.has("distortion_coefficients") ? matrixData(root, "distortion_coefficients", 1, -1)
                                                                : defaults.distortion;
  std::string name = root.get<std::string>("camera_name", "");
  if (name.empty()) name = defaults.name;
  const PinholeCamera c = PinholeCamera::fromCameraInfo(
      name, width, height, K, root.get<std::string>("distortion_model", defaults.distortion_model), D);
  root.rejectUnknownKeys();  // every camera_info field is read above: another key is a misspelling
  try {
    c.validate();
  } catch (const std::invalid_argument& e) {
    // "[PinholeCamera] <what>" -> "[PinholeCamera] <file>: <what>"
    const std::string prefix = std::string("[") + kOwner + "] ";
    std::string what = e.what();
    if (what.rfind(prefix, 0) == 0) what.erase(0, prefix.size());
    throw std::invalid_argument(prefix + path + ": " + what);
  }
  return c;
}

}  // namespace ehc_control
