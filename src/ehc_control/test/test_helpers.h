#pragma once
// Shared fixtures for ehc_control tests: the RealMan robot config and random configurations.

#include "ehc_control/whole_body_model.h"

#include <random>
#include <string>

namespace ehc_control::test {

inline std::string realmanYaml() {
  return std::string(EHC_CONFIG_DIR) + "/robots/realman_rm65_water2/robot.yaml";
}

/// The D435 colour stream's camera_info YAML of the RealMan robot.
inline std::string realmanCameraYaml() {
  return std::string(EHC_CONFIG_DIR) + "/robots/realman_rm65_water2/camera.yaml";
}

inline RobotConfig realmanConfig(BaseType type = BaseType::Differential) {
  RobotConfig c = loadRobotConfig(realmanYaml());
  c.base_type = type;
  return c;
}

/// Uniform random arm configuration strictly inside the joint limits (margin in rad).
inline Eigen::VectorXd randomArm(const RobotConfig& c, std::mt19937& rng, double margin = 0.05) {
  Eigen::VectorXd q(c.nArm());
  for (int i = 0; i < c.nArm(); ++i) {
    std::uniform_real_distribution<double> u(c.arm_lower[i] + margin, c.arm_upper[i] - margin);
    q[i] = u(rng);
  }
  return q;
}

/// TCP -> camera optical frame of the RealMan description (fixed, read at the ready pose).
inline Eigen::Isometry3d realmanTcpToCamera() {
  const RobotConfig rc = realmanConfig();
  const WholeBodyModel model(rc);
  return model.linkPoseInBase(rc.arm_ready, rc.tcp_frame).inverse() * model.linkPoseInBase(rc.arm_ready, rc.camera_frame);
}

inline Eigen::Vector3d randomBase(std::mt19937& rng) {
  std::uniform_real_distribution<double> xy(-5.0, 5.0), yaw(-3.14, 3.14);
  return Eigen::Vector3d(xy(rng), xy(rng), yaw(rng));
}

}  // namespace ehc_control::test
