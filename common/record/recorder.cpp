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

Recorder::Recorder(double flush_s) {
  if (!std::isfinite(flush_s) || !(flush_s > 0.0)) {
    throw std::invalid_argument("Recorder: flush_s must be > 0, got " + std::to_string(flush_s));
  }
  flush_period_ =
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(flush_s));
}

Recorder::~Recorder() { close(); }

void Recorder::open(const std::filesystem::path& dir) {
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
  files_ = std::move(files);
  dir_ = dir;
  rows_ = {};
  write_errors_ = 0;
  open_ = true;
  last_flush_ = Clock::now();
}

void Recorder::add_row(File f, const std::string& line) {
  files_[f] << line;
  ++rows_[f];
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
}

void Recorder::write_positions(double wall_s, double model_time, std::optional<std::int64_t> step,
                               std::uint64_t epoch, std::int32_t agent, double x1, double x2) {
  if (!open_) return;
  add_row(kPositions, csv_row(wall_s, model_time, step, epoch, static_cast<std::int64_t>(agent), x1, x2));
}

void Recorder::write_command(double wall_s, double model_time, std::uint64_t epoch, std::string_view issuer,
                             std::string_view issuer_name, const core::Command& command) {
  if (!open_) return;
  add_row(kCommands, csv_row(wall_s, model_time, epoch, csv_field(issuer), csv_field(issuer_name),
                             csv_field(command_json(command))));
  flush();  // rare, and what every other row is read against
}

void Recorder::write_centre(double wall_s, double model_time, std::uint64_t epoch, double c1, double c2) {
  if (!open_) return;
  add_row(kCentre, csv_row(wall_s, model_time, epoch, c1, c2));
}

void Recorder::flush_if_due(Clock::time_point now) {
  if (open_ && now - last_flush_ >= flush_period_) flush();
}

void Recorder::flush() {
  if (!open_) return;
  for (auto& f : files_) f.flush();
  check_streams();
  last_flush_ = Clock::now();
}

void Recorder::close() {
  if (!open_) return;
  flush();
  for (auto& f : files_) {
    f.close();
    if (!f) ++write_errors_;
    f.clear();
  }
  open_ = false;
}

void Recorder::check_streams() {
  // A failed write leaves the stream in a failed state; count it and keep trying later rows.
  for (auto& f : files_) {
    if (!f) {
      ++write_errors_;
      f.clear();
    }
  }
}

}  // namespace shapeform::record
