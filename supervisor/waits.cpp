#include "waits.hpp"

#include <algorithm>
#include <cstdio>
#include <string>

namespace shapeform::supervisor {

namespace {

std::string fmt(double v, const char* f) {
  char b[32];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

/// The outcome of each blocking action, given whether its deadline has passed.
struct Outcome {
  const SwarmMonitor& monitor;
  const CommandAuthority& authority;
  std::int64_t now;
  bool timed_out;

  std::optional<WaitEnd> operator()(const WaitConverged& w) const {
    if (authority.epoch() != 0 && monitor.converged()) {
      const std::string of = authority.own() ? std::string() : " of " + authority.publisher();
      return WaitEnd{true,
                     "converged at t=" + fmt(authority.model_time(now), "%.0f") + " (" +
                         fmt(authority.since_epoch_s(now), "%.1f") + " s after epoch " +
                         std::to_string(authority.epoch()) + of + ")",
                     ""};
    }
    if (!timed_out) return std::nullopt;
    return WaitEnd{false, "wait converged: timed out after " + fmt(w.timeout_s, "%g") + " s",
                   "wait converged timed out after " + fmt(w.timeout_s, "%g") + " s"};
  }

  std::optional<WaitEnd> operator()(const WaitAgents& w) const {
    // N agents alive, and each hears the others (its status says so): a command sent before discovery
    // completes would be followed by agents that do not yet know all their neighbours.
    const int n = monitor.alive_count(now);
    if (n >= w.count && monitor.all_hear(w.count - 1, now))
      return WaitEnd{
          true,
          "agents: " + std::to_string(n) + " alive, each hearing " + std::to_string(w.count - 1) + " or more",
          ""};
    if (!timed_out) return std::nullopt;
    return WaitEnd{false,
                   "wait agents: timed out after " + fmt(w.timeout_s, "%g") + " s with " + std::to_string(n) +
                       " of " + std::to_string(w.count) + " agents",
                   "wait agents timed out with " + std::to_string(n) + " of " + std::to_string(w.count)};
  }

  std::optional<WaitEnd> operator()(const WaitTime& w) const {
    // Done when every agent on the current command has done T of model time by its own count (a
    // loaded agent skips ticks, a lockstep agent waits for the others: wall time is not enough).
    const auto t = monitor.min_following_model_time(now);
    if (t && monitor.following_count(now) == monitor.alive_count(now) && *t >= w.model_time - 1e-9)
      return WaitEnd{true, "", ""};
    if (!timed_out) return std::nullopt;
    return WaitEnd{false, "wait time: timed out after " + fmt(w.timeout_s, "%g") + " s", ""};
  }

  std::optional<WaitEnd> operator()(const Sleep&) const {
    return timed_out ? std::optional<WaitEnd>(WaitEnd{true, "", ""}) : std::nullopt;
  }
};

double seconds(const Blocking& what) {
  return std::visit(
      [](const auto& w) {
        if constexpr (std::is_same_v<std::decay_t<decltype(w)>, Sleep>)
          return w.seconds;
        else
          return w.timeout_s;
      },
      what);
}

}  // namespace

Wait::Wait(Blocking what, std::int64_t now_ns, dds::CommandId on)
    : what_(std::move(what)),
      deadline_ns_(now_ns + static_cast<std::int64_t>(std::min(seconds(what_), 1e9) * 1e9)),
      on_(on) {}

const char* Wait::name() const {
  static constexpr const char* kNames[] = {"converged", "agents", "time", "sleep"};
  return kNames[what_.index()];
}

std::string Wait::label() const {
  return std::holds_alternative<Sleep>(what_) ? std::string("sleep") : std::string("wait ") + name();
}

bool Wait::on_command() const {
  return std::holds_alternative<WaitConverged>(what_) || std::holds_alternative<WaitTime>(what_);
}

std::optional<WaitEnd> Wait::outcome(const SwarmMonitor& monitor, const CommandAuthority& authority,
                                     std::int64_t now_ns) const {
  return std::visit(Outcome{monitor, authority, now_ns, now_ns >= deadline_ns_}, what_);
}

}  // namespace shapeform::supervisor
