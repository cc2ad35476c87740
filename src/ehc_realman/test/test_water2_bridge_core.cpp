// Water2 bridge core: watchdog and odometry logic on simulated time, then the whole bridge
// against FakeWater2Server on 127.0.0.1 (rate, clamping, stop after timeout, odometry, server
// killed mid-run => zero motion + reconnect, malformed replies). Waits are bounded and
// assertions are about properties of every request, with generous timing tolerances.

#include "ehc_realman/water2_base_bridge.h"
#include "water2_fake_server.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <fstream>
#include <functional>
#include <thread>

using namespace ehc_realman;
using ehc_realman_test::FakeWater2Server;

namespace {
using ehc_realman_test::waitFor;

Water2BridgeConfig loopbackConfig(int port) {
  Water2BridgeConfig c;
  c.host = "127.0.0.1";
  c.port = port;
  c.reply_timeout = 1.0;
  c.backoff_initial = 0.1;
  c.backoff_max = 0.4;
  return c;
}

/// Runs spinOnce in a thread, as the node does.
class BridgeRunner {
 public:
  explicit BridgeRunner(const Water2BridgeConfig& c) : bridge(c) {
    thread_ = std::thread([this] {
      while (running_) bridge.spinOnce(0.02);
    });
  }
  ~BridgeRunner() {
    running_ = false;
    thread_.join();
  }
  Water2BaseBridge bridge;

 private:
  std::atomic<bool> running_{true};
  std::thread thread_;
};

/// Publishes a command at 50 Hz for `seconds` (the controller's /cmd_vel).
void drive(Water2BaseBridge& b, double v, double w, double seconds) {
  const double end = FakeWater2Server::now() + seconds;
  while (FakeWater2Server::now() < end) {
    b.setCommand(v, w);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}
}  // namespace

// ------------------------------------------------------------------ watchdog (simulated time)
TEST(BaseCommandWatchdog, ClampsUniformlyKeepingCurvature) {
  BaseCommandWatchdog w(0.5, 1.0, 0.2, 0.05, 1.0);
  EXPECT_TRUE(w.setCommand(1.0, 0.5, 0.0));
  auto t = w.due(0.0);
  ASSERT_TRUE(t);
  EXPECT_DOUBLE_EQ(t->linear, 0.5);
  EXPECT_DOUBLE_EQ(t->angular, 0.25);
  EXPECT_TRUE(w.setCommand(-0.2, -4.0, 0.1));
  t = w.due(0.1);
  ASSERT_TRUE(t);
  EXPECT_DOUBLE_EQ(t->angular, -1.0);
  EXPECT_DOUBLE_EQ(t->linear, -0.05);
  EXPECT_FALSE(w.setCommand(0.3, 0.3, 0.11));
  EXPECT_THROW(w.setCommand(NAN, 0.0, 0.12), std::invalid_argument);
}

TEST(BaseCommandWatchdog, ResendsWhileFreshThenZeroAtOnceThenQuiet) {
  BaseCommandWatchdog w(0.5, 1.0, 0.15, 0.05, 1.0);
  int sent = 0;
  double first_zero = -1.0, last_send = -1.0;
  for (double t = 0.0; t < 3.0; t += 0.001) {
    if (t < 1.0) w.setCommand(0.3, 0.0, t);  // commands until t = 1
    if (auto tw = w.due(t)) {
      ++sent;
      last_send = t;
      if (t < 1.0) {
        EXPECT_DOUBLE_EQ(tw->linear, 0.3);
      }
      if (tw->linear == 0.0 && first_zero < 0.0) first_zero = t;
      if (t > 1.0 + 0.15 + 1e-9) {
        EXPECT_EQ(tw->linear, 0.0) << "t=" << t;
      }
    }
  }
  EXPECT_NEAR(first_zero, 1.0 + 0.15, 0.002) << "zero sent as soon as commands time out";
  EXPECT_NEAR(last_send, 1.0 + 0.15 + 1.0, 0.06) << "quiet after stop_repeat_duration";
  EXPECT_NEAR(sent, 20 + 3 + 20, 3);  // 20 Hz while fresh, zero at once, 20 Hz of zeros
}

TEST(BaseCommandWatchdog, RequestZeroOverridesAFreshCommand) {
  BaseCommandWatchdog w(0.5, 1.0, 0.2, 0.05, 1.0);
  w.setCommand(0.4, 0.0, 0.0);
  ASSERT_TRUE(w.due(0.0));
  w.requestZero();
  EXPECT_DOUBLE_EQ(w.timeUntilDue(0.01), 0.0);
  auto t = w.due(0.01);
  ASSERT_TRUE(t);
  EXPECT_EQ(t->linear, 0.0);
}

// ------------------------------------------------------------------ odometry (simulated time)
TEST(OdometryEstimator, DeadReckonsBetweenStatusRepliesAndGoesStale) {
  OdometryEstimator e(1.5, 0.6);
  EXPECT_FALSE(e.estimate(0.0)) << "nothing before the first status";
  e.onStatus({1.0, 2.0, 0.0}, 10.0);
  e.onTwistSent({0.5, 0.0}, 10.0);
  auto o = e.estimate(10.2);
  ASSERT_TRUE(o);
  EXPECT_NEAR(o->x, 1.1, 1e-9);
  EXPECT_NEAR(o->y, 2.0, 1e-9);
  EXPECT_DOUBLE_EQ(o->linear, 0.5);
  // The command lapses after 0.5 s on the base; dead reckoning is capped anyway.
  o = e.estimate(11.0);
  ASSERT_TRUE(o);
  EXPECT_NEAR(o->x, 1.25, 1e-9);
  EXPECT_DOUBLE_EQ(o->linear, 0.0);
  EXPECT_FALSE(e.estimate(11.6)) << "stale status is never reported";
  // Turning: quarter circle.
  e.onStatus({0.0, 0.0, 0.0}, 20.0);
  for (int k = 0; k < 10; ++k) e.onTwistSent({0.5, 1.0}, 20.0 + 0.05 * k);
  o = e.estimate(20.5);
  ASSERT_TRUE(o);
  EXPECT_NEAR(o->theta, 0.5, 1e-9);
  EXPECT_NEAR(o->x, 0.5 * std::sin(0.5), 1e-9);
  EXPECT_NEAR(o->y, 0.5 * (1 - std::cos(0.5)), 1e-9);
  e.onStatus({3.0, 0.0, 0.1}, 20.6);
  EXPECT_NEAR(e.estimate(20.6)->x, 3.0, 1e-12) << "a status resets the estimate";
}

// ------------------------------------------------------------------ bridge on loopback
TEST(Water2BaseBridge, StreamsClampedCommandsAtRateAndStopsAfterTimeout) {
  FakeWater2Server server;
  server.start();
  BridgeRunner run(loopbackConfig(server.port()));
  ASSERT_TRUE(waitFor([&] { return run.bridge.odometry().has_value(); }, 5.0))
      << run.bridge.status().message;
  EXPECT_EQ(run.bridge.status().level, Water2BridgeStatus::Level::Ok);
  server.clearRequests();

  const double t0 = FakeWater2Server::now();
  drive(run.bridge, 2.0, 1.0, 2.0);  // above the bounds: s = min(0.25, 1.0) => (0.5, 0.25)
  const double t_last_cmd = FakeWater2Server::now();
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));

  const auto reqs = server.requests();
  int moving = 0, status = 0;
  double first_zero_after = -1.0, last_moving = 0.0;
  for (const auto& r : reqs) {
    if (r.text == "/api/robot_status") {
      ++status;
      continue;
    }
    ASSERT_TRUE(r.joy) << "unexpected request: " << r.text;
    EXPECT_LE(std::abs(r.linear), 0.5 + 1e-9);
    EXPECT_LE(std::abs(r.angular), 1.0 + 1e-9);
    if (r.linear != 0.0) {
      ++moving;
      last_moving = r.time;
      EXPECT_NEAR(r.linear, 0.5, 1e-4);
      EXPECT_NEAR(r.angular, 0.25, 1e-4);
    } else if (r.time > t_last_cmd - 0.05 && first_zero_after < 0.0) {
      first_zero_after = r.time;
    }
  }
  const double rate = moving / (last_moving - t0);
  EXPECT_GE(rate, 10.0) << moving << " joy_control requests";  // configured 20 Hz
  EXPECT_LE(rate, 25.0);
  EXPECT_LE(last_moving - t_last_cmd, 0.15 + 0.2) << "no motion request after the timeout";
  ASSERT_GT(first_zero_after, 0.0) << "a zero command must follow";
  EXPECT_LE(first_zero_after - t_last_cmd, 0.2 + 0.2);
  EXPECT_GE(status, 4) << "robot_status polled about every 0.5 s";
  double x, y, th;
  server.pose(x, y, th);
  EXPECT_GT(x * x + y * y, 0.5) << "the fake base moved";
  const auto o = run.bridge.odometry();
  ASSERT_TRUE(o);
  EXPECT_NEAR(o->x, x, 0.05);
  EXPECT_NEAR(o->y, y, 0.05);
  EXPECT_GT(run.bridge.status().clamped_commands, 50u);
}

TEST(Water2BaseBridge, ServerKilledMidRunStopsMotionAndReconnects) {
  FakeWater2Server server;
  server.start();
  const int port = server.port();
  BridgeRunner run(loopbackConfig(port));
  ASSERT_TRUE(waitFor([&] { return run.bridge.odometry().has_value(); }, 5.0));

  std::atomic<bool> driving{true};
  std::thread controller([&] {
    while (driving) {
      run.bridge.setCommand(0.3, 0.0);
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  server.stop();  // killed mid-run while the controller keeps commanding
  EXPECT_TRUE(waitFor([&] { return !run.bridge.status().connected; }, 2.0));
  EXPECT_EQ(run.bridge.status().level, Water2BridgeStatus::Level::Error);
  EXPECT_TRUE(waitFor([&] { return !run.bridge.odometry().has_value(); }, 3.0))
      << "stale odometry must be withheld";
  std::this_thread::sleep_for(std::chrono::milliseconds(500));  // a few failed attempts
  EXPECT_GT(run.bridge.status().failed_connects, 0u);

  server.start();  // same port
  ASSERT_EQ(server.port(), port);
  ASSERT_TRUE(waitFor([&] { return run.bridge.odometry().has_value(); }, 5.0))
      << run.bridge.status().message;
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  driving = false;
  controller.join();

  const auto s = run.bridge.status();
  EXPECT_TRUE(s.connected);
  EXPECT_GE(s.connects, 2u);
  EXPECT_GE(s.connection_losses, 1u);
  // The first motion request after the reconnection is a zero.
  const auto reqs = server.requests();
  bool seen = false;
  for (const auto& r : reqs) {
    if (r.connection != 2 || !r.joy) continue;
    if (!seen) {
      EXPECT_EQ(r.linear, 0.0) << "first command after reconnect: " << r.text;
    }
    seen = true;
  }
  EXPECT_TRUE(seen);
}

TEST(Water2BaseBridge, SurvivesMalformedRepliesAndRecovers) {
  FakeWater2Server server;
  server.start();
  BridgeRunner run(loopbackConfig(server.port()));
  ASSERT_TRUE(waitFor([&] { return run.bridge.odometry().has_value(); }, 5.0));
  using Mode = FakeWater2Server::ReplyMode;
  for (Mode m : {Mode::Garbage, Mode::BadJson, Mode::MissingType, Mode::BadPose, Mode::Oversized,
                 Mode::ErrorStatus, Mode::Truncated, Mode::Silent}) {
    SCOPED_TRACE(static_cast<int>(m));
    const auto before = run.bridge.status();
    server.setReplyMode(m);
    drive(run.bridge, 0.1, 0.0, 1.2);
    const auto during = run.bridge.status();
    switch (m) {
      case Mode::BadJson:
      case Mode::MissingType:
      case Mode::BadPose:
        EXPECT_GT(during.malformed_replies, before.malformed_replies);
        break;
      case Mode::ErrorStatus:
        EXPECT_GT(during.error_replies, before.error_replies);
        EXPECT_NE(during.last_error.find("ESTOP_ACTIVE"), std::string::npos) << during.last_error;
        break;
      default:
        break;
    }
    server.setReplyMode(Mode::Normal);
    EXPECT_TRUE(waitFor([&] { return run.bridge.odometry().has_value() &&
                                     run.bridge.status().status_age < 0.6; }, 6.0))
        << run.bridge.status().message;
  }
  // Replies that never complete (truncated) or never come (silent) are cured by reconnecting.
  EXPECT_GE(run.bridge.status().connects, 3u);
}

TEST(Water2BaseBridge, UnreachableBaseBacksOffWithoutThrowing) {
  FakeWater2Server probe;
  probe.start();
  const int port = probe.port();
  probe.stop();  // nothing listens on this loopback port now
  Water2BridgeConfig c = loopbackConfig(port);
  c.backoff_initial = 0.05;
  c.backoff_max = 0.2;
  Water2BaseBridge bridge(c);
  const double t0 = FakeWater2Server::now();
  while (FakeWater2Server::now() - t0 < 1.0) bridge.spinOnce(0.02);  // never throws
  const auto s = bridge.status();
  EXPECT_FALSE(s.connected);
  EXPECT_EQ(s.level, Water2BridgeStatus::Level::Error);
  EXPECT_GE(s.failed_connects, 3u);
  EXPECT_LE(s.failed_connects, 12u) << "attempts are spaced by the back-off";
  EXPECT_FALSE(bridge.odometry());
}

TEST(Water2BridgeConfig, MisspelledKeyIsAStartUpError) {
  const std::string path = ::testing::TempDir() + "/typo_water2.yaml";
  {
    std::ofstream f(path);
    f << "water2_base_bridge:\n  max_linear_velocty: 0.2\n";
  }
  try {
    loadWater2BridgeConfig(path);
    FAIL() << "a misspelled key was silently ignored";
  } catch (const std::invalid_argument& e) {
    const std::string w = e.what();
    EXPECT_NE(w.find("typo_water2.yaml"), std::string::npos) << w;
    EXPECT_NE(w.find("did you mean 'water2_base_bridge.max_linear_velocity'"), std::string::npos) << w;
  }
}

TEST(Water2BridgeConfig, ShippedFileLoads) {
  EXPECT_NO_THROW(loadWater2BridgeConfig(EHC_CONFIG_DIR "/realman/water2_base_bridge.yaml"));
}
