#include "ehc_sim/step_scheduler.h"

#include <algorithm>

namespace ehc_sim {

const char* toString(StepAction a) {
  switch (a) {
    case StepAction::Wait: return "wait";
    case StepAction::Step: return "step";
    case StepAction::RepublishState: return "republish_state";
  }
  return "?";
}

StepScheduler::StepScheduler(const ehc_control::RobotConfig& robot, const FakeRobotConfig& config)
    : config_(config), gate_(robot) {
  config_.validate();
}

void StepScheduler::statePublished(double wall_s, std::int64_t stamp_ns, bool fresh) {
  if (fresh) {
    gate_.newState(stamp_ns);
    answered_ = false;
    last_fresh_publish_ = wall_s;
  }
  last_publish_ = wall_s;
}

std::string StepScheduler::onBaseTwist(double wall_s, double vx, double vy, double wz) {
  answered_ = true;
  last_base_cmd_ = wall_s;
  return gate_.onBaseTwist(vx, vy, wz);
}

std::string StepScheduler::onArmCommand(double wall_s, std::int64_t stamp_ns,
                                        const std::vector<std::string>& names,
                                        const std::vector<double>& velocities) {
  answered_ = true;
  const std::string why = gate_.onArmCommand(stamp_ns, names, velocities, lockStep());
  if (why.empty()) last_arm_cmd_ = wall_s;
  return why;
}

StepAction StepScheduler::next(double wall_s) {
  if (lockStep()) {
    if (gate_.ready()) {
      const bool paced = config_.max_real_time_factor > 0.0 &&
                         wall_s - last_fresh_publish_ < config_.dt / config_.max_real_time_factor;
      return paced ? StepAction::Wait : StepAction::Step;
    }
    if (!answered_ && wall_s - last_publish_ > config_.state_republish_period)
      return StepAction::RepublishState;
    return StepAction::Wait;
  }
  if (!next_step_) next_step_ = wall_s + config_.dt;  // first call: one period from now
  if (wall_s < *next_step_) return StepAction::Wait;
  auto stale = [&](const std::optional<double>& t) { return !t || wall_s - *t > config_.command_timeout; };
  if (stale(last_base_cmd_) || stale(last_arm_cmd_)) gate_.zero();
  *next_step_ += config_.dt;
  if (*next_step_ < wall_s) next_step_ = wall_s;  // do not try to catch up after a stall
  return StepAction::Step;
}

double StepScheduler::callbackWait() const {
  if (!lockStep()) return 0.0005;
  if (config_.max_real_time_factor > 0.0)
    return std::min(0.002, 0.25 * config_.dt / config_.max_real_time_factor);
  return 0.002;
}

void StepScheduler::reset() {
  gate_.zero();
  gate_.resetCounters();
}

}  // namespace ehc_sim
