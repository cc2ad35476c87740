#include "ehc_sim/step_scheduler.h"

#include <algorithm>
#include <cmath>
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

const char* toString(AckStream s) {
  switch (s) {
    case AckStream::State: return "state";
    case AckStream::Image: return "image";
    case AckStream::Cloud: return "cloud";
  }
  return "?";
}

AckNode AckNode::parse(const std::string& spec) {
  AckNode n;
  const auto colon = spec.find(':');
  n.name = spec.substr(0, colon);
  if (!n.name.empty() && n.name.front() == '/') n.name.erase(0, 1);
  if (n.name.empty()) throw std::invalid_argument("[StepScheduler] acknowledgement gate: empty node name in '" + spec + "'");
  if (colon == std::string::npos) return n;
  const std::string stream = spec.substr(colon + 1);
  for (const AckStream s : {AckStream::State, AckStream::Image, AckStream::Cloud})
    if (stream == toString(s)) {
      n.stream = s;
      return n;
    }
  throw std::invalid_argument("[StepScheduler] acknowledgement gate: unknown stream '" + stream + "' in '" + spec +
                              "' (state | image | cloud)");
}

std::int64_t AckGateConfig::maxLagNs() const { return static_cast<std::int64_t>(std::llround(max_lag * 1e9)); }

std::string AckGateConfig::summary() const {
  std::string s;
  for (const AckNode& n : nodes) s += " " + n.name + " (" + toString(n.stream) + ")";
  return s;
}

AckGateConfig parseAckGate(const std::vector<std::string>& specs, double max_lag_s) {
  if (!(max_lag_s >= 0.0 && max_lag_s <= 10.0)) {
    std::ostringstream os;
    os << "[StepScheduler] acknowledgement gate: max lag " << max_lag_s << " s is outside [0, 10] s";
    throw std::invalid_argument(os.str());
  }
  AckGateConfig gate;
  gate.max_lag = max_lag_s;
  for (const std::string& spec : specs) gate.nodes.push_back(AckNode::parse(spec));
  return gate;
}

StepScheduler::StepScheduler(const ehc_control::RobotConfig& robot, const FakeRobotConfig& config)
    : config_(config), gate_(robot) {
  config_.validate();
}

void StepScheduler::statePublished(double wall_s, std::int64_t stamp_ns, bool fresh) {
  if (fresh) {
    state_ns_ = stamp_ns;
    newest_ns_ = stamp_ns;
    gate_.newState(stamp_ns);
    last_fresh_publish_ = wall_s;
    recordFrame(AckStream::State, stamp_ns);
  }
  last_publish_ = wall_s;
}

std::string StepScheduler::onBaseTwist(double wall_s, double vx, double vy, double wz) {
  last_base_cmd_ = wall_s;
  return gate_.onBaseTwist(vx, vy, wz);
}

std::string StepScheduler::onArmCommand(double wall_s, std::int64_t stamp_ns,
                                        const std::vector<std::string>& names,
                                        const std::vector<double>& velocities) {
  const std::string why = gate_.onArmCommand(stamp_ns, names, velocities, lockStep());
  if (why.empty()) last_arm_cmd_ = wall_s;
  return why;
}

StepAction StepScheduler::next(double wall_s) {
  if (lockStep()) {
    if (gate_.ready()) {
      std::int64_t frame_ns = 0;
      if (heldBy(&frame_ns) >= 0) return StepAction::Wait;  // a gate node behind: never a timeout
      const bool paced = config_.max_real_time_factor > 0.0 &&
                         wall_s - last_fresh_publish_ < config_.dt / config_.max_real_time_factor;
      return paced ? StepAction::Wait : StepAction::Step;
    }
    if (wall_s - last_publish_ > config_.state_republish_period) return StepAction::RepublishState;
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
  newest_ns_ = 0;  // time restarts: an acknowledgement of a frame before the reset is from the future
  gate_.zero();
  gate_.resetCounters();
  for (auto& f : frames_ns_) f.clear();
  std::fill(acked_ns_.begin(), acked_ns_.end(), std::int64_t{-1});
}

void StepScheduler::setAckGate(const std::vector<AckNode>& nodes, std::int64_t max_lag_ns) {
  if (max_lag_ns < 0) throw std::invalid_argument("[StepScheduler] acknowledgement gate: max lag must be >= 0");
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    if (nodes[i].name.empty()) throw std::invalid_argument("[StepScheduler] acknowledgement gate: empty node name");
    for (std::size_t j = 0; j < i; ++j)
      if (nodes[j].name == nodes[i].name)
        throw std::invalid_argument("[StepScheduler] acknowledgement gate: node '" + nodes[i].name + "' listed twice");
  }
  ack_nodes_ = nodes;
  acked_ns_.assign(nodes.size(), -1);
  max_lag_ns_ = max_lag_ns;
  for (auto& f : frames_ns_) f.clear();
}

void StepScheduler::framePublished(AckStream stream, std::int64_t stamp_ns) { recordFrame(stream, stamp_ns); }

void StepScheduler::recordFrame(AckStream stream, std::int64_t stamp_ns) {
  if (ack_nodes_.empty()) return;
  auto& f = frames_ns_[static_cast<std::size_t>(stream)];
  if (!f.empty() && stamp_ns <= f.back()) f.clear();  // time restarted (reset)
  f.push_back(stamp_ns);
  newest_ns_ = stamp_ns;
}

std::string StepScheduler::onAck(const std::string& node, std::int64_t stamp_ns) {
  if (ack_nodes_.empty()) return "";  // gate off: nothing to count
  const std::string name = !node.empty() && node.front() == '/' ? node.substr(1) : node;
  const auto it = std::find_if(ack_nodes_.begin(), ack_nodes_.end(), [&](const AckNode& n) { return n.name == name; });
  if (it == ack_nodes_.end()) return "'" + name + "' is not a node of the lock-step acknowledgement gate";
  const auto k = static_cast<std::size_t>(it - ack_nodes_.begin());
  if (stamp_ns > newest_ns_ + config_.dtNs()) {
    // No frame of that stamp was published: counting it would open the gate for every frame up
    // to it (for the rest of the run, for a far-future stamp).
    std::ostringstream why;
    why << "'" << name << "' acknowledged " << 1e-9 * static_cast<double>(stamp_ns) << " s, ahead of the newest frame ("
        << 1e-9 * static_cast<double>(newest_ns_) << " s) by more than one step: ignored (" << ++future_acks_
        << " so far)";
    return why.str();
  }
  acked_ns_[k] = std::max(acked_ns_[k], stamp_ns);
  // Frames every joined node of the stream has acknowledged no longer hold anything back.
  std::int64_t all = acked_ns_[k];
  for (std::size_t i = 0; i < ack_nodes_.size(); ++i)
    if (ack_nodes_[i].stream == it->stream && acked_ns_[i] >= 0) all = std::min(all, acked_ns_[i]);
  auto& f = frames_ns_[static_cast<std::size_t>(it->stream)];
  f.erase(f.begin(), std::upper_bound(f.begin(), f.end(), all));
  return "";
}

int StepScheduler::heldBy(std::int64_t* frame_ns) const {
  if (ack_nodes_.empty()) return -1;
  // After the step sim time is state + dt: every frame older than that minus max_lag must be done.
  const std::int64_t limit = state_ns_ + config_.dtNs() - max_lag_ns_;
  for (std::size_t i = 0; i < ack_nodes_.size(); ++i) {
    if (acked_ns_[i] < 0) continue;  // not joined yet
    const auto& f = frames_ns_[static_cast<std::size_t>(ack_nodes_[i].stream)];
    const auto last = std::upper_bound(f.begin(), f.end(), limit - 1);  // stamps < limit
    if (last == f.begin()) continue;
    if (acked_ns_[i] < *(last - 1)) {
      *frame_ns = *(last - 1);
      return static_cast<int>(i);
    }
  }
  return -1;
}

std::string StepScheduler::notJoined() const {
  std::string names;
  for (std::size_t i = 0; i < ack_nodes_.size(); ++i)
    if (acked_ns_[i] < 0) names += (names.empty() ? "" : " ") + ack_nodes_[i].name;
  return names;
}

std::string StepScheduler::ackWait() const {
  std::int64_t frame_ns = 0;
  const int i = heldBy(&frame_ns);
  if (i < 0) return "";
  const AckNode& n = ack_nodes_[static_cast<std::size_t>(i)];
  std::ostringstream s;
  s << n.name << " (" << toString(n.stream) << " at " << 1e-9 * static_cast<double>(frame_ns) << " s)";
  return s.str();
}

}  // namespace ehc_sim
