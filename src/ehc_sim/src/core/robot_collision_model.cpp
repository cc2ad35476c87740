#include "ehc_sim/robot_collision_model.h"

#include "ehc_control/urdf_collision.h"

#include <urdf_parser/urdf_parser.h>

#include <algorithm>
#include <functional>
#include <stdexcept>

namespace ehc_sim {

namespace {
[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument("[RobotCollisionModel] " + what);
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
        for (const ehc_control::UrdfCollisionShape& u : ehc_control::urdfCollisionShapes(*link, "RobotCollisionModel")) {
          LinkShape s;
          s.origin = u.origin;
          s.size = u.size;
          s.type = u.type == ehc_control::UrdfCollisionShape::Type::Box        ? LinkShape::Box
                   : u.type == ehc_control::UrdfCollisionShape::Type::Cylinder ? LinkShape::Cylinder
                                                                               : LinkShape::Sphere;
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
