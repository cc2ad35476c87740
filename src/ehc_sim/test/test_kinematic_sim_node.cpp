// rostest of ehc_kinematic_sim_node (the shipped kinematic_sim.yaml: lock-step, noise off):
// this node plays the controller (lock_step_controller.h). Checks, in one sim-time sequence:
// an unanswered state is resent with the same stamp (time does not advance without an
// answer); a NaN and a wrongly sized arm command and a NaN twist are rejected, counted on
// /sim/status and executed as zero without stalling lock-step; a valid command moves the
// robot by exactly v * t. No assertion depends on wall time.

#include "lock_step_controller.h"

#include <gtest/gtest.h>
#include <ros/ros.h>

#include <cmath>
#include <limits>

namespace {

using ehc_sim::test::State;

ehc_sim::test::LockStepController* ctl = nullptr;
const double kNaN = std::numeric_limits<double>::quiet_NaN();

}  // namespace

TEST(KinematicSimNode, AdvancesOnlyWhenAnsweredAndZeroesRejectedCommands) {
  // 1. First state at sim time 1 s, not answered: it comes again, same stamp, same clock.
  ASSERT_TRUE(ctl->waitState(ros::Time(1.0)));
  const int received = ctl->js_received_;
  ASSERT_TRUE(ctl->spinUntil([&] { return ctl->js_received_ > received; }))
      << "an unanswered state is resent (state_republish_period)";
  EXPECT_EQ(ctl->js_.stamp, ros::Time(1.0)) << "sim time advanced without an answer";
  ASSERT_TRUE(ctl->spinUntil([&] { return !ctl->clock_.isZero(); }));
  EXPECT_EQ(ctl->clock_, ros::Time(1.0));
  EXPECT_EQ(ctl->status_.step, 0u);
  EXPECT_TRUE(ctl->status_.lock_step);

  // 2. Bad commands: rejected, counted, executed as zero; every answered state is one step.
  const auto states = ctl->run(4, [](int k, const State&, geometry_msgs::Twist* b, std::vector<double>* arm) {
    b->linear.x = 0.2;
    (*arm)[0] = 0.5;
    if (k == 0) (*arm)[1] = kNaN;  // NaN arm command
    if (k == 1) arm->resize(5);    // wrongly sized arm command
    if (k == 2) b->angular.z = kNaN;  // NaN twist
  });
  ASSERT_EQ(states.size(), 5u) << "lock-step went on";
  for (std::size_t k = 0; k < states.size(); ++k)
    EXPECT_EQ(states[k].stamp, ros::Time(1.0) + ros::Duration(0.01 * static_cast<double>(k))) << k;
  EXPECT_EQ(ctl->status_.step, 4u);
  EXPECT_EQ(ctl->status_.arm_commands_rejected, 2u);
  EXPECT_EQ(ctl->status_.base_commands_rejected, 1u);
  EXPECT_EQ(ctl->status_.arm_commands_stale, 0u);
  const double dt = 0.01;
  for (int k : {1, 2}) {  // the steps after the rejected arm commands: the arm stood still
    for (double v : states[static_cast<std::size_t>(k)].qd) EXPECT_EQ(v, 0.0) << k;
    EXPECT_EQ(states[static_cast<std::size_t>(k)].q, states[0].q) << k;
    EXPECT_NEAR(states[static_cast<std::size_t>(k)].x, 0.2 * dt * k, 1e-12) << "the base still moved";
  }
  EXPECT_NEAR(states[3].x, states[2].x, 1e-12) << "rejected twist: base stopped";
  EXPECT_NEAR(states[3].qd[0], 0.5, 1e-12) << "the arm still moved";
  EXPECT_NEAR(states[4].x - states[3].x, 0.2 * dt, 1e-12);
  EXPECT_NEAR(states[4].q[0] - states[0].q[0], 2 * 0.5 * dt, 1e-12);

  // 3. Valid commands: exactly v * t without noise.
  const auto more = ctl->run(100, [](int, const State&, geometry_msgs::Twist* b, std::vector<double>* arm) {
    b->linear.x = 0.2;
    (*arm)[0] = 0.1;
  });
  ASSERT_EQ(more.size(), 101u);
  EXPECT_NEAR(more.back().x - more.front().x, 0.2, 1e-9);
  EXPECT_NEAR(more.back().y, 0.0, 1e-12);
  EXPECT_NEAR(more.back().q[0] - more.front().q[0], 0.1, 1e-9);
  EXPECT_EQ(ctl->status_.step, 104u);
  EXPECT_TRUE(ctl->spinUntil([&] { return ctl->clock_ == more.back().stamp; }));
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_kinematic_sim_node");
  ehc_sim::test::LockStepController c;
  ctl = &c;
  if (!c.connected()) {
    ADD_FAILURE() << "ehc_kinematic_sim_node did not come up";
    return 1;
  }
  return RUN_ALL_TESTS();
}
