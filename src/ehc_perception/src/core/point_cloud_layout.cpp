#include "ehc_perception/point_cloud_layout.h"

#include <algorithm>
#include <array>
#include <cstring>
#include <stdexcept>

namespace ehc_perception {

namespace {

struct TypeInfo {
  PointFieldType type;
  const char* name;
  std::size_t size;
};

constexpr std::array<TypeInfo, 8> kTypes = {{
    {PointFieldType::Int8, "INT8", 1},
    {PointFieldType::Uint8, "UINT8", 1},
    {PointFieldType::Int16, "INT16", 2},
    {PointFieldType::Uint16, "UINT16", 2},
    {PointFieldType::Int32, "INT32", 4},
    {PointFieldType::Uint32, "UINT32", 4},
    {PointFieldType::Float32, "FLOAT32", 4},
    {PointFieldType::Float64, "FLOAT64", 8},
}};

const TypeInfo* typeInfo(std::uint8_t datatype) {
  for (const TypeInfo& t : kTypes)
    if (static_cast<std::uint8_t>(t.type) == datatype) return &t;
  return nullptr;
}

bool hostIsBigEndian() {
  const std::uint16_t one = 1;
  unsigned char first = 0;
  std::memcpy(&first, &one, 1);
  return first == 0;
}

const char* const kAxes[3] = {"x", "y", "z"};

/// The x, y, z fields (nullptr where missing; the first of duplicates).
std::array<const PointFieldLayout*, 3> axisFields(const PointCloudLayout& l) {
  std::array<const PointFieldLayout*, 3> axes = {nullptr, nullptr, nullptr};
  for (const PointFieldLayout& f : l.fields)
    for (int a = 0; a < 3; ++a)
      if (f.name == kAxes[a] && !axes[a]) axes[a] = &f;
  return axes;
}

/// Reads one FLOAT32 or FLOAT64 element (the layout is validated) as float.
float readCoordinate(const std::uint8_t* p, std::uint8_t datatype) {
  if (datatype == static_cast<std::uint8_t>(PointFieldType::Float64)) {
    double d;
    std::memcpy(&d, p, sizeof d);
    return static_cast<float>(d);
  }
  float f;
  std::memcpy(&f, p, sizeof f);
  return f;
}

}  // namespace

std::string pointFieldTypeName(std::uint8_t datatype) {
  const TypeInfo* t = typeInfo(datatype);
  return t ? std::string(t->name) : "unknown datatype " + std::to_string(datatype);
}

std::size_t pointFieldTypeSize(std::uint8_t datatype) {
  const TypeInfo* t = typeInfo(datatype);
  return t ? t->size : 0;
}

std::string PointCloudLayout::problem(std::size_t data_size) const {
  // uint32 x uint32 fits in 64 bits: none of these products can overflow.
  const std::uint64_t points = std::uint64_t{width} * height;
  if (points == 0) return "";
  const std::string shape = std::to_string(width) + "x" + std::to_string(height);
  if (point_step == 0) return shape + " points with point_step 0";
  const std::uint64_t row_bytes = std::uint64_t{width} * point_step;
  if (row_step < row_bytes)
    return "row_step " + std::to_string(row_step) + " < width " + std::to_string(width) +
           " x point_step " + std::to_string(point_step);
  const std::uint64_t bytes = std::uint64_t{row_step} * height;
  if (data_size < bytes)
    return std::to_string(data_size) + " data bytes for " + shape + " points of row_step " +
           std::to_string(row_step) + " (" + std::to_string(bytes) + " needed)";
  if (is_bigendian != hostIsBigEndian())
    return std::string(is_bigendian ? "big" : "little") + "-endian data on a " +
           (is_bigendian ? "little" : "big") + "-endian host (byte swapping is not supported)";
  for (const PointFieldLayout& f : fields) {
    const std::size_t size = pointFieldTypeSize(f.datatype);
    if (size == 0) return "field '" + f.name + "' has " + pointFieldTypeName(f.datatype);
    if (f.count == 0) return "field '" + f.name + "' has count 0";
    if (std::uint64_t{f.offset} + std::uint64_t{size} * f.count > point_step)
      return "field '" + f.name + "' (offset " + std::to_string(f.offset) + ", " +
             std::to_string(f.count) + " x " + pointFieldTypeName(f.datatype) +
             ") does not fit in point_step " + std::to_string(point_step);
  }
  const auto axes = axisFields(*this);
  for (int a = 0; a < 3; ++a) {
    if (!axes[a]) return std::string("no field '") + kAxes[a] + "'";
    int copies = 0;
    for (const PointFieldLayout& f : fields) copies += f.name == kAxes[a];
    if (copies > 1) return std::string("field '") + kAxes[a] + "' appears " + std::to_string(copies) + " times";
    const auto type = static_cast<PointFieldType>(axes[a]->datatype);
    if (type != PointFieldType::Float32 && type != PointFieldType::Float64)
      return std::string(kAxes[a]) + " is " + pointFieldTypeName(axes[a]->datatype) +
             ": expected FLOAT32 or FLOAT64";
  }
  return "";
}

PointBudget::PointBudget(std::uint64_t width, std::uint64_t height, std::uint64_t max_points)
    : width_(width), height_(height), selected_(width * height) {
  if (max_points == 0 || selected_ <= max_points) return;
  if (height_ <= 1) {
    selected_ = max_points;
    return;
  }
  // The smallest step whose grid fits: the grid's size does not grow with the step, and the
  // largest step (one point) always fits.
  auto grid = [&](std::uint64_t k) { return ((width_ + k - 1) / k) * ((height_ + k - 1) / k); };
  std::uint64_t lo = 1, hi = std::max(width_, height_);
  while (lo < hi) {
    const std::uint64_t mid = lo + (hi - lo) / 2;
    if (grid(mid) <= max_points) hi = mid;
    else lo = mid + 1;
  }
  step_ = lo;
  selected_ = grid(lo);
}

PointList budgetPoints(const PointList& points, std::size_t max_points) {
  const PointBudget budget(points.size(), 1, max_points);
  if (!budget.subsampled()) return points;
  PointList out;
  out.reserve(budget.selected());
  budget.forEach([&](std::uint64_t, std::uint64_t i) { out.push_back(points[i]); });
  return out;
}

PointList transformPoints(const PointList& points, const Eigen::Isometry3d& T) {
  const Eigen::Isometry3f Tf = T.cast<float>();
  PointList out;
  out.reserve(points.size());
  for (const auto& p : points) out.push_back(Tf * p);
  return out;
}

CloudPoints extractCloudPoints(const PointCloudLayout& layout, const std::uint8_t* data,
                               std::size_t data_size, std::size_t max_points) {
  const std::string problem = layout.problem(data_size);
  if (!problem.empty()) throw std::invalid_argument("[PointCloudLayout] " + problem);
  CloudPoints out;
  const PointBudget budget(layout.width, layout.height, max_points);
  out.total = budget.total();
  if (out.total == 0) return out;
  const auto axes = axisFields(layout);
  // Validated: width x height x point_step <= data_size, so the reservation is bounded.
  out.points.reserve(budget.selected());
  budget.forEach([&](std::uint64_t r, std::uint64_t c) {
    const std::uint8_t* point = data + r * layout.row_step + c * layout.point_step;
    Eigen::Vector3f p;
    for (int a = 0; a < 3; ++a) p[a] = readCoordinate(point + axes[a]->offset, axes[a]->datatype);
    ++out.read;
    if (p.allFinite())
      out.points.push_back(p);
    else
      ++out.non_finite;
  });
  return out;
}

}  // namespace ehc_perception
