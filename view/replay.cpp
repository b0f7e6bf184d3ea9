#include "replay.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <optional>

#include <nlohmann/json.hpp>

#include "config/config.hpp"
#include "core/metric_table.hpp"
#include "record/recorder.hpp"

namespace shapeform::view {

namespace fs = std::filesystem;

namespace {

/// One CSV file: its columns by header name and its rows, each read by column name.
class Table {
 public:
  Table(const fs::path& path, bool required) : path_(path) {
    std::ifstream in(path);
    if (!in) {
      if (required) throw RecordingError(path.string() + ": cannot read this file of the recording");
      return;
    }
    present_ = true;
    std::string line;
    if (!std::getline(in, line)) throw RecordingError(path.string() + ": empty file (no header line)");
    const auto header = fields(line, 1);
    for (std::size_t i = 0; i < header.size(); ++i) columns_[header[i]] = i;
    for (int n = 2; std::getline(in, line); ++n) {
      if (line.empty()) continue;
      rows_.push_back(fields(line, n));
      lines_.push_back(n);
    }
  }
  bool present() const { return present_; }
  std::size_t size() const { return rows_.size(); }
  bool has(const std::string& col) const { return columns_.count(col) > 0; }

  const std::string& text(std::size_t row, const std::string& col) const {
    const auto it = columns_.find(col);
    if (it == columns_.end()) throw RecordingError(path_.string() + ": no column '" + col + "' in the header");
    if (it->second >= rows_[row].size()) throw RecordingError(where(lines_[row]) + ": no field '" + col + "'");
    return rows_[row][it->second];
  }
  /// The number in column col; an empty field is nullopt.
  std::optional<double> optional_number(std::size_t row, const std::string& col) const {
    const std::string& s = text(row, col);
    if (s.empty()) return std::nullopt;
    std::size_t used = 0;
    double v = 0;
    try {
      v = std::stod(s, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != s.size() || !std::isfinite(v))
      throw RecordingError(where(lines_[row]) + ": column '" + col + "': not a number: '" + s.substr(0, 40) + "'");
    return v;
  }
  double number(std::size_t row, const std::string& col) const {
    const auto v = optional_number(row, col);
    if (!v) throw RecordingError(where(lines_[row]) + ": column '" + col + "' is empty");
    return *v;
  }
  std::string where(int line) const { return path_.string() + ":" + std::to_string(line); }
  /// Line n's fields (record::csv_fields), or RecordingError naming the file and line.
  std::vector<std::string> fields(const std::string& line, int n) const {
    try {
      return record::csv_fields(line);
    } catch (const std::invalid_argument& e) {
      throw RecordingError(where(n) + ": " + e.what());
    }
  }
  int line(std::size_t row) const { return lines_[row]; }

 private:
  fs::path path_;
  bool present_ = false;
  std::map<std::string, std::size_t> columns_;
  std::vector<std::vector<std::string>> rows_;
  std::vector<int> lines_;
};

std::uint64_t epoch_of(const Table& t, std::size_t row) {
  return t.has("epoch") ? static_cast<std::uint64_t>(t.number(row, "epoch")) : 0;
}

}  // namespace

fs::path recording_dir(const fs::path& dir) {
  if (fs::is_regular_file(dir / "metrics.csv")) return dir;
  if (fs::is_regular_file(dir / "record" / "metrics.csv")) return dir / "record";
  throw RecordingError((dir / "metrics.csv").string() + ": no such file (nor " + (dir / "record" / "metrics.csv").string() +
                       "): give a launcher run folder or a recording folder");
}

core::CompiledCommand command_from_json(const std::string& json_object) {
  const auto j = nlohmann::json::parse(json_object, nullptr, false);
  if (!j.is_object()) throw RecordingError("command: not a JSON object");
  std::vector<std::string> sets;
  for (const auto& [key, value] : j.items()) sets.push_back(key + "=" + (value.is_string() ? value.get<std::string>() : value.dump()));
  try {
    return config::load_string("schema_version: " + std::to_string(config::kSchemaVersion) + "\n", sets, "command").command;
  } catch (const config::ConfigError& e) {
    std::string all;
    for (const auto& p : e.problems()) all += (all.empty() ? "" : "; ") + p;
    throw RecordingError("command: " + all);
  }
}

Recording load_recording(const fs::path& given) {
  Recording r;
  r.dir = recording_dir(given);
  const Table metrics(r.dir / "metrics.csv", true);
  const Table positions(r.dir / "positions.csv", true);
  const Table commands(r.dir / "commands.csv", false);
  const Table centre(r.dir / "centre.csv", false);
  for (std::size_t i = 0; i < metrics.size(); ++i) {
    Recording::MetricsRow m;
    m.wall_s = metrics.number(i, "wall_s");
    m.model_time = metrics.number(i, "model_time");
    m.epoch = epoch_of(metrics, i);
    m.agents_alive = static_cast<int>(metrics.number(i, "agents_alive"));
    for (const core::MetricInfo& info : core::kMetricTable) {
      if (!metrics.has(std::string(info.name))) continue;  // a recording older than the metric: null
      if (const auto v = metrics.optional_number(i, std::string(info.name))) info.set(m.metrics, *v);
    }
    m.converged = metrics.number(i, "converged") != 0;
    r.metrics.push_back(m);
  }
  for (std::size_t i = 0; i < positions.size(); ++i) {
    Recording::PositionRow p;
    p.wall_s = positions.number(i, "wall_s");
    p.model_time = positions.number(i, "model_time");
    p.epoch = epoch_of(positions, i);
    p.agent = static_cast<std::int32_t>(positions.number(i, "agent"));
    p.x = core::Vec2(positions.number(i, "x1"), positions.number(i, "x2"));
    r.positions.push_back(p);
  }
  for (std::size_t i = 0; i < commands.size(); ++i) {
    try {
      r.commands.push_back({commands.number(i, "wall_s"), epoch_of(commands, i), command_from_json(commands.text(i, "command"))});
    } catch (const RecordingError& e) {
      throw RecordingError(commands.where(commands.line(i)) + ": " + e.what());
    }
  }
  for (std::size_t i = 0; i < centre.size(); ++i) {
    r.centre.push_back({centre.number(i, "wall_s"), core::Vec2(centre.number(i, "c1"), centre.number(i, "c2"))});
  }
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  const auto span = [&](double w) {
    lo = std::min(lo, w);
    hi = std::max(hi, w);
  };
  for (const auto& m : r.metrics) span(m.wall_s);
  for (const auto& p : r.positions) span(p.wall_s);
  for (const auto& c : r.commands) span(c.wall_s);
  if (!std::isfinite(lo)) throw RecordingError((r.dir / "metrics.csv").string() + ": the recording has no rows");
  r.start_s = lo;
  r.end_s = hi;
  return r;
}

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
