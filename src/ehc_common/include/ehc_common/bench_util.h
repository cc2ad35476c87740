#pragma once
// Tiny benchmark helper shared by the bench_* executables: times `n` calls of `fn(i)` one by
// one with steady_clock and prints one JSON line with the median, p99 and mean in microseconds
// (ehc_common::Json, the project's one number format), and the median of the calling thread's
// CPU time (cpu_median_us: what the call costs whatever else runs on the machine).

#include "ehc_common/json.h"

#include <algorithm>
#include <chrono>
#include <ctime>
#include <cstdio>
#include <string>
#include <vector>

namespace ehc_common {

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

/// Prints one JSON line {"bench": name, ...values} (counts, rates, settings beside the timings).
inline void benchPrintValues(const std::string& name, const Json& values) {
  Json line;
  line["bench"] = name;
  for (const auto& [key, value] : values.items()) line[key] = value;
  std::printf("%s\n", jsonLine(line).c_str());
  std::fflush(stdout);
}

/// Prints one JSON line {"bench", "n", "median_us", "p99_us", "mean_us", "max_us", ...extra}.
inline void benchPrint(const std::string& name, std::size_t n, const BenchStats& s,
                       const Json& extra = Json::object()) {
  Json values;
  values["n"] = n;
  values["median_us"] = jsonNumber(s.median_us);
  values["p99_us"] = jsonNumber(s.p99_us);
  values["mean_us"] = jsonNumber(s.mean_us);
  values["max_us"] = jsonNumber(s.max_us);
  for (const auto& [key, value] : extra.items()) values[key] = value;
  benchPrintValues(name, values);
}

/// CPU time of the calling thread, in microseconds.
inline double threadCpuUs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return 1e6 * static_cast<double>(ts.tv_sec) + 1e-3 * static_cast<double>(ts.tv_nsec);
}

template <class Fn>
BenchStats benchReport(const std::string& name, int n, Fn&& fn, const Json& extra = Json::object()) {
  std::vector<double> us, cpu;
  us.reserve(static_cast<std::size_t>(n));
  cpu.reserve(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    const double c0 = threadCpuUs();
    const auto t0 = std::chrono::steady_clock::now();
    fn(i);
    const auto t1 = std::chrono::steady_clock::now();
    cpu.push_back(threadCpuUs() - c0);
    us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
  }
  const BenchStats s = benchStats(us);
  Json values = extra;
  values["cpu_median_us"] = jsonNumber(benchStats(cpu).median_us);
  benchPrint(name, us.size(), s, values);
  return s;
}

}  // namespace ehc_common
