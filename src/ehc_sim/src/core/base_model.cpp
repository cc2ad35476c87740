#include "ehc_sim/base_model.h"

#include "ehc_common/config_node.h"
#include "ehc_common/enum_names.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

using ehc_common::requireRange;

namespace ehc_sim {

using ehc_common::ConfigNode;

namespace {
constexpr ehc_common::EnumNames<BaseModelType, 2> kBaseModelNames = {
    {{BaseModelType::Ideal, "ideal"}, {BaseModelType::Water2, "water2"}}};
constexpr double kEps = 1e-9;  ///< s: sim times are sums of dt

const ehc_realman::Water2BridgeConfig& bridgeDefaults() {
  static const ehc_realman::Water2BridgeConfig c;
  return c;
}

/// One step of a first-order Gauss-Markov process: x decays over `dt` with correlation time `tau`
/// and `noise` (a unit normal draw) keeps its stationary deviation at `sigma`.
double gaussMarkovStep(double x, double dt, double tau, double sigma, double noise) {
  const double a = std::exp(-dt / tau);
  return a * x + std::sqrt(1.0 - a * a) * sigma * noise;
}
}  // namespace

std::string toString(BaseModelType type) { return ehc_common::enumName(kBaseModelNames, type, "BaseModel"); }

BaseModelType baseModelTypeFromString(const std::string& name) {
  return ehc_common::enumValue(kBaseModelNames, name, "BaseModel", "base model");
}

// ------------------------------------------------------------------ parameters
void Water2BaseParams::validate() const {
  const char* o = "Water2BaseParams";
  requireRange(o, "max_linear_velocity", max_linear_velocity, 1e-3, 0.5);
  requireRange(o, "max_angular_velocity", max_angular_velocity, 1e-3, 1.0);
  requireRange(o, "resend_rate", resend_rate, 10.0, 1000.0);  // >= 10 Hz: 0.5 s hold
  requireRange(o, "bridge_command_timeout", bridge_command_timeout, 1e-3, 10.0);
  requireRange(o, "status_period", status_period, 1e-3, 1.0);
  requireRange(o, "max_extrapolation", max_extrapolation, 0.0, 10.0);
  response.validate(o);
  if (bridge_response) bridge_response->validate(o, "bridge_response.");
  requireRange(o, "status_latency", status_latency, 0.0, 1.0);
  requireRange(o, "localisation_position_sigma", localisation_position_sigma, 0.0, 1.0);
  requireRange(o, "localisation_heading_sigma", localisation_heading_sigma, 0.0, 1.0);
  requireRange(o, "localisation_correlation_time", localisation_correlation_time, 1e-3, 1e6);
  if (status_period + status_latency >= bridgeDefaults().status_timeout)
    throw std::invalid_argument("[Water2BaseParams] status_period + status_latency must be below the "
                                "bridge's status_timeout (" +
                                std::to_string(bridgeDefaults().status_timeout) + " s), or /odom goes stale");
}

std::string Water2BaseParams::summary() const {
  std::ostringstream os;
  os << "water2 (bridge: |v| <= " << max_linear_velocity << " m/s, |w| <= " << max_angular_velocity
     << " rad/s, resend " << resend_rate << " Hz, zero after " << bridge_command_timeout
     << " s; base: " << response.summary()
     << (bridge_response ? "; the bridge assumes: " + bridge_response->summary() : std::string())
     << "; status every "
     << status_period << " s + " << status_latency << " s, extrapolation <= " << max_extrapolation
     << " s, localisation sigma " << localisation_position_sigma << " m / "
     << localisation_heading_sigma << " rad over " << localisation_correlation_time << " s)";
  return os.str();
}

std::string BaseModelConfig::summary() const {
  return (type == BaseModelType::Ideal ? std::string("ideal") : water2.summary()) +
         (imprecision.enabled() ? ", base imprecision " + imprecision.summary() : std::string());
}

Water2BaseParams loadWater2BaseParams(const ehc_common::ConfigNode& n) {
  Water2BaseParams p;
  auto get = [&](const char* key, double& field) { field = n.get<double>(key, field); };
  get("max_linear_velocity", p.max_linear_velocity);
  get("max_angular_velocity", p.max_angular_velocity);
  get("resend_rate", p.resend_rate);
  get("bridge_command_timeout", p.bridge_command_timeout);
  get("status_period", p.status_period);
  get("max_extrapolation", p.max_extrapolation);
  ehc_realman::readWater2ResponseParams(n, &p.response);
  if (n.has("bridge_response")) {
    p.bridge_response = p.response;  // the keys given change the base's values
    ehc_realman::readWater2ResponseParams(n.child("bridge_response"), &*p.bridge_response);
  }
  get("status_latency", p.status_latency);
  get("localisation_position_sigma", p.localisation_position_sigma);
  get("localisation_heading_sigma", p.localisation_heading_sigma);
  get("localisation_correlation_time", p.localisation_correlation_time);
  n.rejectUnknownKeys();
  n.validate(p);
  return p;
}

// ------------------------------------------------------------------ base imprecision
BaseImprecisionParams BaseImprecisionParams::levelled() const {
  BaseImprecisionParams e = *this;
  for (double* f : {&e.scale_error, &e.track_error, &e.curvature_error, &e.slip_linear, &e.slip_angular,
                    &e.min_linear_speed, &e.min_angular_speed, &e.command_latency, &e.localisation_period,
                    &e.localisation_position_sigma, &e.localisation_heading_sigma})
    *f *= level;
  return e;
}

void BaseImprecisionParams::validate() const {
  const char* o = "BaseImprecisionParams";
  requireRange(o, "level", level, 0.0, 100.0);
  requireRange(o, "scale_error", scale_error, 0.0, 0.5);
  requireRange(o, "track_error", track_error, 0.0, 0.5);
  requireRange(o, "curvature_error", curvature_error, 0.0, 1.0);
  requireRange(o, "slip_linear", slip_linear, 0.0, 1.0);
  requireRange(o, "slip_angular", slip_angular, 0.0, 1.0);
  requireRange(o, "slip_correlation_time", slip_correlation_time, 1e-3, 1e3);
  requireRange(o, "min_linear_speed", min_linear_speed, 0.0, 0.5);
  requireRange(o, "min_angular_speed", min_angular_speed, 0.0, 0.5);
  requireRange(o, "command_latency", command_latency, 0.0, 1.0);
  requireRange(o, "localisation_period", localisation_period, 0.0, 100.0);
  requireRange(o, "localisation_position_sigma", localisation_position_sigma, 0.0, 1.0);
  requireRange(o, "localisation_heading_sigma", localisation_heading_sigma, 0.0, 1.0);
}

std::string BaseImprecisionParams::summary() const {
  if (!enabled()) return "off (level 0)";
  const BaseImprecisionParams e = levelled();
  std::ostringstream os;
  os << "level " << level << " (per-run sigma: scale " << e.scale_error << ", track " << e.track_error
     << ", curvature " << e.curvature_error << " rad/m; slip sigma " << e.slip_linear << " / " << e.slip_angular
     << " over " << e.slip_correlation_time << " s; min speed " << e.min_linear_speed << " m/s / "
     << e.min_angular_speed << " rad/s; latency " << e.command_latency << " s; localisation ";
  if (e.localisation_period > 0.0)
    os << "every " << e.localisation_period << " s, sigma " << e.localisation_position_sigma << " m / "
       << e.localisation_heading_sigma << " rad)";
  else
    os << "none)";
  return os.str();
}

BaseImprecisionParams loadBaseImprecisionParams(const ConfigNode& n) {
  BaseImprecisionParams p;
  auto get = [&](const char* key, double& field) { field = n.get<double>(key, field); };
  get("level", p.level);
  get("scale_error", p.scale_error);
  get("track_error", p.track_error);
  get("curvature_error", p.curvature_error);
  get("slip_linear", p.slip_linear);
  get("slip_angular", p.slip_angular);
  get("slip_correlation_time", p.slip_correlation_time);
  get("min_linear_speed", p.min_linear_speed);
  get("min_angular_speed", p.min_angular_speed);
  get("command_latency", p.command_latency);
  get("localisation_period", p.localisation_period);
  get("localisation_position_sigma", p.localisation_position_sigma);
  get("localisation_heading_sigma", p.localisation_heading_sigma);
  n.rejectUnknownKeys();
  n.validate(p);
  return p;
}

Eigen::Vector3d integrateBaseTwist(const Eigen::Vector3d& pose, double vx, double vy, double wz, double dt) {
  const double th = wz * dt;
  double dx, dy;
  if (std::abs(th) < 1e-9) {
    dx = vx * dt - 0.5 * vy * th * dt;
    dy = vy * dt + 0.5 * vx * th * dt;
  } else {
    const double s = std::sin(th) / wz, c = (1.0 - std::cos(th)) / wz;
    dx = s * vx - c * vy;
    dy = c * vx + s * vy;
  }
  Eigen::Vector3d p = pose;
  const double cy = std::cos(pose.z()), sy = std::sin(pose.z());
  p.x() += cy * dx - sy * dy;
  p.y() += sy * dx + cy * dy;
  p.z() = std::remainder(pose.z() + th, 2.0 * M_PI);
  return p;
}

BaseImprecision::BaseImprecision(const BaseImprecisionParams& params)
    : params_((params.validate(), params)), eff_(params.levelled()) {
  if (!params_.enabled()) throw std::invalid_argument("[BaseImprecision] level must be > 0 (0 = off: no model)");
  reset(Eigen::Vector3d::Zero(), 0);
}

void BaseImprecision::reset(const Eigen::Vector3d& pose, unsigned seed) {
  // A stream of its own, from the run's seed: the actuation noise's stream is the same at every level.
  std::seed_seq seq{seed, 0x62617365u /* "base" */};
  rng_.seed(seq);
  gauss_.reset();
  scale_ = eff_.scale_error * gauss_(rng_);
  track_ = eff_.track_error * gauss_(rng_);
  curvature_ = eff_.curvature_error * gauss_(rng_);
  commands_.clear();
  in_force_.resize(0);
  slip_.setZero();
  odometry_ = pose;
  odometry_twist_.setZero();
  next_fix_ = eff_.localisation_period;
  fixes_ = 0;
}

Eigen::VectorXd BaseImprecision::delayCommand(const Eigen::VectorXd& base_command, double now) {
  if (in_force_.size() != base_command.size()) in_force_ = Eigen::VectorXd::Zero(base_command.size());
  commands_.emplace_back(now + eff_.command_latency, base_command);
  while (!commands_.empty() && commands_.front().first <= now + kEps) {
    in_force_ = commands_.front().second;
    commands_.pop_front();
  }
  return in_force_;
}

double BaseImprecision::deadbandLinear(double actuation_deadband) const {
  return std::max(actuation_deadband, eff_.min_linear_speed);
}

double BaseImprecision::deadbandAngular(double actuation_deadband) const {
  return std::max(actuation_deadband, eff_.min_angular_speed);
}

Eigen::Vector3d BaseImprecision::trueTwist(const Eigen::Vector3d& wheel_twist, double dt) {
  // Slip: first-order Gauss-Markov per component, stationary sigma, one update per step.
  slip_[0] = gaussMarkovStep(slip_[0], dt, eff_.slip_correlation_time, eff_.slip_linear, gauss_(rng_));
  slip_[1] = gaussMarkovStep(slip_[1], dt, eff_.slip_correlation_time, eff_.slip_angular, gauss_(rng_));
  odometry_ = integrateBaseTwist(odometry_, wheel_twist[0], wheel_twist[1], wheel_twist[2], dt);
  odometry_twist_ = wheel_twist;
  // UMBmark's systematic errors (bounded so that a factor never reverses), then the slip.
  const double es = std::max(0.1, 1.0 + scale_), eb = std::max(0.1, 1.0 + track_);
  const double sv = std::max(0.0, 1.0 + slip_[0]), sw = std::max(0.0, 1.0 + slip_[1]);
  Eigen::Vector3d t;
  t[0] = es * sv * wheel_twist[0];
  t[1] = es * sv * wheel_twist[1];
  t[2] = sw * es * wheel_twist[2] / eb + curvature_ * t[0];
  return t;
}

void BaseImprecision::observe(const Eigen::Vector3d& true_pose, double now) {
  if (eff_.localisation_period <= 0.0) return;
  while (now >= next_fix_ - kEps) {
    odometry_ = true_pose + Eigen::Vector3d(eff_.localisation_position_sigma * gauss_(rng_),
                                            eff_.localisation_position_sigma * gauss_(rng_),
                                            eff_.localisation_heading_sigma * gauss_(rng_));
    odometry_.z() = std::remainder(odometry_.z(), 2.0 * M_PI);
    next_fix_ += eff_.localisation_period;
    ++fixes_;
  }
}

// ------------------------------------------------------------------ the chain
Water2BaseModel::Water2BaseModel(const Water2BaseParams& params)
    : params_((params.validate(), params)),
      bridge_(params.max_linear_velocity, params.max_angular_velocity, params.bridge_command_timeout,
              1.0 / params.resend_rate, bridgeDefaults().stop_repeat_duration),
      estimator_(bridgeDefaults().status_timeout, params.max_extrapolation, params.bridgeResponse()),
      response_(params.response) {
  reset(Eigen::Vector3d::Zero());
}

void Water2BaseModel::reset(const Eigen::Vector3d& pose) {
  bridge_ = ehc_realman::BaseCommandWatchdog(params_.max_linear_velocity, params_.max_angular_velocity,
                                             params_.bridge_command_timeout, 1.0 / params_.resend_rate,
                                             bridgeDefaults().stop_repeat_duration);
  estimator_ = ehc_realman::OdometryEstimator(bridgeDefaults().status_timeout, params_.max_extrapolation,
                                              params_.bridgeResponse());
  estimator_.onStatus(ehc_realman::Water2Pose{pose.x(), pose.y(), pose.z()}, 0.0);
  response_.reset();
  statuses_in_flight_.clear();
  localisation_error_.setZero();
  next_status_sample_ = params_.status_period;
  joy_controls_ = 0;
  statuses_ = 0;
}

bool Water2BaseModel::command(double linear, double angular, double now) {
  return bridge_.setCommand(linear, angular, now);
}

void Water2BaseModel::joyControl(double linear, double angular, double sent) {
  response_.joyControlSent(linear, angular, sent);
  estimator_.onTwistSent(ehc_realman::BaseTwist{linear, angular}, sent);  // the bridge's dead reckoning
  ++joy_controls_;
}

void Water2BaseModel::joyControlReceived(double linear, double angular, double now) {
  if (!std::isfinite(linear) || !std::isfinite(angular))
    throw std::invalid_argument("[Water2BaseModel] joy_control velocities must be finite");
  bridge_bypassed_ = true;
  response_.joyControlAt(linear, angular, now);  // the real connection's latency has elapsed
  ++joy_controls_;
}

Eigen::Vector3d Water2BaseModel::statusPose(const Eigen::Vector3d& true_pose) const {
  Eigen::Vector3d reported = true_pose + localisation_error_;
  reported.z() = std::remainder(reported.z(), 2.0 * M_PI);
  return reported;
}

Eigen::Vector2d Water2BaseModel::advance(double now, double dt, double deadband_linear,
                                         double deadband_angular) {
  if (!bridge_bypassed_)
    if (const auto twist = bridge_.due(now)) joyControl(twist->linear, twist->angular, now);
  return response_.advance(now, dt, deadband_linear, deadband_angular);
}

void Water2BaseModel::observe(const Eigen::Vector3d& true_pose, double now, std::mt19937_64& rng,
                              std::normal_distribution<double>& gauss) {
  while (now >= next_status_sample_ - kEps) {
    // The map pose's error: first-order Gauss-Markov, stationary sigma, one update per sample.
    const Eigen::Vector3d sigma(params_.localisation_position_sigma, params_.localisation_position_sigma,
                                params_.localisation_heading_sigma);
    for (int i = 0; i < 3; ++i)
      if (sigma[i] > 0.0)
        localisation_error_[i] = gaussMarkovStep(localisation_error_[i], params_.status_period,
                                                 params_.localisation_correlation_time, sigma[i], gauss(rng));
    const Eigen::Vector3d reported = statusPose(true_pose);
    statuses_in_flight_.push_back({next_status_sample_ + params_.status_latency, next_status_sample_, reported});
    next_status_sample_ += params_.status_period;
  }
  while (!statuses_in_flight_.empty() && statuses_in_flight_.front().at <= now + kEps) {
    const Eigen::Vector3d& p = statuses_in_flight_.front().value;
    // Valid at the sample time: the bridge stamps a pose with its request's send time.
    estimator_.onStatus(ehc_realman::Water2Pose{p.x(), p.y(), p.z()}, statuses_in_flight_.front().valid);
    statuses_in_flight_.pop_front();
    ++statuses_;
  }
}

BaseOdometryEstimate Water2BaseModel::odometry(double now) const {
  const auto o = estimator_.estimate(now);
  if (!o) throw std::runtime_error("[Water2BaseModel] the bridge has no fresh robot_status at t = " + std::to_string(now));
  BaseOdometryEstimate e;
  e.pose = Eigen::Vector3d(o->x, o->y, o->theta);
  e.linear = o->linear;
  e.angular = o->angular;
  return e;
}

}  // namespace ehc_sim
