#pragma once
// PointCloudLayout: the byte layout of a sensor_msgs/PointCloud2 without ROS types (the nodes
// copy the message's numbers and fields into it), its validation against the data size, and
// the extraction of the x, y, z points.
//
// Every number of the layout is checked before a byte is read (64-bit arithmetic, no
// overflow for any uint32 input):
//   - width x height = 0: a valid empty cloud, nothing else is checked or read;
//   - point_step > 0, row_step >= width x point_step, data size >= row_step x height;
//   - the host's byte order (is_bigendian must match; byte swapping is not supported);
//   - every field: a known datatype, count >= 1, offset + size x count <= point_step;
//   - x, y and z present once each, FLOAT32 or FLOAT64 (FLOAT64 is converted to float);
//     an integer x / y / z (INT8 .. UINT32: a depth image's raw units, not metres) is
//     rejected. Other fields (rgb, intensity, ...) are checked but not read.
// Points with a non-finite coordinate (an organised cloud's "no return") are dropped and
// counted; the others keep their row-major order.
//
// Point budget (PointBudget): a node reads at most max_points of a cloud, chosen from the
// layout's width and height alone, before any per-point work (no conversion, transform or voxel
// grid of the points it skips): the work per message does not grow with the cloud.

#include "ehc_perception/grasp_generator.h"  // PointList

#include <Eigen/Geometry>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace ehc_perception {

/// sensor_msgs/PointField datatype codes.
enum class PointFieldType : std::uint8_t {
  Int8 = 1,
  Uint8 = 2,
  Int16 = 3,
  Uint16 = 4,
  Int32 = 5,
  Uint32 = 6,
  Float32 = 7,
  Float64 = 8,
};

/// "INT8" .. "FLOAT64" for a known code, "unknown datatype <code>" otherwise.
std::string pointFieldTypeName(std::uint8_t datatype);
/// Bytes of one element (1, 2, 4 or 8); 0 for an unknown code.
std::size_t pointFieldTypeSize(std::uint8_t datatype);

/// sensor_msgs/PointField.
struct PointFieldLayout {
  std::string name;
  std::uint32_t offset = 0;  ///< bytes from the start of the point
  std::uint8_t datatype = 0;  ///< PointFieldType code (kept raw: the message may hold any value)
  std::uint32_t count = 1;   ///< elements
};

/// The layout numbers of a sensor_msgs/PointCloud2 (everything but header and data).
struct PointCloudLayout {
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  std::vector<PointFieldLayout> fields;
  bool is_bigendian = false;
  std::uint32_t point_step = 0;  ///< bytes per point
  std::uint32_t row_step = 0;    ///< bytes per row

  /// "" if `data_size` bytes hold this layout's points and x, y, z can be read as above;
  /// otherwise the first problem found, e.g. "x is UINT8: expected FLOAT32 or FLOAT64".
  std::string problem(std::size_t data_size) const;
};

/// Which points of a width x height cloud are read when at most `max_points` may be (0: every
/// point). An organised cloud (height > 1) is read on an even grid: every step-th row and
/// column from the first, with the smallest step whose grid fits the budget. That is the
/// sampling of a lower-resolution image of the same camera, even across the view (a stride
/// through the row-major order would keep whole rows and skip columns). An unorganised cloud
/// (height 1) is read at an even stride: point floor(i x total / max_points), in order.
class PointBudget {
 public:
  PointBudget(std::uint64_t width, std::uint64_t height, std::uint64_t max_points);
  std::uint64_t total() const { return width_ * height_; }
  /// Points read: total() within the budget, else at most max_points.
  std::uint64_t selected() const { return selected_; }
  bool subsampled() const { return selected_ < total(); }
  /// Organised: the row and column step (1: every point); unorganised: 1.
  std::uint64_t step() const { return step_; }
  /// Calls fn(row, column) for every point read, row-major.
  template <class Fn>
  void forEach(Fn&& fn) const {
    if (height_ > 1 || !subsampled()) {
      for (std::uint64_t r = 0; r < height_; r += step_)
        for (std::uint64_t c = 0; c < width_; c += step_) fn(r, c);
    } else {
      for (std::uint64_t i = 0; i < selected_; ++i) fn(std::uint64_t{0}, i * width_ / selected_);
    }
  }

 private:
  std::uint64_t width_, height_, selected_, step_ = 1;
};

/// At most `max_points` of `points` (0: all), as PointBudget reads an unorganised cloud.
PointList budgetPoints(const PointList& points, std::size_t max_points);

/// `points` moved by `T` (e.g. from the camera frame into the world), in float.
PointList transformPoints(const PointList& points, const Eigen::Isometry3d& T);

struct CloudPoints {
  PointList points;            ///< finite points, row-major
  std::size_t non_finite = 0;  ///< points read and dropped for a NaN / Inf coordinate
  std::size_t total = 0;       ///< points in the cloud (width x height)
  std::size_t read = 0;        ///< points read (PointBudget::selected; total without a budget)
};

/// The finite x, y, z points of a cloud (`data`: its `data_size` bytes), at most `max_points`
/// of them read (PointBudget; 0 = every point). Validates the layout first
/// (PointCloudLayout::problem); throws std::invalid_argument("[PointCloudLayout] ...") before
/// reading any byte if it is not valid.
CloudPoints extractCloudPoints(const PointCloudLayout& layout, const std::uint8_t* data,
                               std::size_t data_size, std::size_t max_points = 0);

}  // namespace ehc_perception
