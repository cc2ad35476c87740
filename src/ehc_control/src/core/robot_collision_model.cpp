#include "ehc_control/robot_collision_model.h"

#include <urdf_parser/urdf_parser.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <set>
#include <sstream>
#include <stdexcept>

namespace ehc_control {

namespace {
[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument("[RobotCollisionModel] " + what);
}

/// Every <collision> primitive of `link` (the URDF reader; meshes and degenerate sizes throw).
std::vector<CollisionShape> readShapes(const urdf::Link& link) {
  std::vector<urdf::CollisionSharedPtr> cols = link.collision_array;
  if (cols.empty() && link.collision) cols.push_back(link.collision);
  std::vector<CollisionShape> out;
  for (const auto& c : cols) {
    if (!c || !c->geometry) continue;
    CollisionShape s;
    const urdf::Pose& p = c->origin;
    s.origin.translation() << p.position.x, p.position.y, p.position.z;
    s.origin.linear() =
        Eigen::Quaterniond(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z).normalized().toRotationMatrix();
    switch (c->geometry->type) {
      case urdf::Geometry::BOX: {
        const auto* b = static_cast<const urdf::Box*>(c->geometry.get());
        s.type = CollisionShape::Type::Box;
        s.size << b->dim.x, b->dim.y, b->dim.z;
        break;
      }
      case urdf::Geometry::CYLINDER: {
        const auto* cy = static_cast<const urdf::Cylinder*>(c->geometry.get());
        s.type = CollisionShape::Type::Cylinder;
        s.size << cy->radius, cy->length, 0.0;
        break;
      }
      case urdf::Geometry::SPHERE: {
        const auto* sp = static_cast<const urdf::Sphere*>(c->geometry.get());
        s.type = CollisionShape::Type::Sphere;
        s.size << sp->radius, 0.0, 0.0;
        break;
      }
      default:
        fail("link '" + link.name + "' has a mesh collision geometry; only box, cylinder and sphere are supported");
    }
    if (!s.size.allFinite() || s.size.minCoeff() < 0.0 || s.size[0] <= 0.0)
      fail("link '" + link.name + "' has a degenerate collision shape (non-positive size)");
    out.push_back(s);
  }
  return out;
}
}  // namespace

bool CollisionShape::contains(const Eigen::Vector3d& p_link, double padding) const {
  const Eigen::Vector3d q = origin.inverse() * p_link;
  switch (type) {
    case Type::Box:
      return (q.cwiseAbs() - 0.5 * size).maxCoeff() <= padding;
    case Type::Cylinder:
      return std::abs(q.z()) <= 0.5 * size[1] + padding && q.head<2>().norm() <= size[0] + padding;
    case Type::Sphere:
      return q.norm() <= size[0] + padding;
  }
  return false;
}

double CollisionShape::boundingRadius() const {
  switch (type) {
    case Type::Box:
      return 0.5 * size.norm();
    case Type::Cylinder:
      return std::hypot(size[0], 0.5 * size[1]);
    case Type::Sphere:
      return size[0];
  }
  return 0.0;
}

Eigen::Vector3d CollisionShape::halfExtents() const {
  switch (type) {
    case Type::Box:
      return 0.5 * size;
    case Type::Cylinder:
      return Eigen::Vector3d(size[0], size[0], 0.5 * size[1]);
    case Type::Sphere:
      return Eigen::Vector3d::Constant(size[0]);
  }
  return Eigen::Vector3d::Zero();
}

Eigen::Isometry3d FingerJoint::offset(double opening) const {
  return Eigen::Isometry3d(Eigen::Translation3d(axis * opening));
}

RobotCollisionModel::RobotCollisionModel(const std::string& urdf_xml, const std::vector<std::string>& arm_joints,
                                         const std::vector<std::string>& links) {
  const urdf::ModelInterfaceSharedPtr model = urdf::parseURDF(urdf_xml);
  if (!model) fail("the URDF could not be parsed");
  const urdf::LinkConstSharedPtr root = model->getRoot();
  if (!root) fail("the URDF has no root link");
  root_ = root->name;
  for (const std::string& name : links)
    if (model->links_.find(name) == model->links_.end()) fail("link '" + name + "' is not in the URDF");
  const std::set<std::string> selected(links.begin(), links.end());

  std::function<void(const urdf::LinkConstSharedPtr&, const std::string&)> visit =
      [&](const urdf::LinkConstSharedPtr& link, const std::string& geometric_parent) {
        all_links_.push_back(link->name);
        const std::string parent = link->getParent() ? link->getParent()->name : "";
        parent_[link->name] = parent;
        geometric_parent_[link->name] = geometric_parent;
        RobotLinkGeometry g;
        g.name = link->name;
        g.parent = parent;
        g.parent_joint = link->parent_joint ? link->parent_joint->name : "";
        if (link->parent_joint) {
          const auto& j = *link->parent_joint;
          const bool is_arm = std::find(arm_joints.begin(), arm_joints.end(), j.name) != arm_joints.end();
          if (j.type == urdf::Joint::PRISMATIC && !is_arm) {
            FingerJoint f;
            f.joint = j.name;
            f.parent_link = j.parent_link_name;
            f.child_link = j.child_link_name;
            f.axis = Eigen::Vector3d(j.axis.x, j.axis.y, j.axis.z).normalized();
            if (j.limits) {
              f.lower = j.limits->lower;
              f.upper = j.limits->upper;
              f.velocity = j.limits->velocity;
            }
            if (!(f.upper > f.lower)) fail("finger joint '" + j.name + "' needs limits lower < upper");
            fingers_.push_back(f);
          } else if (j.type != urdf::Joint::FIXED && !is_arm) {
            fail("joint '" + j.name + "' is movable but neither an arm joint nor a prismatic finger");
          }
        }
        const bool keep = selected.empty() || selected.count(link->name) > 0;
        if (keep) g.shapes = readShapes(*link);
        if (!selected.empty() && keep && g.shapes.empty())
          fail("link '" + link->name + "' has no collision geometry");
        const bool has_geometry = !g.shapes.empty();
        if (has_geometry) links_.push_back(g);
        for (const auto& child : link->child_links) visit(child, has_geometry ? link->name : geometric_parent);
      };
  visit(root, "");
  if (links_.empty()) fail("the URDF has no collision geometry");
  if (!links.empty()) {  // the order asked for
    std::vector<RobotLinkGeometry> ordered;
    for (const std::string& name : links)
      for (const RobotLinkGeometry& g : links_)
        if (g.name == name) ordered.push_back(g);
    links_ = std::move(ordered);
  }
}

const std::string& RobotCollisionModel::parentOf(const std::string& link) const {
  const auto it = parent_.find(link);
  if (it == parent_.end()) fail("unknown link '" + link + "'");
  return it->second;
}

const FingerJoint* RobotCollisionModel::fingerOf(const std::string& link) const {
  for (const auto& f : fingers_)
    if (f.child_link == link) return &f;
  return nullptr;
}

bool RobotCollisionModel::adjacent(const std::string& a, const std::string& b) const {
  const auto ia = geometric_parent_.find(a), ib = geometric_parent_.find(b);
  if (ia == geometric_parent_.end() || ib == geometric_parent_.end()) return false;
  return ia->second == b || ib->second == a;
}

Eigen::Isometry3d RobotCollisionModel::fingerOffset(const std::string& link, std::optional<double> opening) const {
  const FingerJoint* f = fingerOf(link);
  if (!f) return Eigen::Isometry3d::Identity();
  return f->offset(opening ? *opening : f->upper);
}

std::string RobotCollisionModel::summary() const {
  std::size_t shapes = 0;
  for (const auto& l : links_) shapes += l.shapes.size();
  std::ostringstream os;
  os << "robot collision model: " << shapes << " shapes on " << links_.size() << " links (";
  for (std::size_t i = 0; i < links_.size(); ++i) {
    os << (i ? ", " : "") << links_[i].name;
    if (const FingerJoint* f = fingerOf(links_[i].name))
      os << " (finger joint '" << f->joint << "', " << f->lower << ".." << f->upper << " m)";
  }
  os << "), " << fingers_.size() << " finger joints";
  return os.str();
}

}  // namespace ehc_control
