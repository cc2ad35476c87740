#pragma once
// Logging constants shared by every node: one throttle period for every repeated
// (ROS_*_THROTTLE) message, so an operator sees each kind of fault at the same rate everywhere.

namespace ehc_common {

/// Seconds between repeats of one throttled log message.
constexpr double kLogThrottle = 1.0;

}  // namespace ehc_common
