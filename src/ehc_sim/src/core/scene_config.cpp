#include "ehc_sim/scene_config.h"

#include "ehc_common/config_node.h"
#include "ehc_sim/fake_robot_config.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>
#include <stdexcept>

using ehc_common::ConfigNode;

namespace ehc_sim {


namespace {
const char* kOwner = "SceneConfig";

Eigen::Isometry3d poseFromXyzRpy(const Eigen::Vector3d& xyz, const Eigen::Vector3d& rpy) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = (Eigen::AngleAxisd(rpy.z(), Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(rpy.y(), Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(rpy.x(), Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  T.translation() = xyz;
  return T;
}

Face faceFromString(const ConfigNode& n, const std::string& key, const std::string& s) {
  if (s == "+x") return Face::PosX;
  if (s == "-x") return Face::NegX;
  if (s == "+y") return Face::PosY;
  if (s == "-y") return Face::NegY;
  if (s == "+z") return Face::PosZ;
  if (s == "-z") return Face::NegZ;
  n.fail(key, "must be one of +x, -x, +y, -y, +z, -z (got '" + s + "')");
}

ShapeType shapeFromString(const ConfigNode& n, const std::string& key, const std::string& s) {
  if (s == "box") return ShapeType::Box;
  if (s == "cylinder") return ShapeType::Cylinder;
  if (s == "mesh") return ShapeType::Mesh;
  n.fail(key, "must be 'box', 'cylinder' or 'mesh' (got '" + s + "')");
}

void checkRange(const ConfigNode& n, const std::string& key, double v, double lo, double hi) {
  if (!(v >= lo && v <= hi)) {
    std::ostringstream os;
    os << "= " << v << " is outside [" << lo << ", " << hi << "]";
    n.fail(key, os.str());
  }
}

BodyConfig loadBody(const ConfigNode& n, bool dynamic, int default_shade) {
  BodyConfig b;
  b.name = n.require<std::string>("name");
  b.shape = shapeFromString(n, "shape", n.get<std::string>("shape", "box"));
  if (b.shape == ShapeType::Mesh) {
    if (n.has("size")) n.fail("size", "is read from the mesh file (its bounding box); set scale instead");
    const std::string file = n.requirePath("mesh");
    try {
      b = meshBody(b.name, file, n.get<double>("scale", 1.0));
    } catch (const std::invalid_argument& e) {
      n.fail("mesh", e.what());
    }
  } else if (b.shape == ShapeType::Box) {
    b.size = n.requireVector("size", 3);
  } else {
    const Eigen::VectorXd s = n.requireVector("size", 2);
    b.size = Eigen::Vector3d(s[0], s[1], 0.0);
  }
  const int nsize = b.shape == ShapeType::Cylinder ? 2 : 3;
  for (int i = 0; i < nsize; ++i) checkRange(n, "size", b.size[i], 0.005, 20.0);
  b.position = n.requireVector("position", 3);
  b.rpy = n.getVector("rpy", Eigen::Vector3d::Zero(), 3);
  if (dynamic) {
    b.mass = n.require<double>("mass");
    checkRange(n, "mass", b.mass, 0.001, 20.0);
  } else {
    if (n.has("mass") && n.require<double>("mass") != 0.0)
      n.fail("mass", "must be 0 or absent (obstacles are static)");
    b.mass = 0.0;
  }
  b.friction = n.get<double>("friction", b.friction);
  checkRange(n, "friction", b.friction, 0.0, 5.0);
  b.shade = n.get<int>("shade", default_shade);
  checkRange(n, "shade", b.shade, 0, 255);
  if (n.has("tag")) {
    const ConfigNode t = n.child("tag");
    b.tag.enabled = true;
    b.tag.id = t.require<int>("id");
    checkRange(t, "id", b.tag.id, 0, 586);
    b.tag.size = t.require<double>("size");
    checkRange(t, "size", b.tag.size, 0.005, 2.0);
    b.tag.face = faceFromString(t, "face", t.get<std::string>("face", "-x"));
    // The printed pattern (10/8 of the black square) must fit on its face.
    const Eigen::Vector3d he = b.halfExtents();
    const double printed = b.tag.size * 10.0 / 8.0;
    double w = 0, h = 0;
    switch (b.tag.face) {
      case Face::PosX: case Face::NegX: w = 2 * he.y(); h = 2 * he.z(); break;
      case Face::PosY: case Face::NegY: w = 2 * he.x(); h = 2 * he.z(); break;
      case Face::PosZ: case Face::NegZ: w = 2 * he.x(); h = 2 * he.y(); break;
    }
    if (b.shape == ShapeType::Cylinder && b.tag.face != Face::PosZ && b.tag.face != Face::NegZ)
      w = b.size.x() * 0.7;  // keep a printed tag on the flat-ish part of the curved side
    if (b.shape == ShapeType::Cylinder && (b.tag.face == Face::PosZ || b.tag.face == Face::NegZ))
      w = h = b.size.x() / std::sqrt(2.0);
    if (b.shape == ShapeType::Mesh) b.tag.surface = b.mesh->exitDistance(tagPoseInBody(b).translation().normalized());
    if (printed > w + 1e-9 || printed > h + 1e-9) {
      std::ostringstream os;
      os << "size " << b.tag.size << " m (printed " << printed << " m with its white border) "
         << "does not fit on face " << toString(b.tag.face) << " (" << w << " x " << h << " m)";
      t.fail("size", os.str());
    }
  }
  return b;
}

TableConfig loadTable(const ConfigNode& n) {
  TableConfig t;
  t.name = n.require<std::string>("name");
  t.size = n.requireVector("size", 2);
  for (int i = 0; i < 2; ++i) checkRange(n, "size", t.size[i], 0.1, 10.0);
  t.center = n.requireVector("center", 2);
  t.yaw = n.get<double>("yaw", 0.0);
  t.height = n.require<double>("height");
  checkRange(n, "height", t.height, 0.05, 3.0);
  t.thickness = n.get<double>("thickness", t.thickness);
  checkRange(n, "thickness", t.thickness, 0.005, 0.5);
  if (t.thickness >= t.height) n.fail("thickness", "must be smaller than the table height");
  t.leg_size = n.get<double>("leg_size", t.leg_size);
  checkRange(n, "leg_size", t.leg_size, 0.01, 0.5);
  if (3.0 * t.leg_size > std::min(t.size.x(), t.size.y()))
    n.fail("leg_size", "is too large for the table top");
  t.shade = n.get<int>("shade", t.shade);
  checkRange(n, "shade", t.shade, 0, 255);
  return t;
}

/// One `targets:` entry (ehc_control::loadTargetSelector), checked against the scene's objects.
ehc_control::TargetSelector loadSceneTarget(const ConfigNode& n, const SceneConfig& c) {
  const ehc_control::TargetSelector t = ehc_control::loadTargetSelector(n);
  using K = ehc_control::TargetSelectorKind;
  if ((t.kind == K::KthFromLeft || t.kind == K::KthFromFront) && t.k > static_cast<int>(c.objects.size()))
    n.fail("k", "= " + std::to_string(t.k) + " is out of range: the scene has " + std::to_string(c.objects.size()) +
                    " object(s)");
  if (t.kind == K::Tag && std::none_of(c.objects.begin(), c.objects.end(), [&](const BodyConfig& o) {
        return o.tag.enabled && o.tag.id == t.tag_id;
      }))
    n.fail("tag_id", "= " + std::to_string(t.tag_id) + " is on none of the scene's objects");
  return t;
}

SceneConfig loadScene(const ConfigNode& root) {
  const ConfigNode s = root.child("scene");
  SceneConfig c;
  c.source_file = root.file();
  c.name = s.get<std::string>("name", c.name);
  if (s.has("robot_start")) c.robot_start = loadBasePose(s.child("robot_start"));
  if (s.has("floor")) {
    const ConfigNode f = s.child("floor");
    c.floor_shade = f.get<int>("shade", c.floor_shade);
    checkRange(f, "shade", c.floor_shade, 0, 255);
    c.floor_friction = f.get<double>("friction", c.floor_friction);
    checkRange(f, "friction", c.floor_friction, 0.0, 5.0);
  }
  for (std::size_t i = 0; i < s.listSize("tables"); ++i)
    c.tables.push_back(loadTable(s.element("tables", i)));
  for (std::size_t i = 0; i < s.listSize("objects"); ++i)
    c.objects.push_back(loadBody(s.element("objects", i), true, 200));
  for (std::size_t i = 0; i < s.listSize("obstacles"); ++i)
    c.obstacles.push_back(loadBody(s.element("obstacles", i), false, 90));
  for (std::size_t i = 0; i < s.listSize("targets"); ++i) c.targets.push_back(loadSceneTarget(s.element("targets", i), c));
  root.validate(c);
  root.rejectUnknownKeys();
  return c;
}
}  // namespace

std::string toString(ShapeType s) {
  switch (s) {
    case ShapeType::Box: return "box";
    case ShapeType::Cylinder: return "cylinder";
    case ShapeType::Mesh: return "mesh";
  }
  return "?";
}

BodyConfig meshBody(const std::string& name, const std::string& file, double scale) {
  BodyConfig b;
  b.name = name;
  b.shape = ShapeType::Mesh;
  b.mesh_file = file;
  b.mesh_scale = scale;
  b.mesh = std::make_shared<const TriangleMesh>(loadObjectMesh(file, scale));
  b.size = b.mesh->boundsMax() - b.mesh->boundsMin();
  return b;
}

std::string toString(Face f) {
  switch (f) {
    case Face::PosX: return "+x";
    case Face::NegX: return "-x";
    case Face::PosY: return "+y";
    case Face::NegY: return "-y";
    case Face::PosZ: return "+z";
    case Face::NegZ: return "-z";
  }
  return "?";
}

Eigen::Isometry3d BodyConfig::pose() const { return poseFromXyzRpy(position, rpy); }

Eigen::Vector3d BodyConfig::halfExtents() const {
  if (shape != ShapeType::Cylinder) return 0.5 * size;
  return Eigen::Vector3d(0.5 * size.x(), 0.5 * size.x(), 0.5 * size.y());
}

std::vector<BodyConfig> SceneConfig::bodies() const {
  std::vector<BodyConfig> out;
  for (const auto& t : tables)
    for (const auto& b : t.bodies()) out.push_back(b);
  out.insert(out.end(), objects.begin(), objects.end());
  out.insert(out.end(), obstacles.begin(), obstacles.end());
  return out;
}

std::string nearestBody(const std::vector<BodyConfig>& bodies, const std::function<Eigen::Isometry3d(int)>& pose,
                        const Eigen::Vector3d& p) {
  std::string best = "floor";
  double best_d = std::abs(p.z());
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    const Eigen::Vector3d local = pose(static_cast<int>(i)).inverse() * p;
    const double d = (local.cwiseAbs() - bodies[i].halfExtents()).cwiseMax(0.0).norm();
    if (d < best_d) {
      best_d = d;
      best = bodies[i].name;
    }
  }
  return best;
}

std::vector<BodyConfig> TableConfig::bodies() const {
  std::vector<BodyConfig> out;
  const Eigen::Isometry3d T = poseFromXyzRpy(Eigen::Vector3d(center.x(), center.y(), 0.0),
                                             Eigen::Vector3d(0, 0, yaw));
  BodyConfig top;
  top.name = name + "_top";
  top.size = Eigen::Vector3d(size.x(), size.y(), thickness);
  top.position = T * Eigen::Vector3d(0, 0, height - 0.5 * thickness);
  top.rpy = Eigen::Vector3d(0, 0, yaw);
  top.shade = shade;
  out.push_back(top);
  const double leg_h = height - thickness;
  const double ox = 0.5 * size.x() - leg_size, oy = 0.5 * size.y() - leg_size;
  const double sx[4] = {1, 1, -1, -1}, sy[4] = {1, -1, 1, -1};
  for (int i = 0; i < 4; ++i) {
    BodyConfig leg;
    leg.name = name + "_leg" + std::to_string(i);
    leg.size = Eigen::Vector3d(leg_size, leg_size, leg_h);
    leg.position = T * Eigen::Vector3d(sx[i] * ox, sy[i] * oy, 0.5 * leg_h);
    leg.rpy = Eigen::Vector3d(0, 0, yaw);
    leg.shade = shade - 40 < 0 ? 0 : shade - 40;
    out.push_back(leg);
  }
  return out;
}

void SceneConfig::validate() const {
  auto fail = [&](const std::string& what) {
    throw std::invalid_argument(std::string("[") + kOwner + "] " + source_file + ": " + what);
  };
  std::set<std::string> names;
  auto unique = [&](const std::string& n, const char* what) {
    if (n.empty()) fail(std::string(what) + " with an empty name");
    if (!names.insert(n).second) fail("name '" + n + "' is used twice (" + what + ")");
  };
  for (const auto& t : tables) {
    unique(t.name, "table");
    for (const auto& b : t.bodies()) unique(b.name, "table part");
  }
  for (const auto& o : objects) {
    unique(o.name, "object");
    if (!(o.mass > 0.0)) fail("object '" + o.name + "' needs a mass > 0");
  }
  for (const auto& o : obstacles) unique(o.name, "obstacle");
  std::set<int> tag_ids;
  for (const auto* list : {&objects, &obstacles})
    for (const auto& b : *list) {
      if (!b.position.allFinite() || !b.rpy.allFinite()) fail("'" + b.name + "' has a non-finite pose");
      if (b.position.z() - b.halfExtents().z() < -1e-6 && std::abs(b.rpy.x()) < 1e-9 &&
          std::abs(b.rpy.y()) < 1e-9)
        fail("'" + b.name + "' reaches below the floor (z = 0)");
      if (b.tag.enabled && !tag_ids.insert(b.tag.id).second)
        fail("tag id " + std::to_string(b.tag.id) + " is used twice ('" + b.name + "')");
    }
  if (!robot_start.allFinite()) fail("robot_start must be finite");
}

std::string SceneConfig::summary() const {
  std::ostringstream os;
  os << "scene '" << name << "' (" << source_file << "): robot start (" << robot_start.x() << ", "
     << robot_start.y() << ", " << robot_start.z() << ")\n";
  for (const auto& t : tables)
    os << "  table " << t.name << ": " << t.size.x() << " x " << t.size.y() << " m, top at "
       << t.height << " m, centre (" << t.center.x() << ", " << t.center.y() << ")\n";
  for (const auto& o : objects) {
    os << "  object " << o.name << ": " << toString(o.shape) << (o.mesh ? " " + o.mesh_file : std::string()) << " at (" << o.position.transpose()
       << "), " << o.mass << " kg";
    if (o.tag.enabled) os << ", tag36h11 id " << o.tag.id << " (" << o.tag.size << " m) on " << toString(o.tag.face);
    os << "\n";
  }
  for (const auto& o : obstacles)
    os << "  obstacle " << o.name << ": " << toString(o.shape) << " at (" << o.position.transpose()
       << ")\n";
  return os.str();
}

int SceneConfig::objectIndex(const std::string& n) const {
  for (std::size_t i = 0; i < objects.size(); ++i)
    if (objects[i].name == n) return static_cast<int>(i);
  return -1;
}

SceneConfig loadSceneConfig(const std::string& path) {
  return loadScene(ConfigNode::loadFile(path, kOwner));
}

SceneConfig loadSceneConfigString(const std::string& text, const std::string& origin) {
  return loadScene(ConfigNode::loadString(text, origin, kOwner));
}

Eigen::Isometry3d tagPoseInBody(const BodyConfig& body) {
  const Eigen::Vector3d he = body.halfExtents();
  Eigen::Vector3d n = -Eigen::Vector3d::UnitX(), up;  // outward normal; pattern's top
  switch (body.tag.face) {
    case Face::PosX: n = Eigen::Vector3d::UnitX(); break;
    case Face::NegX: n = -Eigen::Vector3d::UnitX(); break;
    case Face::PosY: n = Eigen::Vector3d::UnitY(); break;
    case Face::NegY: n = -Eigen::Vector3d::UnitY(); break;
    case Face::PosZ: n = Eigen::Vector3d::UnitZ(); break;
    case Face::NegZ: n = -Eigen::Vector3d::UnitZ(); break;
  }
  const bool cap = body.tag.face == Face::PosZ || body.tag.face == Face::NegZ;
  up = cap ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d z = n, y = up, x = y.cross(z);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear().col(0) = x;
  T.linear().col(1) = y;
  T.linear().col(2) = z;
  T.translation() = body.tag.surface >= 0.0 ? Eigen::Vector3d(body.tag.surface * n) : Eigen::Vector3d(n.cwiseProduct(he));
  return T;
}

}  // namespace ehc_sim
