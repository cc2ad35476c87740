#pragma once
// The collision primitives of a URDF link, read once for every package that needs the robot's
// collision geometry (simulator bodies, obstacle distances). ROS-free (urdfdom).

#include <Eigen/Geometry>

#include <string>
#include <vector>

namespace urdf {
class Link;
}

namespace ehc_control {

struct UrdfCollisionShape {
  enum class Type { Box, Cylinder, Sphere };
  Type type = Type::Box;
  Eigen::Vector3d size = Eigen::Vector3d::Zero();  ///< box: edges; cylinder: [radius, length, 0]; sphere: [radius, 0, 0]
  Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();  ///< shape pose in the link frame
};

/// Every <collision> primitive of `link`. Throws std::invalid_argument "[<owner>] link '...'
/// has a mesh collision geometry ..." (only box, cylinder and sphere are supported) or
/// "... has a degenerate collision shape" (non-positive size).
std::vector<UrdfCollisionShape> urdfCollisionShapes(const urdf::Link& link, const std::string& owner);

}  // namespace ehc_control
