#pragma once
// EhcWeighting: the EHC function of the paper (eq. 10-13). omega = |e*| / |e| where e is the
// TCP-to-target position error and e* the farthest point of the arm's high-reachability set
// r_td = {R > threshold} along the direction of e (ray march in the ReachabilityMap, arm base
// frame, from the arm base origin or from the TCP, see ray_origin). sig(omega) = 1 / (1 + exp(-k (omega - 1))):
//   far  (omega << 1): sig -> 0, the base is cheap and leads;
//   close (omega > 1): sig -> 1, the base is expensive and the arm works.

#include "ehc_control/reachability_map.h"

#include <memory>
#include <string>

namespace ehc_common {
class ConfigNode;
}  // namespace ehc_common

namespace ehc_control {

struct EhcWeightingParams {
  double reach_threshold = 0.95;  ///< R above this defines r_td
  double sigmoid_gain = 10.0;     ///< k of the logistic
  double max_ray_length = 1.6;    ///< m, ray-march range (>= the arm's reach)
  double ray_step = 0.0;          ///< m, 0 = half a voxel
  double omega_max = 10.0;        ///< cap of omega when |e| -> 0
  /// How e* and e are measured:
  ///  "tcp":      e = target - TCP; e* = largest step from the TCP along e that ends in r_td.
  ///  "arm_base": e = target - TCP; e* = reach of r_td from the arm base along e's direction.
  ///  "target":   e = target - arm base; e* = reach of r_td from the arm base along e, so
  ///              omega >= 1 exactly when the target lies inside r_td ("the target is within
  ///              the arm's high-reachability set: the arm takes over").
  std::string ray_origin = "arm_base";
  void validate() const;          ///< throws "[EhcWeighting] ..."
};
EhcWeightingParams loadEhcWeightingParams(const ehc_common::ConfigNode& node);

struct EhcWeight {
  double omega = 0.0;   ///< |e*| / |e|
  double sig = 0.0;     ///< sig(omega) in [0, 1]
  double e_star = 0.0;  ///< |e*|, m
};

class EhcWeighting {
 public:
  EhcWeighting(std::shared_ptr<const ReachabilityMap> map, const EhcWeightingParams& params);

  /// TCP and target positions in the arm base frame. Non-finite input throws.
  EhcWeight evaluate(const Eigen::Vector3d& tcp_arm, const Eigen::Vector3d& target_arm) const;
  /// Logistic 1 / (1 + exp(-k (omega - 1))).
  double sig(double omega) const;
  /// Whether a point (arm base frame) belongs to r_td.
  bool inReachSet(const Eigen::Vector3d& p_arm) const;

  const EhcWeightingParams& params() const { return params_; }
  const ReachabilityMap& map() const { return *map_; }

 private:
  std::shared_ptr<const ReachabilityMap> map_;
  EhcWeightingParams params_;
  double step_;
};

}  // namespace ehc_control
