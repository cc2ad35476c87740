// rm_arm_adapter: /arm/joint_velocity_cmd (ehc_msgs/JointVelocityCommand) -> a stable
// /rm_driver/JointPos stream for the RealMan rm_driver (ROS 1), with speed/step/joint-limit
// clamping, command timeout (hold, then stop), a latched emergency stop and gripper requests.
// Thin wrapper: parameters, message conversion and timing only; the logic is
// ehc_realman::JointPositionStreamer.
//
//   rosrun ehc_realman rm_arm_adapter _config:=config/realman/rm_arm_adapter.yaml
//
// Subscribes: /joint_states (sensor_msgs/JointState), /arm/joint_velocity_cmd,
//   /arm/emergency_stop (std_msgs/Bool, true latches), /arm/emergency_stop_reset (std_msgs/Empty),
//   /arm/gripper/command (std_msgs/String: open|close|pick), /arm/gripper/width (std_msgs/Float64, m)
// Service: /arm/gripper/set (std_srvs/SetBool: true = "pick", false = "open"; the grasp
//   sequencer's gripper_service)
// Publishes: /rm_driver/JointPos, /rm_driver/Emergency_Stop (latched), /rm_driver/Gripper_Set,
//   /rm_driver/Gripper_Pick, /arm/adapter_status (diagnostic_msgs/DiagnosticStatus; key
//   "last_step": the node-clock time of the last stream step)
// Clock (node_clock.h): steady on the robot; ROS time under /use_sim_time, the stream then steps
// on a ROS timer as /clock advances. `_status_every_step:=true` publishes the status after every
// stream step and after every command (a lock-step test's handshake: "frames" says what that
// step published, "commands" + "rejected_commands" that a command was taken).

#include "ehc_common/logging.h"
#include "ehc_common/node_init.h"
#include "ehc_realman/realman_adapter_config.h"
#include "ehc_realman/realman_joint_streamer.h"
#include "diagnostics.h"
#include "node_clock.h"

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
#include <std_srvs/SetBool.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <mutex>
#include <thread>

namespace {

using ehc_common::kLogThrottle;

using SteadyClock = std::chrono::steady_clock;
using ehc_realman_nodes::nodeNow;

using ehc_realman_nodes::kv;

class RmArmAdapterNode {
 public:
  RmArmAdapterNode(ros::NodeHandle& nh, const ehc_realman::RmArmAdapterConfig& config,
                   bool status_every_step)
      : config_(config), streamer_(config.stream, config.limits), status_every_step_(status_every_step) {
    ROS_INFO_STREAM("rm_arm_adapter effective limits:\n" << streamer_.summary());
    joint_pos_pub_ = nh.advertise<rm_msgs::JointPos>("/rm_driver/JointPos", 10);
    estop_pub_ = nh.advertise<rm_msgs::Stop>("/rm_driver/Emergency_Stop", 1, /*latch=*/true);
    gripper_set_pub_ = nh.advertise<rm_msgs::Gripper_Set>("/rm_driver/Gripper_Set", 10);
    gripper_pick_pub_ = nh.advertise<rm_msgs::Gripper_Pick>("/rm_driver/Gripper_Pick", 10);
    status_pub_ = nh.advertise<diagnostic_msgs::DiagnosticStatus>("/arm/adapter_status", 1, true);
    auto hints = ros::TransportHints().tcpNoDelay();
    subs_.push_back(nh.subscribe("/joint_states", 10, &RmArmAdapterNode::onJointState, this, hints));
    subs_.push_back(nh.subscribe("/arm/joint_velocity_cmd", 10, &RmArmAdapterNode::onCommand, this, hints));
    subs_.push_back(nh.subscribe("/arm/emergency_stop", 10, &RmArmAdapterNode::onEmergencyStop, this));
    subs_.push_back(nh.subscribe("/arm/emergency_stop_reset", 10, &RmArmAdapterNode::onReset, this));
    subs_.push_back(nh.subscribe("/arm/gripper/command", 10, &RmArmAdapterNode::onGripperCommand, this));
    subs_.push_back(nh.subscribe("/arm/gripper/width", 10, &RmArmAdapterNode::onGripperWidth, this));
    gripper_srv_ = nh.advertiseService("/arm/gripper/set", &RmArmAdapterNode::onGripperSet, this);
    status_timer_ = ehc_realman_nodes::NodeTimer(nh, 1.0 / config_.status_rate_hz,
                                                 [this] { publishStatus(); });
    if (ros::Time::isSimTime())
      stream_timer_ = ehc_realman_nodes::NodeTimer(nh, streamer_.period(), [this] { streamStep(); });
    else
      stream_thread_ = std::thread([this] { streamLoop(); });
  }

  ~RmArmAdapterNode() {
    running_ = false;
    if (stream_thread_.joinable()) stream_thread_.join();
  }

 private:
  void onJointState(const sensor_msgs::JointState::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    try {
      streamer_.setMeasured(msg->name, msg->position, nodeNow());
    } catch (const std::exception& e) {
      ROS_ERROR_THROTTLE(kLogThrottle, "rm_arm_adapter: %s", e.what());
    }
  }

  void onCommand(const ehc_msgs::JointVelocityCommand::ConstPtr& msg) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      try {
        streamer_.setVelocityCommand(msg->names, msg->velocities, nodeNow());
      } catch (const std::exception& e) {
        ROS_ERROR_THROTTLE(kLogThrottle, "rm_arm_adapter: %s", e.what());
      }
    }
    if (status_every_step_) publishStatus();  // the command's receipt, for a lock-step test
  }

  void onEmergencyStop(const std_msgs::Bool::ConstPtr& msg) {
    if (!msg->data) return;  // only a reset (/arm/emergency_stop_reset) clears the latch
    bool first = false;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      first = !streamer_.emergencyStopped();
      streamer_.emergencyStop();
    }
    rm_msgs::Stop stop;
    stop.state = true;
    estop_pub_.publish(stop);
    if (first) ROS_ERROR("rm_arm_adapter: EMERGENCY STOP latched; JointPos stream stopped");
    publishStatus();
  }

  void onReset(const std_msgs::Empty::ConstPtr&) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!streamer_.emergencyStopped()) return;
      streamer_.resetEmergencyStop();
    }
    ROS_WARN("rm_arm_adapter: emergency stop reset; streaming resumes on the next command");
    publishStatus();
  }

  void publishGripper(const ehc_realman::GripperRequest& r) {
    if (r.kind == ehc_realman::GripperRequest::Kind::Set) {
      rm_msgs::Gripper_Set m;
      m.position = r.position;
      gripper_set_pub_.publish(m);
      ROS_INFO("rm_arm_adapter: Gripper_Set position %u", static_cast<unsigned>(r.position));
    } else {
      rm_msgs::Gripper_Pick m;
      m.speed = r.speed;
      m.force = r.force;
      gripper_pick_pub_.publish(m);
      ROS_INFO("rm_arm_adapter: Gripper_Pick speed %u force %u", static_cast<unsigned>(r.speed),
               static_cast<unsigned>(r.force));
    }
  }

  void onGripperCommand(const std_msgs::String::ConstPtr& msg) {
    try {
      publishGripper(ehc_realman::gripperRequestFromCommand(msg->data, config_.gripper));
    } catch (const std::exception& e) {
      ROS_ERROR_THROTTLE(kLogThrottle, "rm_arm_adapter: %s", e.what());
    }
  }

  void onGripperWidth(const std_msgs::Float64::ConstPtr& msg) {
    try {
      publishGripper(ehc_realman::gripperRequestFromWidth(msg->data, config_.gripper));
    } catch (const std::exception& e) {
      ROS_ERROR_THROTTLE(kLogThrottle, "rm_arm_adapter: %s", e.what());
    }
  }

  /// The grasp sequencer's gripper service: close = "pick" (grip with force), open = "open".
  bool onGripperSet(std_srvs::SetBool::Request& req, std_srvs::SetBool::Response& res) {
    try {
      publishGripper(ehc_realman::gripperRequestFromCommand(req.data ? "pick" : "open", config_.gripper));
      res.success = true;
      res.message = req.data ? "pick" : "open";
    } catch (const std::exception& e) {
      res.success = false;
      res.message = e.what();
      ROS_ERROR_THROTTLE(kLogThrottle, "rm_arm_adapter: %s", e.what());
    }
    return true;
  }

  /// Fixed-period loop on the steady clock (sleep_until keeps the period free of drift).
  void streamLoop() {
    const auto period = std::chrono::duration_cast<SteadyClock::duration>(
        std::chrono::duration<double>(streamer_.period()));
    auto next = SteadyClock::now() + period;
    while (running_ && ros::ok()) {
      std::this_thread::sleep_until(next);
      next += period;
      const auto now = SteadyClock::now();
      if (now > next + 10 * period) next = now + period;  // after a stall: do not burst frames
      streamStep();
    }
  }

  /// One stream period: the streamer's frame (if any) to /rm_driver/JointPos.
  void streamStep() {
    std::optional<ehc_realman::JointFrame> frame;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      const double now = nodeNow();
      // One step per instant of the clock: a ROS timer may fire twice when /clock jumps (the
      // first /clock message under /use_sim_time); the steady clock always advances.
      if (now <= last_step_time_) return;
      last_step_time_ = now;
      frame = streamer_.step(now);
    }
    if (frame) {
      rm_msgs::JointPos msg;
      msg.expand = 0.0f;
      msg.joint.resize(static_cast<std::size_t>(frame->position.size()));
      for (Eigen::Index i = 0; i < frame->position.size(); ++i)
        msg.joint[static_cast<std::size_t>(i)] = static_cast<float>(frame->position[i]);
      joint_pos_pub_.publish(msg);
      if (frame->limit_clamped)
        ROS_WARN_THROTTLE(kLogThrottle, "rm_arm_adapter: joint limit reached, motion clamped");
      if (frame->tracking_clamped)
        ROS_WARN_THROTTLE(kLogThrottle, "rm_arm_adapter: arm lags the command by more than %.3f rad, "
                               "command clamped", config_.stream.max_tracking_error);
      if (frame->speed_clamped)
        ROS_WARN_THROTTLE(kLogThrottle, "rm_arm_adapter: velocity command above the speed limits, scaled");
    }
    if (status_every_step_) publishStatus();
  }

  void publishStatus() {
    diagnostic_msgs::DiagnosticStatus s;
    s.name = "rm_arm_adapter";
    s.hardware_id = "rm_driver";
    ehc_realman::JointStreamerCounters c;
    ehc_realman::StreamPhase phase;
    double last_step = NAN;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      c = streamer_.counters();
      phase = streamer_.phase();
      last_step = last_step_time_;
    }
    char last_step_text[32];
    std::snprintf(last_step_text, sizeof(last_step_text), "%.9f", last_step);
    if (phase == ehc_realman::StreamPhase::EmergencyStopped) {
      s.level = diagnostic_msgs::DiagnosticStatus::ERROR;
      s.message = "emergency stop latched";
    } else if (phase == ehc_realman::StreamPhase::Holding) {
      s.level = diagnostic_msgs::DiagnosticStatus::WARN;
      s.message = "command or joint state timed out: holding";
    } else {
      s.level = diagnostic_msgs::DiagnosticStatus::OK;
      s.message = ehc_realman::toString(phase);
    }
    s.values = {kv("phase", ehc_realman::toString(phase)), kv("frames", std::to_string(c.frames)),
                kv("speed_clamped", std::to_string(c.speed_clamped)),
                kv("step_clamped", std::to_string(c.step_clamped)),
                kv("limit_clamped", std::to_string(c.limit_clamped)),
                kv("tracking_clamped", std::to_string(c.tracking_clamped)),
                kv("commands", std::to_string(c.commands)),
                kv("rejected_commands", std::to_string(c.rejected_commands)),
                kv("rejected_states", std::to_string(c.rejected_states)),
                kv("timeouts", std::to_string(c.timeouts)), kv("last_step", last_step_text)};
    status_pub_.publish(s);
  }

  ehc_realman::RmArmAdapterConfig config_;
  std::mutex mutex_;
  ehc_realman::JointPositionStreamer streamer_;
  ros::Publisher joint_pos_pub_, estop_pub_, gripper_set_pub_, gripper_pick_pub_, status_pub_;
  std::vector<ros::Subscriber> subs_;
  ros::ServiceServer gripper_srv_;
  const bool status_every_step_;
  double last_step_time_ = -std::numeric_limits<double>::infinity();  ///< node clock, s; mutex_
  ehc_realman_nodes::NodeTimer status_timer_, stream_timer_;
  std::atomic<bool> running_{true};
  std::thread stream_thread_;
};

}  // namespace

int main(int argc, char** argv) {
  return ehc_common::runNode(argc, argv, "rm_arm_adapter", 2, [](const ehc_common::NodeParams& params, ros::NodeHandle& nh) {
    const auto config = ehc_realman::loadRmArmAdapterConfig(params.requireText("config", "<rm_arm_adapter.yaml>"));
    const bool status_every_step = params.get("status_every_step", false);
    ehc_common::checkNodeParams(params);
    ROS_INFO_STREAM("rm_arm_adapter configuration:\n" << config.summary() << "\nclock: "
                    << (ros::Time::isSimTime() ? "ROS time (/use_sim_time)" : "steady")
                    << (status_every_step ? ", status after every stream step" : ""));
    auto node = std::make_unique<RmArmAdapterNode>(nh, config, status_every_step);
    ros::spin();
    node.reset();
    return 0;
  });
}
