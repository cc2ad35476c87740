#pragma once
// TriangleMesh: the triangle surfaces of the simulator. Mesh objects of a scene (`shape: mesh`)
// are read from OBJ, STL or PLY files with assimp (loadObjectMesh: welded, checked, centred on
// their bounding box); boxes and cylinders get their surface from bodySurface. The depth camera
// rasterises these triangles (SimulatedCamera::cloud), Bullet builds a mesh body's collision
// shape from the convex hulls of its connected parts (SimWorld), and the object library writes
// its generated meshes with writeMeshFile. ROS-free.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <string>
#include <vector>

namespace ehc_sim {

struct TriangleMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3i> triangles;  ///< vertex indices

  bool empty() const { return triangles.empty(); }
  /// Appends `other` (indices shifted).
  void append(const TriangleMesh& other);
  /// Axis-aligned bounds (min, max) of the vertices; zero for an empty mesh.
  Eigen::Vector3d boundsMin() const;
  Eigen::Vector3d boundsMax() const;
  double area() const;
  /// Unit normal of triangle `t` (from its winding; zero for a degenerate triangle).
  Eigen::Vector3d normal(std::size_t t) const;
  /// The connected parts: triangles grouped by shared vertices (each a mesh of its own).
  std::vector<TriangleMesh> components() const;
  /// Volume of the solid the mesh encloses, overlapping parts counted once (each part is read
  /// as a closed surface: inside where a vertical line has crossed it an odd number of times),
  /// integrated over a grid of `columns` x `columns` vertical lines across the bounds.
  double solidVolume(int columns = 96) const;
  /// Distance from the origin along the unit `direction` to the farthest crossing of the surface
  /// (where that ray leaves the mesh for good); -1 if it crosses none.
  double exitDistance(const Eigen::Vector3d& direction) const;
  /// Merges vertices closer than `tolerance` (m), drops triangles that lose a corner.
  void weld(double tolerance);
};

/// Checks on a mesh read for a scene object; the messages name `origin` (the file).
struct MeshLimits {
  double min_extent = 0.002;  ///< m: a bounding box thinner than this on any axis is degenerate
  double max_extent = 2.0;    ///< m: an object larger than this on any axis is "huge"
  std::size_t max_triangles = 200000;
};

/// Reads an OBJ, STL or PLY file (assimp; every mesh of the file, node transforms applied),
/// scales it by `scale` (file units to metres), welds it, checks it (throws
/// std::invalid_argument "[TriangleMesh] <file>: ..." when the file is missing or unreadable,
/// empty, degenerate (no area, flat, non-finite) or huge) and shifts it so that its
/// bounding-box centre is the origin: the body frame of a mesh object.
TriangleMesh loadObjectMesh(const std::string& path, double scale, const MeshLimits& limits = MeshLimits());

/// Writes `mesh` with assimp's exporter; the format follows the extension (.obj, .stl, .ply).
/// Throws "[TriangleMesh] ..." on an unknown extension or a write error.
void writeMeshFile(const TriangleMesh& mesh, const std::string& path);

/// Closed triangle surfaces of the primitive shapes (body frame, centred): a box of edges
/// `size`; an upright cylinder of `diameter` and `height` whose `sides` vertices lie on the
/// circle (the chord error is r (1 - cos(pi / sides))).
TriangleMesh boxSurface(const Eigen::Vector3d& size);
TriangleMesh cylinderSurface(double diameter, double height, int sides);

}  // namespace ehc_sim
