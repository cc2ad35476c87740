// Base models: the Water2 chain's step response on sim time (latency, 0.5 s hold then stop
// without renewal, acceleration-limited ramp, gain, the bridge's zero after silence), its
// odometry (status rate, dead reckoning between statuses, bounded error), the ideal model
// unchanged, and the configuration (files document the struct's defaults; unknown keys fail).

#include "ehc_common/config_node.h"
#include "ehc_sim/base_model.h"
#include "ehc_sim/fake_robot_config.h"
#include "ehc_sim/kinematic_fake_robot.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

using ehc_sim::ActuationNoise;
using ehc_sim::BaseModelConfig;
using ehc_sim::BaseModelType;
using ehc_sim::KinematicFakeRobot;
using ehc_sim::Water2BaseModel;
using ehc_sim::Water2BaseParams;

namespace {
constexpr double kDt = 0.01;

ehc_control::RobotConfig robot() {
  return ehc_control::loadRobotConfig(std::string(EHC_CONFIG_DIR) + "/robots/realman_rm65_water2/robot.yaml");
}
ActuationNoise off() {
  ActuationNoise n;
  n.enabled = false;
  return n;
}
/// Water2 without localisation error: the status pose is the true pose.
BaseModelConfig water2(double localisation_sigma = 0.0) {
  BaseModelConfig c;
  c.type = BaseModelType::Water2;
  c.water2.localisation_position_sigma = localisation_sigma;
  c.water2.localisation_heading_sigma = localisation_sigma;
  return c;
}
Eigen::VectorXd baseCommand(int n, double v, double w) {
  Eigen::VectorXd c = Eigen::VectorXd::Zero(n);
  c[0] = v;
  c[1] = w;
  return c;
}
}  // namespace

// The controller commands 0.4 m/s from t = 0 on, every step (as in lock-step).
TEST(Water2Base, StepResponseLatencyRampGainAndStop) {
  const Water2BaseParams p;  // the documented defaults
  KinematicFakeRobot r(robot(), off(), 1, water2());
  const Eigen::VectorXd go = baseCommand(r.nDof(), 0.4, 0.0);
  // The bridge sends at t = 0; the wheels act from t = command_latency (0.05 s) on.
  const int first_moving = static_cast<int>(std::lround(p.response.command_latency / kDt));
  double prev = 0.0, max_step = 0.0;
  int k = 0;
  for (; k < 300; ++k) {  // 3 s
    r.step(go, kDt);
    const double v = r.executedVelocity()[0];
    if (k < first_moving) {
      EXPECT_EQ(v, 0.0) << "step " << k << ": before the command arrived";
    } else if (k == first_moving) {
      EXPECT_GT(v, 0.0) << "the command acts after the latency";
    }
    max_step = std::max(max_step, std::abs(v - prev));
    prev = v;
    // Acceleration-limited: the speed can only have grown at a_max since it started.
    EXPECT_LE(v, std::max(0.0, p.response.linear_acceleration * ((k + 1) * kDt - p.response.command_latency)) + 1e-9) << "step " << k;
  }
  EXPECT_LE(max_step, p.response.linear_acceleration * kDt + 1e-12);
  EXPECT_NEAR(prev, p.response.linear_gain * 0.4, 1e-6) << "steady state = gain x command";
  EXPECT_EQ(r.executedVelocity()[1], 0.0);

  // The controller commands zero: the wheels decelerate (acceleration-limited) to exactly 0.
  const Eigen::VectorXd stop = baseCommand(r.nDof(), 0.0, 0.0);
  const double t_stop = r.time();
  double stopped_at = -1.0;
  for (int j = 0; j < 200; ++j, ++k) {
    r.step(stop, kDt);
    const double v = r.executedVelocity()[0];
    if (v != 0.0) {
      EXPECT_LE(std::abs(v - prev), p.response.linear_acceleration * kDt + 1e-12);
    } else {  // static friction: a wheel told to stop stops below its deadband
      EXPECT_LT(std::abs(prev), p.response.linear_acceleration * kDt + ActuationNoise().base_deadband_linear);
    }
    prev = v;
    if (v == 0.0 && stopped_at < 0) stopped_at = r.time() - t_stop;
  }
  EXPECT_EQ(prev, 0.0);
  // Not before latency + v / a_max, and well within 0.5 s + that (the zero renews at once).
  EXPECT_GE(stopped_at, p.response.command_latency + (p.response.linear_gain * 0.4 - 0.005) / p.response.linear_acceleration - 1e-9);
  EXPECT_LE(stopped_at, p.response.command_latency + 2.0 * p.response.linear_gain * 0.4 / p.response.linear_acceleration);
}

// A single joy_control (no renewal) is executed for exactly its 0.5 s lifetime, then the base
// stops by itself; a renewal extends it.
TEST(Water2Base, HoldsAJoyControlForItsLifetimeThenStops) {
  Water2BaseParams p;
  p.response.linear_acceleration = 100.0;  // isolate the hold from the ramp
  p.response.time_constant = 0.0;
  Water2BaseModel base(p);
  base.joyControl(0.3, 0.0, 0.0);
  const auto inForce = [&](double t) {
    base.advance(t, kDt, 0.005, 0.01);
    return base.commandInForce()[0];
  };
  for (int k = 0; k < 100; ++k) {
    const double t = k * kDt;
    const double u = inForce(t);
    if (t < p.response.command_latency - 1e-9 || t >= p.response.command_latency + p.response.command_lifetime - 1e-9)
      EXPECT_EQ(u, 0.0) << "t = " << t;
    else
      EXPECT_EQ(u, 0.3) << "t = " << t;
    EXPECT_EQ(base.wheelVelocity()[0], p.response.linear_gain * u) << "t = " << t;
  }
  EXPECT_EQ(base.joyControls(), 1);  // the bridge sent nothing: no /cmd_vel came in

  // Renewed at 1.2 s: in force from 1.25 to 1.75 s.
  base.joyControl(0.2, 0.1, 1.2);
  EXPECT_EQ(inForce(1.24), 0.0);
  EXPECT_EQ(inForce(1.25), 0.2);
  EXPECT_EQ(base.commandInForce()[1], 0.1);
  base.joyControl(0.2, 0.1, 1.6);  // renewal before expiry: held until 2.15 s
  EXPECT_EQ(inForce(1.9), 0.2);
  EXPECT_EQ(inForce(2.14), 0.2);
  EXPECT_EQ(inForce(2.15), 0.0);
}

// Through the bridge: commands are resent at 20 Hz while fresh, scaled keeping the turn radius,
// and zero is sent once /cmd_vel stops for 0.2 s, so the base stops before its own 0.5 s hold.
TEST(Water2Base, BridgeResendsAt20HzScalesAndSendsZeroAfterSilence) {
  Water2BaseParams p;
  p.response.linear_acceleration = 100.0;
  p.response.time_constant = 0.0;
  Water2BaseModel base(p);
  for (int k = 0; k < 100; ++k) {  // 1 s of /cmd_vel at 100 Hz, twice the bounds
    EXPECT_TRUE(base.command(1.0, 1.0, k * kDt));
    base.advance(k * kDt, kDt, 0.005, 0.01);
  }
  EXPECT_EQ(base.joyControls(), 20) << "20 Hz resend";
  EXPECT_NEAR(base.commandInForce()[0], 0.5, 1e-12);  // scaled as a whole: w / v kept
  EXPECT_NEAR(base.commandInForce()[1], 0.5, 1e-12);
  double zero_at = -1.0;
  for (int k = 100; k < 200; ++k) {  // silence
    base.advance(k * kDt, kDt, 0.005, 0.01);
    if (zero_at < 0 && base.commandInForce()[0] == 0.0) zero_at = k * kDt;
  }
  // Last /cmd_vel at 0.99 s; the bridge's zero at the first step > 0.99 + 0.2, executed 0.05 s later.
  EXPECT_NEAR(zero_at, 0.99 + p.bridge_command_timeout + kDt + p.response.command_latency, 1e-9);
  EXPECT_LT(zero_at, 0.99 + p.response.command_latency + p.response.command_lifetime);
}

// /odom: a new status every 0.5 s (received 0.05 s after sampling), dead-reckoned in between
// with the velocity the base response model predicts; its error from the true pose stays bounded
// over a long drive (it does not grow with the distance: the status is the base's map pose),
// with noise and localisation error on.
TEST(Water2Base, OdometryRateAndBoundedDrift) {
  const Water2BaseParams p;
  {
    KinematicFakeRobot r(robot(), off(), 1, water2());
    const Eigen::VectorXd go = baseCommand(r.nDof(), 0.3, 0.2);
    long statuses = 0;
    for (int k = 1; k <= 300; ++k) {
      r.step(go, kDt);
      if (r.water2()->statuses() != statuses) {
        statuses = r.water2()->statuses();
        // Received at sample + status_latency.
        EXPECT_NEAR(r.time(), statuses * p.status_period + p.status_latency, 1e-9);
      }
    }
    EXPECT_EQ(r.water2()->statuses(), static_cast<long>(std::floor((3.0 - p.status_latency) / p.status_period)));
    // /odom's twist is the predicted base velocity (gain x command in steady state), which is
    // what the wheels do (same model, no noise), not the command.
    const Eigen::Vector3d twist = r.odometryTwist();
    EXPECT_NEAR(twist[0], r.executedVelocity()[0], 1e-9);
    EXPECT_NEAR(twist[2], r.executedVelocity()[1], 1e-9);
    EXPECT_NEAR(twist[0], p.response.linear_gain * 0.3, 1e-6);
    EXPECT_NEAR(twist[2], p.response.angular_gain * 0.2, 1e-6);
  }
  // Long drive, default model (noise, localisation error on): bounded error.
  KinematicFakeRobot r(robot(), ActuationNoise{}, 3, BaseModelConfig{BaseModelType::Water2, p, {}});
  const ActuationNoise noise;
  const double v = 0.4, w = 0.3;
  // Bound: the bridge predicts the wheels exactly but for what it cannot know: Table I noise
  // over one status horizon (4 sigma of its random walk, translation and the heading's lever
  // arm), 4 sigma of localisation error, and the wheel deadband (a command below it is not
  // executed: at most deadband x horizon). None of it grows with the distance travelled.
  const double horizon = p.status_period + p.status_latency;
  const double walk = std::sqrt(horizon * kDt);  // s: sqrt(steps) x dt
  const double bound = 4.0 * noise.base_translation * walk + 4.0 * noise.base_rotation * walk * v * horizon +
                       4.0 * std::sqrt(2.0) * p.localisation_position_sigma + 4.0 * p.localisation_heading_sigma * v * horizon +
                       noise.base_deadband_linear * horizon;
  double worst = 0.0, travelled = 0.0;
  Eigen::Vector3d prev = r.basePose();
  for (int k = 0; k < 6000; ++k) {  // 60 s
    const double s = k * kDt;
    r.step(baseCommand(r.nDof(), v * std::cos(0.2 * s), w * std::sin(0.1 * s)), kDt);
    travelled += (r.basePose() - prev).head<2>().norm();
    prev = r.basePose();
    worst = std::max(worst, (r.odometryPose() - r.basePose()).head<2>().norm());
  }
  EXPECT_GT(travelled, 5.0);
  EXPECT_LT(worst, bound) << "travelled " << travelled << " m";
}

namespace {
/// /odom against the true pose while the controller commands `profile(t)` every 10 ms step.
struct OdometryErrors {
  double worst_error = 0.0;  ///< m: |odom - truth| (x, y), every step
  double worst_heading = 0.0;  ///< rad
  double worst_jump = 0.0;   ///< m: |odom step - true step| at a status reception
  int statuses = 0;
};
template <class Profile>
OdometryErrors odometryErrors(const BaseModelConfig& model, double duration, Profile profile) {
  KinematicFakeRobot r(robot(), off(), 1, model);
  OdometryErrors e;
  long statuses = 0;
  Eigen::Vector3d odom = r.odometryPose(), truth = r.basePose();
  for (int k = 0; k * kDt < duration; ++k) {
    const Eigen::Vector2d c = profile(k * kDt);
    r.step(baseCommand(r.nDof(), c[0], c[1]), kDt);
    const Eigen::Vector3d o = r.odometryPose(), t = r.basePose();
    e.worst_error = std::max(e.worst_error, (o - t).head<2>().norm());
    e.worst_heading = std::max(e.worst_heading, std::abs(std::remainder(o.z() - t.z(), 2.0 * M_PI)));
    if (r.water2()->statuses() != statuses) {
      statuses = r.water2()->statuses();
      ++e.statuses;
      e.worst_jump = std::max(e.worst_jump, ((o - odom) - (t - truth)).head<2>().norm());
    }
    odom = o;
    truth = t;
  }
  return e;
}
}  // namespace

// The rehearsal's finding: /odom jumped by up to 11.4 cm at a robot_status, because
// the bridge dead-reckoned the COMMANDED twist between the 2 Hz statuses while the base follows
// it through latency, lag, an acceleration ramp and a 0.95 gain. The bridge now dead-reckons
// through the base's own response model (ehc_realman::Water2VelocityResponse, the one the
// simulated base runs). Start from rest to 0.4 m/s just after a status, drive, turn, stop.
// Same base, same commands, same statuses: only the bridge's model differs.
TEST(Water2Base, OdometryPredictsTheBaseResponseBetweenStatuses) {
  const auto profile = [](double t) {
    if (t < 0.52) return Eigen::Vector2d(0.0, 0.0);  // rest; start just after the status at 0.5 s
    if (t < 3.0) return Eigen::Vector2d(0.4, 0.0);
    if (t < 5.0) return Eigen::Vector2d(0.3, 0.6);   // turn
    return Eigen::Vector2d(0.0, 0.0);                // stop
  };
  const BaseModelConfig modelled = water2();
  BaseModelConfig commanded = water2();
  commanded.water2.bridge_response = ehc_realman::Water2ResponseParams::commandedVelocity();
  const OdometryErrors m = odometryErrors(modelled, 7.0, profile);
  const OdometryErrors c = odometryErrors(commanded, 7.0, profile);
  EXPECT_EQ(m.statuses, 13);
  EXPECT_EQ(c.statuses, m.statuses);
  // With the model the bridge knows what the wheels do (no noise, status = true pose): what is
  // left is the wheel deadband the bridge does not model (a stopping wheel is zeroed below
  // 5 mm/s: < 5 mm/s x 0.1 s lag = 0.5 mm) and rounding. Bound 2 mm, both for the error and
  // for the jump at a status.
  EXPECT_LT(m.worst_error, 0.002);
  EXPECT_LT(m.worst_jump, 0.002);
  EXPECT_LT(m.worst_heading, 0.002);
  // The commanded twist, as before: several cm (start from rest right after a status: 0.5 s of
  // 0.4 m/s dead-reckoned vs the ramp behind latency and lag).
  EXPECT_GT(c.worst_error, 0.05);
  EXPECT_GT(c.worst_jump, 0.05);
  std::printf("[ odometry ] worst |odom - truth| / jump at a status: model %.4f / %.4f m, commanded twist %.4f / %.4f m\n",
              m.worst_error, m.worst_jump, c.worst_error, c.worst_jump);
}

TEST(Water2Base, IdealOdometryIsTheTruePose) {
  KinematicFakeRobot a(robot(), ActuationNoise{}, 5), b(robot(), ActuationNoise{}, 5, BaseModelConfig{});
  for (int k = 0; k < 200; ++k) {
    const Eigen::VectorXd c = baseCommand(a.nDof(), 0.3, -0.2);
    a.step(c, kDt);
    b.step(c, kDt);
    EXPECT_EQ(a.odometryPose(), a.basePose());
    EXPECT_EQ(a.basePose(), b.basePose());
    EXPECT_EQ(a.odometryTwist()[0], a.executedVelocity()[0]);
  }
  EXPECT_EQ(a.water2(), nullptr);
}

TEST(Water2Base, HolonomicBaseIsRejected) {
  auto rc = robot();
  rc.base_type = ehc_control::BaseType::Holonomic;
  EXPECT_THROW(KinematicFakeRobot(rc, off(), 1, water2()), std::invalid_argument);
}

TEST(Water2Base, ConfigFilesDocumentTheDefaultsAndUnknownKeysFail) {
  const ehc_sim::FakeRobotConfig k =
      ehc_sim::loadFakeRobotConfigFile(std::string(EHC_CONFIG_DIR) + "/sim/kinematic_sim.yaml");
  EXPECT_EQ(k.base_model.type, BaseModelType::Ideal);
  const Water2BaseParams d;
  for (const Water2BaseParams& f : {k.base_model.water2}) {
    EXPECT_EQ(f.max_linear_velocity, d.max_linear_velocity);
    EXPECT_EQ(f.max_angular_velocity, d.max_angular_velocity);
    EXPECT_EQ(f.resend_rate, d.resend_rate);
    EXPECT_EQ(f.bridge_command_timeout, d.bridge_command_timeout);
    EXPECT_EQ(f.status_period, d.status_period);
    EXPECT_EQ(f.max_extrapolation, d.max_extrapolation);
    EXPECT_EQ(f.response.command_lifetime, d.response.command_lifetime);
    EXPECT_EQ(f.response.command_latency, d.response.command_latency);
    EXPECT_EQ(f.status_latency, d.status_latency);
    EXPECT_EQ(f.response.linear_acceleration, d.response.linear_acceleration);
    EXPECT_EQ(f.response.angular_acceleration, d.response.angular_acceleration);
    EXPECT_EQ(f.response.time_constant, d.response.time_constant);
    EXPECT_EQ(f.response.linear_gain, d.response.linear_gain);
    EXPECT_EQ(f.response.angular_gain, d.response.angular_gain);
    EXPECT_EQ(f.localisation_position_sigma, d.localisation_position_sigma);
    EXPECT_EQ(f.localisation_heading_sigma, d.localisation_heading_sigma);
    EXPECT_EQ(f.localisation_correlation_time, d.localisation_correlation_time);
  }
  const std::string robot_file = std::string(EHC_CONFIG_DIR) + "/robots/realman_rm65_water2/robot.yaml";
  auto load = [&](const std::string& extra) {
    const auto root = ehc_common::ConfigNode::loadString("sim:\n  robot: " + robot_file + "\n" + extra,
                                                          "test.yaml", "FakeRobotConfig");
    return ehc_sim::loadFakeRobotConfig(root.child("sim"));
  };
  const auto w = load("  base_model: water2\n  water2: {command_latency: 0.1}\n");
  EXPECT_EQ(w.base_model.type, BaseModelType::Water2);
  EXPECT_EQ(w.base_model.water2.response.command_latency, 0.1);
  EXPECT_EQ(w.base_model.water2.status_period, 0.5);
  try {
    load("  base_model: water2\n  water2: {comand_latency: 0.1}\n");
    FAIL() << "an unknown water2 key must fail";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("comand_latency"), std::string::npos) << e.what();
  }
  // The modelled bridge's belief of the response: unset = the base's; set = the base's values
  // with the keys given changed.
  EXPECT_FALSE(w.base_model.water2.bridge_response);
  const auto b = load("  base_model: water2\n  water2: {time_constant: 0.2, bridge_response: {linear_gain: 1.0}}\n");
  ASSERT_TRUE(b.base_model.water2.bridge_response);
  EXPECT_EQ(b.base_model.water2.bridge_response->linear_gain, 1.0);
  EXPECT_EQ(b.base_model.water2.bridge_response->time_constant, 0.2);
  EXPECT_EQ(b.base_model.water2.response.linear_gain, 0.95);
  EXPECT_THROW(load("  base_model: water2\n  water2: {bridge_response: {linear_gian: 1.0}}\n"), std::invalid_argument);
  EXPECT_THROW(load("  base_model: water3\n"), std::invalid_argument);
  EXPECT_THROW(load("  base_model: water2\n  water2: {status_period: 1.5}\n"), std::invalid_argument);
}
