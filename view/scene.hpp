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

/// Points of the commanded shape at model time t (tracked shapes about C(t)), in world coordinates:
/// `n` points spread evenly by arc length on a closed curve, n + 1 from end to end on an open one,
/// and for the (infinite) line n + 1 points over +-line_half_length (shape units, before scale) about
/// the foot of the shape's origin.
std::vector<core::Vec2> outline(const core::CompiledCommand& cmd, double t, int n = 240,
                                double line_half_length = 100.0);

/// A bounded series of points, thinned as it grows: when full, every other point is dropped, so it
/// always spans the whole history at a coarser spacing (charts of a long run stay a fixed size).
class Series {
 public:
  /// capacity >= 4 points of `width` numbers each.
  Series(std::size_t capacity, std::size_t width);
  void push(const std::vector<double>& point);
  void clear() { points_.clear(); }
  std::size_t size() const { return points_.size(); }
  const std::vector<std::vector<double>>& points() const { return points_; }

 private:
  std::size_t capacity_;
  std::size_t width_;
  std::vector<std::vector<double>> points_;
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

  /// The frame the page draws at now_s (trails older than trail_s are dropped first):
  /// {"now_s", "model_time", "epoch", "converged",
  ///  "agents": [{"id", "x1", "x2", "state", "model_time", "epoch", "heard", "lateness_us", "heading"}],
  ///  "outline": {"points": [[x1, x2], ...], "closed"} or null, "centre": [x1, x2] or null,
  ///  "centre_path": [[x1, x2], ...], "trails": [{"id", "points": [[x1, x2], ...]}],
  ///  "keep_out": [{"circle": [cx, cy, r]} | {"polygon": [[x1, x2], ...]}] (the command's zones, [] without),
  ///  "min_separation": the command's d (0: off),
  ///  "chart": {"columns": ["model_time", "shape_error_mean", "gap_cv", "agents_alive", "min_separation",
  ///                        "min_separation_run"], "points": [[...], ...]},
  ///  "metrics": {"agents_alive", <every metric of core::kMetricTable>} or null,
  ///  "safety": {"min_separation_run", "min_separation_run_time", "filter_interventions",
  ///             "deadlock_sidesteps", "promises_broken", "agents_blocked", "fence_breaches",
  ///             "agents_beyond_fence"}: the latest metrics' run figures, each null when undefined}.
  /// Agent positions are exact; outline, centre path and trail points are rounded to 1e-4. "heading" is
  /// the vehicle's (rad), null without a pose heard within dead_s.
  nlohmann::json frame(double now_s);

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
};

}  // namespace shapeform::view
