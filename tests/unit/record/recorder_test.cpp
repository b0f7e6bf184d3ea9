#include "record/recorder.hpp"

#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "config/config.hpp"
#include "record/mcap.hpp"
#include "record/recording.hpp"
#include "temp_dir.hpp"

using namespace shapeform;
using namespace shapeform::record;
namespace fs = std::filesystem;

namespace {

using shapeform::test::TempDir;

std::vector<std::string> read_lines(const fs::path& p) {
  std::ifstream in(p);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

MetricsRow full_row() {
  MetricsRow row;
  row.wall_s = 12.25;
  row.model_time = 300.0;
  row.epoch = 4;
  row.agents_alive = 20;
  row.metrics.agents = 20;
  row.metrics.shape_error_mean = 0.1;
  row.metrics.shape_error_max = 0.5;
  row.metrics.gap_cv = 0.05;
  row.metrics.nn_cv = 0.125;
  row.metrics.min_separation = 1.5;
  row.metrics.clusters = 1;
  row.metrics.extent = 8.0;
  row.metrics.centroid_error = 1e-05;
  row.metrics.ring_error = 2.0;
  row.metrics.curve_error_mean = 0.25;
  row.metrics.curve_error_max = 0.75;
  row.metrics.arc_gap_cv = 0.03125;
  row.metrics.min_separation_run = 0.5;
  row.metrics.min_separation_run_time = 12.5;
  row.metrics.filter_interventions = 7;
  row.metrics.deadlock_sidesteps = 2;
  row.metrics.promises_broken = 0;
  row.metrics.agents_blocked = 1;
  row.metrics.fence_breaches = 3;
  row.metrics.agents_beyond_fence = 0;
  row.converged = true;
  return row;
}

}  // namespace

TEST_CASE("open creates the directory and writes every header", "[record]") {
  TempDir tmp;
  const fs::path dir = tmp.path() / "nested" / "run1";
  Recorder rec;
  CHECK_FALSE(rec.is_open());
  rec.open(dir);
  CHECK(rec.is_open());
  CHECK(rec.dir() == dir);
  rec.close();
  CHECK(fs::is_directory(dir));
  CHECK(read_lines(dir / "metrics.csv") ==
        std::vector<std::string>{"wall_s,model_time,epoch,agents_alive,shape_error_mean,"
                                 "shape_error_max,gap_cv,nn_cv,min_separation,clusters,extent,"
                                 "centroid_error,ring_error,curve_error_mean,curve_error_max,"
                                 "arc_gap_cv,min_separation_run,min_separation_run_time,filter_interventions,"
                                 "deadlock_sidesteps,promises_broken,agents_blocked,fence_breaches,"
                                 "agents_beyond_fence,converged"});
  CHECK(read_lines(dir / "positions.csv") ==
        std::vector<std::string>{"wall_s,model_time,step,epoch,agent,x1,x2"});
  CHECK(read_lines(dir / "commands.csv") ==
        std::vector<std::string>{"wall_s,model_time,epoch,issuer,issuer_name,command"});
  CHECK(read_lines(dir / "centre.csv") == std::vector<std::string>{"wall_s,model_time,epoch,c1,c2"});
}

TEST_CASE("metrics rows: values, empty fields for undefined values", "[record]") {
  TempDir tmp;
  Recorder rec;
  rec.open(tmp.path());
  rec.write_metrics(full_row());

  MetricsRow empty;
  empty.wall_s = 1.5;
  empty.model_time = 10.0;
  empty.epoch = 3;
  empty.agents_alive = 1;
  rec.write_metrics(empty);

  MetricsRow partial = empty;
  partial.metrics.clusters = 2;
  partial.metrics.shape_error_mean = std::numeric_limits<double>::quiet_NaN();  // non-finite
  partial.metrics.extent = std::numeric_limits<double>::infinity();
  partial.metrics.ring_error = -0.75;
  partial.model_time = std::numeric_limits<double>::quiet_NaN();
  rec.write_metrics(partial);
  CHECK(rec.metrics_rows() == 3);
  rec.close();

  const auto lines = read_lines(tmp.path() / "metrics.csv");
  REQUIRE(lines.size() == 4);
  CHECK(lines[1] == "12.25,300,4,20,0.1,0.5,0.05,0.125,1.5,1,8,1e-05,2,0.25,0.75,0.03125,0.5,12.5,7,2,0,1,3,0,1");
  CHECK(lines[2] == "1.5,10,3,1,,,,,,,,,,,,,,,,,,,,,0");
  CHECK(lines[3] == "1.5,,3,1,,,,,,2,,,-0.75,,,,,,,,,,,,0");
  // Every row has as many fields as the header.
  for (const std::string& line : lines) {
    CHECK(std::count(line.begin(), line.end(), ',') == 24);
  }
}

TEST_CASE("position rows, with and without a step", "[record]") {
  TempDir tmp;
  Recorder rec;
  rec.open(tmp.path());
  rec.write_positions(0.5, 12.0, 12, {{3, 2, 1.25, -4.0, {}}});
  rec.write_positions(0.5, 12.0, std::nullopt, {{17, 2, 0.1, 1e-300, {}}});
  rec.write_positions(0.75, 13.0, std::int64_t{1} << 40, {{0, 0, 0.0, -0.0, {}}});
  CHECK(rec.position_rows() == 3);
  rec.close();
  const auto lines = read_lines(tmp.path() / "positions.csv");
  REQUIRE(lines.size() == 4);
  CHECK(lines[1] == "0.5,12,12,2,3,1.25,-4");
  CHECK(lines[2] == "0.5,12,,2,17,0.1,1e-300");
  CHECK(lines[3] == "0.75,13,1099511627776,0,0,0,-0");
}

TEST_CASE("numbers round-trip exactly", "[record]") {
  TempDir tmp;
  Recorder rec;
  rec.open(tmp.path());
  const double x = 0.1 + 0.2;  // 0.30000000000000004
  rec.write_positions(1.0 / 3.0, 2.0 / 3.0, 1, {{1, 1, x, -x, {}}});
  rec.close();
  const auto lines = read_lines(tmp.path() / "positions.csv");
  REQUIRE(lines.size() == 2);
  std::istringstream fields(lines[1]);
  std::vector<double> v;
  for (std::string f; std::getline(fields, f, ',');) v.push_back(std::stod(f));
  REQUIRE(v.size() == 7);
  CHECK(v[0] == 1.0 / 3.0);
  CHECK(v[1] == 2.0 / 3.0);
  CHECK(v[5] == x);
  CHECK(v[6] == -x);
}

TEST_CASE("flush_if_due flushes once flush_s has passed", "[record]") {
  TempDir tmp;
  Recorder rec(2.0);
  const auto t0 = Recorder::Clock::now();
  rec.open(tmp.path());
  rec.write_positions(0.0, 1.0, 1, {{1, 1, 2.0, 3.0, {}}});
  const fs::path file = tmp.path() / "positions.csv";

  // Not due yet: the row stays in the stream buffer (small rows are buffered by std::filebuf).
  rec.flush_if_due(t0);
  CHECK(read_lines(file).size() == 1);
  // Due: the row reaches the file while the recorder stays open.
  rec.flush_if_due(t0 + std::chrono::seconds(3));
  CHECK(rec.is_open());
  CHECK(read_lines(file).size() == 2);

  // flush() always flushes.
  rec.write_metrics(full_row());
  rec.flush();
  CHECK(read_lines(tmp.path() / "metrics.csv").size() == 2);
  CHECK(rec.write_errors() == 0);
}

TEST_CASE("close flushes; closing twice and writing after close are harmless",
          "[record]") {
  TempDir tmp;
  Recorder rec;
  rec.close();  // never opened
  rec.open(tmp.path());
  rec.write_metrics(full_row());
  rec.close();
  rec.close();
  CHECK_FALSE(rec.is_open());
  rec.write_metrics(full_row());  // ignored
  rec.write_positions(0.0, 0.0, 0, {{0, 0, 0.0, 0.0, {}}});
  rec.write_centre(0.0, 0.0, 1, 0.0, 0.0);
  rec.flush();
  rec.flush_if_due(Recorder::Clock::now() + std::chrono::hours(1));
  CHECK(read_lines(tmp.path() / "metrics.csv").size() == 2);
  CHECK(read_lines(tmp.path() / "positions.csv").size() == 1);
  CHECK(read_lines(tmp.path() / "centre.csv").size() == 1);
}

TEST_CASE("the destructor flushes and closes", "[record]") {
  TempDir tmp;
  {
    Recorder rec;
    rec.open(tmp.path());
    rec.write_positions(0.0, 1.0, 1, {{1, 1, 2.0, 3.0, {}}});
  }
  CHECK(read_lines(tmp.path() / "positions.csv").size() == 2);
}

TEST_CASE("reopening starts new files; the old recording is closed", "[record]") {
  TempDir tmp;
  Recorder rec;
  rec.open(tmp.path() / "a");
  rec.write_metrics(full_row());
  rec.open(tmp.path() / "b");  // closes a
  CHECK(read_lines(tmp.path() / "a" / "metrics.csv").size() == 2);
  CHECK(rec.metrics_rows() == 0);
  rec.close();
  rec.open(tmp.path() / "a");  // truncates
  rec.close();
  CHECK(read_lines(tmp.path() / "a" / "metrics.csv").size() == 1);
}

TEST_CASE("open failures throw naming the path", "[record]") {
  TempDir tmp;
  Recorder rec;

  // A regular file where a directory is needed.
  const fs::path blocker = tmp.path() / "blocker";
  std::ofstream(blocker) << "x";
  try {
    rec.open(blocker / "run");
    FAIL("no exception");
  } catch (const std::runtime_error& e) {
    CHECK_THAT(e.what(), Catch::Contains((blocker / "run").string()));
  }
  CHECK_FALSE(rec.is_open());

  // metrics.csv exists as a directory.
  const fs::path dir = tmp.path() / "run";
  fs::create_directories(dir / "metrics.csv");
  try {
    rec.open(dir);
    FAIL("no exception");
  } catch (const std::runtime_error& e) {
    CHECK(std::string(e.what()) ==
          "cannot open " + (dir / "metrics.csv").string() + " for writing");
  }
  CHECK_FALSE(rec.is_open());
  rec.close();

  // positions.csv fails after metrics.csv opened: nothing stays open.
  const fs::path dir2 = tmp.path() / "run2";
  fs::create_directories(dir2 / "positions.csv");
  CHECK_THROWS_WITH(rec.open(dir2),
                    "cannot open " + (dir2 / "positions.csv").string() + " for writing");
  CHECK_FALSE(rec.is_open());

  // The recorder is still usable afterwards.
  rec.open(tmp.path() / "ok");
  CHECK(rec.is_open());

  // A failed open leaves the recording in progress as it was: still open, nothing lost.
  rec.write_metrics(full_row());
  CHECK_THROWS(rec.open(blocker / "run"));
  CHECK(rec.is_open());
  CHECK(rec.dir() == tmp.path() / "ok");
  rec.write_metrics(full_row());
  rec.close();
  CHECK(read_lines(tmp.path() / "ok" / "metrics.csv").size() == 3);
}

TEST_CASE("reopening the folder being recorded starts it afresh", "[record]") {
  TempDir tmp;
  Recorder rec;
  rec.open(tmp.path() / "a");
  rec.write_metrics(full_row());
  rec.open(tmp.path() / "a");
  rec.write_metrics(full_row());
  rec.close();
  CHECK(read_lines(tmp.path() / "a" / "metrics.csv").size() == 2);
}

TEST_CASE("flush period must be positive", "[record]") {
  CHECK_THROWS_AS(Recorder(0.0), std::invalid_argument);
  CHECK_THROWS_AS(Recorder(-1.0), std::invalid_argument);
  CHECK_THROWS_AS(Recorder(std::numeric_limits<double>::quiet_NaN()), std::invalid_argument);
  CHECK_NOTHROW(Recorder(0.001));
}

TEST_CASE("csv_fields: RFC 4180 quotes keep commas and doubled quotes", "[record]") {
  CHECK(csv_fields("a,,\"b,c\",\"say \"\"hi\"\"\"") == std::vector<std::string>{"a", "", "b,c", "say \"hi\""});
  CHECK(csv_fields("1,2\r") == std::vector<std::string>{"1", "2"});
  CHECK_THROWS_AS(csv_fields("\"open"), std::invalid_argument);
  for (const std::string s : {"", "abc", "a,b", "say \"hi\"", "two\nlines"}) CHECK(csv_fields(csv_field(s)) == std::vector<std::string>{s});
}

TEST_CASE("csv_field quotes only what needs it", "[record]") {
  CHECK(csv_field("") == "");
  CHECK(csv_field("abc") == "abc");
  CHECK(csv_field("a,b") == "\"a,b\"");
  CHECK(csv_field("say \"hi\"") == "\"say \"\"hi\"\"\"");
  CHECK(csv_field("two\nlines") == "\"two\nlines\"");
}

TEST_CASE("command rows hold the whole command, and it rebuilds through --set", "[record]") {
  TempDir tmp;
  const config::Config cfg = config::load("", {"shape.kind=polar", "shape.r_expr=1 + 0.3*cos(3*phi)",
                                               "dynamics.hold=true", "shape.rotation_deg=30"});
  Recorder rec;
  rec.open(tmp.path());
  rec.write_command(0.25, 0.0, 7, "0123456789abcdef01234567", "supervisor on host, pid 9", cfg.command);
  CHECK(rec.command_rows() == 1);
  // Written through at once: a reader sees the command before the rows measured against it.
  auto lines = read_lines(tmp.path() / "commands.csv");
  REQUIRE(lines.size() == 2);
  const auto f = csv_fields(lines[1]);
  REQUIRE(f.size() == 6);
  CHECK(f[0] == "0.25");
  CHECK(f[1] == "0");
  CHECK(f[2] == "7");
  CHECK(f[3] == "0123456789abcdef01234567");
  CHECK(f[4] == "supervisor on host, pid 9");
  const nlohmann::ordered_json j = nlohmann::ordered_json::parse(f[5]);
  const auto settings = config::command_settings(cfg.command);
  REQUIRE(j.size() == settings.size());
  std::vector<std::string> sets;
  std::size_t i = 0;
  for (const auto& [key, value] : j.items()) {
    CHECK(key == settings[i].first);  // table order
    CHECK(value.get<std::string>() == settings[i++].second);
    sets.push_back(key + "=" + value.get<std::string>());
  }
  CHECK(j["dynamics.hold"] == "true");
  CHECK(j["shape.kind"] == "polar");
  const config::Config back = config::load("", sets);
  CHECK(command_json(back.command) == command_json(cfg.command));
  CHECK(back.command.shape.rotation == cfg.command.shape.rotation);
  rec.close();
}

TEST_CASE("centre rows", "[record]") {
  TempDir tmp;
  Recorder rec;
  rec.open(tmp.path());
  rec.write_centre(1.5, 20.0, 3, -0.5, 2.25);
  CHECK(rec.centre_rows() == 1);
  rec.close();
  CHECK(read_lines(tmp.path() / "centre.csv") == std::vector<std::string>{"wall_s,model_time,epoch,c1,c2", "1.5,20,3,-0.5,2.25"});
}

// ---------------------------------------------------------------------------------------------
// run.mcap: the same tables, read back from it as from the CSV files

namespace {

/// A short recording with every table: a tracked command, its centre, metrics and positions samples.
void write_sample_run(Recorder& rec) {
  core::Command cmd = config::Config{}.command;
  cmd.tracking.enabled = true;
  rec.write_command(0.1, 0.0, 1, "01.02", "shapeform_supervisor on test", cmd);
  for (int k = 0; k < 30; ++k) {
    const double w = 0.2 + 0.1 * k, t = 0.5 * k;
    rec.write_centre(w, t, 1, 0.01 * t, 0.0);
    core::Metrics m;
    m.shape_error_mean = 1.0 / (1.0 + k);
    rec.write_metrics({w, t, 1, 3, m, k > 20});
    rec.write_positions(w, t, k, {{0, 1, 1.0 + 0.1 * k, -2.0, 0.5}, {4, 1, 0.3, 1.0 / 3.0, {}}, {7, 0, -1e-300, 2.5, {}}});
  }
}

void require_same(const Recording& a, const Recording& b) {
  REQUIRE(a.metrics.size() == b.metrics.size());
  for (std::size_t i = 0; i < a.metrics.size(); ++i) {
    CHECK(a.metrics[i].wall_s == b.metrics[i].wall_s);
    CHECK(a.metrics[i].model_time == b.metrics[i].model_time);
    CHECK(a.metrics[i].converged == b.metrics[i].converged);
    CHECK(a.metrics[i].metrics.shape_error_mean == b.metrics[i].metrics.shape_error_mean);
  }
  REQUIRE(a.positions.size() == b.positions.size());
  for (std::size_t i = 0; i < a.positions.size(); ++i) {
    CHECK(a.positions[i].agent == b.positions[i].agent);
    CHECK(a.positions[i].epoch == b.positions[i].epoch);
    CHECK(a.positions[i].step == b.positions[i].step);
    CHECK(a.positions[i].x == b.positions[i].x);  // bit for bit: both write the shortest round-trip form
  }
  REQUIRE(a.commands.size() == b.commands.size());
  for (std::size_t i = 0; i < a.commands.size(); ++i) {
    CHECK(a.commands[i].issuer == b.commands[i].issuer);
    CHECK(a.commands[i].issuer_name == b.commands[i].issuer_name);
    CHECK(command_json(a.commands[i].command) == command_json(b.commands[i].command));
  }
  REQUIRE(a.centre.size() == b.centre.size());
  for (std::size_t i = 0; i < a.centre.size(); ++i) CHECK(a.centre[i].c == b.centre[i].c);
  CHECK(a.start_s == b.start_s);
  CHECK(a.end_s == b.end_s);
}

std::map<std::string, std::size_t> messages_per_topic(const McapReader& r) {
  std::map<std::uint16_t, std::string> topic;
  for (const auto& c : r.channels()) topic[c.id] = c.topic;
  std::map<std::string, std::size_t> n;
  for (const auto& m : r.messages()) ++n[topic.at(m.channel)];
  return n;
}

}  // namespace

TEST_CASE("run.mcap: the four tables, the drawing and the caller's channels, read back as the CSV files") {
  TempDir tmp;
  Recorder rec;
  const std::uint16_t raw = rec.add_channel({"shapeform/state", "shapeform::msg::AgentState", "omgidl", "struct X {};", "cdr"});
  rec.open(tmp.path(), 1'700'000'000'000'000'000);
  write_sample_run(rec);
  const std::vector<std::uint8_t> bytes = {0, 1, 0, 0, 42};
  rec.write_message(raw, 0.25, bytes);
  rec.write_event(0.3, R"({"event":"agent","id":4,"change":"joined"})");
  rec.close();
  REQUIRE(rec.write_errors() == 0);

  const McapReader r(tmp.path() / kMcapFile);
  CHECK(r.complete());
  const auto n = messages_per_topic(r);
  CHECK(n.at(kMetricsTopic) == 30);
  CHECK(n.at(kPositionsTopic) == 30);
  CHECK(n.at(kCommandsTopic) == 1);
  CHECK(n.at(kCentreTopic) == 30);
  CHECK(n.at(kEventsTopic) == 1);
  CHECK(n.at("shapeform/scene") == 30);
  CHECK(n.at("shapeform/agent_poses") == 30);
  CHECK(n.at("shapeform/state") == 1);
  // Log times are Unix times: the open's unix_ns plus wall_s.
  for (const auto& m : r.messages()) CHECK(m.log_time >= 1'700'000'000'100'000'000ULL);
  // The drawing shows the command's outline and the centre of the sample.
  std::map<std::uint16_t, std::string> topic;
  for (const auto& c : r.channels()) topic[c.id] = c.topic;
  const McapMessage* last_scene = nullptr;
  for (const auto& m : r.messages())
    if (topic.at(m.channel) == "shapeform/scene") last_scene = &m;
  REQUIRE(last_scene);
  const auto scene = nlohmann::json::parse(last_scene->data.begin(), last_scene->data.end());
  std::map<std::string, nlohmann::json> entity;
  for (const auto& e : scene["entities"]) entity[e["id"].get<std::string>()] = e;
  CHECK(entity.at("agents")["spheres"].size() == 3);
  CHECK(entity.at("headings")["arrows"].size() == 1);  // only agent 0's heading is known
  CHECK(entity.at("outline")["lines"].size() == 1);
  CHECK(entity.at("centre")["spheres"].size() == 1);
  CHECK(entity.at("centre")["spheres"][0]["pose"]["position"]["x"].get<double>() == 0.01 * 0.5 * 29);

  require_same(load_recording(tmp.path() / kMcapFile), load_recording(tmp.path()));
}

TEST_CASE("run.mcap: a recording killed hard reads back every flushed sample") {
  TempDir tmp;
  {
    Recorder rec;
    rec.open(tmp.path());
    write_sample_run(rec);
    rec.flush();  // as the loop's flush_if_due does every flush_s
    rec.write_positions(9.0, 99.0, 99, {{0, 1, 5.0, 5.0, {}}});
    // Killed here: the file as it is on disk, without the last chunk and the summary.
    fs::copy_file(tmp.path() / kMcapFile, tmp.path() / "killed.mcap");
  }
  const Recording got = load_recording(tmp.path() / "killed.mcap");
  CHECK(got.metrics.size() == 30);
  CHECK(got.positions.size() == 90);  // the last sample was not flushed
  CHECK(got.commands.size() == 1);
}

TEST_CASE("write_mcap: a CSV recording converted reads back the same, with no CSV file written beside it") {
  TempDir tmp;
  {
    Recorder rec;
    rec.open(tmp.path() / "csv");
    write_sample_run(rec);
  }
  const Recording csv = load_recording(tmp.path() / "csv");
  fs::create_directories(tmp.path() / "out");
  CHECK(write_mcap(csv, tmp.path() / "out" / "converted.mcap", 0) > 0);
  CHECK(!fs::exists(tmp.path() / "out" / "metrics.csv"));
  require_same(load_recording(tmp.path() / "out" / "converted.mcap"), csv);
}

TEST_CASE("load_recording: an MCAP file that is not a recording's is named") {
  TempDir tmp;
  {
    McapWriter w;
    w.open(tmp.path() / "other.mcap");
  }
  CHECK_THROWS_WITH(load_recording(tmp.path() / "other.mcap"), Catch::Contains("no rows"));
  std::ofstream(tmp.path() / "junk.mcap") << "not mcap";
  CHECK_THROWS_AS(load_recording(tmp.path() / "junk.mcap"), RecordingError);
}
