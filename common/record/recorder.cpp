#include "recorder.hpp"

#include <charconv>
#include <cmath>
#include <stdexcept>
#include <string>
#include <system_error>
#include <type_traits>

#include <nlohmann/json.hpp>

#include "config/config.hpp"
#include "core/metric_table.hpp"
#include "viz/scene_update.hpp"

namespace shapeform::record {
namespace {

/// Appends v in its shortest round-trip form ("0.1", "-2", "1e-05"); non-finite: nothing.
void append(std::string& out, double v) {
  if (!std::isfinite(v)) return;
  char buf[32];
  const auto res = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, res.ptr);
}

template <class Int, class = std::enable_if_t<std::is_integral_v<Int>>>
void append(std::string& out, Int v) {
  char buf[24];
  const auto res = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, res.ptr);
}

/// An unknown value: nothing.
void append(std::string& out, const std::optional<std::int64_t>& v) {
  if (v) append(out, *v);
}

/// A field already in CSV form (csv_field).
void append(std::string& out, std::string_view field) { out += field; }

/// One CSV line of the fields, comma-separated, with its line end.
template <class... Fields>
std::string csv_row(const Fields&... fields) {
  std::string line;
  line.reserve(96);
  bool first = true;
  ((line += first ? "" : ",", first = false, append(line, fields)), ...);
  return line += '\n';
}

void open_file(std::ofstream& f, const std::filesystem::path& path, const std::string& header) {
  f.open(path, std::ios::out | std::ios::trunc);
  if (!f) throw std::runtime_error("cannot open " + path.string() + " for writing");
  f << header << '\n' << std::flush;  // a recording always has its header on disk
  if (!f) throw std::runtime_error("cannot write " + path.string());
}

/// The file names, in Recorder::File order.
constexpr const char* kFileNames[] = {"metrics.csv", "positions.csv", "commands.csv", "centre.csv"};

using json = nlohmann::ordered_json;

/// A JSON Schema of an object with these properties ({name: JSON Schema type or schema}).
std::string object_schema(const char* title, const json& properties) {
  return json{{"$schema", "https://json-schema.org/draft/2020-12/schema"}, {"title", title}, {"type", "object"},
              {"properties", properties}}
      .dump();
}

std::string metrics_schema() {
  json props = {{"wall_s", {{"type", "number"}}}, {"model_time", {{"type", "number"}}},
                {"epoch", {{"type", "integer"}}}, {"agents_alive", {{"type", "integer"}}}};
  for (const core::MetricInfo& info : core::kMetricTable)
    props[std::string(info.name)] = {{"type", json::array({info.count ? "integer" : "number", "null"})}};
  props["converged"] = {{"type", "boolean"}};
  return object_schema("shapeform.record.Metrics", props);
}

std::string positions_schema() {
  const json agent = {{"type", "object"},
                      {"properties",
                       {{"id", {{"type", "integer"}}}, {"epoch", {{"type", "integer"}}}, {"x1", {{"type", "number"}}},
                        {"x2", {{"type", "number"}}}, {"heading", {{"type", "number"}}}}}};
  return object_schema("shapeform.record.Positions",
                       {{"wall_s", {{"type", "number"}}}, {"model_time", {{"type", "number"}}},
                        {"step", {{"type", json::array({"integer", "null"})}}},
                        {"agents", {{"type", "array"}, {"items", agent}}}});
}

std::string commands_schema() {
  return object_schema("shapeform.record.Command",
                       {{"wall_s", {{"type", "number"}}}, {"model_time", {{"type", "number"}}},
                        {"epoch", {{"type", "integer"}}}, {"issuer", {{"type", "string"}}},
                        {"issuer_name", {{"type", "string"}}},
                        {"command", {{"type", "object"}, {"additionalProperties", {{"type", "string"}}}}}});
}

std::string centre_schema() {
  return object_schema("shapeform.record.Centre",
                       {{"wall_s", {{"type", "number"}}}, {"model_time", {{"type", "number"}}},
                        {"epoch", {{"type", "integer"}}}, {"c1", {{"type", "number"}}}, {"c2", {{"type", "number"}}}});
}

std::string events_schema() {
  return json{{"$schema", "https://json-schema.org/draft/2020-12/schema"},
              {"title", "shapeform.Event"},
              {"type", "object"},
              {"properties", {{"event", {{"type", "string"}}}, {"wall_s", {{"type", "number"}}}}},
              {"additionalProperties", true}}
      .dump();
}

/// A finite number, or null (JSON has no NaN or infinity).
json number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

}  // namespace

std::string metrics_header() {
  std::string h = "wall_s,model_time,epoch,agents_alive";
  for (const core::MetricInfo& info : core::kMetricTable) (h += ',') += info.name;
  return h + ",converged";
}

std::string command_json(const core::Command& c) {
  nlohmann::ordered_json j = nlohmann::ordered_json::object();
  for (const auto& [key, value] : config::command_settings(c)) j[key] = value;
  // A received expression is not checked for UTF-8: a stray byte becomes U+FFFD, never an exception.
  return j.dump(-1, ' ', false, nlohmann::ordered_json::error_handler_t::replace);
}

std::string csv_field(std::string_view s) {
  if (s.find_first_of(",\"\r\n") == std::string_view::npos) return std::string(s);
  std::string out = "\"";
  for (const char ch : s) {
    if (ch == '"') out += '"';
    out += ch;
  }
  return out + '"';
}

std::vector<std::string> csv_fields(std::string_view line) {
  std::vector<std::string> out(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char ch = line[i];
    if (quoted) {
      if (ch == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        out.back() += '"';
        ++i;
      } else if (ch == '"') {
        quoted = false;
      } else {
        out.back() += ch;
      }
    } else if (ch == '"') {
      quoted = true;
    } else if (ch == ',') {
      out.emplace_back();
    } else if (ch != '\r') {
      out.back() += ch;
    }
  }
  if (quoted) throw std::invalid_argument("unterminated quoted field");
  return out;
}

Recorder::Recorder(double flush_s, McapOptions mcap) : mcap_(std::move(mcap)) {
  if (!std::isfinite(flush_s) || !(flush_s > 0.0)) {
    throw std::invalid_argument("Recorder: flush_s must be > 0, got " + std::to_string(flush_s));
  }
  flush_period_ =
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(flush_s));
  const auto own = [&](const char* topic, const char* schema_name, const std::string& schema) {
    return add_channel({topic, schema_name, "jsonschema", schema, "json"});
  };
  metrics_ch_ = own(kMetricsTopic, "shapeform.record.Metrics", metrics_schema());
  positions_ch_ = own(kPositionsTopic, "shapeform.record.Positions", positions_schema());
  commands_ch_ = own(kCommandsTopic, "shapeform.record.Command", commands_schema());
  centre_ch_ = own(kCentreTopic, "shapeform.record.Centre", centre_schema());
  events_ch_ = own(kEventsTopic, "shapeform.Event", events_schema());
  const auto& viz = viz::scene_channels();
  const auto viz_channel = [&](std::size_t i) {
    const viz::Channel& c = viz[i];
    return add_channel({c.topic, c.schema_name, c.schema_encoding, std::string(c.schema), c.message_encoding});
  };
  scene_ch_ = viz_channel(viz::kSceneChannel);
  poses_ch_ = viz_channel(viz::kPosesChannel);
}

std::uint16_t Recorder::add_channel(const ChannelSpec& spec) {
  const std::uint16_t schema =
      spec.schema_name.empty() ? 0 : mcap_.add_schema(spec.schema_name, spec.schema_encoding, spec.schema);
  return mcap_.add_channel(schema, spec.topic, spec.message_encoding);
}

std::uint64_t Recorder::log_ns(double wall_s) const {
  const double ns = static_cast<double>(unix_ns_) + wall_s * 1e9;
  return ns > 0.0 && std::isfinite(ns) ? static_cast<std::uint64_t>(ns) : 0;
}

void Recorder::write_message(std::uint16_t channel, double wall_s, const std::uint8_t* data, std::size_t size) {
  if (!open_) return;
  const std::uint64_t t = log_ns(wall_s);
  mcap_.write(channel, t, t, data, size);
}

void Recorder::write_json(std::uint16_t channel, double wall_s, const std::string& text) {
  write_message(channel, wall_s, reinterpret_cast<const std::uint8_t*>(text.data()), text.size());
}

void Recorder::write_event(double wall_s, std::string_view json_object) {
  if (!open_) return;
  json e = json::parse(json_object, nullptr, false);
  if (!e.is_object()) return;  // the caller's own event lines are objects; anything else is not recorded
  e["wall_s"] = number(wall_s);
  write_json(events_ch_, wall_s, e.dump(-1, ' ', false, json::error_handler_t::replace));
}

Recorder::~Recorder() { close(); }

void Recorder::open(const std::filesystem::path& dir, std::int64_t unix_ns) {
  std::error_code ec;
  // Reopening the folder being written: finish it first (new streams would truncate its files).
  if (open_ && std::filesystem::equivalent(dir, dir_, ec)) close();
  std::filesystem::create_directories(dir, ec);
  if (ec) {
    throw std::runtime_error("cannot create recording directory " + dir.string() + ": " +
                             ec.message());
  }
  // The new files first: if they cannot be made, a recording in progress goes on untouched.
  const std::string headers[kFiles] = {metrics_header(), kPositionsHeader, kCommandsHeader, kCentreHeader};
  std::array<std::ofstream, kFiles> files;
  for (std::size_t f = 0; f < kFiles; ++f) open_file(files[f], dir / kFileNames[f], headers[f]);
  close();
  // run.mcap after the previous recording is closed (one writer); a failure leaves no recording open.
  mcap_.open(dir / kMcapFile);
  files_ = std::move(files);
  start(dir, unix_ns, true);
}

void Recorder::open_mcap(const std::filesystem::path& file, std::int64_t unix_ns) {
  close();
  mcap_.open(file);
  start(file.parent_path(), unix_ns, false);
}

void Recorder::start(const std::filesystem::path& dir, std::int64_t unix_ns, bool csv) {
  csv_ = csv;
  unix_ns_ = unix_ns;
  command_.reset();
  fixed_outline_.clear();
  command_epoch_ = 0;
  centre_.reset();
  dir_ = dir;
  rows_ = {};
  write_errors_ = 0;
  open_ = true;
  last_flush_ = Clock::now();
}

void Recorder::add_row(File f, const std::string& line) {
  ++rows_[f];
  if (!csv_) return;
  files_[f] << line;
  check_streams();
}

void Recorder::write_metrics(const MetricsRow& row) {
  if (!open_) return;
  std::string line;
  line.reserve(192);
  append(line, row.wall_s);
  line += ',';
  append(line, row.model_time);
  line += ',';
  append(line, row.epoch);
  line += ',';
  append(line, static_cast<std::int64_t>(row.agents_alive));
  for (const core::MetricInfo& info : core::kMetricTable) {
    line += ',';
    if (const auto v = info.get(row.metrics)) {
      if (info.count) append(line, static_cast<std::int64_t>(std::llround(*v)));
      else append(line, *v);
    }
  }
  line += row.converged ? ",1\n" : ",0\n";
  add_row(kMetrics, line);
  json j = {{"wall_s", number(row.wall_s)}, {"model_time", number(row.model_time)}, {"epoch", row.epoch},
            {"agents_alive", row.agents_alive}};
  for (const core::MetricInfo& info : core::kMetricTable) {
    const auto v = info.get(row.metrics);
    j[std::string(info.name)] = !v ? json(nullptr) : info.count ? json(std::llround(*v)) : number(*v);
  }
  j["converged"] = row.converged;
  write_json(metrics_ch_, row.wall_s, j.dump());
}

void Recorder::write_positions(double wall_s, double model_time, std::optional<std::int64_t> step,
                               const std::vector<AgentRow>& agents) {
  if (!open_) return;
  json list = json::array();
  for (const AgentRow& a : agents) {
    add_row(kPositions, csv_row(wall_s, model_time, step, a.epoch, static_cast<std::int64_t>(a.id), a.x1, a.x2));
    json j = {{"id", a.id}, {"epoch", a.epoch}, {"x1", number(a.x1)}, {"x2", number(a.x2)}};
    if (a.heading) j["heading"] = number(*a.heading);
    list.push_back(std::move(j));
  }
  write_json(positions_ch_, wall_s,
             json{{"wall_s", number(wall_s)}, {"model_time", number(model_time)},
                  {"step", step ? json(*step) : json(nullptr)}, {"agents", std::move(list)}}
                 .dump());
  write_scene(wall_s, model_time, agents);
}

void Recorder::write_scene(double wall_s, double model_time, const std::vector<AgentRow>& agents) {
  viz::SceneSnapshot s;
  s.agents.reserve(agents.size());
  for (const AgentRow& a : agents) s.agents.push_back({a.id, core::Vec2(a.x1, a.x2), viz::AgentLook::Alive, a.heading});
  if (command_) {
    if (command_->tracking.enabled) {
      s.outline = core::outline(*command_, model_time, s.outline_closed);
    } else {  // a fixed shape: drawn the same at every sample
      if (fixed_outline_.empty()) fixed_outline_ = core::outline(*command_, model_time, fixed_outline_closed_);
      s.outline = fixed_outline_;
      s.outline_closed = fixed_outline_closed_;
    }
    s.keep_out = command_->keep_out;
    s.fence = command_->fence;
    s.fence_margin = command_->fence_margin;
  }
  s.centre = centre_;
  const std::uint64_t t = log_ns(wall_s);
  write_json(scene_ch_, wall_s, viz::scene_update_json(s, t));
  write_json(poses_ch_, wall_s, viz::poses_json(s, t));
}

void Recorder::write_command(double wall_s, double model_time, std::uint64_t epoch, std::string_view issuer,
                             std::string_view issuer_name, const core::Command& command) {
  if (!open_) return;
  const std::string settings = command_json(command);
  add_row(kCommands, csv_row(wall_s, model_time, epoch, csv_field(issuer), csv_field(issuer_name), csv_field(settings)));
  write_json(commands_ch_, wall_s,
             json{{"wall_s", number(wall_s)}, {"model_time", number(model_time)}, {"epoch", epoch},
                  {"issuer", issuer}, {"issuer_name", issuer_name}, {"command", json::parse(settings)}}
                 .dump(-1, ' ', false, json::error_handler_t::replace));
  // The scene draws the command in force; a command that does not compile here (it did where it came
  // in force) is drawn without its outline.
  fixed_outline_.clear();
  try {
    command_ = core::compile(command);
  } catch (const std::exception&) {
    command_.reset();
  }
  command_epoch_ = epoch;
  centre_.reset();
  flush();  // rare, and what every other row is read against
}

void Recorder::write_centre(double wall_s, double model_time, std::uint64_t epoch, double c1, double c2) {
  if (!open_) return;
  add_row(kCentre, csv_row(wall_s, model_time, epoch, c1, c2));
  write_json(centre_ch_, wall_s,
             json{{"wall_s", number(wall_s)}, {"model_time", number(model_time)}, {"epoch", epoch},
                  {"c1", number(c1)}, {"c2", number(c2)}}
                 .dump());
  if (epoch == command_epoch_) centre_ = core::Vec2(c1, c2);
}

void Recorder::flush_if_due(Clock::time_point now) {
  if (open_ && now - last_flush_ >= flush_period_) flush();
}

void Recorder::flush() {
  if (!open_) return;
  if (csv_)
    for (auto& f : files_) f.flush();
  mcap_.flush();  // the chunk so far, complete on disk
  check_streams();
  last_flush_ = Clock::now();
}

void Recorder::close() {
  if (!open_) return;
  flush();
  for (auto& f : files_) {
    if (!csv_) break;
    f.close();
    if (!f) ++write_errors_;
    f.clear();
  }
  mcap_.close();  // its write errors stay counted in write_errors() until the next open()
  open_ = false;
}

void Recorder::check_streams() {
  // A failed write leaves the stream in a failed state; count it and keep trying later rows.
  if (!csv_) return;
  for (auto& f : files_) {
    if (!f) {
      ++write_errors_;
      f.clear();
    }
  }
}

}  // namespace shapeform::record
