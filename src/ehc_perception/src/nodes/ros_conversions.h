#pragma once
// Message <-> core conversions shared by the perception nodes (node side only: roscpp types),
// and their log line of what became of their frames (countFrame).
// CameraInfo <-> PinholeCamera: ehc_control/camera_info_msg.h (every package's nodes).

#include "ehc_perception/frame_counts.h"
#include "ehc_perception/grasp_generator.h"
#include "ehc_perception/point_cloud_layout.h"

#include <geometry_msgs/Pose.h>
#include <ros/console.h>
#include <ros/time.h>
#include <geometry_msgs/TransformStamped.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/image_encodings.h>
#include <tf2_eigen/tf2_eigen.h>
#include <visp3/core/vpImage.h>
#include <visp3/core/vpImageConvert.h>

#include <stdexcept>
#include <string>

namespace ehc_perception::ros_conv {

/// sensor_msgs/Image (mono8, rgb8, bgr8, rgba8, bgra8) to an 8-bit grey ViSP image.
inline void imageToGray(const sensor_msgs::Image& msg, vpImage<unsigned char>* out) {
  namespace enc = sensor_msgs::image_encodings;
  int channels = 0;
  if (msg.encoding == enc::MONO8) channels = 1;
  else if (msg.encoding == enc::RGB8 || msg.encoding == enc::BGR8) channels = 3;
  else if (msg.encoding == enc::RGBA8 || msg.encoding == enc::BGRA8) channels = 4;
  else throw std::invalid_argument("unsupported image encoding '" + msg.encoding + "'");
  if (msg.width == 0 || msg.height == 0 || msg.step < msg.width * channels ||
      msg.data.size() < static_cast<std::size_t>(msg.step) * msg.height)
    throw std::invalid_argument("image " + std::to_string(msg.width) + "x" +
                                std::to_string(msg.height) + " step " + std::to_string(msg.step) +
                                " does not match its " + std::to_string(msg.data.size()) +
                                " data bytes");
  out->resize(msg.height, msg.width);
  for (unsigned r = 0; r < msg.height; ++r) {
    const unsigned char* row = msg.data.data() + static_cast<std::size_t>(r) * msg.step;
    unsigned char* dst = (*out)[r];
    if (channels == 1) {
      std::copy(row, row + msg.width, dst);
    } else if (msg.encoding == enc::RGB8) {
      vpImageConvert::RGBToGrey(const_cast<unsigned char*>(row), dst, msg.width);
    } else if (msg.encoding == enc::BGR8) {
      vpImageConvert::BGRToGrey(const_cast<unsigned char*>(row), dst, msg.width, 1, false);
    } else if (msg.encoding == enc::RGBA8) {
      vpImageConvert::RGBaToGrey(const_cast<unsigned char*>(row), dst, msg.width);
    } else {
      vpImageConvert::BGRaToGrey(const_cast<unsigned char*>(row), dst, msg.width, 1, false);
    }
  }
}

/// The finite x, y, z points of a PointCloud2, at most `max_points` of them read (PointBudget;
/// 0 = every point): the message's layout is copied into a PointCloudLayout and validated before
/// any byte is read (FLOAT64 converted, NaN / Inf points dropped). Throws
/// std::invalid_argument("[PointCloudLayout] ...") on a malformed cloud.
inline CloudPoints cloudToPoints(const sensor_msgs::PointCloud2& msg, std::size_t max_points) {
  PointCloudLayout layout;
  layout.width = msg.width;
  layout.height = msg.height;
  for (const sensor_msgs::PointField& f : msg.fields)
    layout.fields.push_back({f.name, f.offset, f.datatype, f.count});
  layout.is_bigendian = msg.is_bigendian;
  layout.point_step = msg.point_step;
  layout.row_step = msg.row_step;
  return extractCloudPoints(layout, msg.data.data(), msg.data.size(), max_points);
}

/// Counts a frame's outcome and logs the counts when FrameCounts::reportDue says so (on the wall
/// clock): WARN once frames were dropped, else INFO (the first frame over the point budget).
inline void countFrame(FrameCounts* counts, FrameOutcome o, const char* node) {
  counts->add(o);
  const std::string report = counts->reportDue(ros::WallTime::now().toSec());
  if (report.empty()) return;
  if (counts->dropped() > 0) ROS_WARN_STREAM(node << ": " << report);
  else ROS_INFO_STREAM(node << ": " << report);
}

inline geometry_msgs::Pose toPose(const Eigen::Isometry3d& T) { return tf2::toMsg(T); }

}  // namespace ehc_perception::ros_conv
