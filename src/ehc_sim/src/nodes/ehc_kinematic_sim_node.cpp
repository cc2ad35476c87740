// ehc_kinematic_sim_node: the noisy kinematic fake robot (ehc_sim::KinematicFakeRobot) as a
// ROS node with a lock-step /clock, for controller tests and tools (no physics, no camera, no
// gripper; the Bullet simulator is ehc_sim_node).
//
//   rosrun ehc_sim ehc_kinematic_sim_node _config:=config/sim/kinematic_sim.yaml
//       [_robot:=robot.yaml] [_free_run:=true] [_seed:=N]
//
// Same contract, configuration schema (ehc_sim::FakeRobotConfig: sim.robot, dt, seed,
// free_run, state_republish_period, command_timeout, noise, base_model, water2, robot_start) and
// stepping policy
// (ehc_sim::StepScheduler around ehc_sim::CommandGate) as ehc_sim_node. Lock-step (default):
// publishes /clock and the state stamped t, waits for the JointVelocityCommand stamped t and a
// /cmd_vel received since the last step, then advances one step of sim.dt; sim time never
// advances on a timeout (a state nobody answered is resent every sim.state_republish_period
// wall seconds). A NaN / wrongly sized / over-limit command is rejected, counted on
// /sim/status and executed as zero for its group. Free-run: steps every sim.dt of wall time.
// Sim time starts at 1 s.
//
// Publishes /clock, /joint_states, /odom and /tf (odom -> base_link) from the base model's
// odometry (water2: the ~2 Hz status dead-reckoned, as the Water2 bridge), /sim/status (step, mode and
// command counters; no collision or gripper fields). Subscribes /cmd_vel,
// /arm/joint_velocity_cmd.

#include "lock_step_node.h"
#include "sim_ros_conversions.h"

#include "ehc_sim/fake_robot_config.h"
#include "ehc_sim/kinematic_fake_robot.h"
#include "ehc_common/node_init.h"
#include "ehc_control/whole_body_model.h"

#include <ros/ros.h>
#include <tf2_msgs/TFMessage.h>

#include <memory>

namespace {

class KinematicSimNode {
 public:
  KinematicSimNode(ros::NodeHandle& nh, const ehc_common::NodeParams& params) : nh_(nh) {
    const std::string config_file = params.requireText("config", "<sim.yaml>");
    cfg_ = ehc_sim::loadFakeRobotConfigFile(config_file);
    ehc_sim::applyNodeOverrides(params, &cfg_);
    const ehc_control::RobotConfig robot = ehc_control::loadRobotConfig(cfg_.robot_file);
    ehc_control::WholeBodyModel check(robot);  // robot.yaml against its URDF: arm joints, calibration joints, frames
    ROS_INFO_STREAM("[ehc_kinematic_sim_node] start-up configuration (" << config_file << ")\n"
                    << cfg_.summary() << robot.summary());

    robot_ = std::make_unique<ehc_sim::KinematicFakeRobot>(robot, cfg_.noise, cfg_.seed, cfg_.base_model);
    robot_->reset(cfg_.robot_start, robot.arm_ready, cfg_.seed);
    lock_step_ = std::make_unique<ehc_sim::LockStepNode>(nh_, "ehc_kinematic_sim_node", robot, cfg_);
    clock_pub_ = nh_.advertise<rosgraph_msgs::Clock>("/clock", 10);
    joint_pub_ = nh_.advertise<sensor_msgs::JointState>("/joint_states", 10);
    odom_pub_ = nh_.advertise<nav_msgs::Odometry>("/odom", 10);
    tf_pub_ = nh_.advertise<tf2_msgs::TFMessage>("/tf", 100);
    status_pub_ = nh_.advertise<ehc_msgs::SimStatus>("/sim/status", 10);
  }

  void run() {
    publishState(true);
    lock_step_->run([this] { step(); }, [this] { publishState(false); });
  }

 private:
  void step() {
    robot_->step(lock_step_->scheduler().command(), cfg_.dt);  // the gate passes finite, right-sized commands only
    ++steps_;
    publishState(true);
  }

  /// Publishes /clock, the state and the status for the current sim time.
  void publishState(bool fresh) {
    const ros::Time stamp = ehc_sim::rosStamp(steps_ * cfg_.dtNs());
    rosgraph_msgs::Clock clock;
    clock.clock = stamp;
    clock_pub_.publish(clock);
    nav_msgs::Odometry odom;
    ehc_sim::fillOdometry(*robot_, stamp, &odom);
    tf2_msgs::TFMessage tf;
    tf.transforms.resize(1);
    ehc_sim::fillBaseTransform(*robot_, stamp, &tf.transforms[0]);
    tf_pub_.publish(tf);
    odom_pub_.publish(odom);
    ehc_msgs::SimStatus status;
    const ehc_sim::StepScheduler& scheduler = lock_step_->scheduler();
    ehc_sim::fillCommandStatus(*robot_, scheduler.gate(), scheduler.lockStep(), steps_, stamp, &status);
    status_pub_.publish(status);
    lock_step_->statePublished(stamp, fresh);
    sensor_msgs::JointState js;
    ehc_sim::fillJointState(*robot_, stamp, &js);
    joint_pub_.publish(js);  // last: the controller answers this one
  }

  ros::NodeHandle nh_;
  ehc_sim::FakeRobotConfig cfg_;
  std::unique_ptr<ehc_sim::KinematicFakeRobot> robot_;
  std::unique_ptr<ehc_sim::LockStepNode> lock_step_;  ///< callback queue, commands, stepping loop
  std::int64_t steps_ = 0;
  ros::Publisher clock_pub_, joint_pub_, odom_pub_, tf_pub_, status_pub_;
};

}  // namespace

int main(int argc, char** argv) {
  return ehc_common::runNode(argc, argv, "ehc_kinematic_sim_node", 1, [](const ehc_common::NodeParams& params, ros::NodeHandle& nh) {
    KinematicSimNode node(nh, params);
    ehc_common::checkNodeParams(params);
    node.run();
    return 0;
  });
}
