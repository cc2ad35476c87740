// PointCloudLayout: every malformed PointCloud2 layout is rejected with a reason before a byte
// is read; FLOAT32 / FLOAT64 x, y, z in any field order are extracted, NaN points dropped.
// PointBudget: at most the budget is read of any cloud (randomized sizes and budgets, seed
// printed), on an even grid of an organised cloud, and a cloud within the budget is read whole.
#include "ehc_perception/point_cloud_layout.h"
#include "ehc_test/perception_fixtures.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <set>
#include <stdexcept>

using namespace ehc_perception;

namespace {

using test::FieldSpec;
using TestCloud = test::PackedCloud;

TestCloud makeCloud(const std::vector<Eigen::Vector3d>& pts, const std::vector<FieldSpec>& fields,
                    std::uint32_t height = 1, std::uint32_t padding = 0, std::uint32_t row_padding = 0) {
  return test::packCloud(pts, fields, height, padding, row_padding);
}

const std::vector<FieldSpec>& kXyz32 = test::xyzFloat32();

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

// ---------------------------------------------------------------- point budget

TEST(PointBudget, AtMostTheBudgetIsReadWhateverTheCloudsSize) {
  const unsigned seed = 20240611;
  std::printf("seed %u\n", seed);
  std::mt19937 rng(seed);
  std::uniform_int_distribution<std::uint64_t> side(1, 5000), budget(1, 200000);
  for (int k = 0; k < 2000; ++k) {
    const std::uint64_t w = side(rng), h = k % 4 == 0 ? 1 : side(rng) % 3000 + 1, b = budget(rng);
    const PointBudget pb(w, h, b);
    SCOPED_TRACE(std::to_string(w) + "x" + std::to_string(h) + " budget " + std::to_string(b));
    ASSERT_EQ(pb.total(), w * h);
    ASSERT_EQ(pb.subsampled(), w * h > b);
    if (h == 1) {
      ASSERT_EQ(pb.selected(), std::min(w, b)) << "unorganised: exactly the budget";
      continue;
    }
    ASSERT_LE(pb.selected(), std::min(w * h, b));
    // The smallest grid step that fits: one step less would not.
    const std::uint64_t k1 = pb.step() - 1;
    if (k1 >= 1) ASSERT_GT(((w + k1 - 1) / k1) * ((h + k1 - 1) / k1), b);
  }
  // An unorganised 2 M-point cloud, the visits counted: the budget, evenly spread, in order.
  const PointBudget flat(2000000, 1, 20000);
  std::uint64_t visits = 0, last = 0, max_gap = 0;
  flat.forEach([&](std::uint64_t r, std::uint64_t c) {
    EXPECT_EQ(r, 0u);
    if (visits++ > 0) max_gap = std::max(max_gap, c - last);
    last = c;
  });
  EXPECT_EQ(visits, 20000u);
  EXPECT_EQ(max_gap, 100u);
  // An organised 1920x1080 frame (2 073 600 points): every step-th row and column.
  const PointBudget grid(1920, 1080, 20000);
  EXPECT_EQ(grid.step(), 11u);  // 175 x 99 = 17 325 points; step 10: 192 x 108 = 20 736
  std::set<std::uint64_t> rows, cols;
  visits = 0;
  grid.forEach([&](std::uint64_t r, std::uint64_t c) {
    ++visits;
    rows.insert(r);
    cols.insert(c);
    EXPECT_EQ(r % 11, 0u);
    EXPECT_EQ(c % 11, 0u);
  });
  EXPECT_EQ(visits, grid.selected());
  EXPECT_EQ(rows.size(), 99u);
  EXPECT_EQ(cols.size(), 175u);
  EXPECT_EQ(*rows.rbegin(), 1078u) << "the grid spans the whole frame";
  EXPECT_EQ(*cols.rbegin(), 1914u);
  // No budget, or one the cloud is within: every point.
  EXPECT_EQ(PointBudget(640, 480, 0).selected(), 307200u);
  EXPECT_EQ(PointBudget(640, 480, 307200).step(), 1u);
  EXPECT_FALSE(PointBudget(0, 0, 10).subsampled());
}

TEST(PointBudget, A2MPointMessageIsReadWithinTheBudgetAndASmallOneWhole) {
  // A 1920x1080 depth frame (2 073 600 points, 25 MB): only the budget's points are read.
  const Eigen::Isometry3d cam = test::lookAt(Eigen::Vector3d(0, 0, 1.2), Eigen::Vector3d(1, 0, 0.6));
  const PointList frame = test::depthCameraCloud(1920, 1080, cam, {});
  const TestCloud big = test::packCloud(frame, kXyz32, 1080);
  const CloudPoints got = big.extract(20000);
  EXPECT_EQ(got.total, 2073600u);
  EXPECT_EQ(got.read, 17325u);
  EXPECT_EQ(got.points.size() + got.non_finite, got.read);
  // The points read are the frame's on the grid, in row-major order (NaN: no return, dropped).
  std::size_t i = 0;
  for (std::size_t r = 0; r < 1080; r += 11)
    for (std::size_t c = 0; c < 1920; c += 11) {
      const Eigen::Vector3f& p = frame[r * 1920 + c];
      if (!p.allFinite()) continue;
      ASSERT_LT(i, got.points.size());
      EXPECT_EQ(got.points[i++], p);
    }
  EXPECT_EQ(i, got.points.size());
  // Within the budget: the same points as without one.
  const auto pts = somePoints(50);
  const TestCloud small = makeCloud(pts, kXyz32, 5);
  const CloudPoints whole = small.extract(), budgeted = small.extract(50);
  EXPECT_EQ(budgeted.points, whole.points);
  EXPECT_EQ(budgeted.read, 50u);
  // A malformed layout is rejected before the budget matters.
  TestCloud bad = small;
  bad.layout.point_step = 0;
  EXPECT_THROW(bad.extract(10), std::invalid_argument);
  // budgetPoints: the unorganised stride of a point list.
  EXPECT_EQ(budgetPoints(frame, 1000).size(), 1000u);
  EXPECT_EQ(budgetPoints(frame, 1000)[1], frame[2073]);
  EXPECT_EQ(budgetPoints(frame, 0).size(), frame.size());
}
