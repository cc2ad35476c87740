#include "ehc_realman/water2_velocity_response.h"

#include "ehc_common/config_node.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace ehc_realman {

namespace {
constexpr double kEps = 1e-9;  ///< s: sim times are sums of dt
}

Water2ResponseParams Water2ResponseParams::commandedVelocity() {
  Water2ResponseParams p;
  p.command_latency = 0.0;
  p.linear_acceleration = std::numeric_limits<double>::infinity();
  p.angular_acceleration = std::numeric_limits<double>::infinity();
  p.time_constant = 0.0;
  p.linear_gain = 1.0;
  p.angular_gain = 1.0;
  return p;
}

void Water2ResponseParams::validate(const std::string& owner, const std::string& field_prefix) const {
  const auto requireRange = [&](const char* field, double value, double lo, double hi) {
    ehc_common::requireRange(owner, field_prefix + field, value, lo, hi);
  };
  requireRange("command_lifetime", command_lifetime, 1e-3, 10.0);
  requireRange("command_latency", command_latency, 0.0, 1.0);
  for (const auto& [name, value] : {std::pair<const char*, double>{"linear_acceleration", linear_acceleration},
                                    {"angular_acceleration", angular_acceleration}})
    if (!(value >= 1e-3))  // +inf allowed (no limit); NaN rejected
      throw std::invalid_argument("[" + owner + "] " + field_prefix + name + " must be >= 0.001 (or .inf), got " +
                                  std::to_string(value));
  requireRange("time_constant", time_constant, 0.0, 10.0);
  requireRange("linear_gain", linear_gain, 0.5, 1.5);
  requireRange("angular_gain", angular_gain, 0.5, 1.5);
}

std::string Water2ResponseParams::summary() const {
  std::ostringstream os;
  os << "latency " << command_latency << " s, hold " << command_lifetime << " s, accel "
     << linear_acceleration << " m/s^2 / " << angular_acceleration << " rad/s^2, lag "
     << time_constant << " s, gain " << linear_gain << " / " << angular_gain;
  return os.str();
}

void readWater2ResponseParams(const ehc_common::ConfigNode& n, Water2ResponseParams* p) {
  auto get = [&](const char* key, double& field) { field = n.get<double>(key, field); };
  get("command_lifetime", p->command_lifetime);
  get("command_latency", p->command_latency);
  get("linear_acceleration", p->linear_acceleration);
  get("angular_acceleration", p->angular_acceleration);
  get("time_constant", p->time_constant);
  get("linear_gain", p->linear_gain);
  get("angular_gain", p->angular_gain);
}

Water2VelocityResponse::Water2VelocityResponse(const Water2ResponseParams& params)
    : params_((params.validate("Water2VelocityResponse"), params)) {}

void Water2VelocityResponse::reset() {
  in_flight_.clear();
  held_.setZero();
  held_until_ = -1.0;
  in_force_.setZero();
  wheel_.setZero();
}

void Water2VelocityResponse::joyControlSent(double linear, double angular, double sent) {
  joyControlAt(linear, angular, sent + params_.command_latency);
}

void Water2VelocityResponse::joyControlAt(double linear, double angular, double at) {
  if (!std::isfinite(linear) || !std::isfinite(angular) || !std::isfinite(at))
    throw std::invalid_argument("[Water2VelocityResponse] joy_control velocities and time must be finite");
  if (!in_flight_.empty()) at = std::max(at, in_flight_.back().at);  // executed in order
  in_flight_.push_back({at, Eigen::Vector2d(linear, angular)});
}

Eigen::Vector2d Water2VelocityResponse::advance(double now, double dt, double deadband_linear,
                                                double deadband_angular) {
  while (!in_flight_.empty() && in_flight_.front().at <= now + kEps) {
    held_ = in_flight_.front().twist;
    held_until_ = in_flight_.front().at + params_.command_lifetime;
    in_flight_.pop_front();
  }
  in_force_ = now < held_until_ - kEps ? held_ : Eigen::Vector2d::Zero();
  const Eigen::Vector2d band(deadband_linear, deadband_angular);
  Eigen::Vector2d u = in_force_;
  if (std::abs(u[0]) < band[0] && std::abs(u[1]) < band[1]) u.setZero();  // static friction
  const Eigen::Vector2d gain(params_.linear_gain, params_.angular_gain);
  const Eigen::Vector2d accel(params_.linear_acceleration, params_.angular_acceleration);
  const double lag = params_.time_constant > 0.0 ? 1.0 - std::exp(-dt / params_.time_constant) : 1.0;
  for (int i = 0; i < 2; ++i) {
    const double target = gain[i] * u[i];
    const double max_change = accel[i] * dt;  // +inf without a limit
    const double change = std::clamp(lag * (target - wheel_[i]), -max_change, max_change);
    wheel_[i] += change;
    if (target == 0.0 && std::abs(wheel_[i]) < band[i]) wheel_[i] = 0.0;
  }
  return wheel_;
}

}  // namespace ehc_realman
