#pragma once
// TargetPoseFilter: the one home of a perceived target pose's smoothing and outlier rejection.
// The grasp sequencer keeps one per object: what it remembers of the object, and the pose its
// goals come from (the grasp node's target is the sequencer's filtered pose, so perception
// glitches stop here). ROS-free.
//
// Each observation (a pose in the world) either
//   - starts the filter (the first one),
//   - is smoothed in: pose = interpolatePose(pose, observation, gain) (ehc_control, SE(3): lerp
//     and slerp), when it is within jump_distance and jump_angle_deg of the pose, or
//   - is a jump: it is held, and the pose does not move. Held jumps that agree with the first
//     one held (within jump_distance and jump_angle_deg of it) and follow each other without an
//     observation near the pose in between are a moved object: at the jump_confirmations-th the
//     pose becomes their own smoothed pose. An observation near the pose again, or one that
//     disagrees with the held ones, drops them as outliers (counted).
// So one far glitch never moves the pose, and a genuinely moved object is followed after
// jump_confirmations consistent observations (1: every jump at once, no rejection).

#include <Eigen/Geometry>

#include <optional>
#include <string>

namespace ehc_common {
class ConfigNode;
}  // namespace ehc_common

namespace ehc_bringup {

struct TargetPoseFilterParams {
  double gain = 0.3;            ///< (0, 1]: weight of a new observation (1 = no smoothing)
  double jump_distance = 0.10;  ///< m: an observation farther than this from the pose is a jump
  double jump_angle_deg = 45.0; ///< deg: ... or turned more than this from it
  int jump_confirmations = 3;   ///< consistent jump observations in a row that move the pose
  /// Throws std::invalid_argument "[TargetPoseFilter] parameter '<field>' ..." (gain in (0, 1],
  /// jump_distance in (0, 10] m, jump_angle_deg in (0, 180], jump_confirmations in [1, 100]).
  void validate() const;
  std::string summary() const;
};

/// Reads pose_filter_gain, pose_jump_distance, pose_jump_angle_deg and pose_jump_confirmations
/// of the sequencer's `sequencer` mapping (all optional).
TargetPoseFilterParams loadTargetPoseFilterParams(const ehc_common::ConfigNode& sequencer);

class TargetPoseFilter {
 public:
  explicit TargetPoseFilter(const TargetPoseFilterParams& params = TargetPoseFilterParams());  ///< validates

  enum class Update {
    First,          ///< the first observation: the pose
    Smoothed,       ///< near the pose: smoothed in
    JumpHeld,       ///< a jump, held (the pose did not move)
    JumpConfirmed,  ///< the jump_confirmations-th consistent jump: the pose moved there
  };
  /// One observation (a rotation and a finite translation; the caller checks).
  Update add(const Eigen::Isometry3d& observation);

  const std::optional<Eigen::Isometry3d>& pose() const { return pose_; }
  /// Jump observations held now (0 .. jump_confirmations - 1).
  int held() const { return held_; }
  /// Jump observations dropped as outliers since construction.
  long outliers() const { return outliers_; }
  /// Forgets the pose and the held jumps (not the outlier count).
  void reset();
  const TargetPoseFilterParams& params() const { return params_; }

 private:
  bool near(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) const;
  void dropHeld();

  TargetPoseFilterParams params_;
  std::optional<Eigen::Isometry3d> pose_;
  Eigen::Isometry3d first_held_ = Eigen::Isometry3d::Identity(), held_pose_ = Eigen::Isometry3d::Identity();
  int held_ = 0;
  long outliers_ = 0;
};
std::string toString(TargetPoseFilter::Update u);

}  // namespace ehc_bringup
