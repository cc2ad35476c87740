// PointCloudLayout: every malformed PointCloud2 layout is rejected with a reason before a byte
// is read; FLOAT32 / FLOAT64 x, y, z in any field order are extracted, NaN points dropped.
#include "ehc_perception/point_cloud_layout.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

using namespace ehc_perception;

namespace {

struct FieldSpec {
  std::string name;
  PointFieldType type;
};

/// A cloud's layout and bytes, as a PointCloud2 would carry them.
struct TestCloud {
  PointCloudLayout layout;
  std::vector<std::uint8_t> data;

  std::string problem() const { return layout.problem(data.size()); }
  CloudPoints extract() const { return extractCloudPoints(layout, data.data(), data.size()); }
};

template <class T>
void putAs(std::uint8_t* at, double v) {
  const T x = static_cast<T>(v);
  std::memcpy(at, &x, sizeof x);
}

void put(std::uint8_t* at, PointFieldType t, double v) {
  switch (t) {
    case PointFieldType::Int8: return putAs<std::int8_t>(at, v);
    case PointFieldType::Uint8: return putAs<std::uint8_t>(at, v);
    case PointFieldType::Int16: return putAs<std::int16_t>(at, v);
    case PointFieldType::Uint16: return putAs<std::uint16_t>(at, v);
    case PointFieldType::Int32: return putAs<std::int32_t>(at, v);
    case PointFieldType::Uint32: return putAs<std::uint32_t>(at, v);
    case PointFieldType::Float32: return putAs<float>(at, v);
    case PointFieldType::Float64: return putAs<double>(at, v);
  }
}

/// Points packed row-major in `height` rows, the fields in the given order (x, y, z from the
/// point, any other field 7), then `padding` bytes per point and `row_padding` bytes per row.
TestCloud makeCloud(const std::vector<Eigen::Vector3d>& pts, const std::vector<FieldSpec>& fields,
                    std::uint32_t height = 1, std::uint32_t padding = 0,
                    std::uint32_t row_padding = 0) {
  TestCloud c;
  std::uint32_t offset = 0;
  for (const FieldSpec& f : fields) {
    c.layout.fields.push_back({f.name, offset, static_cast<std::uint8_t>(f.type), 1});
    offset += static_cast<std::uint32_t>(pointFieldTypeSize(static_cast<std::uint8_t>(f.type)));
  }
  c.layout.height = height;
  c.layout.width = static_cast<std::uint32_t>(pts.size()) / height;
  c.layout.point_step = offset + padding;
  c.layout.row_step = c.layout.width * c.layout.point_step + row_padding;
  c.data.assign(std::size_t{c.layout.row_step} * height, 0xAB);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    std::uint8_t* point = c.data.data() + (i / c.layout.width) * c.layout.row_step +
                          (i % c.layout.width) * c.layout.point_step;
    for (std::size_t k = 0; k < fields.size(); ++k) {
      const std::string& n = fields[k].name;
      const double v = n == "x" ? pts[i].x() : n == "y" ? pts[i].y() : n == "z" ? pts[i].z() : 7.0;
      put(point + c.layout.fields[k].offset, fields[k].type, v);
    }
  }
  return c;
}

const std::vector<FieldSpec> kXyz32 = {
    {"x", PointFieldType::Float32}, {"y", PointFieldType::Float32}, {"z", PointFieldType::Float32}};

std::vector<Eigen::Vector3d> somePoints(int n) {
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < n; ++i) pts.emplace_back(0.1 * i - 0.3, 0.25 - 0.07 * i, 0.5 + 0.013 * i);
  return pts;
}

/// The cloud is rejected: problem() names `reason` and extraction throws it, prefixed.
void expectRejected(const TestCloud& c, const std::string& reason) {
  const std::string p = c.problem();
  EXPECT_NE(p.find(reason), std::string::npos) << "problem '" << p << "' lacks '" << reason << "'";
  try {
    c.extract();
    ADD_FAILURE() << "extracted a cloud with problem '" << p << "'";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "[PointCloudLayout] " + p);
  }
}

void expectPoints(const CloudPoints& got, const std::vector<Eigen::Vector3d>& want) {
  ASSERT_EQ(got.points.size(), want.size());
  for (std::size_t i = 0; i < want.size(); ++i)
    EXPECT_EQ(got.points[i], want[i].cast<float>()) << "point " << i;
}

}  // namespace

TEST(PointCloudLayout, Float32CloudWithPaddingIsReadExactly) {
  // The layout of PointCloud2Modifier::setPointCloud2FieldsByString(1, "xyz"): 16-byte points.
  const auto pts = somePoints(7);
  const TestCloud c = makeCloud(pts, kXyz32, 1, 4);
  EXPECT_EQ(c.layout.point_step, 16u);
  EXPECT_EQ(c.problem(), "");
  const CloudPoints got = c.extract();
  expectPoints(got, pts);
  EXPECT_EQ(got.non_finite, 0u);
}

TEST(PointCloudLayout, EmptyCloudIsValidAndYieldsNoPoints) {
  const TestCloud none;  // a default message: no fields, no data
  EXPECT_EQ(none.problem(), "");
  EXPECT_TRUE(none.extract().points.empty());
  TestCloud no_rows = makeCloud(somePoints(3), kXyz32);
  no_rows.layout.height = 0;
  no_rows.data.clear();
  EXPECT_EQ(no_rows.problem(), "");
  EXPECT_TRUE(no_rows.extract().points.empty());
}

TEST(PointCloudLayout, PointStepZeroWithPointsIsRejected) {
  TestCloud c = makeCloud({}, kXyz32);
  c.layout.width = 1000000;
  c.layout.height = 1;
  c.layout.point_step = 0;
  c.layout.row_step = 0;
  c.data.clear();
  expectRejected(c, "1000000x1 points with point_step 0");
}

TEST(PointCloudLayout, FieldOffsetBeyondPointStepIsRejected) {
  TestCloud c = makeCloud(somePoints(4), kXyz32);
  c.layout.fields[2].offset = 10;  // z's 4 bytes would end at 14 > point_step 12
  expectRejected(c, "field 'z' (offset 10, 1 x FLOAT32) does not fit in point_step 12");
  c.layout.fields[2].offset = 4000000000u;  // no uint32 wrap-around
  expectRejected(c, "field 'z' (offset 4000000000");
  TestCloud rgb = makeCloud(somePoints(4), {{"x", PointFieldType::Float32},
                                            {"y", PointFieldType::Float32},
                                            {"z", PointFieldType::Float32},
                                            {"rgb", PointFieldType::Float32}});
  rgb.layout.fields[3].count = 2;  // every field is checked, even one that is not read
  expectRejected(rgb, "field 'rgb' (offset 12, 2 x FLOAT32) does not fit in point_step 16");
}

TEST(PointCloudLayout, DataShorterThanClaimedIsRejected) {
  TestCloud c = makeCloud(somePoints(5), kXyz32);
  c.data.pop_back();
  expectRejected(c, "59 data bytes for 5x1 points of row_step 60 (60 needed)");
  TestCloud wide = makeCloud(somePoints(5), kXyz32);
  wide.layout.width = 6;
  wide.layout.row_step = 72;
  expectRejected(wide, "60 data bytes for 6x1 points of row_step 72 (72 needed)");
}

TEST(PointCloudLayout, RowStepSmallerThanARowIsRejected) {
  TestCloud c = makeCloud(somePoints(6), kXyz32, 2);
  c.layout.row_step = 3 * 12 - 1;
  expectRejected(c, "row_step 35 < width 3 x point_step 12");
}

TEST(PointCloudLayout, SizeProductsDoNotOverflow) {
  // width x height > 2^32 points with one point of data.
  TestCloud tall = makeCloud(somePoints(1), kXyz32);
  tall.layout.width = 65536;
  tall.layout.height = 65537;
  tall.layout.row_step = 65536 * 12;
  expectRejected(tall, "12 data bytes for 65536x65537 points");
  // width x point_step = 2^32 wraps to 0 in 32 bits: a row_step of 16 would pass.
  TestCloud wrap = makeCloud(somePoints(1), kXyz32);
  wrap.layout.width = 65536;
  wrap.layout.point_step = 65536;
  wrap.layout.row_step = 16;
  expectRejected(wrap, "row_step 16 < width 65536 x point_step 65536");
  // The largest numbers: row_step x height ~ 2^64 bytes.
  TestCloud max = makeCloud(somePoints(1), kXyz32);
  max.layout.width = 1;
  max.layout.height = std::numeric_limits<std::uint32_t>::max();
  max.layout.point_step = std::numeric_limits<std::uint32_t>::max();
  max.layout.row_step = std::numeric_limits<std::uint32_t>::max();
  expectRejected(max, "12 data bytes for 1x4294967295 points of row_step 4294967295");
}

TEST(PointCloudLayout, MissingOrDuplicateAxesAreRejected) {
  expectRejected(makeCloud(somePoints(3), {{"x", PointFieldType::Float32},
                                           {"y", PointFieldType::Float32}}),
                 "no field 'z'");
  expectRejected(makeCloud(somePoints(3), {{"x", PointFieldType::Float32},
                                           {"y", PointFieldType::Float32},
                                           {"z", PointFieldType::Float32},
                                           {"y", PointFieldType::Float32}}),
                 "field 'y' appears 2 times");
}

TEST(PointCloudLayout, IntegerCoordinatesAreRejected) {
  const auto pts = somePoints(3);
  expectRejected(makeCloud(pts, {{"x", PointFieldType::Uint8},
                                 {"y", PointFieldType::Uint8},
                                 {"z", PointFieldType::Uint8}}),
                 "x is UINT8: expected FLOAT32 or FLOAT64");
  expectRejected(makeCloud(pts, {{"x", PointFieldType::Int16},
                                 {"y", PointFieldType::Int16},
                                 {"z", PointFieldType::Int16}}),
                 "x is INT16: expected FLOAT32 or FLOAT64");
  expectRejected(makeCloud(pts, {{"x", PointFieldType::Float32},
                                 {"y", PointFieldType::Float32},
                                 {"z", PointFieldType::Uint32}}),
                 "z is UINT32: expected FLOAT32 or FLOAT64");
}

TEST(PointCloudLayout, UnknownDatatypeZeroCountAndBigEndianAreRejected) {
  TestCloud unknown = makeCloud(somePoints(2), kXyz32);
  unknown.layout.fields[1].datatype = 9;
  expectRejected(unknown, "field 'y' has unknown datatype 9");
  TestCloud zero = makeCloud(somePoints(2), kXyz32);
  zero.layout.fields[0].count = 0;
  expectRejected(zero, "field 'x' has count 0");
  TestCloud big = makeCloud(somePoints(2), kXyz32);
  big.layout.is_bigendian = true;
  expectRejected(big, "big-endian data on a little-endian host");
}

TEST(PointCloudLayout, Float64CoordinatesAreConvertedExactly) {
  std::vector<Eigen::Vector3d> pts = somePoints(5);
  pts.emplace_back(1e-30, -123456.789, 3.0);
  const TestCloud c = makeCloud(pts, {{"x", PointFieldType::Float64},
                                      {"y", PointFieldType::Float64},
                                      {"z", PointFieldType::Float64}});
  EXPECT_EQ(c.layout.point_step, 24u);
  expectPoints(c.extract(), pts);  // each coordinate == static_cast<float>(the double)
  // A double beyond float's range is not a finite float: dropped.
  const TestCloud huge = makeCloud({Eigen::Vector3d(1e300, 0, 1), Eigen::Vector3d(0, 0, 1)},
                                   {{"x", PointFieldType::Float64},
                                    {"y", PointFieldType::Float64},
                                    {"z", PointFieldType::Float64}});
  const CloudPoints got = huge.extract();
  expectPoints(got, {Eigen::Vector3d(0, 0, 1)});
  EXPECT_EQ(got.non_finite, 1u);
}

TEST(PointCloudLayout, FieldsInAnyOrderAndExtraFieldsAreIgnored) {
  const auto pts = somePoints(6);
  // z before x, mixed FLOAT32 / FLOAT64, rgb and intensity fields between them.
  const TestCloud c = makeCloud(pts, {{"z", PointFieldType::Float32},
                                      {"rgb", PointFieldType::Uint32},
                                      {"x", PointFieldType::Float64},
                                      {"intensity", PointFieldType::Uint8},
                                      {"y", PointFieldType::Float32}},
                                3, 3);
  EXPECT_EQ(c.problem(), "");
  expectPoints(c.extract(), pts);
}

TEST(PointCloudLayout, OrganisedCloudIsReadRowByRowAndNonFinitePointsDropped) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<Eigen::Vector3d> pts = somePoints(12);  // 3 rows of 4
  pts[1].x() = nan;
  pts[6].z() = inf;
  pts[11] = Eigen::Vector3d::Constant(nan);
  // Row padding: each row is 8 bytes longer than its points (read by row_step, not by index).
  const TestCloud c = makeCloud(pts, kXyz32, 3, 4, 8);
  EXPECT_EQ(c.layout.row_step, 4u * 16u + 8u);
  const CloudPoints got = c.extract();
  EXPECT_EQ(got.non_finite, 3u);
  expectPoints(got, {pts[0], pts[2], pts[3], pts[4], pts[5], pts[7], pts[8], pts[9], pts[10]});
}

TEST(PointCloudLayout, DatatypeNamesAndSizes) {
  EXPECT_EQ(pointFieldTypeName(static_cast<std::uint8_t>(PointFieldType::Int8)), "INT8");
  EXPECT_EQ(pointFieldTypeName(static_cast<std::uint8_t>(PointFieldType::Float64)), "FLOAT64");
  EXPECT_EQ(pointFieldTypeName(0), "unknown datatype 0");
  EXPECT_EQ(pointFieldTypeSize(static_cast<std::uint8_t>(PointFieldType::Uint16)), 2u);
  EXPECT_EQ(pointFieldTypeSize(static_cast<std::uint8_t>(PointFieldType::Float64)), 8u);
  EXPECT_EQ(pointFieldTypeSize(42), 0u);
}
