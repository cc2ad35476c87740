// RobotCollisionModel, the one collision model (obstacle field, simulator): shapes per link and
// their tests, the link selection and its errors, meshes and bad URDFs rejected, the link tree
// and adjacency, the finger joints and their offsets (toy gripper and the RealMan robot).

#include "ehc_control/robot_collision_model.h"
#include "ehc_test/control_fixtures.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ehc_control {
namespace {

/// Toy gripper: a base box, an arm link (cylinder r 0.03, length 0.20, 0.1 up) on a revolute
/// arm joint, a hand sphere (r 0.05) and two box fingers on prismatic joints (0..0.04 m along
/// +y / -y of the hand); a mesh link and a link without geometry.
const char* kToyUrdf = R"(<?xml version="1.0"?>
<robot name="toy">
  <link name="base"><collision><geometry><box size="0.10 0.06 0.04"/></geometry></collision></link>
  <link name="arm"><collision><origin xyz="0 0 0.1" rpy="0 0 0"/>
    <geometry><cylinder radius="0.03" length="0.20"/></geometry></collision></link>
  <link name="hand"><collision><geometry><sphere radius="0.05"/></geometry></collision></link>
  <link name="left"><collision><geometry><box size="0.01 0.01 0.05"/></geometry></collision></link>
  <link name="right"><collision><geometry><box size="0.01 0.01 0.05"/></geometry></collision></link>
  <link name="mesh"><collision><geometry><mesh filename="package://x/y.stl"/></geometry></collision></link>
  <link name="bare"/>
  <joint name="j_arm" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j_hand" type="fixed"><parent link="arm"/><child link="bare"/><origin xyz="0 0 0.2"/></joint>
  <joint name="j_hand2" type="fixed"><parent link="bare"/><child link="hand"/></joint>
  <joint name="j_left" type="prismatic"><parent link="hand"/><child link="left"/><axis xyz="0 1 0"/>
    <limit lower="0" upper="0.04" effort="1" velocity="0.05"/></joint>
  <joint name="j_right" type="prismatic"><parent link="hand"/><child link="right"/><axis xyz="0 -1 0"/>
    <limit lower="0" upper="0.04" effort="1" velocity="0.05"/></joint>
  <joint name="j_mesh" type="fixed"><parent link="base"/><child link="mesh"/></joint>
</robot>)";

const std::vector<std::string> kToyArm = {"j_arm"};

std::string errorOf(const std::string& urdf, const std::vector<std::string>& arm, const std::vector<std::string>& links) {
  try {
    RobotCollisionModel m(urdf, arm, links);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error for links of " << links.size();
  return "";
}

TEST(RobotCollisionModel, ParsesShapesOfTheListedLinksAndRejectsBadLinks) {
  const RobotCollisionModel m(kToyUrdf, kToyArm, {"hand", "base", "arm"});
  ASSERT_EQ(m.links().size(), 3u);  // in the order asked for
  EXPECT_EQ(m.links()[0].name, "hand");
  EXPECT_EQ(m.links()[1].name, "base");
  EXPECT_EQ(m.links()[2].name, "arm");
  ASSERT_EQ(m.links()[0].shapes.size(), 1u);
  EXPECT_EQ(m.links()[0].shapes[0].type, CollisionShape::Type::Sphere);
  const CollisionShape& box = m.links()[1].shapes.at(0);
  EXPECT_EQ(box.type, CollisionShape::Type::Box);
  EXPECT_TRUE(box.size.isApprox(Eigen::Vector3d(0.10, 0.06, 0.04)));
  EXPECT_NEAR(box.boundingRadius(), 0.5 * std::sqrt(0.01 + 0.0036 + 0.0016), 1e-12);
  EXPECT_TRUE(box.contains(Eigen::Vector3d(0.049, 0.029, 0.019), 0.0));
  EXPECT_FALSE(box.contains(Eigen::Vector3d(0.051, 0, 0), 0.0));
  const CollisionShape& rod = m.links()[2].shapes.at(0);
  EXPECT_EQ(rod.type, CollisionShape::Type::Cylinder);
  EXPECT_NEAR(rod.origin.translation().z(), 0.1, 1e-12);
  EXPECT_TRUE(rod.contains(Eigen::Vector3d(0.02, 0, 0.19), 0.0));
  EXPECT_FALSE(rod.contains(Eigen::Vector3d(0.02, 0, 0.21), 0.0));
  EXPECT_TRUE(rod.contains(Eigen::Vector3d(0.02, 0, 0.21), 0.02));
  EXPECT_NEAR(rod.boundingRadius(), std::hypot(0.03, 0.1), 1e-12);
  EXPECT_TRUE(m.links()[0].shapes[0].contains(Eigen::Vector3d(0, 0.049, 0), 0.0));
  EXPECT_FALSE(m.links()[0].shapes[0].contains(Eigen::Vector3d(0, 0.051, 0), 0.0));
  // The link tree covers every URDF link whatever the selection.
  EXPECT_EQ(m.allLinks().size(), 7u);
  EXPECT_EQ(m.parentOf("hand"), "bare");

  EXPECT_NE(errorOf(kToyUrdf, kToyArm, {"nope"}).find("[RobotCollisionModel] link 'nope' is not in the URDF"),
            std::string::npos);
  EXPECT_NE(errorOf(kToyUrdf, kToyArm, {"bare"}).find("link 'bare' has no collision geometry"), std::string::npos);
  EXPECT_NE(errorOf(kToyUrdf, kToyArm, {"mesh"}).find("mesh"), std::string::npos);
  EXPECT_THROW(RobotCollisionModel("<robot", {}), std::invalid_argument);
}

TEST(RobotCollisionModel, RejectsMeshesAndBadXml) {
  const std::string mesh = R"(<robot name="r"><link name="base_link"><collision><geometry>
      <mesh filename="a.stl"/></geometry></collision></link></robot>)";
  EXPECT_NE(errorOf(mesh, {}, {}).find("[RobotCollisionModel] link 'base_link'"), std::string::npos);
  EXPECT_NE(errorOf(kToyUrdf, kToyArm, {}).find("link 'mesh' has a mesh"), std::string::npos);  // every link read
  EXPECT_THROW(RobotCollisionModel("<robot", {}), std::invalid_argument);
  // A movable joint that is neither an arm joint nor a prismatic finger.
  EXPECT_NE(errorOf(kToyUrdf, {}, {"base"}).find("joint 'j_arm' is movable"), std::string::npos);
}

TEST(RobotCollisionModel, TreeAdjacencyAndFingerOffsets) {
  const RobotCollisionModel m(kToyUrdf, kToyArm, {"base", "arm", "hand", "left", "right"});
  EXPECT_EQ(m.root(), "base");
  EXPECT_EQ(m.parentOf("base"), "");
  EXPECT_EQ(m.parentOf("left"), "hand");
  EXPECT_THROW(m.parentOf("nope"), std::invalid_argument);
  EXPECT_TRUE(m.adjacent("base", "arm"));
  EXPECT_TRUE(m.adjacent("hand", "arm"));  // through "bare", which has no geometry
  EXPECT_TRUE(m.adjacent("left", "hand"));
  EXPECT_FALSE(m.adjacent("left", "right"));
  EXPECT_FALSE(m.adjacent("base", "hand"));
  ASSERT_EQ(m.fingers().size(), 2u);
  const FingerJoint* left = m.fingerOf("left");
  ASSERT_NE(left, nullptr);
  EXPECT_EQ(left->joint, "j_left");
  EXPECT_EQ(left->parent_link, "hand");
  EXPECT_DOUBLE_EQ(left->upper, 0.04);
  EXPECT_DOUBLE_EQ(left->velocity, 0.05);
  EXPECT_EQ(m.fingerOf("hand"), nullptr);
  // Offsets: along the joint axis by the opening; fully open (nullopt) = the upper limit.
  EXPECT_TRUE(m.fingerOffset("left", 0.01).translation().isApprox(Eigen::Vector3d(0, 0.01, 0)));
  EXPECT_TRUE(m.fingerOffset("right", 0.01).translation().isApprox(Eigen::Vector3d(0, -0.01, 0)));
  EXPECT_TRUE(m.fingerOffset("right", std::nullopt).translation().isApprox(Eigen::Vector3d(0, -0.04, 0)));
  EXPECT_TRUE(m.fingerOffset("left", 0.01).linear().isIdentity());
  EXPECT_TRUE(m.fingerOffset("hand", 0.01).isApprox(Eigen::Isometry3d::Identity()));
  EXPECT_TRUE(left->offset(0.02).translation().isApprox(Eigen::Vector3d(0, 0.02, 0)));
  EXPECT_NE(m.summary().find("left (finger joint 'j_left', 0..0.04 m)"), std::string::npos) << m.summary();
}

TEST(RobotCollisionModel, ParsesRealManGeometry) {
  const RobotConfig rc = test::realmanConfig();
  const WholeBodyModel model(rc);
  const RobotCollisionModel m(model.urdfXml(), rc.arm_joints);
  EXPECT_EQ(m.root(), "base_link");
  ASSERT_EQ(m.fingers().size(), 2u);
  EXPECT_EQ(m.fingers()[0].child_link, "left_finger_link");
  EXPECT_NEAR(m.fingers()[0].upper, 0.035, 1e-12);
  EXPECT_TRUE(m.adjacent("link1", "link2"));
  EXPECT_TRUE(m.adjacent("link6", "camera_link"));
  EXPECT_FALSE(m.adjacent("link1", "link3"));
  EXPECT_FALSE(m.adjacent("left_finger_link", "right_finger_link"));
  EXPECT_GE(m.links().size(), 10u);
  // Parents before children.
  for (std::size_t i = 0; i < m.links().size(); ++i)
    for (std::size_t j = i + 1; j < m.links().size(); ++j) EXPECT_NE(m.links()[i].parent, m.links()[j].name);
  EXPECT_TRUE(m.fingerOffset("right_finger_link", std::nullopt).translation().isApprox(Eigen::Vector3d(0, -0.035, 0)));
}

}  // namespace
}  // namespace ehc_control
