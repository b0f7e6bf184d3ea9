// The executor: every action reaches its function, and does what it says.
#include "executor.hpp"

#include <unistd.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "console_parser.hpp"
#include "supervisor_rig.hpp"

using namespace shapeform;
using namespace shapeform::test;
namespace fs = std::filesystem;

namespace {

/// Parses and runs one console line at now.
void run(Rig& r, const std::string& line, std::int64_t now = 0) {
  const supervisor::ParseResult p = supervisor::parse_command(line, r.authority.current());
  INFO(line << ": " << p.error);
  REQUIRE(p.ok());
  r.executor(p.action, now);
}

core::CompiledCommand tracking_circle() {
  core::Command c;
  c.tracking.enabled = true;
  c.tracking.path.kind = core::CentrePath::Kind::Line;
  c.tracking.path.velocity = core::Vec2(1.0, 0.0);
  return core::compile(c);
}

}  // namespace

TEST_CASE("executor: a new command, the scenario, hold, stop, resume and track stop are published",
          "[supervisor][executor]") {
  Rig r(tracking_circle());
  run(r, "start");
  REQUIRE(r.sent.size() == 1);
  CHECK(r.sent[0].command.tracking.enabled);  // the scenario
  run(r, "gains k1=0.5", kS);
  CHECK(r.sent.back().command.gains.k1 == 0.5);
  run(r, "hold", 2 * kS);  // the path restarts where the agents are: 1 s of the epoch at 10 Hz, dt 1
  CHECK(r.sent.back().command.hold);
  CHECK(r.sent.back().command.tracking.path.point.x() == Approx(10.0));
  run(r, "start", 3 * kS);  // a new command stays held
  CHECK(r.sent.back().command.hold);
  run(r, "resume", 4 * kS);
  CHECK_FALSE(r.sent.back().command.hold);
  run(r, "stop", 5 * kS);  // the emergency word: the scenario's path, 1 s after the resume
  CHECK(r.sent.back().command.hold);
  CHECK(r.sent.back().command.tracking.path.point.x() == Approx(10.0));
  run(r, "resume", 5 * kS);
  const std::size_t before = r.sent.size();
  r.take_human();
  run(r, "resume", 6 * kS);
  CHECK(r.sent.size() == before);
  CHECK(r.take_human() == "resume: nothing is held\n");
  run(r, "track stop", 6 * kS);  // 10 more units of model time along the line: the centre at x = 20
  CHECK_FALSE(r.sent.back().command.tracking.enabled);
  CHECK(r.sent.back().command.shape.centre.x() == Approx(20.0));
  CHECK(r.sent.back().id.epoch == r.sent.size());
}

TEST_CASE("executor: start keeps a command in force that another participant published",
          "[supervisor][executor]") {
  Rig r;
  r.follow(2, 4.0, dds::CommandId{4, source(0x30)}, 0.0, 0);
  run(r, "start");
  CHECK(r.sent.empty());
  CHECK(r.take_human() ==
        "start: epoch 4 of another participant is in force; kept ('start replace' publishes the --config "
        "scenario)\n");
  const auto events = r.take_events();
  REQUIRE(events.size() == 1);
  CHECK(events[0]["event"] == "start_kept");
  run(r, "start replace");
  REQUIRE(r.sent.size() == 1);
  CHECK(r.sent[0].id.epoch == 5);
  Rig replacing(circle(), true);  // --command-on-start replace
  replacing.follow(2, 4.0, dds::CommandId{4, source(0x30)}, 0.0, 0);
  run(replacing, "start");
  CHECK(replacing.sent.size() == 1);
}

TEST_CASE("executor: status, metrics, show and help answer with text and events", "[supervisor][executor]") {
  Rig r;
  run(r, "shape circle r=4");
  r.follow(3, 4.0, r.authority.id(), 0.0, 0);
  r.take_human();
  r.take_events();
  run(r, "status");
  CHECK(r.take_human().find("alive") != std::string::npos);
  auto events = r.take_events();
  REQUIRE(events.size() == 1);
  CHECK(events[0]["event"] == "status");
  CHECK(events[0]["agents"].size() == 3);
  CHECK(events[0]["own"] == true);
  run(r, "metrics json");
  const std::string json = r.take_human();
  CHECK(nlohmann::json::parse(json)["epoch"] == 1);
  CHECK(r.take_events()[0]["event"] == "metrics");
  run(r, "show");
  CHECK(r.take_human().find("published by this supervisor") != std::string::npos);
  events = r.take_events();
  REQUIRE(events.size() == 1);
  CHECK(events[0]["event"] == "show");
  CHECK(events[0]["following"] == 3);
  CHECK(events[0]["command"]["shape"]["kind"] == "circle");
  run(r, "help sleep");
  CHECK(r.take_human() == supervisor::help_text("sleep"));
}

TEST_CASE("executor: progress sets when the progress line is printed", "[supervisor][executor]") {
  Rig r;
  const supervisor::SwarmMonitor::Sample s;
  run(r, "progress off");
  CHECK_FALSE(r.progress.due(s, 0, 10 * kS));
  run(r, "progress every 2");
  CHECK(r.progress.due(s, 0, 20 * kS));
  CHECK_FALSE(r.progress.due(s, 0, 21 * kS));
  CHECK(r.progress.due(s, 0, 22 * kS));
}

TEST_CASE("executor: waits and sleep hold the input; quit ends it", "[supervisor][executor]") {
  Rig r;
  run(r, "wait time 5 timeout=3", kS);
  REQUIRE(r.input.pending());
  CHECK(std::string(r.input.pending()->name()) == "time");
  CHECK(r.input.pending()->deadline_ns() == 4 * kS);
  run(r, "wait agents 2");
  CHECK(std::string(r.input.pending()->name()) == "agents");
  run(r, "wait converged");
  CHECK(std::string(r.input.pending()->name()) == "converged");
  run(r, "sleep 0.5");
  CHECK(r.input.pending()->deadline_ns() == kS / 2);
  CHECK_FALSE(r.input.quitting());
  run(r, "quit");
  CHECK(r.input.quitting());
  r.executor(supervisor::NoOp{}, 0);
  CHECK(r.sent.empty());
}

TEST_CASE("executor: record start and stop", "[supervisor][executor]") {
  Rig r;
  const fs::path dir = fs::temp_directory_path() / ("shapeform_executor_test_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  run(r, "shape circle r=3");
  r.take_events();
  run(r, "record start \"" + dir.string() + "\"");
  CHECK(r.recorder.is_open());
  CHECK(r.recorder.command_rows() == 1);  // a recording begins with the command in force
  auto events = r.take_events();
  REQUIRE(events.size() == 1);
  CHECK(events[0] == nlohmann::json({{"event", "record"}, {"dir", dir.string()}, {"open", true}}));
  run(r, "record stop");
  CHECK_FALSE(r.recorder.is_open());
  CHECK(r.take_events()[0]["open"] == false);
  run(r, "record stop");
  CHECK(r.take_human().find("record stop: nothing is being recorded\n") != std::string::npos);
  std::ofstream(dir / "file") << "x";
  run(r, "record start \"" + (dir / "file").string() + "\"");  // a file, not a folder
  CHECK_FALSE(r.recorder.is_open());
  CHECK(r.errors.str().rfind("record start: ", 0) == 0);
  fs::remove_all(dir);
}

TEST_CASE(
    "executor: safety changes are published as new epochs, a bad one publishes nothing, and safety shows "
    "them",
    "[supervisor][executor][safety]") {
  Rig r;
  run(r, "shape circle r=4");
  run(r, "safety separation 0.25", kS);
  REQUIRE(r.sent.size() == 2);
  CHECK(r.sent.back().command.min_separation == 0.25);
  CHECK(r.sent.back().command.shape.r0 == 4.0);  // the rest kept
  run(r, "safety keep_out add circle 5,0 1", kS);
  run(r, "safety fence polygon \"-9,-9;9,-9;0,9\" margin=0.5 action=return", kS);
  REQUIRE(r.sent.size() == 4);
  CHECK(r.sent.back().command.keep_out.size() == 1);
  CHECK(r.sent.back().command.fence.size() == 3);
  CHECK(r.sent.back().command.breach_action == core::BreachAction::Return);
  CHECK(r.sent.back().id.epoch == 4);
  const supervisor::ParseResult bad =
      supervisor::parse_command("safety fence polygon \"0,0;4,0;4,1;1,1;1,4;0,4\"", r.authority.current());
  CHECK_FALSE(bad.ok());
  r.take_human();
  r.take_events();
  run(r, "safety", kS);
  CHECK(r.sent.size() == 4);  // a question publishes nothing
  const std::string shown = r.take_human();
  CHECK(shown == supervisor::safety_lines(r.authority.current()));
  CHECK(shown.find("    1  circle centre (5, 0) r=1\n") != std::string::npos);
  const auto events = r.take_events();
  REQUIRE(events.size() == 1);
  CHECK(events[0]["event"] == "safety");
  CHECK(events[0]["safety"]["breach_action"] == "return");
  CHECK(events[0]["safety"]["fence_margin"] == 0.5);
}
