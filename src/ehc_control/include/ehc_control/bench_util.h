#pragma once
// Tiny benchmark helper shared by the bench_* executables: times `n` calls of `fn(i)` one by
// one with steady_clock and prints one JSON line with the median, p99 and mean in microseconds.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

namespace ehc_control {

struct BenchStats {
  double median_us = 0, p99_us = 0, mean_us = 0, max_us = 0;
};

inline BenchStats benchStats(std::vector<double> us) {
  BenchStats s;
  if (us.empty()) return s;
  std::sort(us.begin(), us.end());
  s.median_us = us[us.size() / 2];
  s.p99_us = us[std::min(us.size() - 1, static_cast<std::size_t>(0.99 * us.size()))];
  s.max_us = us.back();
  double sum = 0;
  for (double v : us) sum += v;
  s.mean_us = sum / static_cast<double>(us.size());
  return s;
}

inline void benchPrint(const std::string& name, std::size_t n, const BenchStats& s,
                       const std::string& extra_json = "") {
  std::printf("{\"bench\":\"%s\",\"n\":%zu,\"median_us\":%.3f,\"p99_us\":%.3f,\"mean_us\":%.3f,"
              "\"max_us\":%.3f%s%s}\n",
              name.c_str(), n, s.median_us, s.p99_us, s.mean_us, s.max_us,
              extra_json.empty() ? "" : ",", extra_json.c_str());
  std::fflush(stdout);
}

template <class Fn>
BenchStats benchReport(const std::string& name, int n, Fn&& fn, const std::string& extra_json = "") {
  std::vector<double> us;
  us.reserve(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    fn(i);
    const auto t1 = std::chrono::steady_clock::now();
    us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
  }
  const BenchStats s = benchStats(us);
  benchPrint(name, us.size(), s, extra_json);
  return s;
}

}  // namespace ehc_control
