#pragma once
/// What a console or script line asks the supervisor to do: one plain struct per action, produced by
/// the console language (console_parser.hpp) and executed by the Executor (executor.hpp), one
/// function per action. Pure data.
#include <string>
#include <variant>

#include "core/compiled_command.hpp"

namespace shapeform::supervisor {

/// Empty line or comment: nothing to do.
struct NoOp {};

/// A new command to publish. Produced by shape, track (line/circle/point), gains, integrator,
/// max_speed, law and safety (separation, keep_out, fence); `command` is the caller's current command with
/// the change applied. Shape and track results are compiled anew (shapes::compile): a shape that cannot be
/// built is a parse error, so nothing is published.
struct SetCommand {
  enum class What { Shape, Track, Gains, Integrator, MaxSpeed, Law, Safety };
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
/// `safety` or `safety show`: print the safety settings in force (separation, keep-out zones numbered
/// as `safety keep_out remove K` takes them, fence, its margin and breach action).
struct ShowSafety {};
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
                            WaitTime, Sleep, RecordStart, RecordStop, Help, Quit, StartScenario, Show,
                            Progress, Hold, Resume, ShowSafety>;

}  // namespace shapeform::supervisor
