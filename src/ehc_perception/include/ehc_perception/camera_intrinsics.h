#pragma once
// CameraIntrinsics: pinhole model loaded from a ROS camera_info YAML file
// (camera_calibration format: image_width, image_height, camera_matrix, distortion_*).

#include <Eigen/Core>

#include <string>

namespace ehc_perception {

struct CameraIntrinsics {
  int width = 640;
  int height = 480;
  double fx = 615.0, fy = 615.0, cx = 320.0, cy = 240.0;
  std::string distortion_model = "plumb_bob";
  Eigen::VectorXd distortion = Eigen::VectorXd::Zero(5);
  std::string name = "camera";

  void validate() const;  ///< throws "[CameraIntrinsics] ..."
  /// Projects a point in the optical frame; false if behind the camera or outside the image.
  bool project(const Eigen::Vector3d& p_cam, Eigen::Vector2d* uv) const;
  std::string summary() const;
};

/// Loads and validates a camera_info YAML file. Throws "[CameraIntrinsics] <file>: ...".
CameraIntrinsics loadCameraIntrinsics(const std::string& path);

}  // namespace ehc_perception
