#include "ehc_sim/simulated_camera.h"

#include "ehc_common/config_node.h"
#include "ehc_sim/sim_world.h"
#include "ehc_sim/triangle_raster.h"

#include <apriltag/apriltag.h>
#include <apriltag/common/image_u8.h>
#include <apriltag/tag36h11.h>

#include <visp3/core/vpCameraParameters.h>
#include <visp3/core/vpColVector.h>
#include <visp3/core/vpHomogeneousMatrix.h>
#include <visp3/core/vpMatrix.h>
#include <visp3/robot/vpImageSimulator.h>

#include <array>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

using ehc_common::requireRange;

namespace ehc_sim {

namespace {
[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument("[SimulatedCamera] " + what);
}

vpHomogeneousMatrix toVisp(const Eigen::Isometry3d& T) {
  vpHomogeneousMatrix M;
  for (unsigned r = 0; r < 3; ++r)
    for (unsigned c = 0; c < 4; ++c) M[r][c] = T.matrix()(r, c);
  return M;
}

vpColVector col(const Eigen::Vector3d& p) {
  vpColVector v(3);
  v[0] = p.x();
  v[1] = p.y();
  v[2] = p.z();
  return v;
}

constexpr int kNoiseTable = 1 << 18;
constexpr double kNearPlane = 0.01;  ///< m: faces with a corner closer than this are not drawn
constexpr int kCylinderSides = 16;
constexpr double kDepthNear = 1e-4;  ///< m: surfaces nearer than this are clipped from the depth
constexpr double kTagBorderMargin = 2.0;  ///< px, tagInView: beyond two cells of the tag

/// The faces the image shows: a box's six, a mesh's triangles, a cylinder as a 16-sided prism
/// whose sides' middles touch the cylinder and face +-x and +-y (vertices half a side off the
/// axes), so that a tag on a +-x / +-y face lies flat 0.5 mm in front of a side (with a vertex
/// on the axis, the edge there poked through the tag and drew a seam across it; close up the
/// detector lost the tag).
std::shared_ptr<const TriangleMesh> imageSurface(const BodyConfig& b) {
  switch (b.shape) {
    case ShapeType::Box: return std::make_shared<const TriangleMesh>(boxSurface(b.size));
    case ShapeType::Cylinder:
      return std::make_shared<const TriangleMesh>(
          cylinderSurface(b.size.x() / std::cos(M_PI / kCylinderSides), b.size.y(), kCylinderSides));
    case ShapeType::Mesh: return b.mesh;
  }
  return nullptr;
}
}  // namespace

vpImage<unsigned char> makeTagTexture(int id, int pixels_per_cell) {
  if (pixels_per_cell < 1 || pixels_per_cell > 64) fail("tag texture: pixels_per_cell must be in [1, 64]");
  apriltag_family_t* family = tag36h11_create();
  if (id < 0 || id >= static_cast<int>(family->ncodes)) {
    const int n = static_cast<int>(family->ncodes);
    tag36h11_destroy(family);
    fail("tag id " + std::to_string(id) + " is not in tag36h11 (0.." + std::to_string(n - 1) + ")");
  }
  image_u8_t* im = apriltag_to_image(family, id);
  const int w = im->width;
  vpImage<unsigned char> out(static_cast<unsigned>(w * pixels_per_cell),
                             static_cast<unsigned>(w * pixels_per_cell));
  for (int r = 0; r < w * pixels_per_cell; ++r)
    for (int c = 0; c < w * pixels_per_cell; ++c)
      out[r][c] = im->buf[(r / pixels_per_cell) * im->stride + c / pixels_per_cell];
  image_u8_destroy(im);
  tag36h11_destroy(family);
  return out;
}

struct SimulatedCamera::Impl {
  struct Quad {
    int body = 0;
    std::array<Eigen::Vector3d, 4> corners;  ///< body frame
    vpImageSimulator sim{vpImageSimulator::GRAY_SCALED};
  };
  std::vector<std::unique_ptr<Quad>> quads;  // vpImageSimulator is heavy: never copied
  /// A tag's pattern as tagInView sees it (its textured quad is one of `quads`).
  struct Tag {
    int body = 0;
    std::array<Eigen::Vector3d, 4> black;  ///< corners of its black square (body frame)
    Eigen::Vector3d outward = Eigen::Vector3d::Zero();  ///< its printed side's normal (body frame)
  };
  std::vector<Tag> tags;
  /// A body's faces as triangles and their grey levels (its shade, lit).
  struct FlatBody {
    int body = 0;
    std::shared_ptr<const TriangleMesh> mesh;
    std::vector<unsigned char> shade;
    bool cull = false;  ///< closed and wound outwards (boxes, cylinders): faces turned away are hidden
  };
  std::vector<FlatBody> bodies;
  int background = 110;
  vpMatrix zbuffer;
  std::vector<signed char> noise;
  vpCameraParameters cam;
  RasterGrid grid;                       ///< the depth samples (the image's pinhole, scaled)
  std::vector<double> depth;             ///< per sample, noiseless, camera z (inf: no surface)
  std::vector<Eigen::Vector3d> normal;   ///< per sample, the surface's normal (camera frame)
};

SimulatedCamera::SimulatedCamera(const ehc_control::PinholeCamera& intrinsics,
                                 const SimulatedCameraConfig& cfg, unsigned seed)
    : intrinsics_(intrinsics), cfg_(cfg), impl_(std::make_unique<Impl>()) {
  intrinsics_.validate();
  // The simulator's own limits on the camera it renders.
  requireRange("SimulatedCamera", "image_width", intrinsics_.width, 16, 8192);
  requireRange("SimulatedCamera", "image_height", intrinsics_.height, 16, 8192);
  requireRange("SimulatedCamera", "fx", intrinsics_.fx, 1.0, 1e5);
  requireRange("SimulatedCamera", "fy", intrinsics_.fy, 1.0, 1e5);
  cfg_.validate();
  impl_->cam.initPersProjWithoutDistortion(intrinsics_.fx, intrinsics_.fy, intrinsics_.cx,
                                           intrinsics_.cy);
  impl_->zbuffer.resize(static_cast<unsigned>(intrinsics_.height), static_cast<unsigned>(intrinsics_.width));
  // Sample (c, r) of the depth grid sits at pixel ((c + 0.5) su - 0.5, (r + 0.5) sv - 0.5).
  const double su = static_cast<double>(intrinsics_.width) / cfg_.ray_cols;
  const double sv = static_cast<double>(intrinsics_.height) / cfg_.ray_rows;
  impl_->grid = RasterGrid{cfg_.ray_cols, cfg_.ray_rows, intrinsics_.fx / su, intrinsics_.fy / sv,
                           (intrinsics_.cx + 0.5) / su - 0.5, (intrinsics_.cy + 0.5) / sv - 0.5};
  reseed(seed);
}

SimulatedCamera::~SimulatedCamera() = default;
SimulatedCamera::SimulatedCamera(SimulatedCamera&&) noexcept = default;

int SimulatedCamera::faceCount() const {
  std::size_t n = impl_->quads.size();
  for (const auto& b : impl_->bodies) n += b.mesh->triangles.size();
  return static_cast<int>(n);
}

void SimulatedCamera::reseed(unsigned seed) {
  rng_.seed(seed);
  gauss_.reset();
  uniform_.reset();
  impl_->noise.resize(kNoiseTable);
  for (auto& v : impl_->noise) {
    const double n = std::round(cfg_.image_noise * gauss_(rng_));
    v = static_cast<signed char>(std::max(-127.0, std::min(127.0, n)));
  }
}

void SimulatedCamera::setScene(const std::vector<BodyConfig>& bodies, int floor_shade) {
  Impl& m = *impl_;
  m.quads.clear();
  m.tags.clear();
  m.bodies.clear();
  m.background = cfg_.background >= 0 ? cfg_.background : floor_shade;
  const Eigen::Vector3d light = Eigen::Vector3d(0.3, -0.2, 1.0).normalized();
  // A textured quad; corners clockwise seen from outside, as vpImageSimulator expects.
  auto pushQuad = [&](int body, const vpImage<unsigned char>& tex, const std::vector<Eigen::Vector3d>& c,
                      bool bilinear) {
    auto q = std::make_unique<Impl::Quad>();
    q->body = body;
    vpColVector X[4];
    for (int i = 0; i < 4; ++i) {
      X[i] = col(c[static_cast<std::size_t>(i)]);
      q->corners[static_cast<std::size_t>(i)] = c[static_cast<std::size_t>(i)];
    }
    q->sim.init(tex, X);
    q->sim.setInterpolationType(bilinear ? vpImageSimulator::BILINEAR_INTERPOLATION
                                         : vpImageSimulator::SIMPLE);
    m.quads.push_back(std::move(q));
  };

  for (std::size_t bi = 0; bi < bodies.size(); ++bi) {
    const BodyConfig& b = bodies[bi];
    const int body = static_cast<int>(bi);
    // The faces: flat-shaded triangles (light from above), drawn by rasterTriangle in render().
    Impl::FlatBody fb{body, imageSurface(b), {}, b.shape != ShapeType::Mesh};
    for (std::size_t t = 0; t < fb.mesh->triangles.size(); ++t) {
      const Eigen::Vector3d n = fb.mesh->normal(t);
      fb.shade.push_back(static_cast<unsigned char>(std::clamp(b.shade * (0.6 + 0.4 * std::max(0.0, n.dot(light))), 0.0, 255.0)));
    }
    m.bodies.push_back(std::move(fb));
    if (b.tag.enabled) {
      const Eigen::Isometry3d T = tagPoseInBody(b);  // x right, y up, z out of the face
      const vpImage<unsigned char> tex = makeTagTexture(b.tag.id, cfg_.tag_pixels_per_cell);
      // vpImageSimulator maps the quad's [0, 1] to texel centres 0 .. W-1: shrink the quad by
      // half a texel on each side so that the printed pattern has its exact size.
      const double a = 0.5 * b.tag.size * 10.0 / 8.0 * (1.0 - 1.0 / tex.getWidth());
      const Eigen::Vector3d lift = 0.0005 * T.linear().col(2);  // 0.5 mm in front of the face
      // Corners top-left, top-right, bottom-right, bottom-left of the pattern: clockwise seen
      // from outside, as vpImageSimulator expects.
      std::vector<Eigen::Vector3d> c = {T * Eigen::Vector3d(-a, a, 0) + lift,
                                        T * Eigen::Vector3d(a, a, 0) + lift,
                                        T * Eigen::Vector3d(a, -a, 0) + lift,
                                        T * Eigen::Vector3d(-a, -a, 0) + lift};
      pushQuad(body, tex, c, true);
      const double s = 0.5 * b.tag.size;
      m.tags.push_back({body,
                        {T * Eigen::Vector3d(-s, s, 0) + lift, T * Eigen::Vector3d(s, s, 0) + lift,
                         T * Eigen::Vector3d(s, -s, 0) + lift, T * Eigen::Vector3d(-s, -s, 0) + lift},
                        T.linear().col(2)});
    }
  }
}

void SimulatedCamera::render(const Eigen::Isometry3d& T_world_cam,
                             const std::vector<Eigen::Isometry3d>& poses,
                             vpImage<unsigned char>* image) {
  Impl& m = *impl_;
  const unsigned W = static_cast<unsigned>(intrinsics_.width), H = static_cast<unsigned>(intrinsics_.height);
  image->resize(H, W);
  *image = static_cast<unsigned char>(m.background);
  double* zb = m.zbuffer.data;
  std::fill(zb, zb + static_cast<std::size_t>(W) * H, -1.0);
  const Eigen::Isometry3d T_cam_world = T_world_cam.inverse();
  for (auto& q : m.quads) {
    if (q->body < 0 || q->body >= static_cast<int>(poses.size())) fail("render: fewer poses than bodies");
    const Eigen::Isometry3d T_cam_body = T_cam_world * poses[static_cast<std::size_t>(q->body)];
    // vpImageSimulator crashes (empty triangles, out-of-bounds writes) on a face with a corner
    // behind or at the camera: such faces are not drawn (no near-plane clipping).
    bool in_front = true;
    for (const auto& c : q->corners) in_front &= (T_cam_body * c).z() > kNearPlane;
    if (!in_front) {
      ++clipped_faces_;
      continue;
    }
    q->sim.setCameraPosition(toVisp(T_cam_body));
    q->sim.getImage(*image, m.cam, m.zbuffer);
  }
  drawFaces(T_cam_world, poses, image);
  if (cfg_.image_noise > 0.0) {
    int k = noiseOffset();
    unsigned char* px = image->bitmap;
    const std::size_t n = static_cast<std::size_t>(W) * H;
    for (std::size_t i = 0; i < n; ++i) {
      const int v = px[i] + m.noise[static_cast<std::size_t>(k)];
      px[i] = static_cast<unsigned char>(v < 0 ? 0 : (v > 255 ? 255 : v));
      k = (k + 1) & (kNoiseTable - 1);
    }
  }
}

void SimulatedCamera::drawFaces(const Eigen::Isometry3d& T_cam_world, const std::vector<Eigen::Isometry3d>& poses,
                                  vpImage<unsigned char>* image) {
  Impl& m = *impl_;
  const RasterGrid g{intrinsics_.width, intrinsics_.height, intrinsics_.fx, intrinsics_.fy, intrinsics_.cx, intrinsics_.cy};
  double* zb = m.zbuffer.data;  // camera z as vpImageSimulator writes it; < 0: empty
  std::vector<Eigen::Vector3d> v;
  for (const Impl::FlatBody& mb : m.bodies) {
    if (mb.body >= static_cast<int>(poses.size())) fail("render: fewer poses than bodies");
    const Eigen::Isometry3d T = T_cam_world * poses[static_cast<std::size_t>(mb.body)];
    v.resize(mb.mesh->vertices.size());
    for (std::size_t k = 0; k < v.size(); ++k) v[k] = T * mb.mesh->vertices[k];
    for (std::size_t t = 0; t < mb.mesh->triangles.size(); ++t) {
      const Eigen::Vector3i& tri = mb.mesh->triangles[t];
      const unsigned char shade = mb.shade[t];
      const Eigen::Vector3d& a = v[static_cast<std::size_t>(tri[0])];
      const Eigen::Vector3d& b = v[static_cast<std::size_t>(tri[1])];
      const Eigen::Vector3d& c3 = v[static_cast<std::size_t>(tri[2])];
      if (mb.cull && (b - a).cross(c3 - a).dot(a) >= 0.0) continue;
      rasterTriangle(g, a, b, c3, kNearPlane, [&](int c, int r, double z) {
                       const std::size_t i = static_cast<std::size_t>(r) * static_cast<std::size_t>(g.width) +
                                             static_cast<std::size_t>(c);
                       if (zb[i] >= 0.0 && z >= zb[i]) return;
                       zb[i] = z;
                       image->bitmap[i] = shade;
                     });
    }
  }
}

namespace {
std::vector<Eigen::Isometry3d> bodyPoses(const SimWorld& world) {
  std::vector<Eigen::Isometry3d> poses(world.bodies().size());
  for (std::size_t i = 0; i < poses.size(); ++i) poses[i] = world.bodyPose(static_cast<int>(i));
  return poses;
}
}  // namespace

void SimulatedCamera::render(const SimWorld& world, vpImage<unsigned char>* image) {
  render(world.cameraPose(), bodyPoses(world), image);
}

bool SimulatedCamera::tagInView(const Eigen::Isometry3d& T_world_cam,
                                const std::vector<Eigen::Isometry3d>& poses) const {
  const Eigen::Isometry3d T_cam_world = T_world_cam.inverse();
  for (const Impl::Tag& tag : impl_->tags) {
    if (tag.body < 0 || tag.body >= static_cast<int>(poses.size())) fail("tagInView: fewer poses than bodies");
    const Eigen::Isometry3d T_cam_body = T_cam_world * poses[static_cast<std::size_t>(tag.body)];
    // Seen from its front: the camera on the outward side of the tag's plane.
    if ((T_cam_body.inverse().translation() - tag.black[0]).dot(tag.outward) <= 0.0) continue;
    std::array<Eigen::Vector2d, 4> uv;
    bool in_front = true;
    for (std::size_t i = 0; i < 4; ++i) {
      const Eigen::Vector3d p = T_cam_body * tag.black[i];
      in_front = in_front && p.z() > kNearPlane;
      if (in_front) uv[i] = intrinsics_.pixel(p);
    }
    if (!in_front) continue;
    // AprilTag extrapolates a corner from the border's edges: measured up to 0.94 of a cell
    // (the black square's side / 8) outside the image. Margin: two cells + 2 px.
    double side = 0.0;
    for (std::size_t i = 0; i < 4; ++i) side = std::max(side, (uv[i] - uv[(i + 1) % 4]).norm());
    const double m = side / 4.0 + kTagBorderMargin;
    bool inside = true;
    for (const auto& p : uv)
      inside = inside && p.x() >= -m && p.y() >= -m && p.x() <= intrinsics_.width - 1 + m &&
               p.y() <= intrinsics_.height - 1 + m;
    if (inside) return true;
  }
  return false;
}

bool SimulatedCamera::tagInView(const SimWorld& world) const {
  return tagInView(world.cameraPose(), bodyPoses(world));
}

int SimulatedCamera::noiseOffset() {
  std::uniform_int_distribution<int> off(0, kNoiseTable - 1);
  return off(rng_);
}

void SimulatedCamera::skipImage() {
  if (cfg_.image_noise > 0.0) noiseOffset();
}

void SimulatedCamera::rasteriseDepth(const SimWorld& world, const Eigen::Isometry3d& T_world_cam) {
  Impl& m = *impl_;
  const RasterGrid& g = m.grid;
  const std::size_t n = static_cast<std::size_t>(g.width) * static_cast<std::size_t>(g.height);
  m.depth.assign(n, std::numeric_limits<double>::infinity());
  m.normal.resize(n);
  const Eigen::Isometry3d T_cam_world = T_world_cam.inverse();
  // The floor, the plane z = 0 of the world: one ray-plane intersection per sample.
  const Eigen::Vector3d floor_n = T_cam_world.linear().col(2);
  const double floor_k = floor_n.dot(T_cam_world.translation());
  for (int r = 0; r < g.height; ++r)
    for (int c = 0; c < g.width; ++c) {
      const double denom = floor_n.dot(g.ray(c, r));
      if (denom == 0.0) continue;
      const double z = floor_k / denom;
      if (z <= kDepthNear) continue;
      const std::size_t i = static_cast<std::size_t>(r) * static_cast<std::size_t>(g.width) + static_cast<std::size_t>(c);
      m.depth[i] = z;
      m.normal[i] = floor_n;
    }
  // Every scene body's triangles, nearest surface kept (z-buffer).
  std::vector<Eigen::Vector3d> v;
  for (std::size_t b = 0; b < world.bodies().size(); ++b) {
    const TriangleMesh& surface = world.bodySurface(static_cast<int>(b));
    const Eigen::Isometry3d T = T_cam_world * world.bodyPose(static_cast<int>(b));
    v.resize(surface.vertices.size());
    for (std::size_t k = 0; k < v.size(); ++k) v[k] = T * surface.vertices[k];
    for (const Eigen::Vector3i& t : surface.triangles) {
      const Eigen::Vector3d& a = v[static_cast<std::size_t>(t[0])];
      const Eigen::Vector3d& bb = v[static_cast<std::size_t>(t[1])];
      const Eigen::Vector3d& cc = v[static_cast<std::size_t>(t[2])];
      const Eigen::Vector3d normal = (bb - a).cross(cc - a).normalized();
      rasterTriangle(g, a, bb, cc, kDepthNear, [&](int col, int row, double z) {
        const std::size_t i = static_cast<std::size_t>(row) * static_cast<std::size_t>(g.width) + static_cast<std::size_t>(col);
        if (z >= m.depth[i]) return;
        m.depth[i] = z;
        m.normal[i] = normal;
      });
    }
  }
}

double SimulatedCamera::disturbedDepth(int c, int r, double z) {
  const Impl& m = *impl_;
  const DepthNoiseConfig& noise = cfg_.depth_noise;
  if (noise.model == DepthNoiseModel::Stereo) {
    const RasterGrid& g = m.grid;
    const Eigen::Vector3d ray = g.ray(c, r);
    // Holes at grazing angles: the angle between the ray and the surface normal.
    const double cos_incidence = std::abs(m.normal[static_cast<std::size_t>(r * g.width + c)].dot(ray)) / ray.norm();
    const double angle = std::acos(std::min(1.0, cos_incidence)) * 180.0 / M_PI;
    if (angle > noise.grazing_angle &&
        uniform_(rng_) < (angle - noise.grazing_angle) / std::max(1e-9, 90.0 - noise.grazing_angle))
      return -1.0;
    // Flying pixels: next to a depth edge, a depth between this surface and the neighbour's. An
    // edge is where the neighbour's depth is off this sample's plane by more than edge_jump (a
    // plane seen at a slant, however steep its depth gradient, has none).
    const Eigen::Vector3d& n = m.normal[static_cast<std::size_t>(r * g.width + c)];
    const double k = n.dot(ray * z);
    double jump = 0.0;
    const int dc[4] = {1, -1, 0, 0}, dr[4] = {0, 0, 1, -1};
    for (int i = 0; i < 4; ++i) {
      const int cc = c + dc[i], rr = r + dr[i];
      if (cc < 0 || rr < 0 || cc >= g.width || rr >= g.height) continue;
      const double zn = m.depth[static_cast<std::size_t>(rr * g.width + cc)];
      if (!std::isfinite(zn)) continue;
      const double denom = n.dot(g.ray(cc, rr));
      const bool off_plane = denom == 0.0 || std::abs(zn - k / denom) > noise.edge_jump;
      if (off_plane && std::abs(zn - z) > std::abs(jump)) jump = zn - z;
    }
    if (jump != 0.0 && uniform_(rng_) < noise.flying_pixels) z += uniform_(rng_) * jump;
  }
  const double sigma = noise.sigma(z);
  return sigma > 0.0 ? z + sigma * gauss_(rng_) : z;
}

void SimulatedCamera::cloud(const SimWorld& world, const Eigen::Isometry3d& T_world_cam,
                            std::vector<Eigen::Vector3f>* points) {
  rasteriseDepth(world, T_world_cam);
  const Impl& m = *impl_;
  const RasterGrid& g = m.grid;
  points->clear();
  points->reserve(m.depth.size());
  for (int r = 0; r < g.height; ++r)
    for (int c = 0; c < g.width; ++c) {
      const double z = m.depth[static_cast<std::size_t>(r * g.width + c)];
      if (!(z >= cfg_.min_range && z <= cfg_.max_range)) continue;
      const double zd = disturbedDepth(c, r, z);
      if (zd <= 0.0) continue;  // a hole
      points->emplace_back((g.ray(c, r) * zd).cast<float>());
    }
}

void SimulatedCamera::cloud(const SimWorld& world, std::vector<Eigen::Vector3f>* points) {
  cloud(world, world.cameraPose(), points);
}

}  // namespace ehc_sim
