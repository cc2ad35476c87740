#include "ehc_control/control_cycle.h"

#include "ehc_common/config_node.h"
#include "ehc_common/enum_names.h"

#include <sstream>
#include <stdexcept>

using ehc_common::ConfigNode;

namespace ehc_control {

namespace {
constexpr ehc_common::EnumNames<ServoType, 2> kServoTypeNames = {{{ServoType::Proportional, "proportional"}, {ServoType::Pbvs, "pbvs"}}};
}  // namespace

std::string toString(ServoType type) { return ehc_common::enumName(kServoTypeNames, type, "ControlCycle"); }
ServoType servoTypeFromString(const std::string& s) { return ehc_common::enumValue(kServoTypeNames, s, "ControlCycle", "servo type"); }

void ControlCycleParams::validate() const {
  controller.validate();
  weighting.validate();
  servo.validate();
  pbvs.validate();
  mpbs.validate();
  tracking.validate();
  watchdog.validate();
  motion_limit.validate();
  ehc_common::requireRange("ControlCycleParams", "tracking.centre_timeout", centre_timeout, 1e-3, 3600.0);
}

ControlCycleParams loadControlCycleParams(const ConfigNode& root) {
  ControlCycleParams p;
  p.robot_file = root.has("robot") ? robotFileField(root, "robot") : resolveRobotFile("realman_rm65_water2");
  p.controller = loadQpControllerParams(root.childOrEmpty("controller"));
  p.weighting = loadEhcWeightingParams(root.childOrEmpty("weighting"));
  const ConfigNode servo = root.childOrEmpty("servo");
  const std::string type = servo.get<std::string>("type", toString(p.servo_type));
  try {
    p.servo_type = servoTypeFromString(type);
  } catch (const std::invalid_argument&) {
    servo.fail("type", "must be 'proportional' or 'pbvs' (got '" + type + "')");
  }
  p.servo = loadPoseServoParams(servo);
  p.pbvs = loadPbvsServoParams(servo);
  p.mpbs = loadMpbsParams(root.childOrEmpty("mpbs"));
  const ConfigNode tracking = root.childOrEmpty("tracking");
  p.tracking = loadTargetTrackerParams(tracking);
  p.centre_timeout = tracking.get("centre_timeout", p.centre_timeout);
  p.watchdog = loadSupervisorParams(root.childOrEmpty("watchdog"));
  p.motion_limit = loadMotionLimitParams(root.childOrEmpty("motion_limit"));
  root.validate(p);
  return p;
}

namespace {

std::shared_ptr<const WholeBodyModel> loadModel(const ControlCycleParams& params) {
  params.validate();
  if (params.robot_file.empty()) throw std::invalid_argument("[ControlCycle] no robot.yaml given (robot_file)");
  return std::make_shared<const WholeBodyModel>(loadRobotConfig(params.robot_file));
}

/// The EHC weighting of the robot's reachability map, nullptr if robot.yaml names none. The map
/// must be this robot's (name, frames, joints; the arm's kinematics when the map records them).
std::shared_ptr<const EhcWeighting> loadWeighting(const WholeBodyModel& model, const EhcWeightingParams& params) {
  const RobotConfig& rc = model.config();
  if (rc.reachability_map_path.empty()) return nullptr;
  auto map = std::make_shared<const ReachabilityMap>(ReachabilityMap::load(rc.reachability_map_path));
  map->checkCompatible(model);
  return std::make_shared<const EhcWeighting>(map, params);
}

}  // namespace

ControlCycle::ControlCycle(const ControlCycleParams& params) : ControlCycle(loadModel(params), params) {}

ControlCycle::ControlCycle(const std::shared_ptr<const WholeBodyModel>& model, const ControlCycleParams& params)
    : ControlCycle(model, loadWeighting(*model, params.weighting), params) {}

ControlCycle::ControlCycle(std::shared_ptr<const WholeBodyModel> model, std::shared_ptr<const EhcWeighting> weighting,
                           const ControlCycleParams& params)
    : params_(params), model_(std::move(model)), weighting_(std::move(weighting)) {
  if (!model_) throw std::invalid_argument("[ControlCycle] no whole-body model");
  params_.validate();
  const RobotConfig& rc = model_->config();
  controller_ = std::make_unique<EhcQpController>(model_, params_.controller, weighting_);
  recovery_ = std::make_unique<ReachRecovery>(*model_, params_.controller.recovery, params_.controller.joint_stop,
                                              params_.controller.joint_influence);
  if (weighting_) recovery_->setPlacementMap(weighting_);
  supervisor_ = std::make_unique<ControllerSupervisor>(rc, params_.watchdog);
  limits_ = std::make_unique<MotionLimitMonitor>(*model_, controller_->params(), params_.motion_limit);
  // Camera: mount on the hand (URDF) for MPBS and TfM, intrinsics from robot.yaml's
  // robot.camera_info (tracking.camera, if set, overrides it).
  if (!model_->hasLink(rc.camera_frame) || !model_->hasLink(rc.tcp_frame))
    throw std::invalid_argument("[ControlCycle] camera frame '" + rc.camera_frame + "' or TCP frame '" +
                                rc.tcp_frame + "' is not in the URDF");
  tcp_T_camera_ = model_->linkPoseInBase(rc.arm_ready, rc.tcp_frame).inverse() *
                  model_->linkPoseInBase(rc.arm_ready, rc.camera_frame);
  if (params_.tracking.camera_file.empty()) params_.tracking.camera_file = rc.camera_info_path;
  const PinholeCamera camera =
      params_.tracking.camera_file.empty() ? PinholeCamera{} : loadPinholeCamera(params_.tracking.camera_file);
  tracker_ = std::make_unique<TargetTracker>(camera, params_.tracking);
  if (params_.servo_type == ServoType::Pbvs && params_.mpbs.enabled && !controller_->hasWeighting())
    throw std::invalid_argument("[ControlCycle] mpbs.enabled needs sig(omega), i.e. a reachability map in robot.yaml");
  mpbs_ = std::make_unique<MpbsServo>(tcp_T_camera_, params_.pbvs, params_.mpbs);
  roll_index_ = findRollJoint(*model_);
}

std::string ControlCycle::setJointState(double t, const std::vector<std::string>& names,
                                        const std::vector<double>& positions) {
  return supervisor_->setJointState(t, names, positions);
}

std::string ControlCycle::setBasePose(double t, const Eigen::Vector3d& base_pose) {
  return supervisor_->setBasePose(t, base_pose);
}

std::string ControlCycle::setTarget(double t, const Eigen::Isometry3d& target) {
  const std::string err = supervisor_->setTarget(t, target);
  if (!err.empty()) return err;
  if (!have_target_ || !target.isApprox(last_target_, 1e-4)) controller_->reset();
  have_target_ = true;
  last_target_ = target;
  return "";
}

std::string ControlCycle::setWatchedCentre(double t, const Eigen::Vector3d& centre) {
  if (!centre.allFinite()) return "watched target centre contains NaN or Inf";
  centre_ = centre;
  t_centre_ = t;
  return "";
}

std::string ControlCycle::setObstacles(double t, const std::vector<ObstaclePair>& obstacles) {
  return supervisor_->setObstacles(t, obstacles);
}

Eigen::Vector3d ControlCycle::watchedCentre(double now) const {
  const double timeout = params_.centre_timeout;
  if (t_centre_ && now - *t_centre_ <= timeout && now - *t_centre_ >= -timeout) return centre_;
  return mpbs_->targetCentre(supervisor_->target());
}

ControlCycleOutput ControlCycle::zeroOutput(double now) const {
  ControlCycleOutput out;
  out.velocity = Eigen::VectorXd::Zero(model_->nDof());
  ControlCycleStatus& st = out.status;
  st.mode = controller_->params().mode;
  st.obstacles_required = params_.watchdog.require_obstacles;
  st.target_age = supervisor_->targetAge(now);
  st.state_age = supervisor_->stateAge(now);
  st.obstacles_age = supervisor_->obstaclesAge(now);
  return out;
}

ControlCycleOutput ControlCycle::stopped(double now, const std::string& reason) const {
  ControlCycleOutput out = zeroOutput(now);
  out.status.phase = ControlPhase::Stopped;
  out.status.reason = reason;
  return out;
}

ControlCycleOutput ControlCycle::update(double now) {
  ControlCycleOutput out = zeroOutput(now);
  ControlCycleStatus& st = out.status;
  const SupervisorDecision d = supervisor_->check(now);
  Vector6d slack = Vector6d::Zero();
  bool have_slack = false;
  double manipulability = -1.0;  // the QP's, when it ran
  try {
    // TfM: every cycle with a target (served or lost), camera pose from the kinematics.
    if (supervisor_->hasTarget() && (d.run || d.phase == ControlPhase::TargetLost)) {
      const Eigen::Vector3d centre = watchedCentre(now);
      if (tracker_->setTarget(centre)) {
        std::ostringstream os;
        os << "new target centre [" << centre.transpose() << "]: TfM restarts";
        out.event = os.str();
      }
      st.target_in_fov =
          tracker_->observe(model_->fk(supervisor_->basePose(), supervisor_->q(), model_->config().camera_frame));
    }
    st.tfm = tracker_->tfm();
    if (!d.run) {
      st.phase = d.phase;
      st.reason = d.reason;
    } else {
      const ControllerCommand c = step(now);
      st.phase = c.ok ? c.phase : ControlPhase::QpFailed;
      st.reason = c.failure;
      st.qp_status = c.qp_status;
      st.wrist_flip = c.wrist_flip;
      st.recovering = c.recovering;
      static_cast<QpStepFigures&>(st) = c;
      if (c.ok) out.velocity = c.velocity;
      slack = c.slack;
      have_slack = c.ok;
      manipulability = c.manipulability;
      if (!c.event.empty()) out.event += (out.event.empty() ? "" : "; ") + c.event;
      // The solve took time: a cycle over its budget, or a command computed from a state (or
      // target, or obstacles) that went stale meanwhile, is not sent.
      if (clock_) {
        const double after = clock_();
        const SupervisorDecision late = supervisor_->check(after);
        if (!late.run) {
          out.velocity.setZero();
          st.phase = late.phase;
          std::ostringstream os;
          os << "after the " << after - now << " s cycle (QP " << c.solve_time_us * 1e-3 << " ms): " << late.reason;
          st.reason = os.str();
          st.state_age = supervisor_->stateAge(after);
          st.target_age = supervisor_->targetAge(after);
          st.obstacles_age = supervisor_->obstaclesAge(after);
        } else if (after - now > params_.watchdog.max_solve_time) {
          out.velocity.setZero();
          st.phase = ControlPhase::QpFailed;
          st.qp_status = QpStatus::Failed;
          std::ostringstream os;
          os << "cycle took " << (after - now) * 1e3 << " ms (QP " << c.solve_time_us * 1e-3
             << " ms), over max_solve_time " << params_.watchdog.max_solve_time * 1e3 << " ms";
          st.reason = os.str();
        }
      }
    }
  } catch (const std::exception& e) {  // core errors: stop safely, say why
    out.velocity.setZero();
    st.phase = ControlPhase::Stopped;
    st.reason = std::string("controller error: ") + e.what();
    st.qp_status = QpStatus::NotRun;
    st.controller_error = true;
  }
  if (!out.velocity.allFinite()) out.velocity.setZero();  // never command NaN
  reportMotionLimit(now, have_slack ? &slack : nullptr, manipulability, &out);
  return out;
}

void ControlCycle::reportMotionLimit(double now, const Vector6d* slack, double manipulability,
                                     ControlCycleOutput* out) {
  if (supervisor_->stateAge(now) < 0.0) return;  // no joint state or odometry yet
  MotionLimitMonitor::Cycle c;
  c.t = now;
  c.base_pose = supervisor_->basePose();
  c.q = supervisor_->q();
  c.command = out->velocity;
  c.slack = slack;
  c.manipulability = manipulability;
  const std::vector<ObstaclePair>& obstacles = supervisor_->obstacles(now);
  c.obstacles = &obstacles;
  c.has_target = supervisor_->hasTarget();
  c.target_in_fov = out->status.target_in_fov;
  try {
    out->status.motion_limit = limits_->update(c);
    obstacle_held_ = out->status.motion_limit.limit == MotionLimit::Obstacle;
  } catch (const std::exception& e) {  // core errors: reported, never thrown out of a cycle
    out->status.motion_limit = MotionLimitReport{};
    if (out->status.reason.empty()) out->status.reason = std::string("motion limit: ") + e.what();
  }
}

std::optional<RollJoint> ControlCycle::rollJointAt(const Eigen::VectorXd& q) const {
  if (roll_index_ < 0) return std::nullopt;
  const RobotConfig& rc = model_->config();
  RollJoint roll;
  roll.q = q[roll_index_];
  roll.lower = rc.arm_lower[roll_index_];
  roll.upper = rc.arm_upper[roll_index_];
  return roll;
}

ControllerCommand ControlCycle::step(double now) {
  const RobotConfig& rc = model_->config();
  const Eigen::Vector3d& base = supervisor_->basePose();
  const Eigen::VectorXd& q = supervisor_->q();
  const Eigen::Isometry3d& target = supervisor_->target();
  const Eigen::Isometry3d tcp = model_->fk(base, q, rc.tcp_frame);
  const std::optional<RollJoint> roll = rollJointAt(q);
  const RollJoint* roll_ptr = roll ? &*roll : nullptr;
  const std::vector<ObstaclePair>& obstacles = supervisor_->obstacles(now);
  // sig(omega) once per cycle, shared by the placement (ehc_place), MPBS (eq. 14) and the QP weighting.
  std::optional<EhcWeight> w;
  if (controller_->hasWeighting()) w = controller_->weight(base, tcp.translation(), target.translation());
  // A joint-limit stall, or in ehc_place a new target's placement: the recovery's whole-body
  // reference replaces the servo (ReachRecovery).
  const bool place = controller_->params().mode == ControlMode::EhcPlace && w;
  const Eigen::VectorXd* reference =
      recovery_->update(now, base, q, tcp, target, place ? &*w : nullptr, obstacle_held_);
  auto withEvent = [this](ControllerCommand c) {
    if (!recovery_->event().empty()) c.event += (c.event.empty() ? "" : "; ") + recovery_->event();
    c.recovering = recovery_->state() == ReachRecovery::State::Moving && !recovery_->placing();  // not a placement
    return c;
  };
  if (params_.servo_type == ServoType::Proportional)
    return withEvent(controller_->step(base, q, target, proportionalPoseServo(tcp, target, params_.servo, roll_ptr),
                                       obstacles, w ? &*w : nullptr, reference));
  const Eigen::Vector3d centre = watchedCentre(now);
  const MpbsOutput servo = mpbs_->compute(tcp, target, w ? w->sig : 1.0, roll_ptr, &centre);
  return withEvent(controller_->step(base, q, target, servo.twist, obstacles, w ? &*w : nullptr, reference));
}

std::string ControlCycle::summary() const {
  const RobotConfig& rc = model_->config();
  std::ostringstream os;
  os << rc.summary();
  if (weighting_) os << weighting_->map().summary() << "\n";
  os << params_.controller.summary() << "\n  ";
  if (params_.servo_type == ServoType::Pbvs)
    os << params_.pbvs.summary() << "\n  " << params_.mpbs.summary();
  else
    os << "servo: proportional (gain " << params_.servo.gain << ", rotation ratio " << params_.servo.rotation_gain_ratio
       << ", roll unwinding " << (params_.servo.unwind_roll ? "on" : "off") << "); mpbs: n/a";
  os << "\n  roll joint "
     << (roll_index_ >= 0 ? rc.arm_joints[static_cast<std::size_t>(roll_index_)] : std::string("none")) << "\n  "
     << params_.tracking.summary() << ", " << tracker_->camera().summary() << ", centre timeout "
     << params_.centre_timeout << " s\n  " << params_.watchdog.summary() << "\n  " << params_.motion_limit.summary();
  return os.str();
}

}  // namespace ehc_control
