#pragma once
// HardwareStandIn: the Bullet SimWorld behind the REAL robot's interfaces, for the deployment
// rehearsal (REALMAN.md): what the vendor rm_driver and the Water2 base do with what the
// unchanged RealMan adapters send them, on the wall clock as the hardware runs.
//   - rm_driver: each /rm_driver/JointPos frame is a position set-point the arm servo follows
//     (rates (q_set - q) / dt, at most robot.yaml's velocity limits). As the driver, it ignores
//     a frame of the wrong size, with a non-finite value or more than 10 deg from the previous
//     set-point. Emergency stop: the arm holds where it is (the set-point is dropped) until the
//     next frame. Gripper_Set position >= 500 opens, below closes; Gripper_Pick closes.
//   - Water2: joy_controls received over its API (Water2ApiServer) drive the water2 base model
//     (KinematicFakeRobot::joyControlReceived: 0.5 s command lifetime, velocity loop,
//     acceleration limits, gain error, actuation noise); robot_status reports the map pose with
//     its localisation error. sim.base_model must be water2.
//   - Time: advanceTo(wall) steps the world by sim.dt until it has caught up with the wall clock
//     (the hardware does not wait for anyone), in one burst after a stall (a physics step is
//     ~30 us: a 1 s stall costs a few ms). The burst is what the hardware did meanwhile: the
//     base runs out its last joy_control (0.5 s lifetime) and stops, the arm reaches its last
//     set-point and holds. Only after a stall longer than max_catch_up_steps steps (default
//     kDefaultMaxCatchUpSteps = 10 s at dt 0.01: a suspended process) is the rest skipped
//     (counted: the world then lags the wall clock by that much). With a 1 s default,
//     on a loaded machine (load 15-25) the stand-in then froze the world for seconds
//     per run (1212 steps in one rehearsal) while the bridge dead-reckoned the commanded motion
//     on the wall clock and the adapter streamed set-points ahead of a frozen arm: odometry off
//     by cm and JointPos frames ignored as "more than 10 deg" jumps, artefacts no robot has.
// ROS-free.

#include "ehc_realman/water2_protocol.h"
#include "ehc_sim/sim_world.h"

#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

namespace ehc_sim {

struct HardwareStandInCounters {
  long steps = 0;
  long skipped_steps = 0;     ///< steps given up after stalls (world time behind the wall clock)
  long frames_accepted = 0;   ///< JointPos frames followed
  long frames_ignored = 0;    ///< JointPos frames the driver ignores (size, NaN, > 10 deg jump)
  long joy_controls = 0;
  long emergency_stops = 0;
};

class HardwareStandIn {
 public:
  static constexpr double kDriverMaxStep = 10.0 * 3.14159265358979323846 / 180.0;  ///< rad
  static constexpr int kGripperOpenPosition = 500;  ///< Gripper_Set position at or above: open

  static constexpr int kDefaultMaxCatchUpSteps = 1000;  ///< 10 s at dt 0.01

  /// `world` must outlive this and use sim.base_model water2 (throws "[HardwareStandIn] ...").
  explicit HardwareStandIn(SimWorld& world, int max_catch_up_steps = kDefaultMaxCatchUpSteps);

  /// Steps the world until its time has caught up with `wall_s` (s, any monotonic origin; the
  /// first call only sets the origin). Returns the number of steps done.
  int advanceTo(double wall_s);

  /// /rm_driver/JointPos: "" if followed, else why the driver ignores it.
  std::string onJointPos(const std::vector<double>& q);
  /// /rm_driver/Emergency_Stop {state: true}.
  void onEmergencyStop();
  /// /rm_driver/Gripper_Set (position 1..1000) and /rm_driver/Gripper_Pick.
  void onGripperSet(int position);
  void onGripperPick();
  /// A joy_control received by the Water2 API.
  void onJoyControl(double linear, double angular);
  /// What the Water2's robot_status reports now.
  ehc_realman::Water2Pose statusPose() const;

  /// Arm rates the servo commands for the next step (zero without a set-point).
  Eigen::VectorXd armRates() const;
  const std::optional<Eigen::VectorXd>& setPoint() const { return set_point_; }
  const HardwareStandInCounters& counters() const { return counters_; }
  const SimWorld& world() const { return world_; }

 private:
  SimWorld& world_;
  int max_catch_up_steps_;
  std::optional<double> origin_;  ///< wall s at world time 0 (moved forward after a stall)
  std::optional<Eigen::VectorXd> set_point_;
  HardwareStandInCounters counters_;
};

}  // namespace ehc_sim
