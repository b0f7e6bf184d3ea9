#pragma once
/// What the viewer shows, without DDS, HTTP or clocks: the latest state of every agent, the command
/// in force with its outline (sampled with the core's curve code) and its keep-out zones, the tracked
/// centre and its path, trails of the last seconds, the metric charts of the current epoch and the
/// run's safety figures; and one frame of all that as JSON, the message the page draws. Fed by the
/// live DDS readers (view/live.cpp) or by a recording (view/replay.hpp) through the same calls;
/// `now_s` is the feeder's clock in seconds (the viewer's steady clock live, the recording's wall_s in
/// replay).
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/compiled_command.hpp"
#include "core/metrics.hpp"

namespace shapeform::view {


/// A bounded series of points, thinned as it grows: when full, every other point is dropped, so it
/// always spans the whole history at a coarser spacing (charts of a long run stay a fixed size).
class Series {
 public:
  /// capacity >= 4 points of `width` numbers each.
  Series(std::size_t capacity, std::size_t width);
  void push(const std::vector<double>& point);
  void clear() {
    points_.clear();
    ++generation_;
  }
  std::size_t size() const { return points_.size(); }
  /// Changes whenever points are dropped (thinning, clear): a reader that saw generation g and k
  /// points may append points()[k..] while generation() is still g, else it reads them all again.
  std::uint64_t generation() const { return generation_; }
  const std::vector<std::vector<double>>& points() const { return points_; }

 private:
  std::size_t capacity_;
  std::size_t width_;
  std::vector<std::vector<double>> points_;
  std::uint64_t generation_ = 0;
};

struct SceneParams {
  double stale_s = 0.3;   ///< an agent unheard for longer is drawn stale
  double dead_s = 1.0;    ///< ... and for longer than this (or disposed) dead
  double trail_s = 5.0;   ///< trails cover the last trail_s seconds (of now_s)
  double trail_step_s = 0.2;  ///< one trail point per agent every trail_step_s at most
  int outline_points = 240;
  std::size_t chart_capacity = 400;  ///< points per chart (Series)
  std::size_t centre_path_capacity = 400;
};

/// One agent as the viewer knows it.
struct AgentInfo {
  core::Vec2 x = core::Vec2::Zero();
  double model_time = 0.0;
  std::uint64_t epoch = 0;        ///< the command the agent follows (0: none)
  double last_seen_s = 0.0;       ///< now_s of its latest state
  bool departed = false;          ///< disposed its instance (left cleanly)
  std::optional<int> heard;                ///< neighbours heard (its latest status)
  std::optional<double> lateness_p99_us;   ///< its loop's lateness, p99 (its latest status)
  std::optional<double> heading;           ///< its vehicle's heading, rad (vehicle.interface ros2: its pose)
  double heading_seen_s = 0.0;             ///< now_s of that pose
  std::vector<std::pair<double, core::Vec2>> trail;  ///< (now_s, x), oldest first
  std::size_t trail_unsent = 0;   ///< trail points added since the last delta (the newest ones)
  nlohmann::json sent;            ///< its row in the last delta (null: never sent)
};

class Scene {
 public:
  explicit Scene(SceneParams p = {});

  void on_state(std::int32_t id, const core::Vec2& x, double model_time, std::uint64_t epoch, double now_s);
  void on_status(std::int32_t id, int heard, double lateness_p99_us);
  /// The heading (rad, counter-clockwise from the x1 axis) of agent id's vehicle, from its pose.
  void on_heading(std::int32_t id, double heading, double now_s);
  void on_departed(std::int32_t id);
  /// The command in force from now (the caller decides which one: dds::CommandArbiter live, the
  /// recording's order in replay).
  void on_command(const core::CompiledCommand& cmd, std::uint64_t epoch);
  /// The tracked centre C at model time t.
  void on_centre(const core::Vec2& c);
  /// A metrics sample of the supervisor (measured against `epoch`). A new epoch, or a model time
  /// going back, starts the charts and the centre path anew.
  void on_metrics(double model_time, std::uint64_t epoch, int agents_alive, const core::Metrics& m, bool converged);
  /// Forgets everything (replay seeks).
  void clear();

  /// "alive", "stale" or "dead" at now_s.
  const char* state(const AgentInfo& a, double now_s) const;
  const std::map<std::int32_t, AgentInfo>& agents() const { return agents_; }
  /// The lowest non-zero epoch an alive agent follows (0: none), what a viewer that knows no command
  /// yet judges epoch jumps from (dds::CommandArbiter).
  std::uint64_t min_epoch_followed(double now_s) const;
  /// The model time shown: the latest metrics sample's, else the largest of the agents'.
  double model_time() const;
  /// Read-only views for other drawings of the same scene (view/foxglove_scene.hpp).
  const SceneParams& params() const { return p_; }
  const std::optional<core::CompiledCommand>& command() const { return command_; }
  const std::optional<core::Vec2>& centre() const { return centre_; }

  /// The frames the page draws. A stream starts with a snapshot (full: everything the page keeps) and
  /// goes on with deltas (what changed since the previous delta); the page keeps the trails, the
  /// centre path and the charts itself. Both are one JSON object:
  /// {"seq": the number of the delta this frame is (or, in a snapshot, the latest delta's),
  ///  "full": true in a snapshot and in a delta that replaces everything (the first one, and the first
  ///          after clear() or after now_s went back): the page forgets what it kept,
  ///  "now_s", "model_time", "epoch", "converged", "trail_s" (every frame),
  ///  "agent_columns": ["id", "x1", "x2", "state", "model_time", "epoch", "heard", "lateness_us", "heading"],
  ///  "agents": [[...], ...]: one row per agent in those columns; a delta has only the agents whose row
  ///            changed (position, state, status, heading); agents are never removed (dead stays drawn),
  ///  "trails": [id, t, x1, x2, id, t, x1, x2, ...]: the trail points added (all of them when full), t
  ///            the now_s they were added at; the page drops points older than now_s - trail_s,
  ///  "centre": [x1, x2] or null (every frame),
  ///  "centre_path": {"replace": bool, "points": [[x1, x2], ...]}: the points to append, or with replace
  ///                 the whole path (full, thinned or started anew),
  ///  "chart": {"columns": ["model_time", "shape_error_mean", "gap_cv", "agents_alive",
  ///            "min_separation", "min_separation_run"], "replace": bool, "points": [[...], ...]}: likewise,
  ///  "outline": {"points": [[x1, x2], ...], "closed"} or null, "keep_out": [{"circle": [cx, cy, r]} |
  ///            {"polygon": [[x1, x2], ...]}] (the command's zones, [] without), "fence": {"polygon",
  ///            "margin", "action"} or null, "min_separation": the command's d (0: off): in a delta only
  ///            when changed since the previous delta (absent: as before),
  ///  "metrics": {"agents_alive", <every metric of core::kMetricTable>} or null,
  ///  "safety": {"min_separation_run", "min_separation_run_time", "filter_interventions",
  ///             "deadlock_sidesteps", "promises_broken", "agents_blocked", "fence_breaches",
  ///             "agents_beyond_fence"}: the latest metrics' run figures, each null when undefined}.
  /// Rounding: agent, trail, outline and centre positions to 1e-4 (shape units; a 1000-unit-wide view on
  /// a 10,000-pixel screen still shows no step), trail times to 1e-3 s, headings to 1e-4 rad,
  /// lateness to 0.1 us; model times, chart values, zones and fence exact. "heading" is the vehicle's
  /// (rad), null without a pose heard within dead_s. Trails older than trail_s are dropped first.

  /// The next delta at now_s: numbered seq + 1, full when the page must start anew.
  nlohmann::json delta(double now_s);
  /// Everything at now_s, numbered like the latest delta, full. Called right after delta() with the same
  /// now_s and no call between, it is the state the next delta applies to (what a stream that joins or
  /// fell behind starts from).
  nlohmann::json snapshot(double now_s);
  /// The number of the latest delta (0: none yet).
  std::uint64_t seq() const { return seq_; }

 private:
  SceneParams p_;
  std::map<std::int32_t, AgentInfo> agents_;
  std::optional<core::CompiledCommand> command_;
  std::uint64_t epoch_ = 0;  ///< of the command in force
  std::optional<core::Vec2> centre_;
  Series centre_path_;
  Series chart_;
  std::uint64_t chart_epoch_ = 0;
  std::optional<double> metrics_time_;
  nlohmann::json metrics_ = nullptr;
  bool converged_ = false;
  // What the latest delta sent (the page holds it).
  std::uint64_t seq_ = 0;
  bool full_next_ = true;
  std::uint64_t chart_sent_generation_ = 0, centre_path_sent_generation_ = 0;
  std::size_t chart_sent_ = 0, centre_path_sent_ = 0;
  nlohmann::json sent_outline_, sent_keep_out_, sent_fence_, sent_min_separation_;

  nlohmann::json build(double now_s, bool full, bool record);
};

}  // namespace shapeform::view
