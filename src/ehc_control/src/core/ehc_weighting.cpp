#include "ehc_control/ehc_weighting.h"

#include "ehc_common/config_node.h"

#include <cmath>
#include <stdexcept>

using ehc_common::requireRange;

namespace ehc_control {

namespace {
const char* kOwner = "EhcWeighting";
}

void EhcWeightingParams::validate() const {
  requireRange(kOwner, "reach_threshold", reach_threshold, 0.0, 1.0);
  requireRange(kOwner, "sigmoid_gain", sigmoid_gain, 0.1, 1000.0);
  requireRange(kOwner, "max_ray_length", max_ray_length, 0.1, 10.0);
  requireRange(kOwner, "ray_step", ray_step, 0.0, 0.5);
  requireRange(kOwner, "omega_max", omega_max, 1.0, 1e6);
  if (ray_origin != "arm_base" && ray_origin != "tcp" && ray_origin != "target")
    throw std::invalid_argument("[EhcWeighting] ray_origin must be 'arm_base', 'tcp' or 'target' (got '" +
                                ray_origin + "')");
}

EhcWeightingParams loadEhcWeightingParams(const ehc_common::ConfigNode& n) {
  EhcWeightingParams p;
  p.reach_threshold = n.get("reach_threshold", p.reach_threshold);
  p.sigmoid_gain = n.get("sigmoid_gain", p.sigmoid_gain);
  p.max_ray_length = n.get("max_ray_length", p.max_ray_length);
  p.ray_step = n.get("ray_step", p.ray_step);
  p.omega_max = n.get("omega_max", p.omega_max);
  p.ray_origin = n.get<std::string>("ray_origin", p.ray_origin);
  n.validate(p);  // errors name the file and the section
  return p;
}

EhcWeighting::EhcWeighting(std::shared_ptr<const ReachabilityMap> map, const EhcWeightingParams& params)
    : map_(std::move(map)), params_(params) {
  if (!map_) throw std::invalid_argument("[EhcWeighting] no reachability map");
  params_.validate();
  step_ = params_.ray_step > 0.0 ? params_.ray_step : 0.5 * map_->resolution();
}

bool EhcWeighting::inReachSet(const Eigen::Vector3d& p) const {
  return map_->reachability(p) > params_.reach_threshold;
}

double EhcWeighting::sig(double omega) const {
  return 1.0 / (1.0 + std::exp(-params_.sigmoid_gain * (omega - 1.0)));
}

EhcWeight EhcWeighting::evaluate(const Eigen::Vector3d& tcp, const Eigen::Vector3d& target) const {
  if (!tcp.allFinite() || !target.allFinite())
    throw std::invalid_argument("[EhcWeighting] TCP or target position is not finite");
  EhcWeight w;
  const Eigen::Vector3d e = params_.ray_origin == "target" ? target : Eigen::Vector3d(target - tcp);
  const double dist = e.norm();
  if (dist < 1e-9) {
    w.omega = params_.omega_max;
  } else {
    const Eigen::Vector3d dir = e / dist;
    // Farthest point of the ray (from the arm base origin or the TCP, along e) in r_td.
    const Eigen::Vector3d origin = params_.ray_origin == "tcp" ? tcp : Eigen::Vector3d::Zero();
    const int steps = static_cast<int>(std::ceil(params_.max_ray_length / step_));
    for (int i = 0; i <= steps; ++i) {
      const double s = std::min(i * step_, params_.max_ray_length);
      if (inReachSet(origin + s * dir)) w.e_star = s;
    }
    w.omega = std::min(params_.omega_max, w.e_star / dist);
  }
  w.sig = sig(w.omega);
  return w;
}

}  // namespace ehc_control
