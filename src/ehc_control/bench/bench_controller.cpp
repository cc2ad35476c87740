// Benchmark: one EHC controller step (model update + dampers + QP build + solve) for the
// RealMan robot (differential base + 6-DOF arm), with 0 and 10 obstacle pairs, over >= 10000
// closed-loop steps to random targets. Prints JSON lines (median / p99 microseconds).
//   bench_controller [--steps N] [--obstacles K]
// --steps: closed-loop steps per run (default 20000); --obstacles: run only with K (0..10)
// obstacle pairs instead of 0 and 10 (e.g. a short run under valgrind --tool=callgrind).
// Bars: median <= 20 us, p99 <= 60 us with 10 obstacle pairs (DESIGN.md section 11
// asks for 50 / 200 us). Instructions per step, load-independent:
//   valgrind --tool=callgrind --toggle-collect='ehc_control::EhcQpController::step*'
//       devel/lib/ehc_control/bench_controller --steps 2000 --obstacles 10
// ("Collected" / 2000).

#include "ehc_common/bench_util.h"
#include "ehc_control/pose_servo.h"
#include "ehc_control/qp_controller.h"

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <iostream>
#include <random>

using namespace ehc_control;
using ehc_common::benchPrint;
using ehc_common::benchStats;

int main(int argc, char** argv) {
  int steps = 20000;
  std::vector<int> obstacle_counts = {0, 10};
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    if (i + 1 < argc && k == "--steps") {
      steps = std::atoi(argv[++i]);
    } else if (i + 1 < argc && k == "--obstacles") {
      obstacle_counts = {std::atoi(argv[++i])};
    } else {
      std::cerr << "usage: bench_controller [--steps N] [--obstacles 0..10]\n";
      return 2;
    }
  }
  if (steps < 1 || obstacle_counts[0] < 0 || obstacle_counts[0] > 10) {
    std::cerr << "bench_controller: --steps must be >= 1 and --obstacles 0..10\n";
    return 2;
  }
  const std::string robot = std::string(EHC_CONFIG_DIR) + "/robots/realman_rm65_water2/robot.yaml";
  const RobotConfig rc = loadRobotConfig(robot);
  auto model = std::make_shared<const WholeBodyModel>(rc);
  auto map = std::make_shared<const ReachabilityMap>(ReachabilityMap::load(rc.reachability_map_path));
  auto weighting = std::make_shared<const EhcWeighting>(map, EhcWeightingParams{});
  const std::vector<std::string> links = {"link1", "link2", "link3", "link4", "link5",
                                          "link6", "gripper_base_link", "camera_link", "arm_base_link", "ee_link"};
  for (int n_obstacles : obstacle_counts) {
    EhcQpController ctrl(model, QpControllerParams{}, weighting);
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Eigen::Vector3d base = Eigen::Vector3d::Zero();
    Eigen::VectorXd q = rc.arm_ready;
    std::vector<double> us;
    us.reserve(static_cast<std::size_t>(steps));
    long rows = 0, failed = 0, iterations = 0;
    int max_iterations = 0;
    Eigen::Isometry3d target = Eigen::Isometry3d::Identity();
    for (int k = 0; k < steps; ++k) {
      if (k % 400 == 0) {  // a new target every 4 s
        target = Eigen::Isometry3d::Identity();
        target.linear() = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY()).toRotationMatrix() *
                          Eigen::AngleAxisd(0.4 * u(rng), Eigen::Vector3d::UnitX()).toRotationMatrix();
        target.translation() << base.x() + 1.2 * u(rng), base.y() + 1.2 * u(rng), 0.7 + 0.2 * u(rng);
        ctrl.reset();
      }
      const Eigen::Isometry3d tcp = model->fk(base, q, rc.tcp_frame);
      const Vector6d nu = proportionalPoseServo(tcp, target, PoseServoParams{});
      std::vector<ObstaclePair> obs;
      for (int i = 0; i < n_obstacles; ++i) {  // a point obstacle 0.15-0.25 m from each link
        ObstaclePair o;
        o.link = links[static_cast<std::size_t>(i)];
        o.link_point = model->fk(base, q, o.link).translation();
        o.normal = Eigen::Vector3d(0.3 * i - 1.0, 1.0, 0.5).normalized();
        o.distance = 0.15 + 0.01 * i;
        o.obstacle_point = o.link_point - o.distance * o.normal;
        obs.push_back(o);
      }
      const auto t0 = std::chrono::steady_clock::now();
      const ControllerCommand c = ctrl.step(base, q, target, nu, obs);
      us.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
      rows += c.obstacle_rows;
      failed += !c.ok;
      iterations += c.qp_iterations;
      max_iterations = std::max(max_iterations, c.qp_iterations);
      // Integrate (differential base, 100 Hz).
      const double dt = 0.01;
      base.x() += std::cos(base.z()) * c.velocity[0] * dt;
      base.y() += std::sin(base.z()) * c.velocity[0] * dt;
      base.z() += c.velocity[1] * dt;
      q += c.velocity.tail(rc.nArm()) * dt;
    }
    benchPrint("controller.step_obstacles_" + std::to_string(n_obstacles), us.size(), benchStats(us),
               {{"obstacle_rows_mean", ehc_common::jsonNumber(static_cast<double>(rows) / steps)},
                {"qp_failures", failed},
                {"qp_iterations_mean", ehc_common::jsonNumber(static_cast<double>(iterations) / steps)},
                {"qp_iterations_max", max_iterations},
                {"bar_median_us", 20},
                {"bar_p99_us", 60}});
  }
  return 0;
}
