#pragma once
// RobotCollisionModel: the robot's collision geometry (boxes, cylinders, spheres) per link and
// the URDF link tree, parsed with urdfdom (urdf::parseURDF, ROS-free). Also the gripper's
// finger joints (prismatic joints that are not arm joints). Used by SimWorld to build the
// kinematic Bullet bodies and decide which link pairs are adjacent.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <map>
#include <set>
#include <string>
#include <vector>

namespace ehc_sim {

struct LinkShape {
  enum Type { Box, Cylinder, Sphere } type = Box;
  Eigen::Vector3d size = Eigen::Vector3d::Zero();  ///< box: edges; cylinder: [radius, length, 0]; sphere: [radius, 0, 0]
  Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();  ///< in the link frame
};

struct RobotLinkGeometry {
  std::string name;
  std::string parent;        ///< parent link ("" for the root)
  std::string parent_joint;  ///< joint from the parent ("" for the root)
  std::vector<LinkShape> shapes;
};

/// A prismatic finger joint: child = parent * origin * Translation(axis * opening).
struct FingerJoint {
  std::string joint;
  std::string parent_link;
  std::string child_link;
  Eigen::Vector3d axis = Eigen::Vector3d::UnitY();
  double lower = 0.0, upper = 0.035, velocity = 0.05;
};

class RobotCollisionModel {
 public:
  /// Parses the URDF XML. `arm_joints` are excluded from the finger joints; every other
  /// prismatic joint is a gripper finger. Throws std::invalid_argument
  /// "[RobotCollisionModel] ..." on a parse error, mesh geometry or an unsupported movable joint.
  RobotCollisionModel(const std::string& urdf_xml, const std::vector<std::string>& arm_joints);

  /// Links that have collision geometry, root first (parents before children).
  const std::vector<RobotLinkGeometry>& links() const { return links_; }
  const std::vector<FingerJoint>& fingers() const { return fingers_; }
  const std::string& root() const { return root_; }
  /// Parent link of any URDF link ("" for the root). Throws on an unknown link.
  const std::string& parentOf(const std::string& link) const;
  /// Every URDF link name (with or without geometry), parents before children.
  const std::vector<std::string>& allLinks() const { return all_links_; }
  /// The finger joint whose child is `link`, or nullptr.
  const FingerJoint* fingerOf(const std::string& link) const;
  /// True if a is the nearest ancestor with geometry of b or vice versa (their shapes touch
  /// by construction and are never checked against each other).
  bool adjacent(const std::string& a, const std::string& b) const;

 private:
  std::vector<RobotLinkGeometry> links_;
  std::vector<FingerJoint> fingers_;
  std::vector<std::string> all_links_;
  std::map<std::string, std::string> parent_;
  std::map<std::string, std::string> geometric_parent_;
  std::string root_;
};

}  // namespace ehc_sim
