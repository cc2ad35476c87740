// Benchmark: the per-cycle servo work of the controller node, over closed-loop steps to random
// targets driven by ControlCycle::update (servo.cycle_<pbvs|mpbs>_update: the whole cycle the
// node runs). Timed apart on the cycle's own parts at the same state, before each update: ViSP
// PBVS alone or MPBS (monitoring pose + SE(3) blend + PBVS), the EHC weighting evaluated once
// for MPBS, the TfM in-view test; servo.cycle_<tag>_weight_servo_fov_step adds the QP step's
// build + solve time (from the cycle's status) to those pieces. JSON lines.

#include "ehc_common/bench_util.h"
#include "ehc_control/control_cycle.h"
#include "ehc_test/control_fixtures.h"

#include <chrono>
#include <random>

using namespace ehc_control;
using ehc_common::benchPrint;
using ehc_common::benchStats;

int main() {
  const std::string dir = std::string(EHC_CONFIG_DIR) + "/robots/realman_rm65_water2/";
  const int steps = 20000;
  const double dt = 0.01;

  for (bool mpbs : {false, true}) {
    ControlCycleParams params;
    params.robot_file = dir + "robot.yaml";
    params.servo_type = ServoType::Pbvs;
    params.mpbs.enabled = mpbs;
    params.tracking.camera_file = dir + "camera.yaml";
    params.watchdog.require_obstacles = false;  // no obstacle lists here
    ControlCycle cycle(params);
    const WholeBodyModel& model = cycle.model();
    const RobotConfig& rc = model.config();
    std::mt19937 rng(3);
    test::KinematicSim sim;
    sim.q = rc.arm_ready;
    const Eigen::Vector3d& base = sim.base;
    const Eigen::VectorXd& q = sim.q;
    std::vector<double> weight_us, servo_us, fov_us, pieces_us, update_us;
    Eigen::Isometry3d target = Eigen::Isometry3d::Identity();
    long failed = 0;
    for (int k = 0; k < steps; ++k) {
      if (k % 400 == 0) target = test::randomDownwardTarget(rng, base);  // a new target every 4 s
      const double now = k * dt;
      cycle.setJointState(now, rc.arm_joints, std::vector<double>(q.data(), q.data() + q.size()));
      cycle.setBasePose(now, base);
      cycle.setTarget(now, target);

      // The pieces, on the cycle's parts at this state.
      const auto t0 = std::chrono::steady_clock::now();
      const Eigen::Isometry3d tcp = model.fk(base, q, rc.tcp_frame);
      const auto t1 = std::chrono::steady_clock::now();
      const EhcWeight w = cycle.controller().weight(base, tcp.translation(), target.translation());
      const auto t2 = std::chrono::steady_clock::now();
      const std::optional<RollJoint> roll = cycle.rollJointAt(q);
      cycle.mpbsServo().compute(tcp, target, w.sig, roll ? &*roll : nullptr);
      const auto t3 = std::chrono::steady_clock::now();
      const Eigen::Vector3d centre = cycle.watchedCentre(now);
      cycle.tracker().camera().projectsInside(model.fk(base, q, rc.camera_frame).inverse() * centre);
      const auto t4 = std::chrono::steady_clock::now();
      // The whole cycle.
      const ControlCycleOutput out = cycle.update(now);
      const auto t5 = std::chrono::steady_clock::now();

      auto us = [](auto a, auto b) { return std::chrono::duration<double, std::micro>(b - a).count(); };
      weight_us.push_back(us(t1, t2));
      servo_us.push_back(us(t2, t3));
      fov_us.push_back(us(t3, t4));
      pieces_us.push_back(us(t0, t4) + out.status.solve_time_us);
      update_us.push_back(us(t4, t5));
      failed += out.status.qp_status != QpStatus::Ok;
      sim.step(model, out.velocity, dt);
    }
    const std::string tag = mpbs ? "mpbs" : "pbvs";
    const ehc_common::Json failures = {{"qp_failures", failed}};
    benchPrint("servo." + tag + "_twist", servo_us.size(), benchStats(servo_us));
    if (mpbs) {
      benchPrint("servo.ehc_weight", weight_us.size(), benchStats(weight_us));
      benchPrint("servo.fov_check_with_camera_fk", fov_us.size(), benchStats(fov_us));
    }
    benchPrint("servo.cycle_" + tag + "_weight_servo_fov_step", pieces_us.size(), benchStats(pieces_us), failures);
    benchPrint("servo.cycle_" + tag + "_update", update_us.size(), benchStats(update_us), failures);
  }
  return 0;
}
