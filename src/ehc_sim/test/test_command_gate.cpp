// CommandGate: lock-step readiness (arm command stamped with the current state AND a base twist
// since the last step), stale commands ignored, NaN / over-limit / malformed commands rejected,
// counted and replaced by zero velocities.

#include "ehc_sim/command_gate.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

using ehc_sim::CommandGate;

namespace {
ehc_control::RobotConfig robot(ehc_control::BaseType t = ehc_control::BaseType::Differential) {
  auto c = ehc_control::loadRobotConfig(std::string(EHC_CONFIG_DIR) +
                                        "/robots/realman_rm65_water2/robot.yaml");
  c.base_type = t;
  return c;
}
const std::vector<std::string> kNames = {"joint1", "joint2", "joint3", "joint4", "joint5", "joint6"};
const std::vector<double> kRates = {0.1, -0.2, 0.3, -0.4, 0.5, -0.6};
}  // namespace

TEST(CommandGate, ReadyOnlyWithArmCommandForThisStateAndABaseTwist) {
  CommandGate g(robot());
  g.newState(10'000'000);
  EXPECT_FALSE(g.ready());
  EXPECT_EQ(g.onArmCommand(10'000'000, kNames, kRates), "");
  EXPECT_FALSE(g.ready()) << "no base twist yet";
  EXPECT_EQ(g.onBaseTwist(0.2, 0.0, -0.3), "");
  EXPECT_TRUE(g.ready());
  const Eigen::VectorXd c = g.command();
  ASSERT_EQ(c.size(), 8);
  EXPECT_DOUBLE_EQ(c[0], 0.2);
  EXPECT_DOUBLE_EQ(c[1], -0.3);
  for (int i = 0; i < 6; ++i) EXPECT_DOUBLE_EQ(c[2 + i], kRates[static_cast<std::size_t>(i)]);
  // Next state: both answers needed again; the base twist order does not matter.
  g.newState(20'000'000);
  EXPECT_FALSE(g.ready());
  EXPECT_EQ(g.onBaseTwist(0.1, 0.0, 0.0), "");
  EXPECT_FALSE(g.ready());
  EXPECT_EQ(g.onArmCommand(20'000'000, {}, kRates), "") << "empty names = command order";
  EXPECT_TRUE(g.ready());
}

TEST(CommandGate, StaleArmCommandsAreIgnoredAndCounted) {
  CommandGate g(robot());
  g.newState(30'000'000);
  g.onBaseTwist(0, 0, 0);
  EXPECT_NE(g.onArmCommand(20'000'000, kNames, kRates), "");
  EXPECT_FALSE(g.ready());
  EXPECT_EQ(g.counters().arm_stale, 1);
  EXPECT_TRUE(g.command().tail(6).isZero());
  // Free-run mode accepts any stamp.
  EXPECT_EQ(g.onArmCommand(1, kNames, kRates, false), "");
  EXPECT_FALSE(g.command().tail(6).isZero());
}

TEST(CommandGate, NamesArePermutedIntoCommandOrder) {
  CommandGate g(robot());
  g.newState(0);
  std::vector<std::string> names(kNames.rbegin(), kNames.rend());
  std::vector<double> rates(kRates.rbegin(), kRates.rend());
  EXPECT_EQ(g.onArmCommand(0, names, rates), "");
  for (int i = 0; i < 6; ++i) EXPECT_DOUBLE_EQ(g.command()[2 + i], kRates[static_cast<std::size_t>(i)]);
}

TEST(CommandGate, BadArmCommandsAreRejectedCountedAndZeroed) {
  CommandGate g(robot());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  struct Case {
    std::vector<std::string> names;
    std::vector<double> v;
    std::string why;
  };
  const std::vector<Case> cases = {
      {kNames, {0.1, nan, 0, 0, 0, 0}, "NaN"},
      {kNames, {0.1, 0, 0, inf, 0, 0}, "NaN or Inf"},
      {kNames, {3.2, 0, 0, 0, 0, 0}, "exceeds its limit"},   // joint1 limit 3.14
      {kNames, {0, 0, 0, 0, 0, -4.0}, "exceeds its limit"},  // joint6 limit 3.92
      {kNames, {0.1, 0.2}, "2 velocities"},
      {{"joint1", "joint2", "joint3", "joint4", "joint5", "jointX"}, kRates, "jointX"},
      {{"joint1", "joint1", "joint3", "joint4", "joint5", "joint6"}, kRates, "repeated"},
      {{"joint1"}, kRates, "1 names"},
  };
  long n = 0;
  for (const auto& c : cases) {
    g.newState(0);
    EXPECT_EQ(g.onArmCommand(0, kNames, kRates), "");  // a good one first
    const std::string why = g.onArmCommand(0, c.names, c.v);
    EXPECT_NE(why.find(c.why), std::string::npos) << why;
    EXPECT_TRUE(g.command().tail(6).isZero()) << "rejected => arm stops: " << c.why;
    EXPECT_EQ(g.counters().arm_rejected, ++n);
  }
  // Exactly at the limit is fine.
  EXPECT_EQ(g.onArmCommand(0, kNames, {3.14, -3.14, 3.92, -3.92, 3.92, -3.92}), "");
}

TEST(CommandGate, BadBaseTwistsAreRejectedCountedAndZeroed) {
  CommandGate g(robot());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  g.onBaseTwist(0.3, 0, 0.2);
  EXPECT_NE(g.onBaseTwist(nan, 0, 0), "");
  EXPECT_TRUE(g.command().head(2).isZero());
  EXPECT_NE(g.onBaseTwist(0.6, 0, 0).find("exceeds"), std::string::npos);  // 0.5 m/s limit
  EXPECT_NE(g.onBaseTwist(0.1, 0, -1.2).find("exceeds"), std::string::npos);  // 1 rad/s limit
  EXPECT_NE(g.onBaseTwist(0.1, 0.1, 0).find("differential"), std::string::npos);
  EXPECT_EQ(g.counters().base_rejected, 4);
  EXPECT_EQ(g.counters().base_accepted, 1);
  // A rejected twist still answers the state (lock-step goes on with the base stopped).
  g.newState(5);
  g.onArmCommand(5, kNames, kRates);
  g.onBaseTwist(nan, 0, 0);
  EXPECT_TRUE(g.ready());
  EXPECT_TRUE(g.command().head(2).isZero());
  // Holonomic base: v_y allowed.
  CommandGate h(robot(ehc_control::BaseType::Holonomic));
  EXPECT_EQ(h.onBaseTwist(0.1, 0.2, 0.3), "");
  EXPECT_EQ(h.command().size(), 9);
  EXPECT_DOUBLE_EQ(h.command()[1], 0.2);
  h.zero();
  EXPECT_TRUE(h.command().isZero());
}
