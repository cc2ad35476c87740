// PCD reading / writing (PCL translation unit 2 of 2).
#include "ehc_perception/grasp_generator.h"

#include <pcl/io/pcd_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace ehc_perception {

namespace {
/// Reads the PCD header far enough to reject files PCL's reader would crash on (it does not
/// validate a header without FIELDS / DATA lines). Returns the POINTS count.
long checkHeader(const std::string& path) {
  std::ifstream f(path);
  if (!f.good()) throw std::invalid_argument("[PointCloudIO] cannot read '" + path + "': no such file");
  std::string line;
  bool fields = false, data = false;
  long points = -1;
  for (int n = 0; n < 20 && std::getline(f, line); ++n) {
    std::istringstream ls(line);
    std::string key;
    ls >> key;
    if (key.empty() || key[0] == '#') continue;
    if (key == "FIELDS") fields = true;
    if (key == "POINTS") ls >> points;
    if (key == "DATA") {
      data = true;
      break;
    }
  }
  if (!fields || !data || points < 0)
    throw std::invalid_argument("[PointCloudIO] cannot read '" + path +
                                "': not a PCD file (header needs FIELDS, POINTS and DATA)");
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
