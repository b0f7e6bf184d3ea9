// The command registry: every command declared once, and parsing, help and completion derived from it.
#include "console_commands.hpp"

#include <catch2/catch.hpp>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "console_parser.hpp"
#include "core/command_table.hpp"

using namespace shapeform;
using namespace shapeform::supervisor;

namespace {

const FormSpec& form_of(std::string_view word, std::string_view sub = {}) {
  const CommandSpec* c = find_command(word);
  REQUIRE(c != nullptr);
  const FormSpec* f = c->form(sub);
  REQUIRE(f != nullptr);
  return *f;
}

const ParamSpec& param_of(const FormSpec& f, std::string_view key) {
  for (const ParamSpec& p : f.params)
    if (p.key == key) return p;
  FAIL("no parameter " << key);
  throw;
}

}  // namespace

TEST_CASE(
    "registry: every parameter bound to a command field takes its range and unit from the command table",
    "[supervisor][registry]") {
  std::set<std::string> seen;
  for (const CommandSpec& c : command_specs()) {
    for (const FormSpec& f : c.forms) {
      for (const ParamSpec& p : c.params(f)) {
        INFO(c.words(f) << " " << p.key);
        if (p.field.empty()) continue;
        const auto* entry = core::params::find_key(p.field);
        REQUIRE(entry != nullptr);
        CHECK(&p.bounds() == &entry->range);
        CHECK(p.unit_name() == entry->unit);
        seen.insert(p.field);
      }
    }
  }
  CHECK(seen.count("shape.r0") == 1);
  CHECK(seen.count("integration.dt") == 1);
  CHECK(param_of(form_of("track", "circle"), "period").unit_name() == "model time");
  CHECK(param_of(form_of("shape", "circle"), "cx").unit_name() == "shape units");
  // A parameter that is no field of the command carries its own bounds and unit.
  const ParamSpec& timeout = param_of(form_of("wait", "converged"), "timeout");
  CHECK(timeout.field.empty());
  CHECK(timeout.unit_name() == "s");
  CHECK(timeout.bounds().text() == "must be >= 0");
}

TEST_CASE("registry: the bounds a parameter declares are the ones the parser enforces",
          "[supervisor][registry]") {
  const ParamSpec& dt = param_of(form_of("integrator"), "dt");
  const std::string too_big = core::params::format_number(dt.bounds().hi * 2);
  const ParseResult r = parse_command("integrator euler dt=" + too_big, core::CompiledCommand{});
  CHECK(r.error == "integrator: dt " + dt.bounds().text_for(dt.bounds().hi * 2) + ", got " + too_big);
}

TEST_CASE("registry: positional values and counts come from the usages", "[supervisor][registry]") {
  using V = std::vector<std::string>;
  CHECK(form_of("metrics").values() == V{"json"});
  CHECK(form_of("metrics").max_positionals() == 1);
  CHECK(form_of("progress").values() == V{"on", "off", "every"});
  CHECK(form_of("progress").max_positionals() == 2);
  CHECK(form_of("integrator").values() == V{"euler", "rk4"});
  CHECK(form_of("law").values() == V{"paper", "arc"});
  CHECK(form_of("wait", "agents").values().empty());  // N is a placeholder
  CHECK(form_of("wait", "agents").max_positionals() == 1);
  CHECK(form_of("status").max_positionals() == 0);
  CHECK(form_of("help").values().empty());
  CHECK(find_command("help")->offers_commands);
  CHECK(form_of("safety", "keep_out").values() == V{"add", "add", "remove", "clear"});
  CHECK(form_of("safety", "keep_out").max_positionals() == 4);
  CHECK(form_of("safety", "fence").values() == V{"box", "polygon"});
}

TEST_CASE("registry: words, aliases and second words", "[supervisor][registry]") {
  CHECK(find_command("exit") == find_command("quit"));
  CHECK(find_command("circle") == nullptr);
  CHECK(find_command("shape")->has_sub());
  CHECK_FALSE(find_command("gains")->has_sub());
  CHECK(find_command("wait")->form("forever") == nullptr);
  const CommandSpec& shape = *find_command("shape");
  CHECK(shape.words(*shape.form("circle")) == "shape circle");
  std::vector<std::string> keys;
  for (const ParamSpec& p : shape.params(*shape.form("line"))) keys.push_back(p.key);
  CHECK(keys == std::vector<std::string>{"m", "c", "rot", "scale"});  // own, then shared
}

TEST_CASE("help is written from the registry: every form's syntax, on its page and in the overview",
          "[supervisor][registry][help]") {
  const std::string overview = help_text();
  for (const CommandSpec& c : command_specs()) {
    const std::string page = help_text(c.word);
    INFO(c.word);
    CHECK(page.rfind(c.word, 0) == 0);
    CHECK(page.find(c.details) != std::string::npos);
    for (const FormSpec& f : c.forms) {
      if (!f.summary.empty()) CHECK(overview.find("  " + f.summary + "\n") != std::string::npos);
      for (const ParamSpec& p : f.params) {
        INFO(p.key);
        const std::string before = p.need == ParamSpec::Need::Optional ? "[" : " ";
        CHECK(page.find(before + p.key + "=" + p.value) != std::string::npos);  // the page has every value
        CHECK(overview.find(before + p.key + "=") != std::string::npos);
      }
    }
  }
  // The description column: at column 60, or two spaces after a syntax that fills it.
  std::istringstream lines(overview);
  std::string line;
  std::getline(lines, line);  // the heading
  while (std::getline(lines, line) && line.rfind("Lines starting", 0) != 0) {
    INFO(line);
    const std::size_t syntax_end = line.find("  ");
    REQUIRE(syntax_end != std::string::npos);
    const std::size_t text = line.find_first_not_of(' ', syntax_end);
    CHECK(syntax_end <= 60);
    CHECK((text == 60 || (syntax_end >= 58 && text == syntax_end + 2)));
  }
  // Long syntaxes write their last optional parameters without values, to keep the column.
  CHECK(overview.find("shape parametric x=\"EXPR\" y=\"EXPR\" [closed=on|off] [cx= cy=]  x(s)") !=
        std::string::npos);
  CHECK(help_text("shape").find("shape parametric x=\"EXPR\" y=\"EXPR\" [closed=on|off] [cx=X cy=Y]\n") !=
        std::string::npos);
  // A form without its own description shares the previous line; usages without parameters are
  // written as alternatives.
  CHECK(overview.find("\nrecord start DIR | record stop ") != std::string::npos);
  CHECK(overview.find("\nmetrics [json] ") != std::string::npos);
  CHECK(help_text("metrics").rfind("metrics\nmetrics json\n", 0) == 0);
  CHECK(help_text("law").rfind("law paper\nlaw arc [k_normal=K] [k_tangent=T] [spacing=S]\n", 0) == 0);
  CHECK(
      help_text("safety").rfind("safety separation D\n"
                                "safety keep_out add circle X,Y R\n"
                                "safety keep_out add polygon \"x,y;x,y;x,y\"\n"
                                "safety keep_out remove K\n"
                                "safety keep_out clear\n"
                                "safety fence box\n"
                                "safety fence polygon \"x,y;x,y;x,y\" [margin=M] [action=hold|stop|return]\n"
                                "safety show\n",
                                0) == 0);
}

TEST_CASE("every form's parse function is reached by its words", "[supervisor][registry]") {
  // One line per form that parses to the Action the form produces.
  const std::vector<std::pair<std::string, std::size_t>> lines = {
      {"shape circle r=2", Action(SetCommand{}).index()},
      {"track stop", Action(TrackStop{}).index()},
      {"gains k1=1", Action(SetCommand{}).index()},
      {"status", Action(Status{}).index()},
      {"metrics json", Action(ShowMetrics{}).index()},
      {"wait converged", Action(WaitConverged{}).index()},
      {"wait agents 2", Action(WaitAgents{}).index()},
      {"wait time 3", Action(WaitTime{}).index()},
      {"sleep 1", Action(Sleep{}).index()},
      {"record start d", Action(RecordStart{}).index()},
      {"record stop", Action(RecordStop{}).index()},
      {"help gains", Action(Help{}).index()},
      {"exit", Action(Quit{}).index()},
      {"start", Action(StartScenario{}).index()},
      {"show", Action(Show{}).index()},
      {"progress off", Action(Progress{}).index()},
      {"stop", Action(Hold{}).index()},
      {"resume", Action(Resume{}).index()},
      {"safety separation 1", Action(SetCommand{}).index()},
      {"safety keep_out add circle 1,2 3", Action(SetCommand{}).index()},
      {"safety fence box", Action(SetCommand{}).index()},
      {"safety show", Action(ShowSafety{}).index()},
      {"safety", Action(ShowSafety{}).index()},
  };
  for (const auto& [line, index] : lines) {
    const ParseResult r = parse_command(line, core::CompiledCommand{});
    INFO(line << ": " << r.error);
    REQUIRE(r.ok());
    CHECK(r.action.index() == index);
  }
}
