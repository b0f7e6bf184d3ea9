#include "dds/stall.hpp"

#include <time.h>

#include <iterator>

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

SplitWatch::SplitWatch(double window_s, double grace_s, bool secured)
    : window_ns_(static_cast<std::int64_t>(window_s * 1e9)),
      grace_ns_(static_cast<std::int64_t>((secured ? kAuthBoundS : grace_s) * 1e9)),
      secured_(secured) {}

void SplitWatch::dropped(const SourceId& peer, std::int64_t now_ns) {
  // Bounded: drops older than kDropMemoryS are forgotten (a return within the window makes one due; a
  // later one is still reported by discovered(), for the log).
  const auto memory_ns = static_cast<std::int64_t>(kDropMemoryS * 1e9);
  for (auto it = dropped_.begin(); it != dropped_.end();) it = now_ns - it->second > memory_ns ? dropped_.erase(it) : std::next(it);
  dropped_[peer] = now_ns;
  returned_.erase(peer);
}

std::optional<double> SplitWatch::discovered(const SourceId& peer, std::int64_t now_ns) {
  const auto it = dropped_.find(peer);
  if (it == dropped_.end()) return std::nullopt;
  const double unheard_s = static_cast<double>(now_ns - it->second) * 1e-9;
  if (now_ns - it->second <= window_ns_) returned_[peer] = {now_ns, unheard_s};
  dropped_.erase(it);
  return unheard_s;
}

void SplitWatch::authenticated(const SourceId& peer) {
  if (secured_) returned_.erase(peer);
}

void SplitWatch::removed(const SourceId& peer) {
  dropped_.erase(peer);
  returned_.erase(peer);
}

void SplitWatch::endpoint(const SourceId& peer) { returned_.erase(peer); }

std::optional<SplitWatch::Split> SplitWatch::due(std::int64_t now_ns) const {
  for (const auto& [peer, back] : returned_)
    if (now_ns - back.first >= grace_ns_) return Split{peer, back.second};
  return std::nullopt;
}

void SplitWatch::clear() {
  dropped_.clear();
  returned_.clear();
}

}  // namespace shapeform::dds
