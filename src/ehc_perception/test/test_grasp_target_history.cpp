// GraspTargetHistory: which target serves which cloud (ehc_grasp_node), on stamps only; and
// stampSeconds, the ROS seconds of a nanosecond stamp.
#include "ehc_perception/grasp_target_history.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace ehc_perception {
namespace {

constexpr StampNs kSecond = 1000000000;
constexpr StampNs kMs = 1000000;

Eigen::Vector3d at(double x) { return Eigen::Vector3d(x, 0.0, 0.0); }

TEST(StampSeconds, IsWholeSecondsPlusTheRestAsRosComputesIt) {
  EXPECT_EQ(stampSeconds(0), 0.0);
  EXPECT_EQ(stampSeconds(2 * kSecond), 2.0);
  EXPECT_EQ(stampSeconds(1 * kSecond + 500 * kMs), 1.5);
  // ros::Time / ros::Duration toSec: static_cast<double>(sec) + 1e-9 * static_cast<double>(nsec).
  for (const StampNs ns : {StampNs(1), StampNs(300 * kMs), StampNs(2 * kSecond + 1), StampNs(1700000000LL * kSecond + 123456789)}) {
    const double sec = static_cast<double>(ns / kSecond), nsec = static_cast<double>(ns % kSecond);
    EXPECT_EQ(stampSeconds(ns), sec + 1e-9 * nsec) << ns;
  }
}

TEST(GraspTargetHistory, TheTargetForACloudIsTheNewestStampedBeforeIt) {
  GraspTargetHistory h(2.0);
  EXPECT_FALSE(h.targetFor(10 * kSecond));  // no target yet: every object
  EXPECT_EQ(h.add(10 * kSecond, at(1)), GraspTargetHistory::Added::Kept);
  EXPECT_EQ(h.add(11 * kSecond, at(2)), GraspTargetHistory::Added::Kept);
  EXPECT_EQ(h.add(12 * kSecond, at(3)), GraspTargetHistory::Added::Kept);
  EXPECT_EQ(h.size(), 3u);
  EXPECT_EQ(*h.targetFor(11 * kSecond + 1), at(2));
  EXPECT_EQ(*h.targetFor(11 * kSecond), at(1));  // stamped before: not at the same stamp
  EXPECT_EQ(*h.targetFor(13 * kSecond), at(3));
}

TEST(GraspTargetHistory, ATargetOlderThanTheTimeoutServesNoCloud) {
  GraspTargetHistory h(2.0);
  h.add(10 * kSecond, at(1));
  EXPECT_TRUE(h.targetFor(12 * kSecond));       // exactly the timeout: still served
  EXPECT_FALSE(h.targetFor(12 * kSecond + 1));  // 1 ns older: none (grasps for every object)
  EXPECT_FALSE(h.targetFor(20 * kSecond));
  GraspTargetHistory zero(0.0);  // target_timeout 0: only a target at the cloud's stamp, never one before it
  zero.add(5 * kSecond, at(1));
  EXPECT_FALSE(zero.targetFor(5 * kSecond + 1));
}

TEST(GraspTargetHistory, TheTimeoutBoundaryIsDecidedAsOnRosDurations) {
  // 0.3 s is not a double; the age of a target 300 ms older is computed as ros::Duration::toSec
  // (0 + 1e-9 * 3e8) and compared with 0.3, whatever that gives.
  GraspTargetHistory h(0.3);
  h.add(kSecond, at(1));
  EXPECT_EQ(static_cast<bool>(h.targetFor(kSecond + 300 * kMs)), 1e-9 * 300000000.0 <= 0.3);
  EXPECT_FALSE(h.targetFor(kSecond + 300 * kMs + 1));
}

TEST(GraspTargetHistory, NonFiniteTargetsAreRejected) {
  GraspTargetHistory h(2.0);
  EXPECT_EQ(h.add(kSecond, Eigen::Vector3d(0, std::nan(""), 0)), GraspTargetHistory::Added::Rejected);
  EXPECT_EQ(h.add(kSecond, Eigen::Vector3d(INFINITY, 0, 0)), GraspTargetHistory::Added::Rejected);
  EXPECT_EQ(h.size(), 0u);
  EXPECT_FALSE(h.targetFor(2 * kSecond));
}

TEST(GraspTargetHistory, AClockThatJumpedBackStartsTheListAgain) {
  GraspTargetHistory h(2.0);
  h.add(10 * kSecond, at(1));
  h.add(11 * kSecond, at(2));
  EXPECT_EQ(h.add(11 * kSecond, at(3)), GraspTargetHistory::Added::Kept);  // the same stamp: kept
  EXPECT_EQ(h.size(), 3u);
  EXPECT_EQ(h.add(1 * kSecond, at(4)), GraspTargetHistory::Added::Restarted);  // simulator reset
  EXPECT_EQ(h.size(), 1u);
  EXPECT_EQ(*h.targetFor(2 * kSecond), at(4));
  EXPECT_FALSE(h.targetFor(10 * kSecond + 500 * kMs));  // the targets before the reset are gone
}

TEST(GraspTargetHistory, ATargetThatComesAfterTheCloudThatShouldHaveUsedItIsLate) {
  GraspTargetHistory h(2.0);
  EXPECT_EQ(h.lastCloud(), 0);
  h.add(10 * kSecond, at(1));
  EXPECT_EQ(*h.targetFor(10 * kSecond + 100 * kMs), at(1));
  EXPECT_EQ(h.lastCloud(), 10 * kSecond + 100 * kMs);
  // Stamped between the cloud's target and the cloud: the cloud should have used it.
  EXPECT_EQ(h.add(10 * kSecond + 50 * kMs, at(2)), GraspTargetHistory::Added::Late);
  EXPECT_EQ(h.size(), 2u);  // kept: a later cloud uses it
  EXPECT_EQ(*h.targetFor(10 * kSecond + 200 * kMs), at(2));
  // After the last cloud: in time.
  EXPECT_EQ(h.add(10 * kSecond + 300 * kMs, at(3)), GraspTargetHistory::Added::Kept);
  // A cloud with no target before it: every target stamped before that cloud is late.
  GraspTargetHistory g(2.0);
  EXPECT_FALSE(g.targetFor(5 * kSecond));
  EXPECT_EQ(g.add(4 * kSecond, at(1)), GraspTargetHistory::Added::Late);
  // The target a cloud found too old still counts as the one it used.
  GraspTargetHistory o(1.0);
  o.add(1 * kSecond, at(1));
  EXPECT_FALSE(o.targetFor(5 * kSecond));
  EXPECT_EQ(o.add(1 * kSecond, at(2)), GraspTargetHistory::Added::Kept);  // not after the one it used
  EXPECT_EQ(o.add(3 * kSecond, at(3)), GraspTargetHistory::Added::Late);
}

TEST(GraspTargetHistory, AtMostCapacityTargetsAreKeptTheOldestDropped) {
  GraspTargetHistory h(1000.0, 3);
  for (int i = 1; i <= 5; ++i) h.add(i * kSecond, at(i));
  EXPECT_EQ(h.size(), 3u);
  EXPECT_EQ(*h.targetFor(3 * kSecond + 1), at(3));
  EXPECT_FALSE(h.targetFor(3 * kSecond));  // 1 and 2 are gone
  EXPECT_EQ(GraspTargetHistory(1.0).size(), 0u);
  EXPECT_EQ(GraspTargetHistory::kDefaultCapacity, 200u);
}

TEST(GraspTargetHistory, BadParametersThrow) {
  EXPECT_THROW(GraspTargetHistory(-1.0), std::invalid_argument);
  EXPECT_THROW(GraspTargetHistory(std::nan("")), std::invalid_argument);
  EXPECT_THROW(GraspTargetHistory(1.0, 0), std::invalid_argument);
  try {
    GraspTargetHistory(-1.0);
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()).rfind("[GraspTargetHistory]", 0), 0u) << e.what();
  }
}

}  // namespace
}  // namespace ehc_perception
