#pragma once
/// A run's recording: the one layout that the supervisor (--record, `record start`) and the simulator
/// (--record) write, and that shapeform_view --replay and scripts/plot_run.py read. docs/RECORDING.md
/// documents every file, column and channel with its unit. No DDS, no clocks: the caller gives every time.
///
///   DIR/metrics.csv    one row per metrics sample
///   DIR/positions.csv  one row per agent per sample
///   DIR/commands.csv   one row per command that comes in force (the full command, as --set settings)
///   DIR/centre.csv     one row per published tracked centre (header only when nothing is tracked)
///   DIR/run.mcap       the same four tables as JSON channels (shapeform/record/*), the events, the
///                      swarm drawn for Foxglove (viz::scene_channels), and the caller's own channels
///                      (the supervisor: every DDS sample it reads or writes, as CDR)
#include <array>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/compiled_command.hpp"
#include "core/metrics.hpp"
#include "record/mcap.hpp"

namespace shapeform::record {

/// One row of metrics.csv. Undefined metrics (std::nullopt) and non-finite numbers are written as
/// empty fields.
struct MetricsRow {
  double wall_s = 0.0;      ///< seconds since the writing program started (steady clock)
  double model_time = 0.0;  ///< model time of the sample, in the epoch's own clock
  std::uint64_t epoch = 0;  ///< epoch of the command measured against (the one in force; 0: none)
  int agents_alive = 0;
  core::Metrics metrics;   ///< metrics.agents is not written (agents_alive is)
  bool converged = false;  ///< written as 0 / 1
};

/// One agent of a positions sample.
struct AgentRow {
  std::int32_t id = 0;
  std::uint64_t epoch = 0;  ///< of the command the agent follows
  double x1 = 0.0, x2 = 0.0;
  std::optional<double> heading;  ///< rad, counter-clockwise from x1; nullopt: not known (no vehicle)
};

/// A channel of run.mcap whose messages the caller makes (Recorder::add_channel).
struct ChannelSpec {
  std::string topic;
  std::string schema_name;      ///< "" : a channel without schema
  std::string schema_encoding;  ///< "omgidl", "jsonschema", ...
  std::string schema;           ///< the schema's text
  std::string message_encoding;  ///< "cdr", "json", ...
};

/// The recorder's own channels of run.mcap: the four tables, one JSON message per CSV row (positions:
/// one per sample, every agent in it), and the caller's events. docs/RECORDING.md gives their fields.
inline constexpr const char* kMetricsTopic = "shapeform/record/metrics";
inline constexpr const char* kPositionsTopic = "shapeform/record/positions";
inline constexpr const char* kCommandsTopic = "shapeform/record/commands";
inline constexpr const char* kCentreTopic = "shapeform/record/centre";
inline constexpr const char* kEventsTopic = "shapeform/events";
/// The MCAP file of a recording folder.
inline constexpr const char* kMcapFile = "run.mcap";

/// Header line of metrics.csv (without the newline): wall_s,model_time,epoch,agents_alive, the
/// names of core::kMetricTable, converged.
std::string metrics_header();
/// Header lines of the other files (without the newline).
inline constexpr const char* kPositionsHeader = "wall_s,model_time,step,epoch,agent,x1,x2";
inline constexpr const char* kCommandsHeader = "wall_s,model_time,epoch,issuer,issuer_name,command";
inline constexpr const char* kCentreHeader = "wall_s,model_time,epoch,c1,c2";

/// The `command` field of commands.csv: one JSON object mapping every command key of the config table to
/// its value as --set takes it (config::command_settings), in table order, e.g.
/// {"shape.kind":"circle","shape.r0":"1.0",...,"dynamics.hold":"false",...}.
std::string command_json(const core::Command& c);
/// `s` as one CSV field (RFC 4180): as it is, or double-quoted with inner quotes doubled when it holds
/// a comma, a double quote or a line break.
std::string csv_field(std::string_view s);
/// One CSV line split into its fields, the inverse of csv_field (RFC 4180: a quoted field may hold
/// commas and doubled quotes; a trailing '\r' is dropped). Throws std::invalid_argument on an
/// unterminated quote.
std::vector<std::string> csv_fields(std::string_view line);

/// Writes the four CSV files and run.mcap. Not thread-safe: use from one thread (the writing program's
/// loop). Numbers are written locale-independently in their shortest round-trip form.
class Recorder {
 public:
  using Clock = std::chrono::steady_clock;

  /// flush_s: longest time between flushes when flush_if_due() is called every tick (> 0); each flush
  /// also ends run.mcap's chunk, so a recording killed hard keeps all but the last flush_s.
  explicit Recorder(double flush_s = 1.0, McapOptions mcap = {});
  ~Recorder();
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  /// Creates `dir` (and parents) and opens the four files and run.mcap in it, truncating them, and
  /// writes their headers; then closes a previous recording. unix_ns: the Unix time (ns) of wall_s 0,
  /// what run.mcap's log times count from (wall_s + unix_ns), so that tools show the run's real time.
  /// Throws std::runtime_error naming the path on failure; a recording in progress then goes on.
  void open(const std::filesystem::path& dir, std::int64_t unix_ns = 0);

  /// Only an MCAP file (no CSV files): `file`, with the same channels (shapeform_mcap convert).
  void open_mcap(const std::filesystem::path& file, std::int64_t unix_ns = 0);

  /// A channel of run.mcap the caller writes (write_message); kept for later recordings. Returns its id.
  std::uint16_t add_channel(const ChannelSpec& spec);
  /// Appends one message of a channel of add_channel (its bytes as they are). Ignored when not open.
  void write_message(std::uint16_t channel, double wall_s, const std::uint8_t* data, std::size_t size);
  void write_message(std::uint16_t channel, double wall_s, const std::vector<std::uint8_t>& bytes) {
    write_message(channel, wall_s, bytes.data(), bytes.size());
  }
  /// Appends one event (a JSON object, as the program prints it with --json) to shapeform/events.
  void write_event(double wall_s, std::string_view json_object);
  bool is_open() const { return open_; }
  /// The directory of the current (or last) recording.
  const std::filesystem::path& dir() const { return dir_; }

  /// Appends a metrics row. Ignored when not open (as every write_*).
  void write_metrics(const MetricsRow& row);
  /// Appends one sample of the agents' positions (shape units): a row per agent in positions.csv, and
  /// in run.mcap one positions message and the swarm drawn (foxglove.SceneUpdate and PosesInFrame,
  /// with the command in force's outline, zones and fence, and the tracked centre). step nullopt
  /// (unknown) is an empty field.
  void write_positions(double wall_s, double model_time, std::optional<std::int64_t> step,
                       const std::vector<AgentRow>& agents);
  /// Appends a command that came in force: issuer is its publisher's GUID prefix (dds::to_string; ""
  /// when it has none, as in the simulator), issuer_name its publisher in words.
  void write_command(double wall_s, double model_time, std::uint64_t epoch, std::string_view issuer,
                     std::string_view issuer_name, const core::Command& command);
  /// Appends one tracked centre C(model_time), shape units.
  void write_centre(double wall_s, double model_time, std::uint64_t epoch, double c1, double c2);

  /// Flushes when at least flush_s has passed since the last flush (or open).
  void flush_if_due(Clock::time_point now);
  /// Flushes every file now.
  void flush();
  /// Flushes and closes; safe to call when not open and more than once.
  void close();

  /// Rows written since open().
  std::uint64_t metrics_rows() const { return rows_[kMetrics]; }
  std::uint64_t position_rows() const { return rows_[kPositions]; }
  std::uint64_t command_rows() const { return rows_[kCommands]; }
  std::uint64_t centre_rows() const { return rows_[kCentre]; }
  /// Failed writes or flushes since open() (disk full, ...). The loop reports and carries on.
  std::uint64_t write_errors() const { return write_errors_ + mcap_.write_errors(); }
  /// Messages written to run.mcap since open().
  std::uint64_t mcap_messages() const { return mcap_.messages(); }

 private:
  enum File : std::size_t { kMetrics, kPositions, kCommands, kCentre, kFiles };
  void add_row(File f, const std::string& line);
  void check_streams();
  /// run.mcap's log time of wall_s.
  std::uint64_t log_ns(double wall_s) const;
  void write_json(std::uint16_t channel, double wall_s, const std::string& json);
  void write_scene(double wall_s, double model_time, const std::vector<AgentRow>& agents);
  /// What open() and open_mcap() share once the files are made.
  void start(const std::filesystem::path& dir, std::int64_t unix_ns, bool csv);

  Clock::duration flush_period_;
  std::filesystem::path dir_;
  std::array<std::ofstream, kFiles> files_;
  std::array<std::uint64_t, kFiles> rows_{};
  bool open_ = false;
  Clock::time_point last_flush_{};
  std::uint64_t write_errors_ = 0;

  McapWriter mcap_;
  bool csv_ = true;  ///< false: open_mcap (the CSV streams stay closed)
  std::int64_t unix_ns_ = 0;
  std::uint16_t metrics_ch_ = 0, positions_ch_ = 0, commands_ch_ = 0, centre_ch_ = 0, events_ch_ = 0;
  std::uint16_t scene_ch_ = 0, poses_ch_ = 0;
  std::optional<core::CompiledCommand> command_;  ///< the command in force (its outline, zones, fence)
  /// command_'s outline while it does not track (it does not move then; empty: not computed yet).
  std::vector<core::Vec2> fixed_outline_;
  bool fixed_outline_closed_ = false;
  std::uint64_t command_epoch_ = 0;
  std::optional<core::Vec2> centre_;  ///< the last tracked centre of the command in force
};

}  // namespace shapeform::record
