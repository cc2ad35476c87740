// Benchmark: the per-cycle servo work of the controller node, measured apart from the QP step
// (bench_controller): ViSP PBVS alone, MPBS (monitoring pose + SE(3) blend + PBVS), the EHC
// weighting evaluated once for MPBS, the TfM in-view test, and the whole cycle
// (weighting + MPBS + QP step) over closed-loop steps to random targets. JSON lines.

#include "ehc_control/bench_util.h"
#include "ehc_control/mpbs.h"
#include "ehc_control/target_tracker.h"

#include <chrono>
#include <random>

using namespace ehc_control;

int main() {
  const std::string dir = std::string(EHC_CONFIG_DIR) + "/robots/realman_rm65_water2/";
  const RobotConfig rc = loadRobotConfig(dir + "robot.yaml");
  auto model = std::make_shared<const WholeBodyModel>(rc);
  auto map = std::make_shared<const ReachabilityMap>(ReachabilityMap::load(rc.reachability_map_path));
  auto weighting = std::make_shared<const EhcWeighting>(map, EhcWeightingParams{});
  const Eigen::Isometry3d eTc = model->linkPoseInBase(rc.arm_ready, rc.tcp_frame).inverse() *
                                model->linkPoseInBase(rc.arm_ready, rc.camera_frame);
  const int roll_index = findRollJoint(*model);
  const int steps = 20000;

  for (bool mpbs : {false, true}) {
    EhcQpController ctrl(model, QpControllerParams{}, weighting);
    MpbsParams mp;
    mp.enabled = mpbs;
    MpbsServo servo(eTc, PbvsServoParams{}, mp);
    TargetTracker tracker(loadPinholeCamera(dir + "camera.yaml"), TargetTrackerParams{});
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Eigen::Vector3d base = Eigen::Vector3d::Zero();
    Eigen::VectorXd q = rc.arm_ready;
    std::vector<double> weight_us, servo_us, fov_us, cycle_us;
    Eigen::Isometry3d target = Eigen::Isometry3d::Identity();
    long failed = 0;
    for (int k = 0; k < steps; ++k) {
      if (k % 400 == 0) {  // a new target every 4 s
        target = Eigen::Isometry3d::Identity();
        target.linear() = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY()).toRotationMatrix() *
                          Eigen::AngleAxisd(0.4 * u(rng), Eigen::Vector3d::UnitX()).toRotationMatrix();
        target.translation() << base.x() + 1.2 * u(rng), base.y() + 1.2 * u(rng), 0.7 + 0.2 * u(rng);
        ctrl.reset();
        tracker.setTarget(servo.targetCentre(target));
      }
      const auto t0 = std::chrono::steady_clock::now();
      const Eigen::Isometry3d tcp = model->fk(base, q, rc.tcp_frame);
      const auto t1 = std::chrono::steady_clock::now();
      const EhcWeight w = ctrl.weight(base, tcp.translation(), target.translation());
      const auto t2 = std::chrono::steady_clock::now();
      RollJoint roll;
      roll.q = q[roll_index];
      roll.lower = rc.arm_lower[roll_index];
      roll.upper = rc.arm_upper[roll_index];
      const MpbsOutput out = servo.compute(tcp, target, w.sig, &roll);
      const auto t3 = std::chrono::steady_clock::now();
      tracker.observe(model->fk(base, q, rc.camera_frame));
      const auto t4 = std::chrono::steady_clock::now();
      const ControllerCommand c = ctrl.step(base, q, target, out.twist, {}, &w);
      const auto t5 = std::chrono::steady_clock::now();
      auto us = [](auto a, auto b) { return std::chrono::duration<double, std::micro>(b - a).count(); };
      weight_us.push_back(us(t1, t2));
      servo_us.push_back(us(t2, t3));
      fov_us.push_back(us(t3, t4));
      cycle_us.push_back(us(t0, t5));
      failed += !c.ok;
      const double dt = 0.01;
      base.x() += std::cos(base.z()) * c.velocity[0] * dt;
      base.y() += std::sin(base.z()) * c.velocity[0] * dt;
      base.z() += c.velocity[1] * dt;
      q += c.velocity.tail(rc.nArm()) * dt;
    }
    const std::string tag = mpbs ? "mpbs" : "pbvs";
    benchPrint("servo." + tag + "_twist", servo_us.size(), benchStats(servo_us));
    if (mpbs) {
      benchPrint("servo.ehc_weight", weight_us.size(), benchStats(weight_us));
      benchPrint("servo.fov_check_with_camera_fk", fov_us.size(), benchStats(fov_us));
    }
    benchPrint("servo.cycle_" + tag + "_weight_servo_fov_step", cycle_us.size(), benchStats(cycle_us),
               "\"qp_failures\":" + std::to_string(failed));
  }
  return 0;
}
