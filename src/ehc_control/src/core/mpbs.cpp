#include "ehc_control/mpbs.h"

#include "ehc_common/config_node.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace ehc_control {

void MpbsParams::validate() const {
  ehc_common::requireRange("MpbsParams", "min_monitor_distance", min_monitor_distance, 1e-3, 10.0);
  if (!target_centre.allFinite()) throw std::invalid_argument("[MpbsParams] target_centre must be finite");
}

std::string MpbsParams::summary() const {
  std::ostringstream os;
  os << "mpbs: " << (enabled ? "on" : "off (plain PBVS to the grasp pose)") << ", min monitor distance "
     << min_monitor_distance << " m, target centre in the target frame [" << target_centre.transpose() << "]";
  return os.str();
}

MpbsParams loadMpbsParams(const ehc_common::ConfigNode& n) {
  MpbsParams p;
  p.enabled = n.get("enabled", p.enabled);
  p.min_monitor_distance = n.get("min_monitor_distance", p.min_monitor_distance);
  p.target_centre = n.getVector("target_centre", p.target_centre, 3);
  n.validate(p);  // errors name the file and the section
  return p;
}

Eigen::Isometry3d interpolatePose(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, double s) {
  if (!a.matrix().allFinite() || !b.matrix().allFinite() || !std::isfinite(s))
    throw std::invalid_argument("[Mpbs] non-finite pose or blend in interpolatePose");
  s = std::clamp(s, 0.0, 1.0);
  const Eigen::Quaterniond qa(a.linear()), qb(b.linear());
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = qa.normalized().slerp(s, qb.normalized()).normalized().toRotationMatrix();
  out.translation() = (1.0 - s) * a.translation() + s * b.translation();
  return out;
}

Eigen::Isometry3d monitoringPose(const Eigen::Vector3d& tcp_position, const Eigen::Isometry3d& grasp,
                                 const Eigen::Vector3d& target_centre, const Eigen::Isometry3d& tcp_T_camera,
                                 double min_monitor_distance) {
  if (!tcp_position.allFinite() || !grasp.matrix().allFinite() || !target_centre.allFinite())
    throw std::invalid_argument("[Mpbs] non-finite input to monitoringPose");
  Eigen::Isometry3d monitor = grasp;
  const Eigen::Vector3d to_target = target_centre - tcp_position;
  const double d = to_target.norm();
  if (d <= min_monitor_distance) return monitor;
  // In the TCP frame the target must lie on the optical axis t + l a (l > 0) at distance d from
  // the TCP origin: |t + l a| = d  =>  l = -(a.t) + sqrt((a.t)^2 - |t|^2 + d^2).
  const Eigen::Vector3d t = tcp_T_camera.translation();
  const Eigen::Vector3d a = tcp_T_camera.linear().col(2);
  const double at = a.dot(t), disc = at * at - t.squaredNorm() + d * d;
  if (disc < 0.0) return monitor;
  const double l = -at + std::sqrt(disc);
  if (l <= 0.0) return monitor;
  const Eigen::Vector3d u_tcp = (t + l * a) / d;  // unit direction TCP -> target, TCP frame
  const Eigen::Quaterniond q_grasp(grasp.linear());
  // Smallest rotation taking that direction (as the grasp orientation holds it) onto the
  // actual direction to the target: the look-at orientation closest to the grasp's.
  const Eigen::Quaterniond swing = Eigen::Quaterniond::FromTwoVectors(q_grasp * u_tcp, to_target / d);
  Eigen::Quaterniond q_look = (swing * q_grasp).normalized();
  const double fade = std::clamp((d - min_monitor_distance) / min_monitor_distance, 0.0, 1.0);
  if (fade < 1.0) q_look = q_grasp.slerp(fade, q_look);
  monitor.linear() = q_look.toRotationMatrix();
  return monitor;
}

Eigen::Isometry3d mpbsDesiredPose(double sig, const Eigen::Isometry3d& grasp, const Eigen::Isometry3d& monitor) {
  return interpolatePose(monitor, grasp, sig);
}

MpbsServo::MpbsServo(const Eigen::Isometry3d& tcp_T_camera, const PbvsServoParams& pbvs, const MpbsParams& mpbs)
    : pbvs_(tcp_T_camera, pbvs), params_(mpbs) {
  params_.validate();
  const Eigen::Vector3d t = tcp_T_camera.translation(), a = tcp_T_camera.linear().col(2);
  const double axis_offset = (t - a.dot(t) * a).norm();  // TCP origin to the optical axis
  if (params_.min_monitor_distance <= axis_offset)
    throw std::invalid_argument("[MpbsServo] min_monitor_distance (" + std::to_string(params_.min_monitor_distance) +
                                " m) must exceed the TCP's distance to the optical axis (" +
                                std::to_string(axis_offset) + " m)");
}

MpbsOutput MpbsServo::compute(const Eigen::Isometry3d& tcp, const Eigen::Isometry3d& grasp, double sig,
                              const RollJoint* roll, const Eigen::Vector3d* centre) {
  if (!std::isfinite(sig)) throw std::invalid_argument("[MpbsServo] non-finite sig");
  MpbsOutput out;
  if (params_.enabled) {
    out.sig = std::clamp(sig, 0.0, 1.0);
    out.monitor = monitoringPose(tcp.translation(), grasp, centre ? *centre : targetCentre(grasp), pbvs_.tcpToCamera(),
                                 params_.min_monitor_distance);
    out.desired = mpbsDesiredPose(out.sig, grasp, out.monitor);
  } else {
    out.sig = 1.0;
    out.monitor = grasp;
    out.desired = grasp;
  }
  out.twist = pbvs_.twist(tcp, out.desired, roll);
  return out;
}

}  // namespace ehc_control
