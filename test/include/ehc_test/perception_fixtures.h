#pragma once
// Synthetic data for the perception tests and benchmarks: object surface clouds (box,
// cylinder, lying bottle), a table plane, image pixel noise, and the shipped camera / robot files.

#include "ehc_control/pose_math.h"
#include "ehc_perception/grasp_generator.h"

#include <Eigen/Geometry>
#include <visp3/core/vpImage.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

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

}  // namespace ehc_perception::test
