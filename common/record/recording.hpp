#pragma once
/// A recording read back (docs/RECORDING.md): the CSV folder the Recorder writes, or its run.mcap (the
/// recorder's own channels, shapeform/record/*), into one in-memory form that shapeform_view --replay
/// plays and shapeform_mcap convert writes as MCAP. No DDS, no clocks.
#include <cstdint>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/compiled_command.hpp"
#include "core/metrics.hpp"
#include "record/recorder.hpp"

namespace shapeform::record {

/// A recording that cannot be read: the message names the file (and line, or channel).
class RecordingError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The recording's rows, each table in file order (wall_s ascending).
struct Recording {
  using MetricsRow = record::MetricsRow;  ///< the recorder's row, read back
  struct PositionRow {
    double wall_s = 0, model_time = 0;
    std::optional<std::int64_t> step;  ///< nullopt: not known
    std::uint64_t epoch = 0;           ///< 0 when the file has no epoch column
    std::int32_t agent = 0;
    core::Vec2 x = core::Vec2::Zero();
  };
  struct CommandRow {
    double wall_s = 0, model_time = 0;
    std::uint64_t epoch = 0;
    std::string issuer, issuer_name;
    core::CompiledCommand command;
  };
  struct CentreRow {
    double wall_s = 0, model_time = 0;
    std::uint64_t epoch = 0;
    core::Vec2 c = core::Vec2::Zero();
  };
  std::filesystem::path dir;  ///< the folder holding the CSV files, or the .mcap file
  std::vector<MetricsRow> metrics;
  std::vector<PositionRow> positions;
  std::vector<CommandRow> commands;  ///< empty when commands.csv is absent (older recordings)
  std::vector<CentreRow> centre;     ///< empty when centre.csv is absent (not tracking)
  double start_s = 0, end_s = 0;     ///< wall_s of the first and last row of any table
};

/// The folder of a CSV recording: `dir` when it holds metrics.csv, else dir/record (a launcher's run
/// folder). Throws RecordingError naming the missing file.
std::filesystem::path recording_dir(const std::filesystem::path& dir);

/// A command of commands.csv: its JSON object of config keys to values (as --set takes them)
/// loaded through the config loader. Throws RecordingError with the loader's problems.
core::CompiledCommand command_from_json(const std::string& json_object);

/// A recording from `path`: an MCAP file (run.mcap: its shapeform/record/* channels, read through its
/// summary or, for a file cut short by a kill, by scanning it), else a CSV folder or a launcher run
/// folder: metrics.csv and positions.csv (required) and commands.csv and centre.csv (when present) of
/// recording_dir(path), columns found by their header names. Throws RecordingError naming the file,
/// the line (or channel) and the column of the first problem.
Recording load_recording(const std::filesystem::path& path);

/// Writes r as an MCAP file with the channels a recording's run.mcap has of its tables (the four
/// shapeform/record/* channels and the swarm drawn for Foxglove; not the DDS samples, which a CSV
/// recording does not hold), rows replayed in wall_s order (at one wall_s: the command, the centre,
/// the metrics, then the positions sample). unix_ns: the Unix time (ns) of wall_s 0. Returns the
/// number of messages written; throws std::runtime_error naming the file when it cannot be written.
std::uint64_t write_mcap(const Recording& r, const std::filesystem::path& file, std::int64_t unix_ns);

}  // namespace shapeform::record
