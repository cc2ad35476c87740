#pragma once
// Triangle rasterisation for the simulated camera: the depth cloud (every scene body, once per
// cloud, on the depth grid) and the grey image of mesh bodies (on the image's pixels, depth-tested
// against the image's z-buffer) both draw triangles through rasterTriangle. The depth of a sample
// is where its pixel ray meets the triangle's plane (exact, not interpolated), so a surface is
// measured where it is. ROS-free, header-only.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>

namespace ehc_sim {

/// A pinhole sampling grid: sample (c, r) looks along ((c - cx) / fx, (r - cy) / fy, 1) in the
/// camera optical frame. The depth grid is the image's pinhole scaled to ray_cols x ray_rows.
struct RasterGrid {
  int width = 0, height = 0;
  double fx = 1.0, fy = 1.0, cx = 0.0, cy = 0.0;
  Eigen::Vector3d ray(int c, int r) const { return {(c - cx) / fx, (r - cy) / fy, 1.0}; }
};

/// Calls write(c, r, z) for every sample of `g` whose ray crosses the triangle (a, b, c) (camera
/// frame) at depth z > near; the part of the triangle nearer than `near` is clipped away.
/// A sample on an edge shared by two triangles may be written by both (same depth).
template <class Write>
void rasterTriangle(const RasterGrid& g, const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                    double near, Write&& write) {
  const Eigen::Vector3d n = (b - a).cross(c - a);
  const double k = n.dot(a);
  if (n.squaredNorm() < 1e-30) return;
  // Clip against z = near (Sutherland-Hodgman, one plane): at most 4 corners.
  std::array<Eigen::Vector3d, 4> poly;
  int np = 0;
  const std::array<const Eigen::Vector3d*, 3> in = {&a, &b, &c};
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d& p = *in[static_cast<std::size_t>(i)];
    const Eigen::Vector3d& q = *in[static_cast<std::size_t>((i + 1) % 3)];
    const bool p_in = p.z() > near, q_in = q.z() > near;
    if (p_in) poly[static_cast<std::size_t>(np++)] = p;
    if (p_in != q_in) poly[static_cast<std::size_t>(np++)] = p + (q - p) * ((near - p.z()) / (q.z() - p.z()));
  }
  if (np < 3) return;
  std::array<Eigen::Vector2d, 4> uv;
  Eigen::Vector2d lo(1e300, 1e300), hi(-1e300, -1e300);
  for (int i = 0; i < np; ++i) {
    const Eigen::Vector3d& p = poly[static_cast<std::size_t>(i)];
    uv[static_cast<std::size_t>(i)] = {g.fx * p.x() / p.z() + g.cx, g.fy * p.y() / p.z() + g.cy};
    lo = lo.cwiseMin(uv[static_cast<std::size_t>(i)]);
    hi = hi.cwiseMax(uv[static_cast<std::size_t>(i)]);
  }
  const int c0 = std::max(0, static_cast<int>(std::ceil(lo.x()))), c1 = std::min(g.width - 1, static_cast<int>(std::floor(hi.x())));
  const int r0 = std::max(0, static_cast<int>(std::ceil(lo.y()))), r1 = std::min(g.height - 1, static_cast<int>(std::floor(hi.y())));
  if (c0 > c1 || r0 > r1) return;
  double area = 0.0;  // orientation of the projected polygon
  for (int i = 0; i < np; ++i) {
    const Eigen::Vector2d& p = uv[static_cast<std::size_t>(i)];
    const Eigen::Vector2d& q = uv[static_cast<std::size_t>((i + 1) % np)];
    area += p.x() * q.y() - q.x() * p.y();
  }
  if (area == 0.0) return;  // seen edge-on
  const double s = area > 0.0 ? 1.0 : -1.0;
  // Edge i is inside where ea[i] col + eb[i] row + ec[i] >= 0; the ray's dot product with the
  // plane normal is dc col + dr row + d0.
  std::array<double, 4> ea{}, eb{}, ec{};
  for (int i = 0; i < np; ++i) {
    const Eigen::Vector2d& p = uv[static_cast<std::size_t>(i)];
    const Eigen::Vector2d& q = uv[static_cast<std::size_t>((i + 1) % np)];
    ea[static_cast<std::size_t>(i)] = -s * (q.y() - p.y());
    eb[static_cast<std::size_t>(i)] = s * (q.x() - p.x());
    ec[static_cast<std::size_t>(i)] = s * ((q.y() - p.y()) * p.x() - (q.x() - p.x()) * p.y());
  }
  const double dc = n.x() / g.fx, dr = n.y() / g.fy, d0 = n.z() - n.x() * g.cx / g.fx - n.y() * g.cy / g.fy;
  for (int r = r0; r <= r1; ++r)
    for (int col = c0; col <= c1; ++col) {
      bool inside = true;
      for (std::size_t i = 0; i < static_cast<std::size_t>(np) && inside; ++i) inside = ea[i] * col + eb[i] * r + ec[i] >= 0.0;
      if (!inside) continue;
      const double denom = dc * col + dr * r + d0;
      if (denom == 0.0) continue;
      const double z = k / denom;
      if (z > near) write(col, r, z);
    }
}

}  // namespace ehc_sim
