#pragma once
/// A wait in progress: `wait converged|agents|time` or `sleep` holds further input until its condition
/// holds or its deadline passes. Pure: its outcome is a function of the swarm, the command in force
/// and the time.
#include <cstdint>
#include <optional>
#include <string>
#include <variant>

#include "actions.hpp"
#include "authority.hpp"
#include "protocol/samples.hpp"
#include "swarm_monitor.hpp"

namespace shapeform::supervisor {

/// The actions that hold further input.
using Blocking = std::variant<WaitConverged, WaitAgents, WaitTime, Sleep>;

/// How a wait ended.
struct WaitEnd {
  bool ok = false;      ///< its condition held (false: it timed out)
  std::string text;     ///< the line for the operator ("" for a sleep that ran out)
  std::string warning;  ///< a line for the log ("" when none)
};

class Wait {
 public:
  /// Begun at now_ns while `on` was in force; its deadline is its timeout (or sleep) later, capped at
  /// 10^9 s (32 years) so that any accepted number of seconds stays inside int64 ns.
  Wait(Blocking what, std::int64_t now_ns, dds::CommandId on);

  /// Its name in the "wait" event: "converged", "agents", "time" or "sleep".
  const char* name() const;
  /// As the operator typed it: "wait converged", "sleep".
  std::string label() const;
  /// Whether it measures the command in force (converged, time): a command that replaces it ends it.
  bool on_command() const;
  const dds::CommandId& on() const { return on_; }
  std::int64_t deadline_ns() const { return deadline_ns_; }

  /// nullopt while it holds input, else how it ended: its condition holds (converged: the epoch in
  /// force converged; agents: N alive, each hearing N - 1 others; time: every alive agent follows the
  /// command and has done T of model time), or now_ns is at its deadline.
  std::optional<WaitEnd> outcome(const SwarmMonitor& monitor, const CommandAuthority& authority,
                                 std::int64_t now_ns) const;

 private:
  Blocking what_;
  std::int64_t deadline_ns_;
  dds::CommandId on_;
};

}  // namespace shapeform::supervisor
