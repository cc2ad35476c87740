#pragma once
// PinholeCamera: the intrinsics the controller needs to tell whether the target is in view
// (TfM, MPBS monitoring). Loaded from a ROS camera_info YAML file (camera_calibration format:
// image_width, image_height, camera_matrix). ROS-free. (ehc_perception has the full
// CameraIntrinsics with distortion; ehc_control cannot depend on it.)

#include <Eigen/Core>

#include <string>

namespace ehc_control {

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
