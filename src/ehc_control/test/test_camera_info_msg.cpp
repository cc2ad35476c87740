// PinholeCamera <-> sensor_msgs/CameraInfo (src/nodes/ehc_control/camera_info_msg.h), the
// conversion every node uses: the fields read and written, and the round trip.
#include "ehc_control/camera_info_msg.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ehc_control {
namespace {

sensor_msgs::CameraInfo d435Info() {
  sensor_msgs::CameraInfo m;
  m.header.frame_id = "camera_color_optical_frame";
  m.width = 640;
  m.height = 480;
  m.distortion_model = "plumb_bob";
  m.D = {0.1, -0.2, 0.001, 0.002, 0.05};
  m.K = {615.5, 0, 321.25, 0, 616.75, 239.5, 0, 0, 1};
  return m;
}

TEST(CameraInfoMsg, CameraFromInfoReadsSizeIntrinsicsAndDistortion) {
  const PinholeCamera c = cameraFromInfo(d435Info());
  EXPECT_EQ(c.name, "camera_color_optical_frame");
  EXPECT_EQ(c.width, 640);
  EXPECT_EQ(c.height, 480);
  EXPECT_EQ(c.fx, 615.5);
  EXPECT_EQ(c.fy, 616.75);
  EXPECT_EQ(c.cx, 321.25);
  EXPECT_EQ(c.cy, 239.5);
  EXPECT_EQ(c.distortion_model, "plumb_bob");
  ASSERT_EQ(c.distortion.size(), 5);
  EXPECT_EQ(c.distortion[1], -0.2);
  EXPECT_NO_THROW(c.validate());

  sensor_msgs::CameraInfo none = d435Info();
  none.D.clear();
  EXPECT_EQ(cameraFromInfo(none).distortion.size(), 0);
}

TEST(CameraInfoMsg, ABadMessageIsConvertedAndCaughtByValidate) {
  sensor_msgs::CameraInfo m = d435Info();
  m.K[0] = 0.0;  // fx
  EXPECT_THROW(cameraFromInfo(m).validate(), std::invalid_argument);
  m = d435Info();
  m.D[3] = std::nan("");
  EXPECT_THROW(cameraFromInfo(m).validate(), std::invalid_argument);
  m = sensor_msgs::CameraInfo();  // all zero: a driver that has not been calibrated
  EXPECT_THROW(cameraFromInfo(m).validate(), std::invalid_argument);
}

TEST(CameraInfoMsg, FillCameraInfoWritesAnIdealPinholeThatReadsBack) {
  PinholeCamera k = cameraFromInfo(d435Info());  // non-zero distortion: not written
  sensor_msgs::CameraInfo m;
  ros::Time stamp;
  stamp.fromNSec(1234567890123ULL);
  fillCameraInfo(k, "cam", stamp, &m);
  EXPECT_EQ(m.header.stamp, stamp);
  EXPECT_EQ(m.header.frame_id, "cam");
  EXPECT_EQ(m.width, 640u);
  EXPECT_EQ(m.height, 480u);
  EXPECT_EQ(m.distortion_model, "plumb_bob");
  EXPECT_EQ(m.D, std::vector<double>(5, 0.0));
  const boost::array<double, 9> K{{615.5, 0, 321.25, 0, 616.75, 239.5, 0, 0, 1}};
  EXPECT_EQ(m.K, K);
  const boost::array<double, 9> R{{1, 0, 0, 0, 1, 0, 0, 0, 1}};
  EXPECT_EQ(m.R, R);
  const boost::array<double, 12> P{{615.5, 0, 321.25, 0, 0, 616.75, 239.5, 0, 0, 0, 1, 0}};
  EXPECT_EQ(m.P, P);

  const PinholeCamera back = cameraFromInfo(m);
  EXPECT_EQ(back.name, "cam");
  EXPECT_TRUE(back.sameIntrinsics(k));
  EXPECT_EQ(back.distortion, Eigen::VectorXd::Zero(5));
}

}  // namespace
}  // namespace ehc_control
