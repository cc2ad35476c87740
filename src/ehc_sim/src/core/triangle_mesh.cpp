#include "ehc_sim/triangle_mesh.h"

#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <map>
#include <numeric>
#include <sstream>
#include <stdexcept>

namespace ehc_sim {

namespace {
[[noreturn]] void fail(const std::string& what) { throw std::invalid_argument("[TriangleMesh] " + what); }

std::string extensionOf(const std::string& path) {
  const auto dot = path.find_last_of('.');
  std::string ext = dot == std::string::npos ? "" : path.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

int findRoot(std::vector<int>& parent, int i) {
  while (parent[static_cast<std::size_t>(i)] != i) {
    parent[static_cast<std::size_t>(i)] = parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(i)])];
    i = parent[static_cast<std::size_t>(i)];
  }
  return i;
}

/// Heights where the vertical line through (x, y) crosses the mesh's triangles, sorted.
std::vector<double> columnCrossings(const TriangleMesh& m, double x, double y) {
  std::vector<double> zs;
  for (const auto& t : m.triangles) {
    const Eigen::Vector3d& a = m.vertices[static_cast<std::size_t>(t[0])];
    const Eigen::Vector3d& b = m.vertices[static_cast<std::size_t>(t[1])];
    const Eigen::Vector3d& c = m.vertices[static_cast<std::size_t>(t[2])];
    const double d = (b.x() - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (b.y() - a.y());
    if (std::abs(d) < 1e-18) continue;  // seen edge-on from above
    const double l1 = ((x - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (y - a.y())) / d;
    const double l2 = ((b.x() - a.x()) * (y - a.y()) - (x - a.x()) * (b.y() - a.y())) / d;
    if (l1 < 0.0 || l2 < 0.0 || l1 + l2 > 1.0) continue;
    zs.push_back(a.z() + l1 * (b.z() - a.z()) + l2 * (c.z() - a.z()));
  }
  std::sort(zs.begin(), zs.end());
  return zs;
}
}  // namespace

void TriangleMesh::append(const TriangleMesh& other) {
  const int offset = static_cast<int>(vertices.size());
  vertices.insert(vertices.end(), other.vertices.begin(), other.vertices.end());
  for (const auto& t : other.triangles) triangles.emplace_back(t + Eigen::Vector3i::Constant(offset));
}

Eigen::Vector3d TriangleMesh::boundsMin() const {
  if (vertices.empty()) return Eigen::Vector3d::Zero();
  Eigen::Vector3d lo = vertices.front();
  for (const auto& v : vertices) lo = lo.cwiseMin(v);
  return lo;
}

Eigen::Vector3d TriangleMesh::boundsMax() const {
  if (vertices.empty()) return Eigen::Vector3d::Zero();
  Eigen::Vector3d hi = vertices.front();
  for (const auto& v : vertices) hi = hi.cwiseMax(v);
  return hi;
}

double TriangleMesh::area() const {
  double a = 0.0;
  for (const auto& t : triangles)
    a += 0.5 * (vertices[static_cast<std::size_t>(t[1])] - vertices[static_cast<std::size_t>(t[0])])
                   .cross(vertices[static_cast<std::size_t>(t[2])] - vertices[static_cast<std::size_t>(t[0])])
                   .norm();
  return a;
}

Eigen::Vector3d TriangleMesh::normal(std::size_t i) const {
  const Eigen::Vector3i& t = triangles[i];
  const Eigen::Vector3d n = (vertices[static_cast<std::size_t>(t[1])] - vertices[static_cast<std::size_t>(t[0])])
                                .cross(vertices[static_cast<std::size_t>(t[2])] - vertices[static_cast<std::size_t>(t[0])]);
  const double len = n.norm();
  return len > 0.0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
}

std::vector<TriangleMesh> TriangleMesh::components() const {
  std::vector<int> parent(vertices.size());
  std::iota(parent.begin(), parent.end(), 0);
  for (const auto& t : triangles)
    for (int k = 1; k < 3; ++k) parent[static_cast<std::size_t>(findRoot(parent, t[k]))] = findRoot(parent, t[0]);
  std::map<int, std::size_t> part_of_root;
  std::vector<TriangleMesh> parts;
  std::vector<std::map<int, int>> index(0);
  for (const auto& t : triangles) {
    const int root = findRoot(parent, t[0]);
    auto it = part_of_root.find(root);
    if (it == part_of_root.end()) {
      it = part_of_root.emplace(root, parts.size()).first;
      parts.emplace_back();
      index.emplace_back();
    }
    TriangleMesh& p = parts[it->second];
    std::map<int, int>& idx = index[it->second];
    Eigen::Vector3i nt;
    for (int k = 0; k < 3; ++k) {
      auto v = idx.find(t[k]);
      if (v == idx.end()) {
        v = idx.emplace(t[k], static_cast<int>(p.vertices.size())).first;
        p.vertices.push_back(vertices[static_cast<std::size_t>(t[k])]);
      }
      nt[k] = v->second;
    }
    p.triangles.push_back(nt);
  }
  return parts;
}

double TriangleMesh::solidVolume(int columns) const {
  if (empty()) return 0.0;
  const std::vector<TriangleMesh> parts = components();
  const Eigen::Vector3d lo = boundsMin(), hi = boundsMax();
  const double dx = (hi.x() - lo.x()) / columns, dy = (hi.y() - lo.y()) / columns;
  double volume = 0.0;
  for (int i = 0; i < columns; ++i)
    for (int j = 0; j < columns; ++j) {
      // Cell centres nudged off the symmetric positions where edges and vertices lie.
      const double x = lo.x() + (i + 0.5 + 1.3e-4) * dx, y = lo.y() + (j + 0.5 + 2.9e-4) * dy;
      std::vector<std::pair<double, double>> inside;
      for (const TriangleMesh& p : parts) {
        const std::vector<double> zs = columnCrossings(p, x, y);
        for (std::size_t k = 0; k + 1 < zs.size(); k += 2) inside.emplace_back(zs[k], zs[k + 1]);
      }
      std::sort(inside.begin(), inside.end());
      double length = 0.0, top = -1e300;
      for (const auto& [z0, z1] : inside) {
        const double from = std::max(z0, top);
        if (z1 > from) length += z1 - from;
        top = std::max(top, z1);
      }
      volume += length * dx * dy;
    }
  return volume;
}

double TriangleMesh::exitDistance(const Eigen::Vector3d& d) const {
  double best = -1.0;
  for (const auto& t : triangles) {  // Moller-Trumbore, ray from the origin
    const Eigen::Vector3d& a = vertices[static_cast<std::size_t>(t[0])];
    const Eigen::Vector3d e1 = vertices[static_cast<std::size_t>(t[1])] - a, e2 = vertices[static_cast<std::size_t>(t[2])] - a;
    const Eigen::Vector3d p = d.cross(e2);
    const double det = e1.dot(p);
    if (std::abs(det) < 1e-18) continue;
    const Eigen::Vector3d s = -a;
    const double u = s.dot(p) / det;
    const Eigen::Vector3d q = s.cross(e1);
    const double v = d.dot(q) / det;
    if (u < 0.0 || v < 0.0 || u + v > 1.0) continue;
    best = std::max(best, e2.dot(q) / det);
  }
  return best;
}

void TriangleMesh::weld(double tolerance) {
  std::map<std::array<long long, 3>, int> cell_index;
  std::vector<int> remap(vertices.size());
  std::vector<Eigen::Vector3d> kept;
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    const std::array<long long, 3> key = {std::llround(vertices[i].x() / tolerance), std::llround(vertices[i].y() / tolerance),
                                          std::llround(vertices[i].z() / tolerance)};
    const auto it = cell_index.emplace(key, static_cast<int>(kept.size()));
    if (it.second) kept.push_back(vertices[i]);
    remap[i] = it.first->second;
  }
  std::vector<Eigen::Vector3i> tris;
  for (const auto& t : triangles) {
    const Eigen::Vector3i r(remap[static_cast<std::size_t>(t[0])], remap[static_cast<std::size_t>(t[1])],
                            remap[static_cast<std::size_t>(t[2])]);
    if (r[0] != r[1] && r[1] != r[2] && r[0] != r[2]) tris.push_back(r);
  }
  vertices = std::move(kept);
  triangles = std::move(tris);
}

TriangleMesh loadObjectMesh(const std::string& path, double scale, const MeshLimits& limits) {
  const std::string ext = extensionOf(path);
  if (ext != "obj" && ext != "stl" && ext != "ply") fail(path + ": not an OBJ, STL or PLY file (extension '" + ext + "')");
  if (!std::ifstream(path).good()) fail(path + ": mesh file not found or not readable");
  if (!(scale > 0.0 && std::isfinite(scale))) fail(path + ": scale must be > 0");
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(path, aiProcess_Triangulate | aiProcess_PreTransformVertices);
  if (!scene) fail(path + ": cannot be read (" + importer.GetErrorString() + ")");
  TriangleMesh m;
  for (unsigned i = 0; i < scene->mNumMeshes; ++i) {
    const aiMesh* a = scene->mMeshes[i];
    const int offset = static_cast<int>(m.vertices.size());
    for (unsigned v = 0; v < a->mNumVertices; ++v)
      m.vertices.emplace_back(scale * a->mVertices[v].x, scale * a->mVertices[v].y, scale * a->mVertices[v].z);
    for (unsigned f = 0; f < a->mNumFaces; ++f)
      if (a->mFaces[f].mNumIndices == 3)
        m.triangles.emplace_back(offset + static_cast<int>(a->mFaces[f].mIndices[0]),
                                 offset + static_cast<int>(a->mFaces[f].mIndices[1]),
                                 offset + static_cast<int>(a->mFaces[f].mIndices[2]));
  }
  for (const auto& v : m.vertices)
    if (!v.allFinite()) fail(path + ": has a non-finite vertex");
  if (m.triangles.empty()) fail(path + ": has no triangles (empty mesh)");
  if (m.triangles.size() > limits.max_triangles)
    fail(path + ": has " + std::to_string(m.triangles.size()) + " triangles (at most " +
         std::to_string(limits.max_triangles) + ")");
  m.weld(1e-7 * std::max(1.0, (m.boundsMax() - m.boundsMin()).norm()));
  const Eigen::Vector3d extent = m.boundsMax() - m.boundsMin();
  std::ostringstream os;
  os << extent.x() << " x " << extent.y() << " x " << extent.z() << " m after scale " << scale;
  if (m.triangles.empty() || m.area() <= 0.0) fail(path + ": is degenerate (no triangle has an area)");
  if (extent.minCoeff() < limits.min_extent)
    fail(path + ": is degenerate: " + os.str() + " (thinner than " + std::to_string(limits.min_extent) + " m)");
  if (extent.maxCoeff() > limits.max_extent)
    fail(path + ": is huge: " + os.str() + " (larger than " + std::to_string(limits.max_extent) +
         " m; wrong units? set scale)");
  const Eigen::Vector3d centre = 0.5 * (m.boundsMin() + m.boundsMax());
  for (auto& v : m.vertices) v -= centre;
  return m;
}

void writeMeshFile(const TriangleMesh& mesh, const std::string& path) {
  const std::string ext = extensionOf(path);
  const char* format = ext == "obj" ? "objnomtl" : ext == "stl" ? "stlb" : ext == "ply" ? "plyb" : nullptr;
  if (!format) fail(path + ": unknown mesh format (use .obj, .stl or .ply)");
  aiScene scene;  // owns everything below (its destructor deletes it)
  scene.mRootNode = new aiNode();
  scene.mRootNode->mNumMeshes = 1;
  scene.mRootNode->mMeshes = new unsigned[1]{0};
  scene.mNumMaterials = 1;
  scene.mMaterials = new aiMaterial*[1]{new aiMaterial()};
  scene.mNumMeshes = 1;
  scene.mMeshes = new aiMesh*[1]{new aiMesh()};
  aiMesh* m = scene.mMeshes[0];
  m->mMaterialIndex = 0;
  m->mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
  m->mNumVertices = static_cast<unsigned>(mesh.vertices.size());
  m->mVertices = new aiVector3D[mesh.vertices.size()];
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
    m->mVertices[i] = aiVector3D(static_cast<ai_real>(mesh.vertices[i].x()), static_cast<ai_real>(mesh.vertices[i].y()),
                                 static_cast<ai_real>(mesh.vertices[i].z()));
  m->mNumFaces = static_cast<unsigned>(mesh.triangles.size());
  m->mFaces = new aiFace[mesh.triangles.size()];
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    m->mFaces[i].mNumIndices = 3;
    m->mFaces[i].mIndices = new unsigned[3];
    for (int k = 0; k < 3; ++k) m->mFaces[i].mIndices[k] = static_cast<unsigned>(mesh.triangles[i][k]);
  }
  Assimp::Exporter exporter;
  if (exporter.Export(&scene, format, path) != AI_SUCCESS)
    fail(path + ": cannot be written (" + exporter.GetErrorString() + ")");
}

TriangleMesh boxSurface(const Eigen::Vector3d& size) {
  TriangleMesh m;
  const Eigen::Vector3d h = 0.5 * size;
  for (int i = 0; i < 8; ++i)
    m.vertices.emplace_back((i & 1 ? 1 : -1) * h.x(), (i & 2 ? 1 : -1) * h.y(), (i & 4 ? 1 : -1) * h.z());
  // Two triangles per face, counter-clockwise seen from outside.
  const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : faces) {
    m.triangles.emplace_back(f[0], f[1], f[2]);
    m.triangles.emplace_back(f[0], f[2], f[3]);
  }
  return m;
}

TriangleMesh cylinderSurface(double diameter, double height, int sides) {
  TriangleMesh m;
  const double r = 0.5 * diameter, hz = 0.5 * height;
  for (int k = 0; k < sides; ++k) {
    const double a = 2.0 * M_PI * (k + 0.5) / sides;
    m.vertices.emplace_back(r * std::cos(a), r * std::sin(a), -hz);
    m.vertices.emplace_back(r * std::cos(a), r * std::sin(a), hz);
  }
  const int bottom = static_cast<int>(m.vertices.size());
  m.vertices.emplace_back(0.0, 0.0, -hz);
  m.vertices.emplace_back(0.0, 0.0, hz);
  for (int k = 0; k < sides; ++k) {
    const int a0 = 2 * k, a1 = a0 + 1, b0 = 2 * ((k + 1) % sides), b1 = b0 + 1;
    m.triangles.emplace_back(a0, b0, b1);
    m.triangles.emplace_back(a0, b1, a1);
    m.triangles.emplace_back(bottom, b0, a0);
    m.triangles.emplace_back(bottom + 1, a1, b1);
  }
  return m;
}

}  // namespace ehc_sim
