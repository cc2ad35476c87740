#pragma once
// Shared by the adapters' rostests that own sim time (test_rm_arm_adapter_node,
// test_water2_base_bridge_node): waiting for a node's lock-step handshake without a timed
// assertion. The wall clock only guards against a hang.

#include <gtest/gtest.h>
#include <ros/ros.h>

#include <functional>

namespace ehc_realman_test {

constexpr double kHangGuard = 30.0;  ///< wall s without a handshake: the test fails (a hang)

/// Spins (ros::spinOnce) until `pred` holds; false and a test failure naming `what` after
/// kHangGuard wall seconds. `resend` (if given) runs every 0.1 wall s while waiting, e.g. the
/// same /clock again in case the node's /clock subscription connected after it went out (same
/// time: idempotent).
inline bool spinUntil(const std::function<bool()>& pred, const char* what,
                      const std::function<void()>& resend = {}) {
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(kHangGuard);
  ros::WallTime next_resend = ros::WallTime::now() + ros::WallDuration(0.1);
  while (ros::ok() && !pred()) {
    if (ros::WallTime::now() > end) {
      ADD_FAILURE() << "hang guard: no " << what << " within " << kHangGuard << " wall s";
      return false;
    }
    if (resend && ros::WallTime::now() > next_resend) {
      resend();
      next_resend = ros::WallTime::now() + ros::WallDuration(0.1);
    }
    ros::WallDuration(0.0005).sleep();
    ros::spinOnce();
  }
  return pred();
}

}  // namespace ehc_realman_test
