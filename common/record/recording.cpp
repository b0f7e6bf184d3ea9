#include "recording.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <optional>

#include <nlohmann/json.hpp>

#include "config/config.hpp"
#include "core/metric_table.hpp"
#include "record/mcap.hpp"
#include "record/recorder.hpp"

namespace shapeform::record {

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

/// start_s and end_s from every table's rows; RecordingError naming `where` when there is none.
void set_span(Recording& r, const std::string& where) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  const auto span = [&](double w) {
    lo = std::min(lo, w);
    hi = std::max(hi, w);
  };
  for (const auto& m : r.metrics) span(m.wall_s);
  for (const auto& p : r.positions) span(p.wall_s);
  for (const auto& c : r.commands) span(c.wall_s);
  if (!std::isfinite(lo)) throw RecordingError(where + ": the recording has no rows");
  r.start_s = lo;
  r.end_s = hi;
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

static Recording load_csv(const fs::path& given) {
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
    if (positions.has("step")) {
      if (const auto k = positions.optional_number(i, "step")) p.step = static_cast<std::int64_t>(*k);
    }
    p.agent = static_cast<std::int32_t>(positions.number(i, "agent"));
    p.x = core::Vec2(positions.number(i, "x1"), positions.number(i, "x2"));
    r.positions.push_back(p);
  }
  for (std::size_t i = 0; i < commands.size(); ++i) {
    try {
      Recording::CommandRow c;
      c.wall_s = commands.number(i, "wall_s");
      c.model_time = commands.has("model_time") ? commands.number(i, "model_time") : 0.0;
      c.epoch = epoch_of(commands, i);
      if (commands.has("issuer")) c.issuer = commands.text(i, "issuer");
      if (commands.has("issuer_name")) c.issuer_name = commands.text(i, "issuer_name");
      c.command = command_from_json(commands.text(i, "command"));
      r.commands.push_back(std::move(c));
    } catch (const RecordingError& e) {
      throw RecordingError(commands.where(commands.line(i)) + ": " + e.what());
    }
  }
  for (std::size_t i = 0; i < centre.size(); ++i) {
    Recording::CentreRow c;
    c.wall_s = centre.number(i, "wall_s");
    c.model_time = centre.has("model_time") ? centre.number(i, "model_time") : 0.0;
    c.epoch = epoch_of(centre, i);
    c.c = core::Vec2(centre.number(i, "c1"), centre.number(i, "c2"));
    r.centre.push_back(c);
  }
  set_span(r, (r.dir / "metrics.csv").string());
  return r;
}

namespace {

using json = nlohmann::json;

/// One JSON message of the recorder's channel `topic`, read by field name.
class JsonRow {
 public:
  JsonRow(const McapMessage& m, const std::string& topic, const std::string& file) : where_(file + ": " + topic) {
    where_ += " message " + std::to_string(m.sequence);
    j_ = json::parse(m.data.begin(), m.data.end(), nullptr, false);
    if (!j_.is_object()) throw RecordingError(where_ + ": not a JSON object");
  }
  const json& at(const char* key) const {
    const auto it = j_.find(key);
    if (it == j_.end()) throw RecordingError(where_ + ": no field '" + key + "'");
    return *it;
  }
  bool has(const char* key) const { return j_.contains(key) && !j_.at(key).is_null(); }
  double number(const char* key) const { return number_of(at(key), key); }
  std::optional<double> optional_number(const char* key) const {
    return has(key) ? std::optional<double>(number(key)) : std::nullopt;
  }
  double number_of(const json& v, const char* key) const {
    if (!v.is_number()) throw RecordingError(where_ + ": field '" + key + "': not a number: " + v.dump().substr(0, 40));
    return v.get<double>();
  }
  std::string text(const char* key) const {
    const json& v = at(key);
    if (!v.is_string()) throw RecordingError(where_ + ": field '" + key + "': not a string");
    return v.get<std::string>();
  }
  const json& raw() const { return j_; }
  const std::string& where() const { return where_; }

 private:
  std::string where_;
  json j_;
};

Recording load_mcap(const fs::path& file) {
  std::optional<McapReader> reader;
  try {
    reader.emplace(file);
  } catch (const std::exception& e) {
    throw RecordingError(e.what());
  }
  std::map<std::uint16_t, std::string> topics;
  for (const McapChannel& c : reader->channels()) topics[c.id] = c.topic;
  Recording r;
  r.dir = file;
  const std::string name = file.string();
  for (const McapMessage& m : reader->messages()) {
    const auto t = topics.find(m.channel);
    if (t == topics.end()) continue;
    const std::string& topic = t->second;
    if (topic == kMetricsTopic) {
      const JsonRow row(m, topic, name);
      Recording::MetricsRow x;
      x.wall_s = row.number("wall_s");
      x.model_time = row.number("model_time");
      x.epoch = static_cast<std::uint64_t>(row.number("epoch"));
      x.agents_alive = static_cast<int>(row.number("agents_alive"));
      for (const core::MetricInfo& info : core::kMetricTable) {
        const std::string key(info.name);
        if (const auto v = row.optional_number(key.c_str())) info.set(x.metrics, *v);
      }
      x.converged = row.at("converged").is_boolean() && row.at("converged").get<bool>();
      r.metrics.push_back(x);
    } else if (topic == kPositionsTopic) {
      const JsonRow row(m, topic, name);
      const double wall = row.number("wall_s"), model_time = row.number("model_time");
      std::optional<std::int64_t> step;
      if (const auto k = row.optional_number("step")) step = static_cast<std::int64_t>(*k);
      const json& agents = row.at("agents");
      if (!agents.is_array()) throw RecordingError(row.where() + ": field 'agents': not an array");
      for (const json& a : agents) {
        if (!a.is_object() || !a.contains("id") || !a.contains("x1") || !a.contains("x2"))
          throw RecordingError(row.where() + ": an agent without id, x1 or x2");
        Recording::PositionRow p;
        p.wall_s = wall;
        p.model_time = model_time;
        p.step = step;
        p.epoch = a.contains("epoch") ? static_cast<std::uint64_t>(row.number_of(a.at("epoch"), "epoch")) : 0;
        p.agent = static_cast<std::int32_t>(row.number_of(a.at("id"), "id"));
        p.x = core::Vec2(row.number_of(a.at("x1"), "x1"), row.number_of(a.at("x2"), "x2"));
        r.positions.push_back(p);
      }
    } else if (topic == kCommandsTopic) {
      const JsonRow row(m, topic, name);
      Recording::CommandRow c;
      c.wall_s = row.number("wall_s");
      c.model_time = row.number("model_time");
      c.epoch = static_cast<std::uint64_t>(row.number("epoch"));
      c.issuer = row.text("issuer");
      c.issuer_name = row.text("issuer_name");
      try {
        c.command = command_from_json(row.at("command").dump());
      } catch (const RecordingError& e) {
        throw RecordingError(row.where() + ": " + e.what());
      }
      r.commands.push_back(std::move(c));
    } else if (topic == kCentreTopic) {
      const JsonRow row(m, topic, name);
      Recording::CentreRow c;
      c.wall_s = row.number("wall_s");
      c.model_time = row.number("model_time");
      c.epoch = static_cast<std::uint64_t>(row.number("epoch"));
      c.c = core::Vec2(row.number("c1"), row.number("c2"));
      r.centre.push_back(c);
    }
  }
  set_span(r, name);
  return r;
}

}  // namespace

std::uint64_t write_mcap(const Recording& r, const fs::path& file, std::int64_t unix_ns) {
  Recorder rec;
  rec.open_mcap(file, unix_ns);
  std::size_t c = 0, e = 0, m = 0, p = 0;
  std::vector<AgentRow> sample;
  const double inf = std::numeric_limits<double>::infinity();
  const auto at = [&](const auto& rows, std::size_t i) { return i < rows.size() ? rows[i].wall_s : inf; };
  while (c < r.commands.size() || e < r.centre.size() || m < r.metrics.size() || p < r.positions.size()) {
    const double w = std::min({at(r.commands, c), at(r.centre, e), at(r.metrics, m), at(r.positions, p)});
    for (; c < r.commands.size() && r.commands[c].wall_s <= w; ++c) {
      const auto& x = r.commands[c];
      rec.write_command(x.wall_s, x.model_time, x.epoch, x.issuer, x.issuer_name, x.command);
    }
    for (; e < r.centre.size() && r.centre[e].wall_s <= w; ++e) {
      const auto& x = r.centre[e];
      rec.write_centre(x.wall_s, x.model_time, x.epoch, x.c.x(), x.c.y());
    }
    for (; m < r.metrics.size() && r.metrics[m].wall_s <= w; ++m) {
      const auto& x = r.metrics[m];
      rec.write_metrics({x.wall_s, x.model_time, x.epoch, x.agents_alive, x.metrics, x.converged});
    }
    // One sample: the rows of one wall_s and model time.
    while (p < r.positions.size() && r.positions[p].wall_s <= w) {
      const auto& first = r.positions[p];
      sample.clear();
      for (; p < r.positions.size() && r.positions[p].wall_s == first.wall_s &&
             r.positions[p].model_time == first.model_time;
           ++p)
        sample.push_back({r.positions[p].agent, r.positions[p].epoch, r.positions[p].x.x(), r.positions[p].x.y(), {}});
      rec.write_positions(first.wall_s, first.model_time, first.step, sample);
    }
  }
  const std::uint64_t n = rec.mcap_messages();
  rec.close();
  if (rec.write_errors() != 0) throw std::runtime_error("cannot write " + file.string());
  return n;
}

Recording load_recording(const fs::path& path) {
  if (fs::is_regular_file(path)) return load_mcap(path);
  return load_csv(path);
}

}  // namespace shapeform::record
