#include "util/proc_stats.hpp"

#include <unistd.h>

#include <ctime>
#include <fstream>

namespace shapeform::util {

namespace {

std::int64_t cpu_clock_ns(clockid_t clock) {
  timespec ts{};
  if (::clock_gettime(clock, &ts) != 0) return 0;
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + static_cast<std::int64_t>(ts.tv_nsec);
}

}  // namespace

// clock_gettime: nanosecond resolution, finer than getrusage's microsecond fields and free of /proc parsing.
std::int64_t process_cpu_ns() { return cpu_clock_ns(CLOCK_PROCESS_CPUTIME_ID); }
std::int64_t thread_cpu_ns() { return cpu_clock_ns(CLOCK_THREAD_CPUTIME_ID); }

double rss_mb() {
  // statm: size resident shared text lib data dt, in pages.
  std::ifstream in("/proc/self/statm");
  long long size_pages = 0;
  long long resident_pages = 0;
  if (!(in >> size_pages >> resident_pages)) return -1.0;
  const long page = ::sysconf(_SC_PAGESIZE);
  if (page <= 0) return -1.0;
  return static_cast<double>(resident_pages) * static_cast<double>(page) / (1024.0 * 1024.0);
}

CpuMeter::CpuMeter() : cpu_ns_(process_cpu_ns()), wall_(std::chrono::steady_clock::now()) {}

double CpuMeter::percent() {
  const std::int64_t cpu = process_cpu_ns();
  const auto wall = std::chrono::steady_clock::now();
  const auto wall_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(wall - wall_).count();
  const std::int64_t cpu_delta = cpu - cpu_ns_;
  cpu_ns_ = cpu;
  wall_ = wall;
  if (wall_ns <= 0 || cpu_delta < 0) return 0.0;
  return 100.0 * static_cast<double>(cpu_delta) / static_cast<double>(wall_ns);
}

}  // namespace shapeform::util
