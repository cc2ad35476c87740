// Water2 bridge core: watchdog and odometry logic on simulated time, then the whole bridge
// against FakeWater2Server on 127.0.0.1 (rate, clamping, stop after timeout, odometry, server
// killed mid-run => zero motion + reconnect, malformed replies), in lock-step on a clock the
// test owns: each 10 ms step advances the clock shared by the bridge and the server, runs the
// bridge's spinOnce (the node's network loop) and waits until the server has handled every
// request sent so far, then drains the replies, so every request and reply is attributed to
// the sim time of the step that produced it whatever the machine's load. Times asserted are
// sim times; the only wall clock is a hang guard.

#include "ehc_realman/water2_base_bridge.h"
#include "water2_fake_server.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <memory>
#include <optional>
#include <thread>

using namespace ehc_realman;
using ehc_realman_test::FakeWater2Server;

namespace {

constexpr double kStep = 0.01;        ///< s of sim time per lock-step
constexpr int kHangGuardSeconds = 30;  ///< wall s without the server's handshake: a hang

Water2BridgeConfig loopbackConfig(int port) {
  Water2BridgeConfig c;
  c.host = "127.0.0.1";
  c.port = port;
  c.reply_timeout = 1.0;
  c.backoff_initial = 0.1;
  c.backoff_max = 0.4;
  // FakeWater2Server's base executes each joy_control at once and exactly.
  c.base_response = Water2ResponseParams::commandedVelocity();
  return c;
}

/// The bridge and FakeWater2Server on one manual clock, stepped by the test.
class LockStep {
 public:
  LockStep() : server_(0, [this] { return now(); }) { server_.start(); }
  /// Builds the bridge (after the server, so that the port is known).
  void makeBridge(const std::function<void(Water2BridgeConfig&)>& edit = {}) {
    Water2BridgeConfig c = loopbackConfig(server_.port());
    if (edit) edit(c);
    bridge_ = std::make_unique<Water2BaseBridge>(c, [this] { return now(); });
  }

  double now() const { return 100.0 + static_cast<double>(steps_.load()) * kStep; }
  FakeWater2Server& server() { return server_; }
  Water2BaseBridge& bridge() { return *bridge_; }

  /// One step: the clock advances, the controller's command (if any), one network cycle, the
  /// server's handshake, the replies drained. False (and a failure) if the handshake hangs.
  bool step(const std::optional<std::pair<double, double>>& command = std::nullopt) {
    ++steps_;
    if (command) bridge_->setCommand(command->first, command->second);
    bridge_->spinOnce(0.0);
    noteConnection();
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(kHangGuardSeconds);
    while (server_.running() && bridge_->status().connected && server_.handled() < expected()) {
      if (std::chrono::steady_clock::now() > deadline) {
        ADD_FAILURE() << "hang guard: after " << kHangGuardSeconds << " wall s the server handled "
                      << server_.handled() << " of "
                      << expected() << " requests";
        return false;
      }
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
    bridge_->spinOnce(0.0);  // the replies (in the socket once handled), at the same sim time
    noteConnection();
    return true;
  }
  /// Steps for `seconds`, commanding (v, w) at 50 Hz (every other step).
  bool drive(double v, double w, double seconds) {
    const int n = static_cast<int>(std::lround(seconds / kStep));
    for (int k = 0; k < n; ++k) {
      if (!step(k % 2 == 0 ? std::optional<std::pair<double, double>>({v, w}) : std::nullopt)) return false;
      if (k % 2 == 0) last_command_ = now();
    }
    return true;
  }
  bool idle(double seconds) {
    const int n = static_cast<int>(std::lround(seconds / kStep));
    for (int k = 0; k < n; ++k)
      if (!step()) return false;
    return true;
  }
  /// Steps (idle, or commanding (v, w) at 50 Hz if `v` is set) until `done` or `seconds` pass.
  bool stepUntil(const std::function<bool()>& done, double seconds,
                 std::optional<std::pair<double, double>> command = std::nullopt) {
    const int n = static_cast<int>(std::lround(seconds / kStep));
    for (int k = 0; k < n && !done(); ++k)
      if (!step(command && k % 2 == 0 ? command : std::nullopt)) return false;
    return done();
  }
  double lastCommand() const { return last_command_; }

  /// Drives (v, w) at 50 Hz until a step sends a robot_status request; the server answers it at
  /// once but the reply reaches the bridge `late_steps` steps later (a descheduled network
  /// thread or a slow link: the clock and the base move on meanwhile), then one normal step.
  /// False on a hang.
  bool driveReadingAStatusLate(double v, double w, int late_steps) {
    for (int k = 0; k < 200; ++k) {
      const auto requested = bridge_->status().status_requests;
      server_.holdReplies(true);
      ++steps_;
      bridge_->setCommand(v, w);
      bridge_->spinOnce(0.0);
      noteConnection();
      if (!waitFor([&] { return server_.handled() >= expected(); })) return false;
      const bool late = bridge_->status().status_requests > requested;
      if (late) steps_ += late_steps;
      const auto releases = server_.releases();
      server_.holdReplies(false);
      if (!waitFor([&] { return server_.releases() > releases; })) return false;
      bridge_->setCommand(v, w);
      bridge_->spinOnce(0.0);  // reads the replies (late, if this step asked for the status)
      noteConnection();
      if (late) return step({{v, w}});
    }
    return false;
  }
  /// Waits (wall clock, hang guard only) until `done`.
  static bool waitFor(const std::function<bool()>& done) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(kHangGuardSeconds);
    while (!done()) {
      if (std::chrono::steady_clock::now() > deadline) {
        ADD_FAILURE() << "hang guard";
        return false;
      }
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
    return true;
  }

 private:
  /// Requests the server must have handled: those sent since the current connection opened.
  std::uint64_t expected() const {
    const auto s = bridge_->status();
    return s.joy_requests + s.status_requests - base_;
  }
  /// A new connection: what was sent on the old one was handled or is lost with it.
  void noteConnection() {
    const auto s = bridge_->status();
    if (s.connects != connects_) {
      connects_ = s.connects;
      base_ = s.joy_requests + s.status_requests - server_.handled();
    }
  }

  std::atomic<long> steps_{0};
  FakeWater2Server server_;
  std::unique_ptr<Water2BaseBridge> bridge_;
  std::uint64_t connects_ = 0, base_ = 0;
  double last_command_ = 0.0;
};

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
  OdometryEstimator e(1.5, 0.6, Water2ResponseParams::commandedVelocity());
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

// /odom's pose covariance: the variances grow with the age of the status the estimate rests on.
TEST(OdometryEstimator, PoseVariancesGrowWithTheStatusAge) {
  OdometryEstimator e(1.5, 0.6, Water2ResponseParams::commandedVelocity());
  e.onStatus({1.0, 2.0, 0.0}, 10.0);
  const auto fresh = e.estimate(10.0);
  ASSERT_TRUE(fresh);
  EXPECT_DOUBLE_EQ(fresh->positionVariance(), 1e-4);
  EXPECT_DOUBLE_EQ(fresh->yawVariance(), 1e-4);
  const auto old = e.estimate(11.0);
  ASSERT_TRUE(old);
  EXPECT_NEAR(old->positionVariance(), 1e-4 + 0.25, 1e-12);  // (0.5 m/s x 1 s)^2
  EXPECT_NEAR(old->yawVariance(), 1e-4 + 1.0, 1e-12);        // (1 rad/s x 1 s)^2
  EXPECT_GT(e.estimate(11.4)->positionVariance(), old->positionVariance());
}

// A status pose applied at the time it was valid, after twists were already sent: they are
// replayed from it (taken as valid when applied instead, the twists sent in between would be
// lost: the base put back by v x delay).
TEST(OdometryEstimator, AppliesALateStatusAtItsValidTimeAndReplaysTheTwistsSentSince) {
  OdometryEstimator e(1.5, 0.6, Water2ResponseParams::commandedVelocity());
  e.onStatus({0.0, 0.0, 0.0}, 0.0);
  for (int k = 0; k <= 24; ++k) e.onTwistSent({0.4, 0.0}, 0.05 * k);  // 0.4 m/s, 20 Hz, until 1.2 s
  // The base was at x = 0.4 at t = 1.0; the reply is read at 1.2 (0.2 s late).
  ASSERT_TRUE(e.onStatus({0.4, 0.0, 0.0}, 1.0));
  auto o = e.estimate(1.2);
  ASSERT_TRUE(o);
  EXPECT_NEAR(o->x, 0.48, 1e-9) << "the pose at 1.0 plus the 0.2 s driven since";
  EXPECT_NEAR(o->status_age, 0.2, 1e-12);
  EXPECT_DOUBLE_EQ(o->linear, 0.4);
  EXPECT_FALSE(e.onStatus({0.3, 0.0, 0.0}, 0.9)) << "an older pose never replaces a newer one";
  EXPECT_NEAR(e.estimate(1.2)->x, 0.48, 1e-9);
  // Commands stop at 1.2: the last one lapses at 1.7; the extrapolation cap (0.6 s past 1.0) too.
  EXPECT_NEAR(e.estimate(1.5)->x, 0.4 + 0.4 * 0.5, 1e-9) << "the last command (1.2) acts until 1.5";
  EXPECT_NEAR(e.estimate(2.0)->x, 0.4 + 0.4 * 0.6, 1e-9) << "at most max_extrapolation past the status";
}

// The dead reckoning predicts what the base does with a command, through the base's response
// model (Water2VelocityResponse): from rest, 0.4 m/s sent at 20 Hz from t = 0 with a status at
// t = 0. Here with latency 0.05 s, acceleration limit 0.5 m/s^2 and no lag: the base stands
// until 0.05 s, then ramps at 0.5 m/s^2 (0.225 m/s at 0.5 s, short of gain x 0.4): it covers
// a/2 (t - 0.05)^2 = 5.1 cm by 0.5 s, where the commanded twist says 20 cm (the 15 cm jump
// at the next status the rehearsal showed, REALMAN.md).
TEST(OdometryEstimator, PredictsTheBaseResponseNotTheCommand) {
  Water2ResponseParams response;  // the defaults (= the simulators' water2 base)
  response.time_constant = 0.0;   // isolate the ramp
  OdometryEstimator e(1.5, 0.6, response);
  OdometryEstimator commanded(1.5, 0.6, Water2ResponseParams::commandedVelocity());
  for (OdometryEstimator* x : {&e, &commanded}) {
    x->onStatus({0.0, 0.0, 0.0}, 0.0);
    for (int k = 0; k < 10; ++k) x->onTwistSent({0.4, 0.0}, 0.05 * k);
  }
  const double a = response.linear_acceleration, t = 0.5 - response.command_latency;
  const auto o = e.estimate(0.5);
  ASSERT_TRUE(o);
  // Stepped at OdometryEstimator::kStep: the discrete ramp is ahead of a t^2 / 2 by a t kStep / 2.
  EXPECT_NEAR(o->x, 0.5 * a * t * t, 0.5 * a * t * OdometryEstimator::kStep + 1e-9);
  EXPECT_NEAR(o->linear, a * t, 1e-9) << "the predicted velocity, not the command";
  EXPECT_NEAR(e.estimate(0.05)->x, 0.0, 1e-12) << "nothing before the latency";
  EXPECT_NEAR(commanded.estimate(0.5)->x, 0.2, 1e-9);
  EXPECT_DOUBLE_EQ(commanded.estimate(0.5)->linear, 0.4);
  // A status resets the pose, not the velocity loop: the ramp goes on from where it was.
  ASSERT_TRUE(e.onStatus({0.05, 0.0, 0.0}, 0.5));
  EXPECT_NEAR(e.estimate(0.6)->linear, a * (t + 0.1), 1e-9);
}

// ------------------------------------------------------------------ bridge on loopback (lock-step)
// A robot_status reply read 0.15 s late (the bridge's thread starved on a loaded computer)
// while the base drives at 0.3 m/s: /odom stays on the base's true pose, because the pose is
// taken as valid when its request was sent (the fake base's pose when it answered). Taken as
// valid when read instead, /odom would put the base 0.3 x 0.15 = 4.5 cm back.
TEST(Water2BaseBridge, AStatusReplyReadLateIsAppliedAtTheTimeItWasValid) {
  LockStep ls;
  ls.makeBridge();
  Water2BaseBridge& bridge = ls.bridge();
  ASSERT_TRUE(ls.stepUntil([&] { return bridge.odometry().has_value(); }, 5.0)) << bridge.status().message;
  ASSERT_TRUE(ls.drive(0.3, 0.0, 0.6));
  ASSERT_TRUE(ls.driveReadingAStatusLate(0.3, 0.0, 15));
  double x = 0.0, y = 0.0, theta = 0.0;
  ls.server().pose(x, y, theta);  // the fake base, exact at the last handled request
  const auto o = bridge.odometry();
  ASSERT_TRUE(o);
  EXPECT_GT(x, 0.2) << "the base drove";
  EXPECT_NEAR(o->x, x, 0.005) << "status age " << o->status_age;
  EXPECT_GT(o->status_age, 0.15) << "the age counts from when the pose was valid";
}

TEST(Water2BaseBridge, StreamsClampedCommandsAtRateAndStopsAfterTimeout) {
  LockStep ls;
  ls.makeBridge();
  Water2BaseBridge& bridge = ls.bridge();
  ASSERT_TRUE(ls.stepUntil([&] { return bridge.odometry().has_value(); }, 5.0)) << bridge.status().message;
  EXPECT_EQ(bridge.status().level, Water2BridgeStatus::Level::Ok);
  ls.server().clearRequests();

  const double t0 = ls.now();
  ASSERT_TRUE(ls.drive(2.0, 1.0, 2.0));  // above the bounds: s = min(0.25, 1.0) => (0.5, 0.25)
  const double t_last_cmd = ls.lastCommand();
  ASSERT_TRUE(ls.idle(1.5));

  const auto reqs = ls.server().requests();
  int moving = 0, status = 0, zeros_after = 0;
  double first_moving = -1.0, first_zero_after = -1.0, last_moving = 0.0;
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
      if (first_moving < 0.0) first_moving = r.time;
      last_moving = r.time;
      EXPECT_NEAR(r.linear, 0.5, 1e-4);
      EXPECT_NEAR(r.angular, 0.25, 1e-4);
    } else if (r.time > t_last_cmd) {
      ++zeros_after;
      if (first_zero_after < 0.0) first_zero_after = r.time;
    }
  }
  // Configured 20 Hz: one request per 0.05 s of sim time while commands are fresh.
  EXPECT_LE(first_moving - t0, 0.05 + kStep + 1e-9) << "the first command within one resend period";
  EXPECT_NEAR((last_moving - first_moving) / (moving - 1), 0.05, 1e-6) << moving << " joy_control requests";
  // The watchdog on the bridge's clock: the last motion request before the 0.2 s timeout, the
  // first zero at the step the timeout passes, then zeros for stop_repeat_duration (1 s).
  EXPECT_LE(last_moving, t_last_cmd + 0.2 + 1e-9) << "no motion request after the timeout";
  ASSERT_GT(first_zero_after, 0.0) << "a zero command must follow";
  EXPECT_GT(first_zero_after - t_last_cmd, 0.2 - 1e-9);
  EXPECT_LE(first_zero_after - t_last_cmd, 0.2 + kStep + 1e-9) << "zero at once after the timeout";
  EXPECT_GE(zeros_after, 20) << "zero at 20 Hz for 1 s";
  EXPECT_LE(zeros_after, 22);
  EXPECT_GE(status, 7) << "robot_status every 0.5 s over 3.5 s";
  std::printf("[water2 bridge] lock-step: %d moving requests at %.3f s intervals, first zero %.3f s (sim) after "
              "the last command, %d zeros\n", moving, (last_moving - first_moving) / (moving - 1),
              first_zero_after - t_last_cmd, zeros_after);
  double x, y, th;
  ls.server().pose(x, y, th);
  EXPECT_GT(x * x + y * y, 0.5) << "the fake base moved";
  const auto o = bridge.odometry();
  ASSERT_TRUE(o);
  EXPECT_NEAR(o->x, x, 0.02);
  EXPECT_NEAR(o->y, y, 0.02);
  EXPECT_GE(bridge.status().clamped_commands, 100u) << "every command of 2 s at 50 Hz";
}

TEST(Water2BaseBridge, ServerKilledMidRunStopsMotionAndReconnects) {
  LockStep ls;
  ls.makeBridge();
  Water2BaseBridge& bridge = ls.bridge();
  ASSERT_TRUE(ls.stepUntil([&] { return bridge.odometry().has_value(); }, 5.0));
  const std::pair<double, double> cmd{0.3, 0.0};
  ASSERT_TRUE(ls.drive(cmd.first, cmd.second, 0.5));
  ls.server().stop();  // killed mid-run while the controller keeps commanding
  const double t_kill = ls.now();
  ASSERT_TRUE(ls.stepUntil([&] { return !bridge.status().connected; }, 2.0, cmd));
  EXPECT_LE(ls.now() - t_kill, 1.0 + 2 * kStep) << "lost within reply_timeout";
  EXPECT_EQ(bridge.status().level, Water2BridgeStatus::Level::Error);
  ASSERT_TRUE(ls.stepUntil([&] { return !bridge.odometry().has_value(); }, 3.0, cmd))
      << "stale odometry must be withheld";
  ASSERT_TRUE(ls.drive(cmd.first, cmd.second, 0.5));  // a few failed attempts
  EXPECT_GT(bridge.status().failed_connects, 0u);

  ls.server().start();  // same port
  ASSERT_TRUE(ls.stepUntil([&] { return bridge.odometry().has_value(); }, 5.0, cmd)) << bridge.status().message;
  ASSERT_TRUE(ls.drive(cmd.first, cmd.second, 0.3));

  const auto s = bridge.status();
  EXPECT_TRUE(s.connected);
  EXPECT_GE(s.connects, 2u);
  EXPECT_GE(s.connection_losses, 1u);
  // The first motion request after the reconnection is a zero.
  bool seen = false;
  for (const auto& r : ls.server().requests()) {
    if (r.connection != 2 || !r.joy) continue;
    if (!seen) {
      EXPECT_EQ(r.linear, 0.0) << "first command after reconnect: " << r.text;
    }
    seen = true;
  }
  EXPECT_TRUE(seen);
}

TEST(Water2BaseBridge, SurvivesMalformedRepliesAndRecovers) {
  LockStep ls;
  ls.makeBridge();
  Water2BaseBridge& bridge = ls.bridge();
  ASSERT_TRUE(ls.stepUntil([&] { return bridge.odometry().has_value(); }, 5.0));
  using Mode = FakeWater2Server::ReplyMode;
  for (Mode m : {Mode::Garbage, Mode::BadJson, Mode::MissingType, Mode::BadPose, Mode::Oversized,
                 Mode::ErrorStatus, Mode::Truncated, Mode::Silent}) {
    SCOPED_TRACE(static_cast<int>(m));
    const auto before = bridge.status();
    ls.server().setReplyMode(m);
    ASSERT_TRUE(ls.drive(0.1, 0.0, 1.2));
    const auto during = bridge.status();
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
    ls.server().setReplyMode(Mode::Normal);
    EXPECT_TRUE(ls.stepUntil([&] { return bridge.odometry().has_value() && bridge.status().status_age < 0.6; },
                             6.0))
        << bridge.status().message;
  }
  // Replies that never complete (truncated) or never come (silent) are cured by reconnecting.
  EXPECT_GE(bridge.status().connects, 3u);
}

TEST(Water2BaseBridge, UnreachableBaseBacksOffWithoutThrowing) {
  LockStep ls;
  ls.makeBridge([](Water2BridgeConfig& c) {
    c.backoff_initial = 0.05;
    c.backoff_max = 0.2;
  });
  ls.server().stop();  // nothing listens on this loopback port now
  Water2BaseBridge& bridge = ls.bridge();
  ASSERT_TRUE(ls.idle(1.0));  // never throws
  const auto s = bridge.status();
  EXPECT_FALSE(s.connected);
  EXPECT_EQ(s.level, Water2BridgeStatus::Level::Error);
  // Attempts at +0, 0.05, 0.15, 0.35, 0.55, 0.75, 0.95 s (back-off 0.05 doubling to 0.2).
  EXPECT_EQ(s.failed_connects, 7u) << "attempts are spaced by the back-off";
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
  const Water2BridgeConfig c = loadWater2BridgeConfig(EHC_CONFIG_DIR "/realman/water2_base_bridge.yaml");
  // The dead reckoning's base response: the documented defaults (the simulators' water2 base).
  const Water2ResponseParams d;
  EXPECT_EQ(c.base_response.command_lifetime, d.command_lifetime);
  EXPECT_EQ(c.base_response.command_latency, d.command_latency);
  EXPECT_EQ(c.base_response.linear_acceleration, d.linear_acceleration);
  EXPECT_EQ(c.base_response.angular_acceleration, d.angular_acceleration);
  EXPECT_EQ(c.base_response.time_constant, d.time_constant);
  EXPECT_EQ(c.base_response.linear_gain, d.linear_gain);
  EXPECT_EQ(c.base_response.angular_gain, d.angular_gain);
}

TEST(Water2BridgeConfig, BaseResponseKeysAreCheckedAndValidated) {
  const auto load = [](const std::string& text) {
    const std::string path = ::testing::TempDir() + "/base_response_water2.yaml";
    {
      std::ofstream f(path);
      f << "water2_base_bridge:\n  base_response:\n" << text;
    }
    return loadWater2BridgeConfig(path);
  };
  EXPECT_EQ(load("    linear_gain: 0.9\n").base_response.linear_gain, 0.9);
  for (const char* bad : {"    linear_gian: 0.9\n", "    linear_gain: 2.0\n", "    time_constant: -0.1\n"}) {
    try {
      load(bad);
      FAIL() << "accepted " << bad;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("base_response.") , std::string::npos) << e.what();
    }
  }
}
