#pragma once
// WholeBodyModel: kinematics of a mobile base (virtual joints) carrying a serial arm parsed
// from a URDF with KDL. World frame = odom. State = base pose (x, y, yaw) in the world plus
// arm joint positions. Velocity vector = [base twist (base frame) ; arm joint rates]:
//   holonomic:    [v_x, v_y, w_z, qd_1 .. qd_n]
//   differential: [v_x, w_z, qd_1 .. qd_n]
// ROS-free: urdfdom + kdl_parser + KDL + Eigen. Not thread-safe (the KDL solvers behind the
// name-based functions keep scratch state). Per control cycle, updateKinematics fills a
// caller-owned KinematicState in one pass over the tree and the Jacobians of any link are read
// from it (same values as the name-based functions, to rounding; no allocation once warm).

#include "ehc_control/robot_config.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <memory>
#include <string>
#include <vector>

namespace ehc_control {

using Matrix6Xd = Eigen::Matrix<double, 6, Eigen::Dynamic>;

class WholeBodyModel;

/// The text of a URDF file. Throws std::invalid_argument "[WholeBodyModel] cannot read URDF
/// file '<path>'".
std::string readUrdfFile(const std::string& path);

/// Every link pose and every arm joint axis of one robot state, from one forward pass over the
/// kinematic tree (WholeBodyModel::updateKinematics). The Jacobian of any link, or of a point
/// fixed to a link, is then read from it without another FK pass (the KinematicState overloads
/// of WholeBodyModel::jacobian). Storage is sized by the first update; later updates with the
/// same model allocate nothing. Link indices come from WholeBodyModel::linkIndex.
class KinematicState {
 public:
  /// World pose of the base frame (WholeBodyModel::baseTransform of the base pose).
  const Eigen::Isometry3d& baseTransform() const { return world_T_base_; }
  /// Pose of a link in the base frame.
  const Eigen::Isometry3d& linkPoseInBase(int link) const {
    return base_T_link_[static_cast<std::size_t>(link)];
  }
  /// Pose of a link in the world frame.
  Eigen::Isometry3d linkPose(int link) const { return world_T_base_ * linkPoseInBase(link); }

 private:
  friend class WholeBodyModel;
  Eigen::Isometry3d world_T_base_ = Eigen::Isometry3d::Identity();
  std::vector<Eigen::Isometry3d> base_T_link_;  ///< per link index
  Eigen::Matrix3Xd joint_axis_;                 ///< per arm joint: unit axis, base frame
  Eigen::Matrix3Xd joint_point_;                ///< per arm joint: a point on its axis, base frame
};

class WholeBodyModel {
 public:
  /// Reads cfg.urdf_path. Throws std::invalid_argument "[WholeBodyModel] ..." on a bad URDF,
  /// arm joints that do not form the chain base -> tcp, or limits wider than the URDF's.
  explicit WholeBodyModel(const RobotConfig& cfg);
  /// Same, with the URDF given as XML text.
  WholeBodyModel(const RobotConfig& cfg, const std::string& urdf_xml);
  ~WholeBodyModel();
  WholeBodyModel(WholeBodyModel&&) noexcept;
  WholeBodyModel& operator=(WholeBodyModel&&) noexcept;

  const RobotConfig& config() const { return cfg_; }
  BaseType baseType() const { return cfg_.base_type; }
  int nBase() const { return cfg_.nBase(); }
  int nArm() const { return cfg_.nArm(); }
  int nDof() const { return cfg_.nBase() + cfg_.nArm(); }
  /// Names of the velocity vector entries: base_vx, [base_vy,] base_wz, then the arm joints.
  std::vector<std::string> dofNames() const;
  /// Every link reachable from the base link (URDF root).
  std::vector<std::string> linkNames() const;
  bool hasLink(const std::string& link) const;
  const std::string& urdfXml() const { return urdf_xml_; }
  /// The URDF with robot.yaml's calibration (tcp / camera fixed joints) applied: the robot this
  /// model computes with, for robot_state_publisher on the real robot (`ehc_kinematics --urdf`).
  std::string calibratedUrdfXml() const;

  /// World pose of the base frame for base pose (x, y, yaw).
  static Eigen::Isometry3d baseTransform(const Eigen::Vector3d& base_pose);

  /// Pose of `link` in the base frame.
  Eigen::Isometry3d linkPoseInBase(const Eigen::VectorXd& q, const std::string& link) const;
  /// Pose of `link` in the world frame.
  Eigen::Isometry3d fk(const Eigen::Vector3d& base_pose, const Eigen::VectorXd& q,
                       const std::string& link) const;
  /// 6 x nArm geometric Jacobian of `link`'s origin, rows [v; w] in the base frame.
  Matrix6Xd armJacobian(const Eigen::VectorXd& q, const std::string& link) const;
  /// 6 x nDof whole-body Jacobian of `link`'s origin, rows [v; w] in the world frame,
  /// columns [base..., arm...]. Optionally returns the link pose and the arm Jacobian (base
  /// frame, as armJacobian()) computed on the way.
  Matrix6Xd jacobian(const Eigen::Vector3d& base_pose, const Eigen::VectorXd& q,
                     const std::string& link, Eigen::Isometry3d* pose = nullptr,
                     Matrix6Xd* arm_jacobian = nullptr) const;

  /// Index of `link` for the KinematicState functions: resolve names once, outside the
  /// control loop. Throws "[WholeBodyModel] unknown link ..." like the name-based functions.
  int linkIndex(const std::string& link) const;
  /// One forward pass over the kinematic tree for (base pose, q): fills `state` with every
  /// link pose and arm joint axis. Same checks (and exceptions) as fk().
  void updateKinematics(const Eigen::Vector3d& base_pose, const Eigen::VectorXd& q,
                        KinematicState* state) const;
  /// jacobian(base_pose, q, link) of the state's configuration, written into `J` (resized only
  /// when its size differs): 6 x nDof, rows [v; w] of the link origin in the world frame.
  /// Optionally the arm Jacobian (6 x nArm, base frame, as armJacobian()).
  void jacobian(const KinematicState& state, int link, Matrix6Xd* J,
                Matrix6Xd* arm_jacobian = nullptr) const;
  /// The same for a point fixed to `link`, given in world coordinates: rows [linear velocity
  /// of the point; angular velocity of the link], world frame.
  void pointJacobian(const KinematicState& state, int link, const Eigen::Vector3d& point_world,
                     Matrix6Xd* J) const;

  /// Yoshikawa manipulability sqrt(det(J J^T)) of the arm at the TCP (J^T J if nArm < 6).
  double manipulability(const Eigen::VectorXd& q) const;
  /// Gradient d m / d q (size nArm): the manipulability Jacobian J_m. Analytic (kinematic
  /// Hessian). Zero at an exact singularity (m == 0).
  Eigen::VectorXd manipulabilityGradient(const Eigen::VectorXd& q, double* m = nullptr) const;
  /// Same, from the TCP arm Jacobian (armJacobian(q, tcp frame)) already at hand.
  Eigen::VectorXd manipulabilityGradientFromJacobian(const Matrix6Xd& tcp_arm_jacobian,
                                                     double* m = nullptr) const;
  /// Same, written into `gradient` (resized only when its size differs; no other allocation).
  void manipulabilityGradientFromJacobian(const Matrix6Xd& tcp_arm_jacobian,
                                          Eigen::VectorXd& gradient, double* m = nullptr) const;

  /// Whole-body inverse kinematics of the TCP (KDL ChainIkSolverPos_NR_JL over a virtual
  /// planar base x, y, yaw + the arm within its joint limits), from `attempts` random seeds.
  /// Used to tell kinematically unreachable targets from controller failures. Returns true and
  /// the solution when the TCP reaches `target` within 1 mm / 0.5 deg. `limit_margin` (rad)
  /// shrinks every arm joint range at both ends (e.g. the controller's joint stop).
  bool inverseKinematics(const Eigen::Isometry3d& target, unsigned seed, int attempts,
                         Eigen::Vector3d* base_pose = nullptr, Eigen::VectorXd* q = nullptr,
                         double limit_margin = 0.0) const;
  /// One solve of the same problem from a given start (base pose x, y, yaw and arm q, clamped
  /// into the shrunk ranges): the solution near that configuration, if the solver converges.
  bool inverseKinematicsFrom(const Eigen::Isometry3d& target, const Eigen::Vector3d& base_start,
                             const Eigen::VectorXd& q_start, Eigen::Vector3d* base_out,
                             Eigen::VectorXd* q_out, double limit_margin = 0.0) const;

  /// The same with the base held at `base` (x, y, yaw): the arm's configuration near `q_start`
  /// (clamped into the shrunk ranges) whose TCP reaches `target`, if the solver converges
  /// within `iterations` Newton-Raphson steps (>= 1).
  bool armInverseKinematicsFrom(const Eigen::Isometry3d& target, const Eigen::Vector3d& base,
                                const Eigen::VectorXd& q_start, Eigen::VectorXd* q_out,
                                double limit_margin = 0.0, int iterations = 500) const;

  /// Throws unless q has nArm finite entries / base pose is finite.
  void checkArm(const Eigen::VectorXd& q) const;
  static void checkBase(const Eigen::Vector3d& base_pose);
  /// Clamps q into the configured joint limits.
  Eigen::VectorXd clampToLimits(const Eigen::VectorXd& q) const;

 private:
  struct Impl;
  struct IkProblem;
  void build();
  /// Whole-body Jacobian of a point fixed to `link`, p_base in base coordinates.
  void pointJacobianInBase(const KinematicState& state, int link, const Eigen::Vector3d& p_base,
                           Matrix6Xd* J, Matrix6Xd* arm_jacobian) const;

  RobotConfig cfg_;
  std::string urdf_xml_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ehc_control
