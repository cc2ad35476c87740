#pragma once
// TargetTracker: whether the target is in the camera's view, and TfM (time for monitoring,
// paper Exp-3): the fraction of control cycles, since the target was set, in which the target
// centre projects inside the image at positive depth. The camera pose comes from the robot's
// kinematics (not from detections), so TfM also counts the cycles in which the controller
// moves on the last good target pose while perception does not see it. A target whose centre
// jumps by more than new_target_distance is a new target and restarts the count (setTarget);
// moveTarget follows a target whose centre estimate moves without restarting. A paused tracker
// still answers whether the target is in view but does not count the cycle, so one tracker per
// TfM window (e.g. the grasp sequencer's: until the arm takes over, until the pre-grasp switch,
// until the gripper closes) counts its own span. ROS-free.

#include "ehc_control/pinhole_camera.h"

#include <Eigen/Geometry>

#include <string>

namespace ehc_common {
class ConfigNode;
}  // namespace ehc_common

namespace ehc_control {

struct TargetTrackerParams {
  std::string camera_file;           ///< camera_info YAML (resolved path), overrides robot.yaml's robot.camera_info; "" = the robot's (none: PinholeCamera defaults)
  double new_target_distance = 0.10; ///< m: centre jump that counts as a new target (TfM restarts)
  void validate() const;             ///< throws "[TargetTrackerParams] ..."
  std::string summary() const;
};
/// Reads the `tracking` section; `camera` is resolved against the YAML file's folder.
TargetTrackerParams loadTargetTrackerParams(const ehc_common::ConfigNode& node);

class TargetTracker {
 public:
  TargetTracker(const PinholeCamera& camera, const TargetTrackerParams& params);

  /// A newly accepted target centre (world). Returns true if it is a new target (first one,
  /// or a jump larger than new_target_distance): the TfM count restarts.
  bool setTarget(const Eigen::Vector3d& centre_world);
  /// The same target at a new centre estimate (world), e.g. a filtered or locked object pose:
  /// the count continues whatever the jump. Starts a target (count 0) when there is none.
  /// Throws on a non-finite centre.
  void moveTarget(const Eigen::Vector3d& centre_world);
  /// One control cycle with the camera optical frame's world pose: updates and returns
  /// whether the target centre is in view (PinholeCamera::projectsInside); counts the cycle
  /// unless paused. No-op (false) before the first target.
  bool observe(const Eigen::Isometry3d& world_T_camera);
  /// Stop / resume counting cycles (observe still updates inView()); the counts are kept.
  void pause() { counting_ = false; }
  void resume() { counting_ = true; }
  bool paused() const { return !counting_; }
  /// New intrinsics (e.g. a camera_info update); the count continues. Validates (throws).
  void setCamera(const PinholeCamera& camera);
  /// Forget the target (TfM 0, no target) and resume counting.
  void reset();

  bool hasTarget() const { return has_target_; }
  bool inView() const { return in_view_; }
  double tfm() const { return cycles_ > 0 ? static_cast<double>(in_view_cycles_) / static_cast<double>(cycles_) : 0.0; }
  long cycles() const { return cycles_; }
  long inViewCycles() const { return in_view_cycles_; }
  const Eigen::Vector3d& centre() const { return centre_; }
  const PinholeCamera& camera() const { return camera_; }

 private:
  PinholeCamera camera_;
  TargetTrackerParams params_;
  bool has_target_ = false, in_view_ = false, counting_ = true;
  Eigen::Vector3d centre_ = Eigen::Vector3d::Zero();
  long cycles_ = 0, in_view_cycles_ = 0;
};

}  // namespace ehc_control
