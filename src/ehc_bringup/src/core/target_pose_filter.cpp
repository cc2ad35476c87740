#include "ehc_bringup/target_pose_filter.h"

#include "ehc_common/config_node.h"
#include "ehc_common/enum_names.h"
#include "ehc_control/mpbs.h"
#include "ehc_control/pose_math.h"

#include <cmath>
#include <sstream>

using ehc_common::requireRange;

namespace ehc_bringup {

namespace {
constexpr ehc_common::EnumNames<TargetPoseFilter::Update, 4> kUpdateNames = {
    {{TargetPoseFilter::Update::First, "first"},
     {TargetPoseFilter::Update::Smoothed, "smoothed"},
     {TargetPoseFilter::Update::JumpHeld, "jump_held"},
     {TargetPoseFilter::Update::JumpConfirmed, "jump_confirmed"}}};
constexpr double kDeg = M_PI / 180.0;
}  // namespace

std::string toString(TargetPoseFilter::Update u) { return ehc_common::enumName(kUpdateNames, u, "TargetPoseFilter"); }

void TargetPoseFilterParams::validate() const {
  const char* o = "TargetPoseFilter";
  if (!(std::isfinite(gain) && gain > 0.0 && gain <= 1.0))
    throw std::invalid_argument(std::string("[") + o + "] parameter 'pose_filter_gain' = " + std::to_string(gain) +
                                " must be in (0, 1]");
  requireRange(o, "pose_jump_distance", jump_distance, 1e-6, 10.0);
  requireRange(o, "pose_jump_angle_deg", jump_angle_deg, 1e-6, 180.0);
  requireRange(o, "pose_jump_confirmations", jump_confirmations, 1, 100);
}

std::string TargetPoseFilterParams::summary() const {
  std::ostringstream s;
  s << "pose filter gain " << gain << "; a perceived pose more than " << jump_distance << " m or "
    << jump_angle_deg << " deg away moves the object only when " << jump_confirmations
    << " agree in a row";
  return s.str();
}

TargetPoseFilterParams loadTargetPoseFilterParams(const ehc_common::ConfigNode& s) {
  TargetPoseFilterParams p;
  p.gain = s.get("pose_filter_gain", p.gain);
  p.jump_distance = s.get("pose_jump_distance", p.jump_distance);
  p.jump_angle_deg = s.get("pose_jump_angle_deg", p.jump_angle_deg);
  p.jump_confirmations = s.get("pose_jump_confirmations", p.jump_confirmations);
  s.validate(p);
  return p;
}

TargetPoseFilter::TargetPoseFilter(const TargetPoseFilterParams& params) : params_(params) { params_.validate(); }

bool TargetPoseFilter::near(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) const {
  return (a.translation() - b.translation()).norm() <= params_.jump_distance &&
         ehc_control::rotationAngle(a.linear(), b.linear()) <= params_.jump_angle_deg * kDeg;
}

void TargetPoseFilter::dropHeld() {
  outliers_ += held_;
  held_ = 0;
}

TargetPoseFilter::Update TargetPoseFilter::add(const Eigen::Isometry3d& observation) {
  if (!pose_) {
    pose_ = observation;
    return Update::First;
  }
  if (near(observation, *pose_)) {
    dropHeld();  // back where it was: the held jumps were outliers
    pose_ = ehc_control::interpolatePose(*pose_, observation, params_.gain);
    return Update::Smoothed;
  }
  if (held_ > 0 && near(observation, first_held_)) {
    held_pose_ = ehc_control::interpolatePose(held_pose_, observation, params_.gain);
    ++held_;
  } else {
    dropHeld();  // none held, or held ones elsewhere: this one starts anew
    first_held_ = held_pose_ = observation;
    held_ = 1;
  }
  if (held_ < params_.jump_confirmations) return Update::JumpHeld;
  pose_ = held_pose_;
  held_ = 0;
  return Update::JumpConfirmed;
}

void TargetPoseFilter::reset() {
  pose_.reset();
  held_ = 0;
}

}  // namespace ehc_bringup
