// rostest: rm_arm_adapter (started by the .test file, /use_sim_time, _status_every_step:=true)
// against a fake rm_driver living in this test node, on sim time that this test owns. The test
// is the robot and the controller: every step it advances /clock by one stream period (10 ms),
// publishes /joint_states (joint1..joint6 + a gripper joint, like the driver) and, at 50 Hz, the
// velocity command; then it waits for the adapter's status of that step ("last_step" = the step's
// time) and for every JointPos frame the status counts ("frames"). So each frame is attributed to
// the sim time of the step that produced it, exactly, whatever the machine's load: the only wall
// clock here is a hang guard (a missing handshake fails the test, it never shifts a time).
// The fake driver checks every frame (size, <= 10 deg and <= v_max/rate per joint from the
// previous frame, joint limits) and executes it perfectly.
// Times asserted are sim times. One step of tolerance where the order of two topics is not
// defined: a command published after a /clock step may be taken before it (at the previous
// step's time); the handshake also waits for the command (status "commands"), never later.

#include "ehc_realman/realman_adapter_config.h"
#include "ehc_realman/realman_joint_streamer.h"

#include <diagnostic_msgs/DiagnosticStatus.h>
#include <ehc_msgs/JointVelocityCommand.h>
#include <rm_msgs/Gripper_Pick.h>
#include <rm_msgs/Gripper_Set.h>
#include <rm_msgs/JointPos.h>
#include <rm_msgs/Stop.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/JointState.h>
#include <std_msgs/Bool.h>
#include <std_msgs/Empty.h>
#include <std_msgs/Float64.h>
#include <std_msgs/String.h>

#include <gtest/gtest.h>

#include "sim_clock_wait.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>

namespace {

using ehc_realman_test::spinUntil;

constexpr double kPeriod = 0.01;          ///< stream period (rate_hz 100 in rm_arm_adapter.yaml)
constexpr double kCommandTimeout = 0.2;   ///< stream.command_timeout
constexpr double kHold = 0.5;             ///< stream.hold_duration

struct Frame {
  double time;  ///< sim time of the step that produced it
  Eigen::VectorXd q;
};

/// The robot (fake rm_driver + /clock) and the controller, stepped in lock-step with the adapter.
class Rig {
 public:
  explicit Rig(ros::NodeHandle& nh)
      : config_(ehc_realman::loadRmArmAdapterConfig(EHC_CONFIG_DIR "/realman/rm_arm_adapter.yaml")),
        streamer_(config_.stream, config_.limits) {
    arm_ = Eigen::VectorXd::Zero(6);
    arm_ << 0.0, 0.5, -1.9, 0.0, -0.5, 0.0;  // ready pose
    clock_pub_ = nh.advertise<rosgraph_msgs::Clock>("/clock", 10);
    joint_state_pub_ = nh.advertise<sensor_msgs::JointState>("/joint_states", 10);
    cmd_pub_ = nh.advertise<ehc_msgs::JointVelocityCommand>("/arm/joint_velocity_cmd", 10);
    estop_pub_ = nh.advertise<std_msgs::Bool>("/arm/emergency_stop", 1);
    reset_pub_ = nh.advertise<std_msgs::Empty>("/arm/emergency_stop_reset", 1);
    gripper_pub_ = nh.advertise<std_msgs::String>("/arm/gripper/command", 10);
    width_pub_ = nh.advertise<std_msgs::Float64>("/arm/gripper/width", 10);
    subs_.push_back(nh.subscribe("/rm_driver/JointPos", 1000, &Rig::onFrame, this,
                                 ros::TransportHints().tcpNoDelay()));
    subs_.push_back(nh.subscribe("/rm_driver/Emergency_Stop", 10, &Rig::onStop, this));
    subs_.push_back(nh.subscribe("/rm_driver/Gripper_Set", 10, &Rig::onGripperSet, this));
    subs_.push_back(nh.subscribe("/rm_driver/Gripper_Pick", 10, &Rig::onGripperPick, this));
    subs_.push_back(nh.subscribe("/arm/adapter_status", 1000, &Rig::onStatus, this,
                                 ros::TransportHints().tcpNoDelay()));
  }

  /// Waits until the adapter is connected to every topic, then starts the clock.
  bool connect() {
    return spinUntil([&] {
      return cmd_pub_.getNumSubscribers() > 0 && estop_pub_.getNumSubscribers() > 0 &&
             reset_pub_.getNumSubscribers() > 0 && gripper_pub_.getNumSubscribers() > 0 &&
             width_pub_.getNumSubscribers() > 0 && joint_state_pub_.getNumSubscribers() > 0 &&
             clock_pub_.getNumSubscribers() > 0 && subs_[0].getNumPublishers() > 0 &&
             subs_[4].getNumPublishers() > 0;
    }, "connection to rm_arm_adapter");
  }

  /// One stream period: /clock += 10 ms, the arm's /joint_states (joint1 offset by `glitch`),
  /// the command if given; then the adapter's status of this step and every frame it counts.
  bool step(const std::optional<std::vector<double>>& command = std::nullopt,
            double command_stamp_offset = 0.0, double glitch = 0.0,
            const std::vector<std::string>& names = {"joint1", "joint2", "joint3", "joint4",
                                                     "joint5", "joint6"}) {
    time_ += ros::Duration(kPeriod);
    t_ = time_.toSec();
    rosgraph_msgs::Clock c;
    c.clock = time_;
    clock_pub_.publish(c);
    sensor_msgs::JointState js;
    js.header.stamp = time_;
    js.name = {"joint1", "joint2", "joint3", "joint4", "joint5", "joint6", "gripper_joint"};
    js.position.assign(arm_.data(), arm_.data() + 6);
    js.position[0] += glitch;
    js.position.push_back(0.035);
    joint_state_pub_.publish(js);
    if (command) {
      ehc_msgs::JointVelocityCommand m;
      m.header.stamp = time_ + ros::Duration(command_stamp_offset);  // the sender's clock
      m.names = names;
      m.velocities = *command;
      cmd_pub_.publish(m);
      ++commands_sent_;
    }
    // The command too (accepted or rejected): its receipt time is this step or the previous one
    // (it may be taken before this step's /clock), never later.
    return spinUntil([&] {
      return last_step_ >= t_ - 1e-6 && frames_.size() >= status_frames_ &&
             count("commands") + count("rejected_commands") >= commands_sent_;
    }, "status of the step (last_step), its frames and the command", [&] { clock_pub_.publish(c); });
  }

  /// Steps for `seconds` of sim time, commanding `v` at 50 Hz (every other step).
  bool command(const std::vector<double>& v, double seconds, double stamp_offset = 0.0,
               const std::vector<std::string>& names = {"joint1", "joint2", "joint3", "joint4",
                                                        "joint5", "joint6"}) {
    const int n = static_cast<int>(std::lround(seconds / kPeriod));
    for (int k = 0; k < n; ++k) {
      const bool send = (k % 2 == 0);
      if (!step(send ? std::optional<std::vector<double>>(v) : std::nullopt, stamp_offset, 0.0, names))
        return false;
      if (send) last_command_time_ = t_;
    }
    return true;
  }

  /// Steps without commands for `seconds` of sim time.
  bool idle(double seconds) {
    const int n = static_cast<int>(std::lround(seconds / kPeriod));
    for (int k = 0; k < n; ++k)
      if (!step()) return false;
    return true;
  }

  std::vector<Frame> framesSince(double t0) const {
    std::vector<Frame> out;
    for (const auto& f : frames_)
      if (f.time >= t0 - 1e-9) out.push_back(f);
    return out;
  }
  std::string statusValue(const std::string& key) const {
    for (const auto& kv : status_.values)
      if (kv.key == key) return kv.value;
    return "";
  }
  unsigned long count(const std::string& key) const {
    const std::string v = statusValue(key);
    return v.empty() ? 0ul : std::stoul(v);
  }

  void publishEstop() {
    std_msgs::Bool b;
    b.data = true;
    estop_pub_.publish(b);
  }
  void publishReset() { reset_pub_.publish(std_msgs::Empty()); }
  void publishGripper(const std::string& s) {
    std_msgs::String m;
    m.data = s;
    gripper_pub_.publish(m);
  }
  void publishWidth(double w) {
    std_msgs::Float64 m;
    m.data = w;
    width_pub_.publish(m);
  }

  double t() const { return t_; }
  double lastCommandTime() const { return last_command_time_; }
  const Eigen::VectorXd& arm() const { return arm_; }
  const ehc_realman::JointPositionStreamer& limits() const { return streamer_; }
  int violations() const { return violations_; }
  int stops() const { return stops_; }
  const std::vector<int>& gripperSets() const { return gripper_sets_; }
  const std::vector<std::pair<int, int>>& gripperPicks() const { return gripper_picks_; }

 private:
  void onFrame(const rm_msgs::JointPos::ConstPtr& msg) {
    if (msg->joint.size() != 6) {
      ++violations_;
      ADD_FAILURE() << "JointPos with " << msg->joint.size() << " joints";
      return;
    }
    Eigen::VectorXd q(6);
    for (int i = 0; i < 6; ++i) q[i] = msg->joint[static_cast<std::size_t>(i)];
    // Compare with the previous frame, or with the arm when a new stream segment starts.
    const bool continues = !frames_.empty() && t_ - frames_.back().time < 1.5 * kPeriod;
    const Eigen::VectorXd ref = continues ? frames_.back().q : arm_;
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
    frames_.push_back({t_, q});
    arm_ = q;  // the driver follows the set-point
  }
  void onStop(const rm_msgs::Stop::ConstPtr& msg) { stops_ += msg->state ? 1 : 0; }
  void onGripperSet(const rm_msgs::Gripper_Set::ConstPtr& msg) { gripper_sets_.push_back(msg->position); }
  void onGripperPick(const rm_msgs::Gripper_Pick::ConstPtr& msg) {
    gripper_picks_.push_back({msg->speed, msg->force});
  }
  void onStatus(const diagnostic_msgs::DiagnosticStatus::ConstPtr& msg) {
    double last_step = -1.0;
    std::size_t frames = 0;
    for (const auto& kv : msg->values) {
      if (kv.key == "last_step") last_step = std::stod(kv.value);  // "nan" before the first step
      if (kv.key == "frames") frames = std::stoul(kv.value);
    }
    if (!std::isfinite(last_step) || last_step < last_step_) return;  // e.g. the 1 Hz status
    status_ = *msg;
    last_step_ = last_step;
    status_frames_ = frames;  // the adapter starts idle: every frame it counts is ours
  }

  ehc_realman::RmArmAdapterConfig config_;
  ehc_realman::JointPositionStreamer streamer_;  // used for its effective limits only
  ros::Publisher clock_pub_, joint_state_pub_, cmd_pub_, estop_pub_, reset_pub_, gripper_pub_, width_pub_;
  std::vector<ros::Subscriber> subs_;
  ros::Time time_{100.0};  ///< the sim time this test publishes (integer ns: no drift)
  double t_ = 100.0;       ///< the same, in seconds
  double last_step_ = -1.0;
  std::size_t status_frames_ = 0;
  unsigned long commands_sent_ = 0;
  double last_command_time_ = 0.0;
  diagnostic_msgs::DiagnosticStatus status_;
  Eigen::VectorXd arm_;
  std::vector<Frame> frames_;
  int violations_ = 0, stops_ = 0;
  std::vector<int> gripper_sets_;
  std::vector<std::pair<int, int>> gripper_picks_;
};

Rig* g_rig = nullptr;

/// Frames that changed the set-point (a frame may repeat the previous one while holding).
int movingFrames(const std::vector<Frame>& frames, const Eigen::VectorXd& start) {
  int moving = 0;
  for (std::size_t k = 0; k < frames.size(); ++k)
    moving += !(frames[k].q == (k == 0 ? Eigen::VectorXd(start.cast<float>().cast<double>())
                                        : frames[k - 1].q));
  return moving;
}

}  // namespace

TEST(RmArmAdapter, StreamsOneFramePerPeriodWithinEveryBound) {
  Rig& r = *g_rig;
  const Eigen::VectorXd start = r.arm();
  const double t0 = r.t();
  const std::vector<double> v = {0.3, -0.2, 0.4, 0.1, -0.3, 0.5};
  ASSERT_TRUE(r.command(v, 2.0));
  const auto frames = r.framesSince(t0);
  // 200 steps: streaming starts at the step that takes the first command (the first or the
  // second) and then produces exactly one frame per step.
  ASSERT_GE(frames.size(), 199u);
  EXPECT_LE(frames.size(), 200u);
  for (std::size_t k = 1; k < frames.size(); ++k)
    EXPECT_NEAR(frames[k].time - frames[k - 1].time, kPeriod, 1e-6) << "frame " << k;
  // Motion follows the command: v * period per frame, every frame.
  EXPECT_EQ(movingFrames(frames, start), static_cast<int>(frames.size()));
  const Eigen::VectorXd moved = frames.back().q - start;
  for (int i = 0; i < 6; ++i)
    EXPECT_NEAR(moved[i], v[static_cast<std::size_t>(i)] * kPeriod * frames.size(), 1e-4);
  EXPECT_EQ(r.violations(), 0);
}

TEST(RmArmAdapter, ClampsFastCommandsToTheSpeedLimit) {
  Rig& r = *g_rig;
  ASSERT_TRUE(r.idle(1.0));  // the previous stream ends
  const double t0 = r.t();
  ASSERT_TRUE(r.command({5.0, 0.0, 0.0, 0.0, 0.0, -5.0}, 0.4));  // 5 rad/s > 3.14 rad/s
  const auto frames = r.framesSince(t0);
  ASSERT_GE(frames.size(), 39u);
  for (std::size_t k = 1; k < frames.size(); ++k) {
    EXPECT_NEAR(frames[k].q[0] - frames[k - 1].q[0], 3.14 * kPeriod, 1e-5) << "at the limit, not below";
    EXPECT_NEAR(frames[k].q[5] - frames[k - 1].q[5], -3.14 * kPeriod, 1e-5);
  }
  EXPECT_GT(r.count("speed_clamped"), 0ul);
  EXPECT_EQ(r.violations(), 0);
}

TEST(RmArmAdapter, StopsAtTheJointLimit) {
  Rig& r = *g_rig;
  ASSERT_TRUE(r.idle(1.0));
  ASSERT_TRUE(r.command({0.0, 0.0, 0.0, 0.0, 3.0, 0.0}, 2.0));  // joint5 towards +128 deg
  EXPECT_NEAR(r.arm()[4], r.limits().upperLimit()[4], 1e-5);
  EXPECT_GT(r.count("limit_clamped"), 0ul);
  ASSERT_TRUE(r.command({0.0, 0.0, 0.0, 0.0, -3.0, 0.0}, 1.0));  // back inside
  EXPECT_LT(r.arm()[4], r.limits().upperLimit()[4] - 1.0);
  EXPECT_EQ(r.violations(), 0);
}

// The command timeout on the adapter's own clock: the commands' header stamps are 0.15 s ahead
// (another machine's clock); the adapter measures from each command's receipt, so it still
// holds command_timeout after the last one, then stops streaming hold_duration later.
TEST(RmArmAdapter, CommandTimeoutHoldsThenStopsOnTheAdaptersClock) {
  Rig& r = *g_rig;
  ASSERT_TRUE(r.idle(1.0));
  ASSERT_TRUE(r.command({0.0, 0.2, 0.0, 0.0, 0.0, 0.0}, 0.5, /*stamp_offset=*/0.15));
  const double t_last = r.lastCommandTime();  // sim time the last command was published
  ASSERT_TRUE(r.idle(2.0));
  const auto frames = r.framesSince(t_last);
  ASSERT_FALSE(frames.empty()) << "the position is held after the timeout";
  const Eigen::VectorXd held = frames.back().q;
  double last_motion = t_last;
  for (std::size_t k = 1; k < frames.size(); ++k)
    if (!(frames[k].q == frames[k - 1].q)) last_motion = frames[k].time;
  // Motion until the timeout after the last command's receipt (this step or the previous one;
  // the step at exactly the timeout may fall either side by rounding), then the same frame.
  EXPECT_GE(last_motion, t_last + kCommandTimeout - 2 * kPeriod - 1e-6);
  EXPECT_LE(last_motion, t_last + kCommandTimeout + kPeriod + 1e-6);
  for (const auto& f : frames) {
    if (f.time > t_last + kCommandTimeout + 2 * kPeriod + 1e-6) {
      EXPECT_TRUE(f.q == held) << "moved while holding";
    }
  }
  // Streaming stops hold_duration after the timeout.
  const double stream_end = frames.back().time;
  EXPECT_GE(stream_end, t_last + kCommandTimeout + kHold - 2 * kPeriod - 1e-6);
  EXPECT_LE(stream_end, t_last + kCommandTimeout + kHold + 2 * kPeriod + 1e-6);
  std::printf("[rm_arm_adapter] command stamps +0.15 s: last motion %.3f s, last frame %.3f s (sim) after the "
              "last command (timeout %.1f s, hold %.1f s)\n",
              last_motion - t_last, stream_end - t_last, kCommandTimeout, kHold);
  EXPECT_GT(r.count("timeouts"), 0ul);
}

// Through the node: a 0.1 s glitch of +1 rad on joint1's /joint_states while
// commanding -0.2 rad/s never moves the set-point the other way; the motion resumes after it.
TEST(RmArmAdapter, JointStateGlitchNeverTurnsIntoMotion) {
  Rig& r = *g_rig;
  ASSERT_TRUE(r.idle(1.0));
  const std::vector<double> v = {-0.2, 0.0, 0.0, 0.0, 0.0, 0.0};
  ASSERT_TRUE(r.command(v, 0.3));
  const double before = r.arm()[0];
  const double t_glitch = r.t();
  for (int k = 0; k < 10; ++k)  // 0.1 s at 100 Hz, commands at 50 Hz
    ASSERT_TRUE(r.step(k % 2 == 0 ? std::optional<std::vector<double>>(v) : std::nullopt, 0.0, /*glitch=*/1.0));
  for (const auto& f : r.framesSince(t_glitch)) {
    EXPECT_LE(f.q[0], before + 2e-6) << "set-point moved against the command at " << f.time - t_glitch;
  }
  ASSERT_TRUE(r.command(v, 0.5));
  EXPECT_LT(r.arm()[0], before - 0.09) << "commanded motion resumes after the glitch";
  EXPECT_EQ(r.violations(), 0);
}

TEST(RmArmAdapter, RejectsMalformedCommands) {
  Rig& r = *g_rig;
  ASSERT_TRUE(r.idle(1.0));
  const unsigned long rejected = r.count("rejected_commands");
  const double t0 = r.t();
  ASSERT_TRUE(r.command({0.1, NAN, 0.1, 0.1, 0.1, 0.1}, 0.5));
  ASSERT_TRUE(r.command({0.1, 0.1}, 0.3));
  ASSERT_TRUE(r.command({0.1, 0.1, 0.1, 0.1, 0.1, 0.1}, 0.3, 0.0, {"a", "b", "c", "d", "e", "f"}));
  ASSERT_TRUE(r.idle(0.1));  // the last command's step
  EXPECT_TRUE(r.framesSince(t0).empty()) << "no stream from rejected commands";
  EXPECT_GE(r.count("rejected_commands"), rejected + 50) << "25 + 15 + 15 rejected (50 Hz)";
}

TEST(RmArmAdapter, EmergencyStopLatchesUntilReset) {
  Rig& r = *g_rig;
  ASSERT_TRUE(r.idle(1.0));
  const std::vector<double> v = {0.0, 0.0, 0.0, 0.2, 0.0, 0.0};
  ASSERT_TRUE(r.command(v, 0.5));
  r.publishEstop();
  // The controller keeps commanding; the latch shows in the status within a few steps.
  const std::string stopped = ehc_realman::toString(ehc_realman::StreamPhase::EmergencyStopped);
  for (int k = 0; k < 100 && r.statusValue("phase") != stopped; ++k) ASSERT_TRUE(r.command(v, 0.02));
  ASSERT_EQ(r.statusValue("phase"), stopped);
  const double t_stop = r.t();
  ASSERT_TRUE(r.command(v, 1.5));
  EXPECT_TRUE(r.framesSince(t_stop + kPeriod / 2).empty()) << "no frame after the stop";
  ASSERT_TRUE(spinUntil([&] { return r.stops() > 0; }, "Stop{state: true}"));
  r.publishReset();
  for (int k = 0; k < 100 && r.statusValue("phase") == stopped; ++k) ASSERT_TRUE(r.idle(0.01));
  const double t1 = r.t();
  ASSERT_TRUE(r.command({0.0, 0.0, 0.0, -0.2, 0.0, 0.0}, 0.5));
  EXPECT_GE(r.framesSince(t1).size(), 49u) << "streaming resumes after the reset";
  EXPECT_EQ(r.violations(), 0);
}

TEST(RmArmAdapter, GripperRequestsMapToDriverMessages) {
  Rig& r = *g_rig;
  r.publishGripper("open");
  r.publishGripper("pick");
  r.publishGripper("bogus");
  r.publishWidth(0.035);
  ASSERT_TRUE(spinUntil([&] { return r.gripperSets().size() >= 2 && !r.gripperPicks().empty(); },
                          "gripper messages"));
  ASSERT_TRUE(r.idle(0.1));  // anything else in flight arrives (ordered per topic)
  EXPECT_EQ(r.gripperSets(), (std::vector<int>{1000, 500}));
  ASSERT_EQ(r.gripperPicks().size(), 1u);
  EXPECT_EQ(r.gripperPicks()[0], (std::pair<int, int>{500, 500}));
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_rm_arm_adapter_node");
  ros::NodeHandle nh;
  Rig rig(nh);
  g_rig = &rig;
  // Connected, then 0.1 s of sim time with /joint_states before the first test: the adapter has
  // a clock and a fresh measured state (the robot is up).
  if (!rig.connect() || !rig.idle(0.1)) return 1;
  return RUN_ALL_TESTS();
}
