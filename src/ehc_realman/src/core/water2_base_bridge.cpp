#include "ehc_realman/water2_base_bridge.h"

#include "ehc_common/config_node.h"
#include "ehc_control/robot_config.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <thread>

using ehc_common::requireRange;

namespace ehc_realman {

namespace {
const char* kOwner = "Water2BridgeConfig";
constexpr double kInf = std::numeric_limits<double>::infinity();

double steadySeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

/// Exact unicycle motion with constant (v, w) for dt seconds.
void integrateUnicycle(double& x, double& y, double& theta, double v, double w, double dt) {
  if (dt <= 0.0) return;
  if (std::abs(w) < 1e-9) {
    x += v * dt * std::cos(theta);
    y += v * dt * std::sin(theta);
  } else {
    const double th1 = theta + w * dt;
    x += v / w * (std::sin(th1) - std::sin(theta));
    y += -v / w * (std::cos(th1) - std::cos(theta));
    theta = th1;
  }
  theta = std::atan2(std::sin(theta), std::cos(theta));
}
}  // namespace

// ------------------------------------------------------------------ config
void Water2BridgeConfig::validate() const {
  if (host.empty()) throw std::invalid_argument(std::string("[") + kOwner + "] host is empty");
  requireRange(kOwner, "port", port, 1, 65535);
  requireRange(kOwner, "connect_timeout", connect_timeout, 0.01, 10.0);
  requireRange(kOwner, "max_linear_velocity", max_linear_velocity, 0.0, 0.5);
  requireRange(kOwner, "max_angular_velocity", max_angular_velocity, 0.0, 1.0);
  requireRange(kOwner, "resend_rate_hz", resend_rate_hz, 10.0, 100.0);
  requireRange(kOwner, "command_timeout", command_timeout, 0.01, 0.5);
  requireRange(kOwner, "stop_repeat_duration", stop_repeat_duration, 0.0, 10.0);
  requireRange(kOwner, "status_period", status_period, 0.05, 10.0);
  requireRange(kOwner, "status_timeout", status_timeout, status_period, 60.0);
  requireRange(kOwner, "max_extrapolation", max_extrapolation, 0.0, 5.0);
  base_response.validate(kOwner, "base_response.");
  requireRange(kOwner, "reply_timeout", reply_timeout, status_period, 60.0);
  requireRange(kOwner, "backoff_initial", backoff_initial, 0.01, 60.0);
  requireRange(kOwner, "backoff_max", backoff_max, backoff_initial, 600.0);
  requireRange(kOwner, "max_object_bytes", max_object_bytes, 256, 16 * 1024 * 1024);
  requireRange(kOwner, "odom_rate_hz", odom_rate_hz, 1.0, 1000.0);
  requireRange(kOwner, "status_rate_hz", status_rate_hz, 0.1, 100.0);
  if (odom_frame.empty() || base_frame.empty() || odom_frame == base_frame)
    throw std::invalid_argument(std::string("[") + kOwner +
                                "] odom_frame and base_frame must be set and differ");
}

std::string Water2BridgeConfig::summary() const {
  std::ostringstream os;
  os << "water2_base_bridge (" << (source_file.empty() ? "built in code" : source_file) << ")\n"
     << "  base: " << host << ":" << port << ", connect timeout " << connect_timeout
     << " s, back-off " << backoff_initial << ".." << backoff_max << " s, reply timeout "
     << reply_timeout << " s\n"
     << "  command: |v| <= " << max_linear_velocity << " m/s, |w| <= " << max_angular_velocity
     << " rad/s" << (robot_file.empty() ? "" : " (tightened by " + robot_file + ")")
     << ", resend " << resend_rate_hz << " Hz, timeout " << command_timeout << " s, zero for "
     << stop_repeat_duration << " s after a timeout\n"
     << "  status: every " << status_period << " s, stale after " << status_timeout
     << " s, dead reckoning <= " << max_extrapolation << " s\n"
     << "  base response (dead reckoning): " << base_response.summary() << "\n"
     << "  odometry: " << odom_frame << " -> " << base_frame << " at " << odom_rate_hz << " Hz\n";
  return os.str();
}

Water2BridgeConfig loadWater2BridgeConfig(const std::string& path) {
  const auto root = ehc_common::ConfigNode::loadFile(path, kOwner);
  const auto b = root.child("water2_base_bridge");
  Water2BridgeConfig c;
  c.source_file = path;
  c.host = b.get<std::string>("host", c.host);
  c.port = b.get<int>("port", c.port);
  c.connect_timeout = b.get<double>("connect_timeout", c.connect_timeout);
  c.command_terminator = b.get<std::string>("command_terminator", c.command_terminator);
  c.max_linear_velocity = b.get<double>("max_linear_velocity", c.max_linear_velocity);
  c.max_angular_velocity = b.get<double>("max_angular_velocity", c.max_angular_velocity);
  c.resend_rate_hz = b.get<double>("resend_rate_hz", c.resend_rate_hz);
  c.command_timeout = b.get<double>("command_timeout", c.command_timeout);
  c.stop_repeat_duration = b.get<double>("stop_repeat_duration", c.stop_repeat_duration);
  c.status_period = b.get<double>("status_period", c.status_period);
  c.status_timeout = b.get<double>("status_timeout", c.status_timeout);
  c.max_extrapolation = b.get<double>("max_extrapolation", c.max_extrapolation);
  readWater2ResponseParams(b.childOrEmpty("base_response"), &c.base_response);
  c.reply_timeout = b.get<double>("reply_timeout", c.reply_timeout);
  c.backoff_initial = b.get<double>("backoff_initial", c.backoff_initial);
  c.backoff_max = b.get<double>("backoff_max", c.backoff_max);
  c.max_object_bytes = b.get<int>("max_object_bytes", c.max_object_bytes);
  c.odom_rate_hz = b.get<double>("odom_rate_hz", c.odom_rate_hz);
  c.status_rate_hz = b.get<double>("status_rate_hz", c.status_rate_hz);
  c.odom_frame = b.get<std::string>("odom_frame", c.odom_frame);
  c.base_frame = b.get<std::string>("base_frame", c.base_frame);
  if (b.has("robot")) {
    c.robot_file = b.requirePath("robot");
    const auto robot = ehc_control::loadRobotConfig(c.robot_file);
    c.max_linear_velocity = std::min(c.max_linear_velocity, robot.max_linear_velocity);
    c.max_angular_velocity = std::min(c.max_angular_velocity, robot.max_angular_velocity);
  }
  root.rejectUnknownKeys();
  root.validate(c);  // errors name the file
  return c;
}

// ------------------------------------------------------------------ watchdog
BaseCommandWatchdog::BaseCommandWatchdog(double max_linear, double max_angular,
                                         double command_timeout, double resend_period,
                                         double stop_repeat_duration)
    : max_linear_(max_linear),
      max_angular_(max_angular),
      command_timeout_(command_timeout),
      resend_period_(resend_period),
      stop_repeat_duration_(stop_repeat_duration) {}

bool BaseCommandWatchdog::setCommand(double linear, double angular, double now) {
  if (!std::isfinite(linear) || !std::isfinite(angular))
    throw std::invalid_argument("[BaseCommandWatchdog] command must be finite");
  double s = 1.0;
  if (std::abs(linear) > max_linear_) s = std::min(s, max_linear_ / std::abs(linear));
  if (std::abs(angular) > max_angular_) s = std::min(s, max_angular_ / std::abs(angular));
  command_.linear = std::clamp(s * linear, -max_linear_, max_linear_);
  command_.angular = std::clamp(s * angular, -max_angular_, max_angular_);
  command_time_ = now;
  return s < 1.0;
}

bool BaseCommandWatchdog::commandFresh(double now) const {
  return now - command_time_ <= command_timeout_;
}

void BaseCommandWatchdog::requestZero() { force_zero_ = true; }

std::optional<BaseTwist> BaseCommandWatchdog::due(double now) {
  const bool fresh = commandFresh(now);
  const bool moving = last_sent_nonzero_;
  if (force_zero_ || (!fresh && moving)) {
    // Reconnected, or commands just stopped: zero at once, not at the next resend slot.
    force_zero_ = false;
    last_send_time_ = now;
    last_sent_nonzero_ = false;
    return BaseTwist{};
  }
  if (now - last_send_time_ < resend_period_ * 0.999) return std::nullopt;
  if (fresh) {
    last_send_time_ = now;
    last_sent_nonzero_ = command_.linear != 0.0 || command_.angular != 0.0;
    return command_;
  }
  if (now - (command_time_ + command_timeout_) <= stop_repeat_duration_) {
    last_send_time_ = now;
    return BaseTwist{};
  }
  return std::nullopt;
}

double BaseCommandWatchdog::timeUntilDue(double now) const {
  if (force_zero_) return 0.0;
  const bool fresh = commandFresh(now);
  if (!fresh && last_sent_nonzero_) return 0.0;
  const double next_slot = std::max(0.0, last_send_time_ + resend_period_ - now);
  if (fresh) return std::min(next_slot, std::max(0.0, command_time_ + command_timeout_ - now));
  if (now - (command_time_ + command_timeout_) <= stop_repeat_duration_) return next_slot;
  return kInf;
}

// ------------------------------------------------------------------ odometry
OdometryEstimator::OdometryEstimator(double status_timeout, double max_extrapolation,
                                     const Water2ResponseParams& response)
    : status_timeout_(status_timeout), max_extrapolation_(max_extrapolation), model_(response) {}

void OdometryEstimator::advanceModelTo(double t) {
  if (model_.inFlight() == 0 && t - model_time_ > kAtRestAfter) {  // long idle: at rest
    model_.reset();
    model_time_ = t;
  }
  while (model_time_ < t) {
    const double dt = std::min(kStep, t - model_time_);
    model_.advance(model_time_, dt);
    model_time_ = dt < kStep ? t : model_time_ + dt;
  }
}

bool OdometryEstimator::onStatus(const Water2Pose& pose, double valid_time) {
  if (status_pose_ && valid_time < status_time_) return false;  // an older pose than the one held
  if (!std::isfinite(model_time_)) model_time_ = valid_time;     // nothing sent yet: at rest
  if (valid_time < model_time_) return false;  // before the predicted velocity's history: stale
  advanceModelTo(valid_time);
  status_pose_ = pose;
  status_time_ = valid_time;
  return true;
}

void OdometryEstimator::onTwistSent(const BaseTwist& twist, double now) {
  now = std::max(now, last_sent_);  // monotonic
  last_sent_ = now;
  if (!std::isfinite(model_time_)) model_time_ = now;  // at rest until now
  model_.joyControlSent(twist.linear, twist.angular, now);
  // Without statuses, forget what no fresh status can need (bounds the queue).
  if (model_time_ < now - status_timeout_) advanceModelTo(now - status_timeout_);
}

double OdometryEstimator::statusAge(double now) const {
  return status_pose_ ? now - status_time_ : kInf;
}

double BaseOdometry::positionVariance() const { return 1e-4 + std::pow(0.5 * status_age, 2); }
double BaseOdometry::yawVariance() const { return 1e-4 + std::pow(1.0 * status_age, 2); }

std::optional<BaseOdometry> OdometryEstimator::estimate(double now) const {
  if (!status_pose_ || now - status_time_ > status_timeout_ || model_time_ > status_time_) return std::nullopt;
  BaseOdometry o;
  o.x = status_pose_->x;
  o.y = status_pose_->y;
  o.theta = status_pose_->theta;
  // The velocity loop from the status on, on a copy: (v, w) over each step of at most kStep.
  Water2VelocityResponse m = model_;
  Eigen::Vector2d velocity = m.wheelVelocity();
  const double horizon = std::min(now, status_time_ + max_extrapolation_);
  for (double t = status_time_; t < horizon;) {
    const double dt = std::min(kStep, horizon - t);
    velocity = m.advance(t, dt);
    integrateUnicycle(o.x, o.y, o.theta, velocity[0], velocity[1], dt);
    t = dt < kStep ? horizon : t + dt;
  }
  o.linear = velocity[0];
  o.angular = velocity[1];
  o.status_age = now - status_time_;
  return o;
}

// ------------------------------------------------------------------ bridge
namespace {
Water2ClientConfig clientConfig(const Water2BridgeConfig& c) {
  Water2ClientConfig cc;
  cc.host = c.host;
  cc.port = c.port;
  cc.connect_timeout = c.connect_timeout;
  cc.terminator = c.command_terminator;
  cc.max_object_bytes = static_cast<std::size_t>(c.max_object_bytes);
  return cc;
}
}  // namespace

Water2BaseBridge::Water2BaseBridge(const Water2BridgeConfig& config, Clock clock)
    : config_((config.validate(), config)),
      clock_(clock ? std::move(clock) : Clock(steadySeconds)),
      client_(clientConfig(config_)),
      watchdog_(config_.max_linear_velocity, config_.max_angular_velocity,
                config_.command_timeout, 1.0 / config_.resend_rate_hz,
                config_.stop_repeat_duration),
      estimator_(config_.status_timeout, config_.max_extrapolation, config_.base_response) {
  counters_.message = "not connected yet";
}

void Water2BaseBridge::setCommand(double linear, double angular) {
  const double t = clock_();
  std::lock_guard<std::mutex> lock(mutex_);
  try {
    if (watchdog_.setCommand(linear, angular, t)) ++counters_.clamped_commands;
    ++counters_.commands;
  } catch (const std::invalid_argument&) {
    ++counters_.rejected_commands;
    throw;
  }
}

void Water2BaseBridge::dropConnection(const std::string& why, double now) {
  ++counters_.connection_losses;  // only called for an established connection
  client_.close();
  status_sent_times_.clear();
  counters_.last_error = why;
  backoff_ = config_.backoff_initial;
  next_connect_time_ = now + backoff_;
}

void Water2BaseBridge::handleReply(const std::string& json, double now) {
  Water2Reply reply;
  try {
    reply = parseWater2Reply(json);
  } catch (const std::exception& e) {
    ++counters_.malformed_replies;
    counters_.last_error = e.what();
    return;
  }
  ++counters_.replies;
  last_reply_time_ = now;
  if (reply.type == "response" && !reply.ok()) {
    ++counters_.error_replies;
    counters_.last_error = "[Water2BaseBridge] " + reply.command + " answered '" + reply.status +
                           "': " + reply.error_message;
  }
  // The pose is valid when its request reached the base, i.e. not before the request was sent
  // (replies come in request order on the one connection); not when the reply was read.
  // Requests older than status_timeout lost their reply (a malformed one): forgotten, so one
  // lost reply cannot shift every later pose to an earlier request.
  double valid_time = now;
  while (!status_sent_times_.empty() && status_sent_times_.front() < now - config_.status_timeout)
    status_sent_times_.pop_front();
  if (reply.command == robotStatusRequest() && !status_sent_times_.empty()) {
    valid_time = std::min(now, status_sent_times_.front());
    status_sent_times_.pop_front();
  }
  if (reply.pose) estimator_.onStatus(*reply.pose, valid_time);
}

void Water2BaseBridge::spinOnce(double max_wait) {
  max_wait = std::max(0.0, max_wait);
  double now = clock_();
  if (!client_.isConnected()) {
    double wait = 0.0;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      wait = next_connect_time_ - now;
    }
    if (wait > 0.0) {
      std::this_thread::sleep_for(std::chrono::duration<double>(std::min(wait, max_wait)));
      return;
    }
    try {
      client_.connect();  // bounded by connect_timeout; no lock held
      std::lock_guard<std::mutex> lock(mutex_);
      now = clock_();
      ++counters_.connects;
      backoff_ = 0.0;
      watchdog_.requestZero();  // never resume motion with a command from before the loss
      next_status_time_ = now;
      last_reply_time_ = now;
      status_sent_times_.clear();
    } catch (const std::exception& e) {
      std::lock_guard<std::mutex> lock(mutex_);
      now = clock_();
      ++counters_.failed_connects;
      counters_.last_error = e.what();
      backoff_ = backoff_ <= 0.0 ? config_.backoff_initial
                                 : std::min(2.0 * backoff_, config_.backoff_max);
      next_connect_time_ = now + backoff_;
    }
    return;
  }

  std::optional<BaseTwist> twist;
  bool want_status = false;
  double wait = max_wait;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (now - last_reply_time_ > config_.reply_timeout) {
      std::ostringstream os;
      os << "[Water2BaseBridge] no valid reply for " << now - last_reply_time_ << " s";
      dropConnection(os.str(), now);
      return;
    }
    twist = watchdog_.due(now);
    if (now >= next_status_time_) {
      want_status = true;
      next_status_time_ = now + config_.status_period;
    }
  }
  try {
    if (twist) client_.send(joyControlRequest(twist->linear, twist->angular));
    const double status_sent = clock_();
    if (want_status) client_.send(robotStatusRequest());
    {
      std::lock_guard<std::mutex> lock(mutex_);
      const double t = clock_();
      if (want_status) status_sent_times_.push_back(status_sent);
      if (twist) {
        ++counters_.joy_requests;
        estimator_.onTwistSent(*twist, t);
      }
      if (want_status) ++counters_.status_requests;
      wait = std::min({max_wait, watchdog_.timeUntilDue(t), std::max(0.0, next_status_time_ - t)});
    }
    const std::vector<std::string> replies = client_.receive(wait);
    std::lock_guard<std::mutex> lock(mutex_);
    const double t = clock_();
    for (const auto& r : replies) handleReply(r, t);
  } catch (const std::exception& e) {
    std::lock_guard<std::mutex> lock(mutex_);
    dropConnection(e.what(), clock_());
  }
}

std::optional<BaseOdometry> Water2BaseBridge::odometry() const {
  const double t = clock_();
  std::lock_guard<std::mutex> lock(mutex_);
  return estimator_.estimate(t);
}

Water2BridgeStatus Water2BaseBridge::status() const {
  const double t = clock_();
  std::lock_guard<std::mutex> lock(mutex_);
  Water2BridgeStatus s = counters_;
  s.connected = client_.isConnected();
  s.status_age = estimator_.statusAge(t);
  s.status_fresh = s.status_age <= config_.status_timeout;
  std::ostringstream os;
  if (!s.connected) {
    s.level = Water2BridgeStatus::Level::Error;
    os << "disconnected from " << config_.host << ":" << config_.port << ", reconnecting";
    if (!s.last_error.empty()) os << " (last error: " << s.last_error << ")";
  } else if (!s.status_fresh) {
    s.level = Water2BridgeStatus::Level::Warn;
    os << "connected, robot_status stale (age " << s.status_age << " s): odometry withheld";
  } else {
    s.level = Water2BridgeStatus::Level::Ok;
    os << "connected, odometry fresh";
  }
  s.message = os.str();
  return s;
}

}  // namespace ehc_realman
