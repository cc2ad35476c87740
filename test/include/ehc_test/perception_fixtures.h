#pragma once
// Synthetic data for the perception tests and benchmarks: object surface clouds (box,
// cylinder, lying bottle), a table plane, a depth camera's organised cloud of boxes on a table,
// PointCloud2 bytes without ROS, image pixel noise, and the shipped camera / robot files.

#include "ehc_control/pose_math.h"
#include "ehc_perception/grasp_generator.h"
#include "ehc_perception/point_cloud_layout.h"

#include <Eigen/Geometry>
#include <visp3/core/vpImage.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <vector>

namespace ehc_perception::test {

inline std::string configDir() { return EHC_CONFIG_DIR; }
inline std::string cameraYaml() { return configDir() + "/robots/realman_rm65_water2/camera.yaml"; }
inline std::string robotYaml() { return configDir() + "/robots/realman_rm65_water2/robot.yaml"; }

/// The simulator's pixel noise (config/sim/bullet_sim.yaml camera.image_noise: 2 grey levels,
/// i.i.d. Gaussian), added to a grey image.
inline void addPixelNoise(vpImage<unsigned char>* image, std::mt19937* rng, double sigma = 2.0) {
  std::normal_distribution<double> n(0.0, sigma);
  for (unsigned k = 0; k < image->getSize(); ++k)
    image->bitmap[k] = static_cast<unsigned char>(std::clamp(std::lround(image->bitmap[k] + n(*rng)), 0L, 255L));
}

/// Optical frame at `eye` looking at `target` (ehc_control/pose_math.h).
using ehc_control::lookAt;

struct Surface {
  PointList points;
  std::vector<Eigen::Vector3f> normals;  ///< outward
  void add(const Eigen::Vector3d& p, const Eigen::Vector3d& n) {
    points.push_back(p.cast<float>());
    normals.push_back(n.cast<float>());
  }
  void append(const Surface& o) {
    points.insert(points.end(), o.points.begin(), o.points.end());
    normals.insert(normals.end(), o.normals.begin(), o.normals.end());
  }
  void transform(const Eigen::Isometry3d& T) {
    for (std::size_t i = 0; i < points.size(); ++i) {
      points[i] = (T * points[i].cast<double>()).cast<float>();
      normals[i] = (T.linear() * normals[i].cast<double>()).cast<float>();
    }
  }
  /// Keeps the points whose outward normal faces the viewpoint (convex objects: visibility).
  Surface visibleFrom(const Eigen::Vector3d& view) const {
    Surface s;
    for (std::size_t i = 0; i < points.size(); ++i)
      if (normals[i].cast<double>().dot(view - points[i].cast<double>()) > 0)
        s.add(points[i].cast<double>(), normals[i].cast<double>());
    return s;
  }
  /// Keeps what a camera at `view` sees of a non-convex surface: the points facing it that are
  /// nearest to it in their direction (a z-buffer over bins of `bin` rad around the direction
  /// to the centroid; a point more than `depth_tol` m behind the nearest of its bin is occluded).
  Surface occludedFrom(const Eigen::Vector3d& view, double bin = 0.006, double depth_tol = 0.003) const {
    const Eigen::Vector3d fwd = (centroid() - view).normalized();
    const Eigen::Vector3d e1 = fwd.unitOrthogonal(), e2 = fwd.cross(e1);
    auto key = [&](const Eigen::Vector3d& p, double* range) {
      const Eigen::Vector3d d = p - view;
      *range = d.norm();
      const double z = d.dot(fwd);
      return std::make_pair(static_cast<long>(std::floor(d.dot(e1) / z / bin)),
                            static_cast<long>(std::floor(d.dot(e2) / z / bin)));
    };
    std::map<std::pair<long, long>, double> nearest;
    const Surface facing = visibleFrom(view);
    for (const auto& pf : facing.points) {
      double r = 0.0;
      const auto k = key(pf.cast<double>(), &r);
      auto it = nearest.find(k);
      if (it == nearest.end() || r < it->second) nearest[k] = r;
    }
    Surface s;
    for (std::size_t i = 0; i < facing.points.size(); ++i) {
      double r = 0.0;
      const auto k = key(facing.points[i].cast<double>(), &r);
      if (r <= nearest[k] + depth_tol) s.add(facing.points[i].cast<double>(), facing.normals[i].cast<double>());
    }
    return s;
  }
  PointList noisy(double sigma, unsigned seed) const {
    std::mt19937 rng(seed);
    std::normal_distribution<double> n(0.0, sigma);
    PointList out = points;
    for (auto& p : out) p += Eigen::Vector3f(n(rng), n(rng), n(rng));
    return out;
  }
  Eigen::Vector3d centroid() const {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (const auto& p : points) c += p.cast<double>();
    return c / static_cast<double>(points.size());
  }
};

/// Axis-aligned box centred at the origin (bottom face at z = -size.z/2 skipped if !bottom).
inline Surface boxSurface(const Eigen::Vector3d& size, double step, bool bottom = false) {
  Surface s;
  const Eigen::Vector3d h = 0.5 * size;
  for (int axis = 0; axis < 3; ++axis) {
    const int a = (axis + 1) % 3, b = (axis + 2) % 3;
    for (int sign : {-1, 1}) {
      if (axis == 2 && sign < 0 && !bottom) continue;
      const int na = std::max(1, static_cast<int>(std::round(size[a] / step)));
      const int nb = std::max(1, static_cast<int>(std::round(size[b] / step)));
      for (int i = 0; i <= na; ++i)
        for (int j = 0; j <= nb; ++j) {
          Eigen::Vector3d p, n = Eigen::Vector3d::Zero();
          p[axis] = sign * h[axis];
          p[a] = -h[a] + size[a] * i / na;
          p[b] = -h[b] + size[b] * j / nb;
          n[axis] = sign;
          s.add(p, n);
        }
    }
  }
  return s;
}

/// Cylinder along z from z0 to z1, radius r; caps optional.
inline Surface cylinderSurface(double r, double z0, double z1, double step, bool cap0, bool cap1) {
  Surface s;
  const int na = std::max(8, static_cast<int>(std::round(2 * M_PI * r / step)));
  const int nz = std::max(1, static_cast<int>(std::round((z1 - z0) / step)));
  for (int i = 0; i < na; ++i) {
    const double a = 2 * M_PI * i / na;
    const Eigen::Vector3d n(std::cos(a), std::sin(a), 0);
    for (int k = 0; k <= nz; ++k) s.add(Eigen::Vector3d(r * n.x(), r * n.y(), z0 + (z1 - z0) * k / nz), n);
  }
  for (int c = 0; c < 2; ++c) {
    if ((c == 0 && !cap0) || (c == 1 && !cap1)) continue;
    const double z = c == 0 ? z0 : z1;
    const Eigen::Vector3d n(0, 0, c == 0 ? -1 : 1);
    for (double rr = 0; rr < r - 1e-9; rr += step) {
      const int m = std::max(1, static_cast<int>(std::round(2 * M_PI * rr / step)));
      for (int i = 0; i < m; ++i) {
        const double a = 2 * M_PI * i / m;
        s.add(Eigen::Vector3d(rr * std::cos(a), rr * std::sin(a), z), n);
      }
    }
  }
  return s;
}

/// Sphere of radius r centred at the origin (latitude rings `step` apart).
inline Surface sphereSurface(double r, double step) {
  Surface s;
  const int nl = std::max(4, static_cast<int>(std::round(M_PI * r / step)));
  for (int i = 0; i <= nl; ++i) {
    const double lat = -0.5 * M_PI + M_PI * i / nl;
    const int na = std::max(1, static_cast<int>(std::round(2 * M_PI * r * std::cos(lat) / step)));
    for (int k = 0; k < na; ++k) {
      const double lon = 2 * M_PI * k / na;
      const Eigen::Vector3d n(std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon), std::sin(lat));
      s.add(r * n, n);
    }
  }
  return s;
}

/// A bent tube (a banana without its tapering ends): radius r round a centre line that is an arc
/// of `bend` m radius in the local x-y plane, `length` m long along it, its middle at the origin
/// with the tangent along x and the arc bending towards +y; end caps closed.
inline Surface bentTubeSurface(double r, double bend, double length, double step) {
  Surface s;
  const double half = 0.5 * length / bend;  // rad of arc each side of the middle
  const int nu = std::max(2, static_cast<int>(std::round(length / step)));
  const int na = std::max(8, static_cast<int>(std::round(2 * M_PI * r / step)));
  const auto centre = [&](double t) { return Eigen::Vector3d(bend * std::sin(t), bend * (1.0 - std::cos(t)), 0.0); };
  for (int k = 0; k <= nu; ++k) {
    const double t = -half + 2.0 * half * k / nu;
    const Eigen::Vector3d c = centre(t), tangent(std::cos(t), std::sin(t), 0.0), inward(-std::sin(t), std::cos(t), 0.0);
    for (int i = 0; i < na; ++i) {
      const double a = 2 * M_PI * i / na;
      const Eigen::Vector3d n = std::cos(a) * inward + std::sin(a) * Eigen::Vector3d::UnitZ();
      s.add(c + r * n, n);
    }
    if (k == 0 || k == nu) {  // the caps
      const Eigen::Vector3d out = k == 0 ? Eigen::Vector3d(-tangent) : tangent;
      for (double rr = 0; rr < r - 1e-9; rr += step) {
        const int m = std::max(1, static_cast<int>(std::round(2 * M_PI * rr / step)));
        for (int i = 0; i < m; ++i) {
          const double a = 2 * M_PI * i / m;
          s.add(c + rr * (std::cos(a) * inward + std::sin(a) * Eigen::Vector3d::UnitZ()), out);
        }
      }
    }
  }
  return s;
}

/// A bottle along its local z: body (r_body, length body_len), conical shoulder, neck.
inline Surface bottleSurface(double r_body, double body_len, double shoulder_len, double r_neck,
                             double neck_len, double step) {
  Surface s = cylinderSurface(r_body, 0.0, body_len, step, true, false);
  const int nz = std::max(1, static_cast<int>(std::round(shoulder_len / step)));
  const double slope = (r_body - r_neck) / shoulder_len;
  for (int k = 0; k <= nz; ++k) {
    const double z = body_len + shoulder_len * k / nz;
    const double r = r_body - slope * (z - body_len);
    const int na = std::max(8, static_cast<int>(std::round(2 * M_PI * r / step)));
    for (int i = 0; i < na; ++i) {
      const double a = 2 * M_PI * i / na;
      s.add(Eigen::Vector3d(r * std::cos(a), r * std::sin(a), z),
            Eigen::Vector3d(std::cos(a), std::sin(a), slope).normalized());
    }
  }
  Surface neck = cylinderSurface(r_neck, body_len + shoulder_len,
                                 body_len + shoulder_len + neck_len, step, false, true);
  s.append(neck);
  return s;
}

/// A cup standing on z = 0, its axis along z: an open cylindrical body (outer radius r, wall
/// `wall` thick, `height` high: outer and inner mantle, the rim's annulus on top, the inner
/// bottom `wall` above the support). `flare` > 0 makes it a bowl: every point's distance from
/// the axis scaled by (r - flare (1 - sin a)) / r at z = height (1 - cos a) (a quarter ellipse
/// from the base's outer radius r - flare up to the rim, vertical there, as the object library's
/// bowls), the mantles' normals tilted to match.
inline Surface cupSurface(double r, double wall, double height, double step, double flare = 0.0) {
  Surface s = cylinderSurface(r, 0.0, height, step, false, false);
  Surface inner = cylinderSurface(r - wall, wall, height, step, true, false);
  for (auto& n : inner.normals) n = -n;  // facing the axis (the bottom up)
  s.append(inner);
  const int na = std::max(8, static_cast<int>(std::round(2 * M_PI * r / step)));
  for (double rr = r - wall; rr <= r + 1e-9; rr += 0.5 * step)
    for (int i = 0; i < na; ++i) {
      const double a = 2 * M_PI * i / na;
      s.add(Eigen::Vector3d(rr * std::cos(a), rr * std::sin(a), height), Eigen::Vector3d::UnitZ());
    }
  if (flare == 0.0) return s;
  for (std::size_t i = 0; i < s.points.size(); ++i) {
    Eigen::Vector3f& p = s.points[i];
    Eigen::Vector3f& n = s.normals[i];
    const double c = std::clamp(1.0 - p.z() / height, 0.0, 1.0), sin_a = std::sqrt(1.0 - c * c);
    const double rho = std::hypot(p.x(), p.y()), k = (r - flare * (1.0 - sin_a)) / r;
    if (std::abs(n.z()) < 0.5 && rho > 0.0) {  // a mantle: d(k rho) / dz = rho flare c / (r height sin a)
      const double outward = (n.x() * p.x() + n.y() * p.y()) / rho;
      n.z() = static_cast<float>(-outward * rho * flare * c / (r * height * std::max(sin_a, 0.1)));
      n.normalize();
    }
    p.x() = static_cast<float>(k * p.x());
    p.y() = static_cast<float>(k * p.y());
  }
  return s;
}

/// cupSurface with a handle on its +x side: a torus arc (the bar's radius `bar`) in the xz plane
/// whose centre line, a half circle from the wall, runs out to `reach` m beyond the mantle.
inline Surface mugSurface(double r, double wall, double height, double bar, double reach, double step) {
  Surface s = cupSurface(r, wall, height, step);
  // Handle: centre line a half circle of radius R about (r, 0, height / 2) in the xz plane.
  const double R = reach + 0.5 * bar, zc = 0.5 * height;
  const int nu = std::max(8, static_cast<int>(std::round(M_PI * R / step)));
  const int nv = std::max(8, static_cast<int>(std::round(2 * M_PI * bar / step)));
  for (int i = 0; i <= nu; ++i) {
    const double u = -0.5 * M_PI + M_PI * i / nu;
    const Eigen::Vector3d c(r - 0.5 * bar + R * std::cos(u), 0.0, zc + R * std::sin(u));
    const Eigen::Vector3d radial(std::cos(u), 0.0, std::sin(u));
    for (int j = 0; j < nv; ++j) {
      const double v = 2 * M_PI * j / nv;
      const Eigen::Vector3d n = std::cos(v) * radial + std::sin(v) * Eigen::Vector3d::UnitY();
      const Eigen::Vector3d p = c + bar * n;
      if (std::hypot(p.x(), p.y()) > r) s.add(p, n);  // the part inside the body is not surface
    }
  }
  return s;
}

/// A prism lying on z = 0 along y, `length` long, its section a right isosceles triangle with
/// the right angle on top (a roof: faces 45 deg from the horizontal, `base` wide); the bottom
/// is not sampled.
inline Surface roofPrismSurface(double base, double length, double step) {
  Surface s;
  const double h = 0.5 * base;
  const Eigen::Vector3d nl = Eigen::Vector3d(-1, 0, 1).normalized(), nr = Eigen::Vector3d(1, 0, 1).normalized();
  for (double y = -0.5 * length; y <= 0.5 * length + 1e-9; y += step)
    for (double t = 0.0; t <= h * std::sqrt(2.0) + 1e-9; t += step) {
      const double d = t / std::sqrt(2.0);
      s.add(Eigen::Vector3d(-h + d, y, d), nl);
      s.add(Eigen::Vector3d(h - d, y, d), nr);
    }
  for (int e : {-1, 1})
    for (double x = -h; x <= h + 1e-9; x += step)
      for (double z = 0.0; z <= h - std::abs(x) + 1e-9; z += step)
        s.add(Eigen::Vector3d(x, 0.5 * e * length, z), Eigen::Vector3d(0, e, 0));
  return s;
}

/// Horizontal rectangle (table top) at height z, centred at (cx, cy).
inline Surface tableSurface(double cx, double cy, double sx, double sy, double z, double step) {
  Surface s;
  for (double x = -0.5 * sx; x <= 0.5 * sx + 1e-9; x += step)
    for (double y = -0.5 * sy; y <= 0.5 * sy + 1e-9; y += step)
      s.add(Eigen::Vector3d(cx + x, cy + y, z), Eigen::Vector3d::UnitZ());
  return s;
}

inline Eigen::Isometry3d pose(double x, double y, double z, double yaw, double pitch = 0,
                              double roll = 0) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() << x, y, z;
  T.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  return T;
}

/// Pose in the camera optical frame of a tag facing the camera (its z towards the camera),
/// tilted by roll-pitch-yaw (rx, ry, rz) about the camera axes.
inline Eigen::Isometry3d facingTag(double x, double y, double z, double rx, double ry, double rz) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() << x, y, z;
  T.linear() = (Eigen::AngleAxisd(rz, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(ry, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(rx, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix() *
               Eigen::Vector3d(1, -1, -1).asDiagonal();
  return T;
}

/// A full 640x480 D435 frame (pinhole, fx = fy = 615) of a wall 1.5 m in front of a camera at
/// (0, 0, 1) looking along +x, in the world frame: 307 200 points.
inline PointList fullD435Wall() {
  PointList pts;
  pts.reserve(640 * 480);
  for (int v = 0; v < 480; ++v)
    for (int u = 0; u < 640; ++u) {
      const float depth = 1.5f;
      const float right = (u - 320.0f) / 615.0f * depth, down = (v - 240.0f) / 615.0f * depth;
      pts.emplace_back(depth, -right, 1.0f - down);
    }
  return pts;
}

/// An oriented box: its centre's pose and its edge lengths.
struct Box {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  Eigen::Vector3d size = Eigen::Vector3d::Constant(0.05);
};

/// Distance along the ray o + t d (|d| = 1) to `box`, +inf if it misses (slab test).
inline double rayBox(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Box& box) {
  const Eigen::Vector3d lo = box.pose.inverse() * o, ld = box.pose.linear().transpose() * d;
  double t0 = 0.0, t1 = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    const double h = 0.5 * box.size[a];
    if (std::abs(ld[a]) < 1e-12) {
      if (std::abs(lo[a]) > h) return std::numeric_limits<double>::infinity();
      continue;
    }
    double ta = (-h - lo[a]) / ld[a], tb = (h - lo[a]) / ld[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return std::numeric_limits<double>::infinity();
  }
  return t0 > 0.0 ? t0 : std::numeric_limits<double>::infinity();
}

/// A depth camera's organised cloud, width x height points row-major in the world frame: a
/// pinhole camera at `T_world_cam` (optical frame: z ahead, x right, y down; fx = fy = 615 per
/// 640 columns, the field of view of fullD435Wall at any resolution, principal point at the
/// centre) sees `boxes` (a table top is a flat box) and the floor z = 0; a pixel whose ray meets
/// nothing within 6 m is NaN (no return). Depth noise: Gaussian, `sigma` m along the ray (seeded).
inline PointList depthCameraCloud(int width, int height, const Eigen::Isometry3d& T_world_cam,
                                  const std::vector<Box>& boxes, double sigma = 0.0, unsigned seed = 1) {
  const double f = 615.0 * width / 640.0;
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma > 0.0 ? sigma : 1.0);
  PointList pts;
  pts.reserve(static_cast<std::size_t>(width) * height);
  const Eigen::Vector3d o = T_world_cam.translation();
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) {
      const Eigen::Vector3d d =
          (T_world_cam.linear() * Eigen::Vector3d((u - 0.5 * width) / f, (v - 0.5 * height) / f, 1.0)).normalized();
      double t = d.z() < -1e-9 ? -o.z() / d.z() : std::numeric_limits<double>::infinity();
      for (const Box& b : boxes) t = std::min(t, rayBox(o, d, b));
      if (t > 6.0) {
        pts.emplace_back(Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN()));
        continue;
      }
      if (sigma > 0.0) t += sigma * noise(rng);
      pts.push_back((o + t * d).cast<float>());
    }
  return pts;
}

/// A PointCloud2's layout and bytes without ROS (what the nodes copy into a PointCloudLayout).
struct PackedCloud {
  PointCloudLayout layout;
  std::vector<std::uint8_t> data;
  std::string problem() const { return layout.problem(data.size()); }
  CloudPoints extract(std::size_t max_points = 0) const {
    return extractCloudPoints(layout, data.data(), data.size(), max_points);
  }
};

/// One field of packCloud's points: its name and datatype.
struct FieldSpec {
  std::string name;
  PointFieldType type;
};
inline const std::vector<FieldSpec>& xyzFloat32() {
  static const std::vector<FieldSpec> f = {
      {"x", PointFieldType::Float32}, {"y", PointFieldType::Float32}, {"z", PointFieldType::Float32}};
  return f;
}

/// Writes `v` at `at` as datatype `t`.
inline void putField(std::uint8_t* at, PointFieldType t, double v) {
  auto put = [&](auto x) { std::memcpy(at, &x, sizeof x); };
  switch (t) {
    case PointFieldType::Int8: return put(static_cast<std::int8_t>(v));
    case PointFieldType::Uint8: return put(static_cast<std::uint8_t>(v));
    case PointFieldType::Int16: return put(static_cast<std::int16_t>(v));
    case PointFieldType::Uint16: return put(static_cast<std::uint16_t>(v));
    case PointFieldType::Int32: return put(static_cast<std::int32_t>(v));
    case PointFieldType::Uint32: return put(static_cast<std::uint32_t>(v));
    case PointFieldType::Float32: return put(static_cast<float>(v));
    case PointFieldType::Float64: return put(v);
  }
}

/// `pts` packed row-major in `height` rows, the fields in the given order (x, y, z from the
/// point, any other field 7), then `padding` bytes per point and `row_padding` bytes per row
/// (filled with 0xAB).
template <class Point>
PackedCloud packCloud(const std::vector<Point>& pts, const std::vector<FieldSpec>& fields = xyzFloat32(),
                      std::uint32_t height = 1, std::uint32_t padding = 0, std::uint32_t row_padding = 0) {
  PackedCloud c;
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
      putField(point + c.layout.fields[k].offset, fields[k].type, v);
    }
  }
  return c;
}

}  // namespace ehc_perception::test
