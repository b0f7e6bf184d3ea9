#pragma once
/// Where a loop's time goes, phase by phase: one clock reading per phase boundary per tick (never per
/// sample), the time since the previous boundary booked to the phase that just ended. Pure bookkeeping:
/// the caller passes the readings (start_at, lap_at) of the clock it chooses (the agent's loop: its
/// thread's CPU time, util::thread_cpu_ns). Reported once, as a log line.
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

namespace shapeform::util {

/// N phases, named at construction; ticks are counted by start().
template <std::size_t N>
class PhaseClock {
 public:
  explicit PhaseClock(std::array<const char*, N> names) : names_(names) {}

  /// A tick begins at now_ns: the next lap books from here.
  void start_at(std::int64_t now_ns) {
    last_ns_ = now_ns;
    ++ticks_;
  }
  /// Phase `phase` ended at now_ns: the time since the previous boundary is booked to it.
  void lap_at(std::size_t phase, std::int64_t now_ns) {
    total_ns_[phase] += now_ns - last_ns_;
    last_ns_ = now_ns;
  }

  std::uint64_t ticks() const { return ticks_; }
  /// Mean time per tick spent in `phase`, microseconds (0 before the first tick).
  double mean_us(std::size_t phase) const {
    return ticks_ == 0 ? 0.0 : static_cast<double>(total_ns_[phase]) * 1e-3 / static_cast<double>(ticks_);
  }
  /// "name1 12.3 us, name2 4.5 us, ..., total 20.1 us per tick over T ticks".
  std::string line() const {
    std::string s;
    double total = 0.0;
    for (std::size_t k = 0; k < N; ++k) {
      total += mean_us(k);
      s += std::string(names_[k]) + " " + format(mean_us(k)) + " us, ";
    }
    return s + "total " + format(total) + " us per tick over " + std::to_string(ticks_) + " ticks";
  }

 private:
  static std::string format(double us) {
    char text[32];
    std::snprintf(text, sizeof text, "%.1f", us);
    return text;
  }
  std::array<const char*, N> names_;
  std::array<std::int64_t, N> total_ns_{};
  std::int64_t last_ns_ = 0;
  std::uint64_t ticks_ = 0;
};

}  // namespace shapeform::util
