// HardwareStandIn + Water2ApiServer (the deployment rehearsal's hardware stand-in): the
// rm_driver rules (frames followed within the velocity limits, wrong / NaN / > 10 deg frames
// ignored, emergency stop holds, gripper mapping), stepping on a wall clock given by the test
// (catching up a stall of seconds, skipping only after a longer one), and the Water2 API served on 127.0.0.1 to the
// bridge's own client (ehc_realman::Water2Client): joy_control drives the water2 base model,
// robot_status reports its pose. No master, no sleeps: the wall times are arguments.

#include "ehc_sim/hardware_stand_in.h"
#include "ehc_sim/water2_api_server.h"

#include "ehc_realman/water2_client.h"
#include "ehc_realman/water2_protocol.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace ehc_sim;

namespace {
const std::string kConfig = std::string(EHC_CONFIG_DIR);

SimConfig standInConfig() {
  SimConfig c = loadSimConfig(kConfig + "/realman/hardware_standin.yaml");
  c.fake_robot.noise.enabled = false;
  return c;
}

struct World {
  SimConfig cfg = standInConfig();
  ehc_control::RobotConfig robot = ehc_control::loadRobotConfig(cfg.fake_robot.robot_file);
  SimWorld world{cfg, robot, loadSceneConfigString("scene:\n  name: empty\n", "empty")};
};

std::vector<double> toVector(const Eigen::VectorXd& q) { return std::vector<double>(q.data(), q.data() + q.size()); }
}  // namespace

TEST(HardwareStandIn, NeedsTheWater2BaseModel) {
  SimConfig cfg = standInConfig();
  cfg.fake_robot.base_model.type = BaseModelType::Ideal;
  const auto robot = ehc_control::loadRobotConfig(cfg.fake_robot.robot_file);
  SimWorld world(cfg, robot, loadSceneConfigString("scene:\n  name: empty\n", "empty"));
  EXPECT_THROW(HardwareStandIn{world}, std::invalid_argument);
}

TEST(HardwareStandIn, StepsWithTheWallClockAndSkipsAfterAStall) {
  World w;
  HardwareStandIn s(w.world, 10);
  const double dt = w.cfg.fake_robot.dt;
  EXPECT_EQ(s.advanceTo(100.0), 0);  // the origin
  EXPECT_EQ(s.advanceTo(100.0 + 3.5 * dt), 3);
  EXPECT_EQ(s.advanceTo(100.0 + 3.9 * dt), 0);
  EXPECT_EQ(s.advanceTo(100.0 + 4.0 * dt), 1);
  EXPECT_EQ(s.counters().skipped_steps, 0);
  // A 1 s stall: 10 steps now, the other 90 given up (the world lags from now on).
  EXPECT_EQ(s.advanceTo(100.0 + 104.0 * dt), 10);
  EXPECT_EQ(s.counters().skipped_steps, 90);
  EXPECT_EQ(s.advanceTo(100.0 + 105.0 * dt), 1);
  EXPECT_EQ(w.world.stepCount(), 15);
  EXPECT_THROW(s.advanceTo(NAN), std::invalid_argument);
}

// A 3 s stall of the stand-in's process (a loaded machine) is caught up by default: the world
// does what the hardware did meanwhile (the base runs its last joy_control for its 0.5 s
// lifetime, then stops), so the world's time and the base pose stay those of the wall clock the
// bridge dead-reckons on. With the old 1 s cap the world froze for 2 s: 200 steps skipped.
TEST(HardwareStandIn, CatchesUpAStallOfSecondsAsTheHardwareMovedMeanwhile) {
  World w;
  HardwareStandIn s(w.world);
  s.advanceTo(0.0);
  s.onJoyControl(0.3, 0.0);
  EXPECT_EQ(s.advanceTo(1.0 + 1e-9), 100);
  const double x_before = w.world.robot().basePose().x();
  s.onJoyControl(0.3, 0.0);  // the last command before the stall
  EXPECT_EQ(s.advanceTo(4.0 + 1e-9), 300);
  EXPECT_EQ(s.counters().skipped_steps, 0);
  EXPECT_NEAR(w.world.time(), 4.0, 1e-9);
  const double moved = w.world.robot().basePose().x() - x_before;
  EXPECT_GT(moved, 0.05) << "the base ran out its last command";
  EXPECT_LT(moved, 0.3 * 0.5 + 0.3 * 0.2) << "and stopped after its 0.5 s lifetime (plus the slow-down)";
  const double x_stopped = w.world.robot().basePose().x();
  EXPECT_EQ(s.advanceTo(4.5 + 1e-9), 50);
  EXPECT_NEAR(w.world.robot().basePose().x(), x_stopped, 1e-9);
}

TEST(HardwareStandIn, FollowsJointPosLikeTheDriverAndIgnoresWhatTheDriverIgnores) {
  World w;
  HardwareStandIn s(w.world);
  const Eigen::VectorXd q0 = w.world.robot().armPositions();
  EXPECT_TRUE(s.armRates().isZero(0.0)) << "no set-point: the arm stands";
  // Wrong size, NaN, a jump of more than 10 deg: ignored, the set-point stays unset.
  EXPECT_NE(s.onJointPos({0.0, 0.0}), "");
  std::vector<double> nan = toVector(q0);
  nan[2] = NAN;
  EXPECT_NE(s.onJointPos(nan), "");
  std::vector<double> jump = toVector(q0);
  jump[0] += 11.0 * M_PI / 180.0;
  EXPECT_NE(s.onJointPos(jump), "");
  EXPECT_FALSE(s.setPoint().has_value());
  EXPECT_EQ(s.counters().frames_ignored, 3);
  // 9 deg on joint1: followed at joint1's velocity limit, then reached.
  std::vector<double> target = toVector(q0);
  target[0] += 9.0 * M_PI / 180.0;
  EXPECT_EQ(s.onJointPos(target), "");
  const double vmax = w.robot.arm_velocity[0];
  EXPECT_NEAR(s.armRates()[0], std::min(vmax, 9.0 * M_PI / 180.0 / w.cfg.fake_robot.dt), 1e-9);
  s.advanceTo(0.0);
  s.advanceTo(2.0);
  EXPECT_NEAR(w.world.robot().armPositions()[0], target[0], 1e-6);
  EXPECT_NEAR((w.world.robot().armPositions() - Eigen::Map<const Eigen::VectorXd>(target.data(), 6)).norm(), 0.0, 1e-6);
  // Emergency stop: the arm holds where it is.
  std::vector<double> back = toVector(q0);
  back[0] += 1.0 * M_PI / 180.0;
  EXPECT_EQ(s.onJointPos(back), "");
  s.onEmergencyStop();
  EXPECT_TRUE(s.armRates().isZero(0.0));
  // Gripper: Gripper_Set >= 500 opens, below closes; Pick closes.
  s.onGripperSet(1);
  EXPECT_EQ(w.world.gripper().state(), GripperState::Closing);
  s.onGripperSet(1000);
  EXPECT_EQ(w.world.gripper().state(), GripperState::Opening);
  s.onGripperPick();
  EXPECT_EQ(w.world.gripper().state(), GripperState::Closing);
}

TEST(HardwareStandIn, ServesTheWater2ApiToTheBridgesClient) {
  World w;
  HardwareStandIn s(w.world);
  Water2ApiServer server(0);
  ASSERT_GT(server.port(), 0);
  ehc_realman::Water2ClientConfig cc;
  cc.host = "127.0.0.1";
  cc.port = server.port();
  ehc_realman::Water2Client client(cc);
  client.connect();
  const auto joy = [&](double v, double ww) { s.onJoyControl(v, ww); };
  const auto pose = [&] { return s.statusPose(); };
  for (int i = 0; i < 20 && !server.clientConnected(); ++i) server.serve(0.05, joy, pose);
  ASSERT_TRUE(server.clientConnected());

  // joy_control every 0.1 s (as the bridge resends) for 2 s of world time: the base drives.
  double wall = 0.0;
  s.advanceTo(wall);
  std::vector<std::string> replies;
  for (int k = 0; k < 20; ++k) {
    client.send(ehc_realman::joyControlRequest(0.3, 0.0));
    for (int i = 0; i < 100 && s.counters().joy_controls <= k; ++i) server.serve(0.01, joy, pose);
    wall += 0.1;
    s.advanceTo(wall);
    for (const std::string& r : client.receive(0.05)) replies.push_back(r);
  }
  EXPECT_EQ(server.counters().joy_controls, 20);
  EXPECT_EQ(s.counters().joy_controls, 20);
  for (const std::string& r : replies) EXPECT_TRUE(ehc_realman::parseWater2Reply(r).ok()) << r;
  const double x = w.world.robot().basePose().x();
  EXPECT_GT(x, 0.3) << "the base drove ~0.3 m/s x 0.95 gain, accelerating at 0.5 m/s^2";
  EXPECT_LT(x, 0.6);

  // robot_status: the map pose (true pose + a localisation error of a few mm).
  client.send(ehc_realman::robotStatusRequest());
  std::optional<ehc_realman::Water2Reply> status;
  for (int i = 0; i < 100 && !status; ++i) {
    server.serve(0.01, joy, pose);
    for (const std::string& r : client.receive(0.01)) {
      const auto reply = ehc_realman::parseWater2Reply(r);
      if (reply.command == "/api/robot_status") status = reply;
    }
  }
  ASSERT_TRUE(status.has_value());
  ASSERT_TRUE(status->pose.has_value());
  EXPECT_NEAR(status->pose->x, x, 0.02);
  EXPECT_NEAR(status->pose->y, w.world.robot().basePose().y(), 0.02);

  // Without renewal the base stops after the 0.5 s command lifetime (and its deceleration).
  wall += 3.0;
  for (int i = 0; i < 30; ++i) s.advanceTo(wall - 3.0 + 0.1 * (i + 1));
  const double x_stop = w.world.robot().basePose().x();
  s.advanceTo(wall + 1.0);
  EXPECT_NEAR(w.world.robot().basePose().x(), x_stop, 1e-9);

  // An unknown request gets an error reply, and the client may hang up and come back.
  client.send("/api/unknown_thing\n");
  for (int i = 0; i < 100 && server.counters().bad_requests == 0; ++i) server.serve(0.01, joy, pose);
  EXPECT_EQ(server.counters().bad_requests, 1);
  client.close();
  for (int i = 0; i < 20 && server.clientConnected(); ++i) server.serve(0.01, joy, pose);
  EXPECT_FALSE(server.clientConnected());
  client.connect();
  for (int i = 0; i < 20 && !server.clientConnected(); ++i) server.serve(0.05, joy, pose);
  EXPECT_TRUE(server.clientConnected());
  EXPECT_EQ(server.counters().connections, 2);
}
