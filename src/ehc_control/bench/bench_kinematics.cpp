// Benchmark: WholeBodyModel FK, whole-body Jacobian and manipulability gradient.
// Prints one JSON object per figure: {"bench":..., "median_us":..., "p99_us":..., "n":...}.

#include "ehc_common/bench_util.h"
#include "ehc_control/whole_body_model.h"

#include <random>

int main(int argc, char** argv) {
  const std::string robot =
      argc > 1 ? argv[1] : std::string(EHC_CONFIG_DIR) + "/robots/realman_rm65_water2/robot.yaml";
  const ehc_control::WholeBodyModel model(ehc_control::loadRobotConfig(robot));
  std::mt19937 rng(1);
  std::vector<Eigen::VectorXd> qs;
  for (int i = 0; i < 1000; ++i) {
    Eigen::VectorXd q(model.nArm());
    for (int j = 0; j < model.nArm(); ++j)
      q[j] = std::uniform_real_distribution<double>(model.config().arm_lower[j],
                                                    model.config().arm_upper[j])(rng);
    qs.push_back(q);
  }
  const Eigen::Vector3d base(1.0, 2.0, 0.3);
  const int n = 20000;
  double sink = 0.0;
  ehc_common::benchReport("kinematics.fk_tcp", n, [&](int i) {
    sink += model.fk(base, qs[static_cast<std::size_t>(i % 1000)], "ee_link").translation().x();
  });
  ehc_common::benchReport("kinematics.whole_body_jacobian_tcp", n, [&](int i) {
    sink += model.jacobian(base, qs[static_cast<std::size_t>(i % 1000)], "ee_link")(0, 0);
  });
  ehc_common::benchReport("kinematics.manipulability_gradient", n, [&](int i) {
    sink += model.manipulabilityGradient(qs[static_cast<std::size_t>(i % 1000)])[0];
  });
  return sink == 12345.678 ? 1 : 0;  // keep the work observable
}
