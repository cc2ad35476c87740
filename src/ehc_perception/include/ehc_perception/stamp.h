#pragma once
// Message stamps in the perception cores: integer nanoseconds (what ros::Time::toNSec gives the
// nodes), so the cores order and match stamps exactly, as the nodes' ros::Time comparisons do.
// ROS-free.

#include <cstdint>

namespace ehc_perception {

using StampNs = std::int64_t;  ///< ns; 0 = no stamp (as ros::Time::isZero)

/// Seconds of a stamp, or of a non-negative difference of two, computed as ros::Time::toSec and
/// ros::Duration::toSec compute them (whole seconds + 1e-9 x the remaining ns): a core's decision
/// on them (an age against a timeout, a rate limit) is the one the node made on ROS types, to the
/// last bit. `ns` >= 0.
inline double stampSeconds(StampNs ns) {
  return static_cast<double>(ns / 1000000000) + 1e-9 * static_cast<double>(ns % 1000000000);
}

}  // namespace ehc_perception
