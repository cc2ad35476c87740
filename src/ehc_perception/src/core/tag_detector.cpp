#include "ehc_perception/tag_detector.h"

#include "ehc_common/config_node.h"

#include <visp3/core/vpCameraParameters.h>
#include <visp3/core/vpHomogeneousMatrix.h>
#include <visp3/core/vpImagePoint.h>
#include <visp3/core/vpImageTools.h>
#include <visp3/core/vpPoint.h>
#include <visp3/detection/vpDetectorAprilTag.h>
#include <visp3/io/vpImageIo.h>

#include <algorithm>
#include <map>
#include <memory>
#include <mutex>
#include <cmath>
#include <limits>
#include <vector>
#include <fstream>
#include <cstring>
#include <sstream>
#include <stdexcept>

using ehc_common::ConfigNode;
using ehc_common::requireRange;

namespace ehc_perception {

namespace {

const char* kOwner = "TagDetector";

[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument(std::string("[TagDetector] ") + what);
}

vpDetectorAprilTag::vpAprilTagFamily familyFromString(const std::string& s) {
  if (s == "36h11") return vpDetectorAprilTag::TAG_36h11;
  if (s == "25h9") return vpDetectorAprilTag::TAG_25h9;
  if (s == "16h5") return vpDetectorAprilTag::TAG_16h5;
  fail("unknown tag family '" + s + "' (expected 36h11, 25h9 or 16h5)");
}

vpDetectorAprilTag::vpPoseEstimationMethod poseMethodFromString(const std::string& s) {
  if (s == "homography") return vpDetectorAprilTag::HOMOGRAPHY;
  if (s == "homography_virtual_vs") return vpDetectorAprilTag::HOMOGRAPHY_VIRTUAL_VS;
  if (s == "dementhon_virtual_vs") return vpDetectorAprilTag::DEMENTHON_VIRTUAL_VS;
  if (s == "lagrange_virtual_vs") return vpDetectorAprilTag::LAGRANGE_VIRTUAL_VS;
  if (s == "best_residual_virtual_vs") return vpDetectorAprilTag::BEST_RESIDUAL_VIRTUAL_VS;
  if (s == "homography_orthogonal_iteration")
    return vpDetectorAprilTag::HOMOGRAPHY_ORTHOGONAL_ITERATION;
  fail("unknown pose_method '" + s + "'");
}

Eigen::Isometry3d toEigen(const vpHomogeneousMatrix& M) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) T.linear()(r, c) = M[static_cast<unsigned>(r)][static_cast<unsigned>(c)];
    T.translation()(r) = M[static_cast<unsigned>(r)][3];
  }
  return T;
}

}  // namespace

// ------------------------------------------------------------------------------ config

double TagDetectorConfig::tagSize(int id) const {
  const auto it = tag_sizes.find(id);
  return it == tag_sizes.end() ? default_tag_size : it->second;
}

std::vector<std::string> TagDetectorConfig::familyNames() { return {"36h11", "25h9", "16h5"}; }

std::vector<std::string> TagDetectorConfig::poseMethodNames() {
  return {"homography", "homography_virtual_vs", "dementhon_virtual_vs", "lagrange_virtual_vs",
          "best_residual_virtual_vs", "homography_orthogonal_iteration"};
}

void TagDetectorConfig::validate() const {
  familyFromString(family);
  poseMethodFromString(pose_method);
  requireRange(kOwner, "default_tag_size", default_tag_size, 1e-3, 5.0);
  for (const auto& kv : tag_sizes) {
    if (kv.first < 0) fail("tag_sizes: tag id " + std::to_string(kv.first) + " is negative");
    requireRange(kOwner, "tag_sizes[" + std::to_string(kv.first) + "]", kv.second,
                              1e-3, 5.0);
  }
  requireRange(kOwner, "quad_decimate", quad_decimate, 1.0, 8.0);
  requireRange(kOwner, "threads", threads, 1, 64);
  requireRange(kOwner, "roi_margin", roi_margin, 0, 10000);
  requireRange(kOwner, "roi_full_frame_every", roi_full_frame_every, 1, 1000);
  requireRange(kOwner, "roi_decimated_tag_px", roi_decimated_tag_px, 0.0, 10000.0);
  ehc_common::requirePositive(kOwner, "max_reprojection_error", max_reprojection_error);
  if (!prior_tag_axis.allFinite() || prior_tag_axis.norm() < 1e-9)
    fail("pose_prior.tag_axis must be a finite, non-zero vector");
  if (!prior_world_direction.allFinite() || prior_world_direction.norm() < 1e-9)
    fail("pose_prior.world_direction must be a finite, non-zero vector");
  requireRange(kOwner, "pose_prior.ambiguity_margin", ambiguity_margin, 0.0,
                            max_reprojection_error);
}

std::string TagDetectorConfig::summary() const {
  std::ostringstream os;
  os << "tag detector: family " << family << ", default size " << default_tag_size << " m";
  for (const auto& kv : tag_sizes) os << ", id " << kv.first << ": " << kv.second << " m";
  os << ", quad_decimate " << quad_decimate << ", threads " << threads << ", pose "
     << pose_method << ", tracking window "
     << (roi_margin > 0 ? "+" + std::to_string(roi_margin) + " px, whole image every " +
                              std::to_string(roi_full_frame_every)
                        : std::string("off"));
  if (roi_margin > 0 && roi_decimated_tag_px > 0.0)
    os << ", windows decimated to tags of >= " << roi_decimated_tag_px << " px";
  os
     << ", max reprojection error " << max_reprojection_error
     << " px, ambiguous poses (within " << ambiguity_margin << " px): tag axis ["
     << prior_tag_axis.transpose() << "] nearest the world's [" << prior_world_direction.transpose()
     << "]";
  return os.str();
}

TagDetectorConfig loadTagDetectorConfig(const ConfigNode& n) {
  TagDetectorConfig c;
  c.family = n.get<std::string>("family", c.family);
  c.default_tag_size = n.get<double>("default_tag_size", c.default_tag_size);
  if (n.has("tag_sizes")) {
    if (!n.yaml()["tag_sizes"].IsMap()) n.fail("tag_sizes", "must be a mapping {tag id: size in m}");
    const ConfigNode sizes = n.child("tag_sizes");
    for (const std::string& key : sizes.keys()) {
      std::size_t used = 0;
      int id = -1;
      try {
        id = std::stoi(key, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used == 0 || used != key.size()) sizes.fail(key, "must be an integer tag id (entries <tag id>: <size in m>)");
      c.tag_sizes[id] = sizes.require<double>(key);  // errors name the entry
    }
  }
  c.quad_decimate = n.get<double>("quad_decimate", c.quad_decimate);
  c.threads = n.get<int>("threads", c.threads);
  c.roi_margin = n.get<int>("roi_margin", c.roi_margin);
  c.roi_full_frame_every = n.get<int>("roi_full_frame_every", c.roi_full_frame_every);
  c.roi_decimated_tag_px = n.get<double>("roi_decimated_tag_px", c.roi_decimated_tag_px);
  c.pose_method = n.get<std::string>("pose_method", c.pose_method);
  c.max_reprojection_error = n.get<double>("max_reprojection_error", c.max_reprojection_error);
  if (n.has("pose_prior")) {
    const ConfigNode p = n.child("pose_prior");
    c.prior_tag_axis = p.getVector("tag_axis", c.prior_tag_axis, 3);
    c.prior_world_direction = p.getVector("world_direction", c.prior_world_direction, 3);
    c.ambiguity_margin = p.get<double>("ambiguity_margin", c.ambiguity_margin);
  }
  n.validate(c);
  return c;
}

// ------------------------------------------------------------------------------ detector

namespace {
/// vpDetectorAprilTag instances kept for reuse, per family: building one builds its family's
/// quick-decode table (tens of ms for 36h11), and the in-process experiments build a TagDetector
/// per trial. A detector keeps nothing from one detect() to the next that its results depend on,
/// and TagDetector sets every option it uses when it takes one. Thread-safe (experiment jobs).
class DetectorPool {
 public:
  static DetectorPool& instance() {
    static DetectorPool pool;
    return pool;
  }
  std::unique_ptr<vpDetectorAprilTag> take(vpDetectorAprilTag::vpAprilTagFamily family) {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      auto& spare = free_[family];
      if (!spare.empty()) {
        std::unique_ptr<vpDetectorAprilTag> d = std::move(spare.back());
        spare.pop_back();
        return d;
      }
    }
    return std::make_unique<vpDetectorAprilTag>(family);
  }
  void give(vpDetectorAprilTag::vpAprilTagFamily family, std::unique_ptr<vpDetectorAprilTag> d) {
    const std::lock_guard<std::mutex> lock(mutex_);
    free_[family].push_back(std::move(d));
  }

 private:
  std::mutex mutex_;
  std::map<vpDetectorAprilTag::vpAprilTagFamily, std::vector<std::unique_ptr<vpDetectorAprilTag>>> free_;
};
}  // namespace

struct TagDetector::Impl {
  /// A detector of the configured family (DetectorPool), every option set from `c`.
  explicit Impl(const TagDetectorConfig& c)
      : family(familyFromString(c.family)), owned(DetectorPool::instance().take(family)), detector(*owned) {
    detector.setAprilTagPoseEstimationMethod(poseMethodFromString(c.pose_method));
    detector.setAprilTagQuadDecimate(static_cast<float>(c.quad_decimate));
    detector.setAprilTagNbThreads(c.threads);
    detector.setDisplayTag(false);
  }
  ~Impl() { DetectorPool::instance().give(family, std::move(owned)); }
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;
  vpDetectorAprilTag::vpAprilTagFamily family;
  std::unique_ptr<vpDetectorAprilTag> owned;
  vpDetectorAprilTag& detector;
  vpCameraParameters cam;
  vpCameraParameters window_cam;  ///< cam with the principal point in the window's pixels
  vpImage<unsigned char> buffer;
  vpImage<unsigned char> window;
};

TagDetector::TagDetector(const TagDetectorConfig& config, const ehc_control::PinholeCamera& camera)
    : config_(config), camera_(camera) {
  config_.validate();
  try {
    camera_.validate();
  } catch (const std::invalid_argument& e) {
    fail(std::string("bad camera: ") + e.what());
  }
  impl_ = std::make_unique<Impl>(config_);
  impl_->cam.initPersProjWithoutDistortion(camera_.fx, camera_.fy, camera_.cx, camera_.cy);
}

TagDetector::~TagDetector() = default;
TagDetector::TagDetector(TagDetector&&) noexcept = default;
TagDetector& TagDetector::operator=(TagDetector&&) noexcept = default;

std::vector<TagDetection> TagDetector::detect(const unsigned char* data, int width, int height,
                                              int stride) {
  if (!data) fail("image buffer is null");
  if (width <= 0 || height <= 0 || stride < width)
    fail("bad image geometry " + std::to_string(width) + "x" + std::to_string(height) +
         " stride " + std::to_string(stride));
  vpImage<unsigned char>& I = impl_->buffer;
  if (static_cast<int>(I.getWidth()) != width || static_cast<int>(I.getHeight()) != height)
    I.resize(static_cast<unsigned>(height), static_cast<unsigned>(width));
  for (int r = 0; r < height; ++r)
    std::memcpy(I[static_cast<unsigned>(r)], data + static_cast<std::size_t>(r) * stride,
                static_cast<std::size_t>(width));
  return detect(I);
}

std::vector<TagDetection> TagDetector::detect(const vpImage<unsigned char>& I) {
  return detectResolving(I, nullptr);
}

std::vector<TagDetection> TagDetector::detect(const vpImage<unsigned char>& I,
                                              const Eigen::Isometry3d& T_world_cam) {
  if (!T_world_cam.matrix().allFinite()) fail("camera pose is not finite");
  return detectResolving(I, &T_world_cam);
}

namespace {
/// The shortest side (px) of a tag's quadrilateral in the image.
double shortestSide(const std::array<Eigen::Vector2d, 4>& corners) {
  double side = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < 4; ++k) side = std::min(side, (corners[(k + 1) % 4] - corners[k]).norm());
  return side;
}
}  // namespace

std::array<int, 4> TagDetector::windowAround(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi) const {
  const Eigen::Vector2d grow = Eigen::Vector2d::Constant(config_.roi_margin) + 0.5 * (hi - lo);
  const double c0 = std::max(0.0, std::floor(lo.x() - grow.x())), r0 = std::max(0.0, std::floor(lo.y() - grow.y()));
  const double c1 = std::min<double>(camera_.width, std::ceil(hi.x() + grow.x()) + 1);
  const double r1 = std::min<double>(camera_.height, std::ceil(hi.y() + grow.y()) + 1);
  if (c1 - c0 < 16 || r1 - r0 < 16) return {{0, 0, 0, 0}};  // also: the box lies outside the image
  return {{static_cast<int>(c0), static_cast<int>(r0), static_cast<int>(c1 - c0), static_cast<int>(r1 - r0)}};
}

TagDetector::Prediction TagDetector::predict(const Eigen::Isometry3d& T_world_cam, std::array<int, 4>* window,
                                             double* tag_px) const {
  if (config_.roi_margin <= 0 || wanted_tags_.empty()) return Prediction::Unknown;
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  bool any_visible = false;
  *tag_px = std::numeric_limits<double>::infinity();
  const Eigen::Isometry3d T_cam_world = T_world_cam.inverse();
  const Eigen::Vector2d m = Eigen::Vector2d::Constant(config_.roi_margin);
  const Eigen::Vector2d size(camera_.width, camera_.height);
  for (int id : wanted_tags_) {
    const auto it = seen_in_world_.find(id);
    if (it == seen_in_world_.end()) return Prediction::Unknown;
    const Eigen::Isometry3d T_cam_tag = T_cam_world * it->second;
    // A tag seen edge-on or from behind cannot be detected: it is predicted out of view.
    if (T_cam_tag.linear().col(2).dot(T_cam_tag.translation()) >= 0.0) continue;
    // So can a tag with a corner behind the camera, or outside the image grown by roi_margin (the
    // prediction's error): a tag is found only when it is whole in the image.
    const double h = 0.5 * config_.tagSize(id);
    std::array<Eigen::Vector3d, 4> corners;
    int k = 0;
    for (const Eigen::Vector2d& c : {Eigen::Vector2d(-h, -h), Eigen::Vector2d(h, -h), Eigen::Vector2d(h, h),
                                     Eigen::Vector2d(-h, h)})
      corners[k++] = T_cam_tag * Eigen::Vector3d(c.x(), c.y(), 0.0);
    if (std::any_of(corners.begin(), corners.end(), [](const Eigen::Vector3d& p) { return p.z() < kMinPredictionDepth; }))
      continue;
    Eigen::Vector2d tag_lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()), tag_hi = -tag_lo;
    std::array<Eigen::Vector2d, 4> pixels;
    for (std::size_t i = 0; i < 4; ++i) {
      pixels[i] = camera_.pixel(corners[i]);
      tag_lo = tag_lo.cwiseMin(pixels[i]);
      tag_hi = tag_hi.cwiseMax(pixels[i]);
    }
    if ((tag_lo.array() < -m.array()).any() || (tag_hi.array() > (size + m).array()).any()) continue;
    lo = lo.cwiseMin(tag_lo);
    hi = hi.cwiseMax(tag_hi);
    *tag_px = std::min(*tag_px, shortestSide(pixels));
    any_visible = true;
  }
  if (!any_visible) return Prediction::OutOfView;
  *window = windowAround(lo, hi);
  return (*window)[2] == 0 ? Prediction::OutOfView : Prediction::InView;
}

bool TagDetector::search(const vpImage<unsigned char>& I, const Eigen::Isometry3d* T_world_cam, int* u0, int* v0,
                         const vpCameraParameters** cam) {
  // The window of the next search: from the last image's detections, else from where the wanted
  // tags were last seen in the world (the camera pose known).
  std::array<int, 4> window = window_;
  double tag_px = window_tag_px_;
  window_ = {{0, 0, 0, 0}};
  Prediction prediction = Prediction::Unknown;
  if (window[2] == 0 && T_world_cam) prediction = predict(*T_world_cam, &window, &tag_px);
  const bool whole = (window[2] == 0 && prediction != Prediction::OutOfView) ||
                     ++images_since_full_ >= config_.roi_full_frame_every;
  *u0 = 0;
  *v0 = 0;
  *cam = &impl_->cam;
  if (whole) {
    images_since_full_ = 0;
    ++full_searches_;
    return impl_->detector.detect(I);
  }
  if (window[2] == 0) {  // predicted out of view: not searched until the next whole image
    ++skipped_searches_;
    return false;
  }
  ++window_searches_;
  *u0 = window[0];
  *v0 = window[1];
  vpImage<unsigned char>& W = impl_->window;
  vpImageTools::crop(I, *v0, *u0, static_cast<unsigned>(window[3]), static_cast<unsigned>(window[2]), W);
  impl_->window_cam.initPersProjWithoutDistortion(camera_.fx, camera_.fy, camera_.cx - *u0, camera_.cy - *v0);
  *cam = &impl_->window_cam;
  // Quads on the decimated window (the expected tag stays >= roi_decimated_tag_px long).
  const double decimate = config_.roi_decimated_tag_px > 0.0
                              ? std::clamp(std::floor(tag_px / config_.roi_decimated_tag_px), 1.0, 4.0)
                              : 1.0;
  if (decimate <= config_.quad_decimate) return impl_->detector.detect(W);
  impl_->detector.setAprilTagQuadDecimate(static_cast<float>(decimate));
  const bool found = impl_->detector.detect(W);
  impl_->detector.setAprilTagQuadDecimate(static_cast<float>(config_.quad_decimate));
  return found;
}

std::vector<TagDetection> TagDetector::detectResolving(const vpImage<unsigned char>& I,
                                                       const Eigen::Isometry3d* T_world_cam) {
  if (I.getSize() == 0) fail("image is empty");
  if (static_cast<int>(I.getWidth()) != camera_.width ||
      static_cast<int>(I.getHeight()) != camera_.height)
    fail("image is " + std::to_string(I.getWidth()) + "x" + std::to_string(I.getHeight()) +
         " but camera '" + camera_.name + "' is " + std::to_string(camera_.width) + "x" +
         std::to_string(camera_.height));
  Eigen::Vector3d prior = Eigen::Vector3d::Zero();
  if (T_world_cam) prior = T_world_cam->linear().transpose() * config_.prior_world_direction.normalized();
  const Eigen::Vector3d* prior_in_camera = T_world_cam ? &prior : nullptr;

  std::vector<TagDetection> out;
  vpDetectorAprilTag& det = impl_->detector;
  // Whole image or a window (then ViSP sees the window, its camera the window's principal
  // point, and the corners are shifted back to image pixels).
  int u0 = 0, v0 = 0;
  const vpCameraParameters* cam = nullptr;
  if (!search(I, T_world_cam, &u0, &v0, &cam)) return out;
  const std::vector<int> ids = det.getTagsId();
  std::map<int, double> sizes;
  for (int id : ids) sizes[id] = config_.tagSize(id);
  const std::vector<std::vector<vpPoint>> pts3d = det.getTagsPoints3D(ids, sizes);
  const Eigen::Vector3d tag_axis = config_.prior_tag_axis.normalized();

  for (std::size_t i = 0; i < ids.size(); ++i) {
    TagDetection d;
    d.id = ids[i];
    d.tag_size = config_.tagSize(d.id);
    const std::vector<vpImagePoint> poly = det.getPolygon(i);
    if (poly.size() != 4 || i >= pts3d.size() || pts3d[i].size() != 4) continue;
    for (std::size_t k = 0; k < 4; ++k)
      d.corners[k] = Eigen::Vector2d(poly[k].get_u() + u0, poly[k].get_v() + v0);
    // RMS reprojection error (px) of a pose; +inf for a pose that is unusable.
    auto reprojection = [&](const Eigen::Isometry3d& T) {
      if (!T.matrix().allFinite() || T.translation().z() <= 0.0)
        return std::numeric_limits<double>::infinity();
      double sq = 0.0;
      for (std::size_t k = 0; k < 4; ++k) {
        const vpPoint& P = pts3d[i][k];
        const Eigen::Vector3d pc = T * Eigen::Vector3d(P.get_oX(), P.get_oY(), P.get_oZ());
        if (pc.z() <= 0.0) return std::numeric_limits<double>::infinity();
        sq += (camera_.pixel(pc) - d.corners[k]).squaredNorm();
      }
      return std::sqrt(sq / 4.0);
    };
    vpHomogeneousMatrix cMo, cMo2;
    if (!det.getPose(i, d.tag_size, *cam, cMo, &cMo2)) continue;
    Eigen::Isometry3d kept = toEigen(cMo), other = toEigen(cMo2);
    double kept_error = reprojection(kept), other_error = reprojection(other);
    if (other_error < kept_error) {
      std::swap(kept, other);
      std::swap(kept_error, other_error);
    }
    if (!std::isfinite(kept_error)) continue;
    if (!std::isfinite(other_error)) {  // one usable solution
      other = kept;
      other_error = kept_error;
    }
    const bool distinct =
        Eigen::AngleAxisd(kept.linear().transpose() * other.linear()).angle() > 1e-6;
    d.ambiguous = distinct && config_.ambiguity_margin > 0.0 &&
                  other_error - kept_error <= config_.ambiguity_margin &&
                  other_error <= config_.max_reprojection_error;
    if (d.ambiguous && prior_in_camera &&
        (other.linear() * tag_axis).dot(*prior_in_camera) >
            (kept.linear() * tag_axis).dot(*prior_in_camera)) {
      std::swap(kept, other);
      std::swap(kept_error, other_error);
    }
    d.T_cam_tag = kept;
    d.reprojection_error = kept_error;
    d.T_cam_tag_other = other;
    d.other_reprojection_error = other_error;
    if (d.reprojection_error > config_.max_reprojection_error) continue;
    out.push_back(d);
  }
  if (T_world_cam)
    for (const TagDetection& d : out) seen_in_world_[d.id] = *T_world_cam * d.T_cam_tag;
  track(out);
  return out;
}

void TagDetector::track(const std::vector<TagDetection>& out) {
  const bool wanted_found = std::all_of(wanted_tags_.begin(), wanted_tags_.end(), [&](int id) {
    return std::any_of(out.begin(), out.end(), [id](const TagDetection& d) { return d.id == id; });
  });
  if (config_.roi_margin <= 0 || out.empty() || !wanted_found) return;
  // The box around the wanted tags (every tag found when none is wanted): other tags in view
  // would widen the window (three on a table: most of the image) and are found again in the
  // next whole image.
  const auto tracked = [&](const TagDetection& d) {
    return wanted_tags_.empty() || std::find(wanted_tags_.begin(), wanted_tags_.end(), d.id) != wanted_tags_.end();
  };
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  window_tag_px_ = std::numeric_limits<double>::infinity();
  for (const TagDetection& d : out)
    if (tracked(d)) {
      window_tag_px_ = std::min(window_tag_px_, shortestSide(d.corners));
      for (const Eigen::Vector2d& c : d.corners) {
        lo = lo.cwiseMin(c);
        hi = hi.cwiseMax(c);
      }
    }
  window_ = windowAround(lo, hi);
}

void TagDetector::setWantedTags(const std::vector<int>& ids) {
  if (ids == wanted_tags_) return;
  wanted_tags_ = ids;
  resetTracking();
}

void TagDetector::resetTracking() {
  window_ = {{0, 0, 0, 0}};
  images_since_full_ = 0;
}

namespace {
constexpr double kMaxImagePixels = 50e6;  ///< far above any camera's frame (D435: 2 Mpx)

/// Width x height a PNG, PNM (P2/P5/P3/P6) or JPEG file declares in its header; 0 if the format
/// is not one of these (the reader then decides). Read before the decoder allocates the image.
double declaredPixels(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::vector<unsigned char> h(64 * 1024);
  f.read(reinterpret_cast<char*>(h.data()), static_cast<std::streamsize>(h.size()));
  h.resize(static_cast<std::size_t>(f.gcount()));
  auto be = [&](std::size_t at, int bytes) {
    double v = 0;
    for (int k = 0; k < bytes; ++k) v = v * 256 + h[at + static_cast<std::size_t>(k)];
    return v;
  };
  if (h.size() >= 24 && h[0] == 0x89 && h[1] == 'P' && h[2] == 'N' && h[3] == 'G')
    return be(16, 4) * be(20, 4);  // IHDR width, height
  if (h.size() >= 2 && h[0] == 'P' && std::string("2356").find(static_cast<char>(h[1])) != std::string::npos) {
    std::string text(h.begin() + 2, h.end());
    std::istringstream ss(text);
    std::string word;
    std::vector<double> dims;
    while (dims.size() < 2 && ss >> word) {
      if (word[0] == '#') {
        std::getline(ss, word);
        continue;
      }
      try {
        dims.push_back(std::stod(word));
      } catch (const std::exception&) {
        return 0;
      }
    }
    return dims.size() == 2 ? dims[0] * dims[1] : 0;
  }
  if (h.size() >= 4 && h[0] == 0xFF && h[1] == 0xD8) {  // JPEG: walk the markers to a SOFn
    std::size_t at = 2;
    while (at + 9 < h.size() && h[at] == 0xFF) {
      const unsigned char m = h[at + 1];
      if (m >= 0xC0 && m <= 0xCF && m != 0xC4 && m != 0xC8 && m != 0xCC)
        return be(at + 5, 2) * be(at + 7, 2);  // SOFn: height, width
      at += 2 + static_cast<std::size_t>(be(at + 2, 2));
    }
  }
  return 0;
}
}  // namespace

vpImage<unsigned char> loadGrayImage(const std::string& path) {
  vpImage<unsigned char> I;
  const double pixels = declaredPixels(path);
  if (pixels > kMaxImagePixels)
    fail("cannot read image '" + path + "': its header declares " +
         std::to_string(static_cast<long long>(pixels)) + " pixels (more than " +
         std::to_string(static_cast<long long>(kMaxImagePixels)) + ")");
  try {
    vpImageIo::read(I, path);
  } catch (const std::exception& e) {
    fail("cannot read image '" + path + "': " + e.what());
  }
  if (I.getSize() == 0) fail("cannot read image '" + path + "': empty image");
  return I;
}

// ------------------------------------------------------------------------------ target

Eigen::Matrix3d rpyToMatrix(const Eigen::Vector3d& rpy) {
  return (Eigen::AngleAxisd(rpy.z(), Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(rpy.y(), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(rpy.x(), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Eigen::Isometry3d TagTargetConfig::offset() const {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = rpyToMatrix(offset_rpy);
  T.translation() = offset_xyz;
  return T;
}

void TagTargetConfig::validate() const {
  if (tag_id < 0) throw std::invalid_argument("[TagTarget] tag_id must be >= 0");
  if (!offset_xyz.allFinite() || !offset_rpy.allFinite())
    throw std::invalid_argument("[TagTarget] grasp offset must be finite");
  if (offset_xyz.norm() > 2.0)
    throw std::invalid_argument("[TagTarget] grasp offset is farther than 2 m from the tag");
}

std::string TagTargetConfig::summary() const {
  std::ostringstream os;
  os << "target: tag id " << tag_id << ", grasp offset xyz [" << offset_xyz.transpose()
     << "] m, rpy [" << offset_rpy.transpose() << "] rad";
  return os.str();
}

TagTargetConfig loadTagTargetConfig(const ConfigNode& n) {
  TagTargetConfig t;
  t.tag_id = n.get<int>("tag_id", t.tag_id);
  if (n.has("grasp_offset")) {
    const ConfigNode g = n.child("grasp_offset");
    t.offset_xyz = g.getVector("xyz", t.offset_xyz, 3);
    t.offset_rpy = g.getVector("rpy", t.offset_rpy, 3);
  }
  try {
    t.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string(e.what()) + " (in " + n.file() + ")");
  }
  return t;
}

bool findTarget(const std::vector<TagDetection>& detections, const TagTargetConfig& target,
                Eigen::Isometry3d* T_cam_target) {
  for (const TagDetection& d : detections) {
    if (d.id != target.tag_id) continue;
    if (T_cam_target) *T_cam_target = d.T_cam_tag * target.offset();
    return true;
  }
  return false;
}

bool findTargetInWorld(const std::vector<TagDetection>& detections, const TagTargetConfig& target,
                       const Eigen::Isometry3d& T_world_cam, Eigen::Isometry3d* T_world_target) {
  Eigen::Isometry3d T_cam_target;
  if (!findTarget(detections, target, &T_cam_target)) return false;
  const Eigen::Isometry3d T_world = T_world_cam * T_cam_target;
  if (!T_world.matrix().allFinite()) throw std::runtime_error("[TagTarget] target pose is not finite");
  if (T_world_target) *T_world_target = T_world;
  return true;
}

}  // namespace ehc_perception
