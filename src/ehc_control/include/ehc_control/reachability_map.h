#pragma once
// ReachabilityMap: offline map of how well the arm reaches each point of its workspace.
// Voxel grid in the arm base frame x discretised approach directions (Fibonacci sphere).
// R(voxel) = fraction of direction bins in which some sampled joint configuration put the TCP
// in that voxel with that approach axis. Built by sampling the joint space (FK via
// WholeBodyModel); deterministic for a given seed. The map records the joint limits it sampled
// and the TCP pose at a few reference configurations, so that a map built for another arm, TCP
// or joint limits is found out (kinematicMismatch). ROS-free.

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

  /// The TCP pose in the arm base frame at one arm configuration, as the map's robot had it.
  struct ReferencePose {
    Eigen::VectorXd q;
    Eigen::Isometry3d tcp = Eigen::Isometry3d::Identity();
  };
  /// Reference configurations recorded per map.
  static constexpr int kReferencePoses = 8;

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
  /// Same, and throws when kinematicMismatch(model) finds a difference.
  void checkCompatible(const WholeBodyModel& model) const;
  /// True for maps that record their joint limits and reference poses (every map built by this
  /// version; maps of the first format do not).
  bool hasKinematics() const { return !references_.empty(); }
  const Eigen::VectorXd& sampledLower() const { return lower_; }
  const Eigen::VectorXd& sampledUpper() const { return upper_; }
  const std::vector<ReferencePose>& referencePoses() const { return references_; }
  /// "" when the model's arm matches the map (same joint limits to 1e-6 rad, and at every
  /// reference configuration the TCP within 0.2 voxel and 0.02 rad of the recorded pose) or the
  /// map records no kinematics; otherwise what differs, e.g. "the TCP at reference
  /// configuration 3 is 0.042 m from where the map's arm had it".
  std::string kinematicMismatch(const WholeBodyModel& model) const;
  std::string summary() const;

  /// Unit directions of the bins (Fibonacci sphere), index = bin.
  static std::vector<Eigen::Vector3d> directionSet(int bins);

 private:
  long index(const Eigen::Vector3d& p) const;  ///< -1 outside
  /// Reads the `limits`, `references` and `reference` header lines (format 2); `expect(key)`
  /// returns the rest of the next line, which must start with key.
  void readKinematics(const std::string& path, const std::function<std::string(const std::string&)>& expect);

  std::string robot_name_, arm_base_frame_, tcp_frame_;
  int n_arm_ = 0;
  double resolution_ = 0.05;
  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();  ///< corner of voxel (0,0,0)
  Eigen::Vector3i dims_ = Eigen::Vector3i::Zero();
  int direction_bins_ = 0;
  long samples_ = 0;
  unsigned seed_ = 0;
  Eigen::VectorXd lower_, upper_;         ///< joint limits sampled (empty: first format)
  std::vector<ReferencePose> references_;  ///< empty: first format
  std::vector<std::uint8_t> reached_;  ///< per voxel: number of direction bins reached
};

}  // namespace ehc_control
