#include "ehc_perception/convex_polygon.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace ehc_perception {

double cross2d(const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return (a - o).x() * (b - o).y() - (a - o).y() * (b - o).x();
}

double pointSegmentDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double l2 = ab.squaredNorm();
  const double t = l2 > 0.0 ? std::clamp((p - a).dot(ab) / l2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).norm();
}

namespace {
bool segmentsCross(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c, const Eigen::Vector2d& d) {
  const double d1 = cross2d(c, d, a), d2 = cross2d(c, d, b), d3 = cross2d(a, b, c), d4 = cross2d(a, b, d);
  return ((d1 > 0) != (d2 > 0)) && ((d3 > 0) != (d4 > 0)) && d1 != 0 && d2 != 0 && d3 != 0 && d4 != 0;
}
}  // namespace

bool insideConvex(const Eigen::Vector2d& p, const std::vector<Eigen::Vector2d>& poly) {
  if (poly.size() < 3) return false;
  for (std::size_t i = 0; i < poly.size(); ++i)
    if (cross2d(poly[i], poly[(i + 1) % poly.size()], p) < 0.0) return false;
  return true;
}

std::vector<Eigen::Vector2d> convexHull2d(std::vector<Eigen::Vector2d> pts) {
  pts.erase(std::remove_if(pts.begin(), pts.end(), [](const Eigen::Vector2d& p) { return !p.allFinite(); }), pts.end());
  std::sort(pts.begin(), pts.end(), [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  pts.erase(std::unique(pts.begin(), pts.end()), pts.end());
  if (pts.size() < 3) return pts;
  std::vector<Eigen::Vector2d> h(2 * pts.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {  // lower hull
    while (k >= 2 && cross2d(h[k - 2], h[k - 1], pts[i]) <= 0.0) --k;
    h[k++] = pts[i];
  }
  for (std::size_t i = pts.size() - 1, t = k + 1; i > 0; --i) {  // upper hull
    while (k >= t && cross2d(h[k - 2], h[k - 1], pts[i - 1]) <= 0.0) --k;
    h[k++] = pts[i - 1];
  }
  h.resize(k - 1);
  return h;
}

double hullDistance(const std::vector<Eigen::Vector2d>& a, const std::vector<Eigen::Vector2d>& b) {
  if (a.empty() || b.empty()) return std::numeric_limits<double>::infinity();
  if (insideConvex(a.front(), b) || insideConvex(b.front(), a)) return 0.0;
  double best = std::numeric_limits<double>::infinity();
  const auto edges = [](const std::vector<Eigen::Vector2d>& p, std::size_t i) {
    return std::make_pair(p[i], p[(i + 1) % p.size()]);
  };
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < b.size(); ++j) {
      const auto [a0, a1] = edges(a, i);
      const auto [b0, b1] = edges(b, j);
      if (segmentsCross(a0, a1, b0, b1)) return 0.0;
      best = std::min({best, pointSegmentDistance(a0, b0, b1), pointSegmentDistance(b0, a0, a1)});
    }
  return best;
}

double polygonArea(const std::vector<Eigen::Vector2d>& poly) {
  double twice = 0.0;
  for (std::size_t i = 0; i < poly.size(); ++i) twice += cross2d(Eigen::Vector2d::Zero(), poly[i], poly[(i + 1) % poly.size()]);
  return 0.5 * twice;
}

}  // namespace ehc_perception
