// rostest: the real controller drives a target through the RealMan adapters, on wall
// time (no /clock), with both hardware ends faked in this test node:
//   - fake rm_driver: checks EVERY /rm_driver/JointPos frame (6 finite joints, <= 10 deg and
//     <= v_max / stream rate per joint from the previous frame, inside the joint limits), records
//     its arrival time (rate, jitter), executes it exactly and publishes /joint_states
//     (joint1..joint6, as the driver does) at 100 Hz from the positions it received;
//   - FakeWater2Server (water2_fake_server.h) on 127.0.0.1: integrates the joy_control commands
//     into the pose it reports in robot_status;
//   - water2_base_bridge: run by this node (rosrun-style arguments, free port), stopped by pid.
// The controller (config/realman/controller.yaml, node.trigger: timer) and rm_arm_adapter are
// started by the .test file. Ground truth is the fakes' state: TCP = FK(server pose, driver arm).
// Asserts: the TCP error to a target 1.5 m away falls below 5 cm (and far below its start) with
// the base actually driving; every frame and every request obeys its limits; no NaN anywhere;
// when the target stops, the chain comes to rest (arm frames constant, base commands zero).
// Time bounds are generous (2 shared CI cores); no single-frame timing is asserted.

#include "water2_fake_server.h"

#include "ehc_realman/realman_adapter_config.h"
#include "ehc_msgs/ControllerStatus.h"
#include "ehc_msgs/JointVelocityCommand.h"
#include "ehc_control/robot_config.h"
#include "ehc_control/whole_body_model.h"

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/Twist.h>
#include <nav_msgs/Odometry.h>
#include <rm_msgs/JointPos.h>
#include <ros/ros.h>
#include <sensor_msgs/JointState.h>

#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <mutex>
#include <sstream>
#include <thread>

using ehc_realman_test::FakeWater2Server;

namespace {

const std::string kRobotYaml = EHC_CONFIG_DIR "/robots/realman_rm65_water2/robot.yaml";
const std::string kAdapterYaml = EHC_CONFIG_DIR "/realman/rm_arm_adapter.yaml";
const std::string kBridgeYaml = EHC_CONFIG_DIR "/realman/water2_base_bridge.yaml";
constexpr double kDriverMaxStep = 10.0 * M_PI / 180.0;   // rm_driver ignores larger steps
constexpr double kDriverMaxSpeed = 180.0 * M_PI / 180.0;  // rm_driver per-joint bound, rad/s
constexpr double kFloatTol = 2e-6;                        // float32 rounding of JointPos

using ehc_realman_test::now;
using ehc_realman_test::sleepFor;
using ehc_realman_test::waitFor;

struct Frame {
  double time;
  Eigen::VectorXd q;
};

/// Fake rm_driver: checks every JointPos frame, executes it, publishes /joint_states.
class FakeRmDriver {
 public:
  FakeRmDriver(ros::NodeHandle& nh, const ehc_control::RobotConfig& robot, double stream_rate)
      : lower_(robot.arm_lower), upper_(robot.arm_upper), arm_(robot.arm_ready) {
    // Per-frame bound: the driver's 10 deg, and the per-joint speed limit (robot.yaml, never
    // above the driver's 180 deg/s) over one nominal stream period.
    step_ = Eigen::VectorXd(6);
    for (int i = 0; i < 6; ++i)
      step_[i] = std::min(kDriverMaxStep, std::min(robot.arm_velocity[i], kDriverMaxSpeed) / stream_rate);
    names_ = robot.arm_joints;
    js_pub_ = nh.advertise<sensor_msgs::JointState>("/joint_states", 10);
    sub_ = nh.subscribe("/rm_driver/JointPos", 1000, &FakeRmDriver::onFrame, this,
                        ros::TransportHints().tcpNoDelay());
    timer_ = nh.createSteadyTimer(ros::WallDuration(0.01), [this](const ros::SteadyTimerEvent&) {
      sensor_msgs::JointState js;
      js.header.stamp = ros::Time::now();
      js.name = names_;
      std::lock_guard<std::mutex> lock(mutex_);
      js.position.assign(arm_.data(), arm_.data() + arm_.size());
      js_pub_.publish(js);
    });
  }

  void onFrame(const rm_msgs::JointPos::ConstPtr& msg) {
    const double t = now();
    std::lock_guard<std::mutex> lock(mutex_);
    ++frames_;
    std::ostringstream why;
    if (msg->joint.size() != 6) {
      why << "JointPos with " << msg->joint.size() << " joints";
    } else if (!std::isfinite(msg->expand)) {
      why << "JointPos.expand is not finite";
    } else {
      Eigen::VectorXd q(6);
      for (int i = 0; i < 6; ++i) q[i] = msg->joint[static_cast<std::size_t>(i)];
      // The previous frame is where the driver is (it executes each frame exactly).
      for (int i = 0; i < 6; ++i) {
        if (!std::isfinite(q[i])) {
          why << " joint" << i + 1 << " not finite;";
          continue;
        }
        const double step = std::abs(q[i] - arm_[i]);
        max_step_ratio_ = std::max(max_step_ratio_, step / step_[i]);
        if (step > step_[i] + kFloatTol)
          why << " joint" << i + 1 << " step " << step << " rad > " << step_[i] << ";";
        if (q[i] > upper_[i] + kFloatTol || q[i] < lower_[i] - kFloatTol)
          why << " joint" << i + 1 << " at " << q[i] << " outside [" << lower_[i] << ", " << upper_[i] << "];";
      }
      if (why.str().empty()) {
        log_.push_back({t, q});
        arm_ = q;  // the driver follows the set-point
        return;
      }
    }
    ++violations_;  // a real driver would ignore this frame: so does the fake
    if (violations_ <= 20) ADD_FAILURE() << "frame " << frames_ << ":" << why.str();
  }

  std::vector<Frame> framesBetween(double t0, double t1) {
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<Frame> out;
    for (const auto& f : log_)
      if (f.time >= t0 && f.time < t1) out.push_back(f);
    return out;
  }
  Eigen::VectorXd arm() {
    std::lock_guard<std::mutex> lock(mutex_);
    return arm_;
  }
  int frames() {
    std::lock_guard<std::mutex> lock(mutex_);
    return frames_;
  }
  int violations() {
    std::lock_guard<std::mutex> lock(mutex_);
    return violations_;
  }
  double maxStepRatio() {
    std::lock_guard<std::mutex> lock(mutex_);
    return max_step_ratio_;
  }

 private:
  Eigen::VectorXd lower_, upper_, step_;
  std::vector<std::string> names_;
  std::mutex mutex_;
  Eigen::VectorXd arm_;
  std::vector<Frame> log_;
  int frames_ = 0, violations_ = 0;
  double max_step_ratio_ = 0.0;
  ros::Publisher js_pub_;
  ros::Subscriber sub_;
  ros::SteadyTimer timer_;
};

/// Everything the controller and the bridge publish, checked for NaN as it arrives.
struct Monitor {
  std::mutex mutex;
  ehc_msgs::ControllerStatus status;
  int statuses = 0, cmd_vels = 0, arm_cmds = 0, odoms = 0;
  int nan_cmd_vel = 0, nan_arm_cmd = 0, nan_status = 0, nan_odom = 0;
  geometry_msgs::Twist last_cmd_vel;
  double last_odom_time = 0.0;

  void onStatus(const ehc_msgs::ControllerStatus::ConstPtr& s) {
    std::lock_guard<std::mutex> lock(mutex);
    status = *s;
    ++statuses;
    if (!std::isfinite(s->position_error) || !std::isfinite(s->orientation_error) ||
        !std::isfinite(s->error_norm) || !std::isfinite(s->base_weight))
      ++nan_status;
  }
  void onCmdVel(const geometry_msgs::Twist::ConstPtr& t) {
    std::lock_guard<std::mutex> lock(mutex);
    ++cmd_vels;
    last_cmd_vel = *t;
    for (double v : {t->linear.x, t->linear.y, t->linear.z, t->angular.x, t->angular.y, t->angular.z})
      if (!std::isfinite(v)) ++nan_cmd_vel;
  }
  void onArmCmd(const ehc_msgs::JointVelocityCommand::ConstPtr& c) {
    std::lock_guard<std::mutex> lock(mutex);
    ++arm_cmds;
    for (double v : c->velocities)
      if (!std::isfinite(v)) ++nan_arm_cmd;
  }
  void onOdom(const nav_msgs::Odometry::ConstPtr& o) {
    std::lock_guard<std::mutex> lock(mutex);
    ++odoms;
    last_odom_time = now();
    const auto& p = o->pose.pose;
    for (double v : {p.position.x, p.position.y, p.position.z, p.orientation.x, p.orientation.y,
                     p.orientation.z, p.orientation.w, o->twist.twist.linear.x, o->twist.twist.angular.z})
      if (!std::isfinite(v)) ++nan_odom;
  }
  std::string phase() {
    std::lock_guard<std::mutex> lock(mutex);
    return status.phase;
  }
  std::string reason() {
    std::lock_guard<std::mutex> lock(mutex);
    return status.reason;
  }
  double odomAge() {
    std::lock_guard<std::mutex> lock(mutex);
    return now() - last_odom_time;
  }
};

std::unique_ptr<ehc_control::WholeBodyModel> g_model;
std::unique_ptr<FakeRmDriver> g_driver;
FakeWater2Server* g_server = nullptr;
Monitor* g_seen = nullptr;
ros::Publisher g_target;
double g_stream_rate = 100.0;
pid_t g_bridge = -1;         ///< the water2_base_bridge process this test started
bool g_bridge_exited = false;

/// True once the bridge process has exited (reaped here, exactly once).
bool bridgeExited() {
  if (!g_bridge_exited && g_bridge > 0 && ::waitpid(g_bridge, nullptr, WNOHANG) == g_bridge)
    g_bridge_exited = true;
  return g_bridge_exited;
}

/// TCP pose from the fakes' state (ground truth, independent of the controller's inputs).
Eigen::Isometry3d trueTcp() {
  double x, y, th;
  g_server->pose(x, y, th);
  return g_model->fk(Eigen::Vector3d(x, y, th), g_driver->arm(), g_model->config().tcp_frame);
}

geometry_msgs::PoseStamped targetMsg(const Eigen::Isometry3d& T) {
  geometry_msgs::PoseStamped p;
  p.header.frame_id = "odom";
  p.header.stamp = ros::Time::now();
  p.pose.position.x = T.translation().x();
  p.pose.position.y = T.translation().y();
  p.pose.position.z = T.translation().z();
  const Eigen::Quaterniond q(T.linear());
  p.pose.orientation.x = q.x();
  p.pose.orientation.y = q.y();
  p.pose.orientation.z = q.z();
  p.pose.orientation.w = q.w();
  return p;
}

double angleBetween(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle();
}

/// Every JointPos frame of [t0, t_reached) was checked on arrival; the stream's rate and jitter.
void checkJointPosStream(double t0, double t_reached, int frames_before) {
  // Every JointPos frame was checked on arrival (FakeRmDriver::onFrame); none broke a limit.
  const auto frames = g_driver->framesBetween(t0, t_reached);
  ASSERT_GE(frames.size(), 100u) << "the arm was streamed to while the controller ran";
  EXPECT_GT(g_driver->frames() - frames_before, 0);
  EXPECT_EQ(g_driver->violations(), 0);
  EXPECT_LE(g_driver->maxStepRatio(), 1.0 + 1e-3) << "largest step / per-frame bound";
  bool arm_moved = false;
  for (std::size_t k = 1; k < frames.size() && !arm_moved; ++k) arm_moved = !(frames[k].q == frames[0].q);
  EXPECT_TRUE(arm_moved);
  // Rate and jitter, measured over every frame of the approach (generous under CI load).
  std::vector<double> dt;
  for (std::size_t k = 1; k < frames.size(); ++k) dt.push_back(frames[k].time - frames[k - 1].time);
  std::sort(dt.begin(), dt.end());
  const double period = 1.0 / g_stream_rate;
  EXPECT_NEAR(dt[dt.size() / 2], period, 0.5 * period) << "median JointPos period";
  EXPECT_LT(dt[dt.size() * 95 / 100], 0.1) << "95th percentile JointPos period";
  const double mean_rate = (frames.size() - 1) / (frames.back().time - frames.front().time);
  EXPECT_GT(mean_rate, 0.5 * g_stream_rate);
  testing::Test::RecordProperty("jointpos_frames", static_cast<int>(frames.size()));
  testing::Test::RecordProperty("jointpos_max_step_over_bound", std::to_string(g_driver->maxStepRatio()));
  testing::Test::RecordProperty("jointpos_median_period_ms", std::to_string(1e3 * dt[dt.size() / 2]));
  testing::Test::RecordProperty("jointpos_p95_period_ms", std::to_string(1e3 * dt[dt.size() * 95 / 100]));
}

/// Every joy_control request of [t0, t_reached): finite, inside the Water2 bounds, resent often.
void checkJoyControls(double t0, double t_reached) {
  // Every joy_control request: finite and inside the Water2 bounds; resent >= 10 Hz on average.
  int joys = 0, moving = 0;
  for (const auto& r : g_server->requests()) {
    if (!r.joy || r.time < t0 || r.time >= t_reached) continue;
    ++joys;
    EXPECT_TRUE(std::isfinite(r.linear) && std::isfinite(r.angular)) << r.text;
    EXPECT_LE(std::abs(r.linear), 0.5 + 1e-9) << r.text;
    EXPECT_LE(std::abs(r.angular), 1.0 + 1e-9) << r.text;
    moving += r.linear != 0.0 || r.angular != 0.0;
  }
  EXPECT_GT(moving, 0);
  EXPECT_GE(joys / std::max(1e-3, t_reached - t0), 10.0) << joys << " joy_control requests";
}

/// Without a target the whole chain comes to rest.
void checkChainComesToRest() {
  // Target no longer published: the controller stops (TARGET_LOST, zero commands), the adapter
  // holds, the bridge sends zero. After a settling second the whole chain is at rest.
  ASSERT_TRUE(waitFor([] { return g_seen->phase() == "TARGET_LOST"; }, 5.0)) << g_seen->phase();
  sleepFor(1.5);
  const double t_rest = now();
  double rx0, ry0, rth0;
  g_server->pose(rx0, ry0, rth0);
  sleepFor(2.0);
  const auto rest = g_driver->framesBetween(t_rest, now());
  for (const auto& f : rest) EXPECT_TRUE(f.q == rest.front().q) << "arm moved without a target";
  int rest_joys = 0;
  for (const auto& r : g_server->requests()) {
    if (!r.joy || r.time < t_rest) continue;
    ++rest_joys;
    EXPECT_EQ(r.linear, 0.0) << r.text;
    EXPECT_EQ(r.angular, 0.0) << r.text;
  }
  double rx1, ry1, rth1;
  g_server->pose(rx1, ry1, rth1);
  EXPECT_NEAR(rx1, rx0, 1e-6);
  EXPECT_NEAR(ry1, ry0, 1e-6);
  EXPECT_NEAR(rth1, rth0, 1e-6);
  EXPECT_EQ(g_driver->violations(), 0);
  EXPECT_FALSE(bridgeExited()) << "water2_base_bridge died during the run";
}

/// Nothing was NaN anywhere in the loop.
void checkNothingWasNan() {
  std::lock_guard<std::mutex> lock(g_seen->mutex);
  EXPECT_GT(g_seen->cmd_vels, 0);
  EXPECT_GT(g_seen->arm_cmds, 0);
  EXPECT_GT(g_seen->odoms, 0);
  EXPECT_EQ(g_seen->nan_cmd_vel, 0);
  EXPECT_EQ(g_seen->nan_arm_cmd, 0);
  EXPECT_EQ(g_seen->nan_status, 0);
  EXPECT_EQ(g_seen->nan_odom, 0);
}

}  // namespace

TEST(RealmanClosedLoop, ControllerReachesTargetThroughAdaptersAndEveryFrameObeysTheLimits) {
  // Bounded start-up: the controller runs on its timer with fresh /joint_states and /odom
  // (IDLE: no target yet), the adapter streams, the target topic is connected.
  const bool ready = waitFor([] {
    return g_seen->phase() == "IDLE" && g_driver->frames() > 10 && g_target.getNumSubscribers() > 0 &&
           g_seen->odomAge() < 0.5;
  }, 60.0);
  ASSERT_TRUE(ready) << "loop not up within 60 s: controller phase '" << g_seen->phase() << "' reason '"
                     << g_seen->reason() << "', " << g_driver->frames() << " JointPos frames, /odom "
                     << g_seen->odomAge() << " s old, bridge "
                     << (bridgeExited() ? "exited" : "alive");
  sleepFor(0.5);
  // Target 1.5 m ahead (beyond the arm's 0.61 m reach: the base must drive), approached 45 deg
  // downwards along +x, as in the simulated controller test.
  Eigen::Isometry3d target = Eigen::Isometry3d::Identity();
  target.translation() << 1.5, 0.3, 0.8;
  target.linear() = Eigen::AngleAxisd(0.75 * M_PI, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const Eigen::Isometry3d tcp0 = trueTcp();
  const double e0 = (target.translation() - tcp0.translation()).norm();
  ASSERT_GT(e0, 0.8) << "the target must start far away";
  ASSERT_TRUE(waitFor([] { return g_seen->phase() == "IDLE"; }, 10.0))
      << "inputs fresh, no target yet: phase " << g_seen->phase() << ", " << g_seen->reason();

  // Drive: publish the target at 20 Hz (as perception would) until the fakes' TCP is within
  // 2 cm (the controller's arrival is 1 cm), at most 120 s of wall time.
  const int frames_before = g_driver->frames();
  const double t0 = now();
  double e = e0, e_min = e0;
  std::vector<std::pair<double, double>> trace;  // (t, error), every 0.5 s for the report
  double next_trace = t0;
  while (now() - t0 < 120.0) {
    g_target.publish(targetMsg(target));
    e = (target.translation() - trueTcp().translation()).norm();
    e_min = std::min(e_min, e);
    if (now() >= next_trace) {
      trace.emplace_back(now() - t0, e);
      next_trace += 0.5;
    }
    if (e < 0.02) break;
    sleepFor(0.05);
  }
  const double t_reached = now();
  // Keep the target a little longer: the controller must hold it, not drift away.
  while (now() - t_reached < 2.0) {
    g_target.publish(targetMsg(target));
    sleepFor(0.05);
  }
  const Eigen::Isometry3d tcp1 = trueTcp();
  const double e_end = (target.translation() - tcp1.translation()).norm();
  std::ostringstream tr;
  for (const auto& p : trace) tr << " " << p.first << "s:" << p.second;
  EXPECT_LT(e, 0.05) << "TCP error " << e << " m after " << t_reached - t0 << " s (start " << e0
                     << " m); trace:" << tr.str();
  EXPECT_LT(e_end, 0.05) << "TCP drifted away from the target while it was held";
  EXPECT_LT(e_end, 0.1 * e0);
  EXPECT_LT(angleBetween(target, tcp1), 10.0 * M_PI / 180.0) << "orientation error";
  RecordProperty("seconds_to_2cm", std::to_string(t_reached - t0));
  RecordProperty("final_error_m", std::to_string(e_end));
  RecordProperty("final_orientation_error_deg", std::to_string(angleBetween(target, tcp1) * 180.0 / M_PI));
  std::printf("[realman_closed_loop] error %.3f m -> %.4f m in %.1f s, orientation error %.2f deg, "
              "phase %s\n", e0, e_end, t_reached - t0, angleBetween(target, tcp1) * 180.0 / M_PI,
              g_seen->phase().c_str());

  // The base drove the Water2 (through joy_control) towards the target.
  double bx, by, bth;
  g_server->pose(bx, by, bth);
  EXPECT_GT(bx, 0.3) << "base pose (" << bx << ", " << by << ", " << bth << ")";

  checkJointPosStream(t0, t_reached, frames_before);
  checkJoyControls(t0, t_reached);
  checkChainComesToRest();
  checkNothingWasNan();
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_realman_closed_loop");
  ros::NodeHandle nh;
  ros::AsyncSpinner spinner(2);
  spinner.start();

  const ehc_control::RobotConfig robot = ehc_control::loadRobotConfig(kRobotYaml);
  g_model = std::make_unique<ehc_control::WholeBodyModel>(robot);
  g_stream_rate = ehc_realman::loadRmArmAdapterConfig(kAdapterYaml).stream.rate_hz;
  g_driver = std::make_unique<FakeRmDriver>(nh, robot, g_stream_rate);
  FakeWater2Server server;  // 127.0.0.1, free port
  server.start();
  g_server = &server;
  Monitor seen;
  g_seen = &seen;
  std::vector<ros::Subscriber> subs;
  subs.push_back(nh.subscribe("/ehc/status", 100, &Monitor::onStatus, &seen));
  subs.push_back(nh.subscribe("/cmd_vel", 100, &Monitor::onCmdVel, &seen));
  subs.push_back(nh.subscribe("/arm/joint_velocity_cmd", 100, &Monitor::onArmCmd, &seen));
  subs.push_back(nh.subscribe("/odom", 100, &Monitor::onOdom, &seen));
  g_target = nh.advertise<geometry_msgs::PoseStamped>("/ehc/target_pose", 10);

  // Run the bridge node with the robot's own configuration, pointed at the fake server.
  const std::string a_config = "_config:=" + kBridgeYaml;
  const std::string a_host = "_host:=127.0.0.1";
  const std::string a_port = "_port:=" + std::to_string(server.port());
  const std::string a_name = "__name:=water2_base_bridge";
  g_bridge = ::fork();
  if (g_bridge == 0) {
    ::execl(WATER2_BRIDGE_BIN, WATER2_BRIDGE_BIN, a_config.c_str(), a_host.c_str(), a_port.c_str(),
            a_name.c_str(), static_cast<char*>(nullptr));
    std::_Exit(127);
  }
  int rc = 1;
  if (g_bridge < 0) {
    std::fprintf(stderr, "test_realman_closed_loop: fork failed\n");
  } else {
    rc = RUN_ALL_TESTS();
    if (!bridgeExited()) {
      ::kill(g_bridge, SIGINT);  // our own child, by its pid
      if (!waitFor(bridgeExited, 10.0)) {
        ::kill(g_bridge, SIGKILL);
        ::waitpid(g_bridge, nullptr, 0);
      }
    }
  }
  server.stop();
  subs.clear();
  g_driver.reset();
  spinner.stop();
  return rc;
}
