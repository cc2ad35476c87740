// GraspGenerator (PCL translation unit 1 of 2). See grasp_generator.h for the method.
#include "ehc_perception/grasp_generator.h"

#include "ehc_common/config_node.h"
#include "ehc_common/enum_names.h"
#include "ehc_common/text_format.h"
#include "ehc_control/pose_math.h"
#include "ehc_perception/point_cloud_layout.h"
#include "scene_clusters.h"
#include "wall_grasps.h"

#include <Eigen/Eigenvalues>
#include <pcl/common/centroid.h>
#include <pcl/features/normal_3d.h>
#include <pcl/filters/extract_indices.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/segmentation/extract_clusters.h>
#include <pcl/segmentation/sac_segmentation.h>

#include <algorithm>
#include <array>
#include <tuple>
#include <map>
#include <cmath>
#include <numeric>
#include <random>
#include <sstream>
#include <stdexcept>

using ehc_common::ConfigNode;
using ehc_common::requireRange;

namespace ehc_perception {

namespace {

const char* kOwner = "GraspGenerator";

constexpr ehc_common::EnumNames<GraspFailure, 13> kFailureNames = {{
    {GraspFailure::None, "none"},
    {GraspFailure::EmptyCloud, "empty_cloud"},
    {GraspFailure::NoFinitePoints, "no_finite_points"},
    {GraspFailure::BadViewpoint, "bad_viewpoint"},
    {GraspFailure::TooFewPoints, "too_few_points"},
    {GraspFailure::BadSupportPlane, "bad_support_plane"},
    {GraspFailure::NoObject, "no_object"},
    {GraspFailure::TooWide, "too_wide"},
    {GraspFailure::NoAntipodalPair, "no_antipodal_pair"},
    {GraspFailure::Collides, "collides"},
    {GraspFailure::Friction, "friction"},
    {GraspFailure::HiddenVolume, "hidden_volume"},
    {GraspFailure::TargetTooFar, "target_too_far"},
}};
constexpr double kDeg = M_PI / 180.0;
/// An upright round body's fitted circle is at most this much wider than its seen footprint.
constexpr double kRoundFootprintRatio = 1.25;
/// A cloud with more of its points hidden behind others along the camera's rays is seen from
/// several sides (HiddenVolume::singleView).
constexpr double kMaxBehindFraction = 0.25;
/// deg: a single view's normal within this of perpendicular to its ray is seen at a grazing
/// angle, where the noise decides which way it faces (orientNormals).
constexpr double kGrazingDeg = 15.0;

using Cloud = pcl::PointCloud<pcl::PointXYZ>;
using Normals = pcl::PointCloud<pcl::Normal>;

[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument(std::string("[GraspGenerator] ") + what);
}

Cloud::Ptr toCloud(const PointList& pts, int* finite = nullptr) {
  Cloud::Ptr c(new Cloud);
  c->reserve(pts.size());
  for (const Eigen::Vector3f& p : pts)
    if (p.allFinite()) c->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
  c->width = static_cast<std::uint32_t>(c->size());
  c->height = 1;
  c->is_dense = true;
  if (finite) *finite = static_cast<int>(c->size());
  return c;
}

Cloud::Ptr voxelFilter(const Cloud::ConstPtr& in, double leaf) {
  Cloud::Ptr out(new Cloud);
  if (in->empty()) return out;
  pcl::VoxelGrid<pcl::PointXYZ> vg;
  vg.setInputCloud(in);
  const float l = static_cast<float>(leaf);
  vg.setLeafSize(l, l, l);
  vg.filter(*out);
  return out;
}

/// The voxel filter at `leaf`, with the leaf grown until at most `max_points` remain: every
/// occupied region keeps a point, only coarser, so the collision checks still see the whole
/// object. If the voxel grid cannot bring it down (PCL's VoxelGrid returns its input unfiltered
/// when the grid's indices would overflow, e.g. points kilometres apart), an even stride
/// (budgetPoints) does. `used` receives the leaf of the result.
Cloud::Ptr boundedVoxelFilter(const Cloud::ConstPtr& in, double leaf, std::size_t max_points, double* used) {
  Cloud::Ptr out = voxelFilter(in, leaf);
  // A surface's voxel count falls with the square of the leaf, a volume's with the cube: the
  // square root of the excess reaches the bound in one step on a surface, in a few on a volume.
  for (int k = 0; k < 8 && out->size() > max_points; ++k) {
    leaf *= 1.01 * std::sqrt(static_cast<double>(out->size()) / static_cast<double>(max_points));
    out = voxelFilter(in, leaf);
  }
  *used = leaf;
  if (out->size() <= max_points) return out;
  PointList pts;
  pts.reserve(out->size());
  for (const auto& p : *out) pts.push_back(p.getVector3fMap());
  return toCloud(budgetPoints(pts, max_points));
}

Eigen::Vector3d pt(const Cloud& c, int i) {
  return c[static_cast<std::size_t>(i)].getVector3fMap().cast<double>();
}

/// Orthonormal bases of the principal subspaces (axes with similar spread are merged).
std::vector<Eigen::MatrixXd> principalSubspaces(const Eigen::Matrix3d& cov, double ratio) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
  const Eigen::Vector3d sd = es.eigenvalues().cwiseMax(0.0).cwiseSqrt();  // ascending
  const Eigen::Matrix3d V = es.eigenvectors();
  std::vector<Eigen::MatrixXd> out;
  int k = 0;
  while (k < 3) {
    int e = k + 1;
    while (e < 3 && sd[e] > 0 && sd[e - 1] / sd[e] >= ratio) ++e;
    out.push_back(V.middleCols(k, e - k));
    k = e;
  }
  return out;
}

double alignment(const std::vector<Eigen::MatrixXd>& subspaces, const Eigen::Vector3d& u) {
  double best = 0.0;
  for (const Eigen::MatrixXd& S : subspaces) best = std::max(best, (S.transpose() * u).norm());
  return std::min(best, 1.0);
}

/// Lowest and highest of `v` after dropping the k most extreme values on each side (noise).
std::pair<double, double> trimmedRange(std::vector<double>& v, std::size_t k) {
  if (v.empty()) return {0.0, 0.0};
  k = std::min(k, (v.size() - 1) / 2);
  std::nth_element(v.begin(), v.begin() + static_cast<long>(k), v.end());
  const double lo = v[k];
  std::nth_element(v.begin(), v.end() - 1 - static_cast<long>(k), v.end());
  return {lo, v[v.size() - 1 - k]};
}

/// Two points on the object's surface that bound it across a closing axis where the cloud does
/// not show it (a round cross-section completed by its fitted circle, see roundCrossSection).
struct ExtentHint {
  bool valid = false;
  Eigen::Vector3d a = Eigen::Vector3d::Zero(), b = Eigen::Vector3d::Zero();
};

/// An object point near a grasp with its estimated surface normal (sign-free).
struct SurfacePoint {
  Eigen::Vector3d p, n;
};

/// One side of the object along a grasp's closing axis, as measured between the fingers.
struct ContactSide {
  bool seen = false;     ///< fitted from the points whose normals face along the closing axis
  /// Fitted, but the fitted surface's normal at the contact is outside the friction cone: the
  /// finger would touch it and slip (not `seen`).
  bool slips = false;
  double y = 0.0;        ///< position along the closing axis (grasp-local, from c0)
  double cos_n = 0.0;    ///< |cos| of the fitted surface's normal at the contact and the axis
};

/// The two contact surfaces of a grasp (see ContactSurfaceFit).
struct Measurement {
  ContactSide side[2];   ///< [0]: towards -y, [1]: towards +y
  double width = 0.0;    ///< m, side[1].y - side[0].y
  int seen() const { return side[0].seen + side[1].seen; }
};

/// The contact surfaces' fit: the object's points in the fingers' slab whose estimated outward
/// normal lies within the friction cone of the closing axis y and that are near one side's
/// outermost points are that side's contact patch; the patch is fitted by least squares with a
/// surface
/// y = a + b x + c x^2 + d z + e z^2 over the finger's breadth (x) and length (z) (a flat face
/// or a curved one: a cylinder's mantle, a ball), refitted without the points beyond 3 RMS,
/// and the side's position is the fitted surface's outermost value over the finger's footprint
/// (where the finger first touches it). Noise averages out in the fit instead of pushing the
/// extreme points outwards: a 66 mm cylinder under 2 mm noise measures 66 mm, not 75. The
/// contact's quality is the cosine of the fitted surface's normal there with the axis. Without
/// such a patch, if the outermost points face the finger at a slant (normals within
/// slanted_contact_deg of the axis) the view shows a contact outside the friction cone: the
/// side slips; else the side is unseen.
class ContactSurfaceFit {
 public:
  ContactSurfaceFit(double cos_cone, double cos_slanted, int min_points, double noise, double leaf)
      : cos_cone_(cos_cone), cos_slanted_(cos_slanted), min_points_(min_points), band_(4.0 * noise + 2.0 * leaf) {}

  /// `pts`: (y, x, z) grasp-local coordinates of the object's points in the slab and `ny` the
  /// cos of their outward normals with y; `lo`, `hi`: the trimmed extremes along y. Side `s`
  /// (+1: +y, -1: -y).
  ContactSide fit(const std::vector<Eigen::Vector3d>& pts, const std::vector<double>& ny, double lo,
                  double hi, int s) const {
    ContactSide out;
    const double mid = 0.5 * (lo + hi), outer = s > 0 ? hi : lo;
    std::vector<const Eigen::Vector3d*> patch;
    int slanted = 0;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const double y = pts[i].x();
      if (s * (y - mid) <= 0.0 || s * (outer - y) > band_ || s * ny[i] < cos_slanted_) continue;
      if (s * ny[i] >= cos_cone_) patch.push_back(&pts[i]);
      else ++slanted;
    }
    Eigen::Matrix<double, 5, 1> c;
    out.slips = static_cast<int>(patch.size()) < min_points_ && slanted >= min_points_;
    if (static_cast<int>(patch.size()) < min_points_ || !solve(patch, &c)) return out;
    // Refit without the points farther than 3 RMS from the first fit (flying pixels, strays).
    double ss = 0.0;
    for (const auto* q : patch) ss += std::pow(q->x() - value(c, q->y(), q->z()), 2);
    const double cut = 3.0 * std::sqrt(ss / static_cast<double>(patch.size())) + 1e-6;
    std::vector<const Eigen::Vector3d*> kept;
    for (const auto* q : patch)
      if (std::abs(q->x() - value(c, q->y(), q->z())) <= cut) kept.push_back(q);
    if (static_cast<int>(kept.size()) < min_points_ || !solve(kept, &c)) return out;
    // Where the fingers touch: along x and along z (separable terms) the fitted surface's
    // vertex where it bends away from the finger significantly (more than twice its standard
    // error) inside the footprint, a cylinder's or a ball's crest; the outer end of a
    // significant slope (a face tilted from the closing axis); else the patch's mean (a flat
    // face: its mean position; the maximum of a noisy fit would be biased out).
    Eigen::Matrix<double, 5, 5> A = Eigen::Matrix<double, 5, 5>::Zero();
    double x0 = kept[0]->y(), x1 = x0, z0 = kept[0]->z(), z1 = z0, xm = 0.0, zm = 0.0, res = 0.0;
    for (const auto* q : kept) {
      Eigen::Matrix<double, 5, 1> r;
      r << 1.0, q->y(), q->y() * q->y(), q->z(), q->z() * q->z();
      A += r * r.transpose();
      x0 = std::min(x0, q->y());
      x1 = std::max(x1, q->y());
      z0 = std::min(z0, q->z());
      z1 = std::max(z1, q->z());
      xm += q->y();
      zm += q->z();
      res += std::pow(q->x() - value(c, q->y(), q->z()), 2);
    }
    const double n = static_cast<double>(kept.size());
    const double var = res / std::max(1.0, n - 5.0);
    const Eigen::Matrix<double, 5, 5> cov = A.inverse() * var;
    auto se = [&](int i) { return std::sqrt(std::max(0.0, cov(i, i))); };
    const double x = crest(c[1], c[2], se(1), se(2), x0, x1, xm / n, s);
    const double z = crest(c[3], c[4], se(3), se(4), z0, z1, zm / n, s);
    out.y = value(c, x, z);
    // The fitted surface's normal at the contact, against the friction cone.
    out.cos_n = 1.0 / std::hypot(1.0, std::hypot(c[1] + 2.0 * c[2] * x, c[3] + 2.0 * c[4] * z));
    out.seen = out.cos_n >= cos_cone_;
    out.slips = !out.seen;  // a fitted slope beyond the cone (the points' normals within it)
    return out;
  }

 private:
  static double value(const Eigen::Matrix<double, 5, 1>& c, double x, double z) {
    return c[0] + c[1] * x + c[2] * x * x + c[3] * z + c[4] * z * z;
  }
  /// Where b t + a t^2 reaches farthest towards side s on [t0, t1], counting only terms that
  /// are significant (more than twice their standard errors se_b, se_a): a crest (s a < 0)
  /// inside the range; else the outer end of a significant slope (a tilted face); else `mean`.
  static double crest(double b, double a, double se_b, double se_a, double t0, double t1, double mean, int s) {
    if (s * a < 0.0 && std::abs(a) > 2.0 * se_a) {
      const double tv = -b / (2.0 * a);
      if (tv >= t0 && tv <= t1) return tv;
    }
    if (std::abs(b) > 2.0 * se_b) return s * b > 0.0 ? t1 : t0;
    return mean;
  }
  /// Least squares with a small ridge on the slope and curvature terms (a patch along one
  /// direction only leaves the other's terms at 0 instead of undetermined).
  static bool solve(const std::vector<const Eigen::Vector3d*>& pts, Eigen::Matrix<double, 5, 1>* c) {
    Eigen::Matrix<double, 5, 5> A = Eigen::Matrix<double, 5, 5>::Zero();
    Eigen::Matrix<double, 5, 1> b = Eigen::Matrix<double, 5, 1>::Zero();
    for (const auto* q : pts) {
      Eigen::Matrix<double, 5, 1> r;
      r << 1.0, q->y(), q->y() * q->y(), q->z(), q->z() * q->z();
      A += r * r.transpose();
      b += r * q->x();
    }
    const double n = static_cast<double>(pts.size());
    A(1, 1) += 1e-6 * n;  // (1 mm)^2 per point
    A(3, 3) += 1e-6 * n;
    A(2, 2) += 1e-10 * n;
    A(4, 4) += 1e-10 * n;
    *c = A.ldlt().solve(b);
    return c->allFinite();
  }

  double cos_cone_, cos_slanted_;
  int min_points_;
  double band_;
};

struct Candidate {
  Eigen::Matrix3d R;
  Eigen::Vector3d c;
  double width = 0, antipodal = 0, wc = 0, wp = 0, score = 0;
  double q = 0;         ///< the hypothesis's antipodal quality
  Measurement m;        ///< the contact surfaces between the fingers
  bool single = false;  ///< single-contact hypothesis (width from the object's extent)
  bool wall = false;    ///< wall grasp (wall_grasps.h: measured there, not refined)
  ExtentHint hint;      ///< completes the object's extent (footprint hypotheses)
};

/// Antipodal quality of a measured grasp: the fitted contacts' normals (min |cos| with the
/// closing axis) where both sides were fitted; otherwise the hypothesis's quality, at most
/// single_contact_weight (a contact the view does not show ranks below seen ones), or halfway
/// from it to 1 for a side completed by a fitted circle or sphere (`completed`).
double supportedQuality(double q, const Measurement& m, double single_weight, bool completed) {
  if (m.seen() == 2) return std::min(m.side[0].cos_n, m.side[1].cos_n);
  const double seen_cos = m.side[0].seen ? m.side[0].cos_n : m.side[1].seen ? m.side[1].cos_n : 1.0;
  // An unseen side bounded by a fitted circle or sphere is supported by the shape's fit:
  // between seen and merely bounded ones.
  return std::min(q, completed ? 0.5 * (1.0 + single_weight) : single_weight) * seen_cos;
}

/// The volume the view hides: along the rays from the camera, behind the object's points whose
/// outward normal faces the camera (where a ray enters the object) and not behind a point facing
/// away (where it leaves, seen in clouds of several views). A range image over the directions
/// from the camera (bins of 1.5 voxels at the object's distance) holds per bin the nearest
/// entering and the farthest leaving point. A point is hidden if it is more than `margin`
/// behind the entering surface in its bin and in the four bins around it (the shadow eroded by
/// a bin: a finger beside a surface seen at a grazing angle is not in it), and not less than
/// `margin` in front of a leaving surface there (inside the object). Disabled (nothing hidden)
/// without a camera. `normals` are oriented outwards (orientNormals). A single view (a depth
/// image) has no point behind another along a ray: singleView() if at most kMaxBehindFraction of
/// the points are more than `margin` behind the nearest point of their bin (a grazing surface's
/// samples may be; a cloud seen from several sides shows its far side behind its near one).
class HiddenVolume {
 public:
  HiddenVolume() = default;
  HiddenVolume(const Cloud& cloud, const Normals& normals, const Eigen::Vector3d& centroid, const Eigen::Vector3d& eye,
               double leaf, double margin) {
    const Eigen::Vector3d d0 = centroid - eye;
    if (d0.norm() < 1e-6) return;
    eye_ = eye;
    fwd_ = d0.normalized();
    e1_ = fwd_.unitOrthogonal();
    e2_ = fwd_.cross(e1_);
    res_ = 1.5 * leaf / d0.norm();
    margin_ = margin;
    double u1 = -1e9, v1 = -1e9;
    u0_ = v0_ = 1e9;
    for (const auto& pf : cloud) {
      double u = 0, v = 0, r = 0;
      if (!project(pf.getVector3fMap().cast<double>(), &u, &v, &r)) continue;
      u0_ = std::min(u0_, u), v0_ = std::min(v0_, v), u1 = std::max(u1, u), v1 = std::max(v1, v);
    }
    if (u1 < u0_) return;
    res_ = std::max({res_, (u1 - u0_) / 511.0, (v1 - v0_) / 511.0});  // at most 512 x 512 bins
    nu_ = static_cast<int>((u1 - u0_) / res_) + 1;
    nv_ = static_cast<int>((v1 - v0_) / res_) + 1;
    entry_.assign(static_cast<std::size_t>(nu_ * nv_), std::numeric_limits<float>::infinity());
    exit_.assign(entry_.size(), -std::numeric_limits<float>::infinity());
    std::vector<float> front(entry_.size(), std::numeric_limits<float>::infinity());
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      const Eigen::Vector3d p = cloud[i].getVector3fMap().cast<double>();
      const Eigen::Vector3d n = normals[i].getNormalVector3fMap().cast<double>();
      int k = 0;
      double r = 0;
      if (!bin(p, 0, 0, &k, &r)) continue;
      front[static_cast<std::size_t>(k)] = std::min(front[static_cast<std::size_t>(k)], static_cast<float>(r));
      if (!n.allFinite() || n.norm() < 0.5) continue;
      float& e = n.dot(eye - p) > 0 ? entry_[static_cast<std::size_t>(k)] : exit_[static_cast<std::size_t>(k)];
      e = n.dot(eye - p) > 0 ? std::min(e, static_cast<float>(r)) : std::max(e, static_cast<float>(r));
    }
    std::size_t behind = 0, binned = 0;
    for (const auto& pf : cloud) {
      int k = 0;
      double r = 0;
      if (!bin(pf.getVector3fMap().cast<double>(), 0, 0, &k, &r)) continue;
      ++binned;
      behind += r > front[static_cast<std::size_t>(k)] + margin_;
    }
    single_view_ = static_cast<double>(behind) <= kMaxBehindFraction * static_cast<double>(binned);
    enabled_ = true;
  }
  bool enabled() const { return enabled_; }
  /// The cloud is one view from the camera (see the class comment); false when disabled.
  bool singleView() const { return enabled_ && single_view_; }
  bool hidden(const Eigen::Vector3d& q) const {
    if (!enabled_) return false;
    static const int du[5] = {0, 1, -1, 0, 0}, dv[5] = {0, 0, 0, 1, -1};
    for (int j = 0; j < 5; ++j) {
      int k = 0;
      double r = 0;
      if (!bin(q, du[j], dv[j], &k, &r)) return false;
      const double behind = r - margin_;
      const float entry = entry_[static_cast<std::size_t>(k)], exit = exit_[static_cast<std::size_t>(k)];
      // Not behind an entering surface, or not in front of a leaving one (in any of the five
      // bins: the bins are coarser than a finger's distance to the surface it closes on).
      if (!(entry < behind) || (exit > entry - margin_ && exit < r + margin_)) return false;
    }
    return true;
  }

 private:
  bool project(const Eigen::Vector3d& p, double* u, double* v, double* r) const {
    const Eigen::Vector3d d = p - eye_;
    const double z = d.dot(fwd_);
    if (z <= 1e-6) return false;
    *u = d.dot(e1_) / z;
    *v = d.dot(e2_) / z;
    *r = d.norm();
    return true;
  }
  /// The bin of q's direction, offset by (du, dv) bins, and q's range.
  bool bin(const Eigen::Vector3d& q, int du, int dv, int* k, double* r) const {
    double u = 0, v = 0;
    if (!project(q, &u, &v, r)) return false;
    const int iu = static_cast<int>(std::floor((u - u0_) / res_)) + du, iv = static_cast<int>(std::floor((v - v0_) / res_)) + dv;
    if (iu < 0 || iv < 0 || iu >= nu_ || iv >= nv_) return false;
    *k = iv * nu_ + iu;
    return true;
  }

  bool enabled_ = false, single_view_ = false;
  Eigen::Vector3d eye_ = Eigen::Vector3d::Zero(), fwd_ = Eigen::Vector3d::UnitZ(), e1_ = Eigen::Vector3d::UnitX(),
                  e2_ = Eigen::Vector3d::UnitY();
  double res_ = 1.0, u0_ = 0, v0_ = 0, margin_ = 0;
  int nu_ = 0, nv_ = 0;
  std::vector<float> entry_, exit_;
};

/// What became of a gripper pose in GripperCheck::evaluate (the first check it failed).
enum class CheckOutcome {
  Pass,
  TooFewPoints,  ///< too few object points between the fingers, or one surface's noise
  TooWide,       ///< the measured width needs more than the opening
  Friction,      ///< a contact the view shows is outside the friction cone
  Collides,      ///< fingers or palm hit the cloud
  Support,       ///< fingers or palm come nearer the support than support_clearance
  Hidden,        ///< a finger at a seen contact, or the palm, is in the volume the view hides
};
constexpr int kOutcomes = 7;

/// Evaluates the gripper at (R, c0): centres it along the closing axis on the object between
/// the fingers, measures it there (ContactSurfaceFit), checks width, friction, finger / palm
/// collisions, the support plane and the hidden volume.
class GripperCheck {
 public:
  /// `noise`: the object cloud's estimated noise (m, see estimateNoise), `leaf` its voxel edge.
  /// `spacing`: its sample spacing (sampleSpacing): min_points_between_fingers holds at the
  /// voxel grid's density (voxel_size); a sparser cloud needs as much of the object's surface
  /// between the fingers, in fewer points (the count scaled by the squared spacing ratio, at
  /// least 3).
  GripperCheck(const GraspGeneratorConfig& cfg, const Eigen::Vector4d& plane, bool has_plane, double noise,
               double leaf, double spacing, const HiddenVolume& hidden)
      : cfg_(cfg), g_(cfg.gripper), plane_(plane), has_plane_(has_plane), noise_(noise), hidden_(hidden), leaf_(leaf),
        gap_(2.0 * std::max(spacing, leaf) + 2.0 * noise),
        density_(std::pow(cfg.voxel_size / std::max(spacing, cfg.voxel_size), 2)),
        min_between_(std::max(std::min(3, cfg.min_points_between_fingers),
                              static_cast<int>(std::lround(cfg.min_points_between_fingers *
                                                           std::pow(cfg.voxel_size / std::max(spacing, cfg.voxel_size), 2))))),
        fit_(std::cos(std::atan(cfg.friction_coefficient)), std::cos(cfg.slanted_contact_deg * kDeg),
             cfg.min_contact_points, noise, leaf) {}

  /// A closing axis y at c0 with the neighbourhood expressed in its (y, u, v) frame (u, v
  /// span the approach plane, v = y x u).
  struct Prepared {
    Eigen::Vector3d c0 = Eigen::Vector3d::Zero(), y = Eigen::Vector3d::Zero(), u = Eigen::Vector3d::Zero(),
                    v = Eigen::Vector3d::Zero();
    std::vector<Eigen::Vector3d> local;  ///< (y, u, v) coordinates of reachable points
    std::vector<Eigen::Vector3d> surface;    ///< (y, u, v) of the object's reachable points
    std::vector<Eigen::Vector3d> surface_n;  ///< their normals in (y, u, v)
    /// Bound unseen sides by the object's extent along y (ext_min / ext_max), computed when a
    /// side first needs it (extentOf) unless a fitted completion gives it.
    mutable bool use_extent = false;
    mutable bool extent_pending = false;
    const Cloud* object = nullptr;
    bool too_wide = false;               ///< object extent along y exceeds the opening
    mutable double ext_min = 0, ext_max = 0;
    bool hint = false;                   ///< ext_min / ext_max are a fitted circle's or sphere's
    /// A contact pair's hypothesis: both sides were seen by the pair's points; a side the
    /// measurement does not see is bounded by the last samples only (see inHiddenVolume).
    bool pair = false;
  };

  /// Drops points no gripper pose around y can touch. `object`: the object's points; with
  /// `bound_by_extent` (single-contact and footprint hypotheses) their extent along y bounds the
  /// part of the object between the fingers where a side is not seen (else the hypothesis is a
  /// contact pair's). `surface`: the object's points near c0 with their normals.
  void prepare(const Eigen::Vector3d& c0, const Eigen::Vector3d& y, const Eigen::Vector3d& u,
               const std::vector<Eigen::Vector3d>& nbrs, const std::vector<SurfacePoint>& surface,
               const Cloud& object, bool bound_by_extent, const ExtentHint& hint, Prepared* pr) {
    pr->c0 = c0;
    pr->y = y;
    pr->u = u;
    pr->v = y.cross(u);
    pr->use_extent = false;
    pr->too_wide = false;
    pr->hint = false;
    pr->pair = !bound_by_extent;
    pr->object = &object;
    pr->extent_pending = bound_by_extent && !hint.valid;
    if (hint.valid) {
      const double ha = y.dot(hint.a - c0), hb = y.dot(hint.b - c0);
      pr->ext_min = std::min(ha, hb);
      pr->ext_max = std::max(ha, hb);
      pr->use_extent = pr->hint = true;
    }
    if (pr->use_extent) {
      // Only a fitted completion is a measurement of the width; the raw extent bounds unseen
      // sides only (the seen ones are fitted between the fingers, see evaluate).
      pr->too_wide = pr->hint && pr->ext_max - pr->ext_min + 2.0 * g_.clearance > g_.max_width;
      if (pr->too_wide) return;
    }
    const double W = g_.max_width, t = g_.finger_thickness;
    const double ymax = std::max(W + 2 * t, 0.5 * g_.palm_width + 0.5 * W);
    const double zmax = std::max(g_.finger_tip_depth, g_.finger_length + g_.palm_height -
                                                          g_.finger_tip_depth);
    const double xmax = 0.5 * std::max(g_.finger_breadth, g_.palm_breadth);
    const double r2 = zmax * zmax + xmax * xmax;
    auto toLocal = [&](const Eigen::Vector3d& p, Eigen::Vector3d* l) {
      const Eigen::Vector3d d = p - c0;
      const double py = y.dot(d);
      if (std::abs(py) > ymax) return false;
      const double pu = u.dot(d), pv = pr->v.dot(d);
      if (pu * pu + pv * pv > r2) return false;
      *l = Eigen::Vector3d(py, pu, pv);
      return true;
    };
    pr->local.clear();
    pr->local.reserve(nbrs.size());
    pr->surface.reserve(surface.size());
    pr->surface_n.reserve(surface.size());
    Eigen::Vector3d l;
    for (const Eigen::Vector3d& p : nbrs)
      if (toLocal(p, &l)) pr->local.push_back(l);
    pr->surface.clear();
    pr->surface_n.clear();
    for (const SurfacePoint& sp : surface)
      if (toLocal(sp.p, &l)) {
        pr->surface.push_back(l);
        pr->surface_n.emplace_back(y.dot(sp.n), u.dot(sp.n), pr->v.dot(sp.n));
      }
  }

  /// Gripper with approach a = cos(phi) u + sin(phi) v: centres it along y on the object
  /// between the fingers (measured by its contact surfaces), checks the opening, finger / palm
  /// collisions and the support plane.
  CheckOutcome evaluate(const Prepared& pr, double cphi, double sphi, Eigen::Matrix3d* Rout,
                        Eigen::Vector3d* c, double* width, Measurement* m);

 private:
  /// The object's points in the fingers' slab in grasp coordinates (y, x, z) with the cos of
  /// their outward normals with y, into slab_ / slab_ny_.
  void surfaceInSlab(const Prepared& pr, double cphi, double sphi);
  /// The two sides: fitted where the view shows them (ContactSurfaceFit), else bounded by
  /// the fitted completion, or by the trimmed extremes of the points between the fingers and
  /// the object's extent. Friction if the view shows a side outside the friction cone.
  CheckOutcome measure(const Prepared& pr, double lo, double hi, int k, Measurement* m) const;
  /// Where the points under the fingers (ys_, out to the fingers' outer faces) running on from
  /// `bound` towards side s (+1: +y) end: each within gap_ of the one before (two samples apart
  /// and the noise), the k most extreme of them dropped as noise (k at the voxel grid's density;
  /// a sparser cloud's sample stands for more surface: k x density_). A side bounded by the
  /// last samples between the fingers is not there if the surface runs on past the opening's
  /// edge (a bar lying along the closing axis): its last samples lie under a finger or beyond.
  double continued(double bound, int s, int k) const;
  /// The object's extent along y for unseen sides (single-contact and footprint hypotheses):
  /// the object rests on the support, so the unseen volume below each seen point, down to the
  /// support, may be object too (single views miss the lower far side). Its extent along y is
  /// that of the points and of their projections onto the support (k most extreme per side
  /// dropped as noise). Computed once per prepared closing axis, when first needed.
  void extentOf(const Prepared& pr) const;
  /// Collisions of the fingers and palm (grasp frame R, centre, opening w) with the cloud and
  /// the support.
  CheckOutcome collides(const Eigen::Matrix3d& R, const Eigen::Vector3d& centre, double yc, double ymin,
                        double ymax, double w, int k) const;
  /// Fingers at seen contacts, or at a contact pair's side bounded by its last samples only, or
  /// the palm in the hidden volume (a quarter of their samples).
  bool inHiddenVolume(const Prepared& pr, const Eigen::Matrix3d& R, const Eigen::Vector3d& centre, double w,
                      const Measurement& m) const;
  /// A finger (frame R, the middle of its inner face at `at`, closing towards -s y) in the
  /// hidden volume: 4 of the 3 x 5 points of its mid-plane.
  bool fingerHidden(const Eigen::Matrix3d& R, const Eigen::Vector3d& at, int s) const;

  const GraspGeneratorConfig& cfg_;
  const GripperGeometry& g_;
  Eigen::Vector4d plane_;
  bool has_plane_;
  double noise_;
  const HiddenVolume& hidden_;
  double leaf_;
  double gap_;       ///< m, the largest gap between samples of one surface (see continued)
  double density_;   ///< the cloud's density over the voxel grid's, at most 1 (see the constructor)
  int min_between_;  ///< object points needed between the fingers (see the constructor)
  ContactSurfaceFit fit_;
  std::vector<double> ys_, inner_, palm_;
  mutable std::vector<double> ext_, run_;
  std::vector<Eigen::Vector3d> slab_;
  std::vector<double> slab_ny_;
};

void GripperCheck::surfaceInSlab(const Prepared& pr, double cphi, double sphi) {
  const double z1 = g_.finger_tip_depth, z0 = z1 - g_.finger_length;
  slab_.clear();
  slab_ny_.clear();
  for (std::size_t i = 0; i < pr.surface.size(); ++i) {
    const Eigen::Vector3d& l = pr.surface[i];
    const double qz = cphi * l.y() + sphi * l.z();
    const double qx = cphi * l.z() - sphi * l.y();
    // Across the closing axis up to the fingers' outer faces: a side near the opening's edge
    // keeps its noise beyond it (cut there, its fit would be biased inwards).
    if (qz > z1 || qz < z0 || std::abs(qx) > 0.5 * g_.finger_breadth ||
        std::abs(l.x()) > 0.5 * g_.max_width + g_.finger_thickness)
      continue;
    slab_.emplace_back(l.x(), qx, qz);
    slab_ny_.push_back(pr.surface_n[i].x());
  }
}

void GripperCheck::extentOf(const Prepared& pr) const {
  pr.extent_pending = false;
  ext_.clear();
  const double yn = has_plane_ ? pr.y.dot(plane_.head<3>()) : 0.0;
  for (const auto& pf : *pr.object) {
    const Eigen::Vector3d p = pf.getVector3fMap().cast<double>();
    const double e = pr.y.dot(p - pr.c0);
    ext_.push_back(e);
    if (has_plane_ && std::abs(yn) > 1e-9) ext_.push_back(e - (plane_.head<3>().dot(p) + plane_[3]) * yn);
  }
  const std::size_t k = static_cast<std::size_t>(cfg_.max_collision_points);
  if (ext_.size() <= 2 * k + 1) return;
  std::tie(pr.ext_min, pr.ext_max) = trimmedRange(ext_, k);
  pr.use_extent = true;
}

double GripperCheck::continued(double bound, int s, int k) const {
  run_.clear();
  for (double y : ys_)
    if (s * (y - bound) > 0.0) run_.push_back(s * (y - bound));
  std::sort(run_.begin(), run_.end());
  std::size_t n = 0;
  for (double prev = 0.0; n < run_.size() && run_[n] - prev <= gap_; ++n) prev = run_[n];
  const auto kk = static_cast<std::size_t>(std::max(0L, std::lround(k * density_)));
  return n > kk ? bound + s * run_[n - 1 - kk] : bound;
}

CheckOutcome GripperCheck::measure(const Prepared& pr, double lo, double hi, int k, Measurement* m) const {
  for (int i = 0; i < 2; ++i) {
    const int s = i == 0 ? -1 : 1;
    ContactSide& side = m->side[i];
    side = fit_.fit(slab_, slab_ny_, lo, hi, s);
    if (side.seen) continue;
    if (pr.hint) {  // the completion's extreme is the contact, beyond the seen slope
      side.y = s > 0 ? pr.ext_max : pr.ext_min;
      continue;
    }
    if (side.slips) return CheckOutcome::Friction;
    if (pr.extent_pending) extentOf(pr);
    // Bounded by the last samples of the surfaces running up to it (a top face's far edge):
    // their trimmed extreme, short of the true side by up to one sample spacing; where they
    // run on past the opening's edge, their end under or beyond the finger (continued).
    side.y = continued(s > 0 ? hi : lo, s, k);
    if (pr.use_extent) side.y = s > 0 ? std::max(side.y, pr.ext_max) : std::min(side.y, pr.ext_min);
  }
  m->width = m->side[1].y - m->side[0].y;
  // Two sides closer than the noise can tell apart are one surface's noise.
  return m->width > 4.0 * noise_ ? CheckOutcome::Pass : CheckOutcome::TooFewPoints;
}

CheckOutcome GripperCheck::evaluate(const Prepared& pr, double cphi, double sphi, Eigen::Matrix3d* Rout,
                                    Eigen::Vector3d* c, double* width, Measurement* m) {
  const double z1 = g_.finger_tip_depth, z0 = z1 - g_.finger_length;
  const double zp = z0 - g_.palm_height;
  const double W = g_.max_width, t = g_.finger_thickness;
  if (pr.too_wide) {
    m->width = pr.ext_max - pr.ext_min;
    return CheckOutcome::TooWide;
  }
  ys_.clear();
  inner_.clear();
  palm_.clear();
  for (const Eigen::Vector3d& l : pr.local) {
    const double qz = cphi * l.y() + sphi * l.z();
    if (qz > z1 || qz < zp) continue;
    const double qx = cphi * l.z() - sphi * l.y();
    const double qy = l.x();
    if (qz >= z0) {
      if (std::abs(qx) <= 0.5 * g_.finger_breadth && std::abs(qy) <= W + 2 * t) {
        ys_.push_back(qy);
        if (std::abs(qy) <= 0.5 * W) inner_.push_back(qy);
      }
    } else if (std::abs(qx) <= 0.5 * g_.palm_breadth &&
               std::abs(qy) <= 0.5 * g_.palm_width + 0.5 * W) {
      palm_.push_back(qy);
    }
  }
  Eigen::Matrix3d R;
  R.col(1) = pr.y;
  R.col(2) = cphi * pr.u + sphi * pr.v;
  R.col(0) = cphi * pr.v - sphi * pr.u;
  // Outliers tolerated per side: max_collision_points, or outlier_fraction of the points.
  const int k = std::max(cfg_.max_collision_points,
                         static_cast<int>(cfg_.outlier_fraction * inner_.size()));
  if (static_cast<int>(inner_.size()) < min_between_ + 2 * k) return CheckOutcome::TooFewPoints;
  // What is between the fingers: its trimmed extremes (the k most extreme points per side are
  // noise) locate the two sides; their contact surfaces measure them.
  const auto kk = static_cast<long>(k);
  std::nth_element(inner_.begin(), inner_.begin() + kk, inner_.end());
  const double lo = inner_[static_cast<std::size_t>(k)];
  std::nth_element(inner_.begin(), inner_.end() - 1 - kk, inner_.end());
  const double hi = inner_[inner_.size() - 1 - static_cast<std::size_t>(k)];
  surfaceInSlab(pr, cphi, sphi);
  const CheckOutcome measured = measure(pr, lo, hi, k, m);
  if (measured != CheckOutcome::Pass) return measured;
  const double ymin = m->side[0].y, ymax = m->side[1].y;
  const double w = ymax - ymin + 2.0 * g_.clearance;
  if (w > W) return CheckOutcome::TooWide;  // m->width: the measured width
  const double yc = 0.5 * (ymin + ymax);
  const Eigen::Vector3d centre = pr.c0 + R.col(1) * yc;
  const CheckOutcome collision = collides(R, centre, yc, ymin, ymax, w, k);
  if (collision != CheckOutcome::Pass) return collision;
  if (inHiddenVolume(pr, R, centre, w, *m)) return CheckOutcome::Hidden;
  *Rout = R;
  *c = centre;
  *width = w;
  return CheckOutcome::Pass;
}

CheckOutcome GripperCheck::collides(const Eigen::Matrix3d& R, const Eigen::Vector3d& centre, double yc,
                                    double ymin, double ymax, double w, int k) const {
  const double z1 = g_.finger_tip_depth, z0 = z1 - g_.finger_length;
  const double zp = z0 - g_.palm_height;
  // Points under the fingers or in the clearance gap, beyond the measured sides by more than
  // the noise (3 x the cloud's estimated noise: points of the contact surfaces themselves).
  const double half = 0.5 * (ymax - ymin) + 3.0 * noise_;
  int finger_hits = 0;
  for (double y : ys_) {
    const double d = std::abs(y - yc);
    if (d > half + 1e-9 && d <= 0.5 * w + g_.finger_thickness) ++finger_hits;
  }
  if (finger_hits > 2 * k) return CheckOutcome::Collides;
  int palm_hits = 0;
  for (double y : palm_)
    if (std::abs(y - yc) <= 0.5 * g_.palm_width) ++palm_hits;
  if (palm_hits > std::max(cfg_.max_collision_points, static_cast<int>(cfg_.outlier_fraction * palm_.size())))
    return CheckOutcome::Collides;
  if (!has_plane_) return CheckOutcome::Pass;
  const double fy = 0.5 * w + g_.finger_thickness;
  const double xs[2] = {0.5 * g_.finger_breadth, 0.5 * g_.palm_breadth};
  const double yss[2] = {fy, 0.5 * g_.palm_width};
  const double zs[2][2] = {{z0, z1}, {zp, z0}};
  for (int b = 0; b < 2; ++b)
    for (double sx : {-1.0, 1.0})
      for (double sy : {-1.0, 1.0})
        for (int iz = 0; iz < 2; ++iz) {
          const Eigen::Vector3d corner = centre + R * Eigen::Vector3d(sx * xs[b], sy * yss[b], zs[b][iz]);
          if (plane_.head<3>().dot(corner) + plane_[3] < cfg_.support_clearance) return CheckOutcome::Support;
        }
  return CheckOutcome::Pass;
}

bool GripperCheck::fingerHidden(const Eigen::Matrix3d& R, const Eigen::Vector3d& at, int s) const {
  const double z1 = g_.finger_tip_depth, z0 = z1 - g_.finger_length;
  int n = 0;
  for (double x : {-0.4, 0.0, 0.4})
    for (int j = 0; j < 5; ++j)
      n += hidden_.hidden(at + R * Eigen::Vector3d(x * g_.finger_breadth, s * 0.5 * g_.finger_thickness,
                                                   z0 + (z1 - z0) * j / 4.0));
  return n >= 4;
}

bool GripperCheck::inHiddenVolume(const Prepared& pr, const Eigen::Matrix3d& R, const Eigen::Vector3d& centre,
                                  double w, const Measurement& m) const {
  if (!hidden_.enabled()) return false;
  const double z0 = g_.finger_tip_depth - g_.finger_length;
  // Each finger on its mid-plane. A finger at an unseen contact of a single-contact or
  // footprint hypothesis is in the hidden volume by construction (that side is bounded by the
  // object's extent or a fitted completion; it ranks lower, see supportedQuality); a contact
  // pair's side bounded by its last samples only is not, where the view hides the finger.
  for (int i = 0; i < 2; ++i) {
    const int s = i == 0 ? -1 : 1;
    const bool checked = m.side[i].seen || (pr.pair && !pr.hint);
    if (checked && fingerHidden(R, centre + R.col(1) * (s * 0.5 * w), s)) return true;
  }
  // The palm's face (behind the fingers) on 3 x 3 points.
  int n = 0;
  const double yp = std::min(0.5 * g_.palm_width, 0.5 * w + g_.finger_thickness);
  for (double x : {-0.4, 0.0, 0.4})
    for (double y : {-1.0, 0.0, 1.0}) n += hidden_.hidden(centre + R * Eigen::Vector3d(x * g_.palm_breadth, y * yp, z0));
  return n >= 3;
}

/// Footprint of an object resting on a support plane: its points projected onto the plane, and
/// the rectangle of least area around them (trimmed extents, orientations in 0.5 deg steps).
/// For a convex object the extreme points along an axis parallel to the support carry that
/// axis as their surface normal, so each rectangle axis is an antipodal closing axis whose
/// width is the rectangle side, even where one of the two contacts is not seen.
struct Footprint {
  Eigen::Vector3d axis[2];   ///< unit axes in the plane (normals of the rectangle's sides)
  double width[2] = {0, 0};  ///< m, trimmed extents along them
  Eigen::Vector3d centre;    ///< rectangle centre at the height of `ref` above the plane
};

/// The points of the first `layers` convex layers of `pts` (onion peeling; a layer: the points
/// on the boundary of the convex hull of what the layers before left). The j-th most extreme
/// point along any direction lies on one of the first j layers, so the trimmed extents of the
/// whole set along every direction are those of these points (k trimmed: k + 1 layers).
std::vector<Eigen::Vector2d> convexLayers(std::vector<Eigen::Vector2d> pts, std::size_t layers) {
  std::vector<Eigen::Vector2d> out;
  for (std::size_t l = 0; l < layers && pts.size() > 2; ++l) {
    const std::vector<Eigen::Vector2d> hull = convexHull2d(pts);  // strict hull vertices
    // The layer: every point on the hull's boundary (ties along an edge included).
    std::vector<Eigen::Vector2d> rest;
    for (const Eigen::Vector2d& p : pts) {
      bool on = false;
      for (std::size_t e = 0; e < hull.size() && !on; ++e) {
        const Eigen::Vector2d& a = hull[e];
        const Eigen::Vector2d& b = hull[(e + 1) % hull.size()];
        on = std::abs(cross2d(a, b, p)) <= 1e-12 * std::max(1.0, (b - a).squaredNorm()) &&
             (p - a).dot(b - a) >= -1e-12 && (p - b).dot(a - b) >= -1e-12;
      }
      (on ? out : rest).push_back(p);
    }
    pts.swap(rest);
  }
  out.insert(out.end(), pts.size() <= 2 ? pts.begin() : pts.end(), pts.end());
  return out;
}

Footprint supportFootprint(const Cloud& cloud, const Eigen::Vector4d& plane, std::size_t k,
                           const Eigen::Vector3d& ref) {
  const Eigen::Vector3d n = plane.head<3>();
  const Eigen::Vector3d e1 = n.unitOrthogonal(), e2 = n.cross(e1);
  std::vector<Eigen::Vector2d> q;
  q.reserve(cloud.size());
  for (const auto& p : cloud) {
    const Eigen::Vector3d v = p.getVector3fMap().cast<double>();
    q.emplace_back(e1.dot(v), e2.dot(v));
  }
  q = convexLayers(std::move(q), k + 1);
  Footprint f;
  double best_area = std::numeric_limits<double>::max();
  std::vector<double> a(q.size()), b(q.size());
  for (int step = 0; step < 180; ++step) {
    const double th = step * 0.5 * kDeg;
    const Eigen::Vector2d d1(std::cos(th), std::sin(th)), d2(-std::sin(th), std::cos(th));
    for (std::size_t i = 0; i < q.size(); ++i) {
      a[i] = d1.dot(q[i]);
      b[i] = d2.dot(q[i]);
    }
    const auto ra = trimmedRange(a, k), rb = trimmedRange(b, k);
    const double area = (ra.second - ra.first) * (rb.second - rb.first);
    if (area >= best_area) continue;
    best_area = area;
    f.axis[0] = d1.x() * e1 + d1.y() * e2;
    f.axis[1] = d2.x() * e1 + d2.y() * e2;
    f.width[0] = ra.second - ra.first;
    f.width[1] = rb.second - rb.first;
    f.centre = ref + f.axis[0] * (0.5 * (ra.first + ra.second) - f.axis[0].dot(ref)) +
               f.axis[1] * (0.5 * (rb.first + rb.second) - f.axis[1].dot(ref));
  }
  return f;
}

/// Circle through 2-D points by Gauss-Newton on the geometric distances, from centre `c` and
/// radius `r`; with `resting`, the circle touches the line h = 0 (centre (u, r)). Points farther
/// than 3 x tolerance are dropped after the first iterations (edges of flat faces, strays);
/// upright (not `resting`), points inside it by more than `tolerance` too (a narrower section of
/// the body, e.g. a bottle's shoulder, whose sloped mantle passes the normal filter: the widest
/// section is the one the fingers must clear). Valid (true) if at least 2/3 of the points are
/// kept and their RMS distance is within `tolerance`.
bool fitCircle(const std::vector<Eigen::Vector2d>& q, bool resting, double tolerance,
               Eigen::Vector2d* c, double* r) {
  if (q.size() < 10 || *r <= 0.0) return false;
  double rms = 0.0;
  int used = 0;
  for (int it = 0; it < 12; ++it) {
    Eigen::Matrix3d JtJ = Eigen::Matrix3d::Zero();
    Eigen::Vector3d Jtd = Eigen::Vector3d::Zero();
    double ss = 0.0;
    used = 0;
    for (const auto& v : q) {
      const Eigen::Vector2d w = v - *c;
      const double rho = w.norm();
      if (rho < 1e-9) continue;
      const double d = rho - *r;
      if (it >= 3 && (std::abs(d) > 3.0 * tolerance || (!resting && d < -tolerance))) continue;
      const Eigen::Vector3d J = resting ? Eigen::Vector3d(-w.x() / rho, -w.y() / rho - 1.0, 0.0)
                                        : Eigen::Vector3d(-w.x() / rho, -w.y() / rho, -1.0);
      JtJ += J * J.transpose();
      Jtd += J * d;
      ss += d * d;
      ++used;
    }
    if (used < 10) return false;
    rms = std::sqrt(ss / used);
    if (resting) JtJ(2, 2) = 1.0;  // the radius is the centre's height
    const Eigen::Vector3d step = JtJ.ldlt().solve(-Jtd);
    if (!step.allFinite()) return false;
    *c += step.head<2>();
    *r = resting ? c->y() : *r + step.z();
    if (*r <= 0.0) return false;
  }
  return used >= static_cast<int>(q.size() * 2 / 3) && rms <= tolerance;
}

/// The angle (rad) the points within 3 x tolerance of the circle (c, r) cover: 2 pi minus the
/// largest gap between their directions from c.
double arcSpan(const std::vector<Eigen::Vector2d>& q, const Eigen::Vector2d& c, double r, double tolerance) {
  std::vector<double> a;
  for (const auto& v : q)
    if (std::abs((v - c).norm() - r) <= 3.0 * tolerance) a.push_back(std::atan2(v.y() - c.y(), v.x() - c.x()));
  if (a.size() < 2) return 0.0;
  std::sort(a.begin(), a.end());
  double gap = a.front() + 2.0 * M_PI - a.back();
  for (std::size_t i = 1; i < a.size(); ++i) gap = std::max(gap, a[i] - a[i - 1]);
  return 2.0 * M_PI - gap;
}

/// Round cross-sections, completed by their circle where the single view shows them only in
/// part (the far side and grazing sides unseen). Lying: the section across closing axis `y`
/// (points projected along `along`, only those whose normal is across `along`, so end caps do
/// not fill it, and, with `half_length` > 0, only those within it of `ref` along `along`: the
/// section where the fingers close, not smeared by a bent body's curve, e.g. a banana's) is a
/// circle resting on the support. Upright (`along` = the support normal):
/// the footprint of the points whose normal is parallel to the support (the mantle) is a
/// circle. Valid if the circle fits (fitCircle), the points on it cover an arc of at least 60
/// deg (arcSpan: a chord of one radius; a few points on a short arc fit any circle), the seen
/// extent along y is at most its diameter (a box's section or footprint is a rectangle: no fit); then the
/// circle's extremes along y, at the height of its centre (lying) or of `ref` (upright).
ExtentHint roundCrossSection(const Cloud& cloud, const Normals& normals, const Eigen::Vector4d& plane,
                             const Eigen::Vector3d& y, const Eigen::Vector3d& along,
                             const Eigen::Vector3d& ref, double tolerance, double half_length = 0.0) {
  ExtentHint hint;
  const Eigen::Vector3d n = plane.head<3>();
  const bool upright = std::abs(along.dot(n)) > 0.9;
  const Eigen::Vector3d v2 = upright ? along.cross(y) : n;  // second section coordinate
  std::vector<Eigen::Vector2d> q;
  double lo = std::numeric_limits<double>::max(), hi = -lo;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3d nv = normals[i].getNormalVector3fMap().cast<double>();
    if (!nv.allFinite() || nv.norm() < 0.5 || std::abs(nv.dot(along)) > 0.7) continue;
    const Eigen::Vector3d p = cloud[i].getVector3fMap().cast<double>();
    if (!upright && half_length > 0.0 && std::abs(along.dot(p - ref)) > half_length) continue;
    q.emplace_back(y.dot(p), upright ? v2.dot(p) : n.dot(p) + plane[3]);
    lo = std::min(lo, q.back().x());
    hi = std::max(hi, q.back().x());
  }
  if (q.size() < 10) return hint;
  // Start: the middle of the seen extent; lying: half the top's height (a round section resting
  // on the support is as high as it is wide); upright: a circle of the seen extent's width
  // whose seen (near) side is the arc.
  Eigen::Vector2d c(0.5 * (lo + hi), 0.0);
  double r = 0.5 * (hi - lo);
  if (upright) {
    double near_v = std::numeric_limits<double>::max(), far_v = -near_v;
    for (const auto& v : q) {
      near_v = std::min(near_v, v.y());
      far_v = std::max(far_v, v.y());
    }
    c.y() = 0.5 * (near_v + far_v);
  } else {
    std::vector<double> hs;
    for (const auto& v : q) hs.push_back(v.y());
    const std::size_t k2 = std::min<std::size_t>(2, hs.size() - 1);
    std::nth_element(hs.begin(), hs.end() - 1 - static_cast<long>(k2), hs.end());
    c.y() = r = 0.5 * hs[hs.size() - 1 - k2];
  }
  if (!fitCircle(q, !upright, tolerance, &c, &r)) return hint;
  if (2.0 * r < hi - lo - 2.0 * tolerance || arcSpan(q, c, r, tolerance) < M_PI / 3.0) return hint;
  const Eigen::Vector3d base = upright ? Eigen::Vector3d(v2 * c.y() + n * n.dot(ref))
                                       : Eigen::Vector3d(n * (c.y() - plane[3]));
  hint.valid = true;
  hint.a = y * (c.x() - r) + base;
  hint.b = y * (c.x() + r) + base;
  return hint;
}

/// A ball: the sphere through the object's points (algebraic least squares, then Gauss-Newton
/// on the geometric distances, points farther than 3 x tolerance dropped after the first
/// iterations). Valid if at least 2/3 of the points are kept, their RMS distance is within
/// `tolerance` and the seen part is a cap at least a radius across in two directions (a flat
/// face fits a huge sphere, a small patch any); then its extremes along every closing axis.
bool fitSphere(const Cloud& cloud, double tolerance, Eigen::Vector3d* centre, double* radius) {
  if (cloud.size() < 20) return false;
  Eigen::Matrix4d A = Eigen::Matrix4d::Zero();
  Eigen::Vector4d b = Eigen::Vector4d::Zero();
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& pf : cloud) mean += pf.getVector3fMap().cast<double>();
  mean /= static_cast<double>(cloud.size());
  for (const auto& pf : cloud) {  // |p|^2 = 2 c.p + k, k = r^2 - |c|^2 (centred for conditioning)
    const Eigen::Vector3d p = pf.getVector3fMap().cast<double>() - mean;
    const Eigen::Vector4d row(2.0 * p.x(), 2.0 * p.y(), 2.0 * p.z(), 1.0);
    A += row * row.transpose();
    b += row * p.squaredNorm();
  }
  const Eigen::Vector4d x = A.ldlt().solve(b);
  Eigen::Vector3d c = x.head<3>();
  double r2 = x[3] + c.squaredNorm();
  if (!x.allFinite() || r2 <= 0.0) return false;
  double r = std::sqrt(r2), rms = 0.0;
  std::size_t used = 0;
  for (int it = 0; it < 8; ++it) {
    Eigen::Matrix4d JtJ = Eigen::Matrix4d::Zero();
    Eigen::Vector4d Jtd = Eigen::Vector4d::Zero();
    double ss = 0.0;
    used = 0;
    for (const auto& pf : cloud) {
      const Eigen::Vector3d w = pf.getVector3fMap().cast<double>() - mean - c;
      const double rho = w.norm();
      if (rho < 1e-9) continue;
      const double d = rho - r;
      if (it >= 3 && std::abs(d) > 3.0 * tolerance) continue;
      const Eigen::Vector4d J(-w.x() / rho, -w.y() / rho, -w.z() / rho, -1.0);
      JtJ += J * J.transpose();
      Jtd += J * d;
      ss += d * d;
      ++used;
    }
    if (used < 20) return false;
    rms = std::sqrt(ss / static_cast<double>(used));
    const Eigen::Vector4d step = JtJ.ldlt().solve(-Jtd);
    if (!step.allFinite()) return false;
    c += step.head<3>();
    r += step[3];
    if (r <= 0.0) return false;
  }
  if (used < cloud.size() * 2 / 3 || rms > tolerance) return false;
  Eigen::Matrix3f covf;
  Eigen::Vector4f cenf;
  pcl::computeMeanAndCovarianceMatrix(cloud, covf, cenf);
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(covf.cast<double>());
  // Spread along the two largest principal axes: a cap of angular radius t has std-dev about
  // r sin(t) / 2 across; at least a radius across (t >= 30 deg) in both.
  if (std::sqrt(std::max(0.0, es.eigenvalues()[1])) < 0.25 * r) return false;
  *centre = c + mean;
  *radius = r;
  return true;
}

std::string num(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

}  // namespace

// ------------------------------------------------------------------------------ config

std::string toString(GraspFailure f) { return ehc_common::enumName(kFailureNames, f, kOwner); }

GraspFailure graspFailureFromString(const std::string& s) {
  return ehc_common::enumValue(kFailureNames, s, kOwner, "grasp failure");
}

void GraspGeneratorConfig::validate() const {
  auto range = [](const std::string& f, double v, double lo, double hi) {
    requireRange(kOwner, f, v, lo, hi);
  };
  const GripperGeometry& g = gripper;
  range("gripper.max_width", g.max_width, 0.005, 0.5);
  range("gripper.finger_length", g.finger_length, 0.005, 0.3);
  range("gripper.finger_tip_depth", g.finger_tip_depth, 0.0, g.finger_length);
  range("gripper.finger_thickness", g.finger_thickness, 0.0, 0.1);
  range("gripper.finger_breadth", g.finger_breadth, 0.002, 0.2);
  range("gripper.palm_height", g.palm_height, 0.0, 0.5);
  range("gripper.palm_width", g.palm_width, 0.0, 1.0);
  range("gripper.palm_breadth", g.palm_breadth, 0.0, 1.0);
  range("gripper.clearance", g.clearance, 0.0, 0.5 * g.max_width);
  if (!up.allFinite() || up.norm() < 1e-6) fail("parameter 'up' must be a non-zero vector");
  range("voxel_size", voxel_size, 0.0005, 0.05);
  range("normal_radius", normal_radius, voxel_size, 0.2);
  range("min_object_points", min_object_points, 3, 1e7);
  range("max_object_points", max_object_points, min_object_points, 1e7);
  range("max_seeds", max_seeds, 1, 1e6);
  range("pairs_per_seed", pairs_per_seed, 1, 100);
  range("approach_steps", approach_steps, 1, 360);
  range("friction_coefficient", friction_coefficient, 0.02, 2.0);
  range("slanted_contact_deg", slanted_contact_deg, std::atan(friction_coefficient) / kDeg, 90.0);
  range("max_approach_tilt_deg", max_approach_tilt_deg, 0.0, 180.0);
  range("max_collision_points", max_collision_points, 0, 1000);
  range("outlier_fraction", outlier_fraction, 0.0, 0.2);
  range("min_points_between_fingers", min_points_between_fingers, 1, 1e6);
  range("support_clearance", support_clearance, -0.05, 0.1);
  range("approach_standoff", approach_standoff, 0.001, 1.0);
  range("centroid_sigma_deg", centroid_sigma_deg, 0.1, 180.0);
  range("pca_power", pca_power, 0.0, 100.0);
  range("pca_approach_power", pca_approach_power, 0.0, 100.0);
  range("pca_isotropy_ratio", pca_isotropy_ratio, 0.0, 1.0);
  range("max_refine_shift", max_refine_shift, 0.0, 0.5);
  range("max_depth_shift", max_depth_shift, 0.0, 0.5);
  range("depth_step", depth_step, 0.0, 0.5);
  range("depth_margin", depth_margin, 0.0, 0.5);
  if (max_depth_shift > 0.0) {  // depth refinement enabled
    const std::string ds = "parameter 'depth_step' = " + num(depth_step);
    if (depth_step <= 0.0) fail(ds + " must be > 0 when max_depth_shift > 0");
    if (depth_step > max_depth_shift)
      fail(ds + " must be <= max_depth_shift (" + num(max_depth_shift) + ")");
    if (max_depth_shift / depth_step > 1000.0)
      fail(ds + " is too small: more than 1000 steps up to max_depth_shift (" +
           num(max_depth_shift) + ")");
    if (depth_margin >= max_depth_shift)
      fail("parameter 'depth_margin' = " + num(depth_margin) + " must be < max_depth_shift (" +
           num(max_depth_shift) + ")");
  }
  range("max_evaluations", max_evaluations, 1, 1e7);
  range("single_contact_weight", single_contact_weight, 0.0, 1.0);
  range("footprint_weight", footprint_weight, 0.0, 1.0);
  range("wall_weight", wall_weight, 0.0, 1.0);
  range("wall_tilt_deg", wall_tilt_deg, 0.0, 80.0);
  range("round_fit_tolerance", round_fit_tolerance, 0.0, 0.05);
  range("min_contact_points", min_contact_points, 5, 1e6);
  range("nms_distance", nms_distance, 0.0, 1.0);
  range("nms_angle_deg", nms_angle_deg, 0.0, 180.0);
  range("top_k", top_k, 1, 10000);
  range("plane_distance", plane_distance, 0.0005, 0.1);
  range("plane_max_tilt_deg", plane_max_tilt_deg, 0.0, 90.0);
  range("min_plane_fraction", min_plane_fraction, 0.0, 1.0);
  range("cluster_tolerance", cluster_tolerance, 0.001, 0.5);
  range("cluster_spacing_factor", cluster_spacing_factor, 0.0, 10.0);
  range("footprint_merge_gap", footprint_merge_gap, -1.0, 0.5);
  range("max_object_extent", max_object_extent, 0.01, 10.0);
  range("min_cluster_points", min_cluster_points, 1, 1e7);
  range("max_objects", max_objects, 1, 1000);
}

std::string GraspGeneratorConfig::summary() const {
  std::ostringstream os;
  os << "grasp generator: gripper max width " << gripper.max_width << " m, fingers "
     << gripper.finger_length << " x " << gripper.finger_breadth << " x "
     << gripper.finger_thickness << " m, palm " << gripper.palm_height << " m; voxel "
     << voxel_size << " m (coarser above " << max_object_points << " points per object), normals r "
     << normal_radius << " m, " << max_seeds << " seeds x "
     << pairs_per_seed << " pairs x " << approach_steps << " approaches, friction mu "
     << friction_coefficient << " (cone " << std::atan(friction_coefficient) / kDeg << " deg; slanted contacts within " << slanted_contact_deg << " deg refused), hidden-volume check "
     << (hidden_volume_check ? "on" : "off") << ", contact fits >= "
     << min_contact_points << " points, centroid sigma " << centroid_sigma_deg << " deg, pca power "
     << pca_power << "/" << pca_approach_power << ", refine shift <= " << max_refine_shift
     << " m, depth shift <= " << max_depth_shift << " m (step " << depth_step << " m, margin "
     << depth_margin << " m), single-contact / footprint / wall weights " << single_contact_weight << " / "
     << footprint_weight << " / " << wall_weight << " (walls also tilted " << wall_tilt_deg << " deg), top " << top_k << ", up ["
     << up.transpose() << "]";
  return os.str();
}

GraspGeneratorConfig loadGraspGeneratorConfig(const ConfigNode& n) {
  GraspGeneratorConfig c;
  const ConfigNode g = n.childOrEmpty("gripper");
  GripperGeometry& gg = c.gripper;
  gg.max_width = g.get("max_width", gg.max_width);
  gg.finger_length = g.get("finger_length", gg.finger_length);
  gg.finger_tip_depth = g.get("finger_tip_depth", gg.finger_tip_depth);
  gg.finger_thickness = g.get("finger_thickness", gg.finger_thickness);
  gg.finger_breadth = g.get("finger_breadth", gg.finger_breadth);
  gg.palm_height = g.get("palm_height", gg.palm_height);
  gg.palm_width = g.get("palm_width", gg.palm_width);
  gg.palm_breadth = g.get("palm_breadth", gg.palm_breadth);
  gg.clearance = g.get("clearance", gg.clearance);
  c.up = n.getVector("up", c.up, 3);
  c.voxel_size = n.get("voxel_size", c.voxel_size);
  c.normal_radius = n.get("normal_radius", c.normal_radius);
  c.min_object_points = n.get("min_object_points", c.min_object_points);
  c.max_object_points = n.get("max_object_points", c.max_object_points);
  c.max_seeds = n.get("max_seeds", c.max_seeds);
  c.pairs_per_seed = n.get("pairs_per_seed", c.pairs_per_seed);
  c.approach_steps = n.get("approach_steps", c.approach_steps);
  c.friction_coefficient = n.get("friction_coefficient", c.friction_coefficient);
  c.slanted_contact_deg = n.get("slanted_contact_deg", c.slanted_contact_deg);
  c.hidden_volume_check = n.get("hidden_volume_check", c.hidden_volume_check);
  c.max_approach_tilt_deg = n.get("max_approach_tilt_deg", c.max_approach_tilt_deg);
  c.max_collision_points = n.get("max_collision_points", c.max_collision_points);
  c.outlier_fraction = n.get("outlier_fraction", c.outlier_fraction);
  c.min_points_between_fingers = n.get("min_points_between_fingers", c.min_points_between_fingers);
  c.support_clearance = n.get("support_clearance", c.support_clearance);
  c.assume_support_below = n.get("assume_support_below", c.assume_support_below);
  c.approach_standoff = n.get("approach_standoff", c.approach_standoff);
  c.centroid_sigma_deg = n.get("centroid_sigma_deg", c.centroid_sigma_deg);
  c.pca_power = n.get("pca_power", c.pca_power);
  c.pca_approach_power = n.get("pca_approach_power", c.pca_approach_power);
  c.pca_isotropy_ratio = n.get("pca_isotropy_ratio", c.pca_isotropy_ratio);
  c.max_refine_shift = n.get("max_refine_shift", c.max_refine_shift);
  c.max_depth_shift = n.get("max_depth_shift", c.max_depth_shift);
  c.depth_step = n.get("depth_step", c.depth_step);
  c.depth_margin = n.get("depth_margin", c.depth_margin);
  c.max_evaluations = n.get("max_evaluations", c.max_evaluations);
  c.single_contact_weight = n.get("single_contact_weight", c.single_contact_weight);
  c.footprint_weight = n.get("footprint_weight", c.footprint_weight);
  c.wall_weight = n.get("wall_weight", c.wall_weight);
  c.wall_tilt_deg = n.get("wall_tilt_deg", c.wall_tilt_deg);
  c.round_fit_tolerance = n.get("round_fit_tolerance", c.round_fit_tolerance);
  c.min_contact_points = n.get("min_contact_points", c.min_contact_points);
  c.nms_distance = n.get("nms_distance", c.nms_distance);
  c.nms_angle_deg = n.get("nms_angle_deg", c.nms_angle_deg);
  c.top_k = n.get("top_k", c.top_k);
  c.seed = n.get("seed", c.seed);
  c.plane_distance = n.get("plane_distance", c.plane_distance);
  c.plane_max_tilt_deg = n.get("plane_max_tilt_deg", c.plane_max_tilt_deg);
  c.min_plane_fraction = n.get("min_plane_fraction", c.min_plane_fraction);
  c.cluster_tolerance = n.get("cluster_tolerance", c.cluster_tolerance);
  c.cluster_spacing_factor = n.get("cluster_spacing_factor", c.cluster_spacing_factor);
  c.footprint_merge_gap = n.get("footprint_merge_gap", c.footprint_merge_gap);
  c.max_object_extent = n.get("max_object_extent", c.max_object_extent);
  c.min_cluster_points = n.get("min_cluster_points", c.min_cluster_points);
  c.max_objects = n.get("max_objects", c.max_objects);
  n.validate(c);
  return c;
}

// ------------------------------------------------------------------------------ generator

GraspGenerator::GraspGenerator(const GraspGeneratorConfig& config) : config_(config) {
  config_.validate();
  config_.up.normalize();
}

GraspGenerator::~GraspGenerator() = default;

namespace {

/// One object prepared for the grasp search: its filtered cloud with normals and search tree,
/// the collision environment, the centre of gravity, the principal subspaces and the support.
struct PreparedObject {
  Cloud::Ptr raw, cloud;
  double leaf = 0.0;  ///< voxel edge of `cloud`: voxel_size, grown for objects over max_object_points
  Normals::Ptr normals;
  pcl::search::KdTree<pcl::PointXYZ>::Ptr tree;
  Cloud::Ptr env;  ///< collision environment (the object, plus other geometry if given)
  pcl::search::KdTree<pcl::PointXYZ>::Ptr env_tree;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  std::vector<Eigen::MatrixXd> subspaces;
  Eigen::Vector4d plane = Eigen::Vector4d::Zero();
  bool has_plane = false;
  double noise = 0.0;  ///< m, the filtered cloud's estimated noise (estimateNoise)
  double spacing = 0.0;  ///< m, the filtered cloud's sample spacing (sampleSpacing), at least `leaf`
  HiddenVolume hidden;  ///< behind the view from the camera (disabled without hidden_volume_check)
  /// Everything behind the view's points (wall grasps' bound; disabled without
  /// hidden_volume_check, a support or wall_weight).
  detail::ViewShadow shadow;
  Eigen::Vector3d eye = Eigen::Vector3d::Zero();  ///< the viewpoint
  /// From the camera to the centroid (unit), zero when the viewpoint is not known (without
  /// hidden_volume_check): approaches are kept within max_approach_tilt_deg of it.
  Eigen::Vector3d view_dir = Eigen::Vector3d::Zero();
};

/// The noise of a cloud from its normals' plane fits: a flat patch of radius r with points
/// scattered sigma about it has the covariance eigenvalues r^2/4, r^2/4 and sigma^2, so PCL's
/// curvature c = l0 / (l0 + l1 + l2) gives sigma^2 = c / (1 - c) r^2 / 2. The median over the
/// points (edges and corners are a minority); a curved surface adds r^2 / (8 R) in quadrature
/// (0.5 mm for r = 12 mm on a 66 mm cylinder).
double estimateNoise(const Normals& normals, double radius) {
  std::vector<double> s;
  s.reserve(normals.size());
  for (const auto& n : normals) {
    const double c = n.curvature;
    if (std::isfinite(c) && c >= 0.0 && c < 1.0 / 3.0) s.push_back(std::sqrt(c / (1.0 - c) * 0.5) * radius);
  }
  if (s.empty()) return 0.0;
  std::nth_element(s.begin(), s.begin() + static_cast<long>(s.size() / 2), s.end());
  return s[s.size() / 2];
}

/// The cloud's sample spacing: the median distance from a point to its nearest neighbour (over
/// at most 256 points, evenly strided). A camera's cloud of a small or distant object can be
/// sparser than the voxel filter's grid.
double sampleSpacing(const Cloud& cloud, pcl::search::KdTree<pcl::PointXYZ>& tree) {
  const std::size_t n = cloud.size(), stride = std::max<std::size_t>(1, n / 256);
  std::vector<int> idx(2);
  std::vector<float> d2(2);
  std::vector<double> d;
  for (std::size_t i = 0; i < n; i += stride)
    if (tree.nearestKSearch(cloud[i], 2, idx, d2) == 2) d.push_back(std::sqrt(static_cast<double>(d2[1])));
  if (d.empty()) return 0.0;
  std::nth_element(d.begin(), d.begin() + static_cast<long>(d.size() / 2), d.end());
  return d[d.size() / 2];
}

/// Input checks and the voxel filter: false (and res->reason) if there is nothing to grasp.
bool filterObject(const GraspGeneratorConfig& cfg, const PointList& object, const Eigen::Vector3d& viewpoint,
                  PreparedObject* po, GraspResult* res) {
  GraspResult& r = *res;
  r.objects = 1;
  r.input_points = static_cast<int>(object.size());
  if (object.empty()) {
    r.reason = "empty cloud";
    r.failure = GraspFailure::EmptyCloud;
    return false;
  }
  po->raw = toCloud(object, &r.finite_points);
  if (r.finite_points == 0) {
    r.reason = "no finite points (" + std::to_string(object.size()) + " points, all NaN/Inf)";
    r.failure = GraspFailure::NoFinitePoints;
    return false;
  }
  if (!viewpoint.allFinite()) {
    r.reason = "viewpoint is not finite";
    r.failure = GraspFailure::BadViewpoint;
    return false;
  }
  po->cloud = boundedVoxelFilter(po->raw, cfg.voxel_size, static_cast<std::size_t>(cfg.max_object_points), &po->leaf);
  r.filtered_points = static_cast<int>(po->cloud->size());
  r.voxel_size = po->leaf;
  if (static_cast<int>(po->cloud->size()) < cfg.min_object_points) {
    r.failure = GraspFailure::TooFewPoints;
    r.reason = "only " + std::to_string(po->cloud->size()) + " points after the " +
               std::to_string(cfg.voxel_size) + " m voxel filter (min_object_points " +
               std::to_string(cfg.min_object_points) + ")";
    return false;
  }
  return true;
}

/// Centre of gravity, principal axes and support plane (given, or the lowest point along up if
/// assume_support_below): false (and res->reason) for a support plane that is not finite.
bool describeObject(const GraspGeneratorConfig& cfg, const Eigen::Vector4d* support_plane, PreparedObject* po,
                    GraspResult* res) {
  const Cloud& cloud = *po->cloud;
  // Centre of gravity and principal axes.
  Eigen::Matrix3f covf = Eigen::Matrix3f::Zero();
  Eigen::Vector4f cenf = Eigen::Vector4f::Zero();
  pcl::computeMeanAndCovarianceMatrix(cloud, covf, cenf);
  po->centroid = cenf.head<3>().cast<double>();
  res->centroids.push_back(po->centroid);
  po->subspaces = principalSubspaces(covf.cast<double>(), cfg.pca_isotropy_ratio);

  // Support plane.
  const Eigen::Vector3d up = cfg.up;
  Eigen::Vector4d plane = Eigen::Vector4d::Zero();
  bool has_plane = false;
  if (support_plane) {
    if (!support_plane->allFinite() || support_plane->head<3>().norm() < 1e-9) {
      res->reason = "support plane is not finite";
      res->failure = GraspFailure::BadSupportPlane;
      return false;
    }
    plane = *support_plane / support_plane->head<3>().norm();
    if (plane.head<3>().dot(up) < 0) plane = -plane;
    has_plane = true;
  } else if (cfg.assume_support_below) {
    double lowest = std::numeric_limits<double>::max();
    for (const auto& p : cloud) lowest = std::min(lowest, up.dot(p.getVector3fMap().cast<double>()));
    plane << up, -lowest;
    has_plane = true;
  }
  res->support_plane_found = has_plane;
  res->support_plane = plane;
  po->plane = plane;
  po->has_plane = has_plane;
  return true;
}

/// Turns the object's normals outwards. Away from the centroid (a convex object's outside);
/// with `eye` (a single view from it), towards the camera: every surface a view shows faces it,
/// whatever the shape (the centroid of one view of a box lies near its most seen face, whose
/// normals it would turn either way; a part of a non-convex object facing the rest faces the
/// centroid), except within kGrazingDeg of perpendicular to the ray, where the centroid decides.
void orientNormals(const Eigen::Vector3d& centroid, const Eigen::Vector3d* eye, PreparedObject* po) {
  const double grazing = std::sin(kGrazingDeg * kDeg);
  for (std::size_t i = 0; i < po->cloud->size(); ++i) {
    auto n = (*po->normals)[i].getNormalVector3fMap();
    if (!n.allFinite()) continue;
    const Eigen::Vector3d p = pt(*po->cloud, static_cast<int>(i)), nd = n.cast<double>();
    bool flip = nd.dot(p - centroid) < 0.0;
    if (eye && (*eye - p).norm() > 1e-9) {
      const double towards = nd.dot((*eye - p).normalized());
      if (std::abs(towards) >= grazing * nd.norm()) flip = towards < 0.0;
    }
    if (flip) n = -n;
  }
}

/// Normals, oriented outwards (orientNormals: towards the camera when the viewpoint is known,
/// hidden_volume_check, and the cloud is a single view), and the collision environment (the
/// object, plus `collision_cloud` if given, voxel-filtered together).
void estimateNormalsAndEnvironment(const GraspGeneratorConfig& cfg, const PointList* collision_cloud,
                                   const Eigen::Vector3d& viewpoint, PreparedObject* po) {
  // Unsorted radius results: the neighbourhoods here are large and their order is irrelevant.
  po->tree.reset(new pcl::search::KdTree<pcl::PointXYZ>(false));
  po->tree->setInputCloud(po->cloud);
  po->spacing = std::max(po->leaf, sampleSpacing(*po->cloud, *po->tree));
  po->normals.reset(new Normals);
  pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> ne;
  ne.setInputCloud(po->cloud);
  ne.setSearchMethod(po->tree);
  const double radius = cfg.normal_radius * po->leaf / cfg.voxel_size;  // as many neighbours on a coarser grid
  ne.setRadiusSearch(radius);
  ne.compute(*po->normals);
  po->noise = estimateNoise(*po->normals, radius);
  if (cfg.hidden_volume_check && (po->centroid - viewpoint).norm() > 1e-6)
    po->view_dir = (po->centroid - viewpoint).normalized();
  orientNormals(po->centroid, nullptr, po);
  if (cfg.hidden_volume_check) {
    const double margin = 3.0 * po->noise + 2.0 * po->leaf;
    po->hidden = HiddenVolume(*po->cloud, *po->normals, po->centroid, viewpoint, po->leaf, margin);
    if (po->hidden.singleView()) {
      orientNormals(po->centroid, &viewpoint, po);
      po->hidden = HiddenVolume(*po->cloud, *po->normals, po->centroid, viewpoint, po->leaf, margin);
    }
  }

  // Collision environment (the object, plus other geometry if given).
  po->env = po->cloud;
  po->env_tree = po->tree;
  if (collision_cloud && !collision_cloud->empty()) {
    Cloud::Ptr both = toCloud(*collision_cloud);
    *both += *po->raw;
    po->env = voxelFilter(both, po->leaf);
    po->env_tree.reset(new pcl::search::KdTree<pcl::PointXYZ>(false));
    po->env_tree->setInputCloud(po->env);
  }
  // The view's shadow over everything seen (the wall grasps' bound): gaps up to the cloud's
  // angular sample spacing count as seen surface, points within the depth noise as behind.
  po->eye = viewpoint;
  const double range = (po->centroid - viewpoint).norm();
  if (cfg.hidden_volume_check && cfg.wall_weight > 0.0 && po->has_plane && range > 1e-6) {
    std::vector<Eigen::Vector3d> seen;
    seen.reserve(po->env->size());
    for (const auto& p : *po->env) seen.push_back(p.getVector3fMap().cast<double>());
    po->shadow = detail::ViewShadow(seen, viewpoint, po->spacing / range, 2.0 * po->noise + 0.5 * po->leaf);
  }
}

/// Contact seeds: every point of the filtered cloud, or max_seeds of them (shuffled with `seed`).
std::vector<int> sampleSeeds(int n, const GraspGeneratorConfig& cfg) {
  std::vector<int> seeds(static_cast<std::size_t>(n));
  std::iota(seeds.begin(), seeds.end(), 0);
  std::mt19937 rng(cfg.seed);
  if (n > cfg.max_seeds) {
    std::shuffle(seeds.begin(), seeds.end(), rng);
    seeds.resize(static_cast<std::size_t>(cfg.max_seeds));
  }
  return seeds;
}

/// Hypotheses: (closing axis, centre, antipodal quality). Antipodal contact pairs; and the
/// seed's own normal as closing axis with the far contact unseen (single-view clouds): the
/// object's extent along that axis stands in for the unseen side (penalised quality).
struct Hyp {
  Eigen::Vector3d y, c0, u, v;
  double q;
  bool single;
  ExtentHint hint;
};

/// A (hypothesis, approach step) with its optimistic score (before the collision checks).
struct Pending {
  double prescore;
  int hyp, step;
};

/// The grasp search on one prepared object: hypotheses, approaches, collision checks, scoring,
/// non-maximum suppression and refinement. Holds the search's constants and its neighbourhood
/// buffers (shared by the stages).
class GraspSearch {
 public:
  GraspSearch(const GraspGeneratorConfig& cfg, const PreparedObject& po)
      : cfg_(cfg), g_(cfg.gripper), po_(po), check_(cfg, po.plane, po.has_plane, po.noise, po.leaf, po.spacing, po.hidden),
        cos_fc_(std::cos(std::atan(cfg.friction_coefficient))),
        cos_tilt_(std::cos(cfg.max_approach_tilt_deg * kDeg)),
        check_radius_(std::sqrt(
            std::pow(0.5 * std::max(g_.palm_width, g_.max_width + 2 * g_.finger_thickness), 2) +
            std::pow(0.5 * std::max(g_.palm_breadth, g_.finger_breadth), 2) +
            std::pow(g_.finger_length + g_.palm_height, 2))),
        sigma_(cfg.centroid_sigma_deg * kDeg), centre_(po.centroid) {
    obj_p_.reserve(po.cloud->size());
    obj_n_.reserve(po.cloud->size());
    for (std::size_t i = 0; i < po.cloud->size(); ++i) {
      const Eigen::Vector3d p = pt(*po.cloud, static_cast<int>(i));
      const Eigen::Vector3d n = (*po.normals)[i].getNormalVector3fMap().cast<double>();
      obj_p_.push_back(p);
      obj_n_.push_back(!n.allFinite() || n.norm() < 0.5 ? Eigen::Vector3d::Zero() : n);  // outwards (orientNormals)
    }
    if (po.env != po.cloud)
      for (std::size_t i = 0; i < po.env->size(); ++i) env_p_.push_back(pt(*po.env, static_cast<int>(i)));
  }

  /// Antipodal pairs and single-contact hypotheses of the seeds; *any_pair: a pair was found.
  std::vector<Hyp> contactHypotheses(const std::vector<int>& seeds, bool* any_pair);
  /// Footprint hypotheses (object on a support), and the round-section hints of every hypothesis.
  void addFootprintHypotheses(std::vector<Hyp>* hyps);
  /// The margin rule's "too wide" reason ("" if the footprint fits the opening, or no footprint).
  std::string tooWide() const;
  /// Why no candidate passed: the check most of them failed (after enough points between the
  /// fingers), with the counts of every check.
  GraspFailure refusal(std::string* reason) const;
  /// Every (hypothesis, approach) within the tilt limit, best optimistic score first; sets each
  /// hypothesis's approach basis (u, v).
  std::vector<Pending> rankApproaches(std::vector<Hyp>* hyps);
  /// Collision checks best first, until enough candidates pass or max_evaluations.
  std::vector<Candidate> checkCandidates(const std::vector<Hyp>& hyps, const std::vector<Pending>& pending);
  /// GS-Net*-style score of a candidate (antipodal x centroid x PCA weight).
  void score(Candidate& cd) const;
  /// Non-maximum suppression of `in` (best first): at most `limit`.
  std::vector<Candidate> suppress(const std::vector<Candidate>& in, std::size_t limit) const;
  /// Wall grasps (wall_grasps.h) within the approach tilt limits, as candidates.
  void addWallCandidates(std::vector<Candidate>* cands) const;
  /// Refinement: move along the finger breadth axis (x) onto the centroid's projection.
  void refineOntoCentroid(std::vector<Candidate>* kept);
  /// Depth refinement: push along the approach axis while the check passes (see the header).
  void refineDepth(std::vector<Candidate>* kept);

 private:
  /// Environment points within `radius` of `centre` into nbrs_, the object's into surf_.
  void gather(const Eigen::Vector3d& centre, double radius);
  /// The gripper with cd's rotation, centred near c0 (re-centred along the closing axis by
  /// evaluate), approach unchanged ((cphi, sphi) = (1, 0)). nbrs_ must hold the environment
  /// within check_radius_ of c0.
  CheckOutcome checkAt(const Candidate& cd, const Eigen::Vector3d& c0, Candidate* out);

  const GraspGeneratorConfig& cfg_;
  const GripperGeometry& g_;
  const PreparedObject& po_;
  GripperCheck check_;
  const double cos_fc_, cos_tilt_;
  const Eigen::Vector3d ref_ = Eigen::Vector3d(0.31, 0.52, 0.79).normalized();
  const double check_radius_;
  const double sigma_;
  Footprint footprint_;
  bool use_footprint_ = false;
  /// The object's middle for the refinement (see addFootprintHypotheses): the centroid without
  /// a support, else the completed footprint's centre, a round body's axis or a ball's centre.
  Eigen::Vector3d centre_;
  /// The object's points, their normals (oriented outwards from the centroid; zero where none
  /// was estimated) and the collision environment's points, for the neighbourhood scans (a
  /// linear scan: the gripper's reach covers most of an object, where a tree search returns
  /// nearly every point).
  std::vector<Eigen::Vector3d> obj_p_, obj_n_, env_p_;
  std::vector<Eigen::Vector3d> nbrs_;
  std::vector<SurfacePoint> surf_;  ///< the object's points (with normals) gathered with nbrs_
  GripperCheck::Prepared scratch_;  ///< checkAt's (its buffers reused)
  std::array<int, kOutcomes> outcomes_{};  ///< checkCandidates' evaluations per CheckOutcome
  /// The outcome of the first pose checked (best first) that held enough of the object.
  CheckOutcome first_refusal_ = CheckOutcome::TooFewPoints;
  double first_width_ = 0.0;  ///< its measured width
};

void GraspSearch::score(Candidate& cd) const {
  const Eigen::Vector3d a = cd.R.col(2);
  const Eigen::Vector3d o = cd.c - cfg_.approach_standoff * a;
  const Eigen::Vector3d to_g = po_.centroid - o;
  const double th = std::acos(std::max(-1.0, std::min(1.0, a.dot(to_g.normalized()))));
  cd.wc = std::exp(-0.5 * (th / sigma_) * (th / sigma_));
  cd.wp = std::pow(alignment(po_.subspaces, cd.R.col(1)), cfg_.pca_power) *
          std::pow(alignment(po_.subspaces, a), cfg_.pca_approach_power);
  cd.score = cd.antipodal * cd.wc * cd.wp;
}

std::vector<Hyp> GraspSearch::contactHypotheses(const std::vector<int>& seeds, bool* any_pair) {
  const Cloud& cloud = *po_.cloud;
  const Normals& normals = *po_.normals;
  std::vector<Hyp> hyps;
  for (int i : seeds) {
    const Eigen::Vector3d pi = pt(cloud, i);
    const Eigen::Vector3d ni = normals[static_cast<std::size_t>(i)].getNormalVector3fMap().cast<double>();
    if (!ni.allFinite() || ni.norm() < 0.5) continue;
    std::vector<std::pair<double, int>> partners;
    const double lmin2 = std::pow(2.0 * cfg_.voxel_size, 2), lmax2 = std::pow(g_.max_width - 2.0 * g_.clearance, 2);
    for (int j = 0; j < static_cast<int>(obj_p_.size()); ++j) {
      const Eigen::Vector3d d = obj_p_[static_cast<std::size_t>(j)] - pi;
      const double L2 = d.squaredNorm();
      if (L2 < lmin2 || L2 > lmax2) continue;
      const double L = std::sqrt(L2);
      const Eigen::Vector3d y = d / L;
      const Eigen::Vector3d& nj = obj_n_[static_cast<std::size_t>(j)];
      const double q = std::min(std::abs(ni.dot(y)), std::abs(nj.dot(y)));
      if (q >= cos_fc_) partners.emplace_back(q, j);
    }
    const std::size_t keep = std::min(partners.size(), static_cast<std::size_t>(cfg_.pairs_per_seed));
    std::partial_sort(partners.begin(), partners.begin() + static_cast<long>(keep), partners.end(),
                      [](const auto& a, const auto& b) { return a.first > b.first; });
    if (keep > 0) *any_pair = true;
    for (std::size_t k = 0; k < keep; ++k) {
      const Eigen::Vector3d pj = pt(cloud, partners[k].second);
      hyps.push_back({(pj - pi).normalized(), 0.5 * (pi + pj), {}, {}, partners[k].first, false, {}});
    }
    if (cfg_.single_contact_weight > 0.0) {
      // Renormalised in double: the float normal's unit length is only float-accurate,
      // and this axis becomes a column of the grasp rotation.
      const Eigen::Vector3d n_out = ni.normalized();  // outwards (orientNormals)
      hyps.push_back({n_out, pi - n_out * (0.5 * g_.max_width - g_.clearance), {}, {},
                      cfg_.single_contact_weight, true, {}});
    }
  }
  return hyps;
}

void GraspSearch::addFootprintHypotheses(std::vector<Hyp>* hyps) {
  // Footprint hypotheses (object on a support): close along the axes of the footprint's
  // least-area rectangle, parallel to the support, width = the object's extent (see
  // supportFootprint). They find the grasp across a lying cylinder, whose single-view cloud
  // shows its sides only at grazing angles (no antipodal pair there, normals tilted up).
  const Cloud& cloud = *po_.cloud;
  const Normals& normals = *po_.normals;
  // The round fits' tolerance on top of the cloud's noise: their RMS is the noise where the
  // shape fits.
  const double tol = std::hypot(cfg_.round_fit_tolerance, po_.noise);
  // A ball: its sphere gives its width across every closing axis (one view shows less than
  // half of it; the seen cap's extent is short of the diameter along most axes).
  Eigen::Vector3d ball_c = Eigen::Vector3d::Zero();
  double ball_r = 0.0;
  const bool ball = fitSphere(cloud, tol, &ball_c, &ball_r);
  if (ball)
    for (Hyp& h : *hyps) h.hint = {true, ball_c - ball_r * h.y, ball_c + ball_r * h.y};
  use_footprint_ = po_.has_plane && cfg_.footprint_weight > 0.0;
  if (!use_footprint_) return;
  const Eigen::Vector4d& plane = po_.plane;
  Footprint& footprint = footprint_;
  footprint = supportFootprint(cloud, plane, static_cast<std::size_t>(cfg_.max_collision_points), po_.centroid);
  if (ball) {
    centre_ = ball_c;
    for (int a = 0; a < 2; ++a) {
      footprint.width[a] = 2.0 * ball_r;
      footprint.centre += footprint.axis[a] * footprint.axis[a].dot(ball_c - footprint.centre);
      hyps->push_back({footprint.axis[a], footprint.centre, {}, {}, cfg_.footprint_weight, true,
                       {true, ball_c - ball_r * footprint.axis[a], ball_c + ball_r * footprint.axis[a]}});
    }
    return;
  }
  // An upright round object (its footprint a circle, the far side unseen): the circle gives
  // its width across every axis parallel to the support, for every hypothesis (a closing on
  // a chord short of the diameter would push it until the diameter is between the fingers).
  ExtentHint upright = roundCrossSection(cloud, normals, plane, footprint.axis[0], plane.head<3>(),
                                         po_.centroid, tol);
  // A round body's seen footprint spans its diameter across the view (the mantle's silhouette,
  // short only by its grazing sides' missing samples): a circle much wider than the footprint
  // is an arc of something else (a banana's bent side fits a circle several times its width).
  if (upright.valid &&
      (upright.b - upright.a).norm() > kRoundFootprintRatio * std::max(footprint.width[0], footprint.width[1]))
    upright.valid = false;
  if (upright.valid) {
    const Eigen::Vector3d c = 0.5 * (upright.a + upright.b);
    const double r = 0.5 * (upright.b - upright.a).norm();
    centre_ = c;
    for (Hyp& h : *hyps) {
      const Eigen::Vector3d yh = h.y - h.y.dot(plane.head<3>()) * plane.head<3>();
      if (yh.norm() < 0.5) continue;  // closing across the support: not this section
      // Only closings across the round body, through its middle half (a handle's, a rim's or
      // a part's contact pair elsewhere is measured on its own).
      const Eigen::Vector3d off = h.c0 - c;
      if ((off - off.dot(plane.head<3>()) * plane.head<3>()).norm() > 0.5 * r) continue;
      // A closing axis tilted from the support crosses the mantle's section obliquely: the
      // object is 2 r / |yh| long along it (its height not counted).
      h.hint = {true, c - r / yh.norm() * h.y, c + r / yh.norm() * h.y};
    }
  }
  for (int a = 0; a < 2; ++a) {
    // A round cross-section across this axis (a cylinder lying along the other axis, seen
    // from one side down to grazing angles) is completed by its circle likewise.
    ExtentHint hint = roundCrossSection(cloud, normals, plane, footprint.axis[a], footprint.axis[1 - a],
                                        po_.centroid, tol, cfg_.gripper.finger_breadth);
    if (!hint.valid && upright.valid) {
      const Eigen::Vector3d c = 0.5 * (upright.a + upright.b);
      const double r = 0.5 * (upright.b - upright.a).norm();
      hint = {true, c - r * footprint.axis[a], c + r * footprint.axis[a]};
    }
    if (hint.valid) {
      footprint.width[a] = std::max(footprint.width[a], footprint.axis[a].dot(hint.b - hint.a));
      // Centre the hypothesis on the completed section.
      footprint.centre += footprint.axis[a] * (0.5 * footprint.axis[a].dot(hint.a + hint.b) -
                                               footprint.axis[a].dot(footprint.centre));
    }
    hyps->push_back({footprint.axis[a], footprint.centre, {}, {}, cfg_.footprint_weight, true, hint});
  }
  // The object's middle, unless a round body's axis gives it: across the footprint's narrow
  // side its completed centre (the grasp closes on the middle line; one view's centroid lies
  // towards the camera, where it shows the most surface), along the long side the centroid
  // (the centre of mass: a view shows an object's length).
  const int narrow = footprint.width[0] <= footprint.width[1] ? 0 : 1;
  if (!upright.valid)
    centre_ = po_.centroid + footprint.axis[narrow] * footprint.axis[narrow].dot(footprint.centre - po_.centroid);
}

std::string GraspSearch::tooWide() const {
  // The margin rule's "too wide" reason: the footprint's narrowest side needs more than the
  // opening (only used when no grasp is found).
  if (!use_footprint_) return "";
  const double narrowest = std::min(footprint_.width[0], footprint_.width[1]);
  if (narrowest + 2.0 * g_.clearance <= g_.max_width) return "";
  return "too wide: the object measures " + num(narrowest) +
         " m across its narrowest axis parallel to the support; the gripper opens " +
         num(g_.max_width) + " m and needs " + num(g_.clearance) +
         " m clearance each side (objects up to " + num(g_.max_width - 2.0 * g_.clearance) +
         " m)";
}

GraspFailure GraspSearch::refusal(std::string* reason) const {
  // The kind: what refused the most promising pose (the best score before the checks) that
  // held enough of the object between its fingers.
  auto count = [&](CheckOutcome o) { return outcomes_[static_cast<std::size_t>(o)]; };
  const GraspFailure most = first_refusal_ == CheckOutcome::TooWide    ? GraspFailure::TooWide
                            : first_refusal_ == CheckOutcome::Friction ? GraspFailure::Friction
                            : first_refusal_ == CheckOutcome::Hidden   ? GraspFailure::HiddenVolume
                                                                       : GraspFailure::Collides;
  int total = 0;
  for (int n : outcomes_) total += n;
  std::ostringstream os;
  if (most == GraspFailure::TooWide)
    os << "too wide: the object measures " << num(first_width_) << " m across the best-ranked closing axis; the gripper opens "
       << num(g_.max_width) << " m and needs " << num(g_.clearance) << " m clearance each side; ";
  os << "no grasp fits: of " << total << " gripper poses checked, " << count(CheckOutcome::TooFewPoints)
     << " hold too little of the object, " << count(CheckOutcome::TooWide) << " need more than the " << g_.max_width
     << " m opening, " << count(CheckOutcome::Friction) << " touch a seen surface outside the friction cone (mu "
     << cfg_.friction_coefficient << "), " << count(CheckOutcome::Collides) + count(CheckOutcome::Support)
     << " collide with the cloud or the support, " << count(CheckOutcome::Hidden)
     << " put a finger or the palm in the volume hidden behind the view";
  *reason = os.str();
  return most;
}

std::vector<Pending> GraspSearch::rankApproaches(std::vector<Hyp>* hyps) {
  // Every (hypothesis, approach) with an optimistic score (before the collision checks,
  // which are the expensive part): candidates are checked best first until enough pass.
  const Eigen::Vector3d up = cfg_.up;
  std::vector<Pending> pending;
  for (std::size_t h = 0; h < hyps->size(); ++h) {
    Hyp& hp = (*hyps)[h];
    if (hp.y.dot(ref_) < 0) hp.y = -hp.y;
    // Approach basis perpendicular to y, u = the most downward direction.
    Eigen::Vector3d u = -up - (-up).dot(hp.y) * hp.y;
    if (u.norm() < 1e-6) u = hp.y.unitOrthogonal();
    hp.u = u.normalized();
    hp.v = hp.y.cross(hp.u);
    for (int s = 0; s < cfg_.approach_steps; ++s) {
      const double phi = 2.0 * M_PI * s / cfg_.approach_steps;
      const Eigen::Vector3d a = std::cos(phi) * hp.u + std::sin(phi) * hp.v;
      // Within the tilt limit of straight down and, the gripper coming from the side the view
      // shows (its path through seen free space), of the view direction.
      if (a.dot(-up) < cos_tilt_ - 1e-12 || (!po_.view_dir.isZero() && a.dot(po_.view_dir) < cos_tilt_ - 1e-12))
        continue;
      Candidate cd;
      cd.R.col(2) = a;
      cd.R.col(1) = hp.y;
      cd.R.col(0) = hp.y.cross(a);
      cd.c = hp.c0;
      cd.antipodal = hp.q;
      score(cd);
      pending.push_back({cd.score, static_cast<int>(h), s});
    }
  }
  std::stable_sort(pending.begin(), pending.end(),
                   [](const Pending& a, const Pending& b) { return a.prescore > b.prescore; });
  return pending;
}

std::vector<Candidate> GraspSearch::checkCandidates(const std::vector<Hyp>& hyps, const std::vector<Pending>& pending) {
  std::vector<Candidate> cands;
  std::map<int, GripperCheck::Prepared> prepared;
  // A hypothesis's prepared neighbourhood is kept until its last approach is checked.
  std::vector<int> remaining(hyps.size(), 0);
  std::vector<GripperCheck::Prepared> spare;
  for (const Pending& pd : pending) ++remaining[static_cast<std::size_t>(pd.hyp)];
  const std::size_t enough = static_cast<std::size_t>(std::max(4 * cfg_.top_k, 40));
  int evaluations = 0;
  // Hypotheses whose fitted completion is wider than the opening: refused once, whatever the
  // approach (their approaches are not checked and do not count against max_evaluations).
  std::vector<char> refused(hyps.size(), 0);
  for (const Pending& pd : pending) {
    if (cands.size() >= enough || evaluations >= cfg_.max_evaluations) break;
    if (refused[static_cast<std::size_t>(pd.hyp)]) continue;
    ++evaluations;
    const Hyp& hp = hyps[static_cast<std::size_t>(pd.hyp)];
    auto it = prepared.find(pd.hyp);
    if (it == prepared.end()) {
      // Neighbourhood of the grasp for the collision checks (shared by all approaches).
      gather(hp.c0, check_radius_);
      // A freed hypothesis's buffers are reused (large allocations would go back to the system).
      it = prepared.emplace(pd.hyp, spare.empty() ? GripperCheck::Prepared() : std::move(spare.back())).first;
      if (!spare.empty()) spare.pop_back();
      check_.prepare(hp.c0, hp.y, hp.u, nbrs_, surf_, *po_.cloud, hp.single, hp.hint, &it->second);
    }
    if (it->second.too_wide) {
      refused[static_cast<std::size_t>(pd.hyp)] = 1;
      remaining[static_cast<std::size_t>(pd.hyp)] = 1;  // its buffers are freed below
      --evaluations;
    }
    const double phi = 2.0 * M_PI * pd.step / cfg_.approach_steps;
    Candidate cd;
    const CheckOutcome o = check_.evaluate(it->second, std::cos(phi), std::sin(phi), &cd.R, &cd.c, &cd.width, &cd.m);
    if (--remaining[static_cast<std::size_t>(pd.hyp)] == 0) {
      spare.push_back(std::move(it->second));
      prepared.erase(it);
    }
    ++outcomes_[static_cast<std::size_t>(o)];
    if (first_refusal_ == CheckOutcome::TooFewPoints) {
      first_refusal_ = o;
      first_width_ = cd.m.width;
    }
    if (o != CheckOutcome::Pass) continue;
    cd.q = hp.q;
    cd.antipodal = supportedQuality(hp.q, cd.m, cfg_.single_contact_weight, hp.hint.valid);
    cd.single = hp.single;
    cd.hint = hp.hint;
    cands.push_back(cd);
  }
  return cands;
}

std::vector<Candidate> GraspSearch::suppress(const std::vector<Candidate>& in, std::size_t limit) const {
  // Non-maximum suppression (a grasp and its 180 deg turn about z are the same grasp).
  const Eigen::Matrix3d flip = Eigen::Vector3d(-1, -1, 1).asDiagonal();
  std::vector<Candidate> out;
  for (const Candidate& cd : in) {
    if (out.size() >= limit) break;
    bool dup = false;
    for (const Candidate& k : out) {
      if ((cd.c - k.c).norm() > cfg_.nms_distance) continue;
      const double ang = std::min(ehc_control::rotationAngle(cd.R, k.R), ehc_control::rotationAngle(cd.R * flip, k.R));
      if (ang < cfg_.nms_angle_deg * kDeg) {
        dup = true;
        break;
      }
    }
    if (!dup) out.push_back(cd);
  }
  return out;
}

void GraspSearch::gather(const Eigen::Vector3d& centre, double radius) {
  const double r2 = radius * radius;
  nbrs_.clear();
  surf_.clear();
  // The object's points (with their outward normals, orientNormals), and the environment's when
  // it is more.
  for (std::size_t e = 0; e < obj_p_.size(); ++e) {
    if ((obj_p_[e] - centre).squaredNorm() > r2) continue;
    if (env_p_.empty()) nbrs_.push_back(obj_p_[e]);
    if (!obj_n_[e].isZero()) surf_.push_back({obj_p_[e], obj_n_[e]});
  }
  for (const Eigen::Vector3d& p : env_p_)
    if ((p - centre).squaredNorm() <= r2) nbrs_.push_back(p);
}

CheckOutcome GraspSearch::checkAt(const Candidate& cd, const Eigen::Vector3d& c0, Candidate* out) {
  GripperCheck::Prepared& pr = scratch_;
  check_.prepare(c0, cd.R.col(1), cd.R.col(2), nbrs_, surf_, *po_.cloud, cd.single, cd.hint, &pr);
  *out = cd;
  const CheckOutcome o = check_.evaluate(pr, 1.0, 0.0, &out->R, &out->c, &out->width, &out->m);
  if (o != CheckOutcome::Pass) return o;
  out->antipodal = supportedQuality(cd.q, out->m, cfg_.single_contact_weight, cd.hint.valid);
  return CheckOutcome::Pass;
}

void GraspSearch::addWallCandidates(std::vector<Candidate>* cands) const {
  if (!po_.shadow.enabled()) return;
  detail::WallInput in;
  in.points = &obj_p_;
  in.normals = &obj_n_;
  in.shadow = &po_.shadow;
  in.eye = po_.eye;
  in.plane = po_.plane;
  in.noise = po_.noise;
  in.leaf = po_.leaf;
  for (const detail::WallGrasp& w : detail::wallGrasps(cfg_, in, env_p_.empty() ? obj_p_ : env_p_)) {
    const Eigen::Vector3d a = w.R.col(2);
    if (a.dot(-cfg_.up) < cos_tilt_ - 1e-12 || (!po_.view_dir.isZero() && a.dot(po_.view_dir) < cos_tilt_ - 1e-12))
      continue;
    Candidate cd;
    cd.R = w.R;
    cd.c = w.c;
    cd.width = w.width;
    cd.q = cfg_.wall_weight;
    cd.antipodal = cfg_.wall_weight * w.cos_n;
    cd.single = cd.wall = true;
    cd.m.side[0].seen = true;
    cd.m.side[0].cos_n = w.cos_n;
    cd.m.side[0].y = w.contact_y;
    cd.m.side[1].y = w.contact_y + w.measured_width;
    cd.m.width = w.measured_width;
    cands->push_back(cd);
  }
}

void GraspSearch::refineOntoCentroid(std::vector<Candidate>* kept) {
  for (Candidate& cd : *kept) {
    if (cd.wall) continue;  // measured at its seed; another position is another wall grasp
    const Eigen::Vector3d x = cd.R.col(0);
    const double shift =
        std::max(-cfg_.max_refine_shift, std::min(cfg_.max_refine_shift, x.dot(centre_ - cd.c)));
    if (std::abs(shift) < 1e-6) continue;
    const Eigen::Vector3d c0 = cd.c + shift * x;
    gather(c0, check_radius_);
    Candidate r;
    if (checkAt(cd, c0, &r) == CheckOutcome::Pass) {
      score(r);
      cd = r;
    }
  }
}

void GraspSearch::refineDepth(std::vector<Candidate>* kept) {
  // Push the grasp along its approach axis (z) while the check passes, stop at the first
  // failing step, back off by depth_margin if a step failed on the cloud (see the header). A
  // step stopped by the support alone (its plane is fitted on many points, not one noisy
  // surface) is not backed off: the deepest passing depth is narrowed down by halving the last
  // step twice, so an object lower than the fingers is closed on near its middle. One
  // neighbourhood covers every step: radius check_radius + max/2 around the middle of the search
  // segment.
  const double smax = cfg_.max_depth_shift;
  std::vector<std::pair<double, Candidate>> passed;  // (shift, checked pose), increasing
  for (Candidate& cd : *kept) {
    if (cd.wall) continue;  // its fingers reach as deep as the view's shadow allowed
    const Eigen::Vector3d a = cd.R.col(2);
    const Eigen::Vector3d base = cd.c;
    gather(base + 0.5 * smax * a, check_radius_ + 0.5 * smax);
    passed.clear();
    CheckOutcome stop = CheckOutcome::Pass;
    double failed_at = smax;
    for (int k = 1;; ++k) {
      const double s = k * cfg_.depth_step >= smax - 1e-9 ? smax : k * cfg_.depth_step;
      Candidate r;
      stop = checkAt(cd, base + s * a, &r);
      if (stop != CheckOutcome::Pass) {
        failed_at = s;
        break;
      }
      passed.emplace_back(s, r);
      if (s >= smax) break;
    }
    if (stop == CheckOutcome::Support) {
      double lo = passed.empty() ? 0.0 : passed.back().first, hi = failed_at;
      for (int h = 0; h < 2; ++h) {
        const double mid = 0.5 * (lo + hi);
        Candidate r;
        if (checkAt(cd, base + mid * a, &r) == CheckOutcome::Pass) {
          passed.emplace_back(mid, r);
          lo = mid;
        } else {
          hi = mid;
        }
      }
      if (passed.empty()) continue;
      cd = passed.back().second;
      score(cd);
      continue;
    }
    if (passed.empty()) continue;  // the first step already fails: depth kept
    const double target = passed.back().first - (stop != CheckOutcome::Pass ? cfg_.depth_margin : 0.0);
    if (target <= 1e-9) continue;  // never behind the original depth
    // The target pose if it is a checked step or passes the check; else the deepest
    // checked step in front of it.
    const Candidate* best = nullptr;
    bool checked = false;
    for (const auto& sp : passed)
      if (sp.first <= target + 1e-9) {
        best = &sp.second;
        checked = std::abs(sp.first - target) < 1e-9;
      }
    Candidate r;
    if (!checked && checkAt(cd, base + target * a, &r) == CheckOutcome::Pass) best = &r;
    if (!best) continue;
    cd = *best;
    score(cd);
  }
}

Grasp toGrasp(const Candidate& cd) {
  Grasp gr;
  gr.pose.linear() = cd.R;
  gr.pose.translation() = cd.c;
  gr.width = cd.width;
  gr.measured_width = cd.m.width;
  gr.seen_contacts = cd.m.seen();
  gr.wall = cd.wall;
  gr.score = cd.score;
  gr.antipodal = cd.antipodal;
  gr.centroid_weight = cd.wc;
  gr.pca_weight = cd.wp;
  return gr;
}

}  // namespace

GraspResult GraspGenerator::generate(const PointList& object, const Eigen::Vector3d& viewpoint,
                                     const Eigen::Vector4d* support_plane,
                                     const PointList* collision_cloud) const {
  const GraspGeneratorConfig& cfg = config_;
  const GripperGeometry& g = cfg.gripper;
  GraspResult res;
  PreparedObject po;
  if (!filterObject(cfg, object, viewpoint, &po, &res)) return res;
  if (!describeObject(cfg, support_plane, &po, &res)) return res;
  estimateNormalsAndEnvironment(cfg, collision_cloud, viewpoint, &po);
  const std::vector<int> seeds = sampleSeeds(static_cast<int>(po.cloud->size()), cfg);

  // Hypotheses (contact pairs, single contacts, footprint axes), their approaches best
  // first, and the collision checks.
  GraspSearch search(cfg, po);
  bool any_pair = false;
  std::vector<Hyp> hyps = search.contactHypotheses(seeds, &any_pair);
  search.addFootprintHypotheses(&hyps);
  const std::vector<Pending> pending = search.rankApproaches(&hyps);
  std::vector<Candidate> cands = search.checkCandidates(hyps, pending);
  search.addWallCandidates(&cands);
  if (cands.empty()) {
    res.failure = search.refusal(&res.reason);
    // Too wide: the margin rule's reason with the object's narrowest footprint, if it breaks it.
    const std::string wide = search.tooWide();
    if (!wide.empty()) {
      res.reason = wide + "; " + res.reason;
      res.failure = GraspFailure::TooWide;
    }
    if (any_pair || res.failure != GraspFailure::Collides) return res;
    res.failure = GraspFailure::NoAntipodalPair;
    res.reason = "no antipodal contact pair within the gripper opening (" + num(g.max_width) +
                 " m) and the friction cone (mu " + num(cfg.friction_coefficient) + "); " + res.reason;
    return res;
  }

  // Score, suppress, refine (onto the centroid, then in depth), suppress again.
  for (Candidate& cd : cands) search.score(cd);
  std::sort(cands.begin(), cands.end(),
            [](const Candidate& a, const Candidate& b) { return a.score > b.score; });
  const std::size_t want = static_cast<std::size_t>(cfg.top_k);
  std::vector<Candidate> kept = search.suppress(cands, 3 * want);
  search.refineOntoCentroid(&kept);
  if (cfg.max_depth_shift > 0.0) search.refineDepth(&kept);
  std::stable_sort(kept.begin(), kept.end(),
                   [](const Candidate& a, const Candidate& b) { return a.score > b.score; });
  // Refined candidates can converge onto the same pose (e.g. several contact pairs at
  // different heights along one approach, all pushed to the deepest pose): suppress again.
  kept = search.suppress(kept, want);

  for (const Candidate& cd : kept) res.grasps.push_back(toGrasp(cd));
  return res;
}

// ------------------------------------------------------------------------------ scenes

namespace {

/// The support plane of a scene (normal within plane_max_tilt_deg of up, at least
/// min_plane_fraction of the points): the largest such plane; with `near` (where the target
/// is), the plane under it: planes are taken out largest first, at most kMaxSupportPlanes,
/// until one lies at most max_object_extent below `near`. A view over a table's edge can show
/// more floor than table top, and the floor is not what the target stands on: above it, the
/// table's edge would be an object.
constexpr int kMaxSupportPlanes = 3;
enum class SupportSearch { Found, NoPlane, NoneUnderTarget };
SupportSearch findSupportPlane(const Cloud::Ptr& cloud, const GraspGeneratorConfig& cfg, const Eigen::Vector3d* near,
                      Eigen::Vector4d* plane) {
  Cloud::Ptr rest = cloud;
  for (int k = 0; k < kMaxSupportPlanes && rest->size() >= 3; ++k) {
    pcl::ModelCoefficients coeffs;
    pcl::PointIndices inliers;
    pcl::SACSegmentation<pcl::PointXYZ> sac;
    sac.setOptimizeCoefficients(true);
    sac.setModelType(pcl::SACMODEL_PERPENDICULAR_PLANE);
    sac.setMethodType(pcl::SAC_RANSAC);
    sac.setAxis(cfg.up.cast<float>());
    sac.setEpsAngle(cfg.plane_max_tilt_deg * kDeg);
    sac.setDistanceThreshold(cfg.plane_distance);
    sac.setMaxIterations(500);
    sac.setInputCloud(rest);
    sac.segment(inliers, coeffs);
    if (coeffs.values.size() != 4 ||
        static_cast<double>(inliers.indices.size()) < cfg.min_plane_fraction * static_cast<double>(cloud->size()))
      return k == 0 ? SupportSearch::NoPlane : SupportSearch::NoneUnderTarget;
    Eigen::Vector4d pl(coeffs.values[0], coeffs.values[1], coeffs.values[2], coeffs.values[3]);
    pl /= pl.head<3>().norm();
    if (pl.head<3>().dot(cfg.up) < 0) pl = -pl;
    const double height = near ? pl.head<3>().dot(*near) + pl[3] : 0.0;
    if (!near || (height >= -cfg.plane_distance && height <= cfg.max_object_extent)) {
      *plane = pl;
      return SupportSearch::Found;
    }
    pcl::ExtractIndices<pcl::PointXYZ> extract;
    extract.setInputCloud(rest);
    extract.setIndices(pcl::PointIndices::Ptr(new pcl::PointIndices(inliers)));
    extract.setNegative(true);
    Cloud::Ptr next(new Cloud);
    extract.filter(*next);
    rest = next;
  }
  return cloud->size() < 3 ? SupportSearch::NoPlane : SupportSearch::NoneUnderTarget;
}

}  // namespace

SceneSegmentation GraspGenerator::segmentScene(const PointList& scene, const Eigen::Vector3d* viewpoint,
                                               const Eigen::Vector3d* near) const {
  const GraspGeneratorConfig& cfg = config_;
  SceneSegmentation seg;
  int finite = 0;
  Cloud::Ptr raw = toCloud(scene, &finite);
  if (finite == 0) {
    seg.reason = scene.empty() ? "empty cloud" : "no finite points (all NaN/Inf)";
    seg.failure = scene.empty() ? GraspFailure::EmptyCloud : GraspFailure::NoFinitePoints;
    return seg;
  }
  Cloud::Ptr cloud = voxelFilter(raw, cfg.voxel_size);
  Cloud::Ptr above(new Cloud);
  Eigen::Vector4d pl;
  const SupportSearch support = findSupportPlane(cloud, cfg, near, &pl);
  if (support == SupportSearch::Found) {
    seg.plane_found = true;
    seg.plane = pl;
    for (const auto& p : *cloud)
      if (pl.head<3>().dot(p.getVector3fMap().cast<double>()) + pl[3] > 1.5 * cfg.plane_distance)
        above->push_back(p);
  } else if (support == SupportSearch::NoneUnderTarget) {
    seg.reason = "no support plane under the target";
    seg.failure = GraspFailure::NoObject;
    return seg;
  } else {
    *above = *cloud;
  }
  for (const auto& p : *above) seg.obstacles.push_back(p.getVector3fMap());
  if (above->empty()) {
    seg.reason = "no points above the support plane";
    seg.failure = GraspFailure::NoObject;
    return seg;
  }
  for (const std::vector<int>& part : detail::clusterObjects(*above, *cloud, viewpoint, cfg.up, cfg)) {
    PointList obj;
    obj.reserve(part.size());
    for (int i : part) obj.push_back((*above)[static_cast<std::size_t>(i)].getVector3fMap());
    seg.objects.push_back(std::move(obj));
  }
  if (seg.objects.empty())
    seg.reason = "no cluster of at least " + std::to_string(cfg.min_cluster_points) + " points";
  if (seg.objects.empty()) seg.failure = GraspFailure::NoObject;
  return seg;
}

Eigen::Vector3d SceneSegmentation::centroid(std::size_t i) const {
  const PointList& o = objects.at(i);
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const auto& p : o) c += p.cast<double>();
  return o.empty() ? c : Eigen::Vector3d(c / static_cast<double>(o.size()));
}

int SceneSegmentation::nearestObject(const Eigen::Vector3d& p) const {
  int best = -1;
  double best_d = std::numeric_limits<double>::max();
  for (std::size_t o = 0; o < objects.size(); ++o) {
    const double d = (centroid(o) - p).norm();
    if (d < best_d) best_d = d, best = static_cast<int>(o);
  }
  return best;
}

GraspResult GraspGenerator::generateFromScene(const PointList& scene,
                                              const Eigen::Vector3d& viewpoint,
                                              const Eigen::Vector3d* near) const {
  if (near && !near->allFinite()) near = nullptr;
  GraspResult res = generateFromSegmentation(segmentScene(scene, &viewpoint, near), viewpoint, near);
  res.input_points = static_cast<int>(scene.size());
  return res;
}

GraspResult GraspGenerator::generateFromSegmentation(const SceneSegmentation& seg, const Eigen::Vector3d& viewpoint,
                                                     const Eigen::Vector3d* near) const {
  GraspResult res;
  res.support_plane_found = seg.plane_found;
  res.support_plane = seg.plane;
  if (seg.objects.empty()) {
    res.reason = seg.reason;
    res.failure = seg.failure;
    return res;
  }
  std::vector<int> which;
  if (near && near->allFinite()) {
    which.push_back(seg.nearestObject(*near));
  } else {
    for (std::size_t o = 0; o < seg.objects.size(); ++o) which.push_back(static_cast<int>(o));
  }
  std::vector<std::string> reasons;
  for (int o : which) {
    const GraspResult r = generate(seg.objects[static_cast<std::size_t>(o)], viewpoint,
                                   seg.plane_found ? &seg.plane : nullptr, &seg.obstacles);
    ++res.objects;
    res.finite_points += r.finite_points;
    res.filtered_points += r.filtered_points;
    res.voxel_size = std::max(res.voxel_size, r.voxel_size);
    res.centroids.insert(res.centroids.end(), r.centroids.begin(), r.centroids.end());
    for (Grasp gr : r.grasps) {
      gr.object = o;
      res.grasps.push_back(gr);
    }
    if (!r.reason.empty()) reasons.push_back("object " + std::to_string(o) + ": " + r.reason);
    if (res.failure == GraspFailure::None) res.failure = r.failure;  // the first (or the target) object's
  }
  std::stable_sort(res.grasps.begin(), res.grasps.end(),
                   [](const Grasp& a, const Grasp& b) { return a.score > b.score; });
  if (!res.grasps.empty()) res.failure = GraspFailure::None;
  if (res.grasps.empty()) {
    for (const std::string& r : reasons) res.reason += (res.reason.empty() ? "" : "; ") + r;
    if (res.reason.empty()) res.reason = "no grasp";
    if (res.failure == GraspFailure::None) res.failure = GraspFailure::Collides;
  }
  return res;
}

void GraspTargetingParams::validate() const {
  requireRange("GraspTargeting", "max_rate_hz", max_rate_hz, 0.01, 100.0);
  requireRange("GraspTargeting", "max_input_points", max_input_points, 100, 10000000);
  requireRange("GraspTargeting", "target_timeout", target_timeout, 0.0, 1e6);
  ehc_common::requirePositive("GraspTargeting", "target_gate", target_gate);
}

std::string GraspTargetingParams::summary() const {
  std::ostringstream os;
  os << "grasp targeting: max " << max_rate_hz << " Hz, at most " << max_input_points
     << " points read per cloud, target timeout " << target_timeout << " s, gate "
     << target_gate << " m";
  return os.str();
}

GraspTargetingParams loadGraspTargetingParams(const ConfigNode& n) {
  GraspTargetingParams p;
  p.max_rate_hz = n.get("max_rate_hz", p.max_rate_hz);
  p.max_input_points = n.get("max_input_points", p.max_input_points);
  p.target_timeout = n.get("target_timeout", p.target_timeout);
  p.target_gate = n.get("target_gate", p.target_gate);
  n.validate(p);
  return p;
}

namespace {
/// generateForTarget's grasps from `seg`, the segmentation of `scene` within the point budget.
GraspResult targetGrasps(const GraspGenerator& generator, const SceneSegmentation& seg, std::size_t scene_points,
                         const Eigen::Vector3d& viewpoint, const Eigen::Vector3d* target,
                         const GraspTargetingParams& targeting) {
  GraspResult res = generator.generateFromSegmentation(seg, viewpoint, target);
  res.input_points = static_cast<int>(scene_points);
  res.budget_points = static_cast<int>(std::min(scene_points, static_cast<std::size_t>(targeting.max_input_points)));
  const double gate = targeting.target_gate;
  if (target && !res.centroids.empty() && (res.centroids.front() - *target).norm() > gate) {
    res.failure = GraspFailure::TargetTooFar;
    res.reason = "nearest object is " + ehc_common::fixedDecimals((res.centroids.front() - *target).norm(), 3) +
                 " m from the target (gate " + ehc_common::fixedDecimals(gate, 3) + " m)";
    res.grasps.clear();
  }
  return res;
}

/// segmentScene of `scene` within the point budget (budgetPoints; a no-op on a cloud the node read
/// within it).
SceneSegmentation segmentWithinBudget(const GraspGenerator& generator, const PointList& scene,
                                      const Eigen::Vector3d& viewpoint, const Eigen::Vector3d* near,
                                      const GraspTargetingParams& targeting) {
  const auto budget = static_cast<std::size_t>(targeting.max_input_points);
  if (near && !near->allFinite()) near = nullptr;
  return generator.segmentScene(scene.size() > budget ? budgetPoints(scene, budget) : scene, &viewpoint, near);
}
/// Whether `object` runs out of the camera's frame: the frame is the angular extent of the scene's
/// points in the camera (optical frame, z forward; at most `budget` of them, evenly strided), and
/// an object point within 1.5 of its pixel pitches (the frame's area over its points) of an edge
/// is cut there. The object's extent beyond it is not in the cloud.
bool cutByFrame(const PointList& scene, const PointList& object, const Eigen::Isometry3d& camera, std::size_t budget) {
  const Eigen::Isometry3d to_cam = camera.inverse();
  double u0 = std::numeric_limits<double>::max(), v0 = u0, u1 = -u0, v1 = -u0;
  std::size_t n = 0;
  const std::size_t step = std::max<std::size_t>(1, (scene.size() + budget - 1) / std::max<std::size_t>(1, budget));
  for (std::size_t i = 0; i < scene.size(); i += step) {
    const Eigen::Vector3d q = to_cam * scene[i].cast<double>();
    if (!q.allFinite() || q.z() <= 1e-6) continue;
    u0 = std::min(u0, q.x() / q.z()), u1 = std::max(u1, q.x() / q.z());
    v0 = std::min(v0, q.y() / q.z()), v1 = std::max(v1, q.y() / q.z());
    ++n;
  }
  if (n < 4 || !(u1 > u0) || !(v1 > v0)) return false;
  const double tol = 1.5 * std::sqrt((u1 - u0) * (v1 - v0) / static_cast<double>(n));
  for (const Eigen::Vector3f& p : object) {
    const Eigen::Vector3d q = to_cam * p.cast<double>();
    if (!q.allFinite() || q.z() <= 1e-6) continue;
    const double u = q.x() / q.z(), v = q.y() / q.z();
    if (u < u0 + tol || u > u1 - tol || v < v0 + tol || v > v1 - tol) return true;
  }
  return false;
}

/// A target cut by the frame (cutByFrame): its unseen sides' bounds (the object's extent, the
/// last samples, the view's shadow) may lie short of the object, which runs on out of the view;
/// only grasps whose two contacts the view shows measure it. The others are dropped.
void keepMeasuredIfCut(const PointList& scene, const SceneSegmentation& seg, int object, const Eigen::Isometry3d& camera,
                       const GraspTargetingParams& targeting, GraspResult* res) {
  if (res->grasps.empty() || object < 0 || static_cast<std::size_t>(object) >= seg.objects.size() ||
      !cutByFrame(scene, seg.objects[static_cast<std::size_t>(object)], camera,
                  static_cast<std::size_t>(targeting.max_input_points)))
    return;
  res->grasps.erase(std::remove_if(res->grasps.begin(), res->grasps.end(), [](const Grasp& g) { return g.seen_contacts < 2; }),
                    res->grasps.end());
  if (!res->grasps.empty()) return;
  res->failure = GraspFailure::HiddenVolume;
  res->reason = "the target runs out of the camera's frame and no grasp has both contacts seen";
}
}  // namespace

GraspResult generateForTarget(const GraspGenerator& generator, const PointList& scene,
                              const Eigen::Vector3d& viewpoint, const Eigen::Vector3d* target,
                              const GraspTargetingParams& targeting) {
  if (target && !target->allFinite()) target = nullptr;
  return targetGrasps(generator, segmentWithinBudget(generator, scene, viewpoint, target, targeting), scene.size(),
                      viewpoint, target, targeting);
}

}  // namespace ehc_perception

namespace ehc_perception {

CloudTargetResult generateForCloudTarget(const GraspGenerator& generator, const PointList& scene,
                                         const Eigen::Isometry3d& camera, const ehc_control::TargetSelector& selector,
                                         const Eigen::Vector3d* tracked, const GraspTargetingParams& targeting) {
  using ehc_control::TargetSelectionStatus;
  CloudTargetResult out;
  const Eigen::Vector3d viewpoint = camera.translation();
  if (tracked && !tracked->allFinite()) tracked = nullptr;
  // A tracked target stands on the plane under it; a target nearest a point, under that point.
  const Eigen::Vector3d* under =
      tracked ? tracked : selector.kind == ehc_control::TargetSelectorKind::Nearest ? &selector.point : nullptr;
  out.segmentation = segmentWithinBudget(generator, scene, viewpoint, under, targeting);
  const SceneSegmentation& seg = out.segmentation;
  if (tracked) {
    out.grasps = targetGrasps(generator, seg, scene.size(), viewpoint, tracked, targeting);
    if (out.grasps.centroids.empty() || out.grasps.failure == GraspFailure::TargetTooFar) {
      out.selection.status = TargetSelectionStatus::NoObject;
      out.selection.detail = selector.summary() + ": the tracked object is not in the view (" + out.grasps.reason + ")";
      out.grasps.grasps.clear();
      return out;
    }
    out.object = seg.nearestObject(*tracked);
    keepMeasuredIfCut(scene, seg, out.object, camera, targeting, &out.grasps);
    out.selection.status = TargetSelectionStatus::Selected;
    out.selection.index = out.object;
    out.selection.centre = out.grasps.centroids.front();
    out.selection.detail = selector.summary() + ": tracked";
    return out;
  }
  std::vector<Eigen::Vector3d> centres;
  for (std::size_t o = 0; o < seg.objects.size(); ++o) centres.push_back(seg.centroid(o));
  out.selection = ehc_control::selectTarget(selector, centres, camera, generator.config().up);
  if (!out.selection.selected()) {
    if (!seg.reason.empty()) out.selection.detail += " (" + seg.reason + ")";
    out.grasps.reason = out.selection.detail;
    out.grasps.failure = GraspFailure::NoObject;
    return out;
  }
  out.object = out.selection.index;
  out.grasps = targetGrasps(generator, seg, scene.size(), viewpoint, &out.selection.centre, targeting);
  keepMeasuredIfCut(scene, seg, out.object, camera, targeting, &out.grasps);
  return out;
}

std::optional<ObjectExtent> cloudTargetExtent(const CloudTargetResult& r, const Eigen::Vector3d& viewpoint,
                                              const Eigen::Vector3d& up_in) {
  const SceneSegmentation& seg = r.segmentation;
  if (!r.selection.selected() || r.object < 0 || static_cast<std::size_t>(r.object) >= seg.objects.size() ||
      !up_in.allFinite() || up_in.norm() < 1e-9)
    return std::nullopt;
  const Eigen::Vector3d up = up_in.normalized();
  std::optional<double> support;
  if (seg.plane_found && std::abs(seg.plane.head<3>().dot(up)) > 1e-3) support = -seg.plane.w() / seg.plane.head<3>().dot(up);
  return clusterExtent(seg.objects[static_cast<std::size_t>(r.object)], viewpoint, up, support);
}

}  // namespace ehc_perception
