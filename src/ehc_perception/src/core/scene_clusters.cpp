#include "scene_clusters.h"

#include <pcl/kdtree/kdtree_flann.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <set>
#include <tuple>

namespace ehc_perception {
namespace detail {

namespace {

struct UnionFind {
  std::vector<int> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int i) {
    while (parent[static_cast<std::size_t>(i)] != i) i = parent[static_cast<std::size_t>(i)] = parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(i)])];
    return i;
  }
  bool join(int a, int b) {
    a = find(a), b = find(b);
    if (a == b) return false;
    parent[static_cast<std::size_t>(std::max(a, b))] = std::min(a, b);
    return true;
  }
};

double diameter(const std::vector<Eigen::Vector2d>& hull) {
  double d = 0.0;
  for (std::size_t i = 0; i < hull.size(); ++i)
    for (std::size_t j = i + 1; j < hull.size(); ++j) d = std::max(d, (hull[i] - hull[j]).norm());
  return d;
}

/// Connected parts of `above` (see the header, step 1), each a list of indices.
std::vector<std::vector<int>> connectedParts(const pcl::PointCloud<pcl::PointXYZ>& above,
                                             const pcl::PointCloud<pcl::PointXYZ>& all, const Eigen::Vector3d* viewpoint,
                                             const GraspGeneratorConfig& cfg) {
  const std::size_t n = above.size();
  std::vector<float> reach(n, static_cast<float>(cfg.cluster_tolerance));
  if (viewpoint && cfg.cluster_spacing_factor > 0.0) {
    const double k = cfg.cluster_spacing_factor * angularPitch(all, *viewpoint);
    for (std::size_t i = 0; i < n; ++i)
      reach[i] = static_cast<float>(std::max(cfg.cluster_tolerance, k * (above[i].getVector3fMap().cast<double>() - *viewpoint).norm()));
  }
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>(above));
  pcl::KdTreeFLANN<pcl::PointXYZ> tree;
  tree.setInputCloud(cloud);
  UnionFind uf(n);
  std::vector<int> idx;
  std::vector<float> d2;
  for (std::size_t i = 0; i < n; ++i) {
    tree.radiusSearch(above[i], reach[i], idx, d2);
    for (int j : idx) uf.join(static_cast<int>(i), j);
  }
  std::vector<std::vector<int>> parts(n);
  for (std::size_t i = 0; i < n; ++i) parts[static_cast<std::size_t>(uf.find(static_cast<int>(i)))].push_back(static_cast<int>(i));
  parts.erase(std::remove_if(parts.begin(), parts.end(), [](const std::vector<int>& p) { return p.empty(); }), parts.end());
  return parts;
}


/// A part seen from inside (the far inner wall of a bowl, a cup, a pot): its footprint is an arc
/// of a circle whose centre lies on the camera's side of it, spanning at least kMinConcaveArc
/// (a bent part seen from its hollow side, e.g. a banana's, spans less). The circle (centre,
/// radius) is then the object's footprint, as far as the view shows it; false otherwise.
constexpr double kMinConcaveArc = 100.0 * M_PI / 180.0;
bool concaveFootprint(const std::vector<Eigen::Vector2d>& pts, const Eigen::Vector2d& camera, double max_radius,
                      Eigen::Vector2d* centre, double* radius) {
  if (pts.size() < 10) return false;
  // Algebraic (Kasa) circle fit: x^2 + y^2 + D x + E y + F = 0.
  Eigen::MatrixXd A(pts.size(), 3);
  Eigen::VectorXd b(pts.size());
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& p : pts) mean += p;
  mean /= static_cast<double>(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const Eigen::Vector2d q = pts[i] - mean;  // centred: well conditioned
    A.row(static_cast<Eigen::Index>(i)) << q.x(), q.y(), 1.0;
    b(static_cast<Eigen::Index>(i)) = -q.squaredNorm();
  }
  const Eigen::Vector3d x = A.colPivHouseholderQr().solve(b);
  const Eigen::Vector2d c = mean - 0.5 * x.head<2>();
  const double r2 = 0.25 * x.head<2>().squaredNorm() - x(2);
  if (!(r2 > 0.0) || !c.allFinite()) return false;
  const double r = std::sqrt(r2);
  if (r < 0.01 || r > max_radius) return false;
  double sq = 0.0;
  std::vector<double> angles;
  for (const auto& p : pts) {
    sq += std::pow((p - c).norm() - r, 2);
    angles.push_back(std::atan2(p.y() - c.y(), p.x() - c.x()));
  }
  if (std::sqrt(sq / static_cast<double>(pts.size())) > 0.2 * r) return false;
  std::sort(angles.begin(), angles.end());
  double gap = angles.front() + 2.0 * M_PI - angles.back();
  for (std::size_t i = 1; i < angles.size(); ++i) gap = std::max(gap, angles[i] - angles[i - 1]);
  if (2.0 * M_PI - gap < kMinConcaveArc) return false;
  if ((c - mean).dot(camera - mean) <= 0.0) return false;  // the hollow faces away: convex as seen
  *centre = c;
  *radius = r;
  return true;
}

std::vector<Eigen::Vector2d> joinedHull(const std::vector<Eigen::Vector2d>& a, const std::vector<Eigen::Vector2d>& b) {
  std::vector<Eigen::Vector2d> both = a;
  both.insert(both.end(), b.begin(), b.end());
  return convexHull2d(both);
}

/// Step 2 of the header: merges the closest pair of footprints within footprint_merge_gap first
/// (the lower index keeps the part), until none is left. A pair's distance and joined width
/// only change when one of its parts grows, so the candidate pairs are kept and only the grown
/// part's recomputed; parts whose bounding boxes are farther apart than the gap are never
/// compared. Noisy views bring hundreds of small parts, so the order matters.
void mergeCloseFootprints(std::vector<std::vector<int>>& parts, std::vector<std::vector<Eigen::Vector2d>>& hulls,
                          const GraspGeneratorConfig& cfg) {
  if (cfg.footprint_merge_gap < 0.0) return;
  const std::size_t n = parts.size();
  std::vector<Eigen::AlignedBox2d> boxes(n);
  for (std::size_t k = 0; k < n; ++k)
    for (const auto& p : hulls[k]) boxes[k].extend(p);
  std::vector<bool> alive(n, true);
  std::set<std::tuple<double, std::size_t, std::size_t>> pairs;  // (distance, lower, higher): ties by index
  const auto consider = [&](std::size_t a, std::size_t b) {
    if (boxes[a].exteriorDistance(boxes[b]) > cfg.footprint_merge_gap) return;  // a box holds its hull
    const double d = hullDistance(hulls[a], hulls[b]);
    if (d <= cfg.footprint_merge_gap && diameter(joinedHull(hulls[a], hulls[b])) <= cfg.max_object_extent)
      pairs.emplace(d, a, b);
  };
  for (std::size_t a = 0; a < n; ++a)
    for (std::size_t b = a + 1; b < n; ++b) consider(a, b);
  while (!pairs.empty()) {
    const auto [d, a, b] = *pairs.begin();
    parts[a].insert(parts[a].end(), parts[b].begin(), parts[b].end());
    hulls[a] = joinedHull(hulls[a], hulls[b]);
    boxes[a].extend(boxes[b]);
    alive[b] = false;
    for (auto it = pairs.begin(); it != pairs.end();) {
      const std::size_t i = std::get<1>(*it), j = std::get<2>(*it);
      it = (i == a || j == a || i == b || j == b) ? pairs.erase(it) : std::next(it);
    }
    for (std::size_t k = 0; k < n; ++k)
      if (alive[k] && k != a) consider(std::min(a, k), std::max(a, k));
  }
  std::size_t kept = 0;
  for (std::size_t k = 0; k < n; ++k)
    if (alive[k]) {
      if (kept != k) parts[kept] = std::move(parts[k]);
      ++kept;
    }
  parts.resize(kept);
}

}  // namespace

double angularPitch(const pcl::PointCloud<pcl::PointXYZ>& cloud, const Eigen::Vector3d& viewpoint) {
  if (cloud.size() < 2) return 0.0;
  pcl::PointCloud<pcl::PointXYZ>::Ptr c(new pcl::PointCloud<pcl::PointXYZ>(cloud));
  pcl::KdTreeFLANN<pcl::PointXYZ> tree;
  tree.setInputCloud(c);
  const std::size_t step = std::max<std::size_t>(1, cloud.size() / 2000);
  std::vector<double> ratios;
  std::vector<int> idx(2);
  std::vector<float> d2(2);
  for (std::size_t i = 0; i < cloud.size(); i += step) {
    if (tree.nearestKSearch(cloud[i], 2, idx, d2) < 2) continue;
    const double range = (cloud[i].getVector3fMap().cast<double>() - viewpoint).norm();
    if (range > 1e-6) ratios.push_back(std::sqrt(static_cast<double>(d2[1])) / range);
  }
  if (ratios.empty()) return 0.0;
  std::nth_element(ratios.begin(), ratios.begin() + static_cast<long>(ratios.size() / 2), ratios.end());
  return ratios[ratios.size() / 2];
}

std::vector<std::vector<int>> clusterObjects(const pcl::PointCloud<pcl::PointXYZ>& above,
                                             const pcl::PointCloud<pcl::PointXYZ>& all,
                                             const Eigen::Vector3d* viewpoint, const Eigen::Vector3d& up,
                                             const GraspGeneratorConfig& cfg) {
  std::vector<std::vector<int>> parts = connectedParts(above, all, viewpoint, cfg);
  // Footprints in the support plane's basis.
  const Eigen::Vector3d u = up.normalized();
  const Eigen::Vector3d e1 = u.unitOrthogonal(), e2 = u.cross(e1);
  std::vector<std::vector<Eigen::Vector2d>> flat(parts.size());
  std::vector<std::vector<Eigen::Vector2d>> hulls(parts.size());
  for (std::size_t k = 0; k < parts.size(); ++k) {
    for (int i : parts[k]) {
      const Eigen::Vector3d p = above[static_cast<std::size_t>(i)].getVector3fMap().cast<double>();
      flat[k].emplace_back(p.dot(e1), p.dot(e2));
    }
    hulls[k] = convexHull2d(flat[k]);
  }
  const auto join = [&](std::size_t a, std::size_t b, std::vector<Eigen::Vector2d> hull) {
    parts[a].insert(parts[a].end(), parts[b].begin(), parts[b].end());
    flat[a].insert(flat[a].end(), flat[b].begin(), flat[b].end());
    hulls[a] = std::move(hull);
    parts.erase(parts.begin() + static_cast<long>(b));
    flat.erase(flat.begin() + static_cast<long>(b));
    hulls.erase(hulls.begin() + static_cast<long>(b));
  };
  // A part seen from inside takes the parts within its circle (most of their points).
  if (viewpoint) {
    const Eigen::Vector2d eye(viewpoint->dot(e1), viewpoint->dot(e2));
    for (std::size_t b = 0; b < parts.size(); ++b) {
      Eigen::Vector2d c;
      double r = 0.0;
      if (!concaveFootprint(flat[b], eye, 0.5 * cfg.max_object_extent, &c, &r)) continue;
      std::vector<std::size_t> takes;
      for (std::size_t a = 0; a < parts.size(); ++a) {
        // Its centre about inside the circle, and most of it within a quarter of the radius beyond
        // (the circle is fitted to the inner wall, narrower than the rim where it slopes; an arc's
        // centre lies inside its circle).
        Eigen::Vector2d mean = Eigen::Vector2d::Zero();
        for (const auto& p : flat[a]) mean += p;
        mean /= static_cast<double>(flat[a].size());
        const auto within = std::count_if(flat[a].begin(), flat[a].end(), [&](const Eigen::Vector2d& p) {
          return (p - c).norm() <= 1.25 * r + std::max(0.0, cfg.footprint_merge_gap);
        });
        if (a != b && (mean - c).norm() <= 1.1 * r && static_cast<double>(within) >= 0.8 * static_cast<double>(flat[a].size()))
          takes.push_back(a);
      }
      for (auto it = takes.rbegin(); it != takes.rend(); ++it) {  // from the last: the indices below stay
        const std::size_t lo = std::min(*it, b), hi = std::max(*it, b);
        std::vector<Eigen::Vector2d> hull = joinedHull(hulls[lo], hulls[hi]);
        if (diameter(hull) > cfg.max_object_extent) continue;
        join(lo, hi, std::move(hull));
        b = lo;
      }
    }
  }
  mergeCloseFootprints(parts, hulls, cfg);
  parts.erase(std::remove_if(parts.begin(), parts.end(),
                             [&](const std::vector<int>& p) { return static_cast<int>(p.size()) < cfg.min_cluster_points; }),
              parts.end());
  std::stable_sort(parts.begin(), parts.end(), [](const std::vector<int>& a, const std::vector<int>& b) { return a.size() > b.size(); });
  if (static_cast<int>(parts.size()) > cfg.max_objects) parts.resize(static_cast<std::size_t>(cfg.max_objects));
  return parts;
}

}  // namespace detail
}  // namespace ehc_perception
