#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>

#include "replay.hpp"

using namespace shapeform;
namespace fs = std::filesystem;

namespace {

/// A recording folder in the layout of docs/RECORDING.md: three metrics rows 0.1 s apart, two agents
/// per row, one command (epoch 1, a circle of radius 3), a centre.
fs::path write_recording(const std::string& name, bool with_commands = true) {
  const fs::path dir = fs::temp_directory_path() / ("shapeform_view_test_" + name) / "record";
  fs::remove_all(dir.parent_path());
  fs::create_directories(dir);
  std::ofstream m(dir / "metrics.csv");
  m << "wall_s,model_time,epoch,agents_alive,shape_error_mean,shape_error_max,gap_cv,nn_cv,min_separation,clusters,"
       "extent,centroid_error,ring_error,curve_error_mean,curve_error_max,arc_gap_cv,converged\n";
  for (int k = 0; k < 3; ++k)
    m << 1.0 + 0.1 * k << "," << 5 * k << ",1,2," << 1.0 / (k + 1) << ",,0.2,,,,,,,,,,0\n";
  std::ofstream p(dir / "positions.csv");
  p << "wall_s,model_time,step,epoch,agent,x1,x2\n";
  for (int k = 0; k < 3; ++k)
    for (int a = 0; a < 2; ++a) p << 1.0 + 0.1 * k << "," << 5 * k << "," << 5 * k << ",1," << a << "," << a + 0.25 * k << ",-1.5\n";
  if (with_commands) {
    std::ofstream c(dir / "commands.csv");
    c << "wall_s,model_time,epoch,issuer,issuer_name,command\n";
    c << "0.9,0,1,01.02,\"supervisor, the first\",\"{\"\"shape.kind\"\":\"\"circle\"\",\"\"shape.r0\"\":\"\"3\"\"}\"\n";
    std::ofstream t(dir / "centre.csv");
    t << "wall_s,model_time,epoch,c1,c2\n1.0,0,1,0.5,0.5\n";
  }
  return dir;
}

}  // namespace

TEST_CASE("command_from_json: config keys to values, through the config loader") {
  const auto c = record::command_from_json(R"({"shape.kind":"ellipse","shape.a":"5","shape.b":2})");
  CHECK(c.shape.kind == core::ShapeKind::Ellipse);
  CHECK(c.shape.a == 5.0);
  CHECK(c.shape.b == 2.0);
  CHECK_THROWS_WITH(record::command_from_json(R"({"shape.r0":"-1"})"), Catch::Contains("shape.r0"));
  CHECK_THROWS_AS(record::command_from_json("[1]"), view::RecordingError);
}

TEST_CASE("load_recording: a run folder or its record folder; every table read by column name") {
  const fs::path dir = write_recording("load");
  for (const fs::path& given : {dir, dir.parent_path()}) {
    const auto r = record::load_recording(given);
    CHECK(r.dir == dir);
    REQUIRE(r.metrics.size() == 3);
    CHECK(r.metrics[1].model_time == 5.0);
    CHECK(r.metrics[1].metrics.shape_error_mean == 0.5);
    CHECK_FALSE(r.metrics[1].metrics.shape_error_max);
    CHECK(r.metrics[1].metrics.gap_cv == 0.2);
    REQUIRE(r.positions.size() == 6);
    CHECK(r.positions[5].agent == 1);
    CHECK(r.positions[5].x == core::Vec2(1.5, -1.5));
    REQUIRE(r.commands.size() == 1);
    CHECK(r.commands[0].command.shape.r0 == 3.0);
    CHECK(r.centre.size() == 1);
    CHECK(r.start_s == 0.9);
    CHECK(r.end_s == Approx(1.2));
  }
}

TEST_CASE("load_recording: a missing or bad file is named, with its line and column") {
  const fs::path dir = write_recording("bad", false);
  CHECK_NOTHROW(record::load_recording(dir));  // commands and centre are optional
  CHECK_THROWS_WITH(record::load_recording(dir / "nowhere"), Catch::Contains("nowhere/metrics.csv"));
  fs::remove(dir / "positions.csv");
  CHECK_THROWS_WITH(record::load_recording(dir), Catch::Contains("positions.csv"));
  std::ofstream(dir / "positions.csv") << "wall_s,model_time,agent,x1,x2\n1.0,0,0,abc,1\n";
  CHECK_THROWS_WITH(record::load_recording(dir), Catch::Contains("positions.csv:2") && Catch::Contains("x1"));
}

TEST_CASE("ReplayClock: plays at its speed, pauses, seeks, clamps to the recording") {
  view::ReplayClock c(10.0, 20.0, 100.0);
  CHECK(c.position(100.0) == 10.0);
  CHECK(c.position(102.0) == 12.0);
  c.set_speed(2.0, 102.0);
  CHECK(c.position(103.0) == 14.0);
  c.pause(103.0);
  CHECK(c.position(110.0) == 14.0);
  CHECK_FALSE(c.playing(110.0));
  c.seek(18.0, 110.0);
  CHECK(c.position(111.0) == 18.0);
  c.play(111.0);
  CHECK(c.position(111.5) == 19.0);
  CHECK(c.position(200.0) == 20.0);
  CHECK_FALSE(c.playing(200.0));
  c.play(200.0);  // at the end: from the start
  CHECK(c.position(200.0) == 10.0);
  c.seek(-5.0, 200.0);
  CHECK(c.position(200.0) == 10.0);
  CHECK_THROWS(c.set_speed(0.0, 0.0));
}

TEST_CASE("apply_control: the page's actions, seek in seconds from the start; bad ones said") {
  view::ReplayClock c(10.0, 20.0, 0.0);
  CHECK(view::apply_control(c, "pause", 0, 1.0).empty());
  CHECK(view::apply_control(c, "seek", 5.0, 1.0).empty());
  CHECK(c.position(3.0) == 15.0);
  CHECK(view::clock_json(c, 3.0)["position_s"] == 5.0);
  CHECK(view::apply_control(c, "speed", 0.0, 1.0).find("speed") != std::string::npos);
  CHECK(view::apply_control(c, "rewind", 0.0, 1.0).find("unknown action 'rewind'") != std::string::npos);
  CHECK(view::apply_control(c, "play", 0.0, 4.0).empty());
  CHECK(c.position(5.0) == 16.0);
}

TEST_CASE("ReplayFeeder: the scene shows what was recorded up to the position; back in time starts anew") {
  const auto r = record::load_recording(write_recording("feed"));
  view::Scene scene;
  view::ReplayFeeder feeder(r, 5.0);
  feeder.advance(scene, 1.15);
  CHECK(scene.model_time() == 5.0);
  CHECK(scene.agents().at(1).x == core::Vec2(1.25, -1.5));
  auto f = scene.snapshot(1.15);
  CHECK(f["epoch"] == 1);
  CHECK(f["outline"]["points"].size() == 240);
  CHECK(f["centre"] == nlohmann::json::array({0.5, 0.5}));
  CHECK(f["chart"]["points"].size() == 2);
  feeder.advance(scene, 1.25);
  CHECK(scene.model_time() == 10.0);
  feeder.advance(scene, 1.0);
  CHECK(scene.model_time() == 0.0);
  CHECK(scene.agents().at(1).x == core::Vec2(1.0, -1.5));
  CHECK(scene.snapshot(1.0)["chart"]["points"].size() == 1);
}

TEST_CASE("ReplayFeeder: a recording older than the safety figures plays, them null; its zones drawn") {
  // write_recording's metrics.csv has min_separation but none of the run's safety columns.
  const fs::path dir = write_recording("safety");
  std::ofstream(dir / "commands.csv")
      << "wall_s,model_time,epoch,issuer,issuer_name,command\n"
         "0.9,0,1,01.02,supervisor,\"{\"\"shape.kind\"\":\"\"circle\"\","
         "\"\"safety.min_separation\"\":\"\"0.2\"\","
         "\"\"safety.keep_out\"\":\"\"[{circle: [4, 0, 1]}, {polygon: [[0, 5], [1, 5], [0, 6]]}]\"\"}\"\n";
  const auto r = record::load_recording(dir);
  view::Scene scene;
  view::ReplayFeeder feeder(r, 5.0);
  feeder.advance(scene, 1.25);
  const auto f = scene.snapshot(1.25);
  CHECK(f["min_separation"] == 0.2);
  REQUIRE(f["keep_out"].size() == 2);
  CHECK(f["keep_out"][0]["circle"] == nlohmann::json({4.0, 0.0, 1.0}));
  CHECK(f["keep_out"][1]["polygon"].size() == 3);
  for (const auto& [name, value] : f["safety"].items()) CHECK(value.is_null());
  REQUIRE(f["chart"]["points"].size() == 3);
  for (const auto& p : f["chart"]["points"]) {
    CHECK(p.size() == f["chart"]["columns"].size());
    CHECK(p.back().is_null());  // min_separation_run: no column
  }
}
