// Benchmark: one EHC controller step (model update + dampers + QP build + solve) for the
// RealMan robot (differential base + 6-DOF arm), with 0 and 10 obstacle pairs, over >= 10000
// closed-loop steps to random targets. Prints JSON lines (median / p99 microseconds).
//   bench_controller [--steps N] [--obstacles K] [--repeats R]
// --steps: closed-loop steps per run (default 20000); --obstacles: run only with K (0..10)
// obstacle pairs instead of 0 and 10 (e.g. a short run under valgrind --tool=callgrind);
// --repeats: the same seeded run R times (default 3). The line reports the run with the lowest
// median wall time (the others are disturbed by whatever else the machine ran; all medians are
// in run_medians_us).
// Bar (DESIGN.md section 11): median <= 10 us with 10 obstacle pairs. Instructions per step,
// load-independent:
//   valgrind --tool=callgrind --toggle-collect='ehc_control::EhcQpController::step*'
//       devel/lib/ehc_control/bench_controller --steps 2000 --obstacles 10 --repeats 1
// ("Collected" / 2000).

#include "ehc_common/bench_util.h"
#include "ehc_test/control_fixtures.h"
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

namespace {

/// One seeded closed-loop run: per-step wall times and the QP's counters.
struct Run {
  std::vector<double> us;
  long rows = 0, failed = 0, iterations = 0;
  int max_iterations = 0;
};

Run runClosedLoop(const RobotConfig& rc, const std::shared_ptr<const WholeBodyModel>& model,
                  const std::shared_ptr<const EhcWeighting>& weighting, int n_obstacles, int steps) {
  const std::vector<std::string> links = {"link1", "link2", "link3", "link4", "link5",
                                          "link6", "gripper_base_link", "camera_link", "arm_base_link", "ee_link"};
  EhcQpController ctrl(model, QpControllerParams{}, weighting);
  std::mt19937 rng(3);
  test::KinematicSim sim;
  sim.q = rc.arm_ready;
  const Eigen::Vector3d& base = sim.base;
  const Eigen::VectorXd& q = sim.q;
  Run run;
  run.us.reserve(static_cast<std::size_t>(steps));
  Eigen::Isometry3d target = Eigen::Isometry3d::Identity();
  for (int k = 0; k < steps; ++k) {
    if (k % 400 == 0) {  // a new target every 4 s
      target = test::randomDownwardTarget(rng, base);
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
    run.us.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
    run.rows += c.obstacle_rows;
    run.failed += !c.ok;
    run.iterations += c.qp_iterations;
    run.max_iterations = std::max(run.max_iterations, c.qp_iterations);
    sim.step(*model, c.velocity, 0.01);  // 100 Hz
  }
  return run;
}

}  // namespace

int main(int argc, char** argv) {
  int steps = 20000, repeats = 3;
  std::vector<int> obstacle_counts = {0, 10};
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    if (i + 1 < argc && k == "--steps") {
      steps = std::atoi(argv[++i]);
    } else if (i + 1 < argc && k == "--obstacles") {
      obstacle_counts = {std::atoi(argv[++i])};
    } else if (i + 1 < argc && k == "--repeats") {
      repeats = std::atoi(argv[++i]);
    } else {
      std::cerr << "usage: bench_controller [--steps N] [--obstacles 0..10] [--repeats R]\n";
      return 2;
    }
  }
  if (steps < 1 || repeats < 1 || obstacle_counts[0] < 0 || obstacle_counts[0] > 10) {
    std::cerr << "bench_controller: --steps and --repeats must be >= 1 and --obstacles 0..10\n";
    return 2;
  }
  const std::string robot = std::string(EHC_CONFIG_DIR) + "/robots/realman_rm65_water2/robot.yaml";
  const RobotConfig rc = loadRobotConfig(robot);
  auto model = std::make_shared<const WholeBodyModel>(rc);
  auto map = std::make_shared<const ReachabilityMap>(ReachabilityMap::load(rc.reachability_map_path));
  auto weighting = std::make_shared<const EhcWeighting>(map, EhcWeightingParams{});
  for (int n_obstacles : obstacle_counts) {
    Run best;
    ehc_common::BenchStats best_stats;
    ehc_common::Json medians = ehc_common::Json::array();
    for (int r = 0; r < repeats; ++r) {
      Run run = runClosedLoop(rc, model, weighting, n_obstacles, steps);
      const ehc_common::BenchStats s = benchStats(run.us);
      medians.push_back(ehc_common::jsonNumber(s.median_us));
      if (r == 0 || s.median_us < best_stats.median_us) {
        best = std::move(run);
        best_stats = s;
      }
    }
    benchPrint("controller.step_obstacles_" + std::to_string(n_obstacles), best.us.size(), best_stats,
               {{"run_medians_us", medians},
                {"obstacle_rows_mean", ehc_common::jsonNumber(static_cast<double>(best.rows) / steps)},
                {"qp_failures", best.failed},
                {"qp_iterations_mean", ehc_common::jsonNumber(static_cast<double>(best.iterations) / steps)},
                {"qp_iterations_max", best.max_iterations},
                {"bar_median_us", 10}});
  }
  return 0;
}
