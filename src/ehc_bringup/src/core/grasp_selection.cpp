#include "ehc_bringup/grasp_selection.h"

#include "ehc_common/enum_names.h"
#include "ehc_control/pose_math.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace ehc_bringup {

namespace {
constexpr ehc_common::EnumNames<ApproachDirection, 5> kApproachNames = {{{ApproachDirection::Tag, "tag"},
                                                                          {ApproachDirection::Forward, "forward"},
                                                                          {ApproachDirection::Downward, "downward"},
                                                                          {ApproachDirection::Sideways, "sideways"},
                                                                          {ApproachDirection::Any, "any"}}};
}  // namespace

std::string toString(ApproachDirection d) { return ehc_common::enumName(kApproachNames, d, "GraspSelection"); }

ApproachDirection approachDirectionFromString(const std::string& s) {
  return ehc_common::enumValue(kApproachNames, s, "GraspSelection", "approach direction");
}

GraspSelectionParams GraspSelectionParams::forCloudTarget() const {
  GraspSelectionParams p = *this;
  p.candidate_gate = cloud_candidate_gate;
  p.centre_from_tag = false;
  p.closing_axis_from_tag = false;
  p.require_candidate = true;
  p.any_approach_fallback = cloud_any_approach;
  return p;
}

void GraspSelectionParams::validate() const {
  auto check = [](bool ok, const std::string& what) {
    if (!ok) throw std::invalid_argument("[GraspSelectionParams] " + what);
  };
  check(std::isfinite(candidate_gate) && candidate_gate > 0.0, "candidate_gate must be > 0");
  check(std::isfinite(cloud_candidate_gate) && cloud_candidate_gate > 0.0, "cloud_candidate_gate must be > 0");
  check(std::isfinite(max_angle_deg) && max_angle_deg > 0.0 && max_angle_deg <= 180.0,
        "max_angle_deg must be in (0, 180]");
  check(std::isfinite(max_width) && max_width > 0.0, "max_width must be > 0");
  check(std::isfinite(sideways_turn_deg) && sideways_turn_deg >= 0.0 && sideways_turn_deg <= 60.0,
        "sideways_turn_deg must be in [0, 60] (0 = straight from the side)");
  check(std::isfinite(sideways_tilt_deg) && sideways_tilt_deg >= 0.0 && sideways_tilt_deg <= 60.0,
        "sideways_tilt_deg must be in [0, 60] (0 = horizontal)");
  check(reach_checks >= 0 && reach_checks <= 50, "reach_checks must be in [0, 50] (0 = no reachability judgement)");
  for (double b : {fallback_backoff_forward, fallback_backoff_downward, fallback_backoff_sideways})
    check(std::isfinite(b) && std::abs(b) <= 0.5, "fallback_backoff_* must be finite, |b| <= 0.5 m");
}

namespace {
/// |approach . up| below this (approach within ~64 deg of horizontal, e.g. a tilted side
/// grasp): the closing axis is levelled and the wrist camera side (TCP +x) put up.
constexpr double kShallow = 0.9;

/// Side approach on side `sign` (+1: along z x fwd, -1: the other side), turned by `turn_deg`
/// towards the forward approach (the hand comes from the robot's side of the object) and
/// tilted down by `tilt_deg` (the hand comes from above the side).
Eigen::Vector3d sideApproach(const Eigen::Vector3d& fwd, double turn_deg, double tilt_deg, double sign) {
  Eigen::Vector3d f(fwd.x(), fwd.y(), 0.0);
  if (f.norm() < 1e-6) f = Eigen::Vector3d::UnitX();  // forward axis vertical: any horizontal
  f.normalize();
  const Eigen::Vector3d s = sign * Eigen::Vector3d::UnitZ().cross(f);
  const double a = turn_deg * M_PI / 180.0, b = tilt_deg * M_PI / 180.0;
  const Eigen::Vector3d horizontal = std::cos(a) * s + std::sin(a) * f;
  return (std::cos(b) * horizontal - std::sin(b) * Eigen::Vector3d::UnitZ()).normalized();
}
}  // namespace

std::optional<Eigen::Vector3d> wantedApproach(ApproachDirection direction,
                                              const Eigen::Isometry3d& tag_target,
                                              const GraspSelectionParams& p,
                                              const Eigen::Vector3d& hint) {
  const Eigen::Vector3d fwd = tag_target.linear().col(2).normalized();
  switch (direction) {
    case ApproachDirection::Tag: return fwd;
    case ApproachDirection::Forward: {
      // Into a side face (shallow): horizontal, as the face of an upright object is vertical.
      // The tag's tilt is the noisiest part of its pose (a small tag seen from afar: a few deg);
      // followed, it tilted the whole hand, and a grasp near the support brought the wrist down
      // by its length x the tilt (UR5e: 1.6 cm at 4 deg, into its stop distance from the table).
      const Eigen::Vector3d level(fwd.x(), fwd.y(), 0.0);
      return std::abs(fwd.z()) < kShallow && level.norm() > 1e-6 ? Eigen::Vector3d(level.normalized()) : fwd;
    }
    case ApproachDirection::Downward: return Eigen::Vector3d(0, 0, -1);
    case ApproachDirection::Sideways: {
      const Eigen::Vector3d a = sideApproach(fwd, p.sideways_turn_deg, p.sideways_tilt_deg, 1.0);
      const Eigen::Vector3d b = sideApproach(fwd, p.sideways_turn_deg, p.sideways_tilt_deg, -1.0);
      return b.dot(hint) > a.dot(hint) ? b : a;
    }
    case ApproachDirection::Any: return std::nullopt;
  }
  return std::nullopt;
}

bool candidateQualifies(const GraspCandidate& c, ApproachDirection direction,
                        const Eigen::Isometry3d& tag_target, const GraspSelectionParams& p) {
  if (direction == ApproachDirection::Tag) return false;
  if (!isValidPose(c.pose) || !std::isfinite(c.width) || !std::isfinite(c.score)) return false;
  if (c.width > p.max_width) return false;
  if ((c.pose.translation() - tag_target.translation()).norm() > p.candidate_gate) return false;
  const Eigen::Vector3d z = c.pose.linear().col(2);
  const auto want = wantedApproach(direction, tag_target, p, z);  // sideways: either side
  if (!want) return true;
  const double cosang = z.dot(*want);
  return std::acos(std::clamp(cosang, -1.0, 1.0)) <= p.max_angle_deg * M_PI / 180.0;
}

Eigen::Isometry3d turnedTagGrasp(const Eigen::Isometry3d& tag_target, const Eigen::Vector3d& approach,
                                 double backoff) {
  const Eigen::Vector3d z = approach.normalized();
  // Closing axis: keep the tag target's y if it is not along the approach, else world-horizontal.
  Eigen::Vector3d y = tag_target.linear().col(1);
  y -= y.dot(z) * z;
  if (std::abs(z.z()) >= kShallow) {
    // Top-down: the tag target's y is horizontal already; otherwise use its x.
    if (y.norm() < 1e-3) y = tag_target.linear().col(0) - tag_target.linear().col(0).dot(z) * z;
  } else {
    // Horizontal approach: closing axis horizontal, x (the wrist camera's side) up.
    y = z.cross(Eigen::Vector3d::UnitZ());
  }
  if (y.norm() < 1e-6) y = z.unitOrthogonal();
  y.normalize();
  const Eigen::Vector3d x = y.cross(z);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear().col(0) = x;
  T.linear().col(1) = y;
  T.linear().col(2) = z;
  T.translation() = tag_target.translation();
  return backedOff(T, backoff);
}

Eigen::Isometry3d backedOff(Eigen::Isometry3d pose, double distance) {
  pose.translation() -= distance * pose.linear().col(2);
  return pose;
}

Eigen::Matrix3d halfTurned(const Eigen::Matrix3d& R) {
  return R * Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

namespace {
/// A parallel-jaw grasp is the same grasp turned by pi about its approach axis: pick R or
/// R * Rz(pi). For a (near-)horizontal approach the one whose x axis points up, so the wrist
/// camera and the gripper body (on the TCP's +x side) stay clear of the support surface;
/// otherwise the one closer to `reference` (less wrist motion).
Eigen::Matrix3d closerHalfTurn(const Eigen::Matrix3d& R, const Eigen::Matrix3d& reference) {
  const Eigen::Matrix3d flipped = halfTurned(R);
  if (std::abs(R.col(2).z()) < kShallow) return R.col(0).z() >= 0.0 ? R : flipped;
  return ehc_control::rotationAngle(flipped, reference) < ehc_control::rotationAngle(R, reference) ? flipped : R;
}
/// The tag fallback's back-off along the approach (m) for a wanted direction.
double fallbackBackoff(ApproachDirection direction, const GraspSelectionParams& p) {
  if (direction == ApproachDirection::Downward) return p.fallback_backoff_downward;
  if (direction == ApproachDirection::Sideways) return p.fallback_backoff_sideways;
  return p.fallback_backoff_forward;
}
}  // namespace

namespace {
/// Candidate `i` as chosen: turned onto the wanted approach, closing along a tag target axis,
/// centred on the tag target, no deeper than the tag fallback (as the parameters say), then
/// the half-turn closer to `reference`.
GraspChoice fromCandidate(const std::vector<GraspCandidate>& candidates, std::size_t i, ApproachDirection direction,
                          const Eigen::Isometry3d& tag_target, const Eigen::Matrix3d& reference,
                          const GraspSelectionParams& p) {
  GraspChoice best;
  best.pose = candidates[i].pose;
  best.score = candidates[i].score;
  best.from_candidate = true;
  best.candidate_index = static_cast<int>(i);
  best.width = candidates[i].width;
  if (p.align_approach) {
    const Eigen::Vector3d z = best.pose.linear().col(2);
    if (auto want = wantedApproach(direction, tag_target, p, z)) {
      Eigen::Matrix3d R = Eigen::Quaterniond::FromTwoVectors(z, *want).toRotationMatrix() * best.pose.linear();
      if (std::abs(want->z()) < kShallow) {
        // Horizontal approach: level the closing axis too (the faces it closes on are vertical
        // for an upright object); closerHalfTurn below then puts the wrist camera up.
        Eigen::Vector3d y = want->cross(Eigen::Vector3d::UnitZ()).normalized();
        if (y.dot(R.col(1)) < 0.0) y = -y;
        R.col(1) = y;
        R.col(2) = *want;
        R.col(0) = y.cross(*want);
      }
      // Re-orthonormalise (exact to rounding; keep isValidPose happy).
      best.pose.linear() = Eigen::Quaterniond(R).normalized().toRotationMatrix();
    }
  }
  if (p.closing_axis_from_tag) {
    // The tag target's axis (its frame is the object's: face normals for a box) nearest the
    // candidate's closing axis, within the plane across the approach.
    const Eigen::Matrix3d R = best.pose.linear();
    const Eigen::Vector3d z = R.col(2);
    Eigen::Vector3d y = R.col(1);
    double best_dot = -1.0;
    for (int k = 0; k < 3; ++k) {
      Eigen::Vector3d a = tag_target.linear().col(k);
      a -= a.dot(z) * z;
      if (a.norm() < 0.5) continue;  // mostly along the approach: not a closing axis
      a.normalize();
      if (a.dot(R.col(1)) < 0.0) a = -a;
      if (a.dot(R.col(1)) > best_dot) {
        best_dot = a.dot(R.col(1));
        y = a;
      }
    }
    best.pose.linear().col(1) = y;
    best.pose.linear().col(0) = y.cross(z);
  }
  if (p.centre_from_tag) {
    // Across the approach, the tag target's centre; along it, the candidate's depth.
    const Eigen::Vector3d z = best.pose.linear().col(2);
    const Eigen::Vector3d d = tag_target.translation() - best.pose.translation();
    best.pose.translation() += d - d.dot(z) * z;
  }
  if (p.align_approach && (direction == ApproachDirection::Downward || direction == ApproachDirection::Sideways)) {
    // No deeper along the turned approach than the tag fallback (see align_approach).
    const Eigen::Vector3d z = best.pose.linear().col(2);
    const double backoff = fallbackBackoff(direction, p);
    const double past_centre = z.dot(best.pose.translation() - tag_target.translation());
    if (past_centre > -backoff) best.pose.translation() -= (past_centre + backoff) * z;
  }
  best.pose.linear() = closerHalfTurn(best.pose.linear(), reference);
  return best;
}

/// The tag target turned to the preferred approach and backed off (no qualifying candidate).
GraspChoice tagFallback(ApproachDirection direction, const Eigen::Isometry3d& tag_target, const Eigen::Matrix3d& reference,
                        const GraspSelectionParams& p) {
  GraspChoice best;
  const double backoff = fallbackBackoff(direction, p);
  Eigen::Vector3d approach = tag_target.linear().col(2);
  if (direction == ApproachDirection::Downward || direction == ApproachDirection::Sideways ||
      direction == ApproachDirection::Forward) {
    // Sideways: the side facing the reference orientation's approach better; forward: levelled.
    approach = *wantedApproach(direction, tag_target, p, reference.col(2));
  }
  if (direction == ApproachDirection::Tag || direction == ApproachDirection::Any ||
      approach.dot(tag_target.linear().col(2)) > 1.0 - 1e-12) {
    best.pose = backedOff(tag_target, backoff);
  } else {
    best.pose = turnedTagGrasp(tag_target, approach, backoff);
  }
  best.pose.linear() = closerHalfTurn(best.pose.linear(), reference);
  return best;
}
}  // namespace

std::optional<GraspChoice> chooseGrasp(const std::vector<GraspCandidate>& candidates,
                                       ApproachDirection direction,
                                       const Eigen::Isometry3d& tag_target,
                                       const Eigen::Matrix3d& reference,
                                       const GraspSelectionParams& p,
                                       const GraspReachable& reachable) {
  if (!isValidPose(tag_target)) return std::nullopt;
  std::vector<std::size_t> order;  // qualifying, best score first (ties: the first given)
  for (std::size_t i = 0; i < candidates.size(); ++i)
    if (candidateQualifies(candidates[i], direction, tag_target, p)) order.push_back(i);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return candidates[a].score > candidates[b].score; });
  const bool judge = reachable && p.reach_checks > 0;
  const bool any_fallback =
      p.any_approach_fallback && direction != ApproachDirection::Any && direction != ApproachDirection::Tag;
  GraspSelectionParams any = p;
  any.any_approach_fallback = false;
  if (order.empty()) {
    if (any_fallback) return chooseGrasp(candidates, ApproachDirection::Any, tag_target, reference, any, reachable);
    if (p.require_candidate && direction != ApproachDirection::Tag) return std::nullopt;
    return tagFallback(direction, tag_target, reference, p);
  }
  GraspChoice first = fromCandidate(candidates, order[0], direction, tag_target, reference, p);
  if (!judge) return first;
  const std::size_t checks = std::min(order.size(), static_cast<std::size_t>(p.reach_checks));
  for (std::size_t k = 0; k < checks; ++k) {
    GraspChoice c = k == 0 ? first : fromCandidate(candidates, order[k], direction, tag_target, reference, p);
    if (reachable(c.pose)) {
      c.reachable = true;
      return c;
    }
  }
  // None of the preferred approach reachable: a reachable one of the generator's own approach.
  if (any_fallback) {
    const auto alt = chooseGrasp(candidates, ApproachDirection::Any, tag_target, reference, any, reachable);
    if (alt && alt->reachable.value_or(false)) return alt;
  }
  first.reachable = false;
  return first;
}

}  // namespace ehc_bringup
