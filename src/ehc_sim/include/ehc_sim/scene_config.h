#pragma once
// SceneConfig: the content of a simulated world, loaded from a scene YAML under config/scenes/.
// Floor (always present, z = 0), tables (top box + four legs), graspable objects (box, cylinder
// or triangle mesh from an OBJ, STL or PLY file, with a mass, optional AprilTag 36h11 on one
// face) and static obstacles, plus the
// robot's start pose. ROS-free (yaml-cpp via ehc_common::ConfigNode); every error names the
// file and the field.

#include "ehc_control/target_selector.h"
#include "ehc_sim/triangle_mesh.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace ehc_sim {

enum class ShapeType { Box, Cylinder, Mesh };

std::string toString(ShapeType s);

/// Face of a box / cylinder in its own frame: "+x", "-x", "+y", "-y", "+z", "-z".
/// Cylinders (axis z) accept "+z"/"-z" (caps) and "+x", "-x", "+y", "-y" (the side, at the
/// point where the outward normal is that axis). On a mesh the tag lies on the face of the
/// bounding box, moved in to where the axis from the centre leaves the mesh.
enum class Face { PosX, NegX, PosY, NegY, PosZ, NegZ };

std::string toString(Face f);

/// An AprilTag (family 36h11) printed on one face of a body. `size` is the edge of the black
/// square (AprilTag convention); the printed pattern including its white border is 10/8 of it.
struct TagConfig {
  bool enabled = false;
  int id = 0;              ///< 0..586 (tag36h11)
  double size = 0.04;      ///< m, black-square edge
  Face face = Face::NegX;  ///< face the tag is printed on
  /// Mesh bodies: distance from the body origin along the face's normal to the surface the tag
  /// lies on (where that axis leaves the mesh); < 0: the bounding box's face.
  double surface = -1.0;
};

/// A box (size = [x, y, z] edges), an upright cylinder (size = [diameter, height]) or a mesh
/// (`mesh: <file>`, `scale`; its body frame is the centre of its bounding box, with the file's
/// axes, and `size` is the bounding box, read from the file).
struct BodyConfig {
  std::string name;
  ShapeType shape = ShapeType::Box;
  Eigen::Vector3d size = Eigen::Vector3d(0.05, 0.05, 0.1);  ///< box, mesh: edges; cylinder: [d, h, unused]
  std::string mesh_file;  ///< mesh: the file (resolved against the scene file's folder)
  double mesh_scale = 1.0;  ///< mesh: file units to metres
  std::shared_ptr<const TriangleMesh> mesh;  ///< mesh: the loaded, centred triangles
  Eigen::Vector3d position = Eigen::Vector3d::Zero();       ///< m, centre, world (odom) frame
  Eigen::Vector3d rpy = Eigen::Vector3d::Zero();            ///< rad, fixed-axis roll/pitch/yaw
  double mass = 0.0;       ///< kg; > 0 for objects, 0 (static) for obstacles and tables
  double friction = 0.8;
  int shade = 150;         ///< grey level 0..255 in the simulated image
  TagConfig tag;

  Eigen::Isometry3d pose() const;
  /// Half extents of the bounding box in the body frame.
  Eigen::Vector3d halfExtents() const;
};

/// A table: rectangular top of `thickness` whose upper surface is at `height`, four legs.
struct TableConfig {
  std::string name;
  Eigen::Vector2d size = Eigen::Vector2d(0.8, 1.2);  ///< m, top edges along its x and y
  Eigen::Vector2d center = Eigen::Vector2d(1.9, 0.0);  ///< m, top centre (x, y), world
  double yaw = 0.0;         ///< rad
  double height = 0.75;     ///< m, upper surface of the top
  double thickness = 0.04;  ///< m
  double leg_size = 0.05;   ///< m, square legs, inset by leg_size from the corners
  int shade = 170;

  /// The top and the legs as static boxes ("<name>_top", "<name>_leg0".."3").
  std::vector<BodyConfig> bodies() const;
};

struct SceneConfig {
  std::string name = "scene";
  std::string source_file;
  Eigen::Vector3d robot_start = Eigen::Vector3d::Zero();  ///< base x, y, yaw in odom
  int floor_shade = 110;
  double floor_friction = 0.8;
  std::vector<TableConfig> tables;
  std::vector<BodyConfig> objects;    ///< graspable, dynamic (mass > 0)
  std::vector<BodyConfig> obstacles;  ///< static
  /// `targets:` (optional): the grasp sequencer's targets in its order (object i of the
  /// sequencer = targets[i]), for the in-process pipeline and the experiments. Empty: every
  /// object's target is its tag (the tag files'). A k-th selector's k is at most the number of
  /// objects, a tag selector names a tag of the scene (errors name the file and the field).
  std::vector<ehc_control::TargetSelector> targets;

  /// Cross-field checks (unique names, sizes, masses, tag fits its face...). Throws
  /// std::invalid_argument "[SceneConfig] <file>: ...".
  void validate() const;
  std::string summary() const;
  /// Index of the object called `name`, -1 if none.
  int objectIndex(const std::string& name) const;
  /// Every body, in SimWorld's order: the tables' parts, the objects, the obstacles.
  std::vector<BodyConfig> bodies() const;
};

/// Name of the body (table part, object, obstacle) or "floor" nearest to `p` (world), by the
/// distance to its bounding box at pose(i) of body i: names a perceived obstacle point.
std::string nearestBody(const std::vector<BodyConfig>& bodies, const std::function<Eigen::Isometry3d(int)>& pose,
                        const Eigen::Vector3d& p);
/// A mesh body (`shape: mesh`) from `file` (loadObjectMesh: a missing, empty, degenerate or huge
/// mesh throws naming the file), with its bounding box as `size`.
BodyConfig meshBody(const std::string& name, const std::string& file, double scale);

/// Loads and validates a scene YAML file (top-level key `scene`).
SceneConfig loadSceneConfig(const std::string& path);
/// Same from YAML text; `origin` stands in for the file name in messages.
SceneConfig loadSceneConfigString(const std::string& text, const std::string& origin);

/// Pose of the tag frame in the body frame, in the convention of ViSP's vpDetectorAprilTag
/// poses (cMo): origin at the tag centre, x to the right and y up in the printed pattern, z out
/// of the face (towards a viewer). On side faces the pattern is upright (its top towards the
/// body's +z); on +z/-z faces its top points to the body's +x.
Eigen::Isometry3d tagPoseInBody(const BodyConfig& body);

}  // namespace ehc_sim
