#pragma once
// The one conversion of a RobotCollisionModel shape into an FCL geometry (self-collision
// pairs here, the obstacle distance field of ehc_perception).

#include "ehc_control/robot_collision_model.h"

#include <fcl/geometry/collision_geometry.h>

#include <memory>

namespace ehc_control {

/// FCL box / cylinder / sphere of `shape` in its own frame (shape.origin not applied), local
/// AABB computed.
std::shared_ptr<fcl::CollisionGeometry<double>> makeFclGeometry(const CollisionShape& shape);

}  // namespace ehc_control
