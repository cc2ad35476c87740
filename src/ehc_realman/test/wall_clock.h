#pragma once
// Wall-clock helpers shared by the RealMan adapter tests (steady clock: the adapters run on
// wall time, as on the robot).

#include <chrono>
#include <functional>
#include <thread>

namespace ehc_realman_test {

inline double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

inline void sleepFor(double s) { std::this_thread::sleep_for(std::chrono::duration<double>(s)); }

/// Polls `pred` every `poll` s until it holds (true) or `timeout` s have passed (its last value).
inline bool waitFor(const std::function<bool()>& pred, double timeout, double poll = 0.01) {
  const double end = now() + timeout;
  while (now() < end) {
    if (pred()) return true;
    sleepFor(poll);
  }
  return pred();
}

}  // namespace ehc_realman_test
