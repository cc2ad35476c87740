#include "ehc_perception/robot_collision_model.h"

#include "ehc_control/urdf_collision.h"

#include <urdf_parser/urdf_parser.h>

#include <cmath>
#include <map>
#include <sstream>
#include <stdexcept>

namespace ehc_perception {

namespace {
[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument("[RobotCollisionModel] " + what);
}

void addShapes(const urdf::Link& link, std::vector<CollisionShape>* out) {
  for (const ehc_control::UrdfCollisionShape& u : ehc_control::urdfCollisionShapes(link, "RobotCollisionModel")) {
    CollisionShape s;
    s.link = link.name;
    s.origin = u.origin;
    s.size = u.size;
    s.type = u.type == ehc_control::UrdfCollisionShape::Type::Box        ? CollisionShape::Type::Box
             : u.type == ehc_control::UrdfCollisionShape::Type::Cylinder ? CollisionShape::Type::Cylinder
                                                                         : CollisionShape::Type::Sphere;
    out->push_back(s);
  }
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

RobotCollisionModel::RobotCollisionModel(const std::string& urdf_xml,
                                         const std::vector<std::string>& links) {
  const urdf::ModelInterfaceSharedPtr model = urdf::parseURDF(urdf_xml);
  if (!model) fail("cannot parse the URDF");
  if (links.empty()) {
    for (const auto& kv : model->links_) {
      const std::size_t before = shapes_.size();
      addShapes(*kv.second, &shapes_);
      if (shapes_.size() > before) links_.push_back(kv.first);
    }
  } else {
    for (const std::string& name : links) {
      const auto it = model->links_.find(name);
      if (it == model->links_.end()) fail("link '" + name + "' is not in the URDF");
      const std::size_t before = shapes_.size();
      addShapes(*it->second, &shapes_);
      if (shapes_.size() == before) fail("link '" + name + "' has no collision geometry");
      links_.push_back(name);
    }
  }
  if (shapes_.empty()) fail("the URDF has no collision geometry");
  for (const std::string& name : links_) {
    Eigen::Isometry3d offset = Eigen::Isometry3d::Identity();
    const urdf::JointConstSharedPtr& j = model->links_.at(name)->parent_joint;
    if (j && j->type == urdf::Joint::PRISMATIC) {
      if (!j->limits || !(j->limits->upper > j->limits->lower))
        fail("prismatic joint '" + j->name + "' of link '" + name + "' needs limits lower < upper");
      // The child link frame is the joint frame, where the axis is expressed.
      offset.translation() = j->limits->upper * Eigen::Vector3d(j->axis.x, j->axis.y, j->axis.z);
    }
    link_offsets_.push_back(offset);
  }
}

std::string RobotCollisionModel::summary() const {
  std::map<std::string, int> count;
  for (const auto& s : shapes_) ++count[s.link];
  std::ostringstream os;
  os << "robot collision model: " << shapes_.size() << " shapes on " << links_.size()
     << " links (";
  for (std::size_t i = 0; i < links_.size(); ++i)
    os << (i ? ", " : "") << links_[i]
       << (link_offsets_[i].translation().isZero() ? "" : " (prismatic: at its upper limit, e.g. a finger fully open)");
  os << ")";
  return os.str();
}

}  // namespace ehc_perception
