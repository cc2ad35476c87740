#include "ehc_sim/parallel_gripper.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace ehc_sim {

ParallelGripper::ParallelGripper(const GripperConfig& cfg, double max_opening)
    : cfg_(cfg), max_opening_(max_opening) {
  cfg_.validate();
  if (!(max_opening > 0.0 && max_opening < 0.5) || !std::isfinite(max_opening))
    throw std::invalid_argument("[ParallelGripper] finger travel must be in (0, 0.5) m");
  reset();
}

void ParallelGripper::reset() {
  state_ = cfg_.start_open ? GripperState::Open : GripperState::ClosedEmpty;
  opening_ = cfg_.start_open ? max_opening_ : 0.0;
  held_ = -1;
  succeeded_ = false;
  have_grasp_z_ = false;
  grasps_ = successes_ = failures_ = 0;
}

void ParallelGripper::command(bool close) {
  if (close) {
    if (state_ == GripperState::Holding || state_ == GripperState::Closing) return;
    if (state_ == GripperState::ClosedEmpty) return;
    state_ = GripperState::Closing;
    succeeded_ = false;
  } else {
    if (state_ == GripperState::Open || state_ == GripperState::Opening) return;
    held_ = -1;
    have_grasp_z_ = false;
    state_ = GripperState::Opening;
  }
}

void ParallelGripper::advance(double dt) {
  if (!(dt > 0.0)) throw std::invalid_argument("[ParallelGripper] dt must be > 0");
  if (state_ == GripperState::Closing) {
    opening_ = std::max(0.0, opening_ - cfg_.speed * dt);
    if (opening_ <= 0.0) {
      state_ = GripperState::ClosedEmpty;
      ++failures_;
    }
  } else if (state_ == GripperState::Opening) {
    opening_ = std::min(max_opening_, opening_ + cfg_.speed * dt);
    if (opening_ >= max_opening_) state_ = GripperState::Open;
  }
}

bool ParallelGripper::onFingerContacts(const std::set<int>& left, const std::set<int>& right) {
  if (state_ != GripperState::Closing) return false;
  for (int o : left)
    if (o >= 0 && right.count(o)) {
      state_ = GripperState::Holding;
      held_ = o;
      have_grasp_z_ = false;
      ++grasps_;
      return true;
    }
  return false;
}

void ParallelGripper::onHeldObjectHeight(double z) {
  if (state_ != GripperState::Holding) return;
  if (!have_grasp_z_) {
    grasp_z_ = z;
    have_grasp_z_ = true;
    return;
  }
  if (!succeeded_ && z - grasp_z_ >= cfg_.lift_height - 1e-9) {
    succeeded_ = true;
    ++successes_;
  }
}

}  // namespace ehc_sim
