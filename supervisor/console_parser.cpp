#include "console_parser.hpp"

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <map>
#include <optional>
#include <stdexcept>
#include <utility>
#include <vector>

#include "core/envelope.hpp"
#include "core/command_table.hpp"
#include "core/enum_names.hpp"
#include "core/params.hpp"
#include "shapes/shapes.hpp"
#include "util/text.hpp"

namespace shapeform::supervisor {
namespace {

// ---------------------------------------------------------------------------------------------
// Tokens

struct Token {
  std::string text;  ///< the whole token, quotes stripped
  bool is_pair = false;
  std::string key;    ///< pairs: left of the first unquoted '='
  std::string value;  ///< pairs: right of it, quotes stripped
};

bool is_space(char ch) {
  return ch == ' ' || ch == '\t' || ch == '\r' || ch == '\n' || ch == '\v' || ch == '\f';
}

/// Splits on whitespace outside double quotes; an unquoted '#' at a token start ends the line.
/// Returns an error message (empty on success).
std::string tokenize(std::string_view line, std::vector<Token>& out) {
  std::size_t i = 0;
  const std::size_t n = line.size();
  while (i < n) {
    while (i < n && is_space(line[i])) ++i;
    if (i >= n || line[i] == '#') break;
    Token tok;
    bool in_quotes = false;
    for (; i < n && (in_quotes || !is_space(line[i])); ++i) {
      const char ch = line[i];
      if (ch == '"') {
        in_quotes = !in_quotes;
        continue;
      }
      if (ch == '=' && !in_quotes && !tok.is_pair) {
        tok.is_pair = true;
        tok.key = tok.text;
        tok.text.push_back(ch);
        continue;
      }
      tok.text.push_back(ch);
      if (tok.is_pair) tok.value.push_back(ch);
    }
    if (in_quotes) return "unterminated double quote";
    out.push_back(std::move(tok));
  }
  return {};
}

// ---------------------------------------------------------------------------------------------
// Errors: thrown inside this file only, turned into ParseResult::error by parse_command.

struct ParseError {
  std::string message;
};

[[noreturn]] void fail(std::string message) { throw ParseError{std::move(message)}; }

// ---------------------------------------------------------------------------------------------
// Numbers

/// strtod with a full-consumption check; nullopt when the text is not a number. May return
/// non-finite values ("inf", "nan", overflow), which callers reject with their own message.
std::optional<double> to_double(const std::string& s) {
  if (s.empty() || is_space(s.front())) return std::nullopt;  // strtod would skip leading blanks
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(s.c_str(), &end);
  if (end != s.c_str() + s.size()) return std::nullopt;
  return v;  // ERANGE overflow gives +-HUGE_VAL (non-finite); underflow gives a finite value
}

namespace params = core::params;
using params::Range;
using util::trim;

/// The range the command table declares for a config key of core::Command ("shape.r0"): the console's
/// parameters are bounded exactly as the config file and the command topic.
const Range& field(std::string_view key) {
  const params::Param<core::Command>* p = params::find_key(key);
  if (p == nullptr) throw std::logic_error("no command key '" + std::string(key) + "'");
  return p->range;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Syntax: the key=value parameters of every command, declared once for the parser and for Tab
// completion. The command words themselves are the help entries' words.

const std::vector<Syntax>& syntax_table() {
  static const std::vector<Syntax> table = [] {
    const std::vector<std::string> placed = {"cx", "cy", "rot", "scale"};
    const auto with = [](std::vector<std::string> keys, const std::vector<std::string>& more) {
      keys.insert(keys.end(), more.begin(), more.end());
      return keys;
    };
    std::vector<Syntax> t = {
        {"shape line", {"m", "c", "rot", "scale"}, {}},
        {"shape circle", with({"r"}, placed), {}},
        {"shape ellipse", with({"a", "b"}, placed), {}},
        {"shape square", with({"a"}, placed), {}},
        {"shape polar", with({"r"}, placed), {}},
        {"shape parametric", with({"x", "y", "closed"}, placed), {}},
        {"shape implicit", with({"f"}, placed), {}},
        {"shape polygon", with({"points", "closed"}, placed), {}},
        {"track line", {"from", "vel", "r", "ff"}, {}},
        {"track circle", {"radius", "period", "r", "cx", "cy", "phase", "ff"}, {}},
        {"track point", {"at", "r", "ff"}, {}},
        {"track stop", {}, {}},
        {"gains", {"k1", "k2", "sigma", "beta", "r"}, {}},
        {"integrator", {"dt"}, params::names(params::kIntegratorNames)},
        {"law", {"k_normal", "k_tangent", "spacing"}, params::names(params::kLawNames)},
        {"wait converged", {"timeout"}, {}},
        {"wait agents", {"timeout"}, {}},
        {"wait time", {"timeout"}, {}},
        {"record start", {}, {}},
        {"record stop", {}, {}},
        {"metrics", {}, {"json"}},
        {"progress", {}, {"on", "off", "every"}},
    };
    return t;
  }();
  return table;
}

namespace {

/// The key=value parameters `words` ("shape circle", "gains") takes, from the syntax table.
const std::vector<std::string>& keys_of(std::string_view words) {
  for (const Syntax& s : syntax_table())
    if (s.words == words) return s.keys;
  throw std::logic_error("no syntax entry for '" + std::string(words) + "'");
}

/// Bounds of parameters that are not fields of the command (timeouts, durations, counts).
constexpr Range kAnyNumber = params::any();
constexpr Range kNonNegative = params::at_least(0);

/// Arguments of one command after its command word(s): positionals and key=value pairs.
class Args {
 public:
  /// Checks unknown and duplicate parameters and too many positionals, in token order.
  Args(std::string name, const std::vector<Token>& tokens, std::size_t first,
       const std::vector<std::string>& keys, std::size_t max_positionals)
      : name_(std::move(name)) {
    for (std::size_t i = first; i < tokens.size(); ++i) {
      const Token& t = tokens[i];
      if (!t.is_pair) {
        if (positionals_.size() >= max_positionals) {
          fail(name_ + ": unexpected argument '" + t.text + "'");
        }
        positionals_.push_back(t.text);
        continue;
      }
      if (t.key.empty()) fail(name_ + ": missing parameter name in '" + t.text + "'");
      bool known = false;
      for (const std::string& k : keys) known = known || t.key == k;
      if (!known) {
        fail(name_ + ": unknown parameter '" + t.key + "' " +
             (keys.size() == 0 ? std::string("(takes no key=value parameters)")
                               : "(expected " + params::join(keys, ", ") + ")"));
      }
      if (!pairs_.emplace(t.key, t.value).second) fail(name_ + ": duplicate parameter " + t.key);
    }
  }

  const std::string& name() const { return name_; }
  bool has(const std::string& key) const { return pairs_.count(key) != 0; }
  bool empty() const { return pairs_.empty() && positionals_.empty(); }
  std::size_t positionals() const { return positionals_.size(); }
  const std::string& positional(std::size_t i) const { return positionals_.at(i); }

  const std::string& raw(const std::string& key) const {
    const auto it = pairs_.find(key);
    if (it == pairs_.end()) fail(name_ + ": missing parameter " + key);
    return it->second;
  }

  /// A required number parameter.
  double number(const std::string& key, const Range& bound) const {
    return check_number(key, raw(key), bound);
  }
  /// An optional number parameter.
  double number_or(const std::string& key, const Range& bound, double fallback) const {
    return has(key) ? number(key, bound) : fallback;
  }

  /// Parses `text` as a number named `label` (empty label: the value of the command itself).
  /// The message names the bound broken, as written ("r must be > 0, got -2"; "dt must be <= 10").
  double check_number(const std::string& label, const std::string& text, const Range& bound) const {
    const std::string owner = label.empty() ? name_ : name_ + ": " + label;
    const std::optional<double> v = to_double(text);
    if (!v) fail(owner + ": not a number: '" + text + "'");
    if (!std::isfinite(*v)) fail(owner + " must be finite, got " + text);
    if (!bound.contains(*v)) fail(owner + " " + bound.text_for(*v) + ", got " + text);
    return *v;
  }

  /// A required `x,y` parameter with finite components.
  core::Vec2 vec2(const std::string& key) const {
    const std::string& text = raw(key);
    const std::size_t comma = text.find(',');
    if (comma == std::string::npos || text.find(',', comma + 1) != std::string::npos) {
      fail(name_ + ": " + key + " must be x,y, got '" + text + "'");
    }
    const std::optional<double> x = to_double(text.substr(0, comma));
    const std::optional<double> y = to_double(text.substr(comma + 1));
    if (!x || !y) fail(name_ + ": " + key + ": not a number: '" + text + "'");
    if (!std::isfinite(*x) || !std::isfinite(*y)) {
      fail(name_ + ": " + key + " must be finite, got " + text);
    }
    return core::Vec2(*x, *y);
  }

  /// An optional on|off parameter.
  bool on_off_or(const std::string& key, bool fallback) const {
    if (!has(key)) return fallback;
    const std::string& text = raw(key);
    if (text == "on") return true;
    if (text == "off") return false;
    fail(name_ + ": " + key + " must be on or off, got '" + text + "'");
  }

  /// Optional centre cx, cy (default 0, 0).
  core::Vec2 centre() const {
    return core::Vec2(number_or("cx", kAnyNumber, 0.0), number_or("cy", kAnyNumber, 0.0));
  }

  /// A required `x,y;x,y;...` parameter (blanks around numbers allowed; empty text: no points).
  std::vector<core::Vec2> points(const std::string& key) const {
    const std::string& text = raw(key);
    std::vector<core::Vec2> out;
    if (trim(text).empty()) return out;
    std::size_t begin = 0;
    for (std::size_t n = 1;; ++n) {
      const std::size_t semi = text.find(';', begin);
      const std::string item =
          trim(text.substr(begin, semi == std::string::npos ? std::string::npos : semi - begin));
      const std::string label = name_ + ": " + key + ": point " + std::to_string(n);
      const std::size_t comma = item.find(',');
      if (comma == std::string::npos || item.find(',', comma + 1) != std::string::npos) {
        fail(label + " must be x,y, got '" + item + "'");
      }
      const std::optional<double> x = to_double(trim(item.substr(0, comma)));
      const std::optional<double> y = to_double(trim(item.substr(comma + 1)));
      if (!x || !y) fail(label + ": not a number: '" + item + "'");
      if (!std::isfinite(*x) || !std::isfinite(*y)) fail(label + " must be finite, got " + item);
      out.emplace_back(*x, *y);
      if (semi == std::string::npos) break;
      begin = semi + 1;
    }
    return out;
  }

  /// Optional rotation rot (degrees, default 0) and scale (default 1) of every shape.
  void placement(core::ShapeSpec& s) const {
    s.rotation = params::radians(number_or("rot", field("shape.rotation_deg"), 0.0));
    s.scale = number_or("scale", field("shape.scale"), 1.0);
  }

 private:
  std::string name_;
  std::vector<std::string> positionals_;
  std::map<std::string, std::string> pairs_;
};

// ---------------------------------------------------------------------------------------------
// Commands

using Tokens = std::vector<Token>;

/// The sub-word at tokens[1] (e.g. `circle` in `shape circle`); fails with `expected` when absent.
const std::string& sub_word(const Tokens& t, const std::string& cmd, const std::string& expected) {
  if (t.size() < 2 || t[1].is_pair) fail(cmd + ": expected " + expected);
  return t[1].text;
}

const std::string kShapeList = params::join(params::names(params::kShapeKindNames), ", ");

/// shapes::compile on a parsed shape: a ShapeError becomes the command's one-line error, named
/// after the command ("shape polar: r(phi) = '4+foo': Unexpected token ...").
void compile_or_fail(const std::string& name, core::CompiledCommand& cmd) {
  try {
    cmd = shapes::compile(cmd);
  } catch (const core::ShapeError& e) {
    std::string what = e.what();
    // "polar: r(phi) ..." under "shape polar" reads "shape polar: r(phi) ...".
    const std::string kind = std::string(core::to_string(cmd.shape.kind)) + ": ";
    if (what.rfind(kind, 0) == 0) what.erase(0, kind.size());
    fail(name + ": " + what);
  }
}

Action parse_shape(const Tokens& t, const core::CompiledCommand& current) {
  const std::string& kind = sub_word(t, "shape", std::string("a shape (") + kShapeList + ")");
  const std::string name = "shape " + kind;
  core::CompiledCommand cmd = current;
  cmd.tracking = core::Tracking{};  // a fixed shape: tracking off, no stale path
  cmd.shape = core::ShapeSpec{};    // nothing of the previous shape (expressions) lingers
  core::ShapeSpec& s = cmd.shape;
  if (!params::parse_name(params::kShapeKindNames, kind, s.kind))
    fail("shape: unknown shape '" + kind + "' (expected " + kShapeList + ")");
  switch (s.kind) {
    case core::ShapeKind::Line: {
      const Args a(name, t, 2, keys_of(name), 0);
      s.m = a.number("m", field("shape.m"));
      s.c = a.number("c", field("shape.c"));
      s.centre = core::Vec2::Zero();
      a.placement(s);
      break;
    }
    case core::ShapeKind::Circle: {
      const Args a(name, t, 2, keys_of(name), 0);
      s.r0 = a.number("r", field("shape.r0"));
      s.centre = a.centre();
      a.placement(s);
      break;
    }
    case core::ShapeKind::Ellipse: {
      const Args a(name, t, 2, keys_of(name), 0);
      s.a = a.number("a", field("shape.a"));
      s.b = a.number("b", field("shape.b"));
      s.centre = a.centre();
      a.placement(s);
      break;
    }
    case core::ShapeKind::Square: {
      const Args a(name, t, 2, keys_of(name), 0);
      s.a = a.number("a", field("shape.a"));
      s.centre = a.centre();
      a.placement(s);
      break;
    }
    case core::ShapeKind::Polar: {
      const Args a(name, t, 2, keys_of(name), 0);
      s.r_expr = a.raw("r");
      s.centre = a.centre();
      a.placement(s);
      break;
    }
    case core::ShapeKind::Parametric: {
      const Args a(name, t, 2, keys_of(name), 0);
      s.x_expr = a.raw("x");
      s.y_expr = a.raw("y");
      s.closed = a.on_off_or("closed", true);
      s.centre = a.centre();
      a.placement(s);
      break;
    }
    case core::ShapeKind::Implicit: {
      const Args a(name, t, 2, keys_of(name), 0);
      s.f_expr = a.raw("f");
      s.centre = a.centre();
      a.placement(s);
      break;
    }
    case core::ShapeKind::Polygon: {
      const Args a(name, t, 2, keys_of(name), 0);
      s.vertices = a.points("points");
      s.closed = a.on_off_or("closed", true);
      s.centre = a.centre();
      a.placement(s);
      break;
    }
  }
  compile_or_fail(name, cmd);
  return SetCommand{SetCommand::What::Shape, cmd};
}

Action parse_track(const Tokens& t, const core::CompiledCommand& current) {
  const std::string& kind = sub_word(t, "track", "line, circle, point or stop");
  const std::string name = "track " + kind;
  if (kind == "stop") {
    const Args a(name, t, 2, {}, 0);
    return TrackStop{};
  }
  core::CentrePath path;
  double r0 = 0.0;
  bool ff = false;
  if (kind == "line") {
    const Args a(name, t, 2, keys_of(name), 0);
    path.kind = core::CentrePath::Kind::Line;
    path.point = a.vec2("from");
    path.velocity = a.vec2("vel");
    r0 = a.number("r", field("shape.r0"));
    ff = a.on_off_or("ff", false);
  } else if (kind == "circle") {
    const Args a(name, t, 2, keys_of(name), 0);
    path.kind = core::CentrePath::Kind::Circle;
    path.radius = a.number("radius", field("tracking.radius"));
    // A circle of radius 0 is `track point`: this command wants a real circle (the config and the
    // topic accept 0).
    if (path.radius == 0.0) fail(name + ": radius must be > 0, got " + a.raw("radius"));
    path.period = a.number("period", field("tracking.period"));
    r0 = a.number("r", field("shape.r0"));
    path.origin = a.centre();
    path.phase = a.number_or("phase", field("tracking.phase"), 0.0);
    ff = a.on_off_or("ff", false);
  } else if (kind == "point") {
    const Args a(name, t, 2, keys_of(name), 0);
    path.kind = core::CentrePath::Kind::Fixed;
    path.point = a.vec2("at");
    r0 = a.number("r", field("shape.r0"));
    ff = a.on_off_or("ff", false);
  } else {
    fail("track: unknown path '" + kind + "' (expected line, circle, point, stop)");
  }
  core::CompiledCommand cmd = current;
  cmd.shape = core::ShapeSpec{};  // a plain circle: no rotation, scale 1
  cmd.shape.kind = core::ShapeKind::Circle;
  cmd.shape.r0 = r0;
  // The centre at t = 0 (shape_at() moves it along the path; this keeps the spec consistent).
  if (path.kind == core::CentrePath::Kind::Circle) {
    cmd.shape.centre =
        path.origin + path.radius * core::Vec2(std::cos(path.phase), std::sin(path.phase));
  } else {
    cmd.shape.centre = path.point;
  }
  cmd.tracking.enabled = true;
  cmd.tracking.path = path;
  cmd.tracking.feedforward = ff;
  compile_or_fail(name, cmd);
  return SetCommand{SetCommand::What::Track, cmd};
}

Action parse_gains(const Tokens& t, const core::CompiledCommand& current) {
  const Args a("gains", t, 1, keys_of("gains"), 0);
  if (a.empty()) fail("gains: expected at least one of k1, k2, sigma, beta, r");
  core::CompiledCommand cmd = current;
  core::Gains& g = cmd.gains;
  g.k1 = a.number_or("k1", field("dynamics.k1"), g.k1);
  g.k2 = a.number_or("k2", field("dynamics.k2"), g.k2);
  g.sigma = a.number_or("sigma", field("dynamics.sigma"), g.sigma);
  g.beta = a.number_or("beta", field("dynamics.beta"), g.beta);
  g.r = a.number_or("r", field("dynamics.r"), g.r);
  return SetCommand{SetCommand::What::Gains, cmd};
}

Action parse_integrator(const Tokens& t, const core::CompiledCommand& current) {
  const Args a("integrator", t, 1, keys_of("integrator"), 1);
  if (a.positionals() == 0)
    fail("integrator: missing method (" + params::join(params::names(params::kIntegratorNames), " or ") + ")");
  core::CompiledCommand cmd = current;
  const std::string& method = a.positional(0);
  if (!params::parse_name(params::kIntegratorNames, method, cmd.integrator))
    fail("integrator: unknown method '" + method + "' (expected " +
         params::join(params::names(params::kIntegratorNames), " or ") + ")");
  cmd.dt = a.number_or("dt", field("integration.dt"), cmd.dt);
  return SetCommand{SetCommand::What::Integrator, cmd};
}

Action parse_max_speed(const Tokens& t, const core::CompiledCommand& current) {
  const Args a("max_speed", t, 1, {}, 1);
  if (a.positionals() == 0) fail("max_speed: missing value (units per model time, 0 = off)");
  core::CompiledCommand cmd = current;
  cmd.max_speed = a.check_number("", a.positional(0), field("dynamics.max_speed"));
  return SetCommand{SetCommand::What::MaxSpeed, cmd};
}

Action parse_law(const Tokens& t, const core::CompiledCommand& current) {
  const Args a("law", t, 1, keys_of("law"), 1);
  if (a.positionals() == 0) fail("law: missing law (" + params::join(params::names(params::kLawNames), " or ") + ")");
  core::CompiledCommand cmd = current;  // the shape (and its curve) is kept
  const std::string& law = a.positional(0);
  if (!params::parse_name(params::kLawNames, law, cmd.law))
    fail("law: unknown law '" + law + "' (expected " + params::join(params::names(params::kLawNames), " or ") + ")");
  if (cmd.law == core::Law::Paper) {
    for (const char* key : {"k_normal", "k_tangent", "spacing"}) {
      if (a.has(key)) fail(std::string("law paper: ") + key + " is a parameter of the arc law");
    }
  } else {
    core::ArcParams& p = cmd.arc;
    p.k_normal = a.number_or("k_normal", field("dynamics.k_normal"), p.k_normal);
    p.k_tangent = a.number_or("k_tangent", field("dynamics.k_tangent"), p.k_tangent);
    p.spacing = a.number_or("spacing", field("dynamics.spacing"), p.spacing);
  }
  return SetCommand{SetCommand::What::Law, cmd};
}

Action parse_wait(const Tokens& t) {
  const std::string& what = sub_word(t, "wait", "converged, agents or time");
  const std::string name = "wait " + what;
  if (what == "converged") {
    const Args a(name, t, 2, keys_of(name), 0);
    return WaitConverged{a.number_or("timeout", kNonNegative, 60.0)};
  }
  if (what == "agents") {
    const Args a(name, t, 2, keys_of(name), 1);
    if (a.positionals() == 0) fail(name + ": missing agent count N");
    const std::string& text = a.positional(0);
    const double n = a.check_number("N", text, kAnyNumber);
    if (!(n >= 1.0) || n != std::floor(n) || n > static_cast<double>(INT_MAX)) {
      fail(name + ": N must be an integer >= 1, got " + text);
    }
    return WaitAgents{static_cast<int>(n), a.number_or("timeout", kNonNegative, 30.0)};
  }
  if (what == "time") {
    const Args a(name, t, 2, keys_of(name), 1);
    if (a.positionals() == 0) fail(name + ": missing model time T");
    const double when = a.check_number("T", a.positional(0), kNonNegative);
    return WaitTime{when, a.number_or("timeout", kNonNegative, 600.0)};
  }
  fail("wait: unknown condition '" + what + "' (expected converged, agents, time)");
}

Action parse_record(const Tokens& t) {
  const std::string& what = sub_word(t, "record", "start DIR or stop");
  const std::string name = "record " + what;
  if (what == "start") {
    const Args a(name, t, 2, {}, 1);
    if (a.positionals() == 0 || a.positional(0).empty()) fail(name + ": missing directory");
    return RecordStart{a.positional(0)};
  }
  if (what == "stop") {
    const Args a(name, t, 2, {}, 0);
    return RecordStop{};
  }
  fail("record: unknown action '" + what + "' (expected start, stop)");
}

Action parse_tokens(const Tokens& t, const core::CompiledCommand& current) {
  const std::string& word = t.front().text;
  if (word == "shape") return parse_shape(t, current);
  if (word == "track") return parse_track(t, current);
  if (word == "gains") return parse_gains(t, current);
  if (word == "integrator") return parse_integrator(t, current);
  if (word == "max_speed") return parse_max_speed(t, current);
  if (word == "law") return parse_law(t, current);
  if (word == "wait") return parse_wait(t);
  if (word == "record") return parse_record(t);
  if (word == "hold" || word == "stop" || word == "resume") {
    const Args a(word, t, 1, {}, 0);
    if (word == "resume") return Resume{};
    return Hold{word == "stop"};
  }
  if (word == "start") {
    const Args a(word, t, 1, {}, 1);
    if (a.positionals() == 1 && a.positional(0) != "replace")
      fail("start: unexpected argument '" + a.positional(0) + "' (expected replace)");
    return StartScenario{a.positionals() == 1};
  }
  if (word == "status" || word == "quit" || word == "exit" || word == "show") {
    const Args a(word, t, 1, {}, 0);
    if (word == "status") return Status{};
    if (word == "show") return Show{};
    return Quit{};
  }
  if (word == "metrics") {
    const Args a(word, t, 1, {}, 1);
    if (a.positionals() == 0) return ShowMetrics{};
    if (a.positional(0) != "json") fail("metrics: unexpected argument '" + a.positional(0) + "'");
    return ShowMetrics{true};
  }
  if (word == "progress") {
    const Args a(word, t, 1, {}, 2);
    const std::string mode = a.positionals() > 0 ? a.positional(0) : "";
    if ((mode == "on" || mode == "off") && a.positionals() == 1)
      return Progress{mode == "on" ? Progress::Mode::OnChange : Progress::Mode::Off, 0.0};
    if (mode == "every") {
      if (a.positionals() < 2) fail("progress every: missing interval S (wall seconds)");
      return Progress{Progress::Mode::Every, a.check_number("S", a.positional(1), params::above(0))};
    }
    fail("progress: expected on, off or every S");
  }
  if (word == "sleep") {
    const Args a(word, t, 1, {}, 1);
    if (a.positionals() == 0) fail("sleep: missing duration (seconds)");
    return Sleep{a.check_number("", a.positional(0), kNonNegative)};
  }
  if (word == "help") {
    const Args a(word, t, 1, {}, 1);
    if (a.positionals() == 0) return Help{};
    const std::string& topic = a.positional(0);
    if (!has_help(topic)) fail("help: unknown command '" + topic + "'");
    return Help{topic};
  }
  fail("unknown command '" + word + "' (try 'help')");
}

// ---------------------------------------------------------------------------------------------
// Help

struct HelpEntry {
  const char* word;
  const char* overview;  ///< one line per syntax variant
  std::string details;
};

/// "(> 0)": the bounds of a command field as the command table declares them.
std::string in(std::string_view key) { return "(" + field(key).bounds() + ")"; }

// clang-format off
const std::vector<HelpEntry>& help_entries() {
  static const std::vector<HelpEntry> entries = {
  {"shape",
   "shape line m=M c=C                                          line x2 = m x1 + c\n"
   "shape circle r=R [cx=X cy=Y]                                circle of radius R\n"
   "shape ellipse a=A b=B [cx=X cy=Y]                           ellipse, semi-axes A (x1), B (x2)\n"
   "shape square a=A [cx=X cy=Y]                                square of half side A\n"
   "shape polar r=\"EXPR\" [cx=X cy=Y]                            polar curve r(phi)\n"
   "shape parametric x=\"EXPR\" y=\"EXPR\" [closed=on|off] [cx= cy=]  x(s), y(s), s in [0, 1]\n"
   "shape implicit f=\"EXPR\" [cx=X cy=Y]                         curve f(x, y) = 0\n"
   "shape polygon points=\"x,y;x,y;...\" [closed=on|off] [cx= cy=]  polygon\n"
   "shape ... [rot=DEG] [scale=S]                               any shape: rotate (deg), scale\n",
   "shape line m=M c=C\n"
   "shape circle r=R [cx=X cy=Y]\n"
   "shape ellipse a=A b=B [cx=X cy=Y]\n"
   "shape square a=A [cx=X cy=Y]\n"
   "shape polar r=\"EXPR\" [cx=X cy=Y]\n"
   "shape parametric x=\"EXPR\" y=\"EXPR\" [closed=on|off] [cx=X cy=Y]\n"
   "shape implicit f=\"EXPR\" [cx=X cy=Y]\n"
   "shape polygon points=\"x,y;x,y;...\" [closed=on|off] [cx=X cy=Y]\n"
   "  and on every shape: [rot=DEG] [scale=S]\n"
   "  Commands a fixed shape and turns tracking off. Parameters are required except the centre,\n"
   "  closed, rot and scale. The shape is checked (expressions parsed, curve built) before\n"
   "  anything is sent: a bad one is refused and the swarm keeps its shape.\n"
   "  m, c    line slope and intercept (any finite value)\n"
   "  r       circle radius " + in("shape.r0") + "; polar: the expression r(phi), phi in [0, 2 pi), r > 0\n"
   "  a, b    ellipse semi-axes along x1 and x2 " + in("shape.a") + "; for the square, a is the half side " +
   in("shape.a") + "\n"
   "  x, y    parametric: the expressions x(s), y(s), s in [0, 1]\n"
   "  f       implicit: the expression f(x, y); the curve is f = 0 (traced in [-20, 20]^2)\n"
   "  points  polygon vertices x,y separated by ';' (closed: >= 3, open: >= 2)\n"
   "  closed  parametric, polygon: join the last point to the first (default on)\n"
   "  cx, cy  centre: where the shape's origin is placed (default 0, 0)\n"
   "  rot     counter-clockwise rotation about the centre, degrees (default 0)\n"
   "  scale   uniform scale about the centre (" + field("shape.scale").bounds() + ", default 1)\n"
   "  Expressions use muparser syntax (+ - * / ^, sin cos exp sqrt abs min max ..., pi);\n"
   "  quote them when they contain spaces: r=\"4 + cos(5*phi)\".\n"},
  {"track",
   "track line from=X,Y vel=VX,VY r=R [ff=on|off]               circle following a line\n"
   "track circle radius=RP period=T r=R [cx= cy= phase=] [ff=]  circle following a circle\n"
   "track point at=X,Y r=R [ff=on|off]                          circle held at a point\n"
   "track stop                                                  stop tracking, stay put\n",
   "track line from=X,Y vel=VX,VY r=R [ff=on|off]\n"
   "track circle radius=RP period=T r=R [cx=X cy=Y] [phase=P] [ff=on|off]\n"
   "track point at=X,Y r=R [ff=on|off]\n"
   "track stop\n"
   "  The swarm forms a circle of radius r " + in("shape.r0") + " around a moving centre C(t).\n"
   "  from     C(0) of the line path; vel: velocity in units per model time\n"
   "  radius   radius of the circular path (> 0); period: model time per revolution " + in("tracking.period") + "\n"
   "  cx, cy   centre of the circular path (default 0, 0); phase: angle at t = 0, rad (default 0)\n"
   "  at       the fixed centre\n"
   "  ff       feed-forward: add dC/dt to every agent's velocity (default off)\n"
   "  track stop keeps the shape where the tracked centre was.\n"},
  {"gains",
   "gains [k1=] [k2=] [sigma=] [beta=] [r=]                     change control gains\n",
   "gains [k1=K1] [k2=K2] [sigma=S] [beta=B] [r=R]\n"
   "  At least one; the others keep their current values.\n"
   "  k1     cohesion gain " + in("dynamics.k1") + "\n"
   "  k2     attraction-to-shape gain " + in("dynamics.k2") + "\n"
   "  sigma  softening length " + in("dynamics.sigma") + "\n"
   "  beta   decay exponent " + in("dynamics.beta") + "\n"
   "  r      nearest-neighbour repulsion magnitude " + in("dynamics.r") + "\n"},
  {"integrator",
   "integrator euler|rk4 [dt=DT]                                integration method and step\n",
   "integrator euler|rk4 [dt=DT]\n"
   "  dt  model time per step, in " + field("integration.dt").bounds() + " (default: keep the current step)\n"},
  {"max_speed",
   "max_speed V                                                 speed limit (0 = off)\n",
   "max_speed V\n"
   "  V  speed limit in units per model time (" + field("dynamics.max_speed").bounds() + "; 0 = no limit), both laws\n"},
  {"law",
   "law paper | law arc [k_normal=] [k_tangent=] [spacing=]     control law\n",
   "law paper\n"
   "law arc [k_normal=K] [k_tangent=T] [spacing=S]\n"
   "  Selects the control law; the shape is kept. paper: eq. 2 with the gains (see 'gains').\n"
   "  arc: arc-length slots, exact and evenly spaced (docs/LAW.md). Parameters not given keep\n"
   "  their current values.\n"
   "  k_normal   rate toward the curve, 1/model time (in " + field("dynamics.k_normal").bounds() +
   "; keep k_normal * dt <= 1)\n"
   "  k_tangent  fraction of the slot error taken per step along the curve (in " +
   field("dynamics.k_tangent").bounds() + ")\n"
   "  spacing    gap between agents on an unbounded curve such as the line " + in("dynamics.spacing") + "\n"},
  {"start",
   "start [replace]                                             publish the scenario of --config\n",
   "start [replace]\n"
   "  Publishes the command of the supervisor's --config file (shape, tracking, gains,\n"
   "  integrator) as a new epoch. The launcher runs it once every agent is heard. When a command\n"
   "  is in force already (published before this supervisor started, by it or by another\n"
   "  participant), plain 'start' keeps it and says so, unless the supervisor was started with\n"
   "  --command-on-start replace; 'start replace' publishes the scenario anyway.\n"},
  {"hold",
   "hold                                                        freeze the swarm where it is\n",
   "hold\n"
   "  Every agent stops moving and keeps its position; model time stands still, so a tracked\n"
   "  centre does not move on either ('wait time' does not advance). Sent on the command topic as\n"
   "  a new epoch with the command in force: an agent that joins later holds too. While held, new\n"
   "  commands (shape, gains, start, ...) are taken but stay held until 'resume'. 'stop' is the\n"
   "  same.\n"},
  {"stop",
   "stop                                                        emergency stop: the same as hold\n",
   "stop\n"
   "  Emergency stop: exactly 'hold' (every agent stops at once and keeps its position, late\n"
   "  joiners too), under the word an operator reaches for. 'resume' releases it. ('track stop'\n"
   "  only ends tracking; the swarm keeps forming its shape.)\n"},
  {"resume",
   "resume                                                      release a hold or stop\n",
   "resume\n"
   "  Publishes the command in force with the hold released (a new epoch): the swarm moves again\n"
   "  and re-converges. A tracked centre continues from where it was held. Without a hold in\n"
   "  force it changes nothing and sends nothing.\n"},
  {"status",
   "status                                                      table of agents\n",
   "status\n"
   "  One row per agent heard: id, alive/DEAD/left, last seen, position, epoch followed,\n"
   "  its shape error and how many neighbours it hears.\n"},
  {"show",
   "show                                                        the command in force and its epoch\n",
   "show\n"
   "  The command in force: shape, tracking, law, gains, integrator, speed limit, its epoch and\n"
   "  who published it (this supervisor, or another participant when the agents follow an epoch\n"
   "  this supervisor did not publish), and how many agents follow it.\n"},
  {"metrics",
   "metrics [json]                                              latest formation metrics\n",
   "metrics\n"
   "metrics json\n"
   "  Prints the latest metrics (shape error, gap CV, clusters, ...) as a table, 4 significant\n"
   "  digits, with units; `metrics json` prints them as one JSON object. With --json both print\n"
   "  the JSON object (and the metrics event on stdout).\n"},
  {"progress",
   "progress on|off|every S                                     when to print the progress line\n",
   "progress on\n"
   "progress off\n"
   "progress every S\n"
   "  The progress line (model time, agents, shape error, gap CV, ...). on (the default): printed\n"
   "  when something changed: the number of agents alive or following, the epoch, the converged\n"
   "  flag, the cluster count, or a metric by more than 10% of its last printed value (changes\n"
   "  smaller than 0.001 ignored); at most once a second. every S: every S wall seconds (> 0).\n"
   "  off: never. At a terminal it is printed above the line being typed.\n"},
  {"wait",
   "wait converged [timeout=S]                                  wait for convergence (S wall seconds)\n"
   "wait agents N [timeout=S]                                   wait for N agents hearing each other\n"
   "wait time T [timeout=S]                                     wait for model time T (not seconds)\n",
   "wait converged [timeout=S]\n"
   "wait agents N [timeout=S]\n"
   "wait time T [timeout=S]\n"
   "  Holds further input until the condition holds or the timeout (wall seconds, >= 0;\n"
   "  default 60 for converged, 30 for agents, 600 for time) runs out. N is an integer >= 1;\n"
   "  T is model time since the current command was published (one paper iteration = dt),\n"
   "  counted by the agents: it holds until every agent on the command has reached T.\n"
   "  At a terminal, Ctrl-C cancels the wait.\n"},
  {"sleep",
   "sleep S                                                     pause input for S wall seconds\n",
   "sleep S\n"
   "  Holds further input for S wall-clock seconds (>= 0). At a terminal, Ctrl-C cancels it.\n"},
  {"record",
   "record start DIR | record stop                              CSV recording\n",
   "record start DIR\n"
   "record stop\n"
   "  Writes DIR/metrics.csv, positions.csv, commands.csv and centre.csv (docs/RECORDING.md;\n"
   "  DIR is created; files are overwritten).\n"
   "  Quote DIR if it contains spaces. record stop closes the files (or says nothing is recording).\n"},
  {"help",
   "help [COMMAND]                                              this list, or details\n",
   "help [COMMAND]\n"
   "  Without COMMAND, one line per command; with it, the details of that command.\n"},
  {"quit",
   "quit | exit                                                 stop the supervisor\n",
   "quit\n"
   "exit\n"
   "  Stops the supervisor (exit status 0, or 3 after a wait timed out). At a terminal, Ctrl-D on\n"
   "  an empty line does the same; Ctrl-C clears the line being typed or cancels a wait, and a\n"
   "  second Ctrl-C within 1 s on an empty line stops the supervisor with exit status 130.\n"},
  };
  return entries;
}
// clang-format on

const HelpEntry* find_help(std::string_view word) {
  if (word == "exit") word = "quit";
  for (const HelpEntry& e : help_entries()) {
    if (word == e.word) return &e;
  }
  return nullptr;
}

}  // namespace

ParseResult parse_command(std::string_view line, const core::CompiledCommand& current) {
  ParseResult result{NoOp{}, {}};
  std::vector<Token> tokens;
  result.error = tokenize(line, tokens);
  if (!result.ok() || tokens.empty()) return result;
  try {
    result.action = parse_tokens(tokens, current);
    // Every new command keeps to its envelope, as the config loader and the agents' receiver check it.
    if (const auto* set = std::get_if<SetCommand>(&result.action)) {
      const auto problems = core::envelope_problems(set->command);
      if (!problems.empty()) fail(tokens.front().text + ": " + core::envelope_text(problems));
    }
  } catch (const ParseError& e) {
    result.action = NoOp{};
    result.error = e.message;
  }
  return result;
}

bool has_help(std::string_view word) { return find_help(word) != nullptr; }

std::vector<std::string> command_words() {
  std::vector<std::string> words;
  for (const HelpEntry& e : help_entries()) {
    words.emplace_back(e.word);
    if (words.back() == "quit") words.emplace_back("exit");
  }
  return words;
}

Completion complete(std::string_view before_cursor) {
  std::vector<Token> tokens;
  Completion c;
  // Complete only outside quotes: an unterminated quote is an expression being typed.
  if (!tokenize(before_cursor, tokens).empty()) return c;
  const bool new_word = before_cursor.empty() || is_space(before_cursor.back());
  std::string word;
  if (!new_word && !tokens.empty()) {
    word = tokens.back().text;
    tokens.pop_back();
  }
  c.start = before_cursor.size() - word.size();
  if (word.find('=') != std::string::npos || word.find('"') != std::string::npos) return c;  // a value
  std::vector<std::string> offer;
  if (tokens.empty()) {
    offer = command_words();
  } else {
    std::string words = tokens[0].text;
    // Second words: those of the syntax entries "FIRST SECOND".
    if (tokens.size() == 1)
      for (const Syntax& s : syntax_table())
        if (s.words.rfind(words + " ", 0) == 0) offer.push_back(s.words.substr(words.size() + 1));
    if (words == "help" && tokens.size() == 1) offer = command_words();
    if (tokens.size() >= 2 && !tokens[1].is_pair) words += " " + tokens[1].text;
    for (const Syntax& s : syntax_table()) {
      if (s.words != words && s.words != tokens[0].text) continue;
      if (s.words == tokens[0].text && tokens.size() == 1) offer.insert(offer.end(), s.values.begin(), s.values.end());
      for (const std::string& k : s.keys) {
        bool given = false;  // a parameter is offered once
        for (const Token& t : tokens) given = given || (t.is_pair && t.key == k);
        if (!given) offer.push_back(k + "=");
      }
      break;
    }
  }
  for (const std::string& o : offer)
    if (o.rfind(word, 0) == 0) c.candidates.push_back(o);
  std::sort(c.candidates.begin(), c.candidates.end());
  c.candidates.erase(std::unique(c.candidates.begin(), c.candidates.end()), c.candidates.end());
  return c;
}

std::string help_text(std::string_view command) {
  if (command.empty()) {
    std::string text =
        "Commands (key=value parameters in any order; `help COMMAND` for details):\n";
    for (const HelpEntry& e : help_entries()) text += e.overview;
    text += "Lines starting with # are comments. Quote values containing spaces: dir=\"a b\".\n";
    return text;
  }
  if (const HelpEntry* e = find_help(command)) return e->details;
  return "no help for '" + std::string(command) + "' (try 'help')\n";
}

}  // namespace shapeform::supervisor
