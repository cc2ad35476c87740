#include "ehc_sim/object_library.h"

#include "ehc_common/config_node.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <random>
#include <set>
#include <sstream>
#include <stdexcept>

using ehc_common::ConfigNode;

namespace ehc_sim {

namespace {
[[noreturn]] void fail(const std::string& what) { throw std::invalid_argument("[ObjectLibrary] " + what); }

constexpr int kSides = 48;  ///< segments around a surface of revolution
constexpr int kWallSectors = 16;  ///< convex parts around a cup's or bowl's wall (sweptSectors)

// ------------------------------------------------------------------------ closed primitives
/// A closed surface of revolution about z: `profile` (r, z) runs from a point on the axis to a
/// point on the axis, with the material on its left (up the outside, down the inside), so that
/// the triangles face outwards.
TriangleMesh lathe(const std::vector<Eigen::Vector2d>& profile, int sides = kSides) {
  TriangleMesh m;
  std::vector<int> first(profile.size());
  for (std::size_t i = 0; i < profile.size(); ++i) {
    first[i] = static_cast<int>(m.vertices.size());
    if (profile[i].x() <= 1e-12) {
      m.vertices.emplace_back(0.0, 0.0, profile[i].y());
      continue;
    }
    for (int k = 0; k < sides; ++k) {
      const double a = 2.0 * M_PI * k / sides;
      m.vertices.emplace_back(profile[i].x() * std::cos(a), profile[i].x() * std::sin(a), profile[i].y());
    }
  }
  auto at = [&](std::size_t i, int k) { return profile[i].x() <= 1e-12 ? first[i] : first[i] + (k % sides); };
  for (std::size_t i = 0; i + 1 < profile.size(); ++i)
    for (int k = 0; k < sides; ++k) {
      const int a = at(i, k), b = at(i, k + 1), c = at(i + 1, k + 1), d = at(i + 1, k);
      if (a != b && b != c && a != c) m.triangles.emplace_back(a, b, c);
      if (a != c && c != d && a != d) m.triangles.emplace_back(a, c, d);
    }
  return m;
}

/// Flips every triangle when the mesh's signed volume is negative (its triangles faced inwards).
void faceOutwards(TriangleMesh* m) {
  double six_v = 0.0;
  for (const auto& t : m->triangles)
    six_v += m->vertices[static_cast<std::size_t>(t[0])].dot(
        m->vertices[static_cast<std::size_t>(t[1])].cross(m->vertices[static_cast<std::size_t>(t[2])]));
  if (six_v < 0.0)
    for (auto& t : m->triangles) std::swap(t[1], t[2]);
}

/// A wall of revolution about z as convex parts: the convex profile polygon `quad` (r, z; r > 0)
/// swept over `sectors` equal sectors, each a closed part of its own with kSides / sectors facets
/// (the outside as a lathe of kSides sides has it). Why parts: the simulator collides a mesh as the
/// convex hulls of its connected parts (SimWorld), and a cup or bowl of one part collides as a
/// solid that no finger can enter. A sector's hull is its exact shape but for its inner arc, whose
/// chord it fills by at most r (1 - cos(pi / sectors)). Each sector reaches kOverlap (rad) into its
/// neighbours and the whole wall is turned by `turn` (rad), so that no two parts (nor a lathe's
/// rings) share a vertex: shared vertices would weld the parts into one again (loadObjectMesh).
TriangleMesh sweptSectors(const std::vector<Eigen::Vector2d>& quad, int sectors, double turn) {
  constexpr double kOverlap = 1e-3;
  const int steps = std::max(1, kSides / sectors);
  const std::size_t n = quad.size();
  TriangleMesh all;
  for (int j = 0; j < sectors; ++j) {
    const double a0 = 2.0 * M_PI * j / sectors + turn - kOverlap, a1 = 2.0 * M_PI * (j + 1) / sectors + turn + kOverlap;
    TriangleMesh m;
    for (int k = 0; k <= steps; ++k) {
      const double a = a0 + (a1 - a0) * k / steps;
      for (const auto& q : quad) m.vertices.emplace_back(q.x() * std::cos(a), q.x() * std::sin(a), q.y());
    }
    auto at = [&](int k, std::size_t i) { return k * static_cast<int>(n) + static_cast<int>(i % n); };
    for (int k = 0; k < steps; ++k)
      for (std::size_t i = 0; i < n; ++i) {
        m.triangles.emplace_back(at(k, i), at(k + 1, i), at(k + 1, i + 1));
        m.triangles.emplace_back(at(k, i), at(k + 1, i + 1), at(k, i + 1));
      }
    for (std::size_t i = 1; i + 1 < n; ++i) {  // the end caps
      m.triangles.emplace_back(at(0, 0), at(0, i + 1), at(0, i));
      m.triangles.emplace_back(at(steps, 0), at(steps, i), at(steps, i + 1));
    }
    faceOutwards(&m);
    all.append(m);
  }
  return all;
}

TriangleMesh transformed(TriangleMesh m, const Eigen::Affine3d& T) {
  for (auto& v : m.vertices) v = T * v;
  if (T.linear().determinant() < 0)
    for (auto& t : m.triangles) std::swap(t[1], t[2]);
  return m;
}

/// A closed cylinder of `radius` from a to b.
TriangleMesh rod(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius, int sides = 24) {
  const double length = (b - a).norm();
  const TriangleMesh m = lathe({{0, 0}, {radius, 0}, {radius, length}, {0, length}}, sides);
  Eigen::Affine3d T = Eigen::Affine3d::Identity();
  T.linear() = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), (b - a) / length).toRotationMatrix();
  T.translation() = a;
  return transformed(m, T);
}

TriangleMesh ellipsoid(const Eigen::Vector3d& centre, const Eigen::Vector3d& radii, const Eigen::Matrix3d& R) {
  std::vector<Eigen::Vector2d> profile;
  const int rows = 16;
  for (int i = 0; i <= rows; ++i) {
    const double t = M_PI * i / rows;
    profile.emplace_back(std::sin(t), -std::cos(t));
  }
  Eigen::Affine3d T = Eigen::Affine3d::Identity();
  T.linear() = R * radii.asDiagonal();
  T.translation() = centre;
  return transformed(lathe(profile, 32), T);
}

TriangleMesh box(const Eigen::Vector3d& centre, const Eigen::Vector3d& size, const Eigen::Matrix3d& R = Eigen::Matrix3d::Identity()) {
  Eigen::Affine3d T = Eigen::Affine3d::Identity();
  T.linear() = R;
  T.translation() = centre;
  return transformed(boxSurface(size), T);
}

/// A tube of varying radius along `path` (parallel-transported frames), capped at both ends.
TriangleMesh tube(const std::vector<Eigen::Vector3d>& path, const std::vector<double>& radii, int sides = 24) {
  TriangleMesh m;
  const std::size_t n = path.size();
  Eigen::Vector3d t = (path[1] - path[0]).normalized();
  Eigen::Vector3d u = t.unitOrthogonal();
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d ti = (path[std::min(i + 1, n - 1)] - path[i > 0 ? i - 1 : 0]).normalized();
    u = (u - u.dot(ti) * ti).normalized();  // transport the frame
    t = ti;
    const Eigen::Vector3d w = t.cross(u);
    for (int k = 0; k < sides; ++k) {
      const double a = 2.0 * M_PI * k / sides;
      m.vertices.push_back(path[i] + radii[i] * (std::cos(a) * u + std::sin(a) * w));
    }
  }
  const int c0 = static_cast<int>(m.vertices.size());
  m.vertices.push_back(path.front());
  m.vertices.push_back(path.back());
  auto at = [&](std::size_t i, int k) { return static_cast<int>(i) * sides + (k % sides); };
  for (std::size_t i = 0; i + 1 < n; ++i)
    for (int k = 0; k < sides; ++k) {
      m.triangles.emplace_back(at(i, k), at(i, k + 1), at(i + 1, k + 1));
      m.triangles.emplace_back(at(i, k), at(i + 1, k + 1), at(i + 1, k));
    }
  for (int k = 0; k < sides; ++k) {
    m.triangles.emplace_back(c0, at(0, k + 1), at(0, k));
    m.triangles.emplace_back(at(n - 1, k), at(n - 1, k + 1), c0 + 1);
  }
  return m;
}

Eigen::Matrix3d rotationZYX(double yaw, double pitch, double roll) {
  return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

double param(const std::map<std::string, double>& p, const std::string& key) {
  const auto it = p.find(key);
  if (it == p.end()) fail("parameter '" + key + "' is missing");
  return it->second;
}
}  // namespace

// ------------------------------------------------------------------------ the kinds
namespace {
TriangleMesh mugMesh(const std::map<std::string, double>& p) {
  const double R = param(p, "radius"), H = param(p, "height"), w = param(p, "wall");
  // The base a disc, the wall convex sectors on it (sweptSectors: the inside stays open).
  TriangleMesh m = lathe({{0, 0}, {R, 0}, {R, 0.008}, {0, 0.008}});
  m.append(sweptSectors({{R - w, 0.008}, {R, 0.008}, {R, H}, {R - w, H}}, kWallSectors, 0.5 * M_PI / kSides));
  // The handle: a chain of short cylinders on a half ellipse on the +y side, its ends inside the
  // wall (so that the parts overlap) and each part convex, the hole between them open.
  const double r = param(p, "handle_thickness"), reach = param(p, "handle_reach"), span = param(p, "handle_span") * H;
  std::vector<Eigen::Vector3d> c;
  const int segments = 7;
  for (int i = 0; i <= segments; ++i) {
    const double a = M_PI * i / segments;
    c.emplace_back(0.0, R - 0.5 * w + reach * std::sin(a), 0.5 * H + 0.5 * span * std::cos(a));
  }
  for (int i = 0; i < segments; ++i) {
    const Eigen::Vector3d d = (c[static_cast<std::size_t>(i + 1)] - c[static_cast<std::size_t>(i)]).normalized();
    m.append(rod(c[static_cast<std::size_t>(i)] - 0.6 * r * d, c[static_cast<std::size_t>(i + 1)] + 0.6 * r * d, r, 16));
  }
  return m;
}

TriangleMesh bowlMesh(const std::map<std::string, double>& p) {
  const double R = param(p, "radius"), H = param(p, "height"), w = param(p, "wall");
  const double rb = param(p, "base_fraction") * R;
  std::vector<Eigen::Vector2d> out = {{0, 0}};
  const int steps = 8;
  for (int s = 0; s <= steps; ++s) {  // outside: base rim up to the top, a quarter ellipse
    const double a = 0.5 * M_PI * s / steps;
    out.emplace_back(rb + (R - rb) * std::sin(a), H * (1.0 - std::cos(a)));
  }
  for (int s = steps; s >= 0; --s) {  // inside, down again, the wall `w` thick
    const double a = 0.5 * M_PI * s / steps;
    out.emplace_back(rb - w + (R - rb) * std::sin(a), std::max(w, H * (1.0 - std::cos(a)) + w * std::cos(a)));
  }
  out.emplace_back(0.0, w);
  // The base a disc, each band of the wall (between two steps of the profile) convex sectors on
  // it (sweptSectors: the inside stays open), the bands turned apart so that none shares a vertex.
  const std::size_t rows = steps + 1;  // out[1..rows]: outside, bottom to top; then the inside, top to bottom
  TriangleMesh m = lathe({out[0], out[1], out[2 * rows], out[2 * rows + 1]});
  for (std::size_t s = 0; s < static_cast<std::size_t>(steps); ++s) {
    const Eigen::Vector2d& o0 = out[1 + s];
    const Eigen::Vector2d& o1 = out[2 + s];
    const Eigen::Vector2d& i1 = out[2 * rows - 1 - s];
    const Eigen::Vector2d& i0 = out[2 * rows - s];
    m.append(sweptSectors({i0, o0, o1, i1}, kWallSectors, (0.5 + 0.1 * static_cast<double>(s)) * M_PI / kSides));
  }
  return m;
}

TriangleMesh bottleMesh(const std::map<std::string, double>& p) {
  const double R = param(p, "radius"), H = param(p, "height"), rn = param(p, "neck_radius");
  const double hn = param(p, "neck_height"), hs = param(p, "shoulder") * (H - hn);
  std::vector<Eigen::Vector2d> out = {{0, 0}, {R - 0.004, 0}, {R, 0.004}, {R, hs}};
  const int steps = 6;
  for (int s = 1; s <= steps; ++s) {
    const double a = 0.5 * M_PI * s / steps;
    out.emplace_back(rn + (R - rn) * std::cos(a), hs + (H - hn - hs) * std::sin(a));
  }
  out.emplace_back(rn, H);
  out.emplace_back(0.0, H);
  return lathe(out);
}

TriangleMesh canMesh(const std::map<std::string, double>& p) {
  const double R = param(p, "radius"), H = param(p, "height");
  return lathe({{0, 0}, {0.9 * R, 0}, {R, 0.006}, {R, H - 0.008}, {0.88 * R, H}, {0, H}});
}

TriangleMesh boxMesh(const std::map<std::string, double>& p) {
  const Eigen::Vector3d s(param(p, "size_x"), param(p, "size_y"), param(p, "size_z"));
  return box(Eigen::Vector3d(0, 0, 0.5 * s.z()), s);
}

/// Tools lie along x: a hammer, a screwdriver, a spatula or a wrench (parameter `variant`).
TriangleMesh toolMesh(const std::map<std::string, double>& p) {
  const int variant = static_cast<int>(param(p, "variant"));
  const double L = param(p, "length"), r = param(p, "handle_radius");
  TriangleMesh m;
  if (variant == 0) {  // hammer: handle and a steel head across it
    m = rod({-0.5 * L, 0, r}, {0.5 * L, 0, r}, r);
    m.append(box({0.5 * L - 0.015, 0, r}, {0.028, param(p, "head_length"), 0.028}));
  } else if (variant == 1) {  // screwdriver: thick handle, thin shaft
    m = rod({-0.5 * L, 0, r}, {-0.5 * L + 0.45 * L, 0, r}, r);
    m.append(rod({-0.5 * L + 0.44 * L, 0, r}, {0.5 * L, 0, r}, 0.0035));
  } else if (variant == 2) {  // spatula: handle and a flat blade
    m = rod({-0.5 * L, 0, r}, {0.5 * L - 0.08, 0, r}, r);
    m.append(box({0.5 * L - 0.045, 0, 0.0015}, {0.09, param(p, "head_length"), 0.003}));
  } else {  // wrench: a flat bar with a ring at each end
    m = box({0, 0, 0.0035}, {L - 0.03, 2.0 * r, 0.007});
    m.append(rod({-0.5 * L + 0.016, 0, 0}, {-0.5 * L + 0.016, 0, 0.008}, 0.016));
    m.append(rod({0.5 * L - 0.016, 0, 0}, {0.5 * L - 0.016, 0, 0.008}, 0.016));
  }
  return m;
}

/// A banana lying on the table: a tube along an arc in the x-y plane, tapered to its ends.
TriangleMesh bananaMesh(const std::map<std::string, double>& p) {
  const double L = param(p, "length"), r = param(p, "radius"), bend = param(p, "bend_radius");
  std::vector<Eigen::Vector3d> path;
  std::vector<double> radii;
  const int n = 24;
  for (int i = 0; i <= n; ++i) {
    const double s = static_cast<double>(i) / n, phi = (s - 0.5) * L / bend;
    const double ri = r * (0.3 + 0.7 * std::pow(std::sin(M_PI * s), 0.4));
    path.emplace_back(bend * std::sin(phi), bend * std::cos(phi) - bend, r);
    radii.push_back(ri);
  }
  return tube(path, radii);
}

/// Two to four bars of square section, each centred on a random point of an earlier bar's axis.
TriangleMesh barsMesh(const std::map<std::string, double>& p, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int count = static_cast<int>(param(p, "count"));
  const double t = param(p, "thickness"), L = param(p, "length");
  struct Bar {
    Eigen::Vector3d centre, axis;
    double length;
  };
  std::vector<Bar> bars = {{Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), L}};
  TriangleMesh m = box(Eigen::Vector3d::Zero(), {L, t, t});
  for (int i = 1; i < count; ++i) {
    const Bar& base = bars[static_cast<std::size_t>(u(rng) * static_cast<double>(bars.size())) % bars.size()];
    const Eigen::Vector3d centre = base.centre + (u(rng) - 0.5) * base.length * base.axis;
    const double length = L * (0.6 + 0.6 * u(rng));
    const Eigen::Matrix3d R = rotationZYX(M_PI * u(rng), 0.6 * (u(rng) - 0.5), 0.0);
    m.append(box(centre, {length, t, t}, R));
    bars.push_back({centre, R.col(0), length});
  }
  return m;
}

/// Three to five overlapping ellipsoids.
TriangleMesh blobMesh(const std::map<std::string, double>& p, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int count = static_cast<int>(param(p, "count"));
  const double r = param(p, "radius"), spread = param(p, "spread");
  TriangleMesh m;
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector3d c = i == 0 ? Eigen::Vector3d::Zero()
                                     : Eigen::Vector3d(spread * (2 * u(rng) - 1), spread * (2 * u(rng) - 1), 0.5 * spread * (2 * u(rng) - 1));
    const Eigen::Vector3d radii(r * (0.7 + 0.6 * u(rng)), r * (0.7 + 0.6 * u(rng)), r * (0.6 + 0.4 * u(rng)));
    m.append(ellipsoid(c, radii, rotationZYX(2 * M_PI * u(rng), 0.5 * (u(rng) - 0.5), 0.5 * (u(rng) - 0.5))));
  }
  return m;
}

struct Range {
  const char* name;
  double lo, hi;
};

/// The plausible ranges of every kind's parameters (m; density kg/m^3 of the solid the mesh
/// encloses: ceramic 2300, a filled can or bottle 1000, wood 650, cardboard box with contents).
const std::map<std::string, std::vector<Range>>& kindRanges() {
  static const std::map<std::string, std::vector<Range>> ranges = {
      {"mug", {{"radius", 0.036, 0.044}, {"height", 0.085, 0.11}, {"wall", 0.0035, 0.005}, {"handle_thickness", 0.005, 0.007},
               {"handle_reach", 0.022, 0.032}, {"handle_span", 0.5, 0.7}, {"density", 2300, 2300}}},
      {"bowl", {{"radius", 0.06, 0.08}, {"height", 0.045, 0.065}, {"wall", 0.004, 0.006}, {"base_fraction", 0.45, 0.6},
                {"density", 2300, 2300}}},
      {"bottle", {{"radius", 0.028, 0.034}, {"height", 0.18, 0.23}, {"neck_radius", 0.011, 0.014}, {"neck_height", 0.025, 0.04},
                  {"shoulder", 0.65, 0.8}, {"density", 1000, 1000}}},
      {"can", {{"radius", 0.026, 0.033}, {"height", 0.095, 0.125}, {"density", 1000, 1000}}},
      {"box", {{"size_x", 0.04, 0.065}, {"size_y", 0.07, 0.16}, {"size_z", 0.05, 0.2}, {"density", 150, 450}}},
      {"tool", {{"length", 0.16, 0.26}, {"handle_radius", 0.009, 0.015}, {"head_length", 0.06, 0.1}, {"density", 1100, 2500}}},
      {"banana", {{"length", 0.17, 0.22}, {"radius", 0.016, 0.019}, {"bend_radius", 0.13, 0.2}, {"density", 950, 950}}},
      {"bars", {{"count", 2, 4}, {"thickness", 0.026, 0.034}, {"length", 0.08, 0.14}, {"density", 650, 650}}},
      {"blob", {{"count", 3, 5}, {"radius", 0.018, 0.03}, {"spread", 0.015, 0.03}, {"density", 1100, 1100}}},
  };
  return ranges;
}

const std::map<std::string, double>& kindFriction() {
  static const std::map<std::string, double> f = {{"mug", 0.6}, {"bowl", 0.6}, {"bottle", 0.5}, {"can", 0.4}, {"box", 0.6},
                                                  {"tool", 0.5}, {"banana", 0.8}, {"bars", 0.6}, {"blob", 0.8}};
  return f;
}
}  // namespace

const std::vector<std::string>& objectKinds() {
  static const std::vector<std::string> kinds = {"mug", "bowl", "bottle", "can", "box", "tool", "banana", "bars", "blob"};
  return kinds;
}

std::map<std::string, double> drawObjectParams(const std::string& kind, unsigned seed) {
  const auto it = kindRanges().find(kind);
  if (it == kindRanges().end()) fail("unknown kind '" + kind + "'");
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::map<std::string, double> p;
  for (const Range& r : it->second) {
    const double v = r.lo + (r.hi - r.lo) * u(rng);
    const bool whole = std::string(r.name) == "count" || std::string(r.name) == "density";
    p[r.name] = whole ? std::round(v) : std::round(v * 1e4) / 1e4;  // 0.1 mm: the manifest's digits
  }
  if (kind == "tool") p["variant"] = seed % 4;
  return p;
}

TriangleMesh generateObjectMesh(const std::string& kind, const std::map<std::string, double>& p, unsigned seed) {
  TriangleMesh m;
  if (kind == "mug") m = mugMesh(p);
  else if (kind == "bowl") m = bowlMesh(p);
  else if (kind == "bottle") m = bottleMesh(p);
  else if (kind == "can") m = canMesh(p);
  else if (kind == "box") m = boxMesh(p);
  else if (kind == "tool") m = toolMesh(p);
  else if (kind == "banana") m = bananaMesh(p);
  else if (kind == "bars") m = barsMesh(p, seed);
  else if (kind == "blob") m = blobMesh(p, seed);
  else fail("unknown kind '" + kind + "'");
  // Resting upright: bottom at z = 0, centred in x and y.
  const Eigen::Vector3d lo = m.boundsMin(), hi = m.boundsMax();
  const Eigen::Vector3d shift(-0.5 * (lo.x() + hi.x()), -0.5 * (lo.y() + hi.y()), -lo.z());
  for (auto& v : m.vertices) v += shift;
  return m;
}

LibraryObject drawLibraryObject(const std::string& name, const std::string& kind, unsigned seed, const std::string& split,
                                const std::string& extension) {
  LibraryObject o;
  o.name = name;
  o.kind = kind;
  o.seed = seed;
  o.split = split;
  o.file = name + "." + extension;
  o.params = drawObjectParams(kind, seed);
  const TriangleMesh m = generateObjectMesh(kind, o.params, seed);
  o.size = m.boundsMax() - m.boundsMin();
  o.mass = o.params.at("density") * m.solidVolume();
  o.friction = kindFriction().at(kind);
  return o;
}

ObjectLibrary drawObjectLibrary(unsigned seed, int per_kind) {
  ObjectLibrary lib;
  lib.seed = seed;
  const char* formats[3] = {"obj", "stl", "ply"};
  int n = 0;
  for (const std::string& kind : objectKinds())
    for (int k = 0; k < per_kind; ++k, ++n) {
      std::ostringstream name;
      name << kind << "_" << std::setw(2) << std::setfill('0') << k + 1;
      lib.objects.push_back(drawLibraryObject(name.str(), kind, seed * 1000 + static_cast<unsigned>(n), k % 2 == 0 ? "tuning" : "validation",
                                              formats[n % 3]));
    }
  return lib;
}

const LibraryObject& ObjectLibrary::object(const std::string& name) const {
  std::string names;
  for (const auto& o : objects) {
    if (o.name == name) return o;
    names += (names.empty() ? "" : ", ") + o.name;
  }
  fail(source_file + ": no object '" + name + "' (known: " + names + ")");
}

BodyConfig libraryBody(const ObjectLibrary& library, const std::string& name) {
  const LibraryObject& o = library.object(name);
  BodyConfig b;
  try {
    b = meshBody(o.name, library.meshPath(o), 1.0);
  } catch (const std::invalid_argument& e) {
    fail(std::string(e.what()) + " (write the library's meshes: rosrun ehc_bringup ehc_object_library meshes --manifest " +
         library.source_file + ")");
  }
  b.mass = o.mass;
  b.friction = o.friction;
  return b;
}

ObjectLibrary loadObjectLibrary(const std::string& path) {
  const ConfigNode root = ConfigNode::loadFile(path, "ObjectLibrary");
  const ConfigNode n = root.child("object_library");
  ObjectLibrary lib;
  lib.source_file = path;
  lib.seed = static_cast<unsigned>(n.require<int>("seed"));
  lib.mesh_dir = n.requirePath("mesh_dir");
  std::set<std::string> names;
  for (std::size_t i = 0; i < n.listSize("objects"); ++i) {
    const ConfigNode e = n.element("objects", i);
    LibraryObject o;
    o.name = e.require<std::string>("name");
    if (!names.insert(o.name).second) e.fail("name", "'" + o.name + "' is used twice");
    o.kind = e.require<std::string>("kind");
    if (!kindRanges().count(o.kind)) e.fail("kind", "unknown kind '" + o.kind + "'");
    o.seed = static_cast<unsigned>(e.require<int>("seed"));
    o.split = e.require<std::string>("split");
    if (o.split != "tuning" && o.split != "validation") e.fail("split", "must be 'tuning' or 'validation'");
    o.file = e.require<std::string>("file");
    const ConfigNode params = e.child("params");
    for (const std::string& key : params.keys()) o.params[key] = params.require<double>(key);
    o.size = e.requireVector("size", 3);
    o.mass = e.require<double>("mass");
    ehc_common::requireRange("ObjectLibrary", e.fieldName("mass"), o.mass, 0.001, 20.0);
    o.friction = e.require<double>("friction");
    ehc_common::requireRange("ObjectLibrary", e.fieldName("friction"), o.friction, 0.0, 5.0);
    lib.objects.push_back(o);
  }
  root.rejectUnknownKeys();
  return lib;
}

std::string objectLibraryYaml(const ObjectLibrary& lib, const std::string& command) {
  std::ostringstream os;
  os << std::setprecision(10);
  os << "# The simulator's object library (ehc_sim/object_library.h), generated by:\n#   " << command
     << "\n# The meshes are written to mesh_dir by `rosrun ehc_bringup ehc_object_library meshes` (the build\n"
     << "# runs it); kind + params + seed give the same triangles. size: bounding box (m); mass: density\n"
     << "# x the solid's volume (kg). split: tuning (develop and tune on these) or validation (report).\n"
     << "object_library:\n  seed: " << lib.seed << "\n  mesh_dir: meshes\n  objects:\n";
  for (const LibraryObject& o : lib.objects) {
    os << "    - {name: " << o.name << ", kind: " << o.kind << ", seed: " << o.seed << ", split: " << o.split
       << ", file: " << o.file << ",\n       params: {";
    bool first = true;
    for (const auto& [k, v] : o.params) {
      os << (first ? "" : ", ") << k << ": " << v;
      first = false;
    }
    os << "},\n       size: [" << std::round(o.size.x() * 1e4) / 1e4 << ", " << std::round(o.size.y() * 1e4) / 1e4 << ", "
       << std::round(o.size.z() * 1e4) / 1e4 << "], mass: " << std::round(o.mass * 1e4) / 1e4 << ", friction: " << o.friction
       << "}\n";
  }
  return os.str();
}

}  // namespace ehc_sim
