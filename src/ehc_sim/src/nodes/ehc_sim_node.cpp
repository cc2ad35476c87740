// ehc_sim_node: the Bullet-backed fake robot (ROS wrapper of ehc_sim::SimWorld,
// SimulatedCamera and StepScheduler, the stepping policy it shares with ehc_kinematic_sim_node).
//
//   rosrun ehc_sim ehc_sim_node _config:=config/sim/bullet_sim.yaml
//       [_scene:=config/scenes/table_three_objects.yaml] [_free_run:=true] [_seed:=N]
//
// Lock-step (default): publishes /clock and the state stamped t, waits for the
// JointVelocityCommand stamped t and a /cmd_vel received since the last step, then advances
// one step of sim.dt (never on a timeout; a state nobody answered is resent every
// sim.state_republish_period wall seconds). Free-run: steps every sim.dt of wall time with the
// latest commands (zeroed after sim.command_timeout without a fresh one). Both policies:
// ehc_sim::StepScheduler. Sim time starts at 1 s.
//
// Publishes /clock, /joint_states, /odom, /tf (odom -> base_link and every URDF link; /odom and
// odom -> base_link from the base model's odometry: sim.base_model water2 = the Water2 bridge's),
// /camera/color/image_raw (mono8) + /camera/color/camera_info, /camera/depth/points,
// /sim/object_poses (ground truth, metrics only), /sim/status.
// Subscribes /cmd_vel, /arm/joint_velocity_cmd, /sim/lockstep_ack (std_msgs/Header: frame_id
// = the acknowledging node's name, stamp = the frame it is done with; the lock-step
// acknowledgement gate of the nodes outside the controller's handshake, private parameters
// _lockstep_acks:="[node[:image|cloud|state], ...]" (default stream image) and
// _lockstep_max_lag:=<s>, default 0; see ehc_sim::StepScheduler). Services /sim/reset (ehc_msgs/ResetScene),
// /sim/gripper (std_srvs/SetBool: true = close, false = open).

#include "lock_step_node.h"
#include "sim_camera_streams.h"
#include "sim_ros_conversions.h"

#include "ehc_common/node_init.h"
#include "ehc_msgs/ResetScene.h"

#include <ros/ros.h>
#include <std_msgs/Header.h>
#include <std_srvs/SetBool.h>
#include <tf2_msgs/TFMessage.h>

#include <memory>

namespace {

using ehc_common::kLogThrottle;

class SimNode {
 public:
  SimNode(ros::NodeHandle& nh, const ehc_common::NodeParams& params) : nh_(nh), setup_(params, "ehc_sim_node") {
    const ehc_control::RobotConfig& robot = setup_.robot;
    world_ = std::make_unique<ehc_sim::SimWorld>(setup_.cfg, robot, setup_.scene);
    camera_ = std::make_unique<ehc_sim::SimCameraStreams>(nh_, setup_, *world_);

    lock_step_ = std::make_unique<ehc_sim::LockStepNode>(nh_, "ehc_sim_node", robot, setup_.cfg.fake_robot);
    clock_pub_ = nh_.advertise<rosgraph_msgs::Clock>("/clock", 10);
    joint_pub_ = nh_.advertise<sensor_msgs::JointState>("/joint_states", 10);
    odom_pub_ = nh_.advertise<nav_msgs::Odometry>("/odom", 10);
    tf_pub_ = nh_.advertise<tf2_msgs::TFMessage>("/tf", 100);
    objects_pub_ = nh_.advertise<ehc_msgs::SimObjectPoses>("/sim/object_poses", 10);
    status_pub_ = nh_.advertise<ehc_msgs::SimStatus>("/sim/status", 10);
    // A YAML list, or one string of specs (rosrun _lockstep_acks:=[a,b:cloud]: roscpp keeps it a string).
    const ehc_sim::AckGateConfig gate =
        ehc_sim::parseAckGate(params.getList("lockstep_acks"), params.get("lockstep_max_lag", 0.0));
    if (!gate.nodes.empty()) {
      lock_step_->scheduler().setAckGate(gate.nodes, gate.maxLagNs());
      ROS_INFO_STREAM("[ehc_sim_node] lock-step acknowledgement gate on /sim/lockstep_ack:"
                      << gate.summary() << "; sim time passes a frame by at most " << gate.max_lag
                      << " s before they are done with it");
    }
    ack_sub_ = nh_.subscribe("/sim/lockstep_ack", 50, &SimNode::onAck, this, ros::TransportHints().tcpNoDelay());
    reset_srv_ = nh_.advertiseService("/sim/reset", &SimNode::onReset, this);
    gripper_srv_ = nh_.advertiseService("/sim/gripper", &SimNode::onGripper, this);
  }

  void run() {
    if (!lock_step_->waitForAckGate()) return;  // every node of the gate sees the first state
    publishState(true);
    lock_step_->run([this] { step(); }, [this] { publishState(false); });
  }

 private:
  void step() {
    const ehc_sim::StepReport& r = world_->step(lock_step_->scheduler().command());
    if (r.robot_world_collision || r.self_collision)
      ROS_WARN_STREAM_THROTTLE(kLogThrottle, "[ehc_sim_node] collision: " << r.collisions.front().a << " | "
                                                                   << r.collisions.front().b);
    publishState(true);
  }

  /// Publishes /clock, the camera (when due), the state and the status for the current time.
  void publishState(bool fresh) {
    const std::int64_t t_ns = world_->timeNs();
    const ros::Time stamp = ehc_sim::rosStamp(t_ns);
    rosgraph_msgs::Clock clock;
    clock.clock = stamp;
    clock_pub_.publish(clock);
    if (fresh) {
      camera_->publishDue(*world_, t_ns, stamp, [this](ehc_sim::AckStream stream, std::int64_t stamp_ns) {
        lock_step_->scheduler().framePublished(stream, stamp_ns);
      });
    }
    sensor_msgs::JointState js;
    ehc_sim::fillJointState(world_->robot(), stamp, &js);
    nav_msgs::Odometry odom;
    ehc_sim::fillOdometry(world_->robot(), stamp, &odom);
    tf2_msgs::TFMessage tf;
    ehc_sim::fillTransforms(*world_, stamp, &tf.transforms);
    tf_pub_.publish(tf);
    odom_pub_.publish(odom);
    ehc_msgs::SimObjectPoses objects;
    ehc_sim::fillObjectPoses(*world_, stamp, &objects);
    objects_pub_.publish(objects);
    ehc_msgs::SimStatus status;
    const ehc_sim::StepScheduler& scheduler = lock_step_->scheduler();
    ehc_sim::fillStatus(*world_, scheduler.gate(), scheduler.lockStep(), stamp, &status);
    status_pub_.publish(status);
    lock_step_->statePublished(stamp, fresh);
    joint_pub_.publish(js);  // last: the controller answers this one
  }

  bool onReset(ehc_msgs::ResetScene::Request& req, ehc_msgs::ResetScene::Response& res) {
    try {
      if (!req.scene_file.empty()) {
        const ehc_sim::SceneConfig scene = ehc_sim::loadSceneConfig(req.scene_file);
        world_->setScene(scene, req.seed);
        camera_->reset(*world_, &scene, req.seed);
      } else {
        world_->reset(req.seed);
        camera_->reset(*world_, nullptr, req.seed);
      }
      lock_step_->scheduler().reset();
      res.success = true;
      res.message = "scene '" + world_->scene().name + "' reset with seed " + std::to_string(req.seed);
      ROS_INFO_STREAM("[ehc_sim_node] " << res.message);
      publishState(true);
    } catch (const std::exception& e) {
      res.success = false;
      res.message = e.what();
      ROS_ERROR_STREAM("[ehc_sim_node] reset failed, scene unchanged: " << e.what());
    }
    return true;
  }

  void onAck(const std_msgs::Header& m) {
    const std::string why = lock_step_->scheduler().onAck(m.frame_id, static_cast<std::int64_t>(m.stamp.toNSec()));
    if (!why.empty()) ROS_WARN_STREAM_THROTTLE(kLogThrottle, "[ehc_sim_node] /sim/lockstep_ack ignored: " << why);
  }

  bool onGripper(std_srvs::SetBool::Request& req, std_srvs::SetBool::Response& res) {
    world_->commandGripper(req.data);
    res.success = true;
    using ehc_control::GripperState;
    res.message = ehc_control::toString(req.data ? GripperState::Closing : GripperState::Opening) + " (state " +
                  ehc_control::toString(world_->gripper().state()) + ")";
    return true;
  }

  ros::NodeHandle nh_;
  ehc_sim::BulletNodeSetup setup_;
  std::unique_ptr<ehc_sim::SimWorld> world_;
  std::unique_ptr<ehc_sim::SimCameraStreams> camera_;  ///< camera.image_rate / cloud_rate on sim time
  std::unique_ptr<ehc_sim::LockStepNode> lock_step_;  ///< callback queue, commands, stepping loop
  ros::Subscriber ack_sub_;  ///< /sim/lockstep_ack (lock-step acknowledgement gate)
  ros::Publisher clock_pub_, joint_pub_, odom_pub_, tf_pub_, objects_pub_, status_pub_;
  ros::ServiceServer reset_srv_, gripper_srv_;
};

}  // namespace

int main(int argc, char** argv) {
  return ehc_common::runNode(argc, argv, "ehc_sim_node", 1, [](const ehc_common::NodeParams& params, ros::NodeHandle& nh) {
    SimNode node(nh, params);
    ehc_common::checkNodeParams(params);
    node.run();
    return 0;
  });
}
