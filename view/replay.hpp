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
#include "record/recording.hpp"
#include "scene.hpp"

namespace shapeform::view {

/// The recording replayed: read by record::load_recording (CSV folder or run.mcap).
using record::Recording;
using record::RecordingError;

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
