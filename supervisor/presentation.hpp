#pragma once
/// What the supervisor prints, as pure functions of what it knows (no DDS, no clocks, no streams):
/// the one-line description of a command, the `status` table and its JSON, the progress line, the
/// `metrics` answer and the exit summary (text and JSON).
#include <cstdint>
#include <cstddef>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/compiled_command.hpp"
#include "swarm_monitor.hpp"

namespace shapeform::supervisor {

/// One line: the shape and its parameters, tracking, law, gains and integration,
/// e.g. "circle r=4 centre (0, 0); k1=1 k2=1 sigma=1 beta=1 r=0, euler dt=1".
std::string describe_command(const core::CompiledCommand& c);

/// One agent as `status` shows it.
struct AgentRow {
  std::int32_t id = 0;
  bool alive = false;
  bool departed = false;      ///< not alive because it left cleanly (else: silent, "DEAD")
  double last_seen_s = 0.0;   ///< seconds since its last state
  core::Vec2 x = core::Vec2::Zero();
  std::uint64_t epoch = 0;    ///< command epoch it follows
  std::optional<double> shape_error;    ///< |x - x_T(x)| when it follows the current command
  std::optional<int> neighbours_heard;  ///< from its latest AgentStatus
  /// The safety filter, from its latest status of the current command: "held by 3", "held by zone 0",
  /// "held by the fence", "beyond the fence", or empty. Zones are numbered from 1, as `safety` lists them.
  std::string safety;
};

/// Every agent the monitor knows, ascending id, at now_ns; the shape error against the current
/// command's shape at model_time.
std::vector<AgentRow> agent_rows(const SwarmMonitor& monitor, std::int64_t now_ns, double model_time);

/// The console's `status` table: agent, alive, last seen, position, epoch followed, shape error,
/// neighbours heard; "(no agent heard yet)" without rows.
std::string status_table(const std::vector<AgentRow>& rows);

/// {"event":"status","epoch":E,"model_time":T,"agents":[{"id","alive","last_seen_s","x","y","epoch",
/// "shape_error" (null when unknown),"neighbours_heard" (null when unknown)}, ...]}.
nlohmann::json status_json(const std::vector<AgentRow>& rows, std::uint64_t epoch, double model_time);

/// The progress line logged about once a second.
std::string progress_line(const SwarmMonitor::Sample& s, const core::Command& current);

/// The `metrics` answer: every metric (app::metrics_json), epoch, model_time, converged, verdict
/// (core::to_string(ConvergenceDetector::Why): why not converged).
nlohmann::json metrics_answer(const SwarmMonitor::Sample& s, std::uint64_t epoch);

/// The `metrics` table: a heading line (epoch, model time, agents, converged), then one row per metric
/// of the metric table: name, value to 4 significant digits ("-" when undefined), unit.
std::string metrics_table(const SwarmMonitor::Sample& s, std::uint64_t epoch);

/// Decides when the progress line is printed: on change (the default), every S seconds, or never.
/// "Changed" means: the agents alive or following, the epoch, the converged flag or the cluster count
/// differ from the last printed line, or a metric moved by more than kRelTol of its last printed value
/// (moves of kAbsFloor or less ignored, so noise around zero prints nothing). On change, at most one line
/// per kMinInterval.
class ProgressFilter {
 public:
  static constexpr double kRelTol = 0.1;
  static constexpr double kAbsFloor = 1e-3;
  static constexpr std::int64_t kMinIntervalNs = 1'000'000'000;

  void on_change() { mode_ = Mode::OnChange; }
  void off() { mode_ = Mode::Off; }
  /// Every `seconds` (> 0) of wall time.
  void every(double seconds);
  /// True when the line for `s` (epoch `epoch`) should be printed at `now_ns`; it is then the
  /// reference for the next decision.
  bool due(const SwarmMonitor::Sample& s, std::uint64_t epoch, std::int64_t now_ns);

 private:
  enum class Mode { OnChange, Every, Off };
  bool changed(const SwarmMonitor::Sample& s, std::uint64_t epoch) const;
  Mode mode_ = Mode::OnChange;
  std::int64_t every_ns_ = 0;
  std::optional<SwarmMonitor::Sample> last_;
  std::uint64_t last_epoch_ = 0;
  std::int64_t last_ns_ = 0;
};

/// What `show` knows about the command in force.
struct ShowInfo {
  core::Command command;           ///< the command in force (before any: the --config one)
  std::uint64_t epoch = 0;         ///< its epoch; 0: none in force yet
  bool own = true;                 ///< published by this supervisor (else learnt from the command topic)
  std::string publisher;           ///< who published it, when not this supervisor ("NAME [GUID prefix]")
  double published_s_ago = 0.0;    ///< wall seconds since it was published (own) or learnt (another's)
  std::uint64_t superseded = 0;    ///< this supervisor's own last epoch when another's replaced it; 0: none
  std::uint64_t agents_epoch = 0;  ///< the newest epoch any agent follows (0: none heard)
  int alive = 0;
  int following = 0;               ///< alive agents on the command in force
};

/// The `show` answer: the epoch in force, who published it and when, how many agents follow it,
/// then one line each for the shape, tracking, law, gains, integrator and speed limit, then the safety
/// settings (safety_lines).
std::string show_text(const ShowInfo& info);

/// The safety settings of a command, one indented line each, as `safety` and `show` print them:
///   "  separation  0.25" ("off" when 0)
///   "  keep_out    2 zones" then "    1  circle centre (5, 0) r=1" / "    2  polygon (0, 0; 1, 0; 0, 1)"
///   "  fence       box [-1000, 1000]^2" or "polygon (x, y; ...)"
///   "  margin      0.5", "  breach      hold"
/// The zones are numbered from 1 in the order `safety keep_out remove K` takes them.
std::string safety_lines(const core::Command& c);

/// What the exit summary reports.
struct Summary {
  std::string name;             ///< the config's name
  core::Command command;        ///< in force at the end
  std::uint64_t epoch = 0;
  SwarmMonitor::Sample sample;  ///< measured at the end (its model_time is the summary's)
  std::size_t agents_seen = 0;
  std::optional<double> settle_time;  ///< model time the current epoch settled at
  /// Alive agents at the end, ascending id: position and own model time.
  std::vector<std::pair<std::int32_t, core::Vec2>> final_positions;
  std::vector<double> final_model_times;
  std::uint64_t samples_rejected = 0;
  std::uint64_t commands_refused = 0;  ///< commands refused: invalid, or an absurd epoch jump
  std::optional<std::string> recording;  ///< the folder being recorded into
  int exit_status = 0;
};

/// The summary as one JSON object: every metric (centroid_error and ring_error only when tracking),
/// name, shape, law, tracking, epoch, model_time, dt, steps, agents_seen, converged, verdict, settle_step,
/// final_ids, final_positions, final_model_times, samples_rejected, commands_refused, recording,
/// exit_status, and
/// "event":"summary".
nlohmann::json summary_json(const Summary& s);

/// The summary as text (two or three lines, each ending with a newline).
std::string summary_text(const Summary& s);

}  // namespace shapeform::supervisor
