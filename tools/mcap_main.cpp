// shapeform_mcap: what an MCAP recording holds (info), a killed recording made whole (recover), and a CSV
// recording converted (convert).
#include <chrono>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "app/app.hpp"
#include "record/mcap.hpp"
#include "record/recorder.hpp"
#include "record/recording.hpp"

namespace shapeform {
namespace {

namespace fs = std::filesystem;
using record::McapReader;

nlohmann::json info_json(const fs::path& file, const McapReader& r) {
  std::map<std::uint16_t, std::uint64_t> counts;
  for (const auto& m : r.messages()) ++counts[m.channel];
  std::map<std::uint16_t, const record::McapSchema*> schemas;
  for (const auto& s : r.schemas()) schemas[s.id] = &s;
  nlohmann::json channels = nlohmann::json::array();
  for (const auto& c : r.channels()) {
    const auto s = schemas.find(c.schema_id);
    channels.push_back({{"id", c.id},
                        {"topic", c.topic},
                        {"message_encoding", c.message_encoding},
                        {"schema", s == schemas.end() ? "" : s->second->name},
                        {"schema_encoding", s == schemas.end() ? "" : s->second->encoding},
                        {"messages", counts[c.id]}});
  }
  std::map<std::string, std::uint64_t> compression;
  std::uint64_t compressed = 0, uncompressed = 0;
  for (const auto& ch : r.chunks()) {
    ++compression[ch.compression.empty() ? "none" : ch.compression];
    compressed += ch.compressed_size;
    uncompressed += ch.uncompressed_size;
  }
  const auto& ms = r.messages();
  const std::uint64_t start = ms.empty() ? 0 : ms.front().log_time, end = ms.empty() ? 0 : ms.back().log_time;
  return {{"file", file.string()},
          {"complete", r.complete()},
          {"truncated", r.truncated()},
          {"dropped_bytes", r.dropped_bytes()},
          {"profile", r.profile()},
          {"library", r.library()},
          {"messages", ms.size()},
          {"start_time_ns", start},
          {"end_time_ns", end},
          {"duration_s", double(end - start) * 1e-9},
          {"chunks",
           {{"count", r.chunks().size()},
            {"compression", compression},
            {"compressed_bytes", compressed},
            {"uncompressed_bytes", uncompressed}}},
          {"channels", channels}};
}

std::string info_text(const nlohmann::json& j) {
  std::ostringstream o;
  o << "file:     " << j["file"].get<std::string>() << '\n';
  if (j["complete"].get<bool>()) {
    o << "state:    complete (read through its summary)\n";
  } else {
    o << "state:    recovered (no summary: read by scanning every record";
    if (j["truncated"].get<bool>())
      o << "; the last " << j["dropped_bytes"] << " bytes, a record cut short, dropped";
    o << "); `shapeform_mcap recover` makes it whole\n";
  }
  o << "library:  " << j["library"].get<std::string>()
    << (j["profile"].get<std::string>().empty() ? "" : ", profile ") << j["profile"].get<std::string>()
    << '\n';
  o << "messages: " << j["messages"] << ", log time " << j["start_time_ns"] << " .. " << j["end_time_ns"]
    << " ns (" << std::fixed << std::setprecision(3) << j["duration_s"].get<double>() << " s)\n";
  const auto& c = j["chunks"];
  o << "chunks:   " << c["count"];
  for (const auto& [name, n] : c["compression"].items()) o << ", " << n << ' ' << name;
  o << "; " << c["compressed_bytes"] << " bytes stored, " << c["uncompressed_bytes"] << " uncompressed";
  if (c["compressed_bytes"].get<std::uint64_t>() > 0)
    o << " (x" << std::setprecision(2)
      << double(c["uncompressed_bytes"].get<std::uint64_t>()) /
             double(c["compressed_bytes"].get<std::uint64_t>())
      << ')';
  o << "\nchannels:\n";
  o << "  " << std::left << std::setw(4) << "id" << std::setw(36) << "topic" << std::setw(10) << "encoding"
    << std::setw(44) << "schema"
    << "messages\n";
  for (const auto& ch : j["channels"]) {
    std::string schema = ch["schema"].get<std::string>();
    if (!schema.empty()) schema += " (" + ch["schema_encoding"].get<std::string>() + ")";
    o << "  " << std::setw(4) << ch["id"].get<int>() << std::setw(36) << ch["topic"].get<std::string>()
      << std::setw(10) << ch["message_encoding"].get<std::string>() << std::setw(44) << schema
      << ch["messages"] << '\n';
  }
  return o.str();
}

/// shapeform_mcap convert: the CSV recording in run_dir as an MCAP file.
int convert_csv(const app::App& app, const std::string& run_dir, std::string out) {
  std::optional<record::Recording> r;
  try {
    r.emplace(record::load_recording(record::recording_dir(run_dir)));
  } catch (const record::RecordingError& e) {
    return app.usage_error(std::string("convert: ") + e.what());
  }
  if (out.empty()) out = (r->dir / record::kMcapFile).string();
  if (fs::exists(out))
    return app.usage_error("convert: OUT " + out + " exists: give another file (a conversion never replaces one)");
  if (const auto problem = app::writable_file_problem(out); !problem.empty())
    return app.usage_error("convert: OUT " + out + ": " + problem);
  return app.run([&] {
    // The run's real time: the metrics file was last written at the end of the run (wall_s end_s).
    std::error_code ec;
    const auto modified = fs::last_write_time(r->dir / "metrics.csv", ec);
    std::int64_t unix_ns = 0;
    if (!ec) {
      // C++17 has no file_clock::to_sys: the file's age, taken from the system clock's now.
      const auto age = fs::file_time_type::clock::now() - modified;
      const auto sys = std::chrono::system_clock::now() - std::chrono::duration_cast<std::chrono::system_clock::duration>(age);
      unix_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(sys.time_since_epoch()).count() -
                static_cast<std::int64_t>(r->end_s * 1e9);
    }
    const std::uint64_t n = record::write_mcap(*r, out, unix_ns);
    std::cerr << "shapeform_mcap: converted " << r->dir.string() << " (" << r->metrics.size() << " metrics rows, "
              << r->positions.size() << " positions, " << r->commands.size() << " commands) into " << out << ": "
              << n << " messages\n";
    return 0;
  });
}

int run(int argc, char** argv) {
  app::App app(
      "shapeform_mcap",
      "shapeform_mcap: inspects an MCAP recording (run.mcap) or makes a killed one whole.\n"
      "  shapeform_mcap info FILE [--json]   channels (schema, encoding, message count), time range,\n"
      "                                      chunks and compression, complete or recovered\n"
      "  shapeform_mcap recover IN OUT        rewrites a recording cut short (a hard kill) as a\n"
      "                                      complete, indexed file: every complete chunk kept\n"
      "  shapeform_mcap convert RUN [OUT]     a CSV recording (a record folder or a launcher run folder,\n"
      "                                      docs/RECORDING.md) as MCAP: its tables and the swarm drawn\n"
      "                                      for Foxglove (default OUT: run.mcap beside the CSV files)");
  auto& cli = app.cli();
  cli.require_subcommand(1);
  std::string info_file, in_file, out_file, compression = "zstd";
  bool json = false;
  auto* info = cli.add_subcommand("info", "what FILE holds");
  info->add_option("FILE", info_file, "an MCAP file")->required()->check(CLI::ExistingFile);
  info->add_flag("--json", json, "one JSON object on stdout instead of the table");
  auto* recover =
      cli.add_subcommand("recover", "IN (complete or cut short) rewritten as a complete, indexed OUT");
  recover->add_option("IN", in_file, "the MCAP file to recover")->required()->check(CLI::ExistingFile);
  recover->add_option("OUT", out_file, "the file to write (must not be IN)")->required();
  recover->add_option("--compression", compression, "chunk compression of OUT: zstd (default), lz4 or none")
      ->check(CLI::IsMember({"zstd", "lz4", "none"}));
  std::string run_dir, convert_out;
  auto* convert = cli.add_subcommand("convert", "a CSV recording RUN written as the MCAP file OUT");
  convert->add_option("RUN", run_dir, "a recording folder (metrics.csv, ...) or a launcher run folder")
      ->required()
      ->check(CLI::ExistingDirectory);
  convert->add_option("OUT", convert_out, "the MCAP file to write (default: run.mcap in the recording folder); "
                                          "never replaces an existing file");
  if (const auto rc = app.parse(argc, argv)) return *rc;

  if (*convert) return convert_csv(app, run_dir, convert_out);

  if (*info) {
    std::optional<McapReader> r;
    try {
      r.emplace(info_file);
    } catch (const std::exception& e) {
      return app.usage_error(e.what());
    }
    const auto j = info_json(info_file, *r);
    std::cout << (json ? j.dump() + "\n" : info_text(j)) << std::flush;
    return 0;
  }
  std::error_code ec;
  if (fs::exists(out_file) && fs::equivalent(in_file, out_file, ec))
    return app.usage_error("recover: OUT " + out_file + " is IN: write the recovered file elsewhere");
  if (const auto problem = app::writable_file_problem(out_file); !problem.empty())
    return app.usage_error("recover: OUT " + out_file + ": " + problem);
  record::McapOptions options;
  options.compression = *record::parse_mcap_compression(compression);
  std::optional<McapReader> r;
  try {
    r.emplace(in_file);  // bad input (not MCAP, a damaged chunk) is a usage error, before OUT is created
  } catch (const std::exception& e) {
    return app.usage_error(e.what());
  }
  return app.run([&] {
    const auto& got = *r;
    record::rewrite_mcap(got, out_file, options);
    std::cerr << "shapeform_mcap: recovered " << got.messages().size() << " messages on "
              << got.channels().size() << " channels from " << in_file
              << (got.complete()    ? " (complete already)"
                  : got.truncated() ? " (cut short: the last " + std::to_string(got.dropped_bytes()) +
                                          " bytes, a record cut short, dropped)"
                                    : " (no summary)")
              << " into " << out_file << '\n';
    return 0;
  });
}

}  // namespace
}  // namespace shapeform

int main(int argc, char** argv) { return shapeform::run(argc, argv); }
