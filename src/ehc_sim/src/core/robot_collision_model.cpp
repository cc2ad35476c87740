#include "ehc_sim/robot_collision_model.h"

#include <urdf_parser/urdf_parser.h>

#include <algorithm>
#include <functional>
#include <stdexcept>

namespace ehc_sim {

namespace {
[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument("[RobotCollisionModel] " + what);
}

Eigen::Isometry3d toEigen(const urdf::Pose& p) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z)
                   .normalized()
                   .toRotationMatrix();
  T.translation() = Eigen::Vector3d(p.position.x, p.position.y, p.position.z);
  return T;
}
}  // namespace

RobotCollisionModel::RobotCollisionModel(const std::string& urdf_xml,
                                         const std::vector<std::string>& arm_joints) {
  urdf::ModelInterfaceSharedPtr model = urdf::parseURDF(urdf_xml);
  if (!model) fail("the URDF could not be parsed");
  const urdf::LinkConstSharedPtr root = model->getRoot();
  if (!root) fail("the URDF has no root link");
  root_ = root->name;

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
          const bool is_arm =
              std::find(arm_joints.begin(), arm_joints.end(), j.name) != arm_joints.end();
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
        for (const auto& c : link->collision_array) {
          if (!c || !c->geometry) continue;
          LinkShape s;
          s.origin = toEigen(c->origin);
          switch (c->geometry->type) {
            case urdf::Geometry::BOX: {
              const auto* b = static_cast<const urdf::Box*>(c->geometry.get());
              s.type = LinkShape::Box;
              s.size = Eigen::Vector3d(b->dim.x, b->dim.y, b->dim.z);
              break;
            }
            case urdf::Geometry::CYLINDER: {
              const auto* cy = static_cast<const urdf::Cylinder*>(c->geometry.get());
              s.type = LinkShape::Cylinder;
              s.size = Eigen::Vector3d(cy->radius, cy->length, 0.0);
              break;
            }
            case urdf::Geometry::SPHERE: {
              const auto* sp = static_cast<const urdf::Sphere*>(c->geometry.get());
              s.type = LinkShape::Sphere;
              s.size = Eigen::Vector3d(sp->radius, 0.0, 0.0);
              break;
            }
            default:
              fail("link '" + link->name + "': only box, cylinder and sphere collision shapes "
                   "are supported (mesh found)");
          }
          if ((s.size.array() < 0.0).any() || s.size.x() <= 0.0)
            fail("link '" + link->name + "': collision shape with a non-positive size");
          g.shapes.push_back(s);
        }
        const bool has_geometry = !g.shapes.empty();
        if (has_geometry) links_.push_back(g);
        for (const auto& child : link->child_links)
          visit(child, has_geometry ? link->name : geometric_parent);
      };
  visit(root, "");
  if (links_.empty()) fail("the URDF has no collision geometry");
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

}  // namespace ehc_sim
