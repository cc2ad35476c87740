#include "ehc_perception/grasp_target_history.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace ehc_perception {

GraspTargetHistory::GraspTargetHistory(double target_timeout, std::size_t capacity)
    : target_timeout_(target_timeout), capacity_(capacity) {
  if (!std::isfinite(target_timeout) || target_timeout < 0.0)
    throw std::invalid_argument("[GraspTargetHistory] target_timeout " + std::to_string(target_timeout) +
                                " s must be finite and >= 0");
  if (capacity == 0) throw std::invalid_argument("[GraspTargetHistory] capacity must be >= 1");
}

GraspTargetHistory::Added GraspTargetHistory::add(StampNs stamp, const Eigen::Vector3d& position) {
  if (!position.allFinite()) return Added::Rejected;
  Added added = Added::Kept;
  if (!targets_.empty() && stamp < targets_.back().first) {
    targets_.clear();
    added = Added::Restarted;
  } else if (stamp < last_cloud_ && stamp > last_cloud_target_) {
    added = Added::Late;
  }
  targets_.emplace_back(stamp, position);
  if (targets_.size() > capacity_) targets_.pop_front();
  return added;
}

std::optional<Eigen::Vector3d> GraspTargetHistory::targetFor(StampNs cloud_stamp) {
  last_cloud_ = cloud_stamp;
  last_cloud_target_ = 0;
  for (auto it = targets_.rbegin(); it != targets_.rend(); ++it)
    if (it->first < cloud_stamp) {
      last_cloud_target_ = it->first;
      if (stampSeconds(cloud_stamp - it->first) <= target_timeout_) return it->second;
      return std::nullopt;
    }
  return std::nullopt;
}

}  // namespace ehc_perception
