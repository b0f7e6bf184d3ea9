#pragma once
/// Process resource figures for status lines and the supervisor's report. Linux only.
#include <chrono>
#include <cstdint>

#include "util/clock.hpp"  // steady_ns(), which status lines stamp with

namespace shapeform::util {

/// Resident set size of this process in MiB (from /proc/self/statm); -1 if it cannot be read.
double rss_mb();

/// CPU time of this process (user + system, all threads), ns; 0 if it cannot be read.
std::int64_t process_cpu_ns();
/// CPU time of the calling thread (user + system), ns; 0 if it cannot be read.
std::int64_t thread_cpu_ns();

/// CPU use of this process (all threads) in percent of one core, measured between calls:
/// 100 = one core fully busy, may exceed 100 with several busy threads.
class CpuMeter {
 public:
  /// Starts the first interval now.
  CpuMeter();

  /// CPU % since the previous call (or construction), then starts a new interval.
  /// 0 when no steady time has passed.
  double percent();

 private:
  std::int64_t cpu_ns_;
  std::chrono::steady_clock::time_point wall_;
};

}  // namespace shapeform::util
