#include "ehc_perception/camera_intrinsics.h"

#include <gtest/gtest.h>

#include <fstream>

using ehc_perception::CameraIntrinsics;
using ehc_perception::loadCameraIntrinsics;

TEST(CameraIntrinsics, ShippedD435FileLoads) {
  const CameraIntrinsics c =
      loadCameraIntrinsics(std::string(EHC_CONFIG_DIR) + "/robots/realman_rm65_water2/camera.yaml");
  EXPECT_EQ(c.width, 640);
  EXPECT_EQ(c.height, 480);
  EXPECT_DOUBLE_EQ(c.fx, 615.0);
  EXPECT_DOUBLE_EQ(c.cy, 240.0);
  Eigen::Vector2d uv;
  EXPECT_TRUE(c.project(Eigen::Vector3d(0, 0, 1), &uv));
  EXPECT_DOUBLE_EQ(uv.x(), 320.0);
  EXPECT_TRUE(c.project(Eigen::Vector3d(0.1, -0.05, 1.0), &uv));
  EXPECT_DOUBLE_EQ(uv.x(), 320.0 + 61.5);
  EXPECT_DOUBLE_EQ(uv.y(), 240.0 - 30.75);
  EXPECT_FALSE(c.project(Eigen::Vector3d(0, 0, -1), &uv));  // behind
  EXPECT_FALSE(c.project(Eigen::Vector3d(1, 0, 1), &uv));   // outside the image
}

TEST(CameraIntrinsics, BadFilesFailClearly) {
  EXPECT_THROW(loadCameraIntrinsics("/nonexistent/camera.yaml"), std::invalid_argument);
  const std::string path = "/tmp/ehc_bad_camera.yaml";
  std::ofstream(path) << "image_width: 640\nimage_height: 480\ncamera_matrix: {data: [1, 2, 3]}\n";
  try {
    loadCameraIntrinsics(path);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("camera_matrix.data' must have 9 elements"),
              std::string::npos)
        << e.what();
  }
  std::ofstream(path) << "image_width: 640\nimage_height: 480\n"
                         "camera_matrix: {data: [-615, 0, 320, 0, 615, 240, 0, 0, 1]}\n";
  EXPECT_THROW(loadCameraIntrinsics(path), std::invalid_argument);
}
