#include "ehc_control/reach_recovery.h"

#include "ehc_common/config_node.h"
#include "ehc_common/text_format.h"
#include "ehc_control/motion_limit.h"
#include "ehc_control/qp_controller.h"

#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace ehc_control {

namespace {
const char* kOwner = "ReachRecoveryParams";
/// Bearing offsets (x pi) of the base placements around the target, the robot's side first.
constexpr double kPlacementOffsets[] = {0.0, 0.25, -0.25, 0.5, -0.5, 0.75, -0.75, 1.0};
constexpr int kOffsets = static_cast<int>(sizeof(kPlacementOffsets) / sizeof(kPlacementOffsets[0]));
constexpr int kFallbackSeeds = 30;  ///< random seeds of the fallback solve (as Exp-1's reachability check)
constexpr int kFixedStarts = 2;  ///< the current configuration; the current base with the ready posture
constexpr double kTurnTravel = 0.3;  ///< m of travel counted per rad of base turn when choosing
/// Placement candidates: radii (x the ready reach) and heading offsets (rad) per bearing.
constexpr double kPlacementRadii[] = {1.0, 0.8, 0.6, 0.4};
constexpr double kPlacementYaws[] = {0.0, 0.3, -0.3};
/// Placement: a solution with the target in r_td wins over any without (score bonus).
constexpr double kInReachBonus = 10.0;
double wrap(double a) { return std::remainder(a, 2.0 * M_PI); }
/// Travel (m) of a differential base from `from` to the pose `to`: its distance, plus per rad the
/// turns onto the straight line and, at its end, onto the goal heading (holonomic: the yaw change).
double unicycleTravel(const Eigen::Vector3d& from, const Eigen::Vector3d& to, bool holonomic) {
  const Eigen::Vector2d d = to.head<2>() - from.head<2>();
  if (holonomic || d.norm() < 1e-6) return d.norm() + kTurnTravel * std::abs(wrap(to.z() - from.z()));
  const double line = std::atan2(d.y(), d.x());
  return d.norm() + kTurnTravel * (std::abs(wrap(line - from.z())) + std::abs(wrap(to.z() - line)));
}

/// One step of ReachRecovery::solve over (x, y, yaw, q): damped least squares onto the pose error
/// `e` (bounded, for far starts) plus the joint-limit gradient `g` in the task's null space
/// (bounded), with J the whole-body TCP Jacobian. An arm joint at its bound (`lo`, `hi`) that the
/// step would push beyond it is clamped: its column leaves J (and its entry g), and the step is
/// solved again, until no clamped joint's step points outwards (an active set). Clamping after
/// the step instead loses that joint's share of the task each iteration, and at a target that
/// needs the joint at its bound the iteration stalls short of it.
Eigen::VectorXd clampedStep(const Eigen::MatrixXd& J, const Vector6d& e, const Eigen::VectorXd& g,
                            const Eigen::VectorXd& qa, const Eigen::VectorXd& lo, const Eigen::VectorXd& hi) {
  const int n = static_cast<int>(J.cols()), na = static_cast<int>(qa.size());
  constexpr double kAtBound = 1e-9;  // rad
  Eigen::MatrixXd Jf = J;
  Eigen::VectorXd gf = g;
  Eigen::VectorXd step;
  for (int pass = 0; pass <= na; ++pass) {
    const Eigen::MatrixXd Jp = Jf.completeOrthogonalDecomposition().pseudoInverse();
    Eigen::VectorXd centre = (Eigen::MatrixXd::Identity(n, n) - Jp * Jf) * gf;
    const double largest = centre.cwiseAbs().maxCoeff();
    if (largest > 0.05) centre *= 0.05 / largest;
    Eigen::VectorXd task =
        Jf.transpose() * (Jf * Jf.transpose() + 1e-4 * Eigen::Matrix<double, 6, 6>::Identity()).ldlt().solve(e);
    const double task_largest = task.cwiseAbs().maxCoeff();
    if (task_largest > 0.2) task *= 0.2 / task_largest;
    step = task + centre;
    bool clamped = false;
    for (int i = 0; i < na; ++i) {
      const int k = n - na + i;
      if (Jf.col(k).isZero() && gf[k] == 0.0) continue;  // clamped already (or a column without effect)
      if ((qa[i] >= hi[i] - kAtBound && step[k] > 0.0) || (qa[i] <= lo[i] + kAtBound && step[k] < 0.0)) {
        Jf.col(k).setZero();
        gf[k] = 0.0;
        clamped = true;
      }
    }
    if (!clamped) break;
  }
  return step;
}
}  // namespace

void ReachRecoveryParams::validate() const {
  using ehc_common::requireRange;
  requireRange(kOwner, "stall_window", stall_window, 0.01, 1000.0);
  requireRange(kOwner, "position_progress", position_progress, 1e-5, 1.0);
  requireRange(kOwner, "orientation_progress", orientation_progress, 1e-5, 1.0);
  requireRange(kOwner, "pinned_progress_fraction", pinned_progress_fraction, 0.0, 0.9);
  requireRange(kOwner, "pinned_margin", pinned_margin, 0.0, 1.0);
  requireRange(kOwner, "starts", starts, 1, 1000);
  requireRange(kOwner, "starts_per_cycle", starts_per_cycle, 1, 1000);
  requireRange(kOwner, "travel_weight", travel_weight, 0.0, 100.0);
  requireRange(kOwner, "joint_gain", joint_gain, 1e-3, 100.0);
  requireRange(kOwner, "base_gain", base_gain, 1e-3, 100.0);
  requireRange(kOwner, "heading_gain", heading_gain, 1e-3, 100.0);
  requireRange(kOwner, "final_heading_gain", final_heading_gain, -100.0, -1e-3);
  if (!(heading_gain > base_gain))
    throw std::invalid_argument("[ReachRecoveryParams] heading_gain must exceed base_gain (stability of the polar law)");
  requireRange(kOwner, "position_tolerance", position_tolerance, 1e-4, 1.0);
  requireRange(kOwner, "yaw_tolerance", yaw_tolerance, 1e-4, 1.0);
  requireRange(kOwner, "joint_tolerance", joint_tolerance, 1e-4, 1.0);
  requireRange(kOwner, "move_timeout", move_timeout, 0.1, 1000.0);
  requireRange(kOwner, "max_attempts", max_attempts, 0, 100);
  requireRange(kOwner, "placement_bearings", placement_bearings, 1, 360);
  requireRange(kOwner, "placement_handover_sig", placement_handover_sig, 0.0, 1.0);
  requireRange(kOwner, "placement_margin", placement_margin, 0.0, 3.0);
}

std::string ReachRecoveryParams::summary() const {
  if (!enabled) return "reach recovery off";
  std::ostringstream os;
  os << "reach recovery after " << stall_window << " s without progress (" << position_progress << " m, "
     << orientation_progress * 180.0 / M_PI << " deg; with a joint pinned near the target also "
     << pinned_progress_fraction << " of the error) with a joint within " << pinned_margin
     << " rad of its stop" << (free_stalls ? " (or near the target with every joint free, no link held at an obstacle)" : "")
     << ": IK from " << starts << " starts, at most "
     << max_attempts << " per target, " << move_timeout << " s each";
  return os.str();
}

ReachRecoveryParams loadReachRecoveryParams(const ehc_common::ConfigNode& n) {
  ReachRecoveryParams p;
  p.enabled = n.get("enabled", p.enabled);
  p.stall_window = n.get("stall_window", p.stall_window);
  p.position_progress = n.get("position_progress", p.position_progress);
  p.orientation_progress = n.get("orientation_progress_deg", p.orientation_progress * 180.0 / M_PI) * M_PI / 180.0;
  p.pinned_margin = n.get("pinned_margin", p.pinned_margin);
  p.pinned_progress_fraction = n.get("pinned_progress_fraction", p.pinned_progress_fraction);
  p.starts = n.get("starts", p.starts);
  p.starts_per_cycle = n.get("starts_per_cycle", p.starts_per_cycle);
  p.travel_weight = n.get("travel_weight", p.travel_weight);
  p.joint_gain = n.get("joint_gain", p.joint_gain);
  p.base_gain = n.get("base_gain", p.base_gain);
  p.heading_gain = n.get("heading_gain", p.heading_gain);
  p.final_heading_gain = n.get("final_heading_gain", p.final_heading_gain);
  p.position_tolerance = n.get("position_tolerance", p.position_tolerance);
  p.yaw_tolerance = n.get("yaw_tolerance_deg", p.yaw_tolerance * 180.0 / M_PI) * M_PI / 180.0;
  p.joint_tolerance = n.get("joint_tolerance", p.joint_tolerance);
  p.move_timeout = n.get("move_timeout", p.move_timeout);
  p.max_attempts = n.get("max_attempts", p.max_attempts);
  p.free_stalls = n.get("free_stalls", p.free_stalls);
  p.placement_bearings = n.get("placement_bearings", p.placement_bearings);
  p.placement_handover_sig = n.get("placement_handover_sig", p.placement_handover_sig);
  p.placement_margin = n.get("placement_margin", p.placement_margin);
  n.validate(p);  // errors name the file and the section
  return p;
}

ReachRecovery::ReachRecovery(const WholeBodyModel& model, const ReachRecoveryParams& params, double joint_stop,
                             double joint_influence)
    : model_(model), params_(params), joint_stop_(joint_stop), joint_influence_(joint_influence) {
  params_.validate();
  const RobotConfig& rc = model_.config();
  const Eigen::Vector3d tcp = model_.linkPoseInBase(rc.arm_ready, rc.tcp_frame).translation();
  reach_ = std::max(0.2, tcp.head<2>().norm());
  ready_bearing_ = readyTcpBearing(model_);
  T_base_arm_ready_ = model_.linkPoseInBase(rc.arm_ready, rc.arm_base_frame);
  vmax_ = rc.velocityLimits();
  reference_ = Eigen::VectorXd::Zero(model_.nDof());
}

void ReachRecovery::reset() {
  state_ = State::Watching;
  have_target_ = false;
  attempts_ = 0;
  far_attempts_ = 0;
  place_ = false;
}

void ReachRecovery::setPlacementMap(std::shared_ptr<const EhcWeighting> weighting) {
  placement_map_ = std::move(weighting);
  // The rings' scale: the farthest horizontal distance from the arm base of a voxel in r_td.
  place_reach_ = reach_;
  if (!placement_map_) return;
  const ReachabilityMap& map = placement_map_->map();
  const Eigen::Vector3i& n = map.dims();
  for (int i = 0; i < n.x(); ++i)
    for (int j = 0; j < n.y(); ++j)
      for (int k = 0; k < n.z(); ++k) {
        const Eigen::Vector3d p = map.origin() + map.resolution() * (Eigen::Vector3d(i, j, k) + Eigen::Vector3d::Constant(0.5));
        if (placement_map_->inReachSet(p)) place_reach_ = std::max(place_reach_, p.head<2>().norm());
      }
}

double ReachRecovery::placementReachability(const Eigen::Isometry3d& target, const Eigen::Vector3d& base_pose) const {
  if (!placement_map_) throw std::invalid_argument("[ReachRecovery] placement needs a reachability map");
  const Eigen::Isometry3d world_T_arm = WholeBodyModel::baseTransform(base_pose) * T_base_arm_ready_;
  return placement_map_->map().reachability(world_T_arm.inverse() * target.translation());
}

std::vector<Eigen::Vector3d> ReachRecovery::placementStarts(const Eigen::Isometry3d& target,
                                                            const Eigen::Vector3d& base_pose) const {
  struct Candidate {
    Eigen::Vector3d base;
    double reach = 0.0, travel = 0.0;
  };
  const Eigen::Vector2d t = target.translation().head<2>();
  const Eigen::Vector2d to_robot = base_pose.head<2>() - t;
  const double robot_side = to_robot.norm() > 1e-6 ? std::atan2(to_robot.y(), to_robot.x()) : base_pose.z() + M_PI;
  const auto better = [](const Candidate& a, const Candidate& b) {
    return a.reach != b.reach ? a.reach > b.reach : a.travel < b.travel;
  };
  std::vector<Candidate> best;  // per bearing
  for (int i = 0; i < params_.placement_bearings; ++i) {
    const double a = robot_side + 2.0 * M_PI * i / params_.placement_bearings;
    Candidate top;
    bool have = false;
    for (double r : kPlacementRadii)
      for (double dyaw : kPlacementYaws) {
        Candidate c;
        c.base = placementFacing(t, a, r * place_reach_, ready_bearing_);
        c.base.z() = wrap(c.base.z() + dyaw);
        c.reach = placementReachability(target, c.base);
        c.travel = unicycleTravel(base_pose, c.base, model_.nBase() == 3);
        if (!have || better(c, top)) top = c, have = true;
      }
    best.push_back(top);
  }
  std::stable_sort(best.begin(), best.end(), better);
  std::vector<Eigen::Vector3d> out;
  for (const Candidate& c : best) out.push_back(c.base);
  return out;
}

double ReachRecovery::margin(const Eigen::VectorXd& q) const {
  const RobotConfig& rc = model_.config();
  return std::min((q - rc.arm_lower).minCoeff(), (rc.arm_upper - q).minCoeff());
}

Eigen::VectorXd ReachRecovery::widestTurn(const Eigen::VectorXd& q) const {
  const RobotConfig& rc = model_.config();
  Eigen::VectorXd out = q;
  const auto margin_of = [&](int i, double v) { return std::min(v - rc.arm_lower[i], rc.arm_upper[i] - v); };
  for (int i = 0; i < q.size(); ++i)
    for (int turns = -2; turns <= 2; ++turns) {
      const double v = q[i] + 2.0 * M_PI * turns;
      if (margin_of(i, v) >= joint_stop_ && margin_of(i, v) > margin_of(i, out[i])) out[i] = v;
    }
  return out;
}

void ReachRecovery::startWatching(double now, double position_error, double orientation_error) {
  state_ = State::Watching;
  best_position_ = position_error;
  best_orientation_ = orientation_error;
  progress_t_ = now;
}

bool ReachRecovery::stalled(double now, double position_error, double orientation_error, const Eigen::VectorXd& q,
                            bool obstacle_held) {
  // Near the target with a joint pinned, progress is also a fall by a fraction of the error: an
  // approach creeping into the trap's equilibrium keeps above the absolute thresholds for long.
  const bool pinned = pinnedJoint(model_.config(), q, joint_stop_ + params_.pinned_margin) >= 0;
  const double fraction = pinned && position_error <= 2.0 * reach_ ? params_.pinned_progress_fraction : 0.0;
  if (position_error < best_position_ - std::max(params_.position_progress, fraction * best_position_) ||
      orientation_error < best_orientation_ - std::max(params_.orientation_progress, fraction * best_orientation_)) {
    best_position_ = std::min(best_position_, position_error);
    best_orientation_ = std::min(best_orientation_, orientation_error);
    progress_t_ = now;
    return false;
  }
  // Far from the target the arm unwinds either way. Near it, a joint pinned; or (free_stalls) the
  // pose task's own equilibrium with every joint free (see the top of reach_recovery.h), unless
  // a link is held at an obstacle (a configuration of the target alone would not clear it).
  if (now - progress_t_ < params_.stall_window) return false;
  if (position_error > 2.0 * reach_) return far_attempts_ < params_.max_attempts;
  if (attempts_ >= params_.max_attempts) return false;
  return pinned || (params_.free_stalls && !obstacle_held) || givenPlan(target_) != nullptr;
}

void ReachRecovery::setGivenPlans(std::vector<GivenPlan> plans) {
  for (const GivenPlan& p : plans)
    if (p.q.size() != model_.config().nArm() || !p.q.allFinite() || !p.base.allFinite())
      throw std::invalid_argument("[ReachRecovery] a given plan needs a finite base pose and arm configuration");
  given_plans_ = std::move(plans);
  given_tcp_.clear();
  for (const GivenPlan& p : given_plans_) given_tcp_.push_back(model_.fk(p.base, p.q, model_.config().tcp_frame));
}

const ReachRecovery::GivenPlan* ReachRecovery::givenPlan(const Eigen::Isometry3d& target) const {
  for (std::size_t i = 0; i < given_plans_.size(); ++i) {
    const Eigen::Isometry3d& tcp = given_tcp_[i];
    if ((tcp.translation() - target.translation()).norm() <= 0.01 &&
        Eigen::AngleAxisd(Eigen::Matrix3d(tcp.linear().transpose() * target.linear())).angle() <= 2.0 * M_PI / 180.0)
      return &given_plans_[i];
  }
  return nullptr;
}

void ReachRecovery::startPlacement(const Eigen::Vector3d& base_pose, const Eigen::VectorXd& q) {
  if (!placement_map_) throw std::invalid_argument("[ReachRecovery] placement needs a reachability map");
  startPlanning(base_pose, q, false);
  --attempts_;  // a placement is not a stall's attempt
  place_ = true;
  far_ = false;
  place_starts_ = placementStarts(target_, base_pose);
}

void ReachRecovery::startPlanning(const Eigen::Vector3d& base_pose, const Eigen::VectorXd& q, bool far) {
  state_ = State::Planning;
  finishing_ = false;
  given_ = false;
  plan_base_ = base_pose;
  plan_q_ = q;
  plan_margin_ = margin(q);
  next_start_ = 0;
  solutions_ = 0;
  have_goal_ = false;
  ++(far ? far_attempts_ : attempts_);
}

double readyTcpBearing(const WholeBodyModel& model) {
  const RobotConfig& rc = model.config();
  const Eigen::Vector3d tcp = model.linkPoseInBase(rc.arm_ready, rc.tcp_frame).translation();
  return std::atan2(tcp.y(), tcp.x());
}

Eigen::Vector3d placementFacing(const Eigen::Vector2d& target, double angle, double radius, double ready_bearing) {
  Eigen::Vector3d out;
  out.head<2>() = target + radius * Eigen::Vector2d(std::cos(angle), std::sin(angle));
  out.z() = wrap(angle + M_PI - ready_bearing);
  return out;
}

Eigen::Vector3d ReachRecovery::readyOver(const Eigen::Isometry3d& target, const Eigen::Vector3d& base) const {
  const Eigen::Vector2d t = target.translation().head<2>();
  const Eigen::Vector2d away = base.head<2>() - t;
  const double angle = away.norm() > 1e-9 ? std::atan2(away.y(), away.x()) : base.z() + ready_bearing_ + M_PI;
  return placementFacing(t, angle, reach_, ready_bearing_);
}

void ReachRecovery::start(int k, const Eigen::Isometry3d& target, Eigen::Vector3d* base, Eigen::VectorXd* q) const {
  const RobotConfig& rc = model_.config();
  *base = plan_base_;
  *q = widestTurn(k == 0 ? plan_q_ : rc.arm_ready);
  if (place_) {  // the ranked placements, the arm at ready
    *q = widestTurn(rc.arm_ready);
    *base = place_starts_[static_cast<std::size_t>(k) % place_starts_.size()];
    return;
  }
  if (k < kFixedStarts) return;
  // Around the target: the base on a circle of the ready reach (second round: 0.7 of it,
  // between the first round's bearings), facing so that the ready TCP is over the target.
  const int i = k - kFixedStarts;
  const bool second = (i / kOffsets) % 2 == 1;
  const Eigen::Vector2d t = target.translation().head<2>();
  const Eigen::Vector2d to_robot = plan_base_.head<2>() - t;
  const double robot_side = to_robot.norm() > 1e-6 ? std::atan2(to_robot.y(), to_robot.x()) : plan_base_.z() + M_PI;
  const double a = robot_side + M_PI * (kPlacementOffsets[i % kOffsets] + (second ? 0.125 : 0.0));
  *base = placementFacing(t, a, (second ? 0.7 : 1.0) * reach_, ready_bearing_);
}

bool ReachRecovery::solve(const Eigen::Isometry3d& target, Eigen::Vector3d* base, Eigen::VectorXd* q,
                          BaseMotion motion) const {
  // Whole-body IK over (x, y, yaw, q) with joint-limit avoidance by gradient projection: each
  // step is a damped least-squares step onto the target plus, in the task's null space, a step
  // of every joint within joint_influence of its nearer limit away from it, so that the base
  // moves to let the arm centre its joints. Joints stay within joint_stop of their limits; a
  // joint at its bound that the step would push beyond it leaves the step (clampedStep), so the
  // others solve what it cannot. (Clamping after the step, as KDL's solver with limits does,
  // stalls at the bound, which is where a stalled approach starts from: at a target whose
  // configurations all have a joint at its stop no start would converge, not even the stalled
  // configuration 1-2 cm from it.) Success: the TCP on the target within 1 mm / 0.5 deg.
  const RobotConfig& rc = model_.config();
  const int na = model_.nArm(), n = 3 + na;
  const Eigen::VectorXd lo = rc.arm_lower + Eigen::VectorXd::Constant(na, joint_stop_);
  const Eigen::VectorXd hi = rc.arm_upper - Eigen::VectorXd::Constant(na, joint_stop_);
  Eigen::Vector3d b = *base;
  Eigen::VectorXd qa = q->cwiseMax(lo).cwiseMin(hi);
  Eigen::MatrixXd J(6, n);
  Eigen::VectorXd g(n);
  // The base's translation per unit of its first two variables: free (x, y), along its heading
  // at the start (the second variable unused), or held (neither, nor the yaw).
  Eigen::Matrix2d along = Eigen::Matrix2d::Identity();
  if (motion == BaseMotion::Straight) along << std::cos(b.z()), 0.0, std::sin(b.z()), 0.0;
  if (motion == BaseMotion::Held) along.setZero();
  for (int it = 0; it < 150; ++it) {
    const Eigen::Isometry3d world_T_base = WholeBodyModel::baseTransform(b);
    const Eigen::Isometry3d tcp = world_T_base * model_.linkPoseInBase(qa, rc.tcp_frame);
    const Vector6d e = poseError(tcp, target);
    g.setZero();
    for (int i = 0; i < na; ++i) {
      const double to_lower = qa[i] - rc.arm_lower[i], to_upper = rc.arm_upper[i] - qa[i];
      if (to_lower < joint_influence_ && to_lower <= to_upper) g[3 + i] = joint_influence_ - to_lower;
      else if (to_upper < joint_influence_) g[3 + i] = -(joint_influence_ - to_upper);
    }
    if (e.head<3>().norm() < 1e-4 && e.tail<3>().norm() < 1e-4 && g.isZero()) break;
    const Matrix6Xd Ja = model_.armJacobian(qa, rc.tcp_frame);
    J.setZero();
    J.topLeftCorner<2, 2>() = along;
    if (motion != BaseMotion::Held) {  // held: the arm alone, the base stays where it stands
      const Eigen::Vector3d r = tcp.translation() - world_T_base.translation();
      J(0, 2) = -r.y();
      J(1, 2) = r.x();
      J(5, 2) = 1.0;
    }
    J.block(0, 3, 3, na) = world_T_base.linear() * Ja.topRows<3>();
    J.block(3, 3, 3, na) = world_T_base.linear() * Ja.bottomRows<3>();
    const Eigen::VectorXd step = clampedStep(J, e, g, qa, lo, hi);
    b.head<2>() += along * step.head<2>();
    b.z() += step[2];
    qa = (qa + step.tail(na)).cwiseMax(lo).cwiseMin(hi);
  }
  const Eigen::Isometry3d tcp = WholeBodyModel::baseTransform(b) * model_.linkPoseInBase(qa, rc.tcp_frame);
  const Vector6d e = poseError(tcp, target);
  if (e.head<3>().norm() > 1e-3 || e.tail<3>().norm() > 0.5 * M_PI / 180.0) return false;
  *base = Eigen::Vector3d(b.x(), b.y(), wrap(b.z()));
  *q = qa;
  return true;
}

void ReachRecovery::plan(const Eigen::Isometry3d& target) {
  for (int n = 0; n < params_.starts_per_cycle && next_start_ < params_.starts; ++n, ++next_start_) {
    Eigen::Vector3d b0, b;
    Eigen::VectorXd q0, q;
    start(next_start_, target, &b0, &q0);
    b = b0;
    q = q0;
    // A placement's first round solves with the base at the ranked pose (the map's R is that
    // pose's); the starts beyond it, from the best poses again, with the base free.
    if (!solve(target, &b, &q,
               place_ && next_start_ < static_cast<int>(place_starts_.size()) ? BaseMotion::Held : BaseMotion::Free))
      continue;
    ++solutions_;
    q = widestTurn(q);
    const double m = margin(q);
    const double travel = (b.head<2>() - plan_base_.head<2>()).norm() + kTurnTravel * std::abs(wrap(b.z() - plan_base_.z()));
    double score = std::min(m, joint_influence_) - params_.travel_weight * travel;
    const double reach = place_ ? placementReachability(target, b) : 0.0;
    if (place_) {  // a margin of placement_margin first, then in r_td, then the least travel
      score = std::min(m, params_.placement_margin) -
              params_.travel_weight * unicycleTravel(plan_base_, b, model_.nBase() == 3);
      if (reach > placement_map_->params().reach_threshold) score += 0.5 * kInReachBonus;
      if (m >= params_.placement_margin) score += kInReachBonus;
    }
    if (!have_goal_ || score > goal_score_) {
      have_goal_ = true;
      goal_score_ = score;
      goal_base_ = b;
      goal_q_ = q;
      goal_margin_ = m;
      goal_reach_ = reach;
    }
  }
  if (have_goal_ || next_start_ < params_.starts) return;
  // No start converged (the damped least-squares steps from these starts miss some targets
  // that need the arm far from every start): the random-restart solver
  // that admits Exp-1's targets (WholeBodyModel::inverseKinematics, KDL with the joint limits
  // shrunk by the stop), once; it finds a configuration of every target it admitted.
  Eigen::Vector3d b;
  Eigen::VectorXd q;
  if (!model_.inverseKinematics(target, 1, kFallbackSeeds, &b, &q, joint_stop_)) return;
  ++solutions_;
  have_goal_ = true;
  goal_base_ = b;
  goal_q_ = widestTurn(q);
  goal_margin_ = margin(goal_q_);
  goal_score_ = std::min(goal_margin_, joint_influence_);
  goal_reach_ = place_ ? placementReachability(target, b) : 0.0;
}

void ReachRecovery::reference(const Eigen::Vector3d& base_pose, const Eigen::VectorXd& q) {
  const int nb = model_.nBase();
  reference_.setZero(model_.nDof());
  reference_.tail(model_.nArm()) = params_.joint_gain * (goal_q_ - q);
  const Eigen::Vector2d d = goal_base_.head<2>() - base_pose.head<2>();
  const double rho = d.norm(), yaw = base_pose.z();
  if (nb == 3) {  // holonomic: proportional in the base frame
    reference_[0] = params_.base_gain * (std::cos(yaw) * d.x() + std::sin(yaw) * d.y());
    reference_[1] = params_.base_gain * (-std::sin(yaw) * d.x() + std::cos(yaw) * d.y());
    reference_[2] = params_.heading_gain * wrap(goal_base_.z() - yaw);
  } else if (rho < params_.position_tolerance) {  // on the spot: turn to the goal heading
    reference_[1] = params_.heading_gain * wrap(goal_base_.z() - yaw);
    // A finish's goal lies along the heading (BaseMotion::Straight): driven straight there.
    if (finishing_ && finish_base_) reference_[0] = params_.base_gain * (std::cos(yaw) * d.x() + std::sin(yaw) * d.y());
  } else {
    // Polar law (Astolfi): alpha = bearing of the goal, beta = goal heading beyond it; a goal
    // behind the base is approached backwards (the same law with the base's rear as its front).
    // A far move's goal faces along the travel: forwards only, turning before driving (cos
    // alpha), since backwards it would arrive facing away and loop round to turn.
    double alpha = wrap(std::atan2(d.y(), d.x()) - yaw);
    const bool forwards = far_ || (place_ && rho > 2.0 * reach_);  // a long drive: facing along it
    const bool backwards = !forwards && std::abs(alpha) > 0.5 * M_PI;
    if (backwards) alpha = wrap(alpha - M_PI);
    const double beta = wrap(goal_base_.z() - yaw - alpha);
    reference_[0] = (backwards ? -1.0 : 1.0) * params_.base_gain * rho * (forwards ? std::max(0.0, std::cos(alpha)) : 1.0);
    // A long drive turns to its bearing only (a goal heading across the travel would hold the
    // clamped law at alpha ~ 90 deg, the two turn terms cancelling); the heading comes near the goal.
    reference_[1] = params_.heading_gain * alpha + (forwards ? 0.0 : params_.final_heading_gain * beta);
  }
  // One scale for the whole reference: its direction survives the velocity limits.
  double scale = 1.0;
  for (int i = 0; i < reference_.size(); ++i)
    if (std::abs(reference_[i]) > vmax_[i]) scale = std::min(scale, vmax_[i] / std::abs(reference_[i]));
  reference_ *= scale;
}

bool ReachRecovery::finish(const Eigen::Vector3d& base_pose, const Eigen::VectorXd& q, double position_error,
                           double orientation_error) {
  // A near move ends within its tolerances of (b*, q*), the TCP up to a few cm off the target;
  // from there the pose task went back into a stop (traces, RealMan `any`: 1.2-5 cm short again,
  // twice per target). Once per move: the arm's own configuration of the target from the base
  // where it stands (a differential base's last centimetres sideways need manoeuvres), tracked
  // by the arm alone, the base's goal its pose. At a target whose configurations all have a
  // joint at its stop (traces, RealMan `any`: a base 2-5 cm off its goal left no arm-only
  // configuration) the base moves too, as it can without manoeuvres: a differential base
  // straight along its heading while turning, a holonomic one freely.
  if (far_ || place_ || finishing_) return false;
  if (position_error < params_.position_progress && orientation_error < params_.orientation_progress) return false;
  Eigen::Vector3d b = base_pose;
  Eigen::VectorXd qs = q;
  finish_base_ = false;
  if (!solve(target_, &b, &qs, BaseMotion::Held)) {
    b = base_pose;
    qs = q;
    if (!solve(target_, &b, &qs, model_.nBase() == 3 ? BaseMotion::Free : BaseMotion::Straight)) return false;
    finish_base_ = true;
  }
  finishing_ = true;
  goal_base_ = finish_base_ ? b : base_pose;
  goal_q_ = widestTurn(qs);
  goal_margin_ = margin(goal_q_);
  return true;
}

bool ReachRecovery::atGoal(const Eigen::Vector3d& base_pose, const Eigen::VectorXd& q, double scale) const {
  // An arm-only finish's base is where it stood: its joints alone say whether it is done.
  const bool base_done = (finishing_ && !finish_base_) ||
                         ((goal_base_.head<2>() - base_pose.head<2>()).norm() < scale * params_.position_tolerance &&
                          std::abs(wrap(goal_base_.z() - base_pose.z())) < scale * params_.yaw_tolerance);
  return base_done && (goal_q_ - q).cwiseAbs().maxCoeff() < scale * params_.joint_tolerance;
}

const Eigen::VectorXd* ReachRecovery::update(double now, const Eigen::Vector3d& base_pose, const Eigen::VectorXd& q,
                                             const Eigen::Isometry3d& tcp, const Eigen::Isometry3d& target,
                                             const EhcWeight* place, bool obstacle_held) {
  event_.clear();
  if (!params_.enabled) return nullptr;
  const double position_error = (target.translation() - tcp.translation()).norm();
  const double orientation_error = Eigen::AngleAxisd(Eigen::Matrix3d(target.linear() * tcp.linear().transpose())).angle();
  // A target that moved (not a perception update of the same one) is a new approach.
  if (!have_target_ || (target.translation() - target_.translation()).norm() > 0.01 ||
      Eigen::AngleAxisd(Eigen::Matrix3d(target.linear() * target_.linear().transpose())).angle() > 2.0 * M_PI / 180.0) {
    reset();
    target_ = target;
    have_target_ = true;
    startWatching(now, position_error, orientation_error);
    if (place) startPlacement(base_pose, q);
  }
  std::ostringstream os;
  switch (state_) {
    case State::Watching:
      if (!stalled(now, position_error, orientation_error, q, obstacle_held)) return nullptr;
      far_ = position_error > 2.0 * reach_;
      startPlanning(base_pose, q, far_);
      if (const GivenPlan* p = far_ ? nullptr : givenPlan(target_)) {
        given_ = have_goal_ = true;
        goal_base_ = p->base;
        goal_q_ = p->q;
        goal_margin_ = margin(goal_q_);
        next_start_ = params_.starts;
      }
      [[fallthrough]];
    case State::Planning:
      if (far_) {  // far: the arm back to ready while the base drives to the target
        if ((model_.config().arm_ready - q).cwiseAbs().maxCoeff() < params_.joint_tolerance) {
          // Nothing to unwind: the arm is at its ready posture, the stall is not the arm's.
          startWatching(now, position_error, orientation_error);
          return nullptr;
        }
        have_goal_ = true;
        goal_base_ = readyOver(target_, plan_base_);
        goal_q_ = model_.config().arm_ready;
        goal_margin_ = margin(goal_q_);
        next_start_ = params_.starts;
      }
      plan(target_);
      if (next_start_ < params_.starts) return nullptr;
      if (!have_goal_) {
        os << (place_ ? "placement" : "stall") << " " << position_error * 100.0 << " cm short, smallest joint margin " << plan_margin_
           << " rad: no whole-body configuration inside the joint stops found (" << solutions_ << " IK solutions of "
           << params_.starts << " starts";
        os << ")";
        event_ = os.str();
        place_ = false;
        startWatching(now, position_error, orientation_error);
        return nullptr;
      }
      state_ = State::Moving;
      move_t_ = now;
      // A far move's time also covers the travel at the base's speed limit.
      move_limit_ = params_.move_timeout +
                    (far_ || place_ || given_ ? (goal_base_.head<2>() - plan_base_.head<2>()).norm() / vmax_[0] : 0.0);
      if (place_)
        os << "placement: moving to base (" << goal_base_.x() << ", " << goal_base_.y() << ", " << goal_base_.z()
           << ") where the map gives the target R " << goal_reach_ << ", margin " << goal_margin_ << " rad";
      else
      os << "stall " << position_error * 100.0 << " cm short, smallest joint margin " << plan_margin_
         << " rad: moving to " << (given_ ? "the given plan's " : "") << "base (" << goal_base_.x() << ", " << goal_base_.y() << ", " << goal_base_.z()
         << ") with margin " << goal_margin_ << " rad (" << (far_ ? "far attempt " : "attempt ")
         << (far_ ? far_attempts_ : attempts_) << ")";
      event_ = os.str();
      [[fallthrough]];
    case State::Moving:
      if (place_ && place && place->sig >= params_.placement_handover_sig) {
        event_ += (event_.empty() ? "" : "; ") + std::string("placement: handing over to the pose task at sig ") +
                  ehc_common::fixedDecimals(place->sig, 2);
        place_ = false;
        startWatching(now, position_error, orientation_error);
        return nullptr;
      }
      // The finish ends with the TCP on the target or within a tenth of the tolerances of its
      // configuration (its base too, when it moves the base).
      const bool at_goal = finishing_ ? (position_error < params_.position_progress &&
                                         orientation_error < params_.orientation_progress) ||
                                            atGoal(base_pose, q, 0.1)
                                      : atGoal(base_pose, q);
      if (at_goal && finish(base_pose, q, position_error, orientation_error)) {
        event_ = "recovery configuration reached with the TCP " + ehc_common::fixedDecimals(position_error * 100.0, 1) +
                 (finish_base_ ? " cm off: the arm and the base (straight along its heading, or holonomic) to the target"
                               : " cm off: the arm alone to the target from this base");
        move_t_ = now;
        move_limit_ = params_.move_timeout;
      } else if (at_goal || now - move_t_ > move_limit_) {
        if (event_.empty()) event_ = at_goal ? "recovery configuration reached" : "recovery move timed out";
        place_ = false;
        startWatching(now, position_error, orientation_error);
        return nullptr;
      }
      reference(base_pose, q);
      return &reference_;
  }
  return nullptr;
}

}  // namespace ehc_control
