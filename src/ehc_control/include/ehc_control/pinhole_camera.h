#pragma once
// PinholeCamera: the intrinsics the controller needs to tell whether the target is in view
// (TfM, MPBS monitoring). Loaded from a ROS camera_info YAML file (camera_calibration format:
// image_width, image_height, camera_matrix). ROS-free. (ehc_perception has the full
// CameraIntrinsics with distortion; ehc_control cannot depend on it.)

#include <Eigen/Core>

#include <string>

namespace ehc_control {

class ConfigNode;

/// The pinhole fields of a ROS camera_info YAML file (camera_calibration format), as written:
/// the one reader every package's intrinsics loader builds on (validation, and distortion for
/// the loaders that use it, stay with each loader).
struct CameraInfoFile {
  std::string camera_name;         ///< "" when absent
  int width = 0, height = 0;
  Eigen::Matrix<double, 9, 1> K;   ///< camera_matrix.data, row-major
  double fx() const { return K[0]; }
  double fy() const { return K[4]; }
  double cx() const { return K[2]; }
  double cy() const { return K[5]; }
  /// K = [fx 0 cx; 0 fy cy; 0 0 1] (no skew).
  bool isPinholeMatrix() const { return K[1] == 0.0 && K[3] == 0.0 && K[6] == 0.0 && K[7] == 0.0 && K[8] == 1.0; }
};
/// Reads the fields from a loaded file; missing or malformed required fields throw with the
/// file and field named (ConfigNode).
CameraInfoFile readCameraInfo(const ConfigNode& root);

struct PinholeCamera {
  int width = 640;
  int height = 480;
  double fx = 615.0, fy = 615.0, cx = 320.0, cy = 240.0;
  double min_depth = 1e-3;  ///< m, points closer to the image plane count as not visible

  void validate() const;  ///< throws "[PinholeCamera] ..."
  /// True when the point (camera optical frame: z forward, x right, y down) lies at depth
  /// > min_depth and projects inside the image [0, width) x [0, height). Optional pixel.
  bool projectsInside(const Eigen::Vector3d& p_camera, Eigen::Vector2d* uv = nullptr) const;
  std::string summary() const;
};

/// Loads and validates a camera_info YAML file. Throws "[PinholeCamera] <file>: ...".
PinholeCamera loadPinholeCamera(const std::string& path);

}  // namespace ehc_control
