#include "ehc_bringup/grasp_sequencer.h"

#include "ehc_common/config_node.h"
#include "ehc_common/text_format.h"
#include "ehc_control/control_status.h"
#include "ehc_common/enum_names.h"
#include "ehc_common/json.h"
#include "ehc_control/pose_math.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>

using ehc_common::ConfigNode;

namespace ehc_bringup {

using ehc_control::GripperState;

namespace {
constexpr ehc_common::EnumNames<GraspPhase, 10> kGraspPhaseNames = {{{GraspPhase::WaitTarget, "WAIT_TARGET"},
                                                                      {GraspPhase::Approach, "APPROACH"},
                                                                      {GraspPhase::PreGrasp, "PRE_GRASP"},
                                                                      {GraspPhase::Grasp, "GRASP"},
                                                                      {GraspPhase::Close, "CLOSE"},
                                                                      {GraspPhase::Lift, "LIFT"},
                                                                      {GraspPhase::Place, "PLACE"},
                                                                      {GraspPhase::Release, "RELEASE"},
                                                                      {GraspPhase::Retreat, "RETREAT"},
                                                                      {GraspPhase::Done, "DONE"}}};
}  // namespace

std::string toString(GraspPhase p) { return ehc_common::enumName(kGraspPhaseNames, p, "GraspSequencer"); }

namespace {
constexpr ehc_common::EnumNames<GraspCause, 8> kGraspCauseNames = {{
    {GraspCause::None, "none"},
    {GraspCause::NotSeen, "not_seen"},
    {GraspCause::NoTarget, "no_target"},
    {GraspCause::NoGrasp, "no_grasp"},
    {GraspCause::Stalled, "stalled"},
    {GraspCause::ClosedEmpty, "closed_empty"},
    {GraspCause::GripperTimeout, "gripper_timeout"},
    {GraspCause::Dropped, "dropped"},
}};
}  // namespace

std::string toString(GraspCause c) { return ehc_common::enumName(kGraspCauseNames, c, "GraspSequencer"); }

namespace {
std::string num(double v, int precision = 3) { return ehc_common::fixedDecimals(v, precision); }

/// Whether /ehc/status's phase is one that zeroes the command (a stall then is the controller's,
/// not what the motion limit names: an infeasible QP held the robot still for good).
bool controllerStopped(const std::string& phase) {
  using ehc_control::ControlPhase;
  for (ControlPhase p : {ControlPhase::Stopped, ControlPhase::TargetLost, ControlPhase::QpFailed, ControlPhase::ObstaclesStale})
    if (phase == ehc_control::toString(p)) return true;
  return false;
}

/// A cloud target's look pose: its pose (ehc_control::cloudTargetPose, z horizontal from the
/// viewpoint) turned about its horizontal y axis so that z points `elevation_deg` below the
/// horizon, then backed off `distance` along it: the camera looks down on the object from
/// distance x sin(elevation) above it.
Eigen::Isometry3d cloudLookPose(Eigen::Isometry3d pose, double distance, double elevation_deg) {
  const Eigen::Vector3d z = pose.linear().col(2);
  Eigen::Vector3d level(z.x(), z.y(), 0.0);
  if (level.norm() > 1e-6) {
    const double e = elevation_deg * M_PI / 180.0;
    const Eigen::Vector3d down = std::cos(e) * level.normalized() - std::sin(e) * Eigen::Vector3d::UnitZ();
    pose.linear() = Eigen::Quaterniond::FromTwoVectors(z, down).toRotationMatrix() * pose.linear();
  }
  return backedOff(pose, distance);
}
}  // namespace

// ---------------------------------------------------------------- parameters

void GraspSequencerParams::validate() const {
  auto check = [](bool ok, const std::string& what) {
    if (!ok) throw std::invalid_argument("[GraspSequencerParams] " + what);
  };
  auto positive = [&](double v, const std::string& name) {
    check(std::isfinite(v) && v > 0.0, name + " must be a finite number > 0 (is " + std::to_string(v) + ")");
  };
  check(!objects.empty(), "objects must list at least one object");
  for (std::size_t i = 0; i < objects.size(); ++i) {
    check(!objects[i].name.empty(), "objects[" + std::to_string(i) + "].name must not be empty");
    objects[i].target.validate();
    check(objects[i].size.allFinite() && objects[i].size.minCoeff() >= 0.0 && objects[i].size.maxCoeff() <= 2.0,
          "objects[" + std::to_string(i) + "].size must be finite, each in [0, 2] m");
    for (std::size_t j = 0; j < i; ++j)
      check(objects[i].name != objects[j].name, "object name '" + objects[i].name + "' appears twice");
  }
  positive(object_time_limit, "object_time_limit");
  positive(perception_hold, "perception_hold");
  check(std::isfinite(obstacle_exclusion_radius) && obstacle_exclusion_radius >= 0.0 && obstacle_exclusion_radius <= 0.5,
        "obstacle_exclusion_radius must be in [0, 0.5] m");
  check(std::isfinite(obstacle_exclusion_margin) && obstacle_exclusion_margin >= 0.0 && obstacle_exclusion_margin <= 0.2,
        "obstacle_exclusion_margin must be in [0, 0.2] m");
  check(std::isfinite(obstacle_exclusion_support_reach) && obstacle_exclusion_support_reach >= 0.0 &&
            obstacle_exclusion_support_reach <= 0.5,
        "obstacle_exclusion_support_reach must be in [0, 0.5] m");
  check(std::isfinite(obstacle_exclusion_support_rise) && obstacle_exclusion_support_rise > 0.0 &&
            obstacle_exclusion_support_rise <= 0.1,
        "obstacle_exclusion_support_rise must be in (0, 0.1] m");
  check(std::isfinite(search_distance) && search_distance >= 0.0 && search_distance <= 2.0,
        "search_distance must be in [0, 2] m");
  check(std::isfinite(search_elevation_deg) && search_elevation_deg >= 0.0 && search_elevation_deg <= 80.0,
        "search_elevation_deg must be in [0, 80] deg");
  pose_filter.validate();
  check(std::isfinite(pregrasp_distance) && pregrasp_distance >= 0.0 && pregrasp_distance <= 0.5,
        "pregrasp_distance must be in [0, 0.5] m");
  positive(pregrasp_switch_distance, "pregrasp_switch_distance");
  check(std::isfinite(unreachable_lock_wait) && unreachable_lock_wait >= 0.0 && unreachable_lock_wait <= 60.0,
        "unreachable_lock_wait must be in [0, 60] s");
  check(std::isfinite(stall_time) && stall_time >= 0.0 && stall_time <= 30.0, "stall_time must be in [0, 30] s");
  check(std::isfinite(stall_tolerance_factor) && stall_tolerance_factor >= 1.0 && stall_tolerance_factor <= 10.0,
        "stall_tolerance_factor must be in [1, 10]");
  check(std::isfinite(max_close_offset) && max_close_offset > 0.0 && max_close_offset <= 0.05,
        "max_close_offset must be in (0, 0.05] m");
  check(std::isfinite(tfm_handover_sig) && tfm_handover_sig > 0.0 && tfm_handover_sig <= 1.0,
        "tfm_handover_sig must be in (0, 1]");
  positive(pregrasp_position_tolerance, "pregrasp_position_tolerance");
  // APPROACH heads for the pre-grasp and ends within pregrasp_switch_distance of the grasp:
  // a TCP at the pre-grasp (within its tolerance) must be inside that distance.
  check(pregrasp_switch_distance > pregrasp_distance + pregrasp_position_tolerance,
        "pregrasp_switch_distance (" + num(pregrasp_switch_distance, 3) + " m) must be > pregrasp_distance + "
        "pregrasp_position_tolerance (" + num(pregrasp_distance + pregrasp_position_tolerance, 3) +
        " m): the approach heads for the pre-grasp and would never switch");
  positive(pregrasp_orientation_tolerance_deg, "pregrasp_orientation_tolerance_deg");
  check(std::isfinite(pregrasp_lateral_tolerance) && pregrasp_lateral_tolerance > 0.0 &&
            pregrasp_lateral_tolerance <= pregrasp_position_tolerance,
        "pregrasp_lateral_tolerance must be in (0, pregrasp_position_tolerance]");
  positive(grasp_position_tolerance, "grasp_position_tolerance");
  positive(grasp_orientation_tolerance_deg, "grasp_orientation_tolerance_deg");
  positive(gripper_timeout, "gripper_timeout");
  positive(lift_height, "lift_height");
  check(std::isfinite(place_height) && place_height >= 0.0 && place_height <= 0.1, "place_height must be in [0, 0.1] m");
  positive(place_tolerance, "place_tolerance");
  check(std::isfinite(place_timeout) && place_timeout >= 0.0 && place_timeout <= 30.0,
        "place_timeout must be in [0, 30] s (0 = release where lifted)");
  positive(release_timeout, "release_timeout");
  check(std::isfinite(retreat_distance) && retreat_distance >= 0.0, "retreat_distance must be >= 0");
  check(std::isfinite(retreat_raise) && retreat_raise >= 0.0, "retreat_raise must be >= 0");
  positive(retreat_tolerance, "retreat_tolerance");
  positive(retreat_timeout, "retreat_timeout");
  selection.validate();
  reach.validate();
}

std::string GraspSequencerParams::summary() const {
  std::ostringstream s;
  s << "GraspSequencer: " << objects.size() << " object(s):";
  for (const auto& o : objects)
    s << " " << o.name << " (" << toString(o.approach) << (o.target.fromCloud() ? ", " + o.target.summary() : std::string()) << ")";
  s << "\n  limit " << object_time_limit << " s/object, perception hold " << perception_hold
    << " s, search " << search_distance << " m (a cloud target from " << search_elevation_deg
    << " deg above), obstacle exclusion: the object's extent + "
    << obstacle_exclusion_margin << " m and its support " << obstacle_exclusion_support_reach << " m round it, "
    << obstacle_exclusion_support_rise << " m up (extent unknown: " << obstacle_exclusion_radius << " m round its centre), " << pose_filter.summary() << ", pre-grasp " << pregrasp_distance << " m"
    << "\n  pre-grasp from " << pregrasp_switch_distance << " m (a grasp judged unreachable locked after "
    << unreachable_lock_wait << " s there); tolerances: pre-grasp " << pregrasp_position_tolerance << " m/" << pregrasp_orientation_tolerance_deg
    << " deg (" << pregrasp_lateral_tolerance << " m across the approach), grasp " << grasp_position_tolerance << " m/" << grasp_orientation_tolerance_deg << " deg"
    << " (stalled for " << stall_time << " s: x" << stall_tolerance_factor << "; the gripper closes within "
    << max_close_offset << " m)"
    << "; TfM until sig(w) >= " << tfm_handover_sig << " or the pre-grasp switch"
    << "\n  gripper timeout " << gripper_timeout << " s, lift " << lift_height << " m, place "
    << (place_timeout > 0.0 ? "back " + num(place_height, 3) + " m above the grasp (tol " + num(place_tolerance, 3) + " m, " +
                                  num(place_timeout, 1) + " s)"
                            : std::string("off"))
    << ", release timeout "
    << release_timeout << " s, retreat " << retreat_distance << " m back + " << retreat_raise << " m up (tol "
    << retreat_tolerance << " m, " << retreat_timeout << " s)"
    << "\n  selection: gate " << selection.candidate_gate << " m (cloud targets " << selection.cloud_candidate_gate << " m"
    << (selection.cloud_any_approach ? ", the generator's approach when none as preferred" : "") << "), max angle " << selection.max_angle_deg
    << " deg, max width " << selection.max_width << " m, "
    << "sideways turned " << selection.sideways_turn_deg << " deg towards forward and tilted "
    << selection.sideways_tilt_deg << " deg down, "
    << (selection.align_approach ? "candidates aligned to the approach, " : "")
    << (selection.centre_from_tag ? "centred on the tag target across the approach, " : "")
    << (selection.closing_axis_from_tag ? "closing along a tag target axis, " : "")
    << (selection.require_candidate ? "candidate required" : "tag fallback") << " (backoff forward "
    << selection.fallback_backoff_forward << ", downward " << selection.fallback_backoff_downward
    << ", sideways " << selection.fallback_backoff_sideways << " m), reachability: the best "
    << selection.reach_checks << " judged per choice"
    << "\n  " << reach.summary();
  return s.str();
}

GraspSequencerParams loadGraspSequencerParams(const ConfigNode& root) {
  GraspSequencerParams p;
  const ConfigNode s = root.childOrEmpty("sequencer");
  p.object_time_limit = s.get("object_time_limit", p.object_time_limit);
  p.perception_hold = s.get("perception_hold", p.perception_hold);
  p.search_distance = s.get("search_distance", p.search_distance);
  p.search_elevation_deg = s.get("search_elevation_deg", p.search_elevation_deg);
  p.obstacle_exclusion_radius = s.get("obstacle_exclusion_radius", p.obstacle_exclusion_radius);
  p.obstacle_exclusion_margin = s.get("obstacle_exclusion_margin", p.obstacle_exclusion_margin);
  p.obstacle_exclusion_support_reach = s.get("obstacle_exclusion_support_reach", p.obstacle_exclusion_support_reach);
  p.obstacle_exclusion_support_rise = s.get("obstacle_exclusion_support_rise", p.obstacle_exclusion_support_rise);
  p.pose_filter = loadTargetPoseFilterParams(s);
  p.pregrasp_distance = s.get("pregrasp_distance", p.pregrasp_distance);
  p.pregrasp_switch_distance = s.get("pregrasp_switch_distance", p.pregrasp_switch_distance);
  p.unreachable_lock_wait = s.get("unreachable_lock_wait", p.unreachable_lock_wait);
  p.stall_time = s.get("stall_time", p.stall_time);
  p.stall_tolerance_factor = s.get("stall_tolerance_factor", p.stall_tolerance_factor);
  p.max_close_offset = s.get("max_close_offset", p.max_close_offset);
  p.tfm_handover_sig = s.get("tfm_handover_sig", p.tfm_handover_sig);
  p.pregrasp_position_tolerance = s.get("pregrasp_position_tolerance", p.pregrasp_position_tolerance);
  p.pregrasp_lateral_tolerance = s.get("pregrasp_lateral_tolerance", p.pregrasp_lateral_tolerance);
  p.pregrasp_orientation_tolerance_deg = s.get("pregrasp_orientation_tolerance_deg", p.pregrasp_orientation_tolerance_deg);
  p.grasp_position_tolerance = s.get("grasp_position_tolerance", p.grasp_position_tolerance);
  p.grasp_orientation_tolerance_deg = s.get("grasp_orientation_tolerance_deg", p.grasp_orientation_tolerance_deg);
  p.gripper_timeout = s.get("gripper_timeout", p.gripper_timeout);
  p.lift_height = s.get("lift_height", p.lift_height);
  p.place_height = s.get("place_height", p.place_height);
  p.place_tolerance = s.get("place_tolerance", p.place_tolerance);
  p.place_timeout = s.get("place_timeout", p.place_timeout);
  p.release_timeout = s.get("release_timeout", p.release_timeout);
  p.retreat_distance = s.get("retreat_distance", p.retreat_distance);
  p.retreat_raise = s.get("retreat_raise", p.retreat_raise);
  p.retreat_tolerance = s.get("retreat_tolerance", p.retreat_tolerance);
  p.retreat_timeout = s.get("retreat_timeout", p.retreat_timeout);
  const ConfigNode sel = s.childOrEmpty("selection");
  p.selection.candidate_gate = sel.get("candidate_gate", p.selection.candidate_gate);
  p.selection.cloud_candidate_gate = sel.get("cloud_candidate_gate", p.selection.cloud_candidate_gate);
  p.selection.cloud_any_approach = sel.get("cloud_any_approach", p.selection.cloud_any_approach);
  p.selection.max_angle_deg = sel.get("max_angle_deg", p.selection.max_angle_deg);
  p.selection.max_width = sel.get("max_width", p.selection.max_width);
  p.selection.require_candidate = sel.get("require_candidate", p.selection.require_candidate);
  p.selection.align_approach = sel.get("align_approach", p.selection.align_approach);
  p.selection.centre_from_tag = sel.get("centre_from_tag", p.selection.centre_from_tag);
  p.selection.closing_axis_from_tag = sel.get("closing_axis_from_tag", p.selection.closing_axis_from_tag);
  p.selection.sideways_turn_deg = sel.get("sideways_turn_deg", p.selection.sideways_turn_deg);
  p.selection.sideways_tilt_deg = sel.get("sideways_tilt_deg", p.selection.sideways_tilt_deg);
  p.selection.fallback_backoff_forward = sel.get("fallback_backoff_forward", p.selection.fallback_backoff_forward);
  p.selection.fallback_backoff_downward = sel.get("fallback_backoff_downward", p.selection.fallback_backoff_downward);
  p.selection.fallback_backoff_sideways = sel.get("fallback_backoff_sideways", p.selection.fallback_backoff_sideways);
  p.selection.reach_checks = sel.get("reach_checks", p.selection.reach_checks);
  p.reach = loadGraspReachParams(s.childOrEmpty("reach"));

  if (!root.has("objects")) root.fail("objects", "is required: a list of {name, approach}");
  for (std::size_t i = 0; i < root.listSize("objects"); ++i) {
    const ConfigNode o = root.element("objects", i);
    GraspObjectSpec spec;
    spec.name = o.require<std::string>("name");
    const std::string a = o.get<std::string>("approach", "forward");
    try {
      spec.approach = approachDirectionFromString(a);
    } catch (const std::invalid_argument&) {
      o.fail("approach", "must be tag | forward | downward | sideways | any (is '" + a + "')");
    }
    spec.size = o.getVector("size", Eigen::Vector3d::Zero(), 3);
    p.objects.push_back(spec);
  }
  root.validate(p);
  return p;
}

// ---------------------------------------------------------------- state machine

GraspSequencer::GraspSequencer(const GraspSequencerParams& params) : params_(params) {
  params_.validate();
  filters_.assign(params_.objects.size(), TargetPoseFilter(params_.pose_filter));
  extents_.assign(params_.objects.size(), std::nullopt);
}

bool GraspSequencer::setObjectExtent(std::size_t index, const ObjectExtent& extent) {
  if (index >= params_.objects.size() || !extent.valid()) {
    ++rejected_;
    return false;
  }
  if (index == current_ && locked_) return true;  // frozen at the lock
  // A view may show a part of the object only (a close view cuts it at the image's edge): a box
  // the one kept holds (within the margin the exclusion grows it by) leaves it; another replaces it.
  if (extents_[index] && extents_[index]->holds(extent, params_.obstacle_exclusion_margin)) return true;
  extents_[index] = extent;
  return true;
}

std::optional<ObjectExtent> GraspSequencer::currentExtent() const {
  if (current_ >= extents_.size()) return std::nullopt;
  if (extents_[current_]) return extents_[current_];
  const Eigen::Vector3d& size = params_.objects[current_].size;
  const std::optional<Eigen::Isometry3d> pose = currentPose();
  if (!pose || size.minCoeff() <= 0.0) return std::nullopt;
  // Known size round the perceived pose (the tag target: origin at the object centre, z into the
  // tagged face, a face normal): upright, turned so that its sides face along z's horizontal
  // part (x's when z is vertical: a tag on the top face). Which side face carries the tag is not
  // known here: both across half extents are the larger.
  const Eigen::Matrix3d& R = pose->linear();
  Eigen::Vector3d f(R(0, 2), R(1, 2), 0.0);
  if (f.norm() < 0.3) f = Eigen::Vector3d(R(0, 0), R(1, 0), 0.0);
  if (f.norm() < 1e-6) f = Eigen::Vector3d::UnitX();
  f.normalize();
  ObjectExtent e;
  e.pose.linear().col(0) = f;
  e.pose.linear().col(1) = Eigen::Vector3d::UnitZ().cross(f);
  e.pose.linear().col(2) = Eigen::Vector3d::UnitZ();
  e.pose.translation() = pose->translation();
  const double across = 0.5 * std::max(size.x(), size.y());
  e.half_extents = Eigen::Vector3d(across, across, 0.5 * size.z());
  return e;
}

bool GraspSequencer::setObjectPose(std::size_t index, double t, const Eigen::Isometry3d& pose) {
  if (index >= params_.objects.size() || !std::isfinite(t) || !isValidPose(pose)) {
    ++rejected_;
    return false;
  }
  const bool current = index == current_ && !done();
  if (current && locked_) return true;  // grasp locked: perception no longer moves it
  TargetPoseFilter& f = filters_[index];
  const std::optional<Eigen::Isometry3d> before = f.pose();
  const long outliers = f.outliers();
  const TargetPoseFilter::Update u = f.add(pose);
  const std::string name = params_.objects[index].name;
  if (f.outliers() > outliers)
    pose_events_.push_back(name + ": " + std::to_string(f.outliers() - outliers) +
                           " perceived pose(s) far from the object ignored (not confirmed by " +
                           std::to_string(params_.pose_filter.jump_confirmations) + " in a row)");
  if (u == TargetPoseFilter::Update::JumpConfirmed)
    pose_events_.push_back(name + ": perceived pose moved " +
                           num((f.pose()->translation() - before->translation()).norm(), 3) + " m, confirmed by " +
                           std::to_string(params_.pose_filter.jump_confirmations) + " observations in a row");
  if (current && u != TargetPoseFilter::Update::JumpHeld) object_pose_t_ = t;
  if (current) no_target_.clear();
  return true;
}

bool GraspSequencer::setTarget(std::size_t index, const ehc_control::TargetSelector& target) {
  if (index >= params_.objects.size() || done() || index < current_ || (index == current_ && locked_)) return false;
  try {
    target.validate();
  } catch (const std::invalid_argument&) {
    return false;
  }
  GraspObjectSpec& o = params_.objects[index];
  if (o.target.summary() == target.summary() && o.target.ambiguity == target.ambiguity) return true;
  o.target = target;
  filters_[index].reset();
  if (index == current_) {
    object_pose_t_ = -1.0;
    candidates_.clear();
    no_target_.clear();
  }
  pose_events_.push_back(o.name + ": target " + target.summary());
  return true;
}

void GraspSequencer::setNoTarget(std::size_t index, const std::string& why) {
  if (index != current_ || done() || locked_ || why == no_target_) return;
  no_target_ = why;
  pose_events_.push_back(params_.objects[index].name + ": no target: " + why);
}

long GraspSequencer::poseOutliers() const {
  long n = 0;
  for (const TargetPoseFilter& f : filters_) n += f.outliers();
  return n;
}

std::optional<Eigen::Isometry3d> GraspSequencer::currentPose() const {
  if (object_pose_t_ < 0.0 || done()) return std::nullopt;
  return filters_[current_].pose();
}

std::optional<Eigen::Vector3d> GraspSequencer::objectCentre() const {
  if (done() || phase_ > GraspPhase::Lift) return std::nullopt;
  if (locked_) return locked_object_centre_;
  if (const auto pose = currentPose()) return pose->translation();
  return std::nullopt;
}

bool GraspSequencer::setCamera(const ehc_control::PinholeCamera& camera) {
  try {
    camera.validate();
  } catch (const std::invalid_argument&) {
    ++rejected_;
    return false;
  }
  for (ehc_control::TargetTracker* t : tfmWindows()) t->setCamera(camera);
  has_camera_ = true;
  return true;
}

void GraspSequencer::setGraspCandidates(double t, const std::vector<GraspCandidate>& candidates) {
  if (locked_) return;
  candidates_t_ = t;
  candidates_.clear();
  for (const auto& c : candidates) {
    if (isValidPose(c.pose) && std::isfinite(c.width) && std::isfinite(c.score)) candidates_.push_back(c);
    else ++rejected_;
  }
}

std::array<ehc_control::TargetTracker*, 3> GraspSequencer::tfmWindows() {
  return {&tfm_distant_, &tfm_switch_, &tfm_close_};
}

std::string GraspSequencer::label() const {
  return current_ < params_.objects.size() ? params_.objects[current_].name : std::string("-");
}

void GraspSequencer::startObject(double t, SequencerOutput* out) {
  // Perception of this object may have arrived before its first cycle: kept (cleared when the
  // previous object is left).
  object_t0_ = t;
  locked_.reset();
  centre_in_tcp_.reset();
  locked_extent_.reset();
  extent_in_tcp_.reset();
  hold_goal_.reset();
  centre_sent_ = tsmm_at_d_ = false;
  unreachable_since_ = -1.0;
  ctrl_fov_cycles_ = ctrl_cycles_ = 0;
  for (ehc_control::TargetTracker* t : tfmWindows()) t->reset();
  was_distant_ = false;
  counting_tfm_ = true;
  cur_ = GraspResult();
  cur_.name = params_.objects[current_].name;
  cur_.approach = toString(params_.objects[current_].approach);
  no_target_.clear();
  last_choice_.reset();
  last_controller_phase_.clear();
  phase_ = GraspPhase::WaitTarget;
  phase_t0_ = t;
  std::ostringstream s;
  s << "object " << (current_ + 1) << "/" << params_.objects.size() << " '" << cur_.name << "' ("
    << cur_.approach << " grasp" << (params_.objects[current_].target.fromCloud() ? ", " + params_.objects[current_].target.summary() : std::string())
    << "): WAIT_TARGET";
  out->events.push_back(s.str());
}

void GraspSequencer::enter(GraspPhase p, double t, SequencerOutput* out, const std::string& why) {
  if (phase_ != GraspPhase::Done && phase_ <= GraspPhase::Lift && current_ < params_.objects.size())
    cur_.phase_times.emplace_back(toString(phase_), t - phase_t0_);
  std::ostringstream s;
  s << label() << ": " << toString(phase_) << " -> " << toString(p) << " at " << std::fixed
    << std::setprecision(2) << (t - object_t0_) << " s";
  if (!why.empty()) s << " (" << why << ")";
  out->events.push_back(s.str());
  phase_ = p;
  phase_t0_ = t;
  best_distance_ = 1e9;
  best_distance_t_ = t;
}

bool GraspSequencer::stalled(const SequencerInput& in, const Eigen::Isometry3d& goal) {
  if (!in.tcp || !isValidPose(*in.tcp)) return false;
  const double d = (in.tcp->translation() - goal.translation()).norm();
  if (d < best_distance_ - 0.002) {
    best_distance_ = d;
    best_distance_t_ = in.t;
  }
  return params_.stall_time > 0.0 && in.t - best_distance_t_ >= params_.stall_time;
}

bool GraspSequencer::nearEnoughWhenStalled(const SequencerInput& in, const Eigen::Isometry3d& goal, double pos,
                                           double ori_deg) {
  return stalled(in, goal) && within(in, goal, params_.stall_tolerance_factor * pos, ori_deg);
}

Eigen::Isometry3d GraspSequencer::preGrasp(const Eigen::Isometry3d& grasp) const {
  return backedOff(grasp, params_.pregrasp_distance);
}

Eigen::Isometry3d GraspSequencer::approachGoal(const SequencerInput& in, const Eigen::Isometry3d& grasp) {
  const std::optional<Eigen::Vector3d> centre = objectCentre();
  if (!centre || !tsmmController(in) || tsmm_at_d_) return preGrasp(grasp);
  Eigen::Isometry3d T = grasp;  // the base stage drives the TCP position only
  T.translation() = *centre;
  centre_sent_ = true;
  return T;
}

bool GraspSequencer::tsmmController(const SequencerInput& in) {
  return in.controller_phase == ehc_control::toString(ehc_control::ControlPhase::TsmmBase) ||
         in.controller_phase == ehc_control::toString(ehc_control::ControlPhase::TsmmArm);
}

bool GraspSequencer::within(const SequencerInput& in, const Eigen::Isometry3d& goal, double pos,
                            double ori_deg) const {
  if (!in.tcp || !isValidPose(*in.tcp)) return false;
  return (in.tcp->translation() - goal.translation()).norm() <= pos &&
         ehc_control::rotationAngle(in.tcp->linear(), goal.linear()) <= ori_deg * M_PI / 180.0;
}

std::optional<GraspChoice> GraspSequencer::currentChoice(const SequencerInput& in) const {
  const std::optional<Eigen::Isometry3d> object_pose = currentPose();
  if (!object_pose) return std::nullopt;
  const Eigen::Matrix3d ref = (in.tcp && isValidPose(*in.tcp)) ? Eigen::Matrix3d(in.tcp->linear())
                                                              : Eigen::Matrix3d(object_pose->linear());
  const GraspObjectSpec& o = params_.objects[current_];
  GraspReachable reachable;
  if (reachable_) reachable = [this](const Eigen::Isometry3d& g) { return reachable_(g, preGrasp(g)); };
  std::optional<GraspChoice> choice = chooseGrasp(candidates_, o.approach, *object_pose, ref,
                                                  o.target.fromCloud() ? params_.selection.forCloudTarget() : params_.selection,
                                                  reachable);
  if (choice && choice->from_candidate) choice->candidates_t = candidates_t_;
  return choice;
}

void GraspSequencer::finishObject(double t, bool success, const std::string& reason,
                                  const SequencerInput& in, SequencerOutput* out) {
  cur_.success = success;
  cur_.time_s = t - object_t0_;
  cur_.failed_phase = success ? "" : toString(phase_);
  cur_.reason = reason;
  if (success) cur_.cause = GraspCause::None;
  else if (phase_ == GraspPhase::WaitTarget)
    cur_.cause = object_pose_t_ >= 0.0 ? GraspCause::NoGrasp : !no_target_.empty() ? GraspCause::NoTarget : GraspCause::NotSeen;
  else if (cur_.timed_out) cur_.cause = GraspCause::Stalled;
  else if (phase_ == GraspPhase::Close)
    cur_.cause = in.gripper_state == ehc_control::GripperState::ClosedEmpty ? GraspCause::ClosedEmpty : GraspCause::GripperTimeout;
  else cur_.cause = GraspCause::Dropped;
  cur_.cycles = tfm_distant_.cycles();
  cur_.tfm = tfm_distant_.tfm();
  cur_.tfm_until_switch = tfm_switch_.tfm();
  cur_.tfm_until_close = tfm_close_.tfm();
  cur_.controller_tfm = ctrl_cycles_ > 0 ? static_cast<double>(ctrl_fov_cycles_) / static_cast<double>(ctrl_cycles_) : 0.0;
  cur_.used_candidate = locked_ ? locked_->from_candidate : false;
  // RETREAT backs off along this approach.
  if (locked_) last_approach_ = locked_->pose.linear().col(2);
  else if (in.tcp && isValidPose(*in.tcp)) last_approach_ = in.tcp->linear().col(2);
  const bool place = success && locked_ && params_.place_timeout > 0.0;
  const std::string why = success ? "grasp succeeded" : "FAILED: " + reason;
  if (place) enter(GraspPhase::Place, t, out, why);
  else startRelease(t, in, out, why);
  results_.push_back(cur_);
  out->events.push_back(graspResultLine(cur_));
  if (place) out->goal = placePose();
}

void GraspSequencer::startRelease(double t, const SequencerInput& in, SequencerOutput* out, const std::string& why) {
  // RELEASE holds the TCP where it is; RETREAT backs off along the approach from there.
  hold_goal_ = (in.tcp && isValidPose(*in.tcp)) ? std::optional<Eigen::Isometry3d>(*in.tcp) : std::nullopt;
  enter(GraspPhase::Release, t, out, why);
  if (in.gripper_state != GripperState::Open) out->gripper_command = false;
}

Eigen::Isometry3d GraspSequencer::placePose() const {
  Eigen::Isometry3d T = locked_->pose;
  T.translation().z() += params_.place_height;
  return T;
}

SequencerOutput GraspSequencer::update(const SequencerInput& in) {
  if (!std::isfinite(in.t)) throw std::invalid_argument("[GraspSequencer] non-finite time");
  if (in.t < last_t_) {
    std::ostringstream s;
    s << "[GraspSequencer] time went backwards (" << in.t << " s after " << last_t_ << " s)";
    throw std::invalid_argument(s.str());
  }
  last_t_ = in.t;
  SequencerOutput out;
  out.events.swap(pose_events_);  // what setObjectPose saw since the last cycle
  if (!started_) {
    started_ = true;
    startObject(in.t, &out);
  }
  if (done()) return out;
  const double t = in.t;
  const double in_object = t - object_t0_;

  // Controller phase bookkeeping (counts per phase; tsmm stages and stops show as events).
  if (phase_ <= GraspPhase::Lift) {
    const std::string cp = in.controller_phase.empty() ? "NONE" : in.controller_phase;
    auto it = std::find_if(cur_.controller_phases.begin(), cur_.controller_phases.end(),
                           [&](const auto& e) { return e.first == cp; });
    if (it == cur_.controller_phases.end()) cur_.controller_phases.emplace_back(cp, 1);
    else ++it->second;
    if (cp != last_controller_phase_ && !last_controller_phase_.empty())
      out.events.push_back(label() + ": controller " + last_controller_phase_ + " -> " + cp);
    last_controller_phase_ = cp;
    if (counting_tfm_ && object_pose_t_ >= 0.0) {
      if (!in.controller_phase.empty()) {
        ++ctrl_cycles_;
        if (in.target_in_fov) ++ctrl_fov_cycles_;
      }
      if (in.camera && has_camera_) {
        if (locked_) {  // the approach ended at the pre-grasp switch
          tfm_switch_.pause();
          tfm_distant_.pause();
        } else {
          // The arm takes over: sig(w) rises to the threshold. An approach that starts within
          // reach (the next object on the same table) has no distant part: it counts whole.
          const bool within_reach = in.sig && *in.sig >= params_.tfm_handover_sig;
          if (!within_reach) was_distant_ = true;
          else if (was_distant_) tfm_distant_.pause();
        }
        const Eigen::Vector3d centre = *objectCentre();  // up to LIFT: there is one
        for (ehc_control::TargetTracker* t : tfmWindows()) {
          t->moveTarget(centre);
          t->observe(*in.camera);
        }
      }
    }
  }

  // Time limit per object.
  if (phase_ <= GraspPhase::Lift && in_object > params_.object_time_limit) {
    std::ostringstream s;
    s << "time limit " << params_.object_time_limit << " s in " << toString(phase_);
    if (locked_ && in.tcp && isValidPose(*in.tcp) && (phase_ == GraspPhase::PreGrasp || phase_ == GraspPhase::Grasp)) {
      const Eigen::Isometry3d goal = phase_ == GraspPhase::Grasp ? locked_->pose : preGrasp(locked_->pose);
      s << " (TCP " << num((in.tcp->translation() - goal.translation()).norm() * 100.0, 1) << " cm from the "
        << (phase_ == GraspPhase::Grasp ? "grasp" : "pre-grasp") << ", " << num(t - best_distance_t_, 1)
        << " s since it last came closer)";
    }
    if (phase_ == GraspPhase::WaitTarget && !no_target_.empty()) s << " (no target: " << no_target_ << ")";
    if (phase_ == GraspPhase::WaitTarget && targetSeenRecently(t)) s << " (target seen, no grasp chosen)";
    recordStall(in);
    s << "; stall: " << cur_.stallCause();
    const std::string detail = cur_.stallDetail();
    if (!detail.empty()) s << " (" << detail << ")";
    if (controllerStopped(in.controller_phase)) s << "; the controller stopped: " << in.controller_phase;
    finishObject(t, false, s.str(), in, &out);
  } else {
    advance(in, &out);
  }
  // Every path, the time limit's too: the exclusion must not lapse for a cycle while the hand
  // is still at the object (a failed descent's RELEASE; the obstacle map would show the object
  // under the fingers, inside their stop distance).
  out.exclusions = obstacleExclusions(in);
  return out;
}

bool GraspSequencer::targetSeenRecently(double t) const {
  return object_pose_t_ >= 0.0 && t - object_pose_t_ <= params_.perception_hold;
}

void GraspSequencer::recordStall(const SequencerInput& in) {
  cur_.timed_out = true;
  cur_.stall = in.motion_limit;
  cur_.stall_body.clear();
  if (phase_ == GraspPhase::WaitTarget) {
    // Perception has no recent pose of the object: that is the cause. With a recent pose nothing
    // held the robot back: no grasp was chosen from its views (cause no_grasp, stall none).
    cur_.stall = ehc_control::MotionLimitReport{};
    if (!targetSeenRecently(in.t)) {
      cur_.stall.limit = ehc_control::MotionLimit::TargetNotSeen;
      cur_.stall.value = in.t - std::max(object_t0_, object_pose_t_);
    }
  } else if (cur_.stall.limit == ehc_control::MotionLimit::Obstacle && namer_) {
    cur_.stall_body = namer_(cur_.stall.obstacle_point);
  }
}

std::string GraspResult::stallDetail() const {
  if (!timed_out) return "";
  if (stall.limit == ehc_control::MotionLimit::Obstacle && !stall_body.empty()) {
    std::ostringstream s;
    s << stall.link << " held at its stop distance from " << stall_body << " (d_s " << (stall.value < 0.0 ? "- " : "+ ")
      << num(std::abs(stall.value), 3) << " m)";
    return s.str();
  }
  return stall.detail();
}

void GraspSequencer::advance(const SequencerInput& in, SequencerOutput* out) {
  const double t = in.t;
  const double in_phase = t - phase_t0_;
  const bool centre_was_sent = centre_sent_;  // the goal of the last cycle (tsmm, see Approach)
  centre_sent_ = false;
  const std::optional<Eigen::Isometry3d> object_pose = currentPose();
  const bool fresh = object_pose && (t - object_pose_t_) <= params_.perception_hold;
  if (object_pose && !locked_) out->object_pose = *object_pose;

  switch (phase_) {
    case GraspPhase::WaitTarget: advanceWaitTarget(in, fresh, out); break;
    case GraspPhase::Approach: advanceApproach(in, fresh, centre_was_sent, out); break;
    case GraspPhase::PreGrasp: advancePreGrasp(in, out); break;
    case GraspPhase::Grasp: advanceGrasp(in, out); break;
    case GraspPhase::Close: advanceClose(in, in_phase, out); break;
    case GraspPhase::Lift: advanceLift(in, in_phase, out); break;
    case GraspPhase::Place: advancePlace(in, in_phase, out); break;
    case GraspPhase::Release: advanceRelease(in, in_phase, out); break;
    case GraspPhase::Retreat: advanceRetreat(in, in_phase, out); break;
    case GraspPhase::Done: break;
  }
}

std::optional<Eigen::Vector3d> GraspSequencer::nearestSeenObject(const Eigen::Vector3d& from) const {
  std::optional<Eigen::Vector3d> best;
  for (std::size_t i = 0; i < filters_.size(); ++i) {
    const std::optional<Eigen::Isometry3d>& seen = filters_[i].pose();
    if (i == current_ || !seen) continue;
    if (!best || (seen->translation() - from).norm() < (*best - from).norm()) best = seen->translation();
  }
  return best;
}

void GraspSequencer::advanceWaitTarget(const SequencerInput& in, bool fresh, SequencerOutput* out) {
  const double t = in.t;
  if (!fresh) {
    const std::optional<Eigen::Isometry3d>& seen = filters_[current_].pose();  // now or before this object
    const ehc_control::TargetSelector& target = params_.objects[current_].target;
    if (seen && params_.search_distance > 0.0) {
      out->goal = target.fromCloud() ? cloudLookPose(*seen, params_.search_distance, params_.search_elevation_deg)
                                     : backedOff(*seen, params_.search_distance);
    } else if (target.kind == ehc_control::TargetSelectorKind::Nearest && params_.search_distance > 0.0 && in.tcp &&
               isValidPose(*in.tcp)) {
      // Never seen, but where to look is known: a look pose at the point, from the TCP's side.
      out->goal = cloudLookPose(ehc_control::cloudTargetPose(target.point, in.tcp->translation()),
                                params_.search_distance, params_.search_elevation_deg);
    } else if (params_.search_distance > 0.0 && in.tcp && isValidPose(*in.tcp)) {
      // Never seen, but other objects of the list were: a look pose at the one nearest the TCP,
      // from the TCP's side. The objects share a scene, and a target too small to find in the
      // image from afar (a tag at ~2 px per cell) is found on the way there; without a goal the
      // robot waited where it could not see it until the time limit.
      if (const auto near = nearestSeenObject(in.tcp->translation()))
        out->goal = backedOff(ehc_control::cloudTargetPose(*near, in.tcp->translation()), params_.search_distance);
    }
    return;
  }
  const auto choice = currentChoice(in);
  if (!choice) {  // require_candidate (a cloud target) and none yet
    if (params_.objects[current_].target.fromCloud() && params_.search_distance > 0.0) {
      // A cloud target seen but no grasp from this view: a closer look (a view that shows its
      // graspable parts), held until a grasp qualifies or the time limit fails it (no_grasp).
      out->goal = cloudLookPose(*currentPose(), params_.search_distance, params_.search_elevation_deg);
    }
    return;
  }
  last_choice_ = choice;
  enter(GraspPhase::Approach, t, out,
        choice->from_candidate ? "grasp candidate" : "tag grasp (no candidate yet)");
  out->goal = approachGoal(in, choice->pose);
}

void GraspSequencer::advanceApproach(const SequencerInput& in, bool fresh, bool centre_was_sent, SequencerOutput* out) {
  const double t = in.t;
  if (!fresh) {  // perception lost: search again
    unreachable_since_ = -1.0;  // the views after it count anew
    enter(GraspPhase::WaitTarget, t, out, "object pose older than " + num(params_.perception_hold, 1) + " s");
    return;
  }
  std::optional<GraspChoice> choice = currentChoice(in);
  // A cloud target's candidates come and go with the views (no tag fallback): the last grasp
  // chosen holds until another qualifies; without a goal the controller would stop the robot
  // (TARGET_LOST) where no new view comes.
  if (choice) last_choice_ = choice;
  else if (params_.objects[current_].target.fromCloud()) choice = last_choice_;
  if (!choice) return;
  // tsmm: the base has stopped d from the object once the controller reports its arm stage
  // for the object centre sent as the goal. No lock before: the lock makes the pre-grasp the
  // goal, which ended the base stage where the lock happened (0.25 m from the grasp, 3-D:
  // ~0.24-0.29 m horizontally from a middle or back object), or never started it when the arm
  // stage of the search pose was still on (the arm alone then stalled 1-3 cm short).
  if (centre_was_sent && in.controller_phase == ehc_control::toString(ehc_control::ControlPhase::TsmmArm))
    tsmm_at_d_ = true;
  // A cloud target's choice judged unreachable: the look pose for unreachable_lock_wait from
  // when the TCP is there or near the grasp, then the choice's pre-grasp (why: the header's
  // unreachable_lock_wait). Without a look pose (search_distance 0, or tsmm, whose stages keep
  // their goals) the wait runs within the switch distance. A tag target locks at once, as over
  // ROS (no judgement there).
  const bool tsmm = tsmmController(in);
  const bool unreachable = params_.objects[current_].target.fromCloud() && choice->reachable && !*choice->reachable;
  std::optional<Eigen::Isometry3d> look;
  if (unreachable && params_.search_distance > 0.0 && !tsmm)
    look = cloudLookPose(*currentPose(), params_.search_distance, params_.search_elevation_deg);
  const bool tsmm_base_pending = tsmm && !tsmm_at_d_;
  const bool near_grasp = !tsmm_base_pending && within(in, choice->pose, params_.pregrasp_switch_distance, 180.0);
  if (!unreachable) unreachable_since_ = -1.0;
  else if (unreachable_since_ < 0.0 && (near_grasp || (look && within(in, *look, params_.pregrasp_switch_distance, 180.0))))
    unreachable_since_ = t;
  const bool waiting = unreachable && (unreachable_since_ < 0.0 || t - unreachable_since_ < params_.unreachable_lock_wait);
  out->goal = look && waiting ? *look : approachGoal(in, choice->pose);
  if (near_grasp && !waiting) {
    locked_object_centre_ = *objectCentre();  // frozen from here (before locked_ is set)
    locked_extent_ = currentExtent();
    locked_ = choice;
    out->goal = preGrasp(choice->pose);
    enter(GraspPhase::PreGrasp, t, out,
          std::string("grasp locked: ") + (choice->from_candidate ? "perception candidate" : "tag fallback") +
              (choice->reachable ? (*choice->reachable ? ", reachable" : ", judged unreachable (none reachable after " + num(params_.unreachable_lock_wait, 1) + " s)") : ""));
  }
}

void GraspSequencer::advancePreGrasp(const SequencerInput& in, SequencerOutput* out) {
  const double t = in.t;
  const Eigen::Isometry3d pre = preGrasp(locked_->pose);
  out->goal = pre;
  // Lateral: the TCP's offset across the approach axis (the grasp's z) through the pre-grasp
  // (within() has checked the TCP).
  const auto lateral = [&](double factor) {
    const Eigen::Vector3d e = in.tcp->translation() - pre.translation();
    const Eigen::Vector3d axis = pre.linear().col(2);
    return (e - e.dot(axis) * axis).norm() <= factor * params_.pregrasp_lateral_tolerance;
  };
  const bool there = within(in, pre, params_.pregrasp_position_tolerance, params_.pregrasp_orientation_tolerance_deg) &&
                     lateral(1.0);
  if (there || (nearEnoughWhenStalled(in, pre, params_.pregrasp_position_tolerance,
                                      params_.pregrasp_orientation_tolerance_deg) &&
                lateral(params_.stall_tolerance_factor))) {
    enter(GraspPhase::Grasp, t, out,
          there ? "" : "stalled " + num((in.tcp->translation() - pre.translation()).norm() * 100.0, 1) +
                           " cm from the pre-grasp: going on");
    out->goal = locked_->pose;
  }
}

void GraspSequencer::advanceGrasp(const SequencerInput& in, SequencerOutput* out) {
  const double t = in.t;
  out->goal = locked_->pose;
  const bool there = within(in, locked_->pose, params_.grasp_position_tolerance, params_.grasp_orientation_tolerance_deg);
  const double stall_tolerance =
      std::min(params_.stall_tolerance_factor * params_.grasp_position_tolerance, params_.max_close_offset) /
      params_.stall_tolerance_factor;
  if (there || nearEnoughWhenStalled(in, locked_->pose, stall_tolerance, params_.grasp_orientation_tolerance_deg)) {
    enter(GraspPhase::Close, t, out,
          there ? "" : "stalled " + num((in.tcp->translation() - locked_->pose.translation()).norm() * 100.0, 1) +
                           " cm from the grasp: closing there");
    counting_tfm_ = false;
    out->gripper_command = true;
    cur_.close_offset = (in.tcp->translation() - locked_->pose.translation()).norm();
    centre_in_tcp_ = in.tcp->inverse() * locked_object_centre_;  // within() checked the TCP
    if (locked_extent_) extent_in_tcp_ = in.tcp->inverse() * locked_extent_->pose;
  }
}

void GraspSequencer::advanceClose(const SequencerInput& in, double in_phase, SequencerOutput* out) {
  const double t = in.t;
  out->goal = locked_->pose;
  if (in.gripper_state == GripperState::Holding) {
    enter(GraspPhase::Lift, t, out, "object held");
    Eigen::Isometry3d lift = locked_->pose;
    lift.translation().z() += params_.lift_height;
    out->goal = lift;
  } else if (in.gripper_state == GripperState::ClosedEmpty) {
    finishObject(t, false, "gripper closed on nothing", in, out);
  } else if (in_phase > params_.gripper_timeout) {
    finishObject(t, false, "gripper did not close within " + std::to_string(params_.gripper_timeout) + " s (state '" +
                               toString(in.gripper_state) + "')", in, out);
  }
}

void GraspSequencer::advanceLift(const SequencerInput& in, double in_phase, SequencerOutput* out) {
  const double t = in.t;
  Eigen::Isometry3d lift = locked_->pose;
  lift.translation().z() += params_.lift_height;
  out->goal = lift;
  if (in.grasp_succeeded && in.gripper_state == GripperState::Holding) {
    finishObject(t, true, "", in, out);
  } else if (in.gripper_state != GripperState::Holding && in_phase > 0.0) {
    finishObject(t, false, "object lost while lifting (gripper '" + toString(in.gripper_state) + "')", in, out);
  }
}

void GraspSequencer::advancePlace(const SequencerInput& in, double in_phase, SequencerOutput* out) {
  const double t = in.t;
  const Eigen::Isometry3d place = placePose();
  out->goal = place;
  const bool there = within(in, place, params_.place_tolerance, 180.0);
  const bool dropped = in.gripper_state != GripperState::Holding;
  if (there || dropped || stalled(in, place) || in_phase > params_.place_timeout) {
    std::string why = there ? "placed" : dropped ? "object no longer held" : "placing stopped";
    if (!there && !dropped && in.tcp && isValidPose(*in.tcp))
      why += " " + num((in.tcp->translation() - place.translation()).norm() * 100.0, 1) + " cm from its place";
    startRelease(t, in, out, why);
    if (hold_goal_) out->goal = *hold_goal_;
  }
}

void GraspSequencer::advanceRelease(const SequencerInput& in, double in_phase, SequencerOutput* out) {
  const double t = in.t;
  if (hold_goal_) out->goal = *hold_goal_;
  if (in.gripper_state == GripperState::Open || in_phase > params_.release_timeout) {
    if (hold_goal_) {
      Eigen::Isometry3d back = *hold_goal_;
      back.translation() -= params_.retreat_distance * last_approach_;
      back.translation().z() += params_.retreat_raise;
      hold_goal_ = back;
      out->goal = back;
    }
    enter(GraspPhase::Retreat, t, out);
  }
}

void GraspSequencer::advanceRetreat(const SequencerInput& in, double in_phase, SequencerOutput* out) {
  const double t = in.t;
  if (hold_goal_) out->goal = *hold_goal_;
  const bool there = hold_goal_ && in.tcp && isValidPose(*in.tcp) &&
                     (in.tcp->translation() - hold_goal_->translation()).norm() <= params_.retreat_tolerance;
  if (there || !hold_goal_ || in_phase > params_.retreat_timeout) {
    if (current_ + 1 < params_.objects.size()) {
      enter(GraspPhase::WaitTarget, t, out);
      ++current_;
      object_pose_t_ = -1.0;
      candidates_.clear();
      startObject(t, out);
    } else {
      enter(GraspPhase::Done, t, out);
      out->goal.reset();
      int ok = 0;
      for (const auto& r : results_) ok += r.success ? 1 : 0;
      out->events.push_back("all objects handled: " + std::to_string(ok) + "/" +
                           std::to_string(results_.size()) + " grasped");
    }
  }
}

bool GraspSequencer::excludesObject(GraspPhase p) {
  // The object may be touched from the descent on (GRASP) until the hand has left it (RETREAT).
  return p >= GraspPhase::Grasp && p <= GraspPhase::Retreat;
}

std::vector<ExclusionSphere> GraspSequencer::standingExclusions(const std::optional<ObjectExtent>& extent,
                                                                const Eigen::Vector3d& centre) const {
  std::vector<ExclusionSphere> zones;
  if (extent) {
    zones = exclusionSpheres(*extent, params_.obstacle_exclusion_margin);
    if (params_.obstacle_exclusion_support_reach > 0.0)
      zones.push_back(supportCap(*extent, params_.obstacle_exclusion_support_reach, params_.obstacle_exclusion_support_rise));
  } else if (params_.obstacle_exclusion_radius > 0.0) {
    zones.push_back({centre, params_.obstacle_exclusion_radius});
  }
  return zones;
}

std::vector<ExclusionSphere> GraspSequencer::obstacleExclusions(const SequencerInput& in) const {
  if (!locked_ || !excludesObject(phase_)) return {};
  // Where it stood, and once closed where the hand carries it: its extent + the margin.
  std::vector<ExclusionSphere> zones = standingExclusions(locked_extent_, locked_object_centre_);
  if (!centre_in_tcp_ || !in.tcp || !isValidPose(*in.tcp)) return zones;
  if (locked_extent_ && extent_in_tcp_) {
    ObjectExtent moved = *locked_extent_;
    moved.pose = *in.tcp * *extent_in_tcp_;
    const std::vector<ExclusionSphere> more = exclusionSpheres(moved, params_.obstacle_exclusion_margin);
    zones.insert(zones.end(), more.begin(), more.end());
  } else if (!locked_extent_ && params_.obstacle_exclusion_radius > 0.0) {
    zones.push_back({*in.tcp * *centre_in_tcp_, params_.obstacle_exclusion_radius});
  }
  return zones;
}

std::vector<ExclusionSphere> GraspSequencer::plannedExclusions(GraspPhase phase) const {
  if (!excludesObject(phase) || phase > GraspPhase::Close) return {};
  if (locked_) return standingExclusions(locked_extent_, locked_object_centre_);
  const std::optional<Eigen::Vector3d> centre = objectCentre();
  if (!centre) return {};
  return standingExclusions(currentExtent(), *centre);
}

std::vector<ExclusionSphere> exclusionSpheres(const ObjectExtent& box, double margin) {
  std::vector<ExclusionSphere> out;
  if (!box.valid() || !std::isfinite(margin) || margin < 0.0) return out;
  const Eigen::Vector3d h = box.half_extents + Eigen::Vector3d::Constant(margin);
  int k = 0;  // the longest axis: the row
  h.maxCoeff(&k);
  const double across = std::hypot(h((k + 1) % 3), h((k + 2) % 3));  // cross-section's half diagonal
  // n slabs of half length h_k / n <= across / 2; each sphere the circumsphere of its slab.
  const int n = std::max(1, static_cast<int>(std::ceil(2.0 * h(k) / std::max(across, 1e-3))));
  const double half_slab = h(k) / n;
  const double radius = std::hypot(across, half_slab);
  const Eigen::Vector3d axis = box.pose.linear().col(k);
  for (int i = 0; i < n; ++i) {
    const double along = -h(k) + (2 * i + 1) * half_slab;
    out.push_back({box.pose.translation() + along * axis, radius});
  }
  return out;
}

ExclusionSphere supportCap(const ObjectExtent& box, double reach, double rise) {
  const Eigen::Vector3d up = box.pose.linear().col(2);
  const double disc = std::hypot(box.half_extents.x(), box.half_extents.y()) + std::max(reach, 0.0);
  const double h = std::max(rise, 1e-3);
  // R - depth = h (the rise), R^2 - depth^2 = disc^2 (the disc on the support's top).
  // At most 1 m (the obstacle map's largest zone): a smaller disc, never a higher rise.
  const double radius = std::min(0.5 * (disc * disc / h + h), 1.0);
  return {box.pose.translation() - (box.half_extents.z() + radius - h) * up, radius};
}

// ---------------------------------------------------------------- reporting

std::string graspResultsToJson(const std::vector<GraspResult>& results, const std::string& mode,
                               double total_time_s) {
  using ehc_common::jsonNumber;
  int ok = 0;
  for (const auto& r : results) ok += r.success ? 1 : 0;
  ehc_common::Json j;
  j["mode"] = mode;
  j["successes"] = ok;
  j["objects_total"] = results.size();
  j["total_time_s"] = jsonNumber(total_time_s);
  j["objects"] = ehc_common::Json::array();
  for (const GraspResult& r : results) {
    ehc_common::Json o;
    o["name"] = r.name;
    o["success"] = r.success;
    o["time_s"] = jsonNumber(r.time_s);
    o["tfm"] = jsonNumber(r.tfm);
    o["tfm_cycles"] = r.cycles;
    o["tfm_until_switch"] = jsonNumber(r.tfm_until_switch);
    o["tfm_until_close"] = jsonNumber(r.tfm_until_close);
    o["controller_tfm"] = jsonNumber(r.controller_tfm);
    o["approach"] = r.approach;
    o["grasp_from_candidate"] = r.used_candidate;
    o["failed_phase"] = r.failed_phase;
    o["reason"] = r.reason;
    o["stall_cause"] = r.stallCause();
    o["stall_joint"] = r.timed_out ? r.stall.joint : "";
    o["stall_link"] = r.timed_out ? r.stall.link : "";
    o["stall_body"] = r.stall_body;
    o["stall_detail"] = r.stallDetail();
    o["close_offset_m"] = jsonNumber(r.close_offset);
    ehc_common::Json& phases = o["phase_times"] = ehc_common::Json::object();
    for (const auto& [phase, time] : r.phase_times) phases[phase] = jsonNumber(time);
    ehc_common::Json& cycles = o["controller_phase_cycles"] = ehc_common::Json::object();
    for (const auto& [phase, n] : r.controller_phases) cycles[phase] = n;
    j["objects"].push_back(o);
  }
  return ehc_common::jsonLine(j);
}

std::string graspResultLine(const GraspResult& r) {
  std::ostringstream s;
  s << std::left << std::setw(8) << r.name << " " << (r.success ? "SUCCESS" : "FAILED ") << "  time "
    << std::right << std::fixed << std::setprecision(2) << std::setw(6) << r.time_s << " s  TfM " << std::setprecision(1)
    << std::setw(5) << 100.0 * r.tfm << " % (" << std::setw(5) << 100.0 * r.tfm_until_switch
    << " % to the pre-grasp switch)  grasp " << (r.used_candidate ? "perception candidate" : "tag fallback")
    << " (" << r.approach << ")";
  if (r.close_offset >= 0.0) s << "  closed " << std::setprecision(1) << 1000.0 * r.close_offset << " mm from the grasp";
  if (!r.success) s << "  [" << r.failed_phase << ": " << r.reason << "]";
  return s.str();
}

}  // namespace ehc_bringup
