// Base imprecision (ehc_sim::BaseImprecisionParams on top of either base model): level 0 is
// today's base bit for bit; each effect does what it says (odometry drift the stack cannot see,
// minimum speed, command latency, localisation fixes that make /odom jump) and the level scales
// it; the same seed gives the same run; bad configuration fails naming the file and the field.
// Seeds are consecutive from a base seed, each printed.

#include "ehc_common/config_node.h"
#include "ehc_sim/base_model.h"
#include "ehc_sim/fake_robot_config.h"
#include "ehc_sim/kinematic_fake_robot.h"
#include "ehc_test/errors.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

using ehc_sim::ActuationNoise;
using ehc_sim::BaseImprecisionParams;
using ehc_sim::BaseModelConfig;
using ehc_sim::BaseModelType;
using ehc_sim::KinematicFakeRobot;

namespace {
constexpr double kDt = 0.01;
constexpr unsigned kBaseSeed = 4100;

ehc_control::RobotConfig robot(const std::string& name = "realman_rm65_water2") {
  return ehc_control::loadRobotConfig(std::string(EHC_CONFIG_DIR) + "/robots/" + name + "/robot.yaml");
}
ActuationNoise noise(bool on) {
  ActuationNoise n;
  n.enabled = on;
  return n;
}
/// Every magnitude zero (a level > 0 then changes nothing): tests switch on one effect.
BaseImprecisionParams none(double level = 1.0) {
  BaseImprecisionParams p;
  p.level = level;
  p.scale_error = p.track_error = p.curvature_error = 0.0;
  p.slip_linear = p.slip_angular = 0.0;
  p.min_linear_speed = p.min_angular_speed = 0.0;
  p.command_latency = 0.0;
  p.localisation_period = 0.0;
  return p;
}
BaseModelConfig model(const BaseImprecisionParams& p, BaseModelType type = BaseModelType::Ideal) {
  BaseModelConfig c;
  c.type = type;
  c.imprecision = p;
  return c;
}
/// Base twist (v_x, [v_y,] w_z), arm at rest.
Eigen::VectorXd baseCommand(const KinematicFakeRobot& r, double vx, double vy, double wz) {
  Eigen::VectorXd c = Eigen::VectorXd::Zero(r.nDof());
  const int nb = r.robot().nBase();
  c[0] = vx;
  if (nb == 3) c[1] = vy;
  c[nb - 1] = wz;
  return c;
}
/// Piecewise-constant random commands (base and arm), a new one every 0.5 s.
std::vector<Eigen::VectorXd> randomCommands(int n_dof, int steps, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Eigen::VectorXd> out;
  Eigen::VectorXd c = Eigen::VectorXd::Zero(n_dof);
  for (int k = 0; k < steps; ++k) {
    if (k % 50 == 0) {
      for (int i = 0; i < n_dof; ++i) c[i] = 0.4 * u(rng);
      if (k % 200 == 150) c.setZero();  // stops too
    }
    out.push_back(c);
  }
  return out;
}
/// |true - odometry| in the plane after driving `distance` m straight at 0.25 m/s (along x; a
/// holonomic base at 60 deg to it), then 1 s standing (noise off: the wheels turn exactly as
/// commanded).
double straightDriveError(const ehc_control::RobotConfig& rc, const BaseModelConfig& m, unsigned seed,
                          double distance = 1.0) {
  KinematicFakeRobot r(rc, noise(false), seed, m);
  const double a = rc.nBase() == 3 ? M_PI / 3.0 : 0.0;
  const Eigen::VectorXd go = baseCommand(r, 0.25 * std::cos(a), 0.25 * std::sin(a), 0.0);
  const Eigen::VectorXd stop = baseCommand(r, 0.0, 0.0, 0.0);
  const int n = static_cast<int>(std::lround(distance / 0.25 / kDt));
  for (int k = 0; k < n; ++k) r.step(go, kDt);
  for (int k = 0; k < 100; ++k) r.step(stop, kDt);
  if (m.imprecision.localisation_period == 0.0 || m.imprecision.level == 0.0) {
    EXPECT_NEAR(r.odometryPose().x(), distance * std::cos(a), 1e-9) << "the odometry counts the wheels' distance";
    EXPECT_NEAR(r.odometryPose().y(), distance * std::sin(a), 1e-9);
  }
  return (r.basePose().head<2>() - r.odometryPose().head<2>()).norm();
}
}  // namespace

TEST(BaseImprecision, LevelZeroIsTodaysBaseBitForBit) {
  // Any magnitudes at level 0: no model, no random draw; ideal and water2, noise on.
  BaseImprecisionParams odd;
  odd.level = 0.0;
  odd.scale_error = 0.3;
  odd.command_latency = 0.7;
  odd.localisation_period = 0.2;
  for (const BaseModelType type : {BaseModelType::Ideal, BaseModelType::Water2}) {
    for (unsigned seed = kBaseSeed; seed < kBaseSeed + 3; ++seed) {
      std::printf("level 0, %s, seed %u\n", ehc_sim::toString(type).c_str(), seed);
      SCOPED_TRACE("seed " + std::to_string(seed));
      BaseModelConfig plain;
      plain.type = type;
      KinematicFakeRobot a(robot(), noise(true), seed, plain), b(robot(), noise(true), seed, model(odd, type));
      EXPECT_EQ(b.imprecision(), nullptr);
      EXPECT_EQ(b.odometryIsTruth(), type == BaseModelType::Ideal);
      for (const Eigen::VectorXd& c : randomCommands(a.nDof(), 1000, seed)) {
        a.step(c, kDt);
        b.step(c, kDt);
        ASSERT_EQ(a.basePose(), b.basePose());
        ASSERT_EQ(a.odometryPose(), b.odometryPose());
        ASSERT_EQ(a.odometryTwist(), b.odometryTwist());
        ASSERT_EQ(a.executedVelocity(), b.executedVelocity());
      }
    }
  }
}

TEST(BaseImprecision, OdometryDriftGrowsWithTheLevelOnEveryBaseType) {
  // Commanded straight 1 m without localisation fixes: the odometry says 1 m along x, the true
  // pose is off by the run's scale and curvature errors and the slip. Differential and
  // holonomic (driving sideways too) bases, 12 seeds per level.
  BaseImprecisionParams p;
  p.localisation_period = 0.0;
  for (const std::string name : {"realman_rm65_water2", "kuka_iiwa14_kmr"}) {
    const ehc_control::RobotConfig rc = robot(name);
    double previous = 0.0;
    for (const double level : {0.0, 0.5, 1.0, 2.0, 4.0}) {
      p.level = level;
      double sum = 0.0;
      for (unsigned seed = kBaseSeed; seed < kBaseSeed + 12; ++seed) sum += straightDriveError(rc, model(p), seed);
      const double mean = sum / 12.0;
      std::printf("%s level %.1f: mean |true - odom| after 1 m = %.4f m (seeds %u..%u)\n", name.c_str(), level, mean,
                  kBaseSeed, kBaseSeed + 11);
      if (level == 0.0) EXPECT_EQ(mean, 0.0) << name;
      else EXPECT_GT(mean, 1.5 * previous) << name << " level " << level;
      previous = mean;
    }
    EXPECT_GT(previous, 0.02) << name << ": level 4 drifts centimetres over 1 m";
  }
  // The systematic part scales with the level: one seed (the same error directions), no slip.
  BaseImprecisionParams systematic = p;
  systematic.slip_linear = systematic.slip_angular = 0.0;
  const ehc_control::RobotConfig rc = robot();
  for (unsigned seed = kBaseSeed; seed < kBaseSeed + 5; ++seed) {
    systematic.level = 0.5;
    const double half = straightDriveError(rc, model(systematic), seed);
    systematic.level = 1.0;
    const double one = straightDriveError(rc, model(systematic), seed);
    std::printf("seed %u systematic only: level 0.5 %.5f m, level 1 %.5f m\n", seed, half, one);
    EXPECT_NEAR(one / half, 2.0, 0.1) << "seed " << seed;
  }
}

TEST(BaseImprecision, MinimumSpeedSwallowsSlowerCommands) {
  BaseImprecisionParams p = none();
  p.min_linear_speed = 0.02;
  p.min_angular_speed = 0.05;
  for (const BaseModelType type : {BaseModelType::Ideal, BaseModelType::Water2}) {
    for (const double level : {1.0, 2.0}) {
      p.level = level;
      auto travel = [&](double v, double w) {
        KinematicFakeRobot r(robot(), noise(true), kBaseSeed, model(p, type));
        for (int k = 0; k < 200; ++k) r.step(baseCommand(r, v, 0.0, w), kDt);
        return Eigen::Vector2d(r.basePose().head<2>().norm(), std::abs(r.basePose().z()));
      };
      const double vmin = level * p.min_linear_speed, wmin = level * p.min_angular_speed;
      SCOPED_TRACE(ehc_sim::toString(type) + " level " + std::to_string(level));
      EXPECT_EQ(travel(0.5 * vmin, 0.0), Eigen::Vector2d::Zero()) << "below the minimum speed: no motion, no noise";
      EXPECT_EQ(travel(0.0, 0.5 * wmin), Eigen::Vector2d::Zero());
      EXPECT_EQ(travel(0.9 * vmin, 0.9 * wmin), Eigen::Vector2d::Zero());
      EXPECT_GT(travel(2.0 * vmin, 0.0)[0], 0.5 * 2.0 * vmin * 2.0) << "above it the base drives";
      EXPECT_GT(travel(0.0, 2.0 * wmin)[1], 0.3 * 2.0 * wmin * 2.0);
    }
  }
}

TEST(BaseImprecision, CommandLatencyDelaysTheFirstMotionByItsLevelledTime) {
  BaseImprecisionParams p = none();
  p.command_latency = 0.1;
  for (const BaseModelType type : {BaseModelType::Ideal, BaseModelType::Water2}) {
    // The Water2 chain's own latency comes on top.
    const double own = type == BaseModelType::Water2 ? ehc_sim::Water2BaseParams().response.command_latency : 0.0;
    for (const double level : {0.5, 1.0, 3.0}) {
      p.level = level;
      KinematicFakeRobot r(robot(), noise(false), kBaseSeed, model(p, type));
      int first = -1;
      for (int k = 0; k < 100 && first < 0; ++k) {
        r.step(baseCommand(r, 0.3, 0.0, 0.0), kDt);
        if (r.executedVelocity()[0] != 0.0) first = k;
      }
      EXPECT_EQ(first, static_cast<int>(std::lround((own + level * p.command_latency) / kDt)))
          << ehc_sim::toString(type) << " level " << level;
    }
  }
}

TEST(BaseImprecision, LocalisationFixesMakeOdomJumpAtTheirRate) {
  // Systematic errors and slip make the odometry drift; every levelled period a fix resets it to
  // the true pose plus its error: /odom jumps then, and only then.
  BaseImprecisionParams p;
  p.localisation_period = 0.5;
  for (const double level : {1.0, 2.0}) {
    p.level = level;
    for (unsigned seed = kBaseSeed; seed < kBaseSeed + 3; ++seed) {
      std::printf("localisation level %.0f seed %u\n", level, seed);
      KinematicFakeRobot r(robot(), noise(true), seed, model(p));
      const double period = level * p.localisation_period;
      const double sigma = level * p.localisation_position_sigma;
      int jumps = 0;
      double worst_after_fix = 0.0, most_drift = 0.0;
      Eigen::Vector3d error_after_fix = Eigen::Vector3d::Zero();
      for (const Eigen::VectorXd& c : randomCommands(r.nDof(), 2000, seed)) {  // 20 s
        const Eigen::Vector3d before = r.odometryPose();
        const Eigen::Vector3d error_before = r.basePose() - before;
        const long fixes = r.imprecision()->fixes();
        r.step(c, kDt);
        const Eigen::Vector3d tw = r.odometryTwist();
        const Eigen::Vector3d dead_reckoned = ehc_sim::integrateBaseTwist(before, tw[0], tw[1], tw[2], kDt);
        const bool jumped = (r.odometryPose() - dead_reckoned).norm() > 1e-9;
        const bool fixed = r.imprecision()->fixes() > fixes;
        ASSERT_EQ(jumped, fixed) << "t = " << r.time();
        if (fixed) {
          ++jumps;
          EXPECT_NEAR(std::remainder(r.time(), period), 0.0, 1e-6) << "a fix at its period";
          // The drift since the last fix, then the new fix's own error.
          most_drift = std::max(most_drift, (error_before - error_after_fix).norm());
          error_after_fix = r.basePose() - r.odometryPose();
          worst_after_fix = std::max(worst_after_fix, error_after_fix.head<2>().norm());
        }
      }
      EXPECT_EQ(jumps, static_cast<int>(std::floor(20.0 / period + 1e-9)));
      EXPECT_LT(worst_after_fix, 5.0 * sigma * std::sqrt(2.0)) << "a fix is the true pose within its error";
      EXPECT_GT(most_drift, 1e-3) << "the odometry drifted between fixes";
    }
  }
}

TEST(BaseImprecision, TheWater2ReportsTheImpreciseOdometry) {
  // robot_status is the base's own (odometry + localisation) pose; without the Water2's
  // localisation error it is exactly the imprecise odometry, and the bridge's /odom follows it.
  BaseModelConfig m = model(BaseImprecisionParams(), BaseModelType::Water2);
  m.imprecision.level = 1.0;
  m.imprecision.localisation_period = 0.0;  // drift without bound
  m.water2.localisation_position_sigma = m.water2.localisation_heading_sigma = 0.0;
  KinematicFakeRobot r(robot(), noise(true), kBaseSeed, m);
  for (const Eigen::VectorXd& c : randomCommands(r.nDof(), 1500, kBaseSeed)) r.step(c, kDt);
  EXPECT_EQ(r.statusPose(), r.imprecision()->odometryPose());
  EXPECT_FALSE(r.odometryIsTruth());
  const double drift = (r.basePose() - r.imprecision()->odometryPose()).head<2>().norm();
  const double bridge = (r.odometryPose() - r.imprecision()->odometryPose()).head<2>().norm();
  std::printf("water2 + level 1 after 15 s: true - odometry %.4f m, bridge - odometry %.4f m\n", drift, bridge);
  EXPECT_GT(drift, 1e-3);
  EXPECT_LT(bridge, drift);
}

TEST(BaseImprecision, SameSeedSameRunOtherSeedOtherErrors) {
  BaseImprecisionParams p;
  p.level = 1.0;
  const BaseModelConfig m = model(p, BaseModelType::Water2);
  KinematicFakeRobot a(robot(), noise(true), kBaseSeed, m), b(robot(), noise(true), kBaseSeed, m),
      c(robot(), noise(true), kBaseSeed + 1, m);
  const auto commands = randomCommands(a.nDof(), 800, kBaseSeed);
  for (const auto& cmd : commands) {
    a.step(cmd, kDt);
    b.step(cmd, kDt);
    c.step(cmd, kDt);
    ASSERT_EQ(a.basePose(), b.basePose());
    ASSERT_EQ(a.odometryPose(), b.odometryPose());
  }
  EXPECT_EQ(a.imprecision()->systematicErrors(), b.imprecision()->systematicErrors());
  EXPECT_NE(a.imprecision()->systematicErrors(), c.imprecision()->systematicErrors());
  EXPECT_NE(a.basePose(), c.basePose());
  // reset() with the run's seed repeats it.
  const Eigen::Vector3d end = a.basePose();
  a.reset(Eigen::Vector3d::Zero(), a.robot().arm_ready, kBaseSeed);
  for (const auto& cmd : commands) a.step(cmd, kDt);
  EXPECT_EQ(a.basePose(), end);
}

TEST(BaseImprecision, ConfigurationIsReadValidatedAndPrinted) {
  const std::string robot_file = std::string(EHC_CONFIG_DIR) + "/robots/realman_rm65_water2/robot.yaml";
  auto load = [&](const std::string& extra) {
    const auto root = ehc_common::ConfigNode::loadString("sim:\n  robot: " + robot_file + "\n" + extra,
                                                          "test.yaml", "FakeRobotConfig");
    return ehc_sim::loadFakeRobotConfig(root.child("sim"));
  };
  const ehc_sim::FakeRobotConfig c = load("  base_imprecision: {level: 1.5, command_latency: 0.2}\n");
  EXPECT_EQ(c.base_model.imprecision.level, 1.5);
  EXPECT_EQ(c.base_model.imprecision.command_latency, 0.2);
  EXPECT_DOUBLE_EQ(c.base_model.imprecision.levelled().command_latency, 0.3);
  EXPECT_EQ(c.base_model.imprecision.levelled().slip_correlation_time, BaseImprecisionParams().slip_correlation_time);
  EXPECT_NE(c.summary().find("base imprecision level 1.5"), std::string::npos) << c.summary();
  EXPECT_NE(load("").summary().find("base imprecision off"), std::string::npos);
  for (const auto& [yaml, field] : std::vector<std::pair<std::string, std::string>>{
           {"{level: -1}", "level"},
           {"{level: .nan}", "level"},
           {"{level: 101}", "level"},
           {"{slip_linear: -0.1}", "slip_linear"},
           {"{localisation_period: .inf}", "localisation_period"},
           {"{comand_latency: 0.1}", "comand_latency"}}) {
    const std::string e = ehc_test::errorOf([&] { load("  base_imprecision: " + yaml + "\n"); });
    EXPECT_NE(e.find(field), std::string::npos) << yaml << ": " << e;
    EXPECT_NE(e.find("test.yaml"), std::string::npos) << yaml << ": " << e;
    std::printf("%s -> %s\n", yaml.c_str(), e.c_str());
  }
  // Both simulators' files document the defaults (off).
  const BaseImprecisionParams d;
  for (const std::string file : {"kinematic_sim.yaml", "bullet_sim.yaml"}) {
    const auto root = ehc_common::ConfigNode::loadFile(std::string(EHC_CONFIG_DIR) + "/sim/" + file, "test");
    const BaseImprecisionParams f = ehc_sim::loadBaseImprecisionParams(root.child("sim").child("base_imprecision"));
    SCOPED_TRACE(file);
    EXPECT_EQ(f.level, 0.0);
    EXPECT_EQ(f.scale_error, d.scale_error);
    EXPECT_EQ(f.track_error, d.track_error);
    EXPECT_EQ(f.curvature_error, d.curvature_error);
    EXPECT_EQ(f.slip_linear, d.slip_linear);
    EXPECT_EQ(f.slip_angular, d.slip_angular);
    EXPECT_EQ(f.slip_correlation_time, d.slip_correlation_time);
    EXPECT_EQ(f.min_linear_speed, d.min_linear_speed);
    EXPECT_EQ(f.min_angular_speed, d.min_angular_speed);
    EXPECT_EQ(f.command_latency, d.command_latency);
    EXPECT_EQ(f.localisation_period, d.localisation_period);
    EXPECT_EQ(f.localisation_position_sigma, d.localisation_position_sigma);
    EXPECT_EQ(f.localisation_heading_sigma, d.localisation_heading_sigma);
  }
}
