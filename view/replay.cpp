#include "replay.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

#include <nlohmann/json.hpp>


namespace shapeform::view {

ReplayClock::ReplayClock(double start_s, double end_s, double real_s)
    : start_s_(start_s), end_s_(std::max(start_s, end_s)), anchor_pos_(start_s), anchor_real_(real_s) {}

double ReplayClock::position(double real_s) const {
  const double p = playing_ ? anchor_pos_ + (real_s - anchor_real_) * speed_ : anchor_pos_;
  return std::clamp(p, start_s_, end_s_);
}

void ReplayClock::anchor(double real_s) {
  anchor_pos_ = position(real_s);
  anchor_real_ = real_s;
}

void ReplayClock::play(double real_s) {
  anchor(real_s);
  if (anchor_pos_ >= end_s_) anchor_pos_ = start_s_;
  playing_ = true;
}

void ReplayClock::pause(double real_s) {
  anchor(real_s);
  playing_ = false;
}

void ReplayClock::set_speed(double speed, double real_s) {
  if (!(speed > 0 && speed <= 100)) throw std::invalid_argument("speed: expected a number in (0, 100]");
  anchor(real_s);
  speed_ = speed;
}

void ReplayClock::seek(double pos, double real_s) {
  anchor_real_ = real_s;
  anchor_pos_ = std::clamp(pos, start_s_, end_s_);
}

std::string apply_control(ReplayClock& clock, const std::string& action, double value, double real_s) {
  if (!std::isfinite(value)) return "value: expected a finite number";
  if (action == "play") {
    clock.play(real_s);
  } else if (action == "pause") {
    clock.pause(real_s);
  } else if (action == "speed") {
    if (!(value > 0 && value <= 100)) return "speed: expected a number in (0, 100], got " + std::to_string(value);
    clock.set_speed(value, real_s);
  } else if (action == "seek") {
    clock.seek(clock.start_s() + value, real_s);
  } else {
    return "unknown action '" + action.substr(0, 40) + "' (play, pause, speed, seek)";
  }
  return "";
}

nlohmann::json clock_json(const ReplayClock& clock, double real_s) {
  return {{"start_s", 0.0},
          {"end_s", clock.end_s() - clock.start_s()},
          {"position_s", clock.position(real_s) - clock.start_s()},
          {"playing", clock.playing(real_s)},
          {"speed", clock.speed()}};
}

void ReplayFeeder::advance(Scene& scene, double pos) {
  if (fed_any_ && pos < fed_) {
    scene.clear();
    metrics_ = positions_ = commands_ = centre_ = 0;
    fed_any_ = false;
  }
  const double from = pos - window_s_;
  if (!fed_any_ || from > fed_) {
    // Positions older than the window are never shown: skip them.
    const auto first = std::lower_bound(r_.positions.begin() + static_cast<std::ptrdiff_t>(positions_), r_.positions.end(), from,
                                        [](const Recording::PositionRow& p, double w) { return p.wall_s < w; });
    positions_ = static_cast<std::size_t>(first - r_.positions.begin());
  }
  // Commands first: the metrics and positions of a moment are measured against the command then in force.
  for (; commands_ < r_.commands.size() && r_.commands[commands_].wall_s <= pos; ++commands_)
    scene.on_command(r_.commands[commands_].command, r_.commands[commands_].epoch);
  for (; centre_ < r_.centre.size() && r_.centre[centre_].wall_s <= pos; ++centre_) scene.on_centre(r_.centre[centre_].c);
  for (; metrics_ < r_.metrics.size() && r_.metrics[metrics_].wall_s <= pos; ++metrics_) {
    const auto& m = r_.metrics[metrics_];
    scene.on_metrics(m.model_time, m.epoch, m.agents_alive, m.metrics, m.converged);
  }
  for (; positions_ < r_.positions.size() && r_.positions[positions_].wall_s <= pos; ++positions_) {
    const auto& p = r_.positions[positions_];
    scene.on_state(p.agent, p.x, p.model_time, p.epoch, p.wall_s);
  }
  fed_ = pos;
  fed_any_ = true;
}

}  // namespace shapeform::view
