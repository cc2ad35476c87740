// PinholeCamera, the one camera model: camera_info YAML loading (the shipped D435 file, errors
// naming the file and the field), validation, projection and the in-image test, and the
// camera_info conversion the nodes use.

#include "ehc_control/pinhole_camera.h"
#include "ehc_test/control_fixtures.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <unistd.h>

namespace ehc_control {
namespace {

using test::realmanCameraYaml;

std::string writeTemp(const std::string& name, const std::string& text) {
  const std::string path = "/tmp/ehc_control_test_" + std::to_string(::getpid()) + "_" + name;
  std::ofstream(path) << text;
  return path;
}

using ehc_control::test::errorOf;

TEST(PinholeCamera, LoadsTheD435Intrinsics) {
  const PinholeCamera c = loadPinholeCamera(realmanCameraYaml());
  EXPECT_EQ(c.width, 640);
  EXPECT_EQ(c.height, 480);
  EXPECT_EQ(c.fx, 615.0);
  EXPECT_EQ(c.fy, 615.0);
  EXPECT_EQ(c.cx, 320.0);
  EXPECT_EQ(c.cy, 240.0);
  EXPECT_EQ(c.name, "d435_color");
  EXPECT_EQ(c.distortion_model, "plumb_bob");
  ASSERT_EQ(c.distortion.size(), 5);
  EXPECT_EQ(c.distortion.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_NE(c.summary().find("'d435_color': 640x480"), std::string::npos) << c.summary();
}

TEST(PinholeCamera, ShippedD435FileProjects) {
  const PinholeCamera c = loadPinholeCamera(realmanCameraYaml());
  Eigen::Vector2d uv;
  EXPECT_TRUE(c.projectsInside(Eigen::Vector3d(0, 0, 1), &uv));
  EXPECT_DOUBLE_EQ(uv.x(), 320.0);
  EXPECT_TRUE(c.projectsInside(Eigen::Vector3d(0.1, -0.05, 1.0), &uv));
  EXPECT_DOUBLE_EQ(uv.x(), 320.0 + 61.5);
  EXPECT_DOUBLE_EQ(uv.y(), 240.0 - 30.75);
  EXPECT_TRUE(c.pixel(Eigen::Vector3d(0.1, -0.05, 1.0)).isApprox(uv));
  EXPECT_FALSE(c.projectsInside(Eigen::Vector3d(0, 0, -1), &uv));  // behind
  EXPECT_FALSE(c.projectsInside(Eigen::Vector3d(1, 0, 1), &uv));   // outside the image
}

TEST(PinholeCamera, BadFilesNameTheFileAndField) {
  EXPECT_NE(errorOf([] { loadPinholeCamera("/nonexistent/camera.yaml"); }).find("[PinholeCamera]"), std::string::npos);
  const std::string no_k = writeTemp("no_k.yaml", "image_width: 640\nimage_height: 480\n");
  std::string e = errorOf([&] { loadPinholeCamera(no_k); });
  EXPECT_NE(e.find("camera_matrix"), std::string::npos) << e;
  EXPECT_NE(e.find(no_k), std::string::npos) << e;
  const std::string bad_f =
      writeTemp("bad_f.yaml", "image_width: 640\nimage_height: 480\ncamera_matrix: {data: [0, 0, 320, 0, 615, 240, 0, 0, 1]}\n");
  e = errorOf([&] { loadPinholeCamera(bad_f); });
  EXPECT_NE(e.find("fx"), std::string::npos) << e;
  EXPECT_NE(e.find(bad_f), std::string::npos) << e;
  const std::string short_k =
      writeTemp("short_k.yaml", "image_width: 640\nimage_height: 480\ncamera_matrix: {data: [1, 2, 3]}\n");
  e = errorOf([&] { loadPinholeCamera(short_k); });
  EXPECT_NE(e.find("camera_matrix.data' must have 9 elements"), std::string::npos) << e;
  const std::string negative_f = writeTemp(
      "negative_f.yaml", "image_width: 640\nimage_height: 480\ncamera_matrix: {data: [-615, 0, 320, 0, 615, 240, 0, 0, 1]}\n");
  EXPECT_THROW(loadPinholeCamera(negative_f), std::invalid_argument);
  const std::string skew = writeTemp(
      "skew.yaml", "image_width: 640\nimage_height: 480\ncamera_matrix: {data: [615, 1, 320, 0, 615, 240, 0, 0, 1]}\n");
  e = errorOf([&] { loadPinholeCamera(skew); });
  EXPECT_NE(e.find("camera_matrix.data"), std::string::npos) << e;
  const std::string no_height = writeTemp("no_height.yaml", "image_width: 640\n");
  e = errorOf([&] { loadPinholeCamera(no_height); });
  EXPECT_NE(e.find("image_height"), std::string::npos) << e;
  const std::string outside = writeTemp(
      "outside.yaml", "image_width: 640\nimage_height: 480\ncamera_matrix: {data: [615, 0, 700, 0, 615, 240, 0, 0, 1]}\n");
  e = errorOf([&] { loadPinholeCamera(outside); });
  EXPECT_NE(e.find("'cx'"), std::string::npos) << e;
  const std::string distorted = writeTemp(
      "distorted.yaml", "camera_name: cam\nimage_width: 320\nimage_height: 240\n"
                        "camera_matrix: {data: [300, 0, 160, 0, 300, 120, 0, 0, 1]}\n"
                        "distortion_model: rational_polynomial\ndistortion_coefficients: {data: [0.1, -0.2, 0, 0, 0.01, 0, 0, 0]}\n");
  const PinholeCamera d = loadPinholeCamera(distorted);
  EXPECT_EQ(d.name, "cam");
  EXPECT_EQ(d.distortion_model, "rational_polynomial");
  ASSERT_EQ(d.distortion.size(), 8);
  EXPECT_EQ(d.distortion[1], -0.2);
  // The matrices' shapes: rows / cols of the wrong type or size, a projection of the wrong size.
  const std::string k_rows = writeTemp(
      "k_rows.yaml", "image_width: 640\nimage_height: 480\ncamera_matrix: {rows: abc, cols: 3, data: [615, 0, 320, 0, 615, 240, 0, 0, 1]}\n");
  e = errorOf([&] { loadPinholeCamera(k_rows); });
  EXPECT_NE(e.find(k_rows + ": field 'camera_matrix.rows' has the wrong type"), std::string::npos) << e;
  const std::string p_size = writeTemp(
      "p_size.yaml", "image_width: 640\nimage_height: 480\ncamera_matrix: {data: [615, 0, 320, 0, 615, 240, 0, 0, 1]}\n"
                     "projection_matrix: {rows: 3, cols: 4, data: [615, 0, 320, 0, 615, 240, 0, 0, 1]}\n");
  e = errorOf([&] { loadPinholeCamera(p_size); });
  EXPECT_NE(e.find("field 'projection_matrix.data' must have 12 elements"), std::string::npos) << e;
  const std::string d_cols = writeTemp(
      "d_cols.yaml", "image_width: 640\nimage_height: 480\ncamera_matrix: {data: [615, 0, 320, 0, 615, 240, 0, 0, 1]}\n"
                     "distortion_coefficients: {rows: 1, cols: 5, data: [0, 0, 0, 0]}\n");
  e = errorOf([&] { loadPinholeCamera(d_cols); });
  EXPECT_NE(e.find("field 'distortion_coefficients.data' must have 5 elements"), std::string::npos) << e;
  const std::string typo = writeTemp(
      "typo.yaml", "image_width: 640\nimage_heigth: 480\nimage_height: 480\ncamera_matrix: {data: [615, 0, 320, 0, 615, 240, 0, 0, 1]}\n");
  e = errorOf([&] { loadPinholeCamera(typo); });
  EXPECT_NE(e.find(typo + ": unknown field 'image_heigth' (did you mean 'image_height'?)"), std::string::npos) << e;
  for (const auto& f : {no_k, bad_f, short_k, negative_f, skew, no_height, outside, distorted, k_rows, p_size, d_cols, typo})
    std::remove(f.c_str());
}

TEST(PinholeCamera, InViewMeansInsideTheImageAtPositiveDepth) {
  const PinholeCamera c = loadPinholeCamera(realmanCameraYaml());
  Eigen::Vector2d uv;
  EXPECT_TRUE(c.projectsInside(Eigen::Vector3d(0, 0, 1), &uv));
  EXPECT_TRUE(uv.isApprox(Eigen::Vector2d(320, 240)));
  EXPECT_FALSE(c.projectsInside(Eigen::Vector3d(0, 0, -1)));  // behind
  EXPECT_FALSE(c.projectsInside(Eigen::Vector3d(0, 0, 0)));
  EXPECT_FALSE(c.projectsInside(Eigen::Vector3d(0, 0, 0.5 * c.min_depth)));  // at the image plane
  // Horizontal edge: u = 320 + 615 x / z; inside for u < 640, i.e. x/z < 320/615.
  EXPECT_TRUE(c.projectsInside(Eigen::Vector3d(0.52, 0, 1)));
  EXPECT_FALSE(c.projectsInside(Eigen::Vector3d(0.521, 0, 1)));
  EXPECT_TRUE(c.projectsInside(Eigen::Vector3d(-0.52, 0, 1)));
  EXPECT_FALSE(c.projectsInside(Eigen::Vector3d(-0.521, 0, 1)));
  // Vertical edge: v = 240 + 615 y / z; inside for |y/z| < 240/615 = 0.390.
  EXPECT_TRUE(c.projectsInside(Eigen::Vector3d(0, 0.39, 1)));
  EXPECT_FALSE(c.projectsInside(Eigen::Vector3d(0, 0.391, 1)));
  EXPECT_FALSE(c.projectsInside(Eigen::Vector3d(std::nan(""), 0, 1)));
}

TEST(PinholeCamera, ValidationAndCameraInfoConversion) {
  EXPECT_NO_THROW(PinholeCamera().validate());
  auto invalid = [](void (*edit)(PinholeCamera&), const std::string& field) {
    PinholeCamera c;
    edit(c);
    const std::string e = errorOf([&] { c.validate(); });
    EXPECT_NE(e.find("[PinholeCamera]"), std::string::npos) << e;
    EXPECT_NE(e.find(field), std::string::npos) << e;
  };
  invalid([](PinholeCamera& c) { c.width = 0; }, "image_width");
  invalid([](PinholeCamera& c) { c.height = -1; }, "image_height");
  invalid([](PinholeCamera& c) { c.fx = 0.0; }, "fx");
  invalid([](PinholeCamera& c) { c.fy = std::nan(""); }, "fy");
  invalid([](PinholeCamera& c) { c.cy = 481.0; }, "cy");
  invalid([](PinholeCamera& c) { c.distortion[2] = INFINITY; }, "distortion");
  invalid([](PinholeCamera& c) { c.min_depth = -1.0; }, "min_depth");

  Eigen::Matrix<double, 9, 1> K;
  K << 500, 0, 300, 0, 510, 200, 0, 0, 1;
  const PinholeCamera c = PinholeCamera::fromCameraInfo("optical", 600, 400, K, "plumb_bob", Eigen::VectorXd());
  EXPECT_EQ(c.name, "optical");
  EXPECT_EQ(c.width, 600);
  EXPECT_EQ(c.height, 400);
  EXPECT_EQ(c.fx, 500.0);
  EXPECT_EQ(c.fy, 510.0);
  EXPECT_EQ(c.cx, 300.0);
  EXPECT_EQ(c.cy, 200.0);
  EXPECT_EQ(c.distortion.size(), 0);
  EXPECT_NO_THROW(c.validate());
}

TEST(PinholeCamera, SameIntrinsicsComparesSizeAndIntrinsicsOnly) {
  const PinholeCamera a;
  PinholeCamera b = a;
  b.name = "other";
  b.distortion_model = "equidistant";
  b.distortion = Eigen::VectorXd::Ones(4);
  b.min_depth = 0.5;
  EXPECT_TRUE(a.sameIntrinsics(b));  // what a projection uses is the same
  for (void (*edit)(PinholeCamera&) :
       {+[](PinholeCamera& c) { c.width = 641; }, +[](PinholeCamera& c) { c.height = 479; },
        +[](PinholeCamera& c) { c.fx += 1e-9; }, +[](PinholeCamera& c) { c.fy += 1e-9; },
        +[](PinholeCamera& c) { c.cx += 1e-9; }, +[](PinholeCamera& c) { c.cy += 1e-9; }}) {
    PinholeCamera c = a;
    edit(c);
    EXPECT_FALSE(a.sameIntrinsics(c));
    EXPECT_FALSE(c.sameIntrinsics(a));
  }
}

}  // namespace
}  // namespace ehc_control
