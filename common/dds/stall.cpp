#include "dds/stall.hpp"

#include <time.h>

namespace shapeform::dds {

double stall_threshold_s(const TransportConfig& cfg) { return cfg.lease_s - cfg.announce_s; }

std::int64_t boot_ns() {
  timespec ts{};
  clock_gettime(CLOCK_BOOTTIME, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000LL + ts.tv_nsec;
}

std::optional<double> StallWatch::check(std::int64_t now_ns, double period_s, double threshold_s) {
  const std::int64_t last = last_ns_;
  last_ns_ = now_ns;
  if (last < 0) return std::nullopt;
  const double late_s = static_cast<double>(now_ns - last) * 1e-9 - period_s;
  if (late_s > threshold_s) return late_s;
  return std::nullopt;
}

}  // namespace shapeform::dds
