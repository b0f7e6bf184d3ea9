#pragma once
/// The supervisor's input: the lines of its --script, then those of its console, each parsed against
/// the command in force and handed to the executor. A wait or sleep holds further lines until it ends
/// (its outcome is reported: text, "wait" event, exit status 3 when it timed out); Ctrl-C cancels it
/// (and the script), or quits when pressed twice within a second on an idle console. No DDS, no clock:
/// the caller passes the time.
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "actions.hpp"
#include "authority.hpp"
#include "console_input.hpp"
#include "exit_status.hpp"
#include "output.hpp"
#include "swarm_monitor.hpp"
#include "waits.hpp"

namespace shapeform::supervisor {

class InputDriver {
 public:
  /// Runs one parsed action.
  using Dispatch = std::function<void(const Action&, std::int64_t now_ns)>;

  InputDriver(Output& out, const SwarmMonitor& monitor, const CommandAuthority& authority);

  /// Checks every line of the script at `path` (each parsed against the command the lines before it
  /// leave, from `initial`) and keeps it to run first. False, each problem reported, when a line is bad
  /// or the file cannot be read: then nothing runs.
  bool load_script(const std::string& path, const core::CompiledCommand& initial);
  /// The console, read once the script has ended (not owned; null: none).
  void set_console(LineSource* console) { console_ = console; }
  void set_dispatch(Dispatch dispatch) { dispatch_ = std::move(dispatch); }

  /// Runs lines until one holds input (wait, sleep), none is ready, or quit.
  void run_lines(std::int64_t now_ns);
  /// Holds further lines until `wait` ends.
  void block(Wait wait) { pending_ = std::move(wait); }
  /// Ctrl-C: cancels the wait and abandons the script; with neither, arms the quit, and a second one
  /// within 1 s quits with kExitInterrupted.
  void interrupt(std::int64_t now_ns);
  /// The command in force was replaced by another participant's: a wait that measures it ends, not ok.
  void command_replaced(std::int64_t now_ns);
  void quit() { quit_ = true; }

  bool quitting() const { return quit_; }
  /// A wait holds input, or the script still runs.
  bool busy() const { return pending_.has_value() || script_running(); }
  /// Every input has ended: the script is done, nothing waits, and the console is at its end.
  bool done() const { return !busy() && (console_ == nullptr || console_->eof()); }
  const std::optional<Wait>& pending() const { return pending_; }
  int exit_status() const { return exit_status_; }

 private:
  bool script_running() const { return script_ && !script_->eof(); }
  /// The pending wait's outcome, reported; false while it still holds input.
  bool wait_over(std::int64_t now_ns);
  /// Ends the pending wait: the "wait" event with `extra` fields.
  void end_wait(bool ok, nlohmann::json extra, std::int64_t now_ns);

  Output& out_;
  const SwarmMonitor& monitor_;
  const CommandAuthority& authority_;
  Dispatch dispatch_;
  std::unique_ptr<ScriptSource> script_;
  LineSource* console_ = nullptr;
  std::optional<Wait> pending_;
  bool quit_ = false;
  int exit_status_ = kExitOk;
  std::int64_t armed_quit_ns_ = -1;  ///< when Ctrl-C last found nothing to cancel (-1: not armed)
};

}  // namespace shapeform::supervisor
