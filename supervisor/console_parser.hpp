#pragma once
/// The supervisor's console language: one line in, one action (or one error line) out.
/// Pure: no I/O, no clocks, no DDS. The main loop executes the actions.
///
/// Syntax: a command word (sometimes two: `shape circle`, `wait agents`), then positional values
/// and key=value parameters in any order. Tokens split on whitespace except inside double quotes;
/// quotes are stripped (`r="4 + 1"` gives key r, value `4 + 1`). A token starting with `#`
/// (outside quotes) starts a comment; blank and comment-only lines are no-ops.
#include <cstddef>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

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
/// `metrics`: print the latest metrics as a table; `metrics json`: as one JSON object.
struct ShowMetrics {
  bool json = false;
};
/// `show`: print the command in force, its epoch and who published it.
struct Show {};
/// `progress on|off|every S`: when the loop prints its progress line.
struct Progress {
  enum class Mode { OnChange, Off, Every };
  Mode mode = Mode::OnChange;
  double every_s = 0.0;  ///< Every: wall seconds between two lines (> 0)
};
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
/// `start [replace]`: publish the supervisor's configured scenario (its --config command) as a new
/// epoch; without `replace`, a command already in force is kept (unless --command-on-start replace).
struct StartScenario {
  bool replace = false;
};
/// `hold`, or `stop` (the emergency alias, same effect): the caller publishes the command in force
/// with Command::hold set (a new epoch): every agent keeps its position, model time stands still.
struct Hold {
  bool emergency = false;  ///< typed as `stop`
};
/// `resume`: the caller publishes the command in force with Command::hold cleared (a new epoch).
struct Resume {};

using Action = std::variant<NoOp, SetCommand, TrackStop, Status, ShowMetrics, WaitConverged, WaitAgents,
                            WaitTime, Sleep, RecordStart, RecordStop, Help, Quit, StartScenario, Show, Progress,
                            Hold, Resume>;

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

/// The key=value parameters and positional values of one command, declared once: the parser checks
/// parameters against `keys` and Tab completion offers them.
struct Syntax {
  std::string words;                ///< the command words: "gains", "shape circle"
  std::vector<std::string> keys;    ///< parameter names, e.g. {"k1", "k2", ...}
  std::vector<std::string> values;  ///< positional values offered by completion ("euler", "rk4")
};
const std::vector<Syntax>& syntax_table();

/// The command words (`shape`, `wait`, `quit`, `exit`, ...), in help order.
std::vector<std::string> command_words();

/// Tab completion of the word that ends `before_cursor` (the line up to the cursor): command words,
/// second words (shape kinds, track paths, wait conditions, record start/stop), positional values
/// (law and integrator names, help topics, progress modes) and parameter names, offered as "key=".
struct Completion {
  std::size_t start = 0;                ///< where the word being completed starts in the line
  std::vector<std::string> candidates;  ///< whole replacements for the word, sorted
};
Completion complete(std::string_view before_cursor);

}  // namespace shapeform::supervisor
