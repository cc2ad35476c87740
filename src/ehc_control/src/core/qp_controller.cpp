#include "ehc_control/qp_controller.h"

#include "ehc_common/enum_names.h"

#include "ehc_common/config_node.h"
#include "ehc_control/qp_solver.h"
#include "ehc_control/joint_limit_centring.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

using ehc_common::requireRange;

namespace ehc_control {

namespace {
const char* kOwner = "QpControllerParams";

std::string knownQpSolvers() {
  std::string known;
  for (const std::string& n : qpSolverNames()) known += (known.empty() ? "" : ", ") + n;
  return known;
}
}  // namespace

namespace {
constexpr ehc_common::EnumNames<ControlMode, 5> kControlModeNames = {{{ControlMode::Ehc, "ehc"},
                                                                      {ControlMode::EhcPlace, "ehc_place"},
                                                                      {ControlMode::NeoE, "neo_e"},
                                                                      {ControlMode::NeoC, "neo_c"},
                                                                      {ControlMode::Tsmm, "tsmm"}}};
}  // namespace

std::string toString(ControlMode m) { return ehc_common::enumName(kControlModeNames, m, "EhcQpController"); }

ControlMode controlModeFromString(const std::string& s) {
  return ehc_common::enumValue(kControlModeNames, s, "EhcQpController", "mode");
}

void FarApproachParams::validate() const {
  requireRange("FarApproachParams", "distance", distance, 0.05, 100.0);
  requireRange("FarApproachParams", "posture_gain", posture_gain, 0.0, 100.0);
  requireRange("FarApproachParams", "orientation_release", orientation_release, 0.0, 1.0);
}

std::string FarApproachParams::summary() const {
  std::ostringstream os;
  os << "far approach (TCP beyond " << distance << " m, fully beyond " << 2.0 * distance << " m): "
     << (face_target ? "base faces the target" : "base faces the TCP") << ", arm posture gain +" << posture_gain
     << ", orientation rows weighed " << 1.0 - orientation_release << " when far";
  return os.str();
}

void QpControllerParams::validate() const {
  requireRange(kOwner, "arm_weight", arm_weight, 1e-6, 1e3);
  requireRange(kOwner, "ehc_base_weight_min", ehc_base_weight_min, 1e-6, 1e4);
  requireRange(kOwner, "ehc_base_weight_max", ehc_base_weight_max, 1e-6, 1e4);
  if (ehc_base_weight_max < ehc_base_weight_min)
    throw std::invalid_argument("[QpControllerParams] ehc_base_weight_max must be >= ehc_base_weight_min");
  requireRange(kOwner, "neo_c_base_weight", neo_c_base_weight, 1e-6, 1e4);
  requireRange(kOwner, "min_error", min_error, 1e-6, 1.0);
  requireRange(kOwner, "slack_bound", slack_bound, 1e-3, 1e3);
  requireRange(kOwner, "base_turn_gain", base_turn_gain, 0.0, 100.0);
  requireRange(kOwner, "manipulability_gain", manipulability_gain, 0.0, 100.0);
  requireRange(kOwner, "manipulability_fade_distance", manipulability_fade_distance, 0.0, 5.0);
  requireRange(kOwner, "posture_gain", posture_gain, 0.0, 100.0);
  far_approach.validate();
  requireRange(kOwner, "limit_centring_gain", limit_centring_gain, 0.0, 100.0);
  wrist_flip.validate();
  recovery.validate();
  requireRange(kOwner, "joint_stop", joint_stop, 0.0, 1.0);
  requireRange(kOwner, "joint_influence", joint_influence, 0.0, 3.0);
  if (joint_influence <= joint_stop)
    throw std::invalid_argument("[QpControllerParams] joint_influence must be > joint_stop");
  requireRange(kOwner, "joint_damper_gain", joint_damper_gain, 1e-3, 100.0);
  requireRange(kOwner, "obstacle_stop", obstacle_stop, 0.0, 1.0);
  requireRange(kOwner, "obstacle_influence", obstacle_influence, 0.0, 5.0);
  if (obstacle_influence <= obstacle_stop)
    throw std::invalid_argument("[QpControllerParams] obstacle_influence must be > obstacle_stop");
  for (const auto& [link, d] : obstacle_stop_links) {
    requireRange(kOwner, "obstacle_stop_links." + link, d, 0.0, 1.0);
    if (obstacle_influence <= d)
      throw std::invalid_argument("[QpControllerParams] obstacle_influence must be > obstacle_stop_links." + link);
  }
  requireRange(kOwner, "obstacle_damper_gain", obstacle_damper_gain, 1e-3, 100.0);
  requireRange(kOwner, "obstacle_recovery_gain", obstacle_recovery_gain, 0.0, 100.0);
  requireRange(kOwner, "obstacle_recovery_share", obstacle_recovery_share, 1e-3, 1.0);
  requireRange(kOwner, "max_obstacle_rows", max_obstacle_rows, 0, 1000);
  requireRange(kOwner, "max_qp_iterations", max_qp_iterations, 1, 100000);
  const std::vector<std::string> solvers = qpSolverNames();
  if (std::find(solvers.begin(), solvers.end(), qp_solver) == solvers.end())
    throw std::invalid_argument("[QpControllerParams] qp_solver must be one of: " + knownQpSolvers() + " (got '" +
                                qp_solver + "')");
  requireRange(kOwner, "tsmm_switch_distance", tsmm_switch_distance, 0.0, 5.0);
  requireRange(kOwner, "arrival_position", arrival_position, 1e-5, 1.0);
  requireRange(kOwner, "arrival_orientation", arrival_orientation, 1e-5, M_PI);
}

std::string QpControllerParams::summary() const {
  std::ostringstream os;
  os << "controller: mode " << toString(mode) << ", w_arm " << arm_weight << ", ehc base weight ["
     << ehc_base_weight_min << ", " << ehc_base_weight_max << "], neo_c base weight "
     << neo_c_base_weight << ", |e| floor " << min_error << ", slack bound " << slack_bound
     << ", k_eps " << base_turn_gain << (base_turn_unwinding ? " (unwound)" : "") << ", k_m " << manipulability_gain
     << (manipulability_fade_distance > 0.0 ? " (fading within " + std::to_string(manipulability_fade_distance) + " m)" : std::string())
     << ", k_p "
     << posture_gain << ", limit centring " << limit_centring_gain << "; " << far_approach.summary() << "; " << wrist_flip.summary() << "; " << recovery.summary() << "\n"
     << "  joint dampers: influence " << joint_influence << " rad, stop " << joint_stop
     << " rad, gain " << joint_damper_gain << "; obstacle dampers: d_i " << obstacle_influence
     << " m, d_s " << obstacle_stop << " m";
  for (const auto& [link, d] : obstacle_stop_links) os << " (" << link << " " << d << " m)";
  os << ", gain " << obstacle_damper_gain << ", recovery inside d_s " << obstacle_recovery_gain << " 1/s (at most "
     << obstacle_recovery_share << " of the fastest opening), at most " << max_obstacle_rows << " rows (nearest first)"
     << "; QP " << qp_solver << ", at most " << max_qp_iterations << " iterations"
     << "; tsmm switch " << tsmm_switch_distance << " m; arrival " << arrival_position << " m / "
     << arrival_orientation * 180.0 / M_PI << " deg";
  return os.str();
}

QpControllerParams loadQpControllerParams(const ehc_common::ConfigNode& n) {
  QpControllerParams p;
  if (n.has("mode")) {
    const std::string m = n.require<std::string>("mode");
    try {
      p.mode = controlModeFromString(m);
    } catch (const std::invalid_argument&) {
      n.fail("mode", "must be ehc, ehc_place, neo_e, neo_c or tsmm (got '" + m + "')");
    }
  }
  p.arm_weight = n.get("arm_weight", p.arm_weight);
  p.ehc_base_weight_min = n.get("ehc_base_weight_min", p.ehc_base_weight_min);
  p.ehc_base_weight_max = n.get("ehc_base_weight_max", p.ehc_base_weight_max);
  p.neo_c_base_weight = n.get("neo_c_base_weight", p.neo_c_base_weight);
  p.min_error = n.get("min_error", p.min_error);
  p.slack_bound = n.get("slack_bound", p.slack_bound);
  p.base_turn_gain = n.get("base_turn_gain", p.base_turn_gain);
  p.base_turn_unwinding = n.get("base_turn_unwinding", p.base_turn_unwinding);
  p.manipulability_gain = n.get("manipulability_gain", p.manipulability_gain);
  p.manipulability_fade_distance = n.get("manipulability_fade_distance", p.manipulability_fade_distance);
  p.posture_gain = n.get("posture_gain", p.posture_gain);
  {
    const ehc_common::ConfigNode far = n.childOrEmpty("far_approach");
    p.far_approach.distance = far.get("distance", p.far_approach.distance);
    p.far_approach.face_target = far.get("face_target", p.far_approach.face_target);
    p.far_approach.posture_gain = far.get("posture_gain", p.far_approach.posture_gain);
    p.far_approach.orientation_release = far.get("orientation_release", p.far_approach.orientation_release);
  }
  p.limit_centring_gain = n.get("limit_centring_gain", p.limit_centring_gain);
  {
    const ehc_common::ConfigNode flip = n.childOrEmpty("wrist_flip");
    p.wrist_flip.margin = flip.get("margin", p.wrist_flip.margin);
    p.wrist_flip.speed = flip.get("speed", p.wrist_flip.speed);
    p.wrist_flip.gain = flip.get("gain", p.wrist_flip.gain);
    p.wrist_flip.tolerance = flip.get("tolerance", p.wrist_flip.tolerance);
  }
  p.recovery = loadReachRecoveryParams(n.childOrEmpty("recovery"));
  p.joint_influence = n.get("joint_influence", p.joint_influence);
  p.joint_stop = n.get("joint_stop", p.joint_stop);
  p.joint_damper_gain = n.get("joint_damper_gain", p.joint_damper_gain);
  p.obstacle_influence = n.get("obstacle_influence", p.obstacle_influence);
  p.obstacle_stop = n.get("obstacle_stop", p.obstacle_stop);
  if (n.has("obstacle_stop_links"))  // robot-specific: lives in robot.yaml now
    n.fail("obstacle_stop_links", "names robot links: move it to the robot's robot.yaml as robot.obstacle_stop_distances");
  p.obstacle_damper_gain = n.get("obstacle_damper_gain", p.obstacle_damper_gain);
  p.obstacle_recovery_gain = n.get("obstacle_recovery_gain", p.obstacle_recovery_gain);
  p.obstacle_recovery_share = n.get("obstacle_recovery_share", p.obstacle_recovery_share);
  p.max_obstacle_rows = n.get("max_obstacle_rows", p.max_obstacle_rows);
  p.max_qp_iterations = n.get("max_qp_iterations", p.max_qp_iterations);
  p.qp_solver = n.get("qp_solver", p.qp_solver);
  p.tsmm_switch_distance = n.get("tsmm_switch_distance", p.tsmm_switch_distance);
  p.arrival_position = n.get("arrival_position", p.arrival_position);
  p.arrival_orientation = n.get("arrival_orientation_deg", p.arrival_orientation * 180.0 / M_PI) * M_PI / 180.0;
  n.validate(p);  // errors name the file and the section
  return p;
}

Vector6d poseError(const Eigen::Isometry3d& tcp, const Eigen::Isometry3d& target) {
  Vector6d e;
  e.head<3>() = target.translation() - tcp.translation();
  const Eigen::AngleAxisd aa(Eigen::Matrix3d(target.linear() * tcp.linear().transpose()));
  e.tail<3>() = aa.axis() * aa.angle();
  return e;
}

/// The QP solver and every per-cycle matrix, sized on first use: once warm, step() allocates
/// nothing but the returned command.
struct EhcQpController::Workspace {
  std::unique_ptr<QpSolver> qp;       ///< params.qp_solver, at most max_qp_iterations steps
  Eigen::MatrixXd G, C;               ///< QP in the free rates: cost, inequality rows (top-left blocks used)
  Eigen::VectorXd g, d, x_free;
  Eigen::MatrixXd no_rows;            ///< 0 x nd: the QP has no equality rows
  Eigen::VectorXd no_rhs;
  Eigen::Matrix<double, 6, Eigen::Dynamic> task;  ///< TCP task rows over the free rates (held columns 0)
  Vector6d task_rhs = Vector6d::Zero();           ///< nu_e minus the held rates' share
  std::array<bool, 6> task_released{};            ///< orientation rows left to the slack
  std::vector<int> free;              ///< DOFs in the QP (not held), ascending

  KinematicState kinematics;          ///< one FK pass per cycle
  int tcp_link = -1;                  ///< tree index of the TCP
  Matrix6Xd J, J_arm, J_point;        ///< TCP (world, arm) and obstacle point Jacobians
  Eigen::VectorXd Jm, h, c, lb, ub, x_eigen;
  std::vector<char> held;             ///< per QP variable: left out of the problem (tsmm, wrist flip)
  Eigen::VectorXd fixed;              ///< per QP variable: the value of a held one (0, or a wrist flip rate)
  Eigen::VectorXd last_arm_rates;     ///< arm rates of this command (0 unless it succeeded)
  Eigen::VectorXd prev_arm_rates;     ///< arm rates of the previous command
  Eigen::MatrixXd row_a;              ///< obstacle damper rows, one per column
  std::vector<double> row_b;
  int n_rows = 0;
  std::vector<std::pair<double, const ObstaclePair*>> nearest;  ///< this cycle's obstacle pairs, nearest first
  /// Obstacle pair links resolved to tree indices and stop distances once: the entry of the
  /// pair at position k stays valid while the pair at k names the same link.
  struct PairLink {
    std::string name;
    int index = -1;
    double stop = 0.0;
  };
  std::vector<PairLink> pair_links;
};

EhcQpController::EhcQpController(std::shared_ptr<const WholeBodyModel> model,
                                 const QpControllerParams& params,
                                 std::shared_ptr<const EhcWeighting> weighting)
    : model_(std::move(model)), params_(params), weighting_(std::move(weighting)),
      ws_(std::make_unique<Workspace>()) {
  if (!model_) throw std::invalid_argument("[EhcQpController] no whole-body model");
  // Per-link stop distances: robot.yaml's robot.obstacle_stop_distances, unless set in params.
  for (const auto& kv : model_->config().obstacle_stop_distances) params_.obstacle_stop_links.insert(kv);
  for (const auto& kv : params_.obstacle_stop_links)
    if (!model_->hasLink(kv.first))
      throw std::invalid_argument("[EhcQpController] obstacle_stop_links names link '" + kv.first +
                                  "' which is not in the robot's URDF");
  params_.validate();
  if (usesWeighting(params_.mode) && !weighting_)
    throw std::invalid_argument("[EhcQpController] mode " + toString(params_.mode) + " needs a reachability map (EhcWeighting)");
  const RobotConfig& rc = model_->config();
  base_T_arm_ = model_->linkPoseInBase(rc.arm_ready, rc.arm_base_frame);
  vmax_ = rc.velocityLimits();
  ws_->tcp_link = model_->linkIndex(rc.tcp_frame);
  yaw_joint_ = armYawJoint(*model_);
  flip_ = std::make_unique<WristFlip>(*model_, params_.wrist_flip);
  ws_->last_arm_rates = Eigen::VectorXd::Zero(model_->nArm());
  ws_->no_rows.resize(0, model_->nDof());
  ws_->free.reserve(static_cast<std::size_t>(model_->nDof()));
  ws_->qp = makeQpSolver(params_.qp_solver);
}

EhcQpController::~EhcQpController() = default;

const QpSolver& EhcQpController::qpSolver() const { return *ws_->qp; }

void EhcQpController::setQpSolver(std::unique_ptr<QpSolver> solver) {
  if (!solver) throw std::invalid_argument("[EhcQpController] no QP solver");
  ws_->qp = std::move(solver);
}

int armYawJoint(const WholeBodyModel& model) {
  const RobotConfig& rc = model.config();
  const Matrix6Xd J = model.armJacobian(rc.arm_ready, rc.tcp_frame);
  for (int i = 0; i < model.nArm(); ++i) {
    const Eigen::Vector3d axis = J.block<3, 1>(3, i);
    if (axis.norm() > 0.5 && std::abs(axis.normalized().z()) > 1.0 - 1e-6) return i;
  }
  return -1;
}

double unwoundBearing(double bearing, double winding) {
  while (bearing - winding > M_PI) bearing -= 2.0 * M_PI;
  while (bearing - winding < -M_PI) bearing += 2.0 * M_PI;
  return bearing;
}

void EhcQpController::reset() {
  // Nothing of the QP carries over between cycles (each solve starts at the unconstrained
  // minimum).
  // The tsmm stage is not reset here (a new goal near the grasping position keeps the base
  // standing); step() leaves the arm stage for a target farther than d from the switch point.
}

void EhcQpController::setMode(ControlMode m) {
  if (usesWeighting(m) && !weighting_)
    throw std::invalid_argument("[EhcQpController] mode " + toString(m) + " needs a reachability map (EhcWeighting)");
  params_.mode = m;
  reset();
  tsmm_arm_stage_ = false;
}

EhcWeight EhcQpController::weight(const Eigen::Vector3d& base_pose, const Eigen::Vector3d& tcp_world,
                                  const Eigen::Vector3d& target_world) const {
  if (!weighting_) throw std::invalid_argument("[EhcQpController] no EHC weighting (reachability map) configured");
  if (!base_pose.allFinite() || !tcp_world.allFinite() || !target_world.allFinite())
    throw std::invalid_argument("[EhcQpController] non-finite input to weight()");
  const Eigen::Isometry3d arm_T_world = (WholeBodyModel::baseTransform(base_pose) * base_T_arm_).inverse();
  return weighting_->evaluate(arm_T_world * tcp_world, arm_T_world * target_world);
}

ControllerCommand EhcQpController::fail(ControllerCommand c, const std::string& why) const {
  c.velocity = Eigen::VectorXd::Zero(model_->nDof());
  c.slack.setZero();
  c.ok = false;
  c.qp_status = QpStatus::Failed;
  c.failure = why;
  flip_->cancel();  // a flip resumes only from a fresh decision
  return c;
}

void EhcQpController::nearestObstaclePairs(const std::vector<ObstaclePair>& obstacles,
                                           std::vector<std::pair<double, const ObstaclePair*>>* ranked,
                                           std::string* bad_pair) const {
  ranked->clear();
  for (const ObstaclePair& o : obstacles) {
    if (!(std::isfinite(o.distance) && o.link_point.allFinite() && o.normal.allFinite())) {
      *bad_pair = "non-finite obstacle pair for link '" + o.link + "'";
      ranked->clear();
      return;
    }
    if (o.distance >= params_.obstacle_influence) continue;
    if (!model_->hasLink(o.link)) {
      *bad_pair = "obstacle pair for unknown link '" + o.link + "'";
      ranked->clear();
      return;
    }
    if (o.normal.norm() < 1e-9) {
      *bad_pair = "obstacle pair with a zero normal for link '" + o.link + "'";
      ranked->clear();
      return;
    }
    // Margin to the link's stop distance, looked up once per pair (not per comparison).
    ranked->emplace_back(o.distance - params_.obstacleStop(o.link), &o);
  }
  const std::size_t keep = std::min(ranked->size(), static_cast<std::size_t>(params_.max_obstacle_rows));
  // Nearest first: smallest margin; ties keep the input order (the pointers into `obstacles`
  // ascend with it). A partial sort on (margin, pointer) gives the order of a stable sort
  // without its buffer (no allocation per cycle).
  std::partial_sort(ranked->begin(), ranked->begin() + static_cast<std::ptrdiff_t>(keep), ranked->end(),
                    [](const auto& a, const auto& b) { return a.first < b.first || (a.first == b.first && a.second < b.second); });
  ranked->resize(keep);
}

std::vector<const ObstaclePair*> EhcQpController::nearestObstaclePairs(const std::vector<ObstaclePair>& obstacles,
                                                                       std::string* bad_pair) const {
  std::vector<std::pair<double, const ObstaclePair*>> ranked;
  nearestObstaclePairs(obstacles, &ranked, bad_pair);
  std::vector<const ObstaclePair*> out;
  out.reserve(ranked.size());
  for (const auto& r : ranked) out.push_back(r.second);
  return out;
}

ControllerCommand EhcQpController::step(const Eigen::Vector3d& base_pose, const Eigen::VectorXd& q,
                                        const Eigen::Isometry3d& target, const Vector6d& nu_e,
                                        const std::vector<ObstaclePair>& obstacles,
                                        const EhcWeight* weight, const Eigen::VectorXd* reference) {
  const auto t0 = std::chrono::steady_clock::now();
  const int na = model_->nArm(), nd = model_->nDof();
  ControllerCommand out;
  out.velocity = Eigen::VectorXd::Zero(nd);

  if (q.size() != na) return fail(out, "arm state has " + std::to_string(q.size()) + " joints, expected " + std::to_string(na));
  if (!q.allFinite() || !base_pose.allFinite()) return fail(out, "non-finite robot state");
  if (!target.matrix().allFinite()) return fail(out, "non-finite target pose");
  if (!nu_e.allFinite()) return fail(out, "non-finite desired twist");
  if (reference && (reference->size() != nd || !reference->allFinite()))
    return fail(out, "reference velocity must have " + std::to_string(nd) + " finite entries");

  // --- model: one FK pass; TCP pose, whole-body Jacobian, manipulability gradient
  const Eigen::Isometry3d T_tcp = updateKinematics(base_pose, q, &out.manipulability);

  // --- errors and weighting
  const Vector6d e = poseError(T_tcp, target);
  out.position_error = e.head<3>().norm();
  out.orientation_error = e.tail<3>().norm();
  out.error_norm = e.cwiseAbs().sum();
  const double e_floor = std::max(out.error_norm, params_.min_error);
  reportWeighting(base_pose, T_tcp, target, weight, &out);
  const HeldGroups held = applyMode(e, target, e_floor, &out);

  // --- cost, bounds and joint dampers, obstacle dampers, wrist flip
  buildCost(q, ws_->kinematics.baseTransform().inverse() * target.translation(), e_floor, out, reference);
  std::string failure = buildBounds(q, held, &out);
  if (!failure.empty()) return fail(out, failure);
  failure = buildObstacleRows(obstacles, &out);
  if (!failure.empty()) return fail(out, failure);
  const bool flip = applyWristFlip(q, held, reference == nullptr, &out);

  // --- the QP in the rates alone (see buildTaskAndCost), solved through the QpSolver interface
  if (reference) buildTaskAndCost(ws_->J * *reference, held.arm ? 0.0 : 1.0);
  else
    buildTaskAndCost(nu_e, held.arm || flip ? 0.0
                                            : 1.0 - params_.far_approach.orientation_release *
                                                        params_.far_approach.fraction(out.position_error));
  QpSolveResult solved = QpSolveResult::Infeasible;
  try {
    solved = solveQp(&out);
  } catch (const std::invalid_argument& ex) {  // a cost that is not positive definite (not finite)
    out.solve_time_us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
    return fail(out, std::string("QP: ") + ex.what());
  }
  out.solve_time_us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
  if (solved == QpSolveResult::IterationLimit)
    return fail(out, "QP iteration limit (" + std::to_string(params_.max_qp_iterations) +
                         " active-set iterations, degenerate constraints)");
  if (solved != QpSolveResult::Solved) return fail(out, "QP infeasible");
  failure = assembleCommand(&out);
  if (!failure.empty()) return fail(out, failure);
  return out;
}

QpSolveResult EhcQpController::solveQp(ControllerCommand* out) {
  Workspace& s = *ws_;
  const int nf = static_cast<int>(s.free.size());
  auto solve = [&] {
    const int rows = buildInequalities();
    const QpProblemView problem(s.G.topLeftCorner(nf, nf), s.g.head(nf), s.no_rows.leftCols(nf), s.no_rhs,
                                s.C.topLeftCorner(rows, nf), s.d.head(rows));
    const QpSolveResult r = s.qp->solve(problem, &s.x_free, params_.max_qp_iterations);
    out->qp_iterations += s.qp->iterations();
    return r;
  };
  out->qp_iterations = 0;
  const QpSolveResult first = solve();
  if (first != QpSolveResult::Infeasible) return first;
  // Pairs inside d_s that cannot all open at once (a finger each side of an obstacle, a link
  // pushed against a joint damper): holding them (d_dot >= 0) keeps the robot from going deeper
  // and lets the task move it along and out; a zero command every cycle would hold it there for good.
  bool opening = false;
  for (int r = 0; r < s.n_rows; ++r)
    if (s.row_b[static_cast<std::size_t>(r)] < 0.0) {
      s.row_b[static_cast<std::size_t>(r)] = 0.0;
      opening = true;
    }
  if (!opening) return first;
  out->obstacles_held = true;
  return solve();
}

Eigen::Isometry3d EhcQpController::updateKinematics(const Eigen::Vector3d& base_pose, const Eigen::VectorXd& q,
                                                   double* manipulability) {
  const WholeBodyModel& m = *model_;
  Workspace& s = *ws_;
  // The previous command's arm rates (for WristFlip); zero unless this step succeeds.
  s.prev_arm_rates.swap(s.last_arm_rates);
  s.last_arm_rates.setZero(m.nArm());
  m.updateKinematics(base_pose, q, &s.kinematics);
  const Eigen::Isometry3d T_tcp = s.kinematics.linkPose(s.tcp_link);
  m.jacobian(s.kinematics, s.tcp_link, &s.J, &s.J_arm);
  m.manipulabilityGradientFromJacobian(s.J_arm, s.Jm, manipulability);
  return T_tcp;
}

void EhcQpController::reportWeighting(const Eigen::Vector3d& base_pose, const Eigen::Isometry3d& T_tcp,
                                      const Eigen::Isometry3d& target, const EhcWeight* weight,
                                      ControllerCommand* out) const {
  if (weight) {
    out->omega = weight->omega;
    out->sig = weight->sig;
  } else if (weighting_) {
    const EhcWeight w = this->weight(base_pose, T_tcp.translation(), target.translation());
    out->omega = w.omega;
    out->sig = w.sig;
  }
}

EhcQpController::HeldGroups EhcQpController::applyMode(const Vector6d& e, const Eigen::Isometry3d& target,
                                                       double e_floor, ControllerCommand* out) {
  HeldGroups held;
  switch (params_.mode) {
    case ControlMode::Ehc:
    case ControlMode::EhcPlace:
      out->base_weight = params_.ehc_base_weight_min +
                         (params_.ehc_base_weight_max - params_.ehc_base_weight_min) * out->sig;
      break;
    case ControlMode::NeoE:
      out->base_weight = params_.arm_weight / e_floor;
      break;
    case ControlMode::NeoC:
      out->base_weight = params_.neo_c_base_weight;
      break;
    case ControlMode::Tsmm: {
      const double horizontal = e.head<2>().norm();
      if (tsmm_arm_stage_ &&
          (target.translation() - tsmm_stage_target_).head<2>().norm() > params_.tsmm_switch_distance)
        tsmm_arm_stage_ = false;  // a target away from the grasping position: the base drives again
      if (!tsmm_arm_stage_ && horizontal <= params_.tsmm_switch_distance) {
        tsmm_arm_stage_ = true;
        tsmm_stage_target_ = target.translation();
      }
      out->base_weight = params_.arm_weight;
      held.arm = !tsmm_arm_stage_;
      held.base = tsmm_arm_stage_;
      out->phase = tsmm_arm_stage_ ? ControlPhase::TsmmArm : ControlPhase::TsmmBase;
      break;
    }
  }
  if (out->position_error < params_.arrival_position && out->orientation_error < params_.arrival_orientation)
    out->phase = ControlPhase::Arrived;
  return held;
}

double EhcQpController::turnBearing(const Eigen::VectorXd& q, const Eigen::Vector3d& target_in_base, double far) {
  const Workspace& s = *ws_;
  const RobotConfig& rc = model_->config();
  Eigen::Vector3d towards = s.kinematics.linkPoseInBase(s.tcp_link).translation();
  // Far from the target the base faces the target's way, not the TCP's (FarApproachParams).
  if (params_.far_approach.face_target) towards += far * (target_in_base - towards);
  double bearing = std::atan2(towards.y(), towards.x());
  if (params_.base_turn_unwinding && yaw_joint_ >= 0) {
    // The branch of the yaw joint's winding, while the TCP lies on the side the yaw joint
    // points to. Reaching over the shoulder (the TCP more than 90 deg from that direction)
    // the winding's branch border (TCP opposite the yaw joint) is near, and sensor noise would
    // flip the bearing by 2 pi and the base turn with it, cycle to cycle (Exp-1 traces: the
    // base chattering between -1.0 and +0.3 rad/s for 20 s, TCP 2-7 cm short): there the
    // bearing continues the previous cycle's branch instead.
    const double winding = q[yaw_joint_] - rc.arm_ready[yaw_joint_];
    const double relative = std::remainder(bearing - winding, 2.0 * M_PI);
    bearing = unwoundBearing(bearing, have_bearing_ && std::abs(relative) > 0.5 * M_PI ? last_bearing_ : winding);
    last_bearing_ = bearing;
    have_bearing_ = true;
  }
  return bearing;
}

void EhcQpController::buildCost(const Eigen::VectorXd& q, const Eigen::Vector3d& target_in_base, double e_floor,
                                const ControllerCommand& out, const Eigen::VectorXd* reference) {
  const RobotConfig& rc = model_->config();
  const int nb = model_->nBase(), na = model_->nArm(), nx = model_->nDof() + 6;
  Workspace& s = *ws_;
  Eigen::VectorXd& h = s.h;
  Eigen::VectorXd& c = s.c;
  h.resize(nx);
  c.setZero(nx);
  h.head(nb).setConstant(out.base_weight);
  h.segment(nb, na).setConstant(params_.arm_weight);
  h.tail(6).setConstant(1.0 / e_floor);
  if (reference) {  // track the reference: minimum of 1/2 qd^T H qd + c^T qd at qd = reference
    c.head(nb + na) = -h.head(nb + na).cwiseProduct(*reference);
    return;
  }
  const double far = params_.far_approach.fraction(out.position_error);
  const double bearing = turnBearing(q, target_in_base, far);
  c[nb - 1] = -params_.base_turn_gain * bearing;
  const double fade = params_.manipulability_fade_distance > 0.0
                          ? std::min(1.0, out.position_error / params_.manipulability_fade_distance)
                          : 1.0;
  const double posture = params_.posture_gain + far * params_.far_approach.posture_gain;
  c.segment(nb, na) = -params_.manipulability_gain * fade * s.Jm + posture * (q - rc.arm_ready);
  if (params_.limit_centring_gain > 0.0)
    JointLimitCentring{params_.limit_centring_gain, params_.joint_influence, params_.joint_stop}
        .addGradient(q, rc.arm_lower, rc.arm_upper, c.segment(nb, na));
}

std::string EhcQpController::buildBounds(const Eigen::VectorXd& q, const HeldGroups& groups, ControllerCommand* out) {
  const RobotConfig& rc = model_->config();
  const int nb = model_->nBase(), na = model_->nArm(), nd = model_->nDof(), nx = nd + 6;
  Workspace& s = *ws_;
  Eigen::VectorXd& ub = s.ub;
  Eigen::VectorXd& lb = s.lb;
  ub.resize(nx);
  ub.head(nd) = vmax_;
  ub.tail(6).setConstant(params_.slack_bound);
  lb = -ub;
  // Held DOFs (tsmm stages) leave the problem: zero Jacobian column, no cost, no bound rows;
  // the separable optimum is then exactly 0. (Bounds lb = ub = 0 would make two opposite rows
  // active at once, a degenerate active set.)
  std::vector<char>& held = s.held;
  held.assign(static_cast<std::size_t>(nx), 0);
  for (int i = 0; i < nd; ++i) held[static_cast<std::size_t>(i)] = i < nb ? groups.base : groups.arm;

  // --- joint-position velocity dampers (arm joints within the influence angle). A damper
  // constrains a single joint rate, so it is applied as a tightened bound (identical feasible
  // set to an extra row; duplicate parallel rows would make the active set degenerate):
  //   -qd_i <= xi (q - q_min - ps) / (pi - ps),   qd_i <= xi (q_max - q - ps) / (pi - ps)
  const double pi = params_.joint_influence, ps = params_.joint_stop;
  for (int i = 0; i < na; ++i) {
    const double to_lower = q[i] - rc.arm_lower[i], to_upper = rc.arm_upper[i] - q[i];
    if (to_lower < pi) {
      lb[nb + i] = std::max(lb[nb + i], -params_.joint_damper_gain * (to_lower - ps) / (pi - ps));
      ++out->joint_damper_rows;
    }
    if (to_upper < pi) {
      ub[nb + i] = std::min(ub[nb + i], params_.joint_damper_gain * (to_upper - ps) / (pi - ps));
      ++out->joint_damper_rows;
    }
    if (lb[nb + i] > ub[nb + i]) return "joint " + rc.arm_joints[static_cast<std::size_t>(i)] + " dampers are contradictory";
  }
  return std::string();
}

std::string EhcQpController::buildObstacleRows(const std::vector<ObstaclePair>& obstacles, ControllerCommand* out) {
  const WholeBodyModel& m = *model_;
  const int nd = m.nDof(), nx = nd + 6;
  Workspace& s = *ws_;
  const std::vector<char>& held = s.held;
  // --- obstacle velocity dampers, one row per link-obstacle pair closer than d_i
  std::string bad_pair;
  nearestObstaclePairs(obstacles, &s.nearest, &bad_pair);
  if (!bad_pair.empty()) return bad_pair;
  const std::size_t n_pairs = s.nearest.size();  // <= max_obstacle_rows: buffers grow only
  if (s.row_a.rows() != nx || s.row_a.cols() < static_cast<Eigen::Index>(n_pairs))
    s.row_a.resize(nx, static_cast<Eigen::Index>(std::max<std::size_t>(n_pairs, 1)));
  if (s.row_b.size() < n_pairs) s.row_b.resize(n_pairs);
  if (s.pair_links.size() < n_pairs) {
    s.pair_links.resize(n_pairs);
    for (Workspace::PairLink& link : s.pair_links) link.name.reserve(64);  // a name change copies, no allocation
  }
  s.n_rows = 0;
  const double di = params_.obstacle_influence;
  for (std::size_t k = 0; k < n_pairs; ++k) {
    const ObstaclePair& o = *s.nearest[k].second;
    Workspace::PairLink& link = s.pair_links[k];  // link index and d_s, cached per row
    if (link.index < 0 || link.name != o.link) {
      link.name = o.link;
      link.index = m.linkIndex(o.link);
      link.stop = params_.obstacleStop(o.link);
    }
    const double ds = link.stop;
    const Eigen::Vector3d n = o.normal.normalized();
    // Linear velocity of the link point: rows 0-2 of its Jacobian.
    m.pointJacobian(s.kinematics, link.index, o.link_point, &s.J_point);
    // d_dot = n^T J_p qd >= -xi (d - d_s) / (d_i - d_s)
    auto a = s.row_a.col(s.n_rows);
    a.head(nd).noalias() = s.J_point.topRows<3>().transpose() * (-n);
    a.tail(6).setZero();
    // Held DOFs (tsmm stages) cannot move the point: a pair only they move (the base link in
    // the arm stage) leaves no row (a zero row only adds a degenerate constraint).
    for (int i = 0; i < nd; ++i)
      if (held[static_cast<std::size_t>(i)]) a[i] = 0.0;
    double b = params_.obstacle_damper_gain * (o.distance - ds) / (di - ds);
    // Inside d_s: out at least at the recovery rate (QpControllerParams::obstacle_recovery_gain).
    if (o.distance < ds) b = std::min(b, params_.obstacle_recovery_gain * (o.distance - ds));
    if (b < 0.0) {  // an opening demanded: at most its share of the fastest within the bounds
      double fastest = 0.0;  // max of -a.qd over lb <= qd <= ub
      for (int i = 0; i < nd; ++i) fastest += std::max(-a[i] * s.lb[i], -a[i] * s.ub[i]);
      b = std::max(b, -params_.obstacle_recovery_share * std::max(fastest, 0.0));
    }
    const double norm = a.norm();
    ++out->obstacle_rows;
    if (norm < 1e-9) continue;  // the link point cannot move along n: nothing to constrain
    a /= norm;
    b /= norm;
    // Parallel rows (e.g. two links sharing an origin) are redundant: keep the tighter one.
    bool merged = false;
    for (int r = 0; r < s.n_rows; ++r)
      if (s.row_a.col(r).dot(a) > 1.0 - 1e-6) {
        s.row_b[static_cast<std::size_t>(r)] = std::min(s.row_b[static_cast<std::size_t>(r)], b);
        merged = true;
        break;
      }
    if (!merged) s.row_b[static_cast<std::size_t>(s.n_rows++)] = b;
  }
  return std::string();
}

bool EhcQpController::applyWristFlip(const Eigen::VectorXd& q, const HeldGroups& groups, bool may_run,
                                     ControllerCommand* out) {
  const int nb = model_->nBase(), nx = model_->nDof() + 6;
  Workspace& s = *ws_;
  // --- wrist flip (WristFlip): the triple's rates are prescribed (held at the flip rate, within
  // the bounds and dampers), the orientation rows go to the slack; not when arrived, with the
  // arm held, or with an obstacle within influence (the flip sweeps the hand).
  const bool flip =
      flip_->update(q, s.prev_arm_rates, may_run && !groups.arm && out->phase != ControlPhase::Arrived && s.nearest.empty());
  s.fixed.setZero(nx);
  if (flip) {
    for (int k = 0; k < 3; ++k) {
      const int i = nb + flip_->first() + k;
      s.held[static_cast<std::size_t>(i)] = 1;
      s.fixed[i] = std::clamp(flip_->rates()[k], s.lb[i], s.ub[i]);
    }
    out->wrist_flip = true;
    out->event = flip_->event();
  }
  return flip;
}

void EhcQpController::buildTaskAndCost(const Vector6d& nu_e, double orientation_scale) {
  const int nd = model_->nDof();
  Workspace& s = *ws_;
  const Matrix6Xd& J = s.J;
  const std::vector<char>& held = s.held;
  const Eigen::VectorXd& h = s.h;
  const Eigen::VectorXd& c = s.c;
  // --- the QP in the rates alone. The slack is what the task rows leave, delta = nu_e - J qd,
  // so its cost and bounds become terms in qd (the same optimum as with delta as variables and
  // [J I] x = nu_e as equality rows, in n_dof instead of n_dof + 6 variables, no equality rows):
  //   min 1/2 qd^T (H_qd + w_delta J^T J) qd + (c_qd - w_delta J^T nu_e)^T qd
  //   s.t.  lb <= qd <= ub,   -delta+ <= nu_e - J qd <= delta+,   obstacle rows
  // over the DOFs not held; a held DOF's value (0, or a wrist-flip rate) moves to the right-hand
  // sides, and a released task row (orientation in the tsmm base stage or a wrist flip) has
  // delta = 0 and no row.
  s.free.clear();
  for (int i = 0; i < nd; ++i)
    if (!held[static_cast<std::size_t>(i)]) s.free.push_back(i);
  const int nf = static_cast<int>(s.free.size());
  const double w_slack = h[nd];  // the six slack weights are equal (1 / max(|e|, e_min))
  s.task.setZero(6, nd);
  for (int r = 0; r < 6; ++r) {
    // The tsmm base stage only brings the TCP to the target position (orientation comes with
    // the arm stage), and so does a wrist flip: their orientation rows are left to the slack.
    const double scale = r >= 3 ? orientation_scale : 1.0;
    s.task_released[r] = scale <= 0.0;
    double br = s.task_released[r] ? 0.0 : nu_e[r];
    if (!s.task_released[r])
      for (int k = 0; k < nd; ++k) {
        if (held[static_cast<std::size_t>(k)])
          br -= J(r, k) * s.fixed[k];  // a prescribed rate's share of the task
        else
          s.task(r, k) = J(r, k);
      }
    s.task.row(r) *= scale;
    s.task_rhs[r] = scale * br;
  }
  if (s.G.rows() < nd) s.G.resize(nd, nd);
  if (s.g.size() < nd) s.g.resize(nd);
  for (int a = 0; a < nf; ++a) {
    const int ia = s.free[static_cast<std::size_t>(a)];
    for (int b = 0; b <= a; ++b)
      s.G(a, b) = s.G(b, a) = w_slack * s.task.col(ia).dot(s.task.col(s.free[static_cast<std::size_t>(b)]));
    s.G(a, a) += h[ia];
    s.g[a] = c[ia] - w_slack * s.task.col(ia).dot(s.task_rhs);
  }
}

int EhcQpController::buildInequalities() {
  const int nd = model_->nDof();
  Workspace& s = *ws_;
  const std::vector<char>& held = s.held;
  const int nf = static_cast<int>(s.free.size());
  const int n_in = 2 * nf + 12 + s.n_rows;
  if (s.C.rows() < n_in || s.C.cols() < nd) s.C.resize(std::max<Eigen::Index>(n_in, s.C.rows()), nd);
  if (s.d.size() < n_in) s.d.resize(s.C.rows());
  s.C.topLeftCorner(n_in, nf).setZero();
  int row = 0;
  for (int a = 0; a < nf; ++a) {  // velocity bounds and dampers
    const int i = s.free[static_cast<std::size_t>(a)];
    s.C(row, a) = 1.0;
    s.d[row++] = s.ub[i];
    s.C(row, a) = -1.0;
    s.d[row++] = -s.lb[i];
  }
  for (int r = 0; r < 6; ++r) {  // slack bounds: |nu_e - J qd| <= delta+
    if (s.task_released[r]) continue;
    for (int a = 0; a < nf; ++a) {
      s.C(row, a) = s.task(r, s.free[static_cast<std::size_t>(a)]);
      s.C(row + 1, a) = -s.C(row, a);
    }
    s.d[row++] = params_.slack_bound + s.task_rhs[r];
    s.d[row++] = params_.slack_bound - s.task_rhs[r];
  }
  for (int r = 0; r < s.n_rows; ++r) {  // obstacle dampers
    double dr = s.row_b[static_cast<std::size_t>(r)];
    for (int k = 0; k < nd; ++k)
      if (held[static_cast<std::size_t>(k)]) dr -= s.row_a(k, r) * s.fixed[k];
    for (int a = 0; a < nf; ++a) s.C(row, a) = s.row_a(s.free[static_cast<std::size_t>(a)], r);
    s.d[row++] = dr;
  }
  return row;
}

std::string EhcQpController::assembleCommand(ControllerCommand* out) {
  const int nb = model_->nBase(), na = model_->nArm(), nd = model_->nDof(), nx = nd + 6;
  Workspace& s = *ws_;
  const std::vector<char>& held = s.held;
  const Eigen::VectorXd& lb = s.lb;
  const Eigen::VectorXd& ub = s.ub;
  const int nf = static_cast<int>(s.free.size());
  if (!s.x_free.allFinite()) return "QP solution is not finite";
  Eigen::VectorXd& x = s.x_eigen;  // [qd; delta]
  x.resize(nx);
  for (int i = 0; i < nd; ++i) x[i] = s.fixed[i];
  for (int a = 0; a < nf; ++a) x[s.free[static_cast<std::size_t>(a)]] = s.x_free[a];
  x.tail<6>() = s.task_rhs - s.task * x.head(nd);  // held columns of `task` are 0
  // The solver meets the bounds to its tolerance; clamp so limits are never exceeded.
  const double tol = 1e-4;
  bool violates = false;  // held variables are not in the problem (their value is set above)
  for (int i = 0; i < nx; ++i)
    violates = violates || (!held[static_cast<std::size_t>(i)] && (x[i] - ub[i] > tol || lb[i] - x[i] > tol));
  if (violates) return "QP solution violates the velocity bounds";
  for (int i = 0; i < nx; ++i)
    if (!held[static_cast<std::size_t>(i)]) x[i] = std::clamp(x[i], lb[i], ub[i]);
  out->velocity = x.head(nd);
  s.last_arm_rates = out->velocity.segment(nb, na);
  out->slack = x.tail<6>();
  out->ok = true;
  out->qp_status = QpStatus::Ok;
  return std::string();
}

}  // namespace ehc_control
