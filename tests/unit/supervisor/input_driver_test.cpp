// The input driver: lines run in order, a wait holds them, Ctrl-C, the script, and a wait ended by
// another participant's command.
#include "input_driver.hpp"

#include <unistd.h>

#include <catch2/catch.hpp>
#include <deque>
#include <filesystem>
#include <fstream>

#include "supervisor_rig.hpp"

using namespace shapeform;
using namespace shapeform::test;
namespace fs = std::filesystem;

namespace {

/// Console lines given in advance.
class Lines : public supervisor::LineSource {
 public:
  explicit Lines(std::deque<std::string> lines, bool ended = true)
      : lines_(std::move(lines)), ended_(ended) {}
  std::optional<std::string> poll() override {
    if (lines_.empty()) return std::nullopt;
    std::string line = lines_.front();
    lines_.pop_front();
    return line;
  }
  bool eof() const override { return ended_ && lines_.empty(); }
  void add(std::string line) { lines_.push_back(std::move(line)); }

 private:
  std::deque<std::string> lines_;
  bool ended_;
};

fs::path script(const std::string& name, const std::string& content) {
  const fs::path p =
      fs::temp_directory_path() / ("shapeform_input_test_" + std::to_string(::getpid()) + "_" + name);
  std::ofstream(p) << content;
  return p;
}

}  // namespace

TEST_CASE("input: lines run in order until a wait holds them; its end is reported and input resumes",
          "[supervisor][input]") {
  Rig r;
  Lines console({"sleep 1", "shape circle r=3"});
  r.input.set_console(&console);
  r.input.run_lines(0);
  CHECK(r.sent.empty());  // held by the sleep
  CHECK(r.input.busy());
  CHECK_FALSE(r.input.done());
  r.input.run_lines(kS - 1);
  CHECK(r.sent.empty());
  r.input.run_lines(kS);
  REQUIRE(r.sent.size() == 1);
  CHECK(r.sent[0].command.shape.r0 == 3.0);
  const auto events = r.take_events();
  REQUIRE(events.size() == 2);
  CHECK(events[0]["event"] == "wait");
  CHECK(events[0]["wait"] == "sleep");
  CHECK(events[0]["ok"] == true);
  CHECK(events[1]["event"] == "epoch");
  CHECK(r.input.done());
  CHECK(r.input.exit_status() == 0);
}

TEST_CASE("input: each line is parsed against the command in force; a bad one is reported and skipped",
          "[supervisor][input]") {
  Rig r;
  Lines console({"shape circle r=-1", "gains k1=0.25", "gains k2=2"});
  r.input.set_console(&console);
  r.input.run_lines(0);
  CHECK(r.errors.str() == "shape circle: r must be > 0, got -1\n");
  REQUIRE(r.sent.size() == 2);
  CHECK(r.sent[1].command.gains.k1 == 0.25);  // the second change kept the first
  CHECK(r.sent[1].command.gains.k2 == 2.0);
}

TEST_CASE("input: a wait that times out sets exit status 3", "[supervisor][input]") {
  Rig r;
  Lines console({"wait agents 2 timeout=1", "status"});
  r.input.set_console(&console);
  r.input.run_lines(0);
  REQUIRE(r.input.pending());
  r.input.run_lines(kS);
  CHECK_FALSE(r.input.pending());
  CHECK(r.input.exit_status() == supervisor::kExitWaitTimedOut);
  const std::string text = r.take_human();
  CHECK(text.find("wait agents: timed out after 1 s with 0 of 2 agents\n") != std::string::npos);
  CHECK(text.find("(no agent heard yet)") != std::string::npos);  // then `status` ran
}

TEST_CASE("input: the script is checked whole before anything runs, then runs before the console",
          "[supervisor][input]") {
  Rig r;
  const fs::path bad = script("bad", "gains k1=0.5\nshape circle r=-1\nbogus\n");
  CHECK_FALSE(r.input.load_script(bad.string(), circle()));
  CHECK(r.errors.str() == bad.string() + ":2: shape circle: r must be > 0, got -1\n" + bad.string() +
                              ":3: unknown command 'bogus' (try 'help')\n");
  CHECK_FALSE(r.input.load_script((bad.string() + ".missing"), circle()));
  const fs::path good = script("good", "# a comment\nshape circle r=3\n");
  REQUIRE(r.input.load_script(good.string(), circle()));
  Lines console({"shape circle r=5"});
  r.input.set_console(&console);
  r.input.run_lines(0);
  REQUIRE(r.sent.size() == 2);
  CHECK(r.sent[0].command.shape.r0 == 3.0);
  CHECK(r.sent[1].command.shape.r0 == 5.0);
  fs::remove(bad);
  fs::remove(good);
}

TEST_CASE("input: Ctrl-C cancels a wait and the script; twice within a second on an idle console quits",
          "[supervisor][input]") {
  Rig r;
  const fs::path path = script("ctrl_c", "wait converged\nshape circle r=3\n");
  REQUIRE(r.input.load_script(path.string(), circle()));
  Lines console({}, false);
  r.input.set_console(&console);
  r.input.run_lines(0);
  REQUIRE(r.input.pending());
  r.input.interrupt(kS);
  CHECK_FALSE(r.input.busy());
  CHECK(r.take_human() ==
        "wait converged: cancelled (Ctrl-C)\nscript " + path.string() + " abandoned after line 1\n");
  const auto events = r.take_events();
  REQUIRE(events.size() == 1);
  CHECK(events[0]["cancelled"] == true);
  CHECK(events[0]["ok"] == false);
  r.input.run_lines(kS);
  CHECK(r.sent.empty());      // the rest of the script never ran
  r.input.interrupt(2 * kS);  // idle: armed
  CHECK(r.take_human() == "(Ctrl-C again within 1 s, Ctrl-D or 'quit' to leave)\n");
  r.input.interrupt(4 * kS);  // too late: armed again
  CHECK_FALSE(r.input.quitting());
  r.input.interrupt(5 * kS);
  CHECK(r.input.quitting());
  CHECK(r.input.exit_status() == supervisor::kExitInterrupted);
  fs::remove(path);
}

TEST_CASE("input: another participant's command ends a wait on the command, not a wait on agents",
          "[supervisor][input]") {
  Rig r;
  Lines console({"shape circle r=3", "wait converged"}, false);
  r.input.set_console(&console);
  r.input.run_lines(0);
  REQUIRE(r.input.pending());
  r.take_events();
  REQUIRE(r.authority.hear(rival(circle(), 9), 0, kS));
  r.input.command_replaced(kS);
  CHECK_FALSE(r.input.pending());
  CHECK(r.input.exit_status() == supervisor::kExitWaitTimedOut);
  CHECK(r.take_human().find("wait converged: ended, epoch 1 was superseded by epoch 9 of rival") !=
        std::string::npos);
  const auto events = r.take_events();
  REQUIRE(events.size() == 2);  // in_force, then the wait
  CHECK(events[1]["superseded"] == true);
  CHECK(events[1]["epoch"] == 9);
  console.add("wait agents 1");
  r.input.run_lines(kS);
  REQUIRE(r.input.pending());
  r.input.command_replaced(kS);
  CHECK(r.input.pending());
}
