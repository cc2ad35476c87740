#pragma once
// Self-collision pairs a collision checker skips, computed from the URDF as MoveIt's setup
// assistant does: adjacent links (RobotCollisionModel::adjacent: their shapes touch by
// construction) and pairs whose shapes are in contact in every sampled arm configuration
// (seeded uniform samples within robot.yaml's joint limits, finger openings within their
// travel; FCL), plus robot.yaml's robot.collision.ignore_pairs. ROS-free.

#include "ehc_control/robot_collision_model.h"
#include "ehc_control/whole_body_model.h"

#include <string>
#include <utility>
#include <vector>

namespace ehc_control {

using LinkPair = std::pair<std::string, std::string>;  ///< first < second

struct SelfCollisionSampling {
  int samples = 1000;  ///< arm configurations sampled
  unsigned seed = 1;
  void validate() const;  ///< throws "[SelfCollisionSampling] ..."
};

/// Pairs of `collision`'s links (not adjacent) in contact in every sampled configuration,
/// sorted, first < second.
std::vector<LinkPair> alwaysCollidingPairs(const WholeBodyModel& model, const RobotCollisionModel& collision,
                                           const SelfCollisionSampling& sampling = {});

/// Every pair of `collision`'s links a self-collision check skips: adjacent, always colliding
/// (alwaysCollidingPairs) and model.config().ignore_pairs; sorted, unique, first < second.
std::vector<LinkPair> selfCollisionIgnorePairs(const WholeBodyModel& model, const RobotCollisionModel& collision,
                                               const SelfCollisionSampling& sampling = {});

}  // namespace ehc_control
