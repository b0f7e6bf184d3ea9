#pragma once
/// The supervisor's console language: one line in, one action (or one error line) out.
/// Pure: no I/O, no clocks, no DDS. The main loop executes the actions.
///
/// Syntax: a command word (sometimes two: `shape circle`, `wait agents`), then positional values
/// and key=value parameters in any order. Tokens split on whitespace except inside double quotes;
/// quotes are stripped (`r="4 + 1"` gives key r, value `4 + 1`). A token starting with `#`
/// (outside quotes) starts a comment; blank and comment-only lines are no-ops.
#include <string>
#include <string_view>
#include <variant>

#include "core/compiled_command.hpp"

namespace shapeform::supervisor {

/// Empty line or comment: nothing to do.
struct NoOp {};

/// A new command to publish. Produced by shape, track (line/circle/point), gains, integrator,
/// max_speed and law; `command` is the caller's current command with the change applied. Shape and
/// track results are compiled anew (shapes::compile): a shape that cannot be built is a
/// parse error, so nothing is published.
struct SetCommand {
  enum class What { Shape, Track, Gains, Integrator, MaxSpeed, Law };
  What what = What::Shape;
  core::CompiledCommand command;
};

/// `track stop`: the caller disables tracking and keeps the shape where the tracked centre was.
struct TrackStop {};
/// `status`: print the current command, agents, loop statistics.
struct Status {};
/// `metrics`: print the latest metrics.
struct ShowMetrics {};
/// `wait converged [timeout=S]`: block further input until converged or timeout.
struct WaitConverged {
  double timeout_s = 60.0;
};
/// `wait agents N [timeout=S]`: block further input until at least `count` agents are alive.
struct WaitAgents {
  int count = 1;
  double timeout_s = 30.0;
};
/// `wait time T [timeout=S]`: block further input until the current epoch's model time reaches T.
struct WaitTime {
  double model_time = 0.0;
  double timeout_s = 600.0;
};
/// `sleep S`: block further input for S seconds of wall time.
struct Sleep {
  double seconds = 0.0;
};
/// `record start DIR`: start CSV recording into DIR (created if missing).
struct RecordStart {
  std::string dir;
};
/// `record stop`.
struct RecordStop {};
/// `help [command]`: `topic` is empty for the overview, else a known command word.
struct Help {
  std::string topic;
};
/// `quit` or `exit`.
struct Quit {};
/// Publish the supervisor's configured scenario (its --config command) as a new epoch.
struct StartScenario {};
/// `hold`, or `stop` (the emergency alias, same effect): the caller publishes the command in force
/// with Command::hold set (a new epoch): every agent keeps its position, model time stands still.
struct Hold {
  bool emergency = false;  ///< typed as `stop`
};
/// `resume`: the caller publishes the command in force with Command::hold cleared (a new epoch).
struct Resume {};

using Action = std::variant<NoOp, SetCommand, TrackStop, Status, ShowMetrics, WaitConverged, WaitAgents,
                            WaitTime, Sleep, RecordStart, RecordStop, Help, Quit, StartScenario, Hold, Resume>;

/// Either an action (error empty) or an error (action is NoOp).
struct ParseResult {
  Action action;
  std::string error;  ///< one line naming the command and what is wrong, e.g.
                      ///< `shape circle: r must be > 0, got -2`; empty on success
  bool ok() const { return error.empty(); }
};

/// Parses one console or script line. `current` is the command in force; commands that change it
/// return a copy of it with the change applied. Never throws for bad input.
ParseResult parse_command(std::string_view line, const core::CompiledCommand& current);

/// Help text: with an empty `command`, one line per command with its syntax; with a command word
/// (`shape`, `track`, `gains`, ...), the details of that command. Unknown words give a line saying
/// so. Every returned text ends with a newline.
std::string help_text(std::string_view command = {});

/// True when `help_text(word)` has a details page for `word`.
bool has_help(std::string_view word);

}  // namespace shapeform::supervisor
