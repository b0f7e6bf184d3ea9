#pragma once
#include <string>

#include "config/config.hpp"
#include "exit_status.hpp"

namespace shapeform::supervisor {

struct SupervisorOptions {
  std::string script;      ///< run this script's lines first (validated up front)
  std::string record_dir;  ///< start recording here at once
  /// Machine output: stdout carries only JSON lines with an "event" key (epoch, in_force, start_kept,
  /// rejected, wait, status, metrics, show, agent, record, recovered, summary); the human text goes to
  /// stderr. The events about the command in force carry its "epoch", "issuer" (GUID prefix), "publisher"
  /// (name, host and pid as the publisher announced them, and the GUID prefix) and "own".
  bool json = false;
  /// `start` publishes the --config scenario even when a command is in force that this supervisor did
  /// not publish (--command-on-start replace); by default it keeps that command.
  bool replace_on_start = false;
};

/// Runs the supervisor until `quit`, SIGINT/SIGTERM, or the end of all input (script done and console
/// at end of input, and no recording running). At a terminal, Ctrl-D on an empty line ends it too,
/// and Ctrl-C is the console's (see ConsoleInput). Returns the exit status.
int run_supervisor(const config::Config& cfg, const SupervisorOptions& opt);

}  // namespace shapeform::supervisor
