#include "ehc_sim/hardware_stand_in.h"

#include <cmath>
#include <stdexcept>

namespace ehc_sim {

HardwareStandIn::HardwareStandIn(SimWorld& world, int max_catch_up_steps)
    : world_(world), max_catch_up_steps_(max_catch_up_steps) {
  if (world.config().fake_robot.base_model.type != BaseModelType::Water2)
    throw std::invalid_argument("[HardwareStandIn] the Water2 API needs sim.base_model: water2");
  if (max_catch_up_steps < 1) throw std::invalid_argument("[HardwareStandIn] max_catch_up_steps must be >= 1");
}

int HardwareStandIn::advanceTo(double wall_s) {
  if (!std::isfinite(wall_s)) throw std::invalid_argument("[HardwareStandIn] wall time must be finite");
  if (!origin_) {
    origin_ = wall_s - world_.time();
    return 0;
  }
  const double dt = world_.config().fake_robot.dt;
  const long due = static_cast<long>(std::floor((wall_s - *origin_) / dt + 1e-9)) - world_.stepCount();
  if (due <= 0) return 0;
  const long steps = std::min<long>(due, max_catch_up_steps_);
  if (due > steps) {  // a stall: give the rest up, the world now lags the wall clock
    counters_.skipped_steps += due - steps;
    *origin_ += static_cast<double>(due - steps) * dt;
  }
  const int nb = world_.robot().robot().nBase();
  Eigen::VectorXd command = Eigen::VectorXd::Zero(world_.robot().nDof());
  for (long i = 0; i < steps; ++i) {
    command.tail(command.size() - nb) = armRates();
    world_.step(command);
    ++counters_.steps;
  }
  return static_cast<int>(steps);
}

Eigen::VectorXd HardwareStandIn::armRates() const {
  const ehc_control::RobotConfig& robot = world_.robot().robot();
  if (!set_point_) return Eigen::VectorXd::Zero(robot.nArm());
  const double dt = world_.config().fake_robot.dt;
  const Eigen::VectorXd& vmax = robot.arm_velocity;
  return ((*set_point_ - world_.robot().armPositions()) / dt).cwiseMax(-vmax).cwiseMin(vmax);
}

std::string HardwareStandIn::onJointPos(const std::vector<double>& q) {
  const ehc_control::RobotConfig& robot = world_.robot().robot();
  std::string why;
  const Eigen::VectorXd from = set_point_ ? *set_point_ : world_.robot().armPositions();
  if (static_cast<int>(q.size()) != robot.nArm()) {
    why = "JointPos has " + std::to_string(q.size()) + " joints, the arm " + std::to_string(robot.nArm());
  } else {
    const Eigen::Map<const Eigen::VectorXd> target(q.data(), static_cast<Eigen::Index>(q.size()));
    if (!target.allFinite()) why = "JointPos has a non-finite joint";
    else if ((target - from).cwiseAbs().maxCoeff() > kDriverMaxStep + 1e-6)
      why = "JointPos jumps more than 10 deg from the previous set-point";
    else set_point_ = target;
  }
  ++(why.empty() ? counters_.frames_accepted : counters_.frames_ignored);
  return why;
}

void HardwareStandIn::onEmergencyStop() {
  set_point_.reset();
  ++counters_.emergency_stops;
}

void HardwareStandIn::onGripperSet(int position) { world_.commandGripper(position < kGripperOpenPosition); }

void HardwareStandIn::onGripperPick() { world_.commandGripper(true); }

void HardwareStandIn::onJoyControl(double linear, double angular) {
  world_.baseJoyControlReceived(linear, angular);
  ++counters_.joy_controls;
}

ehc_realman::Water2Pose HardwareStandIn::statusPose() const {
  const Eigen::Vector3d p = world_.robot().statusPose();
  return ehc_realman::Water2Pose{p.x(), p.y(), p.z()};
}

}  // namespace ehc_sim
