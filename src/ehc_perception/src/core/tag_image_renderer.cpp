#include "ehc_perception/tag_image_renderer.h"

#include <visp3/core/vpCameraParameters.h>
#include <visp3/core/vpColVector.h>
#include <visp3/core/vpHomogeneousMatrix.h>
#include <visp3/robot/vpImageSimulator.h>

#include <apriltag/apriltag.h>
#include <apriltag/tag16h5.h>
#include <apriltag/tag25h9.h>
#include <apriltag/tag36h11.h>

#include <algorithm>
#include <list>
#include <memory>
#include <stdexcept>

namespace ehc_perception {

namespace {

[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument("[TagImageRenderer] " + what);
}

/// RAII holder of a libapriltag family.
struct Family {
  explicit Family(const std::string& name) {
    if (name == "36h11") {
      fam = tag36h11_create();
      destroy = tag36h11_destroy;
    } else if (name == "25h9") {
      fam = tag25h9_create();
      destroy = tag25h9_destroy;
    } else if (name == "16h5") {
      fam = tag16h5_create();
      destroy = tag16h5_destroy;
    } else {
      fail("unknown tag family '" + name + "' (expected 36h11, 25h9 or 16h5)");
    }
  }
  ~Family() {
    if (fam) destroy(fam);
  }
  Family(const Family&) = delete;
  Family& operator=(const Family&) = delete;
  apriltag_family_t* fam = nullptr;
  void (*destroy)(apriltag_family_t*) = nullptr;
};

vpHomogeneousMatrix toVisp(const Eigen::Isometry3d& T) {
  vpHomogeneousMatrix M;
  for (unsigned r = 0; r < 3; ++r) {
    for (unsigned c = 0; c < 3; ++c) M[r][c] = T.linear()(r, c);
    M[r][3] = T.translation()(r);
  }
  return M;
}

}  // namespace

TagImageRenderer::TagImageRenderer(const ehc_control::PinholeCamera& camera, const std::string& family,
                                   int pixels_per_cell)
    : camera_(camera), family_(family), pixels_per_cell_(pixels_per_cell) {
  camera_.validate();
  if (pixels_per_cell < 1 || pixels_per_cell > 64) fail("pixels_per_cell must be in [1, 64]");
  Family f(family_);
  total_cells_ = f.fam->total_width;
  border_cells_ = f.fam->width_at_border;
  family_size_ = static_cast<int>(f.fam->ncodes);
}

vpImage<unsigned char> TagImageRenderer::bitmap(int id) const {
  if (id < 0 || id >= family_size_)
    fail("tag id " + std::to_string(id) + " is outside the family " + family_ + " (0.." +
         std::to_string(family_size_ - 1) + ")");
  Family f(family_);
  image_u8_t* im = apriltag_to_image(f.fam, id);
  if (!im) fail("apriltag_to_image failed for id " + std::to_string(id));
  const unsigned s = static_cast<unsigned>(pixels_per_cell_);
  vpImage<unsigned char> out(static_cast<unsigned>(im->height) * s,
                             static_cast<unsigned>(im->width) * s);
  for (unsigned r = 0; r < out.getHeight(); ++r)
    for (unsigned c = 0; c < out.getWidth(); ++c)
      out[r][c] = im->buf[(r / s) * static_cast<unsigned>(im->stride) + c / s];
  image_u8_destroy(im);
  return out;
}

vpImage<unsigned char> TagImageRenderer::render(const std::vector<TagPlacement>& tags,
                                                unsigned char background) const {
  vpImage<unsigned char> I(static_cast<unsigned>(camera_.height),
                           static_cast<unsigned>(camera_.width), background);
  vpCameraParameters cam;
  cam.initPersProjWithoutDistortion(camera_.fx, camera_.fy, camera_.cx, camera_.cy);

  std::vector<TagPlacement> order;
  for (const TagPlacement& t : tags) {
    if (!t.T_cam_tag.matrix().allFinite() || !(t.tag_size > 0.0))
      fail("tag placement of id " + std::to_string(t.id) + " is not finite / has size <= 0");
    if (t.T_cam_tag.translation().z() > 1e-3) order.push_back(t);
  }
  std::sort(order.begin(), order.end(), [](const TagPlacement& a, const TagPlacement& b) {
    return a.T_cam_tag.translation().z() > b.T_cam_tag.translation().z();
  });
  for (const TagPlacement& t : order) {
    // Corners of the whole bitmap (quiet zone included) in the tag frame (x right, y up):
    // top-left, top-right, bottom-right, bottom-left.
    // vpImageSimulator maps the first / last texture pixel centres onto the corners: place
    // the corners half a texture pixel inside the bitmap's outer edge.
    const double W = static_cast<double>(total_cells_ * pixels_per_cell_);
    const double h = 0.5 * t.tag_size * total_cells_ / border_cells_ * (W - 1.0) / W;
    vpColVector X[4];
    const double xy[4][2] = {{-h, h}, {h, h}, {h, -h}, {-h, -h}};
    for (int k = 0; k < 4; ++k) {
      X[k].resize(3);
      X[k][0] = xy[k][0];
      X[k][1] = xy[k][1];
      X[k][2] = 0.0;
    }
    vpImageSimulator sim(vpImageSimulator::GRAY_SCALED);
    sim.setInterpolationType(vpImageSimulator::BILINEAR_INTERPOLATION);
    sim.init(bitmap(t.id), X);
    sim.setCameraPosition(toVisp(t.T_cam_tag));
    sim.getImage(I, cam);
  }
  return I;
}

}  // namespace ehc_perception
