#include "ehc_control/pbvs_servo.h"

#include "ehc_common/config_node.h"

#include <visp3/core/vpHomogeneousMatrix.h>
#include <visp3/core/vpVelocityTwistMatrix.h>
#include <visp3/visual_features/vpFeatureThetaU.h>
#include <visp3/visual_features/vpFeatureTranslation.h>
#include <visp3/vs/vpAdaptiveGain.h>
#include <visp3/vs/vpServo.h>

#include <cmath>
#include <sstream>
#include <stdexcept>

using ehc_common::requireRange;

namespace ehc_control {

namespace {
const char* kOwner = "PbvsServoParams";

vpHomogeneousMatrix toVisp(const Eigen::Isometry3d& T) {
  vpHomogeneousMatrix M;
  for (unsigned r = 0; r < 3; ++r)
    for (unsigned c = 0; c < 4; ++c) M[r][c] = T.matrix()(r, c);
  return M;
}
}  // namespace

void PbvsServoParams::validate() const {
  requireRange(kOwner, "gain_at_zero", gain_at_zero, 1e-3, 100.0);
  requireRange(kOwner, "gain_at_infinity", gain_at_infinity, 1e-3, 100.0);
  if (gain_at_infinity > gain_at_zero)
    throw std::invalid_argument("[PbvsServoParams] gain_at_infinity must be <= gain_at_zero");
  requireRange(kOwner, "slope_at_zero", slope_at_zero, 0.0, 1000.0);
  requireRange(kOwner, "max_linear", max_linear, 1e-3, 100.0);
  requireRange(kOwner, "max_angular", max_angular, 1e-3, 100.0);
}

std::string PbvsServoParams::summary() const {
  std::ostringstream os;
  os << "servo: pbvs (ViSP eye-in-hand, cdMc translation + theta-u), adaptive gain l0 " << gain_at_zero
     << " linf " << gain_at_infinity << " l0' " << slope_at_zero << ", |v| <= " << max_linear << " m/s, |w| <= "
     << max_angular << " rad/s, roll unwinding " << (unwind_roll ? "on" : "off");
  return os.str();
}

PbvsServoParams loadPbvsServoParams(const ehc_common::ConfigNode& n) {
  PbvsServoParams p;
  p.gain_at_zero = n.get("gain_at_zero", p.gain_at_zero);
  p.gain_at_infinity = n.get("gain_at_infinity", p.gain_at_infinity);
  p.slope_at_zero = n.get("slope_at_zero", p.slope_at_zero);
  p.max_linear = n.get("max_linear", p.max_linear);
  p.max_angular = n.get("max_angular", p.max_angular);
  p.unwind_roll = n.get("unwind_roll", p.unwind_roll);
  n.validate(p);  // errors name the file and the section
  return p;
}

struct PbvsServo::Impl {
  // vpServo keeps pointers to the features: they live next to it, at a fixed address.
  vpServo task;
  vpFeatureTranslation s_t{vpFeatureTranslation::cdMc}, s_t_star{vpFeatureTranslation::cdMc};
  vpFeatureThetaU s_tu{vpFeatureThetaU::cdRc}, s_tu_star{vpFeatureThetaU::cdRc};
  vpHomogeneousMatrix eMc, cMe;
  vpVelocityTwistMatrix eVc;
  vpAdaptiveGain lambda;  ///< same law as the task's, to report the gain used
};

PbvsServo::PbvsServo(const Eigen::Isometry3d& tcp_T_camera, const PbvsServoParams& params)
    : impl_(std::make_unique<Impl>()), params_(params), tcp_T_camera_(tcp_T_camera) {
  params_.validate();
  if (!tcp_T_camera.matrix().allFinite() ||
      (tcp_T_camera.linear().transpose() * tcp_T_camera.linear() - Eigen::Matrix3d::Identity()).norm() > 1e-6)
    throw std::invalid_argument("[PbvsServo] tcp_T_camera is not a rigid transform");
  Impl& m = *impl_;
  m.eMc = toVisp(tcp_T_camera);
  m.cMe = m.eMc.inverse();
  m.eVc.buildFrom(m.eMc);
  // Desired features: identity cdMc (the current camera frame coincides with the desired one).
  m.s_t_star.buildFrom(vpHomogeneousMatrix());
  m.s_tu_star.buildFrom(vpHomogeneousMatrix());
  m.task.setServo(vpServo::EYEINHAND_CAMERA);
  m.task.setInteractionMatrixType(vpServo::CURRENT);
  m.lambda.initStandard(params_.gain_at_zero, params_.gain_at_infinity, params_.slope_at_zero);
  m.task.setLambda(m.lambda);
  m.task.addFeature(m.s_t, m.s_t_star);
  m.task.addFeature(m.s_tu, m.s_tu_star);
}

PbvsServo::~PbvsServo() = default;
PbvsServo::PbvsServo(PbvsServo&&) noexcept = default;
PbvsServo& PbvsServo::operator=(PbvsServo&&) noexcept = default;

Vector6d PbvsServo::twist(const Eigen::Isometry3d& tcp, const Eigen::Isometry3d& desired, const RollJoint* roll) {
  if (!tcp.matrix().allFinite() || !desired.matrix().allFinite())
    throw std::invalid_argument("[PbvsServo] non-finite TCP or desired pose");
  const Eigen::Isometry3d goal = (roll && params_.unwind_roll) ? rollUnwoundTarget(tcp, desired, *roll) : desired;
  Impl& m = *impl_;
  // Current camera frame c in the desired camera frame cd: cdMc = (wMe* eMc)^-1 (wMe eMc).
  const vpHomogeneousMatrix cdMc = m.cMe * toVisp(goal.inverse(Eigen::Isometry) * tcp) * m.eMc;
  m.s_t.buildFrom(cdMc);
  m.s_tu.buildFrom(cdMc);
  const vpColVector v_c = m.task.computeControlLaw();  // camera twist, camera frame
  const vpColVector v_e = m.eVc * v_c;                  // TCP twist, TCP frame
  const vpColVector err = m.task.getError();
  error_norm_ = err.frobeniusNorm();
  // vpServo evaluates the adaptive gain on e1 = L^+ (s - s*) (|.|_inf), as done here.
  gain_ = m.lambda(m.task.getTaskJacobianPseudoInverse() * err);
  const Eigen::Matrix3d& R = tcp.linear();
  Vector6d nu;
  for (int i = 0; i < 6; ++i) camera_twist_[i] = v_c[static_cast<unsigned>(i)];
  nu.head<3>() = R * Eigen::Vector3d(v_e[0], v_e[1], v_e[2]);
  nu.tail<3>() = R * Eigen::Vector3d(v_e[3], v_e[4], v_e[5]);
  const double v = nu.head<3>().norm(), w = nu.tail<3>().norm();
  scale_ = std::min({1.0, v > params_.max_linear ? params_.max_linear / v : 1.0,
                     w > params_.max_angular ? params_.max_angular / w : 1.0});
  nu *= scale_;
  if (!nu.allFinite()) throw std::runtime_error("[PbvsServo] non-finite twist");
  return nu;
}

}  // namespace ehc_control
