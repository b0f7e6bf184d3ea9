#include "util/rate_loop.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>

#include "util/stats.hpp"

namespace shapeform::util {

namespace {

double to_us(std::chrono::nanoseconds d) { return static_cast<double>(d.count()) / 1e3; }

std::chrono::nanoseconds period_from_rate(double rate_hz) {
  if (!std::isfinite(rate_hz) || rate_hz <= 0.0) {
    throw std::invalid_argument("RateLoop: rate_hz must be finite and > 0, got " +
                                std::to_string(rate_hz));
  }
  const double ns = std::round(1e9 / rate_hz);
  if (ns > 1e18) {
    throw std::invalid_argument("RateLoop: rate_hz too small, got " + std::to_string(rate_hz));
  }
  return std::chrono::nanoseconds(std::max<std::int64_t>(1, static_cast<std::int64_t>(ns)));
}

}  // namespace

LoopClock LoopClock::steady() {
  return LoopClock{[] { return std::chrono::steady_clock::now(); },
                   [](SteadyTime t) { std::this_thread::sleep_until(t); }};
}

RateLoop::RateLoop(double rate_hz, LoopClock clock)
    : rate_hz_(rate_hz), period_(period_from_rate(rate_hz)), clock_(std::move(clock)) {
  if (!clock_.now || !clock_.sleep_until) {
    throw std::invalid_argument("RateLoop: clock must provide now and sleep_until");
  }
  scratch_.reserve(kLatenessWindow);
}

bool RateLoop::wait_next(const std::atomic<bool>& stop) {
  SteadyTime now = clock_.now();
  if (!started_) {
    started_ = true;
    deadline_ = now + period_;
  } else {
    stats_.work_max_us = std::max(stats_.work_max_us, to_us(now - last_return_));
  }

  for (;;) {
    if (stop.load(std::memory_order_relaxed)) return false;
    if (now >= deadline_) break;
    clock_.sleep_until(std::min<SteadyTime>(deadline_, now + kMaxSleepSlice));
    now = clock_.now();
  }

  record_lateness(to_us(now - deadline_));
  ++stats_.ticks;

  // Exactly one period forward; if that deadline has passed too, skip whole periods (rcl_timer).
  deadline_ += period_;
  if (now >= deadline_) {
    const auto skipped = (now - deadline_) / period_ + 1;
    deadline_ += skipped * period_;
    stats_.overruns += static_cast<std::uint64_t>(skipped);
  }
  last_return_ = now;
  return true;
}

void RateLoop::record_lateness(double lateness_us) {
  stats_.lateness_max_us = std::max(stats_.lateness_max_us, lateness_us);
  lateness_us_[lateness_next_] = lateness_us;
  lateness_next_ = (lateness_next_ + 1) % kLatenessWindow;
  lateness_count_ = std::min(lateness_count_ + 1, kLatenessWindow);
}

LoopStats RateLoop::stats() const {
  LoopStats s = stats_;
  scratch_.assign(lateness_us_.begin(),
                  lateness_us_.begin() + static_cast<std::ptrdiff_t>(lateness_count_));
  s.lateness_p99_us = percentile(scratch_, 99.0).value_or(0.0);
  return s;
}

void RateLoop::reset_stats() {
  stats_ = LoopStats{};
  lateness_count_ = 0;
  lateness_next_ = 0;
}

}  // namespace shapeform::util
