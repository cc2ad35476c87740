#pragma once
// GraspSequencer: the per-object grasp state machine behind `make demo` (ROS-free; the node
// ehc_grasp_sequencer_node only converts messages and calls it).
//
// For every object in order:
//   WAIT_TARGET  until a fresh perceived pose (tag target) of the object arrives; meanwhile, if
//                the object was seen before (every object's pose is remembered, e.g. from the
//                start position), goal = a look pose search_distance back along its approach
//                axis, so that the camera finds it again (search_distance 0: no goal, the
//                controller stops on TARGET_LOST); a target `nearest` a point never seen yet: a
//                look pose search_distance back from the point, horizontally from the TCP; any
//                other target never seen yet while other objects of the list were: the same
//                look pose at the seen object nearest the TCP (the objects share a scene; a tag
//                too small in the image from afar is found on the way there; none seen: no
//                goal). A cloud target seen but without a qualifying candidate: the look pose at it (a
//                closer view), held until one qualifies; in APPROACH its last grasp holds while
//                no candidate qualifies
//   APPROACH     goal = the pre-grasp of the current best grasp (re-chosen as perception and
//                grasp candidates update; the controller's MPBS watches the object centre), so
//                the hand arrives from the approach side instead of cutting across the object;
//                base + arm drive. Ends when the TCP is within pregrasp_switch_distance of the
//                grasp position. A cloud target's choice judged unreachable: the goal is the
//                look pose at it instead (the hand camera keeps it in view while new views
//                come), unreachable_lock_wait from when the TCP is there, then that choice's
//                pre-grasp; a reachable one at any time is approached at once. tsmm (paper, section IV-D: "the robot first moves to a position
//                d away from the target object's position, measured from the end-effector"):
//                until the tsmm base stage has stopped the goal is the object centre itself
//                (with the grasp's orientation, which the base stage does not servo), so the
//                controller's tsmm_switch_distance d (0.2 m, horizontal) is measured from the
//                TCP to the object, not to the pre-grasp 0.1 m before it; from TSMM_ARM on the
//                goal is the pre-grasp again (0.1 m from the grasp, well within d of the switch
//                point: the base stays stopped) and the arm alone does the rest. The goal stays
//                the object centre, and the grasp is not locked (PRE_GRASP), until the controller
//                reports TSMM_ARM for that goal (an arm stage still on from the search pose, or
//                the lock's pre-grasp goal, would stop the base where it is, not at d)
//   PRE_GRASP    the grasp is locked in the world frame (the object is static until touched, and
//                the tag may leave the view at close range); goal = pre-grasp pose, tight tolerance
//   GRASP        goal = grasp pose; ends within grasp tolerance (or stalled near it, see
//                stall_time, never farther than max_close_offset; PRE_GRASP likewise)
//   CLOSE        gripper close command once; HOLDING -> LIFT, CLOSED_EMPTY -> failure
//   LIFT         goal = grasp pose raised by lift_height; the simulator's grasp result decides:
//                grasp_succeeded -> success, the object dropped -> failure
//   PLACE        (after a successful lift) goal = the grasp pose raised by place_height: the
//                object is put back where it stood before the gripper opens, until within
//                place_tolerance, stalled (stall_time) or place_timeout. Released at the lift
//                height instead, the demo's middle cylinder fell over, rolled against the back
//                box and the hand pushed both, the box 2.5 cm: the back grasp closed on nothing
//                (demo.sh seed 4009, ground truth recorded). place_timeout 0: no PLACE
//   RELEASE      (after PLACE, or after a failure) gripper open; until open or release_timeout
//   RETREAT      goal = the TCP pose at release, backed off along the approach and raised;
//                until within retreat_tolerance or retreat_timeout; then the next object
//   DONE         all objects handled: no goal any more (the controller stops on TARGET_LOST)
// WAIT_TARGET..LIFT of one object must finish within object_time_limit (30 s), else the object
// is failed with the phase it was in and the stall's cause (GraspResult::stall): in WAIT_TARGET
// target_not_seen (no perceived pose), else the controller's motion limit of the last cycle
// (/ehc/status motion_limit: a pinned joint, a link held at its stop distance from an obstacle,
// singular, slack saturated, base not moving, target out of view; none if nothing held it). Time = sim time (s). NaN/Inf inputs are rejected
// (counted); a non-finite or decreasing time throws "[GraspSequencer] ...".
//
// TfM of an object = fraction of cycles of the approach at a distance in which the object centre
// (objectCentre()) projects inside the camera image in front of the camera (camera pose from tf,
// ehc_control::PinholeCamera from camera_info; the in-view test and the counting are
// ehc_control::TargetTracker's, the controller's too: one tracker per window below, paused when
// its window closes). The approach at a distance runs from the object's first
// perceived pose until the arm takes over (/ehc/status sig(w) >= tfm_handover_sig: the target
// is within the arm's reach) or the pre-grasp switch (pregrasp_switch_distance from the grasp),
// whichever comes first. An approach that starts within reach (the next object on the same
// table: sig(w) at or above the threshold from its first cycle) counts whole, up to the switch. That is what MPBS is for (paper, Exp-3: the camera keeps the target
// in view while the robot is at a distance). Once sig(w) ~ 1, MPBS's desired pose is the grasp
// pose, and a grasp orientation that looks away from the object (a side grasp reached from
// the front) turns the camera away from it. tfm_until_switch counts until the pre-grasp
// switch whatever sig(w) is; tfm_until_close up to the gripper closing (closer, the hand
// camera, off the gripper axis, cannot see the object centre by geometry).
// Cycles without a camera pose are not counted. The controller's own in-FOV flag (/ehc/status)
// is reported as controller_tfm (from the first pose until the gripper closes).

#include "ehc_bringup/grasp_reach.h"
#include "ehc_bringup/grasp_selection.h"
#include "ehc_bringup/target_pose_filter.h"
#include "ehc_control/gripper_state.h"
#include "ehc_control/motion_limit.h"
#include "ehc_control/pinhole_camera.h"
#include "ehc_control/target_selector.h"
#include "ehc_control/target_tracker.h"
#include "ehc_perception/object_extent.h"

#include <Eigen/Geometry>

#include <array>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace ehc_common {
class ConfigNode;
}  // namespace ehc_common

namespace ehc_bringup {

enum class GraspPhase { WaitTarget, Approach, PreGrasp, Grasp, Close, Lift, Place, Release, Retreat, Done };
std::string toString(GraspPhase p);

struct GraspObjectSpec {
  std::string name;
  ApproachDirection approach = ApproachDirection::Forward;
  /// Which object it is (ehc_control::TargetSelector). Tag (the default): its poses come from
  /// the tag detector. A cloud kind: from the depth cloud (generateForCloudTarget, the object's
  /// cloud centre, ehc_control::cloudTargetPose), the grasp chosen with
  /// GraspSelectionParams::forCloudTarget(); the rest of the sequence is the same. Set by the
  /// scene's `targets:` (in-process) or the target selector topic (ehc_grasp_sequencer_node).
  ehc_control::TargetSelector target;
  /// m, the object's bounding box standing upright (x, y across, z up; a cylinder: diameter,
  /// diameter, height); zero = unknown. A tag object's known size: its exclusion (see
  /// obstacle_exclusion_margin) is this box upright round the perceived pose, its sides facing
  /// along the tag's normal, both across half extents the larger of x and y (which side face
  /// carries the tag is not known). A cloud target's extent comes from its cluster (setObjectExtent).
  Eigen::Vector3d size = Eigen::Vector3d::Zero();
};

struct GraspSequencerParams {
  std::vector<GraspObjectSpec> objects;
  double object_time_limit = 30.0;        ///< s, WAIT_TARGET..LIFT per object
  double perception_hold = 1.0;           ///< s: before the lock, an older pose -> WAIT_TARGET
  double search_distance = 0.40;          ///< m: look pose back along the approach (0 = off)
  /// deg below the horizon that a target without a tag is looked at from (its look pose is
  /// search_distance back along a view tilted down this much; a tag target's keeps its approach).
  /// From a level view a box in front of a 28 mm tool hid it ("no object in view"); from above,
  /// objects behind others are seen, and the view shows their tops, where top-down grasps go.
  double search_elevation_deg = 45.0;
  /// From GRASP (the descent from the pre-grasp) until the retreat ends the obstacle map ignores
  /// the object and the support right under it, which the fingers must touch; until then the
  /// object is an obstacle like any other. The ignored region is the object's extent (a tag
  /// object's `size`, a cloud target's cluster: setObjectExtent) grown by
  /// obstacle_exclusion_margin, so a neighbour's near face stays an obstacle
  /// (exclusionSpheres). Only an object whose extent is unknown gets the sphere of
  /// obstacle_exclusion_radius (m) round its centre.
  double obstacle_exclusion_radius = 0.10;
  /// m: at least the obstacle map's voxel size plus the largest stop distance of the gripper
  /// links (robot.obstacle_stop_distances): a finger touching the object keeps out of the
  /// object's own voxels' stop distance.
  double obstacle_exclusion_margin = 0.035;
  /// m: the support under the object is left out too (supportCap), in a disc reaching this far
  /// beyond the object's footprint, up to obstacle_exclusion_support_rise above the support: the
  /// fingers come down beside a low object onto it and the wrist passes over it (the robot's hand
  /// from the fingertips to its wrist link; the stop distances of the wrist links are 2-3 cm).
  /// 0: no support cap. See supportCap for the disc's largest radius.
  double obstacle_exclusion_support_reach = 0.20;
  /// m: at least the obstacle map's voxel size (the support's own voxels); a neighbour standing
  /// within the disc is an obstacle above this height.
  double obstacle_exclusion_support_rise = 0.02;
  /// Perceived poses: smoothing, and jumps held until confirmed (TargetPoseFilter, one per object).
  TargetPoseFilterParams pose_filter;
  double pregrasp_distance = 0.10;        ///< m, pre-grasp = grasp backed off along the approach
  double pregrasp_switch_distance = 0.25;  ///< m: APPROACH -> PRE_GRASP (TCP to grasp position)
  /// s in [0, 60]: with a reachability judgement (setReachability), while a cloud target's
  /// grasp is judged unreachable (none of the candidates reachable) the APPROACH goal is the
  /// look pose at it (search_distance, search_elevation_deg; none with search_distance 0 or
  /// under tsmm), for this long from when the TCP is within the switch distance of it (or of
  /// the grasp); then the unreachable grasp's pre-grasp, locked within the switch distance. The
  /// views meanwhile (a new view every grasp run) may bring a reachable candidate, approached and
  /// locked at once. The view lost meanwhile (WAIT_TARGET), the wait starts anew. Driving the
  /// arm towards a pre-grasp it cannot reach turned the hand camera away: the object ran out of
  /// its frame and no reachable candidate came. A robot already near the object (the next object
  /// of a scene) otherwise locked the first view's choice within ~1 s. A tag target locks at
  /// once, as the ROS sequencer node (no reachability judgement) does.
  double unreachable_lock_wait = 3.0;
  double pregrasp_position_tolerance = 0.015;     ///< m
  /// m: and the TCP within this of the approach axis through the pre-grasp, so that the straight
  /// move to the grasp brings the fingers in along the axis. A TCP that entered the position
  /// tolerance from the side (downward and sideways approaches come in across the axis) went on
  /// with 2-3 cm of lateral error; on the way in a finger then swept into a 5 cm box (1 cm of
  /// clearance a side in the 7 cm gripper) and pushed it away (Exp-3).
  double pregrasp_lateral_tolerance = 0.01;
  double pregrasp_orientation_tolerance_deg = 5.0;
  double grasp_position_tolerance = 0.01;         ///< m
  double grasp_orientation_tolerance_deg = 4.0;
  /// When the TCP has come no closer (by 2 mm) to the pre-grasp / grasp for stall_time, the
  /// controller has converged as far as its constraints allow (obstacle dampers near clutter,
  /// joint limits): within stall_tolerance_factor x the position tolerance (orientation
  /// within its tolerance) the sequencer goes on anyway and says so; otherwise it keeps waiting
  /// (the object time limit ends it). stall_time 0: off.
  double stall_time = 1.0;                ///< s
  double stall_tolerance_factor = 2.5;
  /// m: the gripper never closes farther than this from the locked grasp position, stalled or
  /// not (a grasp closed 2.4 cm short closed on nothing). A stall in GRASP beyond it
  /// keeps waiting; the object time limit then fails it and says how far the TCP stalled.
  double max_close_offset = 0.01;
  /// TfM counts the approach until sig(w) reaches this (the arm takes over), see above.
  /// (0, 1]; 1 = until the pre-grasp switch.
  double tfm_handover_sig = 0.5;
  double gripper_timeout = 3.0;           ///< s, CLOSE without HOLDING / CLOSED_EMPTY
  double lift_height = 0.15;              ///< m, above the grasp pose (> the sim's 0.10 m)
  double place_height = 0.005;            ///< m, PLACE: the grasp pose raised by this (the object just above its support)
  double place_tolerance = 0.01;          ///< m, PLACE ends within this of its pose
  double place_timeout = 4.0;             ///< s, PLACE ends after this at the latest; 0 = no PLACE
  double release_timeout = 2.0;           ///< s
  double retreat_distance = 0.12;         ///< m back along the approach
  double retreat_raise = 0.05;            ///< m up
  double retreat_tolerance = 0.04;        ///< m
  double retreat_timeout = 4.0;           ///< s
  GraspSelectionParams selection;
  /// The reachability judgement (GraspReach) that whoever runs the sequencer builds and sets
  /// (setReachability); `reach:` of the sequencer section.
  GraspReachParams reach;
  void validate() const;                  ///< throws "[GraspSequencerParams] ..."
  std::string summary() const;
};
/// Reads `sequencer:` (scalars, `selection:` child) and `objects:` (list of {name, approach})
/// from the node's YAML; errors name the file and the field.
GraspSequencerParams loadGraspSequencerParams(const ehc_common::ConfigNode& root);

/// Everything the sequencer reads each cycle (one controller status).
struct SequencerInput {
  double t = 0.0;                                  ///< sim time, s
  std::optional<Eigen::Isometry3d> tcp;            ///< TCP pose in the world (tf), if known
  std::optional<Eigen::Isometry3d> camera;         ///< camera optical frame in the world, if known
  std::string controller_phase;                    ///< /ehc/status phase ("" if none yet)
  bool target_in_fov = false;                      ///< /ehc/status target_in_fov
  std::optional<double> sig;                       ///< /ehc/status sig_omega, if any
  ehc_control::GripperState gripper_state = ehc_control::GripperState::Open;  ///< /sim/status gripper_state
  bool grasp_succeeded = false;                    ///< /sim/status grasp_succeeded
  ehc_control::MotionLimitReport motion_limit;     ///< /ehc/status motion_limit*
};

/// A sphere of the obstacle map to ignore (world).
struct ExclusionSphere {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double radius = 0.0;
};

using ehc_perception::ObjectExtent;
using ehc_perception::clusterExtent;

/// Spheres that together cover `box` grown by `margin` on every side (the exclusion spheres the
/// obstacle map takes): a row along its longest axis, each sphere the circumsphere of one slab
/// of the grown box, the slabs at most half as long as the cross-section's half diagonal (so
/// a sphere reaches at most ~3 % beyond the grown box across the row; along it, at its ends, by
/// the same). Empty for an invalid box.
std::vector<ExclusionSphere> exclusionSpheres(const ObjectExtent& box, double margin);

/// The sphere that leaves out the support under and round an upright `box` (its axis z = up, its
/// bottom face on the support): it cuts the support's top in a disc reaching `reach` beyond the
/// box's footprint (its half diagonal) and rises only `rise` above the support (its centre deep
/// below it). The fingers of a grasp low on the object come down beside it onto the support; a
/// neighbour standing on the support within the disc keeps all but its lowest `rise` an obstacle.
/// At most a 1 m sphere (the obstacle map's largest zone): the disc reaches at most
/// sqrt(2 x 1 m x rise - rise^2) from the object's axis (0.2 m for a 2 cm rise).
ExclusionSphere supportCap(const ObjectExtent& box, double reach, double rise);

struct SequencerOutput {
  std::optional<Eigen::Isometry3d> goal;           ///< TCP goal for the controller (publish it)
  /// Obstacle-map exclusions for this cycle (empty: none): from GRASP to the end of RETREAT the
  /// object where it was perceived and, once the gripper closes, where the hand carries it.
  std::vector<ExclusionSphere> exclusions;
  std::optional<Eigen::Isometry3d> object_pose;    ///< current object's filtered pose (grasp node)
  std::optional<bool> gripper_command;             ///< true = close, false = open (send once)
  std::vector<std::string> events;                 ///< progress lines
};

/// Why an object was not grasped, in one word (one string map): none (grasped), not_seen (no
/// pose before the time limit), no_target (perception named no target: setNoTarget), no_grasp (a
/// pose, but no grasp chosen: a cloud target or require_candidate without a qualifying
/// candidate), stalled (the time limit in a later phase: GraspResult::stall), closed_empty
/// (the gripper closed on nothing), gripper_timeout, dropped (lost while lifting).
enum class GraspCause { None, NotSeen, NoTarget, NoGrasp, Stalled, ClosedEmpty, GripperTimeout, Dropped };
std::string toString(GraspCause c);

struct GraspResult {
  std::string name;
  bool success = false;
  double time_s = 0.0;            ///< object start -> lift success (or failure)
  double tfm = 0.0;               ///< [0, 1], object centre in the image (see above)
  long cycles = 0;                ///< cycles counted for TfM
  double tfm_until_switch = 0.0;  ///< [0, 1], same test until the pre-grasp switch
  double tfm_until_close = 0.0;   ///< [0, 1], same test up to the gripper closing
  double controller_tfm = 0.0;    ///< [0, 1], /ehc/status target_in_fov over the same span
  std::string failed_phase;       ///< "" on success
  std::string reason;             ///< "" on success
  GraspCause cause = GraspCause::None;
  bool used_candidate = false;    ///< grasp from perception candidates (else the tag fallback)
  /// m, TCP position to the locked grasp position when the gripper was commanded to close;
  /// -1: it never closed. Above grasp_position_tolerance only after a stall (see stall_time).
  double close_offset = -1.0;
  std::string approach;           ///< wanted approach direction
  std::vector<std::pair<std::string, double>> phase_times;  ///< phase -> s spent
  std::vector<std::pair<std::string, long>> controller_phases;  ///< controller phase -> cycles
  /// The object's time limit fired (WAIT_TARGET..LIFT): `stall` names the cause (see above).
  bool timed_out = false;
  ehc_control::MotionLimitReport stall;
  /// obstacle: the body the obstacle point belongs to (GraspSequencer::setObstacleNamer), else "".
  std::string stall_body;
  /// "" unless timed out; else the cause's name, e.g. "joint_limit".
  std::string stallCause() const { return timed_out ? ehc_control::toString(stall.limit) : ""; }
  /// "" unless timed out; else what the cause names (MotionLimitReport::detail, the body if known).
  std::string stallDetail() const;
};

class GraspSequencer {
 public:
  explicit GraspSequencer(const GraspSequencerParams& params);  ///< validates

  /// Perceived pose of object `index` at time t (world), into the object's TargetPoseFilter
  /// (the current object's only until its grasp is locked): a far jump moves the object only
  /// once confirmed (an event says so, and one says when a jump was dropped as an outlier).
  /// Returns false (and counts it) if the index is unknown or the pose is not finite / not a
  /// rotation.
  bool setObjectPose(std::size_t index, double t, const Eigen::Isometry3d& pose);
  /// Latest grasp candidates (world). Non-finite candidates are dropped (counted).
  void setGraspCandidates(double t, const std::vector<GraspCandidate>& candidates);
  /// Sets object `index`'s target (e.g. from the target selector topic). False, and nothing
  /// changes, for an unknown index, an invalid selector (TargetSelector::validate), an object
  /// already handled, or the current one once its grasp is locked. A new target forgets the
  /// object's pose (it may name another object) and, for the current object, its candidates.
  bool setTarget(std::size_t index, const ehc_control::TargetSelector& target);
  /// Perception found no target for object `index` (a cloud target: no object in the view, fewer
  /// than k, ambiguous; TargetSelection::detail): an event when the reason changes, and the
  /// reason of the object's failure if its time limit fires before a pose arrives. An accepted
  /// pose (setObjectPose) clears it.
  void setNoTarget(std::size_t index, const std::string& why);
  /// Extent of object `index` (world): the obstacle map's exclusion from GRASP on follows it (see
  /// obstacle_exclusion_radius). Taken like a perceived pose: for the current object until its
  /// grasp is locked (then frozen), a later one any time. One view may show a part of the object
  /// only (a close view cuts it at the image's edge): an extent within obstacle_exclusion_margin
  /// of the one kept (ObjectExtent::holds) leaves it; any other replaces it (a whole view, the
  /// object moved). False (counted) for an unknown index or an invalid extent.
  bool setObjectExtent(std::size_t index, const ObjectExtent& extent);
  /// Camera intrinsics for TfM (e.g. from camera_info); false (ignored, counted) if invalid
  /// (PinholeCamera::validate). No TfM cycle is counted before the first valid camera.
  bool setCamera(const ehc_control::PinholeCamera& camera);
  /// Names the body an obstacle point (world) belongs to, for a stall held by an obstacle
  /// (GraspResult::stall_body); e.g. the simulator's scene. None: the point is reported.
  using ObstacleNamer = std::function<std::string(const Eigen::Vector3d&)>;
  void setObstacleNamer(ObstacleNamer namer) { namer_ = std::move(namer); }
  /// Whether the robot can reach a grasp and its pre-grasp (TCP poses, world), e.g.
  /// GraspReach::reachable with the robot's model and the support perceived: the grasp choice
  /// prefers reachable candidates (chooseGrasp). None (the default): the choice by score alone.
  using Reachability = std::function<bool(const Eigen::Isometry3d& grasp, const Eigen::Isometry3d& pre_grasp)>;
  void setReachability(Reachability reachable) { reachable_ = std::move(reachable); }
  /// The obstacle-map exclusions the current object will have in `phase` (before the gripper
  /// closes: up to CLOSE), as it is perceived now (its extent, else its pose): the zones
  /// SequencerOutput::exclusions then carries, for checking a planned configuration against the
  /// map as the controller will see it (GraspReach). Empty in a phase without exclusions or
  /// before the object has a pose.
  std::vector<ExclusionSphere> plannedExclusions(GraspPhase phase) const;

  /// One cycle. Throws "[GraspSequencer] ..." for a non-finite or decreasing time.
  SequencerOutput update(const SequencerInput& in);

  GraspPhase phase() const { return phase_; }
  bool done() const { return phase_ == GraspPhase::Done; }
  std::size_t currentObject() const { return current_; }
  const std::vector<GraspResult>& results() const { return results_; }
  long rejectedInputs() const { return rejected_; }
  /// Perceived poses dropped as outliers (far jumps not confirmed), every object.
  long poseOutliers() const;
  const GraspSequencerParams& params() const { return params_; }
  /// Locked grasp of the current object (PRE_GRASP onwards).
  const std::optional<GraspChoice>& lockedGrasp() const { return locked_; }
  /// The current object's last grasp chosen (APPROACH on; kept until the next object starts):
  /// the one the robot drove to when the object failed before its grasp was locked.
  const std::optional<GraspChoice>& lastChoice() const { return last_choice_; }
  /// Whether perceived poses and grasp candidates can change what the sequencer does: until the
  /// current object's grasp is locked. From the lock until the next object starts they would only
  /// refresh the remembered poses of later objects (the in-process pipeline then skips the image
  /// and the grasp generation: it renders only what perception consumes).
  bool wantsPerception() const { return !done() && !locked_; }
  /// Centre of the object being grasped, if any and up to LIFT: the origin of its perceived
  /// (filtered) pose, frozen where it was at the grasp lock. That pose is the tag node's target,
  /// which sits at the object centre (its grasp_offset), so this is MpbsServo::targetCentre of
  /// the object pose with a zero offset; MPBS's own fallback applies its offset to the
  /// controller's goal (pre-grasp, grasp, lift pose), hence this centre is published on
  /// /ehc/target_centre. The one centre TfM and the node use.
  std::optional<Eigen::Vector3d> objectCentre() const;

 private:
  void startObject(double t, SequencerOutput* out);
  /// The phase logic of one cycle (update() without the bookkeeping and the time limit).
  void advance(const SequencerInput& in, SequencerOutput* out);
  // One function per phase (advance()'s cases): `fresh` = the object pose is younger than
  // perception_hold, `in_phase` = s since the phase began, `centre_was_sent` = last cycle's
  // goal was the object centre (tsmm).
  void advanceWaitTarget(const SequencerInput& in, bool fresh, SequencerOutput* out);
  void advanceApproach(const SequencerInput& in, bool fresh, bool centre_was_sent, SequencerOutput* out);
  void advancePreGrasp(const SequencerInput& in, SequencerOutput* out);
  void advanceGrasp(const SequencerInput& in, SequencerOutput* out);
  void advanceClose(const SequencerInput& in, double in_phase, SequencerOutput* out);
  void advanceLift(const SequencerInput& in, double in_phase, SequencerOutput* out);
  void advancePlace(const SequencerInput& in, double in_phase, SequencerOutput* out);
  void advanceRelease(const SequencerInput& in, double in_phase, SequencerOutput* out);
  void advanceRetreat(const SequencerInput& in, double in_phase, SequencerOutput* out);
  /// SequencerOutput::exclusions for the phase reached this cycle (every cycle, whatever ended it).
  std::vector<ExclusionSphere> obstacleExclusions(const SequencerInput& in) const;
  /// Whether the object is left out of the obstacle map in phase `p`.
  static bool excludesObject(GraspPhase p);
  /// The exclusion of an object standing with `extent` (else a sphere round `centre`).
  std::vector<ExclusionSphere> standingExclusions(const std::optional<ObjectExtent>& extent,
                                                  const Eigen::Vector3d& centre) const;
  void enter(GraspPhase p, double t, SequencerOutput* out, const std::string& why = "");
  void finishObject(double t, bool success, const std::string& reason, const SequencerInput& in,
                    SequencerOutput* out);
  /// Enters RELEASE: holds the TCP where it is (hold_goal_) and opens the gripper.
  void startRelease(double t, const SequencerInput& in, SequencerOutput* out, const std::string& why);
  std::optional<GraspChoice> currentChoice(const SequencerInput& in) const;
  /// Position of the other object (not the current one) nearest `from` whose pose was ever
  /// perceived; nullopt if none.
  std::optional<Eigen::Vector3d> nearestSeenObject(const Eigen::Vector3d& from) const;
  Eigen::Isometry3d preGrasp(const Eigen::Isometry3d& grasp) const;
  Eigen::Isometry3d placePose() const;  ///< PLACE goal: the locked grasp raised by place_height
  /// APPROACH goal: the pre-grasp of `grasp`; the object centre while the controller is in the
  /// tsmm base stage (see the header comment).
  /// Until the tsmm base stage has stopped d from the object (tsmm_at_d_).
  Eigen::Isometry3d approachGoal(const SequencerInput& in, const Eigen::Isometry3d& grasp);
  /// The controller runs tsmm (reports one of its stages).
  static bool tsmmController(const SequencerInput& in);
  bool within(const SequencerInput& in, const Eigen::Isometry3d& goal, double pos, double ori_deg) const;
  std::string label() const;
  std::array<ehc_control::TargetTracker*, 3> tfmWindows();  ///< the three TfM trackers
  /// Updates the best distance to `goal` in this phase; true when it has not improved for
  /// stall_time.
  bool stalled(const SequencerInput& in, const Eigen::Isometry3d& goal);
  bool nearEnoughWhenStalled(const SequencerInput& in, const Eigen::Isometry3d& goal, double pos, double ori_deg);

  GraspSequencerParams params_;
  GraspPhase phase_ = GraspPhase::WaitTarget;
  std::size_t current_ = 0;
  bool started_ = false;
  double last_t_ = -1.0;
  double object_t0_ = 0.0, phase_t0_ = 0.0;
  double best_distance_ = 1e9, best_distance_t_ = 0.0;  ///< stall detection, per phase
  // perception of the current object
  /// Every object's perceived pose (the last one seen: the search pose of WAIT_TARGET).
  std::vector<TargetPoseFilter> filters_;
  /// Time of the current object's last perceived pose that the filter took in since the object
  /// started (-1: none yet); until then the object has no current pose (currentPose()).
  double object_pose_t_ = -1.0;
  std::optional<Eigen::Isometry3d> currentPose() const;
  std::vector<std::string> pose_events_;  ///< from setObjectPose, out with the next update
  std::string no_target_;  ///< the current object's setNoTarget reason ("" = none / a pose came)
  std::vector<GraspCandidate> candidates_;
  double candidates_t_ = -1.0;  ///< time stamp of candidates_ (GraspChoice::candidates_t)
  std::optional<GraspChoice> locked_;
  std::optional<GraspChoice> last_choice_;  ///< the current object's last grasp chosen before the lock
  Eigen::Vector3d locked_object_centre_ = Eigen::Vector3d::Zero();
  /// Every object's extent (setObjectExtent, or its size round its perceived pose).
  std::vector<std::optional<ObjectExtent>> extents_;
  /// The current object's extent frozen at the lock (nullopt: unknown, the sphere) and its pose
  /// in the TCP frame when the gripper closed (the object moves with the hand).
  std::optional<ObjectExtent> locked_extent_;
  std::optional<Eigen::Isometry3d> extent_in_tcp_;
  /// The current object's extent now: setObjectExtent's, else its size round its pose.
  std::optional<ObjectExtent> currentExtent() const;
  /// Object centre in the TCP frame when the gripper closed (the object moves with the hand).
  std::optional<Eigen::Vector3d> centre_in_tcp_;
  std::optional<Eigen::Isometry3d> hold_goal_;  ///< RELEASE / RETREAT goal
  Eigen::Vector3d last_approach_ = Eigen::Vector3d::UnitX();
  bool centre_sent_ = false;  ///< this cycle's goal is the object centre (tsmm base stage)
  bool tsmm_at_d_ = false;    ///< tsmm: the arm stage began with the centre as the goal (base stopped at d)
  /// Since when the choice within the switch distance has been judged unreachable (< 0: not).
  double unreachable_since_ = -1.0;
  // bookkeeping
  GraspResult cur_;
  // TfM windows (see the header comment), one tracker each: until the arm takes over (tfm),
  // until the pre-grasp switch, until the gripper closes.
  ehc_control::TargetTracker tfm_distant_{ehc_control::PinholeCamera{}, ehc_control::TargetTrackerParams{}};
  ehc_control::TargetTracker tfm_switch_{ehc_control::PinholeCamera{}, ehc_control::TargetTrackerParams{}};
  ehc_control::TargetTracker tfm_close_{ehc_control::PinholeCamera{}, ehc_control::TargetTrackerParams{}};
  bool has_camera_ = false;   ///< a valid camera was set
  bool was_distant_ = false;  ///< a cycle of this approach had sig(w) below tfm_handover_sig
  long ctrl_fov_cycles_ = 0, ctrl_cycles_ = 0;
  bool counting_tfm_ = true;
  std::string last_controller_phase_;
  std::vector<GraspResult> results_;
  long rejected_ = 0;
  ObstacleNamer namer_;
  Reachability reachable_;
  /// The stall's cause when the object's time limit fires in the current phase (see above).
  void recordStall(const SequencerInput& in);
  /// The current object's pose came within perception_hold of `t`.
  bool targetSeenRecently(double t) const;
};

/// JSON summary: {"mode": ..., "objects": [{"name", "success", "time_s", "tfm", ...}], "successes": n,
/// "total_time_s": t}.
std::string graspResultsToJson(const std::vector<GraspResult>& results, const std::string& mode,
                               double total_time_s);
/// One human-readable line per object.
std::string graspResultLine(const GraspResult& r);

}  // namespace ehc_bringup
