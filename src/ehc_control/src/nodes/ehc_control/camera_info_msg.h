#pragma once
// PinholeCamera <-> sensor_msgs/CameraInfo: the one home of this conversion for the nodes of
// every package (the tag node and the grasp sequencer read camera_info, the simulators publish
// it). Node side only: it includes ROS message headers, so it sits beside ehc_control's nodes
// (src/nodes/, exported to the nodes of the packages that depend on ehc_control, as ehc_common
// exports its lockstep_ack.h), never in the ROS-free include/. Header-only.

#include "ehc_control/pinhole_camera.h"

#include <sensor_msgs/CameraInfo.h>

#include <cstdint>
#include <string>

namespace ehc_control {

/// The camera of a camera_info message: its frame_id as the name, width, height, K (fx, fy, cx,
/// cy), distortion model and D (kept for information). Not validated: call
/// PinholeCamera::validate() (a sender's bad values reach the caller).
inline PinholeCamera cameraFromInfo(const sensor_msgs::CameraInfo& msg) {
  return PinholeCamera::fromCameraInfo(
      msg.header.frame_id, static_cast<int>(msg.width), static_cast<int>(msg.height),
      Eigen::Map<const Eigen::Matrix<double, 9, 1>>(msg.K.data()), msg.distortion_model,
      Eigen::Map<const Eigen::VectorXd>(msg.D.data(), static_cast<Eigen::Index>(msg.D.size())));
}

/// The camera_info message of images rendered or rectified for the ideal pinhole `k` (every user
/// of the stack projects one): K of k, zero plumb_bob distortion whatever k.distortion holds,
/// R = identity, P = [K | 0].
inline void fillCameraInfo(const PinholeCamera& k, const std::string& frame, const ros::Time& stamp,
                           sensor_msgs::CameraInfo* m) {
  m->header.stamp = stamp;
  m->header.frame_id = frame;
  m->width = static_cast<std::uint32_t>(k.width);
  m->height = static_cast<std::uint32_t>(k.height);
  m->distortion_model = "plumb_bob";
  m->D.assign(5, 0.0);
  m->K = {k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1};
  m->R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  m->P = {k.fx, 0, k.cx, 0, 0, k.fy, k.cy, 0, 0, 0, 1, 0};
}

}  // namespace ehc_control
