// Wall grasps (see wall_grasps.h).
#include "wall_grasps.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ehc_perception {
namespace detail {

ViewShadow::ViewShadow(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& eye, double tolerance,
                       double margin) {
  if (points.size() < 3 || !eye.allFinite() || !(tolerance > 0.0)) return;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& p : points) centroid += p;
  centroid /= static_cast<double>(points.size());
  if ((centroid - eye).norm() < 1e-6) return;
  eye_ = eye;
  fwd_ = (centroid - eye).normalized();
  e1_ = fwd_.unitOrthogonal();
  e2_ = fwd_.cross(e1_);
  tol_ = tolerance;
  margin_ = margin;
  std::vector<Eigen::Vector3f> proj;
  proj.reserve(points.size());
  double u1 = -1e9, v1 = -1e9;
  u0_ = v0_ = 1e9;
  for (const auto& p : points) {
    double u = 0, v = 0, r = 0;
    if (!project(p, &u, &v, &r)) continue;
    proj.emplace_back(static_cast<float>(u), static_cast<float>(v), static_cast<float>(r));
    u0_ = std::min(u0_, u), v0_ = std::min(v0_, v), u1 = std::max(u1, u), v1 = std::max(v1, v);
  }
  if (proj.empty()) return;
  // Cells at least the tolerance wide (a query scans its cell and the eight around it), at most
  // 512 x 512 of them.
  cell_ = std::max({tol_, (u1 - u0_) / 511.0, (v1 - v0_) / 511.0, 1e-9});
  nu_ = static_cast<int>((u1 - u0_) / cell_) + 1;
  nv_ = static_cast<int>((v1 - v0_) / cell_) + 1;
  std::vector<int> cell(proj.size());
  start_.assign(static_cast<std::size_t>(nu_ * nv_) + 1, 0);
  for (std::size_t i = 0; i < proj.size(); ++i) {
    const int iu = std::min(nu_ - 1, static_cast<int>((proj[i].x() - u0_) / cell_));
    const int iv = std::min(nv_ - 1, static_cast<int>((proj[i].y() - v0_) / cell_));
    cell[i] = iv * nu_ + iu;
    ++start_[static_cast<std::size_t>(cell[i]) + 1];
  }
  for (std::size_t k = 1; k < start_.size(); ++k) start_[k] += start_[k - 1];
  pts_.resize(proj.size());
  std::vector<int> fill(start_.begin(), start_.end() - 1);
  for (std::size_t i = 0; i < proj.size(); ++i) pts_[static_cast<std::size_t>(fill[static_cast<std::size_t>(cell[i])]++)] = proj[i];
  enabled_ = true;
}

bool ViewShadow::project(const Eigen::Vector3d& q, double* u, double* v, double* r) const {
  const Eigen::Vector3d d = q - eye_;
  const double z = d.dot(fwd_);
  if (z <= 1e-6) return false;
  *u = d.dot(e1_) / z;
  *v = d.dot(e2_) / z;
  *r = d.norm();
  return true;
}

bool ViewShadow::mayBeSolid(const Eigen::Vector3d& q) const {
  if (!enabled_) return false;
  double u = 0, v = 0, r = 0;
  if (!project(q, &u, &v, &r)) return false;
  const int iu = static_cast<int>(std::floor((u - u0_) / cell_)), iv = static_cast<int>(std::floor((v - v0_) / cell_));
  const double tol2 = tol_ * tol_;
  for (int jv = std::max(0, iv - 1); jv <= std::min(nv_ - 1, iv + 1); ++jv)
    for (int ju = std::max(0, iu - 1); ju <= std::min(nu_ - 1, iu + 1); ++ju) {
      const int k = jv * nu_ + ju;
      for (int e = start_[static_cast<std::size_t>(k)]; e < start_[static_cast<std::size_t>(k) + 1]; ++e) {
        const Eigen::Vector3f& s = pts_[static_cast<std::size_t>(e)];
        if (std::pow(s.x() - u, 2) + std::pow(s.y() - v, 2) <= tol2 && s.z() <= r + margin_) return true;
      }
    }
  return false;
}

namespace {

/// The search at one seed point: grasp frame (y closing into the seen surface, z = a: straight
/// down or tilted about y, x = y x z) and the points around it in that frame, (y, x, z) from the
/// seed.
class WallSearch {
 public:
  WallSearch(const GraspGeneratorConfig& cfg, const WallInput& in, const std::vector<Eigen::Vector3d>& collision)
      : cfg_(cfg), g_(cfg.gripper), in_(in), collision_(collision),
        cos_cone_(std::cos(std::atan(cfg.friction_coefficient))), up_(in.plane.head<3>()),
        z1_(g_.finger_tip_depth), z0_(g_.finger_tip_depth - g_.finger_length),
        sweep_(cfg.approach_standoff), band_(4.0 * in.noise + 2.0 * in.leaf),
        k_(cfg.max_collision_points) {}

  /// The seen surface's normal at point i, turned towards the camera (zero if none).
  Eigen::Vector3d facing(std::size_t i) const {
    Eigen::Vector3d n = (*in_.normals)[i];
    if (n.isZero()) return n;
    return n.dot(in_.eye - (*in_.points)[i]) >= 0.0 ? n : Eigen::Vector3d(-n);
  }
  /// The wall grasp at point i approached `tilt` (rad) from straight down about its closing
  /// axis, the approach's horizontal part away from the eye, if any.
  bool at(std::size_t i, double tilt, WallGrasp* out);

 private:
  Eigen::Vector3d world(double ly, double lx, double lz) const { return p_ + y_ * ly + x_ * lx + a_ * lz; }
  /// m: the lowest fingertip edge's height above the support.
  double tipClearance() const {
    const double h = up_.dot(world(0.0, 0.0, z1_)) + in_.plane[3];
    return h - std::abs(up_.dot(x_)) * 0.5 * g_.finger_breadth;
  }
  void gather();
  /// Collision points in the box ly in [y0, y1], |lx| <= hx, lz in [za, zb].
  int countIn(double y0, double y1, double hx, double za, double zb) const {
    int n = 0;
    for (const Eigen::Vector3d& l : near_)
      n += l.x() >= y0 && l.x() <= y1 && std::abs(l.y()) <= hx && l.z() >= za && l.z() <= zb;
    return n;
  }
  /// Collision points in a finger's box and path (ly in [y0, y1]; finger_ys_ sorted).
  int fingerCount(double y0, double y1) const {
    return static_cast<int>(std::upper_bound(finger_ys_.begin(), finger_ys_.end(), y1) -
                            std::lower_bound(finger_ys_.begin(), finger_ys_.end(), y0));
  }
  /// The finger beyond the wall, its inner face at yo: neither its volume nor its path in from
  /// approach_standoff above may lie behind a seen point (fingertip first: most likely hidden).
  bool outerFingerFree(double yo) const;
  /// Shadow samples of the seen-side finger's mid-plane at ym (4 of 15 tolerated) and the palm's
  /// face (3 of 9).
  bool seenSideHidden(double ym, double yc, double w) const;
  /// Gathers the points around p_ and measures the seen contact: where the finger first touches
  /// its points (the outermost after dropping one as noise, *y_in) and the median of their
  /// normals' cosines with -y (*cos_n); false with fewer than 3 such points.
  bool seenContact(double* y_in, double* cos_n);
  /// The middle of the wall's seen thickness between the fingers: from the seen contact y_in to
  /// the object's farthest point between the fingers short of the free bound y_free, if the top
  /// of what the view shows of the object there is at most band_ above the fingers (the rim's
  /// top seen from above: the wall's far edge seen, not where the view ends on a face that goes
  /// on up); else NaN.
  double seenMiddle(double y_in, double y_free) const;
  /// Whether the grasp centred at yc (the seen contact at y_in, the far finger's bound at yo)
  /// passes the open fingers' (1: no, try farther), the palm's and the hidden volume's checks
  /// (2: no; 0: yes).
  int placementRefused(double y_in, double yo, double yc) const;

  const GraspGeneratorConfig& cfg_;
  const GripperGeometry& g_;
  const WallInput& in_;
  const std::vector<Eigen::Vector3d>& collision_;
  const double cos_cone_;
  const Eigen::Vector3d up_;
  const double z1_, z0_, sweep_, band_;
  const int k_;
  Eigen::Vector3d p_, x_, y_, a_;
  std::vector<Eigen::Vector3d> near_;  ///< collision points around the seed, (y, x, z)
  std::vector<double> finger_ys_;      ///< y of those in the fingers' footprint and path, sorted
  /// (ly, cos) of the object's points in the fingers' reach, any distance from the seed (the
  /// seen contact's: within band_ of it, cos within the friction cone)
  std::vector<std::pair<double, double>> reach_;
  std::vector<std::pair<double, double>> strip_;  ///< (ly, lz) of the object's points above the fingertips
};

void WallSearch::gather() {
  near_.clear();
  const double ry = g_.max_width + g_.palm_width, rx = 0.5 * std::max(g_.palm_breadth, g_.finger_breadth);
  const double za = z0_ - g_.palm_height - sweep_;
  for (const Eigen::Vector3d& q : collision_) {
    const Eigen::Vector3d d = q - p_;
    const double ly = y_.dot(d), lx = x_.dot(d), lz = a_.dot(d);
    if (std::abs(ly) <= ry && std::abs(lx) <= rx && lz >= za && lz <= z1_) near_.emplace_back(ly, lx, lz);
  }
  finger_ys_.clear();
  for (const Eigen::Vector3d& l : near_)
    if (std::abs(l.y()) <= 0.5 * g_.finger_breadth && l.z() >= z0_ - sweep_) finger_ys_.push_back(l.x());
  std::sort(finger_ys_.begin(), finger_ys_.end());
  reach_.clear();
  strip_.clear();
  const auto& pts = *in_.points;
  for (std::size_t j = 0; j < pts.size(); ++j) {
    const Eigen::Vector3d d = pts[j] - p_;
    const double ly = y_.dot(d), lz = a_.dot(d);
    if (std::abs(x_.dot(d)) > 0.5 * g_.finger_breadth || lz > z1_ || std::abs(ly) > g_.max_width) continue;
    strip_.emplace_back(ly, lz);
    if (lz >= z0_) reach_.emplace_back(ly, -facing(j).dot(y_));
  }
}

bool WallSearch::outerFingerFree(double yo) const {
  const double b = g_.finger_breadth, t = g_.finger_thickness;
  for (double lz = z1_; lz >= z0_ - sweep_ - 1e-9; lz -= lz > z0_ ? 0.005 : 0.01)
    for (double fx : {0.0, -0.5, 0.5})
      for (double fy : {yo, yo + t})
        if (in_.shadow->mayBeSolid(world(fy, fx * b, lz))) return false;
  return true;
}

bool WallSearch::seenSideHidden(double ym, double yc, double w) const {
  int n = 0;
  for (double fx : {-0.4, 0.0, 0.4})
    for (int j = 0; j < 5; ++j) n += in_.shadow->mayBeSolid(world(ym, fx * g_.finger_breadth, z0_ + (z1_ - z0_) * j / 4.0));
  if (n >= 4) return true;
  n = 0;
  const double yp = std::min(0.5 * g_.palm_width, 0.5 * w + g_.finger_thickness);
  for (double fx : {-0.4, 0.0, 0.4})
    for (double fy : {-1.0, 0.0, 1.0}) n += in_.shadow->mayBeSolid(world(yc + fy * yp, fx * g_.palm_breadth, z0_));
  return n >= 3;
}

bool WallSearch::seenContact(double* y_in, double* cos_n) {
  gather();
  std::vector<double> ys, cs;
  for (const auto& l : reach_)
    if (std::abs(l.first) <= band_ && l.second >= cos_cone_) ys.push_back(l.first), cs.push_back(l.second);
  if (ys.size() < 3) return false;
  std::sort(ys.begin(), ys.end());
  std::nth_element(cs.begin(), cs.begin() + static_cast<long>(cs.size() / 2), cs.end());
  *y_in = ys[ys.size() >= 5 ? 1 : 0];
  *cos_n = cs[cs.size() / 2];
  return true;
}

double WallSearch::seenMiddle(double y_in, double y_free) const {
  const std::pair<double, double>* far = nullptr;
  double top = std::numeric_limits<double>::infinity();
  for (const auto& l : strip_) {
    if (l.first < y_in - band_ || l.first >= y_free) continue;
    top = std::min(top, l.second);
    if (l.first >= y_in && (!far || l.first > far->first)) far = &l;
  }
  if (!far || top < z0_ - band_) return std::numeric_limits<double>::quiet_NaN();
  return 0.5 * (y_in + far->first);
}

int WallSearch::placementRefused(double y_in, double yo, double yc) const {
  const double c = g_.clearance, t = g_.finger_thickness, W = g_.max_width;
  // The fingers come in fully open, centred on yc: both free there too.
  if (fingerCount(yc - 0.5 * W - t, yc - 0.5 * W) > 0 || fingerCount(yc + 0.5 * W, yc + 0.5 * W + t) > 0 ||
      !outerFingerFree(yc + 0.5 * W))
    return 1;
  // The palm and its path, then the hidden volume at the seen side's finger and the palm (its
  // face as wide as the opening reaching both sides from yc).
  const double w = 2.0 * std::max(yo - yc, yc - (y_in - c));
  if (countIn(yc - 0.5 * g_.palm_width, yc + 0.5 * g_.palm_width, 0.5 * g_.palm_breadth, z0_ - g_.palm_height - sweep_,
              z0_) > k_ ||
      seenSideHidden(y_in - c - 0.5 * t, yc, w) || seenSideHidden(yc - 0.5 * W - 0.5 * t, yc, w))
    return 2;
  return 0;
}

bool WallSearch::at(std::size_t i, double tilt, WallGrasp* out) {
  p_ = (*in_.points)[i];
  const Eigen::Vector3d n = facing(i);
  const Eigen::Vector3d nh = n - n.dot(up_) * up_;
  if (n.isZero() || nh.norm() < cos_cone_) return false;
  y_ = -nh.normalized();
  // Tilted about y: the approach's horizontal part across the wall, away from the eye.
  Eigen::Vector3d side = up_.cross(y_);
  if (side.dot(p_ - in_.eye) < 0.0) side = -side;
  a_ = -std::cos(tilt) * up_ + std::sin(tilt) * side;
  x_ = y_.cross(a_);
  // The fingertips stay support_clearance above the support.
  if (tipClearance() < cfg_.support_clearance) return false;
  double y_in = 0.0, cos_n = 0.0;
  if (!seenContact(&y_in, &cos_n)) return false;
  // The closing line at least 3 x the noise + half a voxel below the seen surface's top there
  // (a seed at the rim's edge would close on its noise above the rim), in height: moved along
  // the approach, tilted or not, until it is.
  double top = 0.0;  ///< height above the seed
  const double up_x = up_.dot(x_), up_a = up_.dot(a_);
  for (const Eigen::Vector3d& l : near_)
    if (std::abs(l.y()) <= 0.5 * g_.finger_breadth && l.x() >= y_in - band_ && l.x() <= y_in + 2.0 * band_)
      top = std::max(top, up_x * l.y() + up_a * l.z());
  const double below = 3.0 * in_.noise + 0.5 * in_.leaf;
  if (top < below) {
    p_ += a_ * ((below - top) / -up_a);
    if (tipClearance() < cfg_.support_clearance || !seenContact(&y_in, &cos_n)) return false;
  }
  const double c = g_.clearance, t = g_.finger_thickness, W = g_.max_width;
  // The seen-side finger and its path: nothing beyond the contact surface's noise. In the finger
  // itself, no seen surface facing away from it beyond its inner face, and none facing it more
  // than the noise beyond that face: the noise tolerance above is for the contact surface by the
  // seed, and a finger tilted along a cup's curved rim reaches 30-40 mm along it, where the
  // wall's face (its normal turned out of the friction cone), top and back face come 1.6-3.5 mm
  // into its far corner.
  if (fingerCount(y_in - c - t, y_in - 3.0 * in_.noise - 0.5 * in_.leaf) > k_) return false;
  const auto inside = [&](const std::pair<double, double>& l) {
    return l.first >= y_in - c - t && l.first < y_in - c - (l.second > 0.0 ? in_.noise : 0.0);
  };
  if (std::count_if(reach_.begin(), reach_.end(), inside) > k_) return false;
  // The other finger at the nearest position the view proves free (1 mm steps): no point seen in
  // it or its path (a seen point there contradicts the bound; none is tolerated as noise), none
  // of it behind a seen point.
  const double step = 0.001;
  // The centre: the middle of the wall's seen thickness where its far edge is seen (the fingers
  // then reach it together: a centre nearer one side pushes the object before the other
  // touches), within the opening; else the middle between the seen contact and the bound.
  for (double yo = y_in + c + std::max(step, 2.0 * in_.noise); yo <= y_in + W - c + 1e-9; yo += step) {
    if (fingerCount(yo - c, yo + t) > 0 || !outerFingerFree(yo)) continue;
    const double bound_middle = 0.5 * (yo + y_in - c), seen = seenMiddle(y_in, yo - c);
    // Fully open, the fingers reach the bound only from a centre at most half the opening short
    // of it: a wall whose bound lies farther is grasped as near its middle as that allows.
    const double yc = std::isfinite(seen) ? std::min(bound_middle, std::max(seen, yo - 0.5 * W)) : bound_middle;
    const int refused = placementRefused(y_in, yo, yc);
    if (refused == 1) continue;
    if (refused == 2) return false;
    out->R.col(1) = y_;
    out->R.col(2) = a_;
    out->R.col(0) = y_.cross(a_);
    out->c = p_ + y_ * yc;
    out->measured_width = yo - c - y_in;
    out->width = out->measured_width + 2.0 * c;
    out->contact_y = y_in - yc;
    out->cos_n = cos_n;
    return true;
  }
  return false;
}

}  // namespace

std::vector<WallGrasp> wallGrasps(const GraspGeneratorConfig& cfg, const WallInput& in,
                                  const std::vector<Eigen::Vector3d>& collision) {
  std::vector<WallGrasp> out;
  if (!in.shadow || !in.shadow->enabled() || cfg.wall_weight <= 0.0 || !in.points || !in.normals) return out;
  WallSearch search(cfg, in, collision);
  const double cos_cone = std::cos(std::atan(cfg.friction_coefficient));
  const Eigen::Vector3d up = in.plane.head<3>();
  std::vector<std::size_t> seeds;
  for (std::size_t i = 0; i < in.points->size(); ++i) {
    const Eigen::Vector3d n = search.facing(i);
    if (!n.isZero() && (n - n.dot(up) * up).norm() >= cos_cone) seeds.push_back(i);
  }
  // Evenly strided down to a quarter of max_seeds (deterministic).
  const std::size_t most = static_cast<std::size_t>(std::max(1, cfg.max_seeds / 4));
  const std::size_t stride = std::max<std::size_t>(1, (seeds.size() + most - 1) / most);
  std::vector<double> tilts{0.0};
  if (cfg.wall_tilt_deg > 0.0) tilts.push_back(cfg.wall_tilt_deg * M_PI / 180.0);
  for (std::size_t s = 0; s < seeds.size(); s += stride)
    for (double tilt : tilts) {
      WallGrasp w;
      if (search.at(seeds[s], tilt, &w)) out.push_back(w);
    }
  return out;
}

}  // namespace detail
}  // namespace ehc_perception
