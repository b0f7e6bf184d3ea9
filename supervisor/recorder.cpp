#include "recorder.hpp"

#include <charconv>
#include <cmath>
#include <stdexcept>
#include <string>
#include <system_error>
#include <type_traits>

#include "core/metric_table.hpp"

namespace shapeform::supervisor {
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


void open_file(std::ofstream& f, const std::filesystem::path& path, const std::string& header) {
  f.open(path, std::ios::out | std::ios::trunc);
  if (!f) throw std::runtime_error("cannot open " + path.string() + " for writing");
  f << header << '\n' << std::flush;  // a recording always has its header on disk
  if (!f) throw std::runtime_error("cannot write " + path.string());
}

}  // namespace

std::string metrics_header() {
  std::string h = "wall_s,model_time,epoch,agents_alive";
  for (const core::MetricInfo& info : core::kMetricTable) (h += ',') += info.name;
  return h + ",converged";
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
  std::ofstream metrics, positions;
  open_file(metrics, dir / "metrics.csv", metrics_header());
  open_file(positions, dir / "positions.csv", kPositionsHeader);
  close();
  metrics_ = std::move(metrics);
  positions_ = std::move(positions);
  dir_ = dir;
  metrics_rows_ = position_rows_ = write_errors_ = 0;
  open_ = true;
  last_flush_ = Clock::now();
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
  metrics_ << line;
  ++metrics_rows_;
  check_streams();
}

void Recorder::write_positions(double wall_s, double model_time, std::optional<std::int64_t> step,
                               std::int32_t agent, double x1, double x2) {
  if (!open_) return;
  std::string line;
  line.reserve(96);
  append(line, wall_s);
  line += ',';
  append(line, model_time);
  line += ',';
  if (step) append(line, *step);
  line += ',';
  append(line, static_cast<std::int64_t>(agent));
  line += ',';
  append(line, x1);
  line += ',';
  append(line, x2);
  line += '\n';
  positions_ << line;
  ++position_rows_;
  check_streams();
}

void Recorder::flush_if_due(Clock::time_point now) {
  if (open_ && now - last_flush_ >= flush_period_) flush();
}

void Recorder::flush() {
  if (!open_) return;
  metrics_.flush();
  positions_.flush();
  check_streams();
  last_flush_ = Clock::now();
}

void Recorder::close() {
  if (!open_) return;
  flush();
  metrics_.close();
  positions_.close();
  if (!metrics_ || !positions_) ++write_errors_;
  metrics_.clear();
  positions_.clear();
  open_ = false;
}

void Recorder::check_streams() {
  // A failed write leaves the stream in a failed state; count it and keep trying later rows.
  for (std::ofstream* f : {&metrics_, &positions_}) {
    if (!*f) {
      ++write_errors_;
      f->clear();
    }
  }
}

}  // namespace shapeform::supervisor
