#pragma once
// GraspTargetHistory: the recent target positions ehc_grasp_node aims its grasps at, and which
// one serves a cloud. Time is the messages' stamps only (never when they arrive), so which cloud
// is processed with which target does not depend on the receipt order: the target for a cloud
// is the newest one stamped before it, if at most target_timeout older. The targets are kept in
// stamp order, at most `capacity` (the oldest is dropped); a target stamped before the newest one
// kept (a clock that jumped back: simulator reset) starts the list again. A target that comes
// after the cloud that should have used it (stamped between that cloud and the target the cloud
// used) is reported so the node can log it. ROS-free; stamps in ns (stamp.h).

#include "ehc_perception/stamp.h"

#include <Eigen/Core>

#include <cstddef>
#include <deque>
#include <optional>
#include <utility>

namespace ehc_perception {

class GraspTargetHistory {
 public:
  /// Targets kept by default: the sequencer sends one per control cycle.
  static constexpr std::size_t kDefaultCapacity = 200;

  /// `target_timeout` s (GraspTargetingParams::target_timeout, >= 0), `capacity` >= 1.
  /// Throws std::invalid_argument "[GraspTargetHistory] ..." otherwise.
  explicit GraspTargetHistory(double target_timeout, std::size_t capacity = kDefaultCapacity);

  enum class Added {
    Kept,       ///< appended
    Late,       ///< appended, but the last cloud (stamped after it) already used an older one
    Restarted,  ///< stamped before the newest target kept: the list starts again with it
    Rejected,   ///< a non-finite position: ignored, nothing changed
  };
  /// A target position (world frame) stamped `stamp`.
  Added add(StampNs stamp, const Eigen::Vector3d& position);

  /// The target for a cloud stamped `cloud_stamp`: the newest one stamped before it, if at most
  /// target_timeout s older; none otherwise (grasps for every object). Remembers the cloud and
  /// the target it found (the newest before it, even a too old one) for add()'s Late.
  std::optional<Eigen::Vector3d> targetFor(StampNs cloud_stamp);

  /// The stamp of the last cloud given to targetFor (0 before the first).
  StampNs lastCloud() const { return last_cloud_; }
  std::size_t size() const { return targets_.size(); }

 private:
  double target_timeout_;
  std::size_t capacity_;
  std::deque<std::pair<StampNs, Eigen::Vector3d>> targets_;  ///< by stamp, newest last
  StampNs last_cloud_ = 0, last_cloud_target_ = 0;  ///< the last cloud's stamp and its target's (0: none)
};

}  // namespace ehc_perception
