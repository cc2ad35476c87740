#pragma once
// PinholeCamera: the one camera model of the stack (controller TfM and MPBS monitoring, tag
// detection and rendering, the simulated camera, the grasp sequencer's TfM): image size, pinhole
// intrinsics, name, distortion model + coefficients (kept for information: every user projects
// an ideal pinhole, i.e. rectified images), projection of a point in the optical frame and the
// in-image test. Loaded from a ROS camera_info YAML file (camera_calibration format:
// camera_name, image_width, image_height, camera_matrix, distortion_model,
// distortion_coefficients); nodes convert it from and to sensor_msgs/CameraInfo with
// src/nodes/ehc_control/camera_info_msg.h (cameraFromInfo, fillCameraInfo). ROS-free.

#include <Eigen/Core>

#include <string>

namespace ehc_control {

struct PinholeCamera {
  std::string name = "camera";  ///< camera_name (YAML) or the camera_info frame
  int width = 640;
  int height = 480;
  double fx = 615.0, fy = 615.0, cx = 320.0, cy = 240.0;
  std::string distortion_model = "plumb_bob";
  Eigen::VectorXd distortion = Eigen::VectorXd::Zero(5);  ///< coefficients (any length, may be empty)
  double min_depth = 1e-3;  ///< m, points closer to the image plane count as not visible

  /// Throws std::invalid_argument "[PinholeCamera] parameter '<field>' ...": image size in
  /// [1, 10000] px, fx, fy in [1e-3, 1e6], principal point inside the image, finite
  /// distortion coefficients, min_depth in [0, 10] m.
  void validate() const;
  /// Pixel (u right, v down) of a point in the optical frame (z forward, x right, y down):
  /// [fx x / z + cx, fy y / z + cy]. No depth check (see projectsInside).
  Eigen::Vector2d pixel(const Eigen::Vector3d& p_camera) const;
  /// True when the point (optical frame) is finite, lies at depth > min_depth and projects
  /// inside the image [0, width) x [0, height). The pixel is written to `uv` (if given) when
  /// the depth test passes.
  bool projectsInside(const Eigen::Vector3d& p_camera, Eigen::Vector2d* uv = nullptr) const;
  std::string summary() const;
  /// Same image size and intrinsics (fx, fy, cx, cy) as `o`: what a projection uses (name and
  /// distortion are not compared).
  bool sameIntrinsics(const PinholeCamera& o) const {
    return width == o.width && height == o.height && fx == o.fx && fy == o.fy && cx == o.cx && cy == o.cy;
  }

  /// The camera of ROS camera_info fields (YAML file or sensor_msgs/CameraInfo): K row-major
  /// [fx 0 cx; 0 fy cy; 0 0 1] (the other entries are not read), distortion model and
  /// coefficients D. Not validated (call validate()).
  static PinholeCamera fromCameraInfo(const std::string& name, int width, int height,
                                      const Eigen::Matrix<double, 9, 1>& K,
                                      const std::string& distortion_model, const Eigen::VectorXd& D);
};

/// Loads and validates a camera_info YAML file. Missing or malformed fields, a camera_matrix
/// with skew or a bad value throw std::invalid_argument "[PinholeCamera] <file>: ..." naming
/// the field (ConfigNode). camera_name, distortion_model and distortion_coefficients are
/// optional (defaults: "camera", plumb_bob, 5 zeros).
PinholeCamera loadPinholeCamera(const std::string& path);

}  // namespace ehc_control
