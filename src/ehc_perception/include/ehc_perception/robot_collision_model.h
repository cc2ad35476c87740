#pragma once
// RobotCollisionModel: the robot's collision primitives, read from the URDF <collision>
// elements (urdfdom, ROS-free). Boxes, cylinders and spheres; meshes are rejected.
// Shapes are expressed in their link frame; WholeBodyModel poses the links.

#include <Eigen/Geometry>

#include <string>
#include <vector>

namespace ehc_perception {

struct CollisionShape {
  enum class Type { Box, Cylinder, Sphere };
  std::string link;
  Type type = Type::Box;
  /// Box: full sizes x, y, z. Cylinder: radius, length (along the shape's z), 0. Sphere: r, 0, 0.
  Eigen::Vector3d size = Eigen::Vector3d::Zero();
  Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();  ///< shape pose in the link frame

  /// Signed distance-like test: true if `p_link` (link frame) is inside the shape inflated
  /// by `padding` (m).
  bool contains(const Eigen::Vector3d& p_link, double padding) const;
  /// Radius of a sphere around the shape origin that encloses the shape.
  double boundingRadius() const;
};

class RobotCollisionModel {
 public:
  /// Parses `urdf_xml` and keeps the collision elements of `links` (every link that has
  /// collision geometry if `links` is empty). Throws std::invalid_argument
  /// "[RobotCollisionModel] ..." on a bad URDF, an unknown link, a listed link without
  /// collision geometry, or a mesh.
  RobotCollisionModel(const std::string& urdf_xml, const std::vector<std::string>& links);

  const std::vector<CollisionShape>& shapes() const { return shapes_; }
  /// Link names in the order given (or URDF order), each with at least one shape.
  const std::vector<std::string>& links() const { return links_; }
  /// Pose of links()[i] relative to where WholeBodyModel puts it. WholeBodyModel holds every
  /// joint outside the arm at 0; a link on a prismatic joint (a gripper finger: 0 = closed)
  /// is moved here to the joint's upper limit, i.e. the gripper fully open, the widest it
  /// gets. Identity for every other link.
  const Eigen::Isometry3d& linkOffset(std::size_t i) const { return link_offsets_.at(i); }
  std::string summary() const;

 private:
  std::vector<CollisionShape> shapes_;
  std::vector<std::string> links_;
  std::vector<Eigen::Isometry3d> link_offsets_;  ///< per links_ entry, see linkOffset()
};

}  // namespace ehc_perception
