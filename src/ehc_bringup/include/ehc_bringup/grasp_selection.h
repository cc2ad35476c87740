#pragma once
// Grasp choice for the grasp sequencer (ROS-free, Eigen only).
//
// Inputs: the object's target pose from the AprilTag (tag node: TCP pose of a forward grasp,
// origin at the grasp centre, z = approach into the tagged face, y = finger closing axis) and
// the grasp candidates of the perception grasp node (same frame convention, world frame).
// The preferred approach direction decides which candidates qualify:
//   tag       the tag target itself (no candidates)
//   forward   approach along the tag target's z axis (into the tagged face); into a side face
//             (that axis within ~64 deg of horizontal) its horizontal direction: the face of
//             an upright object is vertical, and the tag's tilt is the noisiest part of its
//             pose (a few deg from afar), which would tilt the hand and bring the wrist down
//             towards the support by its length x the tilt
//   downward  approach straight down (world -z)
//   sideways  approach horizontally from either side, perpendicular to the forward axis or
//             turned by sideways_turn_deg towards it (the hand then comes from the robot's
//             side of the object: an arm in front of the table reaches the side of an object
//             near the table edge without bending its wrist past the joint limit)
//   any       every candidate
// Without a qualifying candidate the fallback is the tag target turned to the preferred
// approach (closing axis kept horizontal) and backed off along it by a configured distance.
// A target without a tag (ehc_control::TargetSelector, a cloud kind) comes as a pose of the same
// convention (ehc_control::cloudTargetPose: origin at the object's cloud centre, z horizontal from
// the camera to it): its orientation says nothing of the object's faces and its centre is that of
// the seen points only, so such a target is chosen with forCloudTarget()'s parameters: no
// centring on it, no closing axis from it, no fallback (a candidate is required), the wider
// cloud_candidate_gate, and (cloud_any_approach) the generator's own approach when none
// approaches as preferred.

#include "ehc_control/pose_math.h"

#include <Eigen/Geometry>

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace ehc_bringup {

enum class ApproachDirection { Tag, Forward, Downward, Sideways, Any };
std::string toString(ApproachDirection d);
/// Throws std::invalid_argument "[GraspSelection] unknown approach direction '...'".
ApproachDirection approachDirectionFromString(const std::string& s);

struct GraspCandidate {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  ///< world frame, z = approach
  double width = 0.0;                                       ///< m
  double score = 0.0;
};

struct GraspSelectionParams {
  double candidate_gate = 0.05;         ///< m: candidate centre within this of the tag target
  double max_angle_deg = 30.0;          ///< candidate approach within this of the preferred one
  double max_width = 0.07;              ///< m: gripper aperture
  bool require_candidate = false;       ///< false: fall back to the turned tag target
  /// No candidate approaches as preferred: take the best one under ApproachDirection::Any, as it
  /// is (set by forCloudTarget() from cloud_any_approach; not a configuration key).
  bool any_approach_fallback = false;
  /// Turn a chosen candidate (about its centre, by the smallest rotation) so that its approach
  /// is exactly the wanted one: straight down, along the tag normal, or horizontal sideways.
  /// A horizontal approach also gets a level closing axis (an upright object's side faces are
  /// vertical). The descent from the pre-grasp is then a straight line along that direction
  /// and the fingers close level. `tag` and `any` keep the candidate as it is.
  /// A candidate turned onto a downward or sideways approach keeps its depth along it only up to
  /// the tag fallback's (the tag target moved back by fallback_backoff_<direction> along the
  /// approach): the generator checked its palm for its own approach, not for the turned one. A
  /// candidate from the front-top turned straight down kept its height, 2 cm below the centre of
  /// the 12 cm box, so the palm (4 cm behind the TCP) came down on the box's top and knocked it
  /// over (Exp-3, downward: 38 of 75 NEO grasps "closed on nothing").
  bool align_approach = true;
  /// Move a chosen candidate across its approach (along its closing and x axes) onto the tag
  /// target's centre; keep its depth along the approach. A single-view cloud misses the far
  /// side of the object, so a candidate closing along the camera's line of sight is centred
  /// short of the object (measured: 2.7 cm on the 6 cm box, which the 7 cm gripper then
  /// pushed instead of grasping). The tag pose gives the centre whatever the view.
  bool centre_from_tag = true;
  /// Turn a chosen candidate about its approach so that it closes along the tag target's axis
  /// nearest its own closing axis (the tag target's frame is the object's: for a box, its face
  /// normals). The 7 cm gripper clears the 6 cm box only within about 10 deg of a face normal;
  /// measured candidate closing axes were up to 25 deg off.
  bool closing_axis_from_tag = true;
  /// Sideways approach turned this much (deg, [0, 60]) from the pure side direction towards the
  /// forward approach. 0 = straight from the side.
  double sideways_turn_deg = 0.0;
  /// Sideways approach tilted this much (deg, [0, 60]) down from horizontal: the hand comes
  /// from above the side, still closing on the faces the pure side grasp closes on.
  double sideways_tilt_deg = 0.0;
  double fallback_backoff_forward = 0.0;   ///< m, fallback TCP moved back along the approach
  double fallback_backoff_downward = 0.03;
  double fallback_backoff_sideways = 0.0;
  /// m: candidate_gate for a cloud target. Its centre is the centroid of the seen side of the
  /// object, and a grasp on a part of it (a handle, a rim) lies farther from it than from a tag's
  /// centre; the candidates come from the target's cluster alone (generateForCloudTarget).
  double cloud_candidate_gate = 0.10;
  /// A target without a tag: when no candidate approaches as preferred, the best candidate
  /// approaching as the generator proposes it (any direction it checked: the fingers and palm
  /// against the cloud, the hidden volume and the support) is taken as it is, not turned. A flat
  /// object (a banana, a bowl, a box lying down) offers no grasp within max_angle_deg of a
  /// horizontal forward approach, and a cloud target has no tag fallback. false: such a target
  /// waits for a qualifying candidate (no_grasp when none comes).
  bool cloud_any_approach = true;
  /// With a reachability judgement (chooseGrasp's `reachable`): the best-scored qualifying
  /// candidates judged per choice, [0, 50]; the first reachable one is chosen. 0: none judged.
  int reach_checks = 10;
  void validate() const;  ///< throws "[GraspSelectionParams] ..."
  /// These parameters for a target without a tag (see the header comment).
  GraspSelectionParams forCloudTarget() const;
};

struct GraspChoice {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  ///< TCP grasp pose, world
  bool from_candidate = false;
  double score = 0.0;
  int candidate_index = -1;
  double width = 0.0;  ///< m, the candidate's opening (0: the tag fallback)
  /// s, time stamp of the candidate set it was chosen from (GraspSequencer::setGraspCandidates;
  /// the view its grasp came from); -1: not from a candidate set.
  double candidates_t = -1.0;
  /// The reachability judgement's verdict on this grasp (nullopt: not judged).
  std::optional<bool> reachable;
};

/// Whether the robot can reach a grasp (TCP pose, world), e.g. GraspReach::reachable of it and its
/// pre-grasp.
using GraspReachable = std::function<bool(const Eigen::Isometry3d& grasp)>;

/// Unit approach direction wanted for `direction` given the tag target; nullopt for Any
/// (the tag target's z for Tag, levelled for Forward into a side face, world -z for Downward). Sideways has one direction
/// per side (see sideways_turn_deg): the one closer to `hint` (e.g. a candidate's approach or
/// the current TCP's) is returned.
std::optional<Eigen::Vector3d> wantedApproach(ApproachDirection direction,
                                              const Eigen::Isometry3d& tag_target,
                                              const GraspSelectionParams& p,
                                              const Eigen::Vector3d& hint);

/// True if the candidate is finite, a proper rotation, within the gate, opens wide enough and
/// approaches as preferred.
bool candidateQualifies(const GraspCandidate& c, ApproachDirection direction,
                        const Eigen::Isometry3d& tag_target, const GraspSelectionParams& p);

/// Best qualifying candidate (highest score), or the fallback, or nullopt (require_candidate
/// and nothing qualifies, or a non-finite tag target). A parallel-jaw grasp is symmetric about
/// its approach axis: the candidate or its half-turn about z, whichever is closer to
/// `reference` (e.g. the current TCP orientation), is returned.
/// With `reachable` (and reach_checks > 0), reachability comes before score: the qualifying
/// candidates are judged as chosen (turned, centred), best score first, at most reach_checks of
/// them, and the first reachable one wins; when none is, a reachable one of the generator's own
/// approach (any_approach_fallback); else the best-scored one as before (GraspChoice::reachable
/// false). The tag fallback is not judged.
std::optional<GraspChoice> chooseGrasp(const std::vector<GraspCandidate>& candidates,
                                       ApproachDirection direction,
                                       const Eigen::Isometry3d& tag_target,
                                       const Eigen::Matrix3d& reference,
                                       const GraspSelectionParams& p,
                                       const GraspReachable& reachable = {});

/// Tag target turned so that its z axis is `approach` (unit), with its y (closing) axis
/// horizontal when possible, backed off by `backoff` along the approach.
Eigen::Isometry3d turnedTagGrasp(const Eigen::Isometry3d& tag_target, const Eigen::Vector3d& approach,
                                 double backoff);

/// `pose` moved `distance` back along its z (approach) axis: a grasp's pre-grasp, a target's
/// look pose, the tag fallback's grasp.
Eigen::Isometry3d backedOff(Eigen::Isometry3d pose, double distance);

/// A parallel-jaw grasp's orientation turned by pi about its approach (z) axis: the same grasp.
Eigen::Matrix3d halfTurned(const Eigen::Matrix3d& R);

using ehc_control::isValidPose;

}  // namespace ehc_bringup
