// rostest: rm_arm_adapter (started by the .test file) against a fake rm_driver living in this
// test node. The fake driver checks every /rm_driver/JointPos frame (size, <= 10 deg and
// <= v_max/rate per joint from the previous frame, joint limits) and executes it perfectly,
// publishing /joint_states (joint1..joint6 + a gripper joint, like the driver) at 200 Hz.
// A scripted commander publishes /arm/joint_velocity_cmd. Rates are measured over many frames
// with generous tolerances.

#include "wall_clock.h"

#include "ehc_realman/realman_adapter_config.h"
#include "ehc_realman/realman_joint_streamer.h"

#include <diagnostic_msgs/DiagnosticStatus.h>
#include <ehc_msgs/JointVelocityCommand.h>
#include <rm_msgs/Gripper_Pick.h>
#include <rm_msgs/Gripper_Set.h>
#include <rm_msgs/JointPos.h>
#include <rm_msgs/Stop.h>
#include <ros/ros.h>
#include <sensor_msgs/JointState.h>
#include <std_msgs/Bool.h>
#include <std_msgs/Empty.h>
#include <std_msgs/Float64.h>
#include <std_msgs/String.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <mutex>
#include <thread>

namespace {

using ehc_realman_test::now;
using ehc_realman_test::sleepFor;
using ehc_realman_test::waitFor;

struct Frame {
  double time;
  Eigen::VectorXd q;
};

/// Fake rm_driver: checks and executes every frame.
class FakeRmDriver {
 public:
  explicit FakeRmDriver(ros::NodeHandle& nh)
      : config_(ehc_realman::loadRmArmAdapterConfig(EHC_CONFIG_DIR "/realman/rm_arm_adapter.yaml")),
        streamer_(config_.stream, config_.limits) {
    arm_ = Eigen::VectorXd::Zero(6);
    arm_ << 0.0, 0.5, -1.9, 0.0, -0.5, 0.0;  // ready pose
    joint_state_pub_ = nh.advertise<sensor_msgs::JointState>("/joint_states", 10);
    subs_.push_back(nh.subscribe("/rm_driver/JointPos", 1000, &FakeRmDriver::onFrame, this,
                                 ros::TransportHints().tcpNoDelay()));
    subs_.push_back(nh.subscribe("/rm_driver/Emergency_Stop", 10, &FakeRmDriver::onStop, this));
    subs_.push_back(nh.subscribe("/rm_driver/Gripper_Set", 10, &FakeRmDriver::onGripperSet, this));
    subs_.push_back(nh.subscribe("/rm_driver/Gripper_Pick", 10, &FakeRmDriver::onGripperPick, this));
    subs_.push_back(nh.subscribe("/arm/adapter_status", 10, &FakeRmDriver::onStatus, this));
    timer_ = nh.createSteadyTimer(ros::WallDuration(0.005), [this](const ros::SteadyTimerEvent&) {
      sensor_msgs::JointState js;
      js.header.stamp = ros::Time::now();
      js.name = {"joint1", "joint2", "joint3", "joint4", "joint5", "joint6", "gripper_joint"};
      std::lock_guard<std::mutex> lock(mutex_);
      js.position.assign(arm_.data(), arm_.data() + 6);
      js.position.push_back(0.035);
      joint_state_pub_.publish(js);
    });
  }

  void onFrame(const rm_msgs::JointPos::ConstPtr& msg) {
    const double t = now();
    std::lock_guard<std::mutex> lock(mutex_);
    ++frames_;
    if (msg->joint.size() != 6) {
      ++violations_;
      ADD_FAILURE() << "JointPos with " << msg->joint.size() << " joints";
      return;
    }
    Eigen::VectorXd q(6);
    for (int i = 0; i < 6; ++i) q[i] = msg->joint[static_cast<std::size_t>(i)];
    // Compare with the previous frame, or with the arm when a new stream segment starts.
    const bool continues = !frames_log_.empty() && t - frames_log_.back().time < 0.1;
    const Eigen::VectorXd ref = continues ? frames_log_.back().q : arm_;
    for (int i = 0; i < 6; ++i) {
      const double step = std::abs(q[i] - ref[i]);
      const double tol = 2e-6;  // float32 rounding
      if (step > 10.0 * M_PI / 180.0 + tol || step > streamer_.stepLimit()[i] + tol) {
        ++violations_;
        ADD_FAILURE() << "joint" << i + 1 << " step " << step << " rad exceeds the bound";
      }
      if (q[i] > streamer_.upperLimit()[i] + tol || q[i] < streamer_.lowerLimit()[i] - tol) {
        ++violations_;
        ADD_FAILURE() << "joint" << i + 1 << " at " << q[i] << " outside its limits";
      }
    }
    if (estopped_) {
      ++frames_after_estop_;
    }
    frames_log_.push_back({t, q});
    arm_ = q;  // the driver follows the set-point
  }

  void onStop(const rm_msgs::Stop::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (msg->state) {
      estopped_ = true;
      ++stops_;
    }
  }
  void onGripperSet(const rm_msgs::Gripper_Set::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    gripper_sets_.push_back(msg->position);
  }
  void onGripperPick(const rm_msgs::Gripper_Pick::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    gripper_picks_.push_back({msg->speed, msg->force});
  }
  void onStatus(const diagnostic_msgs::DiagnosticStatus::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    status_ = *msg;
  }

  std::vector<Frame> framesSince(double t0) {
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<Frame> out;
    for (const auto& f : frames_log_)
      if (f.time >= t0) out.push_back(f);
    return out;
  }
  Eigen::VectorXd arm() {
    std::lock_guard<std::mutex> lock(mutex_);
    return arm_;
  }
  std::string statusValue(const std::string& key) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& kv : status_.values)
      if (kv.key == key) return kv.value;
    return "";
  }

  ehc_realman::RmArmAdapterConfig config_;
  ehc_realman::JointPositionStreamer streamer_;  // used for its effective limits only
  std::mutex mutex_;
  Eigen::VectorXd arm_;
  std::vector<Frame> frames_log_;
  int frames_ = 0, violations_ = 0, stops_ = 0, frames_after_estop_ = 0;
  bool estopped_ = false;
  std::vector<int> gripper_sets_;
  std::vector<std::pair<int, int>> gripper_picks_;
  diagnostic_msgs::DiagnosticStatus status_;

 private:
  ros::Publisher joint_state_pub_;
  std::vector<ros::Subscriber> subs_;
  ros::SteadyTimer timer_;
};

std::unique_ptr<FakeRmDriver> g_driver;
ros::Publisher g_cmd, g_estop, g_reset, g_gripper, g_width;


/// Publishes `v` at 50 Hz for `seconds` (the controller).
void command(const std::vector<double>& v, double seconds,
             std::vector<std::string> names = {"joint1", "joint2", "joint3", "joint4", "joint5",
                                               "joint6"}) {
  ehc_msgs::JointVelocityCommand c;
  c.names = names;
  c.velocities = v;
  const double end = now() + seconds;
  while (now() < end) {
    c.header.stamp = ros::Time::now();
    g_cmd.publish(c);
    sleepFor(0.02);
  }
}

/// Average frame rate over a stream segment.
double rate(const std::vector<Frame>& f) {
  if (f.size() < 2) return 0.0;
  return (f.size() - 1) / (f.back().time - f.front().time);
}

}  // namespace

TEST(RmArmAdapter, StreamsAtTheConfiguredRateWithinEveryBound) {
  const Eigen::VectorXd start = g_driver->arm();
  const double t0 = now();
  const std::vector<double> v = {0.3, -0.2, 0.4, 0.1, -0.3, 0.5};
  command(v, 2.0);
  const auto frames = g_driver->framesSince(t0);
  ASSERT_GE(frames.size(), 100u) << "configured 100 Hz for 2 s";
  const double r = rate(frames);
  EXPECT_NEAR(r, 100.0, 15.0);
  // Jitter: intervals measured over every frame; most are near the period.
  std::vector<double> dt;
  for (std::size_t k = 1; k < frames.size(); ++k) dt.push_back(frames[k].time - frames[k - 1].time);
  std::sort(dt.begin(), dt.end());
  EXPECT_NEAR(dt[dt.size() / 2], 0.01, 0.003) << "median period";
  EXPECT_LT(dt[dt.size() * 95 / 100], 0.1) << "95th percentile period (generous under CI load)";
  // Motion follows the command: displacement = v * dt per moving frame (a frame may repeat the
  // previous one if the adapter had to hold, e.g. a /joint_states stall under CI load).
  const Eigen::VectorXd moved = frames.back().q - start;
  int moving = 0;
  for (std::size_t k = 0; k < frames.size(); ++k)
    moving += !(frames[k].q == (k == 0 ? Eigen::VectorXd(start.cast<float>().cast<double>())
                                        : frames[k - 1].q));
  const double streamed = moving / 100.0;  // nominal dt per frame
  for (int i = 0; i < 6; ++i) EXPECT_NEAR(moved[i], v[static_cast<std::size_t>(i)] * streamed, 1e-3);
  EXPECT_EQ(g_driver->violations_, 0);
}

TEST(RmArmAdapter, ClampsFastCommandsToTheSpeedLimit) {
  sleepFor(1.0);  // previous stream ends
  const double t0 = now();
  command({5.0, 0.0, 0.0, 0.0, 0.0, -5.0}, 0.4);  // 5 rad/s > 3.14 rad/s
  const auto frames = g_driver->framesSince(t0);
  ASSERT_GE(frames.size(), 20u);
  for (std::size_t k = 1; k < frames.size(); ++k) {
    const double step = frames[k].q[0] - frames[k - 1].q[0];
    if (frames[k].time - frames[k - 1].time > 0.1) continue;
    EXPECT_LE(std::abs(step), 3.14 / 100.0 + 2e-6);
  }
  EXPECT_NEAR(frames[10].q[0] - frames[9].q[0], 3.14 / 100.0, 1e-5) << "at the limit, not below";
  EXPECT_TRUE(waitFor([] { return g_driver->statusValue("speed_clamped") != "" &&
                                  std::stoul(g_driver->statusValue("speed_clamped")) > 0; }, 3.0));
  EXPECT_EQ(g_driver->violations_, 0);
}

TEST(RmArmAdapter, StopsAtTheJointLimit) {
  sleepFor(1.0);
  command({0.0, 0.0, 0.0, 0.0, 3.0, 0.0}, 2.0);  // joint5 towards +128 deg
  const Eigen::VectorXd q = g_driver->arm();
  EXPECT_NEAR(q[4], g_driver->streamer_.upperLimit()[4], 1e-5);
  EXPECT_TRUE(waitFor([] { return g_driver->statusValue("limit_clamped") != "" &&
                                  std::stoul(g_driver->statusValue("limit_clamped")) > 0; }, 3.0));
  command({0.0, 0.0, 0.0, 0.0, -3.0, 0.0}, 1.0);  // back inside
  EXPECT_LT(g_driver->arm()[4], g_driver->streamer_.upperLimit()[4] - 1.0);
  EXPECT_EQ(g_driver->violations_, 0);
}

TEST(RmArmAdapter, CommandTimeoutHoldsThenStopsStreaming) {
  sleepFor(1.0);
  command({0.0, 0.2, 0.0, 0.0, 0.0, 0.0}, 0.5);
  const double t_last = now();
  sleepFor(2.0);
  const auto frames = g_driver->framesSince(t_last);
  ASSERT_FALSE(frames.empty()) << "the position is held after the timeout";
  const Eigen::VectorXd held = frames.back().q;
  for (const auto& f : frames) {
    if (f.time > t_last + 0.2 + 0.1) {
      EXPECT_TRUE(f.q == held) << "no motion while holding";
    }
  }
  // Streaming stopped: hold 0.5 s after the 0.2 s timeout (generous margin for CI load).
  EXPECT_LT(frames.back().time - t_last, 0.2 + 0.5 + 0.4);
  EXPECT_GT(frames.back().time - t_last, 0.2 + 0.5 - 0.2);
  EXPECT_TRUE(g_driver->framesSince(now() - 0.5).empty());
}

TEST(RmArmAdapter, RejectsMalformedCommands) {
  sleepFor(0.5);
  const double t0 = now();
  command({0.1, NAN, 0.1, 0.1, 0.1, 0.1}, 0.5);
  command({0.1, 0.1}, 0.3);
  command({0.1, 0.1, 0.1, 0.1, 0.1, 0.1}, 0.3, {"a", "b", "c", "d", "e", "f"});
  EXPECT_TRUE(g_driver->framesSince(t0).empty()) << "no stream from rejected commands";
  EXPECT_TRUE(waitFor([] { return g_driver->statusValue("rejected_commands") != "" &&
                                  std::stoul(g_driver->statusValue("rejected_commands")) >= 10; },
                      3.0));
}

TEST(RmArmAdapter, EmergencyStopLatchesUntilReset) {
  std::thread ctrl([] { command({0.0, 0.0, 0.0, 0.2, 0.0, 0.0}, 2.0); });
  sleepFor(0.5);
  std_msgs::Bool b;
  b.data = true;
  g_estop.publish(b);
  const double t_stop = now();
  ASSERT_TRUE(waitFor([] { return g_driver->stops_ > 0; }, 2.0)) << "Stop{state: true} published";
  ctrl.join();  // the controller kept commanding for 1.5 s
  EXPECT_TRUE(g_driver->framesSince(t_stop + 0.1).empty()) << "no frame after the stop";
  std_msgs::Empty e;
  g_reset.publish(e);
  sleepFor(0.2);
  const double t1 = now();
  command({0.0, 0.0, 0.0, -0.2, 0.0, 0.0}, 0.5);
  EXPECT_GE(g_driver->framesSince(t1).size(), 20u) << "streaming resumes after the reset";
  EXPECT_EQ(g_driver->violations_, 0);
}

TEST(RmArmAdapter, GripperRequestsMapToDriverMessages) {
  std_msgs::String s;
  s.data = "open";
  g_gripper.publish(s);
  s.data = "pick";
  g_gripper.publish(s);
  s.data = "bogus";
  g_gripper.publish(s);
  std_msgs::Float64 w;
  w.data = 0.035;
  g_width.publish(w);
  ASSERT_TRUE(waitFor([] {
    std::lock_guard<std::mutex> lock(g_driver->mutex_);
    return g_driver->gripper_sets_.size() >= 2 && !g_driver->gripper_picks_.empty();
  }, 3.0));
  sleepFor(0.3);
  std::lock_guard<std::mutex> lock(g_driver->mutex_);
  EXPECT_EQ(g_driver->gripper_sets_, (std::vector<int>{1000, 500}));
  ASSERT_EQ(g_driver->gripper_picks_.size(), 1u);
  EXPECT_EQ(g_driver->gripper_picks_[0], (std::pair<int, int>{500, 500}));
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_rm_arm_adapter_node");
  ros::NodeHandle nh;
  ros::AsyncSpinner spinner(2);
  spinner.start();
  g_driver = std::make_unique<FakeRmDriver>(nh);
  g_cmd = nh.advertise<ehc_msgs::JointVelocityCommand>("/arm/joint_velocity_cmd", 10);
  g_estop = nh.advertise<std_msgs::Bool>("/arm/emergency_stop", 1);
  g_reset = nh.advertise<std_msgs::Empty>("/arm/emergency_stop_reset", 1);
  g_gripper = nh.advertise<std_msgs::String>("/arm/gripper/command", 10);
  g_width = nh.advertise<std_msgs::Float64>("/arm/gripper/width", 10);
  // Wait (bounded) until the adapter is connected to every topic of this test.
  const bool ready = waitFor([] {
    return g_cmd.getNumSubscribers() > 0 && g_estop.getNumSubscribers() > 0 &&
           g_reset.getNumSubscribers() > 0 && g_gripper.getNumSubscribers() > 0 &&
           g_width.getNumSubscribers() > 0;
  }, 30.0);
  if (!ready) {
    ADD_FAILURE() << "rm_arm_adapter did not subscribe within 30 s";
  }
  sleepFor(0.5);  // adapter's publishers -> our subscribers
  const int rc = RUN_ALL_TESTS();
  g_driver.reset();
  spinner.stop();
  return rc;
}
