#include "ehc_realman/realman_joint_streamer.h"

#include "ehc_common/config_node.h"
#include "ehc_control/joint_state.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <set>
#include <sstream>
#include <stdexcept>

using ehc_common::requireRange;

namespace ehc_realman {

namespace {
constexpr double kDegToRad = M_PI / 180.0;

[[noreturn]] void failWith(const char* owner, const std::string& what) {
  throw std::invalid_argument(std::string("[") + owner + "] " + what);
}

/// Largest s in (0, 1] with |s * x_i| <= bound_i for all i.
double uniformScale(const Eigen::VectorXd& x, const Eigen::VectorXd& bound) {
  double s = 1.0;
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    const double a = std::abs(x[i]);
    if (a > bound[i]) s = std::min(s, bound[i] / a);
  }
  return s;
}
}  // namespace

void JointStreamerConfig::validate() const {
  const std::string o = "JointStreamerConfig";
  requireRange(o, "rate_hz", rate_hz, 1.0, 1000.0);
  requireRange(o, "max_step_deg", max_step_deg, 0.01, 10.0);
  requireRange(o, "driver_max_speed_deg", driver_max_speed_deg, 1.0, 180.0);
  requireRange(o, "speed_scale", speed_scale, 1e-3, 1.0);
  requireRange(o, "command_timeout", command_timeout, 1e-3, 5.0);
  requireRange(o, "hold_duration", hold_duration, 0.0, 60.0);
  requireRange(o, "state_timeout", state_timeout, 1e-3, 5.0);
  requireRange(o, "max_tracking_error", max_tracking_error, 1e-3, 1.0);
  requireRange(o, "limit_margin", limit_margin, 0.0, 0.5);
}

void ArmJointLimits::validate() const {
  const auto n = static_cast<Eigen::Index>(names.size());
  if (n < 1) failWith("ArmJointLimits", "no arm joints");
  if (std::set<std::string>(names.begin(), names.end()).size() != names.size())
    failWith("ArmJointLimits", "joint names must be unique");
  if (lower.size() != n || upper.size() != n || velocity.size() != n)
    failWith("ArmJointLimits", "lower/upper/velocity need one value per joint");
  if (!lower.allFinite() || !upper.allFinite() || !velocity.allFinite())
    failWith("ArmJointLimits", "limits must be finite");
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!(lower[i] < upper[i])) failWith("ArmJointLimits", "lower >= upper for " + names[i]);
    if (!(velocity[i] > 0.0)) failWith("ArmJointLimits", "velocity <= 0 for " + names[i]);
  }
}

std::string toString(StreamPhase p) {
  switch (p) {
    case StreamPhase::Idle: return "idle";
    case StreamPhase::Streaming: return "streaming";
    case StreamPhase::Holding: return "holding";
    case StreamPhase::EmergencyStopped: return "emergency_stopped";
  }
  return "unknown";
}

JointPositionStreamer::JointPositionStreamer(const JointStreamerConfig& config,
                                             const ArmJointLimits& limits)
    : config_(config), limits_(limits) {
  config_.validate();
  limits_.validate();
  lower_ = limits_.lower.array() + config_.limit_margin;
  upper_ = limits_.upper.array() - config_.limit_margin;
  for (Eigen::Index i = 0; i < lower_.size(); ++i)
    if (!(lower_[i] < upper_[i]))
      fail("limit_margin " + std::to_string(config_.limit_margin) + " leaves no range for " +
           limits_.names[static_cast<std::size_t>(i)]);
  const double driver_speed = config_.driver_max_speed_deg * kDegToRad;
  speed_limit_ = config_.speed_scale * limits_.velocity.cwiseMin(driver_speed);
  step_limit_ = (speed_limit_ / config_.rate_hz).cwiseMin(config_.max_step_deg * kDegToRad);
  const auto n = lower_.size();
  measured_ = Eigen::VectorXd::Zero(n);
  command_ = Eigen::VectorXd::Zero(n);
  last_frame_ = Eigen::VectorXd::Zero(n);
}

void JointPositionStreamer::fail(const std::string& what) const {
  throw std::invalid_argument("[JointPositionStreamer] " + what);
}

void JointPositionStreamer::setMeasured(const std::vector<std::string>& names,
                                        const std::vector<double>& positions, double now) {
  Eigen::VectorXd q;  // the one joint-state parser (ehc_control/joint_state.h)
  const std::string why =
      ehc_control::armPositionsFromJointState(limits_.names, names, positions, &q);
  if (!why.empty()) {
    ++counters_.rejected_states;
    fail(why);
  }
  measured_ = q;
  measured_time_ = now;
  has_measured_ = true;
}

void JointPositionStreamer::setVelocityCommand(const std::vector<std::string>& names,
                                               const std::vector<double>& velocities,
                                               double now) {
  const std::size_t n = limits_.names.size();
  auto reject = [&](const std::string& what) {
    ++counters_.rejected_commands;
    fail("velocity command rejected: " + what);
  };
  if (velocities.size() != n)
    reject("has " + std::to_string(velocities.size()) + " velocities, the arm has " +
           std::to_string(n) + " joints");
  Eigen::VectorXd v(static_cast<Eigen::Index>(n));
  if (names.empty()) {
    for (std::size_t j = 0; j < n; ++j) v[static_cast<Eigen::Index>(j)] = velocities[j];
  } else {
    if (names.size() != n)
      reject("has " + std::to_string(names.size()) + " names for " +
             std::to_string(velocities.size()) + " velocities");
    std::vector<bool> seen(n, false);
    for (std::size_t k = 0; k < n; ++k) {
      const auto it = std::find(limits_.names.begin(), limits_.names.end(), names[k]);
      if (it == limits_.names.end()) reject("unknown joint '" + names[k] + "'");
      const auto j = static_cast<std::size_t>(it - limits_.names.begin());
      if (seen[j]) reject("joint '" + names[k] + "' listed twice");
      seen[j] = true;
      v[static_cast<Eigen::Index>(j)] = velocities[k];
    }
  }
  if (!v.allFinite()) reject("non-finite velocity");
  command_ = v;
  command_time_ = now;
  has_command_ = true;
  ++counters_.commands;
}

void JointPositionStreamer::emergencyStop() { phase_ = StreamPhase::EmergencyStopped; }

void JointPositionStreamer::resetEmergencyStop() {
  if (phase_ == StreamPhase::EmergencyStopped) phase_ = StreamPhase::Idle;
  // A command sent before the reset must not restart the arm.
  has_command_ = false;
}

bool JointPositionStreamer::measuredFresh(double now) const {
  return has_measured_ && now - measured_time_ <= config_.state_timeout;
}

bool JointPositionStreamer::commandFresh(double now) const {
  return has_command_ && now - command_time_ <= config_.command_timeout;
}

std::optional<JointFrame> JointPositionStreamer::step(double now) {
  if (phase_ == StreamPhase::EmergencyStopped) return std::nullopt;
  const bool inputs_fresh = commandFresh(now) && measuredFresh(now);

  if (phase_ == StreamPhase::Idle) {
    if (!inputs_fresh) return std::nullopt;
    // Start from where the arm is: the first frame is the measured position (clamped into the
    // limits only as far as the step bound allows, see below).
    last_frame_ = measured_;
    phase_ = StreamPhase::Streaming;
  } else if (phase_ == StreamPhase::Streaming && !inputs_fresh) {
    phase_ = StreamPhase::Holding;
    hold_start_ = now;
    ++counters_.timeouts;
  } else if (phase_ == StreamPhase::Holding && inputs_fresh) {
    phase_ = StreamPhase::Streaming;
  }

  JointFrame frame;
  frame.phase = phase_;
  if (phase_ == StreamPhase::Holding) {
    if (now - hold_start_ > config_.hold_duration) {
      phase_ = StreamPhase::Idle;
      return std::nullopt;
    }
    frame.position = last_frame_;
    ++counters_.frames;
    return frame;
  }

  // Streaming: integrate the (speed-limited) command over one nominal period.
  const double dt = period();
  const double s = uniformScale(command_, speed_limit_);
  frame.speed_clamped = s < 1.0;
  Eigen::VectorXd target = last_frame_ + s * command_ * dt;

  // No wind-up: the set-point integrates from its own last value; the measured position only
  // shortens a commanded step that would take the set-point further than max_tracking_error from
  // it. The clamp never moves the set-point against (or beyond) the commanded step, so a
  // measured-state glitch (or an arm pushed away) holds the set-point instead of dragging it
  // after the measurement.
  const Eigen::VectorXd lo_track = measured_.array() - config_.max_tracking_error;
  const Eigen::VectorXd hi_track = measured_.array() + config_.max_tracking_error;
  const Eigen::VectorXd tracked = target.cwiseMax(lo_track)
                                      .cwiseMin(hi_track)
                                      .cwiseMax(last_frame_.cwiseMin(target))
                                      .cwiseMin(last_frame_.cwiseMax(target));
  frame.tracking_clamped = (tracked - target).cwiseAbs().maxCoeff() > 0.0;
  target = tracked;

  // Joint limits: never move further outside than the previous frame already was.
  const Eigen::VectorXd lo = lower_.cwiseMin(last_frame_);
  const Eigen::VectorXd hi = upper_.cwiseMax(last_frame_);
  const Eigen::VectorXd limited = target.cwiseMax(lo).cwiseMin(hi);
  frame.limit_clamped = (limited - target).cwiseAbs().maxCoeff() > 0.0;
  target = limited;

  // Per-frame step bound (uniform scaling keeps the direction; stays inside [lo, hi]).
  const Eigen::VectorXd delta = target - last_frame_;
  const double ds = uniformScale(delta, step_limit_);
  frame.step_clamped = ds < 1.0;
  last_frame_ = last_frame_ + ds * delta;

  frame.position = last_frame_;
  ++counters_.frames;
  counters_.speed_clamped += frame.speed_clamped;
  counters_.tracking_clamped += frame.tracking_clamped;
  counters_.limit_clamped += frame.limit_clamped;
  counters_.step_clamped += frame.step_clamped;
  return frame;
}

std::string JointPositionStreamer::summary() const {
  std::ostringstream os;
  os << "JointPositionStreamer: " << config_.rate_hz << " Hz, command timeout "
     << config_.command_timeout << " s, hold " << config_.hold_duration << " s, state timeout "
     << config_.state_timeout << " s, tracking error <= " << config_.max_tracking_error
     << " rad, limit margin " << config_.limit_margin << " rad\n";
  for (std::size_t j = 0; j < limits_.names.size(); ++j) {
    const auto i = static_cast<Eigen::Index>(j);
    os << "  " << limits_.names[j] << ": [" << lower_[i] << ", " << upper_[i] << "] rad, |qd| <= "
       << speed_limit_[i] << " rad/s, step <= " << step_limit_[i] << " rad/frame\n";
  }
  return os.str();
}

// ------------------------------------------------------------------ gripper
void GripperConfig::validate() const {
  const std::string o = "GripperConfig";
  requireRange(o, "max_opening", max_opening, 1e-3, 1.0);
  requireRange(o, "open_position", open_position, 1, 1000);
  requireRange(o, "close_position", close_position, 1, 1000);
  requireRange(o, "pick_speed", pick_speed, 1, 1000);
  requireRange(o, "pick_force", pick_force, 1, 1000);
}

GripperRequest gripperRequestFromCommand(const std::string& command, const GripperConfig& config) {
  std::string c;
  for (char ch : command)
    if (!std::isspace(static_cast<unsigned char>(ch)))
      c += static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  GripperRequest r;
  if (c == "open") {
    r.kind = GripperRequest::Kind::Set;
    r.position = config.open_position;
  } else if (c == "close") {
    r.kind = GripperRequest::Kind::Set;
    r.position = config.close_position;
  } else if (c == "pick") {
    r.kind = GripperRequest::Kind::Pick;
    r.speed = config.pick_speed;
    r.force = config.pick_force;
  } else {
    failWith("GripperCommand", "unknown gripper command '" + command +
                                   "' (expected open, close or pick)");
  }
  return r;
}

GripperRequest gripperRequestFromWidth(double width_m, const GripperConfig& config) {
  if (!std::isfinite(width_m)) failWith("GripperCommand", "gripper width must be finite");
  const double p = std::round(1000.0 * width_m / config.max_opening);
  GripperRequest r;
  r.kind = GripperRequest::Kind::Set;
  r.position = static_cast<std::uint16_t>(std::clamp(p, 1.0, 1000.0));
  return r;
}

}  // namespace ehc_realman
