// CycleWatchdog (controller_supervisor.h), driven with synthetic ROS and wall times as
// ehc_controller_node's timers drive it: nothing before the first cycle; the ROS-time watchdog
// fires when no cycle ran for more than state_timeout (or the clock jumped back by as much); the
// wall-clock watchdog only while ROS time stands still; with a ControlCycle, a stale state gives
// the watchdog's zero command and a fresh one runs the controller again.

#include "ehc_control/control_cycle.h"
#include "ehc_control/controller_supervisor.h"
#include "ehc_test/control_fixtures.h"

#include <gtest/gtest.h>

#include <string>

namespace ehc_control {
namespace {

TEST(CycleWatchdog, NothingFiresBeforeTheFirstCycle) {
  CycleWatchdog w(0.2, 0.5);
  EXPECT_EQ(w.checkRosTime(100.0), "");
  for (double wall = 0.0; wall < 10.0; wall += 0.05) EXPECT_EQ(w.checkWallClock(wall, 1.0), "");
}

TEST(CycleWatchdog, RosTimeFiresAfterTheStateTimeoutEitherWay) {
  CycleWatchdog w(0.2, 0.5);
  w.cycleRan(10.0, 1000.0);
  EXPECT_EQ(w.checkRosTime(10.0), "");
  EXPECT_EQ(w.checkRosTime(10.2), "");
  EXPECT_EQ(w.checkRosTime(9.85), "");
  EXPECT_EQ(w.checkRosTime(10.25), "no control cycle for 0.25 s (lock-step: no joint state + odometry pair)");
  EXPECT_NE(w.checkRosTime(9.7), "");  // the clock jumped back (simulator reset)
  w.cycleRan(10.3, 1000.1);            // a cycle: quiet again
  EXPECT_EQ(w.checkRosTime(10.4), "");
}

TEST(CycleWatchdog, WallClockFiresOnlyWhileRosTimeStandsStill) {
  CycleWatchdog w(0.2, 0.5);
  double wall = 1000.0, ros = 10.0;
  w.cycleRan(ros, wall);
  // ROS time moves (slowly: a loaded lock-step simulator): no cycle for 2 wall s, no stop.
  for (int i = 0; i < 40; ++i) {
    wall += 0.05;
    ros += 0.001;
    EXPECT_EQ(w.checkWallClock(wall, ros), "") << wall;
  }
  // ROS time stops: the watchdog fires once it has stood still for more than wall_timeout.
  std::string why;
  const double stopped_at = wall;
  while (why.empty() && wall < stopped_at + 2.0) {
    wall += 0.05;
    why = w.checkWallClock(wall, ros);
  }
  EXPECT_GT(wall - stopped_at, 0.5);
  EXPECT_LE(wall - stopped_at, 0.6);
  EXPECT_EQ(why.rfind("no control cycle for ", 0), 0u) << why;
  EXPECT_NE(why.find(" wall s (ROS time 10.04 stands still? simulator dead?)"), std::string::npos) << why;
  // ROS time moves again: quiet, whatever the wall time since the last cycle.
  EXPECT_EQ(w.checkWallClock(wall + 0.05, ros + 0.01), "");
}

TEST(CycleWatchdog, WallClockStaysQuietWhileCyclesRun) {
  CycleWatchdog w(0.2, 0.5);
  for (int i = 0; i < 100; ++i) {
    const double wall = 1000.0 + 0.05 * i;
    w.cycleRan(10.0, wall);  // ROS time stands still but the cycle runs (e.g. timer mode, paused sim)
    EXPECT_EQ(w.checkWallClock(wall + 0.01, 10.0), "");
  }
}

TEST(CycleWatchdog, RejectsNonPositiveTimeouts) {
  EXPECT_THROW(CycleWatchdog(0.0, 0.5), std::invalid_argument);
  EXPECT_THROW(CycleWatchdog(0.2, -1.0), std::invalid_argument);
}

/// What ehc_controller_node does: cycles on fresh states, the ROS-time timer in between.
TEST(CycleWatchdog, StaleStateGivesTheZeroCommandAndAFreshOneRuns) {
  ControlCycleParams p;
  p.robot_file = test::realmanYaml();
  p.watchdog.require_obstacles = false;  // no obstacle lists here
  ControlCycle cycle(p);
  const RobotConfig& rc = cycle.model().config();
  CycleWatchdog w(p.watchdog.state_timeout, 0.5);
  const Eigen::VectorXd q = rc.arm_ready;
  const std::vector<double> qv(q.data(), q.data() + q.size());
  const Eigen::Isometry3d target = test::approachPose(1.5, 0.0, 0.8, Eigen::Vector3d(1, 0, -1));
  auto runAt = [&](double t) {
    EXPECT_EQ(cycle.setJointState(t, rc.arm_joints, qv), "");
    EXPECT_EQ(cycle.setBasePose(t, Eigen::Vector3d::Zero()), "");
    EXPECT_EQ(cycle.setTarget(t, target), "");
    w.cycleRan(t, 1000.0 + t);
    return cycle.update(t);
  };
  const ControlCycleOutput fresh = runAt(1.0);
  EXPECT_NE(fresh.status.phase, ControlPhase::Stopped);
  EXPECT_GT(fresh.velocity.norm(), 0.0);
  EXPECT_EQ(w.checkRosTime(1.1), "");  // within state_timeout: no watchdog output
  const double late = 1.0 + p.watchdog.state_timeout + 0.05;
  const std::string why = w.checkRosTime(late);  // no state since: the timer publishes zeros
  ASSERT_NE(why, "");
  const ControlCycleOutput stop = cycle.stopped(late, why);
  EXPECT_EQ(stop.status.phase, ControlPhase::Stopped);
  EXPECT_EQ(stop.status.reason, why);
  EXPECT_TRUE((stop.velocity.array() == 0.0).all());
  EXPECT_EQ(cycle.update(late).status.phase, ControlPhase::Stopped);  // the supervisor agrees: stale state
  const ControlCycleOutput again = runAt(late + 0.01);                 // a fresh state: runs again
  EXPECT_NE(again.status.phase, ControlPhase::Stopped);
  EXPECT_GT(again.velocity.norm(), 0.0);
  EXPECT_EQ(w.checkRosTime(late + 0.02), "");
}

}  // namespace
}  // namespace ehc_control
