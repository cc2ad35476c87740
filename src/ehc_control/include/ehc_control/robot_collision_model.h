#pragma once
// RobotCollisionModel: the robot's collision geometry, read once from the URDF (urdfdom,
// ROS-free) for every package that needs it (the obstacle distance field of ehc_perception,
// SimWorld of ehc_sim):
//  - the URDF link tree: every link's parent, and for the links with geometry their nearest
//    ancestor with geometry ("geometric parent": adjacent links, whose shapes touch by
//    construction);
//  - the collision shapes per link (box, cylinder, sphere, in the link frame); a mesh is
//    rejected with an error naming the link;
//  - the gripper's finger joints (prismatic joints that are not arm joints) and the pose
//    offset of a finger link for a given finger opening. WholeBodyModel only moves the arm
//    joints, so it puts a finger link where it is at opening 0 (closed); whoever poses the
//    links applies fingerOffset() with the opening it models (SimWorld: the gripper's state;
//    ObstacleDistanceField: fully open by default).

#include <Eigen/Geometry>

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace ehc_control {

struct CollisionShape {
  enum class Type { Box, Cylinder, Sphere };
  Type type = Type::Box;
  /// Box: full edges x, y, z. Cylinder: radius, length (along the shape's z), 0. Sphere: r, 0, 0.
  Eigen::Vector3d size = Eigen::Vector3d::Zero();
  Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();  ///< shape pose in the link frame

  /// True if `p_link` (link frame) is inside the shape inflated by `padding` (m).
  bool contains(const Eigen::Vector3d& p_link, double padding) const;
  /// Radius of a sphere around the shape origin that encloses the shape.
  double boundingRadius() const;
  /// Half edges of the box around the shape, in the shape's frame (its origin at the centre).
  Eigen::Vector3d halfExtents() const;
};

/// A link with collision geometry.
struct RobotLinkGeometry {
  std::string name;
  std::string parent;        ///< URDF parent link ("" for the root)
  std::string parent_joint;  ///< joint from the parent ("" for the root)
  std::vector<CollisionShape> shapes;  ///< at least one
};

/// A prismatic finger joint: child = parent * origin * Translation(axis * opening).
struct FingerJoint {
  std::string joint;
  std::string parent_link;
  std::string child_link;
  Eigen::Vector3d axis = Eigen::Vector3d::UnitY();  ///< unit, in the child (joint) frame
  double lower = 0.0, upper = 0.035, velocity = 0.05;  ///< URDF limits (m, m/s)
  /// The child link's pose at `opening` relative to its pose at opening 0.
  Eigen::Isometry3d offset(double opening) const;
};

class RobotCollisionModel {
 public:
  /// Parses `urdf_xml`. `arm_joints` are excluded from the finger joints; every other
  /// prismatic joint is a gripper finger (limits lower < upper required), any other movable
  /// joint outside the arm is an error. `links`: the links whose geometry is kept, in this
  /// order (each must exist and have collision geometry; meshes on the other links are not
  /// read); empty = every link with collision geometry, parents before children. Throws
  /// std::invalid_argument "[RobotCollisionModel] ..." on a bad URDF, an unknown link, a
  /// listed link without collision geometry, a mesh, or a bad joint.
  RobotCollisionModel(const std::string& urdf_xml, const std::vector<std::string>& arm_joints,
                      const std::vector<std::string>& links = {});

  /// The kept links with their shapes (see the constructor for the order).
  const std::vector<RobotLinkGeometry>& links() const { return links_; }
  const std::vector<FingerJoint>& fingers() const { return fingers_; }
  const std::string& root() const { return root_; }
  /// Parent link of any URDF link ("" for the root). Throws on an unknown link.
  const std::string& parentOf(const std::string& link) const;
  /// Every URDF link name (with or without geometry), parents before children.
  const std::vector<std::string>& allLinks() const { return all_links_; }
  /// The finger joint whose child is `link`, or nullptr.
  const FingerJoint* fingerOf(const std::string& link) const;
  /// True if a is the nearest kept ancestor with geometry of b or vice versa (their shapes
  /// touch by construction and are never checked against each other).
  bool adjacent(const std::string& a, const std::string& b) const;
  /// Pose of `link` relative to where it is with every finger joint at 0: for a finger link
  /// FingerJoint::offset(opening), where `opening` std::nullopt = the joint's upper limit
  /// (fully open); identity for every other link.
  Eigen::Isometry3d fingerOffset(const std::string& link, std::optional<double> opening) const;
  std::string summary() const;

 private:
  std::vector<RobotLinkGeometry> links_;
  std::vector<FingerJoint> fingers_;
  std::vector<std::string> all_links_;
  std::map<std::string, std::string> parent_;
  std::map<std::string, std::string> geometric_parent_;
  std::string root_;
};

}  // namespace ehc_control
