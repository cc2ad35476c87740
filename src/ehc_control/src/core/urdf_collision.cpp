#include "ehc_control/urdf_collision.h"

#include <urdf_model/link.h>

#include <stdexcept>

namespace ehc_control {

std::vector<UrdfCollisionShape> urdfCollisionShapes(const urdf::Link& link, const std::string& owner) {
  auto fail = [&](const std::string& what) {
    throw std::invalid_argument("[" + owner + "] link '" + link.name + "' " + what);
  };
  std::vector<urdf::CollisionSharedPtr> cols = link.collision_array;
  if (cols.empty() && link.collision) cols.push_back(link.collision);
  std::vector<UrdfCollisionShape> out;
  for (const auto& c : cols) {
    if (!c || !c->geometry) continue;
    UrdfCollisionShape s;
    const urdf::Pose& p = c->origin;
    s.origin.translation() << p.position.x, p.position.y, p.position.z;
    s.origin.linear() =
        Eigen::Quaterniond(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z).normalized().toRotationMatrix();
    switch (c->geometry->type) {
      case urdf::Geometry::BOX: {
        const auto* b = static_cast<const urdf::Box*>(c->geometry.get());
        s.type = UrdfCollisionShape::Type::Box;
        s.size << b->dim.x, b->dim.y, b->dim.z;
        break;
      }
      case urdf::Geometry::CYLINDER: {
        const auto* cy = static_cast<const urdf::Cylinder*>(c->geometry.get());
        s.type = UrdfCollisionShape::Type::Cylinder;
        s.size << cy->radius, cy->length, 0.0;
        break;
      }
      case urdf::Geometry::SPHERE: {
        const auto* sp = static_cast<const urdf::Sphere*>(c->geometry.get());
        s.type = UrdfCollisionShape::Type::Sphere;
        s.size << sp->radius, 0.0, 0.0;
        break;
      }
      default:
        fail("has a mesh collision geometry; only box, cylinder and sphere are supported");
    }
    if (!s.size.allFinite() || s.size.minCoeff() < 0.0 || s.size[0] <= 0.0)
      fail("has a degenerate collision shape (non-positive size)");
    out.push_back(s);
  }
  return out;
}

}  // namespace ehc_control
