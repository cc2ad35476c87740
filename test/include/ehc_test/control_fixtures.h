#pragma once
// Shared fixtures for ehc_control tests: the RealMan robot config and random configurations.

#include "ehc_control/whole_body_model.h"
#include "ehc_test/errors.h"

#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

namespace ehc_control::test {

using ehc_test::errorOf;

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

/// Noise-free kinematic robot for closed loops: integrates [base twist; arm rates] over dt
/// (base twist in the base frame: v_x, [v_y,] w_z).
struct KinematicSim {
  Eigen::Vector3d base = Eigen::Vector3d::Zero();
  Eigen::VectorXd q;
  void step(const WholeBodyModel& m, const Eigen::VectorXd& v, double dt) {
    const int nb = m.nBase();
    const double vx = v[0], vy = nb == 3 ? v[1] : 0.0, wz = v[nb - 1];
    const double c = std::cos(base.z()), s = std::sin(base.z());
    base.x() += (c * vx - s * vy) * dt;
    base.y() += (s * vx + c * vy) * dt;
    base.z() += wz * dt;
    q += v.tail(m.nArm()) * dt;
  }
};

/// A random TCP target for closed loops: the hand pointing down (tilted up to 0.4 rad about its
/// x axis), within 1.2 m of `base` in x and y and 0.5-0.9 m high.
inline Eigen::Isometry3d randomDownwardTarget(std::mt19937& rng, const Eigen::Vector3d& base) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::Isometry3d target = Eigen::Isometry3d::Identity();
  const double tilt = 0.4 * u(rng);
  target.linear() = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY()).toRotationMatrix() *
                    Eigen::AngleAxisd(tilt, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const double x = base.x() + 1.2 * u(rng), y = base.y() + 1.2 * u(rng), z = 0.7 + 0.2 * u(rng);
  target.translation() << x, y, z;
  return target;
}

/// TCP pose at (x, y, z) whose z axis is `approach`, x axis horizontal.
inline Eigen::Isometry3d approachPose(double x, double y, double z, const Eigen::Vector3d& approach) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  const Eigen::Vector3d zz = approach.normalized();
  Eigen::Vector3d xx = Eigen::Vector3d::UnitZ().cross(zz);
  if (xx.norm() < 1e-6) xx = Eigen::Vector3d::UnitX();
  xx.normalize();
  T.linear().col(0) = xx;
  T.linear().col(1) = zz.cross(xx);
  T.linear().col(2) = zz;
  T.translation() << x, y, z;
  return T;
}

inline Eigen::Vector3d randomBase(std::mt19937& rng) {
  std::uniform_real_distribution<double> xy(-5.0, 5.0), yaw(-3.14, 3.14);
  return Eigen::Vector3d(xy(rng), xy(rng), yaw(rng));
}

}  // namespace ehc_control::test
