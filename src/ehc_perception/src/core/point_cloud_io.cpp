// PCD reading / writing (PCL translation unit 2 of 2).
#include "ehc_perception/grasp_generator.h"

#include <pcl/io/pcd_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace ehc_perception {

namespace {
/// Reads the PCD header far enough to reject files PCL's reader would crash on (it does not
/// validate a header without FIELDS / DATA lines) and point counts the file cannot hold (PCL
/// allocates POINTS x point size before reading: a header claiming 10^9 points must be refused
/// before that allocation). Returns the POINTS count.
long checkHeader(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f.good()) throw std::invalid_argument("[PointCloudIO] cannot read '" + path + "': no such file");
  auto fail = [&](const std::string& what) -> void {
    throw std::invalid_argument("[PointCloudIO] cannot read '" + path + "': " + what);
  };
  std::string line, data;
  bool fields = false;
  long points = -1;
  std::vector<long> sizes, counts;
  for (int n = 0; n < 20 && std::getline(f, line); ++n) {
    std::istringstream ls(line);
    std::string key;
    ls >> key;
    if (key.empty() || key[0] == '#') continue;
    if (key == "FIELDS") fields = true;
    if (key == "POINTS") ls >> points;
    for (long v; key == "SIZE" && ls >> v;) sizes.push_back(v);
    for (long v; key == "COUNT" && ls >> v;) counts.push_back(v);
    if (key == "DATA") {
      ls >> data;
      break;
    }
  }
  if (!fields || data.empty() || points < 0)
    fail("not a PCD file (header needs FIELDS, POINTS and DATA)");
  const std::streamoff data_start = f.tellg();
  f.seekg(0, std::ios::end);
  const double data_bytes = static_cast<double>(f.tellg() - data_start);
  long point_bytes = 0;
  for (std::size_t k = 0; k < sizes.size(); ++k)
    point_bytes += std::max(1L, sizes[k]) * (k < counts.size() ? std::max(1L, counts[k]) : 1L);
  point_bytes = std::max(1L, point_bytes);
  // Bytes the data section needs at least: binary = the raw points; ascii >= 2 characters
  // ("0 " / "0\n") per value but the file's last; binary_compressed: LZF expands at most ~100x.
  const double needed = data == "binary"  ? static_cast<double>(points) * point_bytes
                        : data == "ascii" ? 2.0 * static_cast<double>(points) *
                                                    std::max<std::size_t>(1, sizes.size()) - 1.0
                                          : static_cast<double>(points) * point_bytes / 100.0;
  if (needed > data_bytes)
    fail("header claims " + std::to_string(points) + " points but the file holds only " +
         std::to_string(static_cast<long>(data_bytes)) + " bytes of " + data + " data");
  return points;
}
}  // namespace

PointList loadPcd(const std::string& path) {
  if (checkHeader(path) == 0) return {};
  pcl::PCLPointCloud2 blob;
  pcl::PCDReader reader;
  if (reader.read(path, blob) < 0)
    throw std::invalid_argument("[PointCloudIO] cannot read '" + path + "': not a valid PCD file");
  bool has_x = false, has_y = false, has_z = false;
  for (const auto& f : blob.fields) {
    has_x |= f.name == "x";
    has_y |= f.name == "y";
    has_z |= f.name == "z";
  }
  if (!has_x || !has_y || !has_z)
    throw std::invalid_argument("[PointCloudIO] cannot read '" + path + "': no x, y, z fields");
  pcl::PointCloud<pcl::PointXYZ> cloud;
  pcl::fromPCLPointCloud2(blob, cloud);
  PointList out;
  out.reserve(cloud.size());
  for (const auto& p : cloud) out.push_back(p.getVector3fMap());
  return out;
}

void savePcd(const std::string& path, const PointList& points) {
  pcl::PointCloud<pcl::PointXYZ> cloud;
  cloud.reserve(points.size());
  for (const auto& p : points) cloud.push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
  cloud.width = static_cast<std::uint32_t>(cloud.size());
  cloud.height = 1;
  cloud.is_dense = false;
  if (cloud.empty()) {
    // PCL refuses to write an empty binary cloud; an ASCII header with 0 points is valid.
    std::ofstream f(path);
    f << "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
         "WIDTH 0\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 0\nDATA ascii\n";
    if (!f) throw std::runtime_error("[PointCloudIO] cannot write '" + path + "'");
    return;
  }
  if (pcl::io::savePCDFileBinary(path, cloud) < 0)
    throw std::runtime_error("[PointCloudIO] cannot write '" + path + "'");
}

}  // namespace ehc_perception
