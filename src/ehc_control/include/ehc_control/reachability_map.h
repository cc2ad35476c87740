#pragma once
// ReachabilityMap: offline map of how well the arm reaches each point of its workspace.
// Voxel grid in the arm base frame x discretised approach directions (Fibonacci sphere).
// R(voxel) = fraction of direction bins in which some sampled joint configuration put the TCP
// in that voxel with that approach axis. Built by sampling the joint space (FK via
// WholeBodyModel); deterministic for a given seed. ROS-free.

#include "ehc_control/whole_body_model.h"

#include <Eigen/Core>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace ehc_control {

struct ReachabilityMapParams {
  double resolution = 0.05;  ///< voxel edge, m
  int direction_bins = 6;    ///< approach directions on the unit sphere (coarse: R > 0.95
                             ///< then means "reachable from every principal direction")
  void validate() const;     ///< throws "[ReachabilityMap] ..."
};

class ReachabilityMap {
 public:
  using Progress = std::function<void(long done, long total)>;

  /// Samples `samples` uniform random arm configurations within the joint limits.
  static ReachabilityMap generate(const WholeBodyModel& model, long samples, unsigned seed,
                                  const ReachabilityMapParams& params,
                                  const Progress& progress = nullptr);
  /// Loads a map written by save(). Throws "[ReachabilityMap] ..." on a missing/corrupt file.
  static ReachabilityMap load(const std::string& path);
  void save(const std::string& path) const;

  /// R in [0, 1] at a point in the arm base frame; 0 outside the grid.
  double reachability(const Eigen::Vector3d& p_arm) const;
  double resolution() const { return resolution_; }
  const Eigen::Vector3d& origin() const { return origin_; }
  const Eigen::Vector3i& dims() const { return dims_; }
  int directionBins() const { return direction_bins_; }
  long samples() const { return samples_; }
  unsigned seed() const { return seed_; }
  const std::string& robotName() const { return robot_name_; }
  const std::string& armBaseFrame() const { return arm_base_frame_; }
  const std::string& tcpFrame() const { return tcp_frame_; }
  /// Number of voxels with R above `threshold`.
  long countAbove(double threshold) const;
  /// Throws unless the map was built for this robot (name, frames, joint count).
  void checkCompatible(const RobotConfig& robot) const;
  std::string summary() const;

  /// Unit directions of the bins (Fibonacci sphere), index = bin.
  static std::vector<Eigen::Vector3d> directionSet(int bins);

 private:
  long index(const Eigen::Vector3d& p) const;  ///< -1 outside

  std::string robot_name_, arm_base_frame_, tcp_frame_;
  int n_arm_ = 0;
  double resolution_ = 0.05;
  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();  ///< corner of voxel (0,0,0)
  Eigen::Vector3i dims_ = Eigen::Vector3i::Zero();
  int direction_bins_ = 0;
  long samples_ = 0;
  unsigned seed_ = 0;
  std::vector<std::uint8_t> reached_;  ///< per voxel: number of direction bins reached
};

}  // namespace ehc_control
