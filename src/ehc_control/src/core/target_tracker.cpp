#include "ehc_control/target_tracker.h"

#include "ehc_common/config_node.h"

#include <sstream>
#include <stdexcept>

namespace ehc_control {

void TargetTrackerParams::validate() const {
  ehc_common::requireRange("TargetTrackerParams", "new_target_distance", new_target_distance, 1e-4, 100.0);
}

std::string TargetTrackerParams::summary() const {
  std::ostringstream os;
  os << "tracking: camera " << (camera_file.empty() ? std::string("<defaults>") : camera_file)
     << ", new target when the centre jumps > " << new_target_distance << " m";
  return os.str();
}

TargetTrackerParams loadTargetTrackerParams(const ehc_common::ConfigNode& n) {
  TargetTrackerParams p;
  const std::string camera = n.get<std::string>("camera", "");
  if (!camera.empty()) p.camera_file = n.requirePath("camera");
  p.new_target_distance = n.get("new_target_distance", p.new_target_distance);
  n.validate(p);  // errors name the file and the section
  return p;
}

TargetTracker::TargetTracker(const PinholeCamera& camera, const TargetTrackerParams& params)
    : camera_(camera), params_(params) {
  camera_.validate();
  params_.validate();
}

bool TargetTracker::setTarget(const Eigen::Vector3d& centre) {
  if (!centre.allFinite()) throw std::invalid_argument("[TargetTracker] non-finite target centre");
  const bool is_new = !has_target_ || (centre - centre_).norm() > params_.new_target_distance;
  if (is_new) {
    cycles_ = 0;
    in_view_cycles_ = 0;
    in_view_ = false;
  }
  has_target_ = true;
  centre_ = centre;
  return is_new;
}

void TargetTracker::moveTarget(const Eigen::Vector3d& centre) {
  if (!has_target_) {
    setTarget(centre);
    return;
  }
  if (!centre.allFinite()) throw std::invalid_argument("[TargetTracker] non-finite target centre");
  centre_ = centre;
}

bool TargetTracker::observe(const Eigen::Isometry3d& world_T_camera) {
  if (!has_target_) return false;
  in_view_ = world_T_camera.matrix().allFinite() && camera_.projectsInside(world_T_camera.inverse() * centre_);
  if (counting_) {
    ++cycles_;
    if (in_view_) ++in_view_cycles_;
  }
  return in_view_;
}

void TargetTracker::setCamera(const PinholeCamera& camera) {
  camera.validate();
  camera_ = camera;
}

void TargetTracker::reset() {
  has_target_ = false;
  in_view_ = false;
  counting_ = true;
  cycles_ = 0;
  in_view_cycles_ = 0;
}

}  // namespace ehc_control
