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

#include "ehc_perception/grasp_generator.h"  // PointList

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

struct CloudPoints {
  PointList points;            ///< finite points, row-major
  std::size_t non_finite = 0;  ///< points dropped for a NaN / Inf coordinate
};

/// The finite x, y, z points of a cloud (`data`: its `data_size` bytes). Validates the layout
/// first (PointCloudLayout::problem); throws std::invalid_argument("[PointCloudLayout] ...")
/// before reading any byte if it is not valid.
CloudPoints extractCloudPoints(const PointCloudLayout& layout, const std::uint8_t* data,
                               std::size_t data_size);

}  // namespace ehc_perception
