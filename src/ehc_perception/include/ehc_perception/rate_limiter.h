#pragma once
// RateLimiter: lets an event through at most rate_hz times per second of the caller's clock
// (ROS time in the nodes, sim time in the in-process pipeline). The first event passes; a clock
// that jumped back (simulator reset) passes too. ROS-free.

#include <optional>

namespace ehc_perception {

class RateLimiter {
 public:
  explicit RateLimiter(double rate_hz) : period_(1.0 / rate_hz) {}
  /// True (and the event is counted as the last one) if `now` is at least one period after the
  /// last accepted event.
  bool accept(double now) {
    if (last_ && now >= *last_ && now - *last_ < period_) return false;
    last_ = now;
    return true;
  }
  void reset() { last_.reset(); }

 private:
  double period_;
  std::optional<double> last_;
};

}  // namespace ehc_perception
