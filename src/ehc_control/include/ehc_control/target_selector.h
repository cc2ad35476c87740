#pragma once
// TargetSelector: which object is the target. The one home of a target's definition for the
// grasp sequencer, the grasp selection, the controller's watched centre (MPBS, TfM), the grasp
// node (topic ehc_msgs/TargetSelector) and the scene's `targets:` (in-process experiments).
// ROS-free, Eigen only.
//
// Kinds (one string map, toString / targetSelectorKindFromString):
//   tag             the object carrying AprilTag `tag_id` (its pose from the tag detector)
//   nearest         the object whose cloud centre is nearest to `point` (world, m), among those
//                   within `radius` of it (0: any distance); the grasp sequencer searches for it
//                   from a look pose at `point` until it is seen
//   kth_from_left   the k-th object (k = 1, 2, ...) counted from the left as the camera looks
//   kth_from_front  the k-th object counted from the front (nearest to the camera first)
// Left and front are taken in the table plane: `front` is the camera's viewing direction (its
// optical z axis) projected onto the plane normal to `up` (looking straight down: the image's up
// direction), `left` is up x front. An object's
// centre (cloud targets) is the centroid of its segmented cluster (GraspGenerator::segmentScene).
//
// selectTarget() ranks the objects of one view by the rule and returns the chosen one, or a
// status saying why there is none: no object in the view, fewer than k objects, or two objects
// closer than `ambiguity` (m) in the ranked quantity (distance to the point, lateral or forward
// position), so that the choice would depend on noise. A tag target is not selected from
// clouds (status NotCloudTarget).

#include <Eigen/Geometry>

#include <string>
#include <vector>

namespace ehc_common {
class ConfigNode;
}  // namespace ehc_common

namespace ehc_control {

enum class TargetSelectorKind { Tag, Nearest, KthFromLeft, KthFromFront };
std::string toString(TargetSelectorKind k);
/// Throws std::invalid_argument "[TargetSelector] unknown selector kind '...' (expected one of ...)".
TargetSelectorKind targetSelectorKindFromString(const std::string& s);

struct TargetSelector {
  TargetSelectorKind kind = TargetSelectorKind::Tag;
  int tag_id = 0;                                  ///< tag: 0..586 (tag36h11)
  Eigen::Vector3d point = Eigen::Vector3d::Zero(); ///< nearest: world, m
  double radius = 0.0;                             ///< nearest: m, objects farther are not it; 0 = any
  int k = 1;                                       ///< kth_*: 1 = the first
  double ambiguity = 0.02;                         ///< m, see the header comment (> 0)
  /// The target comes from the depth cloud (every kind but tag).
  bool fromCloud() const { return kind != TargetSelectorKind::Tag; }
  /// Throws std::invalid_argument "[TargetSelector] parameter '<field>' ..." (tag_id in
  /// [0, 586], k in [1, 100], point finite, radius in [0, 10] m, ambiguity in (0, 1] m).
  void validate() const;
  /// e.g. "tag 1", "nearest to (1.7, 0, 0.8)", "2nd from the left".
  std::string summary() const;
};

/// Reads a selector mapping {select: <kind>, tag_id, point: [x, y, z], radius, k, ambiguity}: only the
/// fields of its kind are allowed (another kind's field is an error naming it). Errors name the
/// file and the field.
TargetSelector loadTargetSelector(const ehc_common::ConfigNode& node);

enum class TargetSelectionStatus { Selected, NoObject, TooFewObjects, Ambiguous, NotCloudTarget };
std::string toString(TargetSelectionStatus s);

struct TargetSelection {
  TargetSelectionStatus status = TargetSelectionStatus::NoObject;
  int index = -1;                                   ///< into the centres; -1 unless Selected
  Eigen::Vector3d centre = Eigen::Vector3d::Zero(); ///< the chosen centre (Selected)
  std::string detail;                               ///< why there is none, or what was chosen
  bool selected() const { return status == TargetSelectionStatus::Selected; }
};

/// The object of `centres` (world) that `selector` names, seen from `camera` (optical frame in
/// the world: z = viewing direction); `up` = world up. Non-finite centres are ignored.
TargetSelection selectTarget(const TargetSelector& selector, const std::vector<Eigen::Vector3d>& centres,
                             const Eigen::Isometry3d& camera, const Eigen::Vector3d& up = Eigen::Vector3d::UnitZ());

/// Pose of a cloud target (the tag target's convention: origin at the object centre, z =
/// forward approach, y = finger closing axis): z = the horizontal direction from `viewpoint`
/// to `centre`, y = z x up (horizontal), x = y x z = up: the frame of a tag target on a side
/// face (a tag node's forward grasp). A viewpoint straight above the centre gives z = world x.
Eigen::Isometry3d cloudTargetPose(const Eigen::Vector3d& centre, const Eigen::Vector3d& viewpoint,
                                  const Eigen::Vector3d& up = Eigen::Vector3d::UnitZ());

}  // namespace ehc_control
