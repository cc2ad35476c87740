// Pins the md5sums of the rm_msgs messages to the values of the RealMan rm_driver (ROS 1):
// ROS 1 connects a publisher and a subscriber only when the md5sums agree, so a changed field
// would silently cut the adapter off the real arm. Reference values: md5 of the field lists
//   JointPos "float32[] joint\nfloat32 expand", Stop "bool state",
//   Gripper_Set "uint16 position", Gripper_Pick "uint16 speed\nuint16 force"
// (as published in the driver's generated message code).

#include <rm_msgs/Gripper_Pick.h>
#include <rm_msgs/Gripper_Set.h>
#include <rm_msgs/JointPos.h>
#include <rm_msgs/Stop.h>
#include <ros/message_traits.h>
#include <ros/serialization.h>

#include <gtest/gtest.h>

#include <string>

namespace {
template <class M>
std::string md5() {
  return ros::message_traits::MD5Sum<M>::value();
}
template <class M>
std::string type() {
  return ros::message_traits::DataType<M>::value();
}
}  // namespace

TEST(RmMsgs, Md5sumsMatchTheRealManDriver) {
  EXPECT_EQ(md5<rm_msgs::JointPos>(), "278dfe354f7a05e095637c9789d0fcfe");
  EXPECT_EQ(md5<rm_msgs::Stop>(), "001fde3cab9e313a150416ff09c08ee4");
  EXPECT_EQ(md5<rm_msgs::Gripper_Set>(), "e6fa9d1b49571c7fff8bae5e451e5e59");
  EXPECT_EQ(md5<rm_msgs::Gripper_Pick>(), "bccee2d260af47427a90b0534ed4c5ac");
}

TEST(RmMsgs, TypeNamesMatchTheDriver) {
  EXPECT_EQ(type<rm_msgs::JointPos>(), "rm_msgs/JointPos");
  EXPECT_EQ(type<rm_msgs::Stop>(), "rm_msgs/Stop");
  EXPECT_EQ(type<rm_msgs::Gripper_Set>(), "rm_msgs/Gripper_Set");
  EXPECT_EQ(type<rm_msgs::Gripper_Pick>(), "rm_msgs/Gripper_Pick");
}

TEST(RmMsgs, WireLayoutIsTheDriverOne) {
  // JointPos: uint32 length + 6 float32 + float32 expand = 4 + 24 + 4 bytes.
  rm_msgs::JointPos j;
  j.joint = {0.1f, 0.2f, 0.3f, 0.4f, 0.5f, 0.6f};
  j.expand = 0.0f;
  EXPECT_EQ(ros::serialization::serializationLength(j), 32u);
  rm_msgs::Stop s;
  EXPECT_EQ(ros::serialization::serializationLength(s), 1u);
  rm_msgs::Gripper_Set g;
  EXPECT_EQ(ros::serialization::serializationLength(g), 2u);
  rm_msgs::Gripper_Pick p;
  EXPECT_EQ(ros::serialization::serializationLength(p), 4u);
}
