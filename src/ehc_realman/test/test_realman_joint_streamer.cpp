// JointPositionStreamer and the rm_arm_adapter configuration: every produced frame respects the
// per-frame step bound, the speed limits and the joint limits; timeouts hold then stop; the
// emergency stop latches; bad inputs are rejected. Time is simulated (no sleeps).

#include "ehc_realman/realman_adapter_config.h"
#include "ehc_realman/realman_joint_streamer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <random>

using ehc_realman::ArmJointLimits;
using ehc_realman::JointFrame;
using ehc_realman::JointPositionStreamer;
using ehc_realman::JointStreamerConfig;
using ehc_realman::StreamPhase;

namespace {
const std::vector<std::string> kNames = {"joint1", "joint2", "joint3", "joint4", "joint5", "joint6"};
constexpr double kDeg = M_PI / 180.0;

ArmJointLimits rm65Limits() {
  ArmJointLimits l;
  l.names = kNames;
  l.lower.resize(6);
  l.upper.resize(6);
  l.velocity.resize(6);
  l.upper << 178, 130, 135, 178, 128, 360;
  l.upper *= kDeg;
  l.lower = -l.upper;
  l.velocity << 3.14, 3.14, 3.92, 3.92, 3.92, 3.92;
  return l;
}

std::vector<double> vec(const Eigen::VectorXd& v) { return {v.data(), v.data() + v.size()}; }

/// Drives a streamer with a perfectly tracking arm (measured = last frame) and checks every
/// frame against the bounds. Returns the frames.
struct Harness {
  JointStreamerConfig config;
  ArmJointLimits limits = rm65Limits();
  std::unique_ptr<JointPositionStreamer> streamer;
  Eigen::VectorXd measured = Eigen::VectorXd::Zero(6);
  Eigen::VectorXd previous;
  double t = 100.0;
  int frames = 0;

  void make() { streamer = std::make_unique<JointPositionStreamer>(config, limits); }

  std::optional<JointFrame> tick(const std::optional<Eigen::VectorXd>& command, bool track = true) {
    streamer->setMeasured(kNames, vec(measured), t);
    if (command) streamer->setVelocityCommand(kNames, vec(*command), t);
    auto f = streamer->step(t);
    t += 1.0 / config.rate_hz;
    if (f) {
      ++frames;
      EXPECT_TRUE(f->position.allFinite());
      if (previous.size()) {
        const Eigen::VectorXd step = (f->position - previous).cwiseAbs();
        for (int i = 0; i < 6; ++i) {
          EXPECT_LE(step[i], 10.0 * kDeg + 1e-12) << "joint " << i;
          EXPECT_LE(step[i], streamer->speedLimit()[i] / config.rate_hz + 1e-12) << "joint " << i;
        }
      }
      for (int i = 0; i < 6; ++i) {
        EXPECT_GE(f->position[i], std::min(streamer->lowerLimit()[i], previous.size() ? previous[i] : measured[i]) - 1e-12);
        EXPECT_LE(f->position[i], std::max(streamer->upperLimit()[i], previous.size() ? previous[i] : measured[i]) + 1e-12);
      }
      previous = f->position;
      if (track) measured = f->position;
    } else {
      previous.resize(0);
    }
    return f;
  }
};
}  // namespace

TEST(JointStreamerConfig, RejectsOutOfRangeValues) {
  JointStreamerConfig c;
  EXPECT_NO_THROW(c.validate());
  c.max_step_deg = 12.0;  // the driver ignores frames > 10 deg apart
  EXPECT_THROW(c.validate(), std::invalid_argument);
  c = JointStreamerConfig();
  c.rate_hz = 0.0;
  EXPECT_THROW(c.validate(), std::invalid_argument);
  c = JointStreamerConfig();
  c.speed_scale = 1.5;
  EXPECT_THROW(c.validate(), std::invalid_argument);
  try {
    c.validate();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("[JointStreamerConfig]"), std::string::npos);
  }
}

TEST(JointPositionStreamer, IdleUntilCommandAndStateAreFresh) {
  Harness h;
  h.make();
  EXPECT_FALSE(h.streamer->step(h.t));  // nothing yet
  h.streamer->setVelocityCommand(kNames, std::vector<double>(6, 0.1), h.t);
  EXPECT_FALSE(h.streamer->step(h.t)) << "no measured state: must not stream";
  h.streamer->setMeasured(kNames, vec(h.measured), h.t);
  auto f = h.streamer->step(h.t);
  ASSERT_TRUE(f);
  EXPECT_EQ(f->phase, StreamPhase::Streaming);
  // First frame starts from the measured position: one period of motion.
  EXPECT_NEAR(f->position[0], 0.1 / 100.0, 1e-12);
}

TEST(JointPositionStreamer, IntegratesVelocityExactly) {
  Harness h;
  h.make();
  Eigen::VectorXd v(6);
  v << 0.2, -0.1, 0.3, 0.0, 0.05, -0.4;
  for (int k = 0; k < 100; ++k) ASSERT_TRUE(h.tick(v));
  EXPECT_TRUE(h.measured.isApprox(v * 1.0, 1e-9)) << h.measured.transpose();
  EXPECT_EQ(h.streamer->counters().speed_clamped, 0u);
}

TEST(JointPositionStreamer, ScalesFastCommandsUniformlyToTheSpeedLimits) {
  Harness h;
  h.make();
  Eigen::VectorXd v(6);
  v << 10.0, 5.0, 0.0, 0.0, 0.0, 0.0;  // joint1 limit: min(3.14, pi) = 3.14 rad/s
  const auto f = h.tick(v);
  ASSERT_TRUE(f);
  EXPECT_TRUE(f->speed_clamped);
  EXPECT_NEAR(f->position[0], 3.14 / 100.0, 1e-12);
  EXPECT_NEAR(f->position[1], 3.14 / 200.0, 1e-12) << "direction kept";
  for (int k = 0; k < 50; ++k) h.tick(v);
  EXPECT_EQ(h.streamer->counters().speed_clamped, 51u);
}

TEST(JointPositionStreamer, DriverSpeedBoundCapsFasterJoints) {
  Harness h;
  h.make();
  // joint3 allows 3.92 rad/s in robot.yaml but the driver accepts at most 180 deg/s.
  EXPECT_NEAR(h.streamer->speedLimit()[2], M_PI, 1e-12);
  EXPECT_NEAR(h.streamer->speedLimit()[0], 3.14, 1e-12);
}

TEST(JointPositionStreamer, LowRateNeverExceedsTenDegreesPerFrame) {
  Harness h;
  h.config.rate_hz = 5.0;  // v_max * dt = 36 deg > 10 deg: the step bound must win
  h.make();
  Eigen::VectorXd v = Eigen::VectorXd::Constant(6, 3.0);
  for (int k = 0; k < 20; ++k) {
    const auto f = h.tick(v);
    ASSERT_TRUE(f);
  }
  EXPECT_NEAR(h.streamer->stepLimit()[0], 10.0 * kDeg, 1e-12);
  EXPECT_GT(h.streamer->counters().tracking_clamped + h.streamer->counters().step_clamped, 0u);
}

TEST(JointPositionStreamer, StopsAtJointLimitsAndReports) {
  Harness h;
  h.config.limit_margin = 0.01;
  h.make();
  h.measured[1] = h.streamer->upperLimit()[1] - 0.05;
  Eigen::VectorXd v = Eigen::VectorXd::Zero(6);
  v[1] = 2.0;
  bool clamped = false;
  for (int k = 0; k < 200; ++k) clamped |= h.tick(v)->limit_clamped;
  EXPECT_TRUE(clamped);
  EXPECT_NEAR(h.measured[1], h.streamer->upperLimit()[1], 1e-12);
  EXPECT_LT(h.measured[1], rm65Limits().upper[1]);
  EXPECT_GT(h.streamer->counters().limit_clamped, 0u);
}

TEST(JointPositionStreamer, StartingOutsideTheLimitsNeverMovesFurtherOut) {
  Harness h;
  h.make();
  h.measured[4] = h.streamer->upperLimit()[4] + 0.05;  // e.g. limits tightened in robot.yaml
  Eigen::VectorXd out = Eigen::VectorXd::Zero(6);
  out[4] = 1.0;
  for (int k = 0; k < 50; ++k) {
    const auto f = h.tick(out);
    ASSERT_TRUE(f);
    EXPECT_LE(f->position[4], h.streamer->upperLimit()[4] + 0.05 + 1e-12);
  }
  Eigen::VectorXd in = -out;
  for (int k = 0; k < 100; ++k) h.tick(in);
  EXPECT_LT(h.measured[4], h.streamer->upperLimit()[4]) << "moving back inside is allowed";
}

TEST(JointPositionStreamer, LaggingArmDoesNotWindUp) {
  Harness h;
  h.make();
  Eigen::VectorXd v = Eigen::VectorXd::Zero(6);
  v[0] = 1.0;
  for (int k = 0; k < 200; ++k) h.tick(v, /*track=*/false);  // the arm does not move
  EXPECT_NEAR(h.previous[0], 0.2, 1e-12) << "commanded position stays within max_tracking_error";
  EXPECT_GT(h.streamer->counters().tracking_clamped, 0u);
}

// A 0.1 s glitch of +1 rad on joint1's measured state while commanding
// -0.2 rad/s drove the set-point 0.28 rad the other way (the tracking clamp chased the glitch).
TEST(JointPositionStreamer, MeasuredStateGlitchNeverMovesTheSetPointAgainstTheCommand) {
  Harness h;
  h.make();
  Eigen::VectorXd v = Eigen::VectorXd::Zero(6);
  v[0] = -0.2;
  for (int k = 0; k < 20; ++k) h.tick(v);  // streaming, tracked perfectly
  const double before = h.previous[0];
  double highest = before;
  const Eigen::VectorXd true_position = h.measured;
  for (int k = 0; k < 10; ++k) {  // 0.1 s at 100 Hz: joint1 reads +1 rad off
    h.measured = true_position;
    h.measured[0] += 1.0;
    const auto f = h.tick(v, /*track=*/false);
    ASSERT_TRUE(f);
    highest = std::max(highest, f->position[0]);
    EXPECT_LE(f->position[0], before + 1e-12) << "set-point moved against the command";
    for (int i = 1; i < 6; ++i) EXPECT_NEAR(f->position[i], true_position[i], 1e-12);
  }
  EXPECT_LE(highest - before, 1e-12);
  h.measured = h.previous;  // the glitch ends; the arm is where it was commanded
  for (int k = 0; k < 50; ++k) h.tick(v);
  EXPECT_LT(h.previous[0], before - 0.09) << "commanded motion resumes after the glitch";
}

// The measured state only bounds the set-point's distance: a step toward the measured position
// is always allowed, a step away from it stops at max_tracking_error.
TEST(JointPositionStreamer, SetPointFarFromMeasuredMayOnlyApproachIt) {
  Harness h;
  h.make();
  Eigen::VectorXd v = Eigen::VectorXd::Zero(6);
  v[1] = 0.5;
  for (int k = 0; k < 5; ++k) h.tick(v);
  const double start = h.previous[1];
  h.measured[1] = start + 0.6;  // measured jumps far ahead of the command direction
  for (int k = 0; k < 10; ++k) {
    const auto f = h.tick(v, /*track=*/false);
    ASSERT_TRUE(f);
  }
  EXPECT_NEAR(h.previous[1], start + 10 * 0.5 / h.config.rate_hz, 1e-9)
      << "moving toward the measured position is unrestricted";
  v[1] = -0.5;
  const double held = h.previous[1];
  for (int k = 0; k < 10; ++k) h.tick(v, /*track=*/false);
  EXPECT_NEAR(h.previous[1], held, 1e-12) << "moving away is held (error > max_tracking_error)";
}

TEST(JointPositionStreamer, CommandTimeoutHoldsThenStops) {
  Harness h;
  h.make();
  Eigen::VectorXd v = Eigen::VectorXd::Constant(6, 0.2);
  const double t_start = h.t;
  for (int k = 0; k < 50; ++k) h.tick(v);
  const double t_last_cmd = h.t - 0.01;
  const Eigen::VectorXd held = h.measured;
  int holding = 0, streaming_after = 0;
  std::optional<double> stop_time;
  while (h.t < t_last_cmd + 2.0) {
    const double t = h.t;
    const auto f = h.tick(std::nullopt);
    if (!f) {
      if (!stop_time) stop_time = t;
      continue;
    }
    EXPECT_FALSE(stop_time) << "no frame after the stream stopped";
    if (f->phase == StreamPhase::Holding) {
      ++holding;
      EXPECT_TRUE(f->position.isApprox(h.measured));
    } else {
      ++streaming_after;
      EXPECT_LE(t - t_last_cmd, 0.2 + 1e-9);
    }
  }
  (void)t_start;
  (void)held;
  ASSERT_TRUE(stop_time);
  EXPECT_NEAR(*stop_time - t_last_cmd, 0.2 + 0.5, 0.03);
  EXPECT_NEAR(holding, 50, 3);  // 0.5 s at 100 Hz
  EXPECT_EQ(h.streamer->counters().timeouts, 1u);
  EXPECT_EQ(h.streamer->phase(), StreamPhase::Idle);
  // A new command restarts from the measured position.
  h.measured[0] += 0.3;  // someone moved the arm meanwhile
  const auto f = h.tick(v);
  ASSERT_TRUE(f);
  EXPECT_NEAR(f->position[0], h.measured[0], 0.2 / 100.0 + 1e-9);
}

TEST(JointPositionStreamer, StaleJointStateHolds) {
  Harness h;
  h.make();
  Eigen::VectorXd v = Eigen::VectorXd::Constant(6, 0.2);
  for (int k = 0; k < 10; ++k) h.tick(v);
  // Commands keep coming but /joint_states stop.
  const double t_last_state = h.t - 0.01;
  std::optional<double> first_hold;
  for (int k = 0; k < 40; ++k) {
    h.streamer->setVelocityCommand(kNames, vec(v), h.t);
    auto f = h.streamer->step(h.t);
    if (f && f->phase == StreamPhase::Holding && !first_hold) first_hold = h.t;
    if (f && !first_hold) {
      EXPECT_LE(h.t - t_last_state, 0.2 + 1e-9) << "streams only while fresh";
    }
    h.t += 0.01;
  }
  ASSERT_TRUE(first_hold);
  EXPECT_NEAR(*first_hold - t_last_state, 0.2, 0.011);
}

TEST(JointPositionStreamer, EmergencyStopLatchesUntilReset) {
  Harness h;
  h.make();
  Eigen::VectorXd v = Eigen::VectorXd::Constant(6, 0.2);
  for (int k = 0; k < 10; ++k) ASSERT_TRUE(h.tick(v));
  h.streamer->emergencyStop();
  for (int k = 0; k < 50; ++k) EXPECT_FALSE(h.tick(v)) << "no frame while latched";
  EXPECT_TRUE(h.streamer->emergencyStopped());
  h.streamer->resetEmergencyStop();
  EXPECT_FALSE(h.streamer->step(h.t)) << "a command from before the reset must not restart";
  EXPECT_TRUE(h.tick(v)) << "a new command restarts";
}

TEST(JointPositionStreamer, RejectsBadCommandsAndStates) {
  Harness h;
  h.make();
  const double t = h.t;
  auto bad_cmd = [&](const std::vector<std::string>& n, const std::vector<double>& v) {
    EXPECT_THROW(h.streamer->setVelocityCommand(n, v, t), std::invalid_argument);
  };
  bad_cmd(kNames, {0.1, 0.1});
  bad_cmd({"joint1", "joint2", "joint3", "joint4", "joint5", "jointX"}, std::vector<double>(6, 0.1));
  bad_cmd({"joint1", "joint1", "joint3", "joint4", "joint5", "joint6"}, std::vector<double>(6, 0.1));
  bad_cmd(kNames, {0.1, NAN, 0.1, 0.1, 0.1, 0.1});
  bad_cmd(kNames, {0.1, INFINITY, 0.1, 0.1, 0.1, 0.1});
  EXPECT_EQ(h.streamer->counters().rejected_commands, 5u);
  EXPECT_THROW(h.streamer->setMeasured({"joint1"}, {0.0}, t), std::invalid_argument);
  EXPECT_THROW(h.streamer->setMeasured(kNames, {0, 0, 0, NAN, 0, 0}, t), std::invalid_argument);
  try {
    h.streamer->setMeasured({"joint1"}, {0.0}, t);
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("[JointPositionStreamer]"), std::string::npos);
  }
  EXPECT_FALSE(h.streamer->step(t)) << "rejected inputs never start the stream";
}

TEST(JointPositionStreamer, AcceptsAnyNameOrderAndExtraStateJoints) {
  Harness h;
  h.make();
  h.streamer->setMeasured({"gripper", "joint6", "joint5", "joint4", "joint3", "joint2", "joint1"},
                          {0.5, 6, 5, 4, 3, 2, 1}, h.t);
  h.streamer->setVelocityCommand({"joint6", "joint5", "joint4", "joint3", "joint2", "joint1"},
                                 {0, 0, 0, 0, 0, 1.0}, h.t);
  const auto f = h.streamer->step(h.t);
  ASSERT_TRUE(f);
  EXPECT_NEAR(f->position[0], 1.0 + 0.01, 1e-12);
  EXPECT_NEAR(f->position[5], 6.0, 1e-12);
  // Empty names: command order.
  h.streamer->setVelocityCommand({}, {0, 0, 0, 0, 0, 1.0}, h.t);
  const auto g = h.streamer->step(h.t + 0.01);
  ASSERT_TRUE(g);
  EXPECT_NEAR(g->position[5], 6.0 + 0.01, 1e-12);
}

TEST(JointPositionStreamer, RandomCommandsAlwaysRespectEveryBound) {
  Harness h;
  h.config.limit_margin = 0.02;
  h.make();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-8.0, 8.0);
  std::bernoulli_distribution drop(0.02), lag(0.3);
  for (int k = 0; k < 5000; ++k) {
    Eigen::VectorXd v(6);
    for (int i = 0; i < 6; ++i) v[i] = u(rng);
    h.tick(drop(rng) ? std::nullopt : std::optional<Eigen::VectorXd>(v), !lag(rng));
  }
  EXPECT_GT(h.frames, 4000);
}

TEST(Gripper, CommandsAndWidthsMapToDriverRequests) {
  ehc_realman::GripperConfig g;
  auto open = ehc_realman::gripperRequestFromCommand(" Open ", g);
  EXPECT_EQ(open.kind, ehc_realman::GripperRequest::Kind::Set);
  EXPECT_EQ(open.position, 1000);
  EXPECT_EQ(ehc_realman::gripperRequestFromCommand("close", g).position, 1);
  const auto pick = ehc_realman::gripperRequestFromCommand("pick", g);
  EXPECT_EQ(pick.kind, ehc_realman::GripperRequest::Kind::Pick);
  EXPECT_EQ(pick.speed, 500);
  EXPECT_EQ(pick.force, 500);
  EXPECT_THROW(ehc_realman::gripperRequestFromCommand("grab", g), std::invalid_argument);
  EXPECT_EQ(ehc_realman::gripperRequestFromWidth(0.035, g).position, 500);
  EXPECT_EQ(ehc_realman::gripperRequestFromWidth(0.5, g).position, 1000);
  EXPECT_EQ(ehc_realman::gripperRequestFromWidth(-0.1, g).position, 1);
  EXPECT_THROW(ehc_realman::gripperRequestFromWidth(NAN, g), std::invalid_argument);
}

TEST(RmArmAdapterConfig, LoadsTheShippedFile) {
  const auto c = ehc_realman::loadRmArmAdapterConfig(EHC_CONFIG_DIR "/realman/rm_arm_adapter.yaml");
  EXPECT_EQ(c.limits.names, kNames);
  EXPECT_DOUBLE_EQ(c.stream.rate_hz, 100.0);
  EXPECT_DOUBLE_EQ(c.stream.command_timeout, 0.2);
  EXPECT_NEAR(c.limits.velocity[0], 3.14, 1e-12);
  EXPECT_NE(c.summary().find("rm_arm_adapter"), std::string::npos);
}

TEST(RmArmAdapterConfig, ErrorsNameTheFileAndField) {
  const std::string path = ::testing::TempDir() + "/bad_rm_arm_adapter.yaml";
  {
    std::ofstream f(path);
    f << "rm_arm_adapter:\n  robot: " EHC_CONFIG_DIR "/robots/realman_rm65_water2/robot.yaml\n"
      << "  stream:\n    rate_hz: fast\n";
  }
  try {
    ehc_realman::loadRmArmAdapterConfig(path);
    FAIL() << "expected an exception";
  } catch (const std::invalid_argument& e) {
    const std::string w = e.what();
    EXPECT_NE(w.find("bad_rm_arm_adapter.yaml"), std::string::npos) << w;
    EXPECT_NE(w.find("rate_hz"), std::string::npos) << w;
  }
  {
    std::ofstream f(path);
    f << "rm_arm_adapter:\n  robot: " EHC_CONFIG_DIR "/robots/realman_rm65_water2/robot.yaml\n"
      << "  stream:\n    max_step_deg: 15\n";
  }
  EXPECT_THROW(ehc_realman::loadRmArmAdapterConfig(path), std::invalid_argument);
}

// The first-run safety settings of REALMAN.md, misspelled, must not run at full limits.
TEST(RmArmAdapterConfig, MisspelledKeyIsAStartUpError) {
  const std::string path = ::testing::TempDir() + "/typo_rm_arm_adapter.yaml";
  {
    std::ofstream f(path);
    f << "rm_arm_adapter:\n  robot: " EHC_CONFIG_DIR "/robots/realman_rm65_water2/robot.yaml\n"
      << "  stream:\n    speed_scal: 0.2\n";
  }
  try {
    ehc_realman::loadRmArmAdapterConfig(path);
    FAIL() << "a misspelled key was silently ignored";
  } catch (const std::invalid_argument& e) {
    const std::string w = e.what();
    EXPECT_NE(w.find("typo_rm_arm_adapter.yaml"), std::string::npos) << w;
    EXPECT_NE(w.find("unknown field 'rm_arm_adapter.stream.speed_scal'"), std::string::npos) << w;
    EXPECT_NE(w.find("did you mean 'rm_arm_adapter.stream.speed_scale'"), std::string::npos) << w;
  }
}
