#pragma once
#include <string>

#include "config/config.hpp"

namespace shapeform::supervisor {

struct SupervisorOptions {
  std::string script;      ///< run this script's lines first (validated up front)
  std::string record_dir;  ///< start recording here at once
  /// Machine output: stdout carries only JSON lines with an "event" key (epoch, wait, status, metrics,
  /// agent, record, recovered, summary); the human text goes to stderr.
  bool json = false;
};

/// Exit statuses.
inline constexpr int kExitOk = 0;
inline constexpr int kExitRuntime = 1;
inline constexpr int kExitBadInput = 2;
inline constexpr int kExitWaitTimedOut = 3;
/// Two Ctrl-C within a second on an empty console line (128 + SIGINT, as a shell reports it).
inline constexpr int kExitInterrupted = 130;

/// Runs the supervisor until `quit`, SIGINT/SIGTERM, or the end of all input (script done and console
/// at end of input, and no recording running). At a terminal, Ctrl-D on an empty line ends it too,
/// and Ctrl-C is the console's (see ConsoleInput). Returns the exit status.
int run_supervisor(const config::Config& cfg, const SupervisorOptions& opt);

}  // namespace shapeform::supervisor
