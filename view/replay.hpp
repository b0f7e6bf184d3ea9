#pragma once
/// Replay of a recording (docs/RECORDING.md): the files read into memory, the replay clock (play,
/// pause, speed, seek) and the feeder that hands a Scene what was recorded up to a moment. No DDS,
/// no HTTP, no clock of its own: every call takes the times it needs.
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/compiled_command.hpp"
#include "core/metrics.hpp"
#include "scene.hpp"

namespace shapeform::view {

/// A recording that cannot be read: the message names the file (and line).
class RecordingError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The recording's rows, each table in file order (wall_s ascending).
struct Recording {
  struct MetricsRow {
    double wall_s = 0, model_time = 0;
    std::uint64_t epoch = 0;
    int agents_alive = 0;
    core::Metrics metrics;
    bool converged = false;
  };
  struct PositionRow {
    double wall_s = 0, model_time = 0;
    std::uint64_t epoch = 0;  ///< 0 when the file has no epoch column
    std::int32_t agent = 0;
    core::Vec2 x = core::Vec2::Zero();
  };
  struct CommandRow {
    double wall_s = 0;
    std::uint64_t epoch = 0;
    core::CompiledCommand command;
  };
  struct CentreRow {
    double wall_s = 0;
    core::Vec2 c = core::Vec2::Zero();
  };
  std::filesystem::path dir;  ///< the folder holding the files
  std::vector<MetricsRow> metrics;
  std::vector<PositionRow> positions;
  std::vector<CommandRow> commands;  ///< empty when commands.csv is absent (older recordings)
  std::vector<CentreRow> centre;     ///< empty when centre.csv is absent (not tracking)
  double start_s = 0, end_s = 0;     ///< wall_s of the first and last row of any table
};

/// The folder of a recording: `dir` when it holds metrics.csv, else dir/record (a launcher's run
/// folder). Throws RecordingError naming the missing file.
std::filesystem::path recording_dir(const std::filesystem::path& dir);

/// A command of commands.csv: its JSON object of config keys to values (as --set takes them)
/// loaded through the config loader. Throws RecordingError with the loader's problems.
core::CompiledCommand command_from_json(const std::string& json_object);

/// Reads metrics.csv and positions.csv (required) and commands.csv and centre.csv (when present)
/// from recording_dir(dir). Columns are found by their header names. Throws RecordingError naming the
/// file, the line and the column of the first problem.
Recording load_recording(const std::filesystem::path& dir);

/// The replay's clock: a position in recording time (wall_s) that advances at `speed` times real
/// time while playing, clamped to [start_s, end_s]. `real_s` is any steady clock in seconds.
class ReplayClock {
 public:
  ReplayClock(double start_s, double end_s, double real_s);
  double position(double real_s) const;
  /// Playing and not yet at the end.
  bool playing(double real_s) const { return playing_ && position(real_s) < end_s_; }
  double speed() const { return speed_; }
  double start_s() const { return start_s_; }
  double end_s() const { return end_s_; }
  /// Plays from where it is (from the start when at the end).
  void play(double real_s);
  void pause(double real_s);
  /// speed in (0, 100]; throws std::invalid_argument otherwise.
  void set_speed(double speed, double real_s);
  /// Moves to pos (clamped), playing or paused as before.
  void seek(double pos, double real_s);

 private:
  void anchor(double real_s);
  double start_s_, end_s_;
  double anchor_pos_, anchor_real_;
  bool playing_ = true;
  double speed_ = 1.0;
};

/// A control of the page applied to the clock: "play", "pause", "speed" (value: the speed) or "seek"
/// (value: seconds from the recording's start). "" when done, else why not ("unknown action 'x'
/// (play, pause, speed, seek)", "speed: expected a number in (0, 100]").
std::string apply_control(ReplayClock& clock, const std::string& action, double value, double real_s);

/// The clock as the page shows it: {"start_s", "end_s", "position_s", "playing", "speed"}, times in
/// seconds from the recording's start (position_s = position - start_s).
nlohmann::json clock_json(const ReplayClock& clock, double real_s);

/// Feeds a Scene from a Recording as the replay's position moves: everything recorded up to the
/// position (positions only within `window_s` before it, enough for trails and for the stale and dead
/// states). Going back clears the scene and feeds it again.
class ReplayFeeder {
 public:
  ReplayFeeder(const Recording& r, double window_s) : r_(r), window_s_(window_s) {}
  void advance(Scene& scene, double pos);

 private:
  const Recording& r_;
  double window_s_;
  bool fed_any_ = false;
  double fed_ = 0.0;
  std::size_t metrics_ = 0, positions_ = 0, commands_ = 0, centre_ = 0;
};

}  // namespace shapeform::view
