#pragma once
// ObjectLibrary: the simulator's everyday objects, generated. Each object is a kind (mug, bowl,
// bottle, can, box, tool, banana, bars, blob), its generator parameters and a seed; the same
// kind, parameters and seed give the same triangles (generateObjectMesh). The manifest
// (config/objects/library.yaml) lists every object with its parameters, bounding box, mass
// (density x solid volume), friction, mesh file and split (tuning or validation); the meshes
// themselves are written from it by `ehc_object_library meshes` (the build runs it) and are not
// kept in the repository. Shapes are unions of closed parts (a mug: a base disc, a wall of convex
// sectors and a handle made of short cylinders; bars: overlapping boxes), so the simulator's
// convex hulls of parts (SimWorld) are close to the shape. ROS-free.

#include "ehc_sim/scene_config.h"
#include "ehc_sim/triangle_mesh.h"

#include <Eigen/Core>

#include <map>
#include <string>
#include <vector>

namespace ehc_sim {

struct LibraryObject {
  std::string name;
  std::string kind;
  unsigned seed = 0;
  std::string split;  ///< "tuning" or "validation"
  std::string file;   ///< mesh file name in the library's mesh folder (.obj, .stl or .ply)
  std::map<std::string, double> params;  ///< generator parameters (m, kg/m^3), by name
  Eigen::Vector3d size = Eigen::Vector3d::Zero();  ///< m, bounding box of the mesh
  double mass = 0.0;      ///< kg
  double friction = 0.8;
};

struct ObjectLibrary {
  std::string source_file;
  unsigned seed = 0;      ///< the seed the manifest was drawn with
  std::string mesh_dir;   ///< absolute: where the mesh files are (the manifest's mesh_dir)
  std::vector<LibraryObject> objects;

  /// The object called `name`; throws "[ObjectLibrary] ..." listing the names if none.
  const LibraryObject& object(const std::string& name) const;
  std::string meshPath(const LibraryObject& o) const { return mesh_dir + "/" + o.file; }
};

/// A scene object (shape: mesh) of library object `name`: its mesh file (written by
/// `ehc_object_library meshes`; a missing file is an error naming it and that command), mass and
/// friction from the manifest; position and tag are the caller's.
BodyConfig libraryBody(const ObjectLibrary& library, const std::string& name);

/// The kinds generateObjectMesh knows, in manifest order.
const std::vector<std::string>& objectKinds();

/// Parameters of an object of `kind` drawn from its plausible ranges (uniform) with `seed`.
std::map<std::string, double> drawObjectParams(const std::string& kind, unsigned seed);

/// The object's triangles (metres, resting upright with its bottom at z = 0, centred in x, y).
/// Throws std::invalid_argument "[ObjectLibrary] ..." on an unknown kind or a missing parameter.
TriangleMesh generateObjectMesh(const std::string& kind, const std::map<std::string, double>& params, unsigned seed);

/// A library object drawn with `seed`: parameters, mesh, bounding box and mass filled in.
LibraryObject drawLibraryObject(const std::string& name, const std::string& kind, unsigned seed,
                                const std::string& split, const std::string& extension);

/// The whole library: `per_kind` objects of every kind, seeds seed * 1000 + k, alternately
/// tuning and validation, mesh formats in turn obj, stl, ply.
ObjectLibrary drawObjectLibrary(unsigned seed, int per_kind);

/// Reads and checks a manifest (top-level key object_library; unknown keys are errors).
ObjectLibrary loadObjectLibrary(const std::string& path);
/// The manifest as YAML text (what loadObjectLibrary reads; mesh_dir written relative: `meshes`).
std::string objectLibraryYaml(const ObjectLibrary& library, const std::string& command);

}  // namespace ehc_sim
