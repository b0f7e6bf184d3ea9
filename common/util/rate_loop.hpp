#pragma once
/// The one fixed-rate loop of shapeform processes, deadline-based like ROS 2 rcl timers.
///
///   RateLoop loop(rate_hz);
///   while (loop.wait_next(stop_flag())) { ...one tick of work... }
///
/// Deadlines sit on a fixed grid t0 + k * period, where t0 is the time of the first wait_next call.
/// After a tick the deadline moves forward by exactly one period; if the loop is late by one or
/// more whole periods, those periods are skipped (never run back to back) and counted as overruns,
/// and the next deadline stays on the original grid. Not thread-safe: use one RateLoop from one
/// thread.
#include <array>
#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

namespace shapeform::util {

using SteadyTime = std::chrono::steady_clock::time_point;

/// Statistics kept by the loop itself (ArduPilot PerfInfo style). Times in microseconds.
struct LoopStats {
  std::uint64_t ticks = 0;       ///< wait_next calls that returned true
  std::uint64_t overruns = 0;    ///< whole periods skipped because the loop fell behind
  double lateness_max_us = 0.0;  ///< max of (wake-up time - deadline) since start / reset_stats()
  double lateness_p99_us = 0.0;  ///< p99 lateness over the last kLatenessWindow ticks; 0 if none
  double work_max_us = 0.0;      ///< max time from wait_next returning to the next wait_next call
};

/// Time source of a RateLoop. The default is std::chrono::steady_clock and std::this_thread;
/// tests inject a fake clock whose sleep_until just advances its time, so no real sleeping happens.
struct LoopClock {
  std::function<SteadyTime()> now;
  std::function<void(SteadyTime)> sleep_until;

  /// steady_clock::now and std::this_thread::sleep_until.
  static LoopClock steady();
};

class RateLoop {
 public:
  /// Number of recent lateness samples the p99 is computed over.
  static constexpr std::size_t kLatenessWindow = 1024;
  /// Longest single sleep, so a stop flag is noticed within about this long.
  static constexpr std::chrono::milliseconds kMaxSleepSlice{50};

  /// rate_hz: ticks per second, finite and > 0 (throws std::invalid_argument otherwise).
  /// The period is 1/rate_hz rounded to whole nanoseconds.
  explicit RateLoop(double rate_hz, LoopClock clock = LoopClock::steady());

  /// Sleeps until the next deadline, waking at least every kMaxSleepSlice to check `stop`.
  /// Returns false as soon as `stop` is seen set (the tick is not taken), true at the deadline.
  /// The first call anchors the grid: its deadline is (time of the first call) + period, so set-up
  /// time before the loop never counts as lateness or overruns.
  bool wait_next(const std::atomic<bool>& stop);

  /// Snapshot of the statistics. Computes the p99 on demand without allocating.
  LoopStats stats() const;

  /// Whole periods skipped since start / reset_stats() (stats().overruns, without computing the p99).
  std::uint64_t overruns() const { return stats_.overruns; }

  /// Clears lateness/work maxima, the lateness window and the counters; keeps the deadline grid.
  void reset_stats();

  /// Nominal period (use it, not measured time, as the model step so runs are reproducible).
  std::chrono::nanoseconds period() const { return period_; }
  double period_s() const { return std::chrono::duration<double>(period_).count(); }
  double rate_hz() const { return rate_hz_; }

  /// Deadline the next wait_next call will sleep until (meaningless before the first call).
  SteadyTime next_deadline() const { return deadline_; }

 private:
  void record_lateness(double lateness_us);

  double rate_hz_;
  std::chrono::nanoseconds period_;
  LoopClock clock_;
  bool started_ = false;
  SteadyTime deadline_{};
  SteadyTime last_return_{};
  LoopStats stats_{};
  std::array<double, kLatenessWindow> lateness_us_{};  ///< ring buffer of recent lateness samples
  std::size_t lateness_count_ = 0;                     ///< samples written, saturates at the window
  std::size_t lateness_next_ = 0;                      ///< next ring slot to write
  mutable std::vector<double> scratch_;                ///< reserved once; used by stats()
};

}  // namespace shapeform::util
