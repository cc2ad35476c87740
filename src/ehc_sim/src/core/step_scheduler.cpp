#include "ehc_sim/step_scheduler.h"

#include <algorithm>
#include <sstream>
#include <stdexcept>

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
    state_ns_ = stamp_ns;
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
      std::int64_t image_ns = 0;
      if (heldBy(&image_ns) >= 0) return StepAction::Wait;  // perception behind: never a timeout
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
  images_ns_.clear();
  std::fill(acked_ns_.begin(), acked_ns_.end(), std::int64_t{-1});
}

void StepScheduler::setPerceptionGate(const std::vector<std::string>& nodes, std::int64_t max_lag_ns) {
  if (max_lag_ns < 0) throw std::invalid_argument("[StepScheduler] perception max lag must be >= 0");
  for (const auto& n : nodes)
    if (n.empty()) throw std::invalid_argument("[StepScheduler] empty perception node name");
  perception_nodes_ = nodes;
  acked_ns_.assign(nodes.size(), -1);
  max_lag_ns_ = max_lag_ns;
  images_ns_.clear();
}

void StepScheduler::imagePublished(std::int64_t stamp_ns) {
  if (perception_nodes_.empty()) return;
  if (!images_ns_.empty() && stamp_ns <= images_ns_.back()) images_ns_.clear();  // time restarted (reset)
  images_ns_.push_back(stamp_ns);
}

std::string StepScheduler::onPerceptionAck(const std::string& node, std::int64_t stamp_ns) {
  if (perception_nodes_.empty()) return "";  // gate off: nothing to count
  const std::string name = !node.empty() && node.front() == '/' ? node.substr(1) : node;
  const auto it = std::find(perception_nodes_.begin(), perception_nodes_.end(), name);
  if (it == perception_nodes_.end()) return "'" + name + "' is not a perception node of the lock-step gate";
  auto& a = acked_ns_[static_cast<std::size_t>(it - perception_nodes_.begin())];
  a = std::max(a, stamp_ns);
  // Images every node has acknowledged no longer hold anything back.
  std::int64_t all = a;
  for (const std::int64_t x : acked_ns_)
    if (x >= 0) all = std::min(all, x);
  images_ns_.erase(images_ns_.begin(), std::upper_bound(images_ns_.begin(), images_ns_.end(), all));
  return "";
}

int StepScheduler::heldBy(std::int64_t* image_ns) const {
  if (perception_nodes_.empty() || images_ns_.empty()) return -1;
  // After the step sim time is state + dt: every image older than that minus max_lag must be done.
  const std::int64_t limit = state_ns_ + config_.dtNs() - max_lag_ns_;
  const auto last = std::upper_bound(images_ns_.begin(), images_ns_.end(), limit - 1);  // stamps < limit
  if (last == images_ns_.begin()) return -1;
  *image_ns = *(last - 1);
  for (std::size_t i = 0; i < acked_ns_.size(); ++i)
    if (acked_ns_[i] >= 0 && acked_ns_[i] < *image_ns) return static_cast<int>(i);  // -1: not joined yet
  return -1;
}

std::string StepScheduler::perceptionWait() const {
  std::int64_t image_ns = 0;
  const int i = heldBy(&image_ns);
  if (i < 0) return "";
  std::ostringstream s;
  s << perception_nodes_[static_cast<std::size_t>(i)] << " (image at " << 1e-9 * static_cast<double>(image_ns) << " s)";
  return s.str();
}

}  // namespace ehc_sim
