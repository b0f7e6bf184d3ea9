#pragma once
/// CSV recording of a run: DIR/metrics.csv (one row per metrics sample) and DIR/positions.csv
/// (one row per agent state). No DDS; the supervisor's loop feeds it.
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>

#include "core/metrics.hpp"

namespace shapeform::supervisor {

/// One row of metrics.csv. Undefined metrics (std::nullopt) and non-finite numbers are written as
/// empty fields.
struct MetricsRow {
  double wall_s = 0.0;      ///< seconds since the supervisor started (steady clock)
  double model_time = 0.0;  ///< model time of the sample
  std::uint64_t epoch = 0;  ///< epoch of the command measured against (the one in force)
  int agents_alive = 0;
  core::Metrics metrics;   ///< metrics.agents is not written (agents_alive is)
  bool converged = false;  ///< written as 0 / 1
};

/// Header line of metrics.csv (without the newline): wall_s,model_time,epoch,agents_alive, the
/// names of core::kMetricTable, converged.
std::string metrics_header();
/// Header line of positions.csv (without the newline). The simulator writes the last four columns.
inline constexpr const char* kPositionsHeader = "wall_s,model_time,step,agent,x1,x2";

/// Writes the two CSV files. Not thread-safe: use from one thread (the supervisor's loop).
/// Numbers are written locale-independently in their shortest round-trip form.
class Recorder {
 public:
  using Clock = std::chrono::steady_clock;

  /// flush_s: longest time between flushes when flush_if_due() is called every tick (> 0).
  explicit Recorder(double flush_s = 1.0);
  ~Recorder();
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  /// Creates `dir` (and parents) and opens DIR/metrics.csv and DIR/positions.csv, truncating
  /// them, and writes the headers; then closes a previous recording.
  /// Throws std::runtime_error naming the path on failure; a recording in progress then goes on.
  void open(const std::filesystem::path& dir);
  bool is_open() const { return open_; }
  /// The directory of the current (or last) recording.
  const std::filesystem::path& dir() const { return dir_; }

  /// Appends a metrics row. Ignored when not open.
  void write_metrics(const MetricsRow& row);
  /// Appends one agent position; step nullopt (unknown) is an empty field. Ignored when not open.
  void write_positions(double wall_s, double model_time, std::optional<std::int64_t> step,
                       std::int32_t agent, double x1, double x2);

  /// Flushes when at least flush_s has passed since the last flush (or open).
  void flush_if_due(Clock::time_point now);
  /// Flushes both files now.
  void flush();
  /// Flushes and closes; safe to call when not open and more than once.
  void close();

  /// Rows written since open().
  std::uint64_t metrics_rows() const { return metrics_rows_; }
  std::uint64_t position_rows() const { return position_rows_; }
  /// Failed writes or flushes since open() (disk full, ...). The loop reports and carries on.
  std::uint64_t write_errors() const { return write_errors_; }

 private:
  void check_streams();

  Clock::duration flush_period_;
  std::filesystem::path dir_;
  std::ofstream metrics_;
  std::ofstream positions_;
  bool open_ = false;
  Clock::time_point last_flush_{};
  std::uint64_t metrics_rows_ = 0;
  std::uint64_t position_rows_ = 0;
  std::uint64_t write_errors_ = 0;
};

}  // namespace shapeform::supervisor
