#pragma once
// FakeRobotConfig: the settings both fake robots share — the Bullet simulator (ehc_sim_node,
// part of SimConfig) and the kinematic one (ehc_kinematic_sim_node): robot file, control step,
// noise seed, stepping policy (lock-step or free-run, see StepScheduler), Table I actuation
// noise, the base model (ideal | water2, base_model.h) with its base imprecision and the robot's start pose. One loader reads them from the `sim` mapping of either
// simulator's YAML file, so both files use the same keys:
//
//   sim:
//     robot: ../robots/realman_rm65_water2/robot.yaml   # relative to the file
//     dt: 0.01                     # s, whole nanoseconds
//     seed: 1
//     free_run: false              # false = lock-step
//     state_republish_period: 1.0  # wall s, lock-step: resend a state nobody answered
//     command_timeout: 0.5         # wall s, free-run: zero commands older than this
//     max_real_time_factor: 0      # lock-step pacing: at most this many sim s per wall s (0 = none)
//     noise: {enabled: true, base_translation: 0.05, base_rotation: 0.05, arm: 0.002}
//     base_model: ideal            # ideal | water2 (the Water2 chain, base_model.h)
//     water2: {command_latency: 0.05, ...}  # Water2BaseParams (optional; any subset)
//     base_imprecision: {level: 0, ...}     # BaseImprecisionParams on top of either model (0 = off)
//     robot_start: {x: 0, y: 0, yaw: 0}  # kinematic simulator only (Bullet: the scene's)
//
// Keys of the kinematic simulator's former schema (lockstep, lockstep_timeout_wall, noise as a
// flag, noise_base_translation, noise_base_rotation, noise_arm, initial_base) are errors that
// name the replacement. ROS-free.

#include "ehc_sim/kinematic_fake_robot.h"

#include <Eigen/Core>

#include <cstdint>
#include <string>

namespace ehc_common {
class ConfigNode;
}  // namespace ehc_common

namespace ehc_sim {

struct FakeRobotConfig {
  std::string robot_file;               ///< robot.yaml (resolved against the config file)
  double dt = 0.01;                     ///< s, control / lock-step period
  unsigned seed = 1;                    ///< actuation noise seed
  bool free_run = false;                ///< false = lock-step (the nodes' _free_run overrides it)
  double state_republish_period = 1.0;  ///< wall s, lock-step: resend a state nobody answered
  double command_timeout = 0.5;         ///< wall s, free-run: zero velocities without fresh commands
  /// Lock-step pacing: at most this many sim seconds per wall second (0 = as fast as the
  /// controller answers). Only ever delays an answered step, never makes one; for tests whose
  /// other inputs (targets) come on wall-clock timers.
  double max_real_time_factor = 0.0;
  ActuationNoise noise;
  BaseModelConfig base_model;  ///< ideal (default: today's base) | water2
  Eigen::Vector3d robot_start = Eigen::Vector3d::Zero();  ///< base x, y, yaw in odom

  /// dt in nanoseconds (exact: validate() requires whole nanoseconds).
  std::int64_t dtNs() const;
  void validate() const;  ///< throws "[FakeRobotConfig] ..."
  /// Three lines: robot and start pose; dt, seed, mode, noise; base model and base imprecision.
  std::string summary() const;
};

/// Reads the shared keys of a simulator's `sim` mapping (see the file comment). `water2` is read
/// and checked whichever base_model is selected.
FakeRobotConfig loadFakeRobotConfig(const ehc_common::ConfigNode& sim);
/// Reads a kinematic simulator file: only the keys above, under `sim` (anything else, e.g. a
/// Bullet simulator key, is an error naming the file and the field).
FakeRobotConfig loadFakeRobotConfigFile(const std::string& path);

/// `noise` mapping: enabled, base_translation, base_rotation, arm (all optional).
ActuationNoise loadActuationNoise(const ehc_common::ConfigNode& n);
/// A planar base pose mapping {x, y, yaw} (each optional, default 0): the scenes'
/// robot_start and FakeRobotConfig::robot_start.
Eigen::Vector3d loadBasePose(const ehc_common::ConfigNode& n);

}  // namespace ehc_sim
