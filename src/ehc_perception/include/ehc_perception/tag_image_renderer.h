#pragma once
// TagImageRenderer: synthetic grey images of AprilTags seen by a pinhole camera (ViSP
// vpImageSimulator, bilinear). Tag bitmaps come from libapriltag's family codes
// (apriltag_to_image). Used by tests and benchmarks, and by the simulator's camera.
// Tag frame = TagDetector's (centre, x right, y up, z out of the printed face).

#include "ehc_control/pinhole_camera.h"

#include <Eigen/Geometry>
#include <visp3/core/vpImage.h>

#include <string>
#include <vector>

namespace ehc_perception {

struct TagPlacement {
  int id = 0;
  double tag_size = 0.05;  ///< m, edge of the black square
  Eigen::Isometry3d T_cam_tag = Eigen::Isometry3d::Identity();
};

class TagImageRenderer {
 public:
  /// family: 36h11 | 25h9 | 16h5. Throws std::invalid_argument "[TagImageRenderer] ...".
  TagImageRenderer(const ehc_control::PinholeCamera& camera, const std::string& family = "36h11",
                   int pixels_per_cell = 12);

  /// Renders the tags (farthest first) over a uniform background of the camera's size.
  /// Tags behind the camera are skipped.
  vpImage<unsigned char> render(const std::vector<TagPlacement>& tags,
                                unsigned char background = 160) const;

  /// The tag bitmap (white quiet zone included), `pixels_per_cell` px per bit cell.
  vpImage<unsigned char> bitmap(int id) const;
  /// Bit cells across the whole bitmap / across the black square (10 / 8 for 36h11).
  int totalCells() const { return total_cells_; }
  int borderCells() const { return border_cells_; }

 private:
  ehc_control::PinholeCamera camera_;
  std::string family_;
  int pixels_per_cell_;
  int total_cells_ = 0;
  int border_cells_ = 0;
  int family_size_ = 0;
};

}  // namespace ehc_perception
