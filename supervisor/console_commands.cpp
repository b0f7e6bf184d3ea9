#include "console_commands.hpp"

#include <algorithm>
#include <cctype>
#include <climits>
#include <cmath>
#include <sstream>
#include <utility>

#include "core/enum_names.hpp"
#include "core/fence.hpp"
#include "core/safety.hpp"
#include "shapes/shapes.hpp"

namespace shapeform::supervisor {

namespace {

namespace params = core::params;
using Need = ParamSpec::Need;
using core::CompiledCommand;

// ---------------------------------------------------------------------------------------------
// Declaring parameters and forms

/// `key=VALUE`, bounded by the command table's `field`.
ParamSpec req(std::string key, std::string value, std::string field) {
  return {std::move(key), std::move(value), Need::Required, std::move(field), {}, {}};
}
/// `[key=VALUE]`.
ParamSpec opt(std::string key, std::string value, std::string field) {
  return {std::move(key), std::move(value), Need::Optional, std::move(field), {}, {}};
}
/// ` key=VALUE` inside the previous parameter's brackets.
ParamSpec joined(std::string key, std::string value, std::string field) {
  return {std::move(key), std::move(value), Need::Joined, std::move(field), {}, {}};
}
/// `[key=VALUE]` that is not a field of the command: its own bounds and unit.
ParamSpec opt_own(std::string key, std::string value, params::Range range, std::string unit) {
  return {std::move(key), std::move(value), Need::Optional, {}, range, std::move(unit)};
}

/// A form whose Action does not depend on its arguments (`status`, `hold`).
FormSpec fixed(std::string summary, Action action) {
  FormSpec f;
  f.summary = std::move(summary);
  f.parse = [action](const Args&, const CompiledCommand&) { return action; };
  return f;
}

/// A form with positional usages and a parse function.
FormSpec form(std::string sub, std::vector<std::string> usages, std::vector<ParamSpec> ps,
              std::string summary, ParseFn parse) {
  return {std::move(sub), std::move(usages), std::move(ps), std::move(summary), std::move(parse)};
}

/// A command of one form and its help page's text.
CommandSpec single(std::string word, FormSpec f, std::string details = {}) {
  CommandSpec c;
  c.word = std::move(word);
  c.forms.push_back(std::move(f));
  c.details = std::move(details);
  return c;
}

/// "(> 0)": the bounds of a command field as the command table declares them.
std::string in(std::string_view key) { return "(" + field_range(key).bounds() + ")"; }

std::string either(const std::vector<std::string>& names) { return params::join(names, " or "); }

// ---------------------------------------------------------------------------------------------
// shape

/// shapes::compile on a parsed shape: a ShapeError becomes the command's one-line error, named
/// after the command ("shape polar: r(phi) = '4+foo': Unexpected token ...").
void compile_or_fail(const std::string& name, CompiledCommand& cmd) {
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

using ShapeFill = void (*)(const Args&, core::ShapeSpec&);

/// `shape KIND ...`: a fixed shape of that kind (tracking off, nothing of the previous shape kept),
/// `fill` reading its own parameters, then the centre (when it takes one), rot and scale, compiled.
FormSpec shape_form(core::ShapeKind kind, std::vector<ParamSpec> ps, std::string summary, ShapeFill fill) {
  const bool centred = std::any_of(ps.begin(), ps.end(), [](const ParamSpec& p) { return p.key == "cx"; });
  const auto parse = [kind, fill, centred](const Args& a, const CompiledCommand& current) -> Action {
    CompiledCommand cmd = current;
    cmd.tracking = core::Tracking{};  // a fixed shape: tracking off, no stale path
    cmd.shape = core::ShapeSpec{};    // nothing of the previous shape (expressions) lingers
    cmd.shape.kind = kind;
    fill(a, cmd.shape);
    if (centred) cmd.shape.centre = a.centre();
    a.placement(cmd.shape);
    compile_or_fail(a.name(), cmd);
    return SetCommand{SetCommand::What::Shape, cmd};
  };
  return form(std::string(core::to_string(kind)), {""}, std::move(ps), std::move(summary), parse);
}

/// `ps`, then the optional centre `[cx=X cy=Y]` of a shape.
std::vector<ParamSpec> centred(std::vector<ParamSpec> ps) {
  ps.push_back(opt("cx", "X", "shape.centre"));
  ps.push_back(joined("cy", "Y", "shape.centre"));
  return ps;
}

std::string shape_help() {
  // clang-format off
  return "  Commands a fixed shape and turns tracking off. Parameters are required except the centre,\n"
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
         "  scale   uniform scale about the centre (" + field_range("shape.scale").bounds() + ", default 1)\n"
         "  Expressions use muparser syntax (+ - * / ^, sin cos exp sqrt abs min max ..., pi);\n"
         "  quote them when they contain spaces: r=\"4 + cos(5*phi)\".\n";
  // clang-format on
}

CommandSpec shape_command() {
  using K = core::ShapeKind;
  using S = core::ShapeSpec;
  const ParamSpec closed = opt("closed", "on|off", "shape.closed");
  CommandSpec c;
  c.word = "shape";
  c.noun = "shape";
  c.expected = "a shape (" + params::join(params::names(params::kShapeKindNames), ", ") + ")";
  c.shared = {opt("rot", "DEG", "shape.rotation_deg"), opt("scale", "S", "shape.scale")};
  c.shared_summary = "any shape: rotate (deg), scale";
  c.forms = {
      shape_form(K::Line, {req("m", "M", "shape.m"), req("c", "C", "shape.c")}, "line x2 = m x1 + c",
                 [](const Args& a, S& s) {
                   s.m = a.number("m");
                   s.c = a.number("c");
                 }),
      shape_form(K::Circle, centred({req("r", "R", "shape.r0")}), "circle of radius R",
                 [](const Args& a, S& s) { s.r0 = a.number("r"); }),
      shape_form(K::Ellipse, centred({req("a", "A", "shape.a"), req("b", "B", "shape.b")}),
                 "ellipse, semi-axes A (x1), B (x2)",
                 [](const Args& a, S& s) {
                   s.a = a.number("a");
                   s.b = a.number("b");
                 }),
      shape_form(K::Square, centred({req("a", "A", "shape.a")}), "square of half side A",
                 [](const Args& a, S& s) { s.a = a.number("a"); }),
      shape_form(K::Polar, centred({req("r", "\"EXPR\"", "shape.r_expr")}), "polar curve r(phi)",
                 [](const Args& a, S& s) { s.r_expr = a.raw("r"); }),
      shape_form(
          K::Parametric,
          centred({req("x", "\"EXPR\"", "shape.x_expr"), req("y", "\"EXPR\"", "shape.y_expr"), closed}),
          "x(s), y(s), s in [0, 1]",
          [](const Args& a, S& s) {
            s.x_expr = a.raw("x");
            s.y_expr = a.raw("y");
            s.closed = a.on_off_or("closed", true);
          }),
      shape_form(K::Implicit, centred({req("f", "\"EXPR\"", "shape.f_expr")}), "curve f(x, y) = 0",
                 [](const Args& a, S& s) { s.f_expr = a.raw("f"); }),
      shape_form(K::Polygon, centred({req("points", "\"x,y;x,y;...\"", "shape.vertices"), closed}), "polygon",
                 [](const Args& a, S& s) {
                   s.vertices = a.points("points");
                   s.closed = a.on_off_or("closed", true);
                 }),
  };
  c.details = shape_help();
  return c;
}

// ---------------------------------------------------------------------------------------------
// track

/// The command of a tracked circle of radius r0 about `path` (its centre at t = 0 on the spec).
Action tracked(const Args& a, const CompiledCommand& current, const core::CentrePath& path, double r0) {
  const bool ff = a.on_off_or("ff", false);
  CompiledCommand cmd = current;
  cmd.shape = core::ShapeSpec{};  // a plain circle: no rotation, scale 1
  cmd.shape.kind = core::ShapeKind::Circle;
  cmd.shape.r0 = r0;
  // The centre at t = 0 (shape_at() moves it along the path; this keeps the spec consistent).
  if (path.kind == core::CentrePath::Kind::Circle) {
    cmd.shape.centre = path.origin + path.radius * core::Vec2(std::cos(path.phase), std::sin(path.phase));
  } else {
    cmd.shape.centre = path.point;
  }
  cmd.tracking.enabled = true;
  cmd.tracking.path = path;
  cmd.tracking.feedforward = ff;
  compile_or_fail(a.name(), cmd);
  return SetCommand{SetCommand::What::Track, cmd};
}

Action track_line(const Args& a, const CompiledCommand& current) {
  core::CentrePath path;
  path.kind = core::CentrePath::Kind::Line;
  path.point = a.vec2("from");
  path.velocity = a.vec2("vel");
  return tracked(a, current, path, a.number("r"));
}

Action track_circle(const Args& a, const CompiledCommand& current) {
  core::CentrePath path;
  path.kind = core::CentrePath::Kind::Circle;
  path.radius = a.number("radius");
  // A circle of radius 0 is `track point`: this command wants a real circle (the config and the
  // topic accept 0).
  if (path.radius == 0.0) fail(a.name() + ": radius must be > 0, got " + a.raw("radius"));
  path.period = a.number("period");
  const double r0 = a.number("r");
  path.origin = a.centre();
  path.phase = a.number_or("phase", 0.0);
  return tracked(a, current, path, r0);
}

Action track_point(const Args& a, const CompiledCommand& current) {
  core::CentrePath path;
  path.kind = core::CentrePath::Kind::Fixed;
  path.point = a.vec2("at");
  return tracked(a, current, path, a.number("r"));
}

CommandSpec track_command() {
  const ParamSpec r = req("r", "R", "shape.r0"), ff = opt("ff", "on|off", "tracking.feedforward");
  CommandSpec c;
  c.word = "track";
  c.noun = "path";
  c.expected = "line, circle, point or stop";
  c.forms = {
      form("line", {""},
           {req("from", "X,Y", "tracking.point"), req("vel", "VX,VY", "tracking.velocity"), r, ff},
           "circle following a line", track_line),
      form("circle", {""},
           {req("radius", "RP", "tracking.radius"), req("period", "T", "tracking.period"), r,
            opt("cx", "X", "tracking.origin"), joined("cy", "Y", "tracking.origin"),
            opt("phase", "P", "tracking.phase"), ff},
           "circle following a circle", track_circle),
      form("point", {""}, {req("at", "X,Y", "tracking.point"), r, ff}, "circle held at a point", track_point),
      form("stop", {""}, {}, "stop tracking, stay put",
           [](const Args&, const CompiledCommand&) -> Action { return TrackStop{}; }),
  };
  // clang-format off
  c.details =
      "  The swarm forms a circle of radius r " + in("shape.r0") + " around a moving centre C(t).\n"
      "  from     C(0) of the line path; vel: velocity in units per model time\n"
      "  radius   radius of the circular path (> 0); period: model time per revolution " + in("tracking.period") + "\n"
      "  cx, cy   centre of the circular path (default 0, 0); phase: angle at t = 0, rad (default 0)\n"
      "  at       the fixed centre\n"
      "  ff       feed-forward: add dC/dt to every agent's velocity (default off)\n"
      "  track stop keeps the shape where the tracked centre was.\n";
  // clang-format on
  return c;
}

// ---------------------------------------------------------------------------------------------
// The command's other fields: gains, integrator, max_speed, law

CommandSpec gains_command() {
  const auto parse = [](const Args& a, const CompiledCommand& current) -> Action {
    if (a.empty()) fail("gains: expected at least one of " + params::join(a.keys(), ", "));
    CompiledCommand cmd = current;
    core::Gains& g = cmd.gains;
    g.k1 = a.number_or("k1", g.k1);
    g.k2 = a.number_or("k2", g.k2);
    g.sigma = a.number_or("sigma", g.sigma);
    g.beta = a.number_or("beta", g.beta);
    g.r = a.number_or("r", g.r);
    return SetCommand{SetCommand::What::Gains, cmd};
  };
  CommandSpec c = single("gains", form("", {""},
                                       {opt("k1", "K1", "dynamics.k1"), opt("k2", "K2", "dynamics.k2"),
                                        opt("sigma", "S", "dynamics.sigma"),
                                        opt("beta", "B", "dynamics.beta"), opt("r", "R", "dynamics.r")},
                                       "change control gains", parse));
  // clang-format off
  c.details =
      "  At least one; the others keep their current values.\n"
      "  k1     cohesion gain " + in("dynamics.k1") + "\n"
      "  k2     attraction-to-shape gain " + in("dynamics.k2") + "\n"
      "  sigma  softening length " + in("dynamics.sigma") + "\n"
      "  beta   decay exponent " + in("dynamics.beta") + "\n"
      "  r      nearest-neighbour repulsion magnitude " + in("dynamics.r") + "\n";
  // clang-format on
  return c;
}

CommandSpec integrator_command() {
  const auto parse = [](const Args& a, const CompiledCommand& current) -> Action {
    const std::string methods = either(params::names(params::kIntegratorNames));
    if (a.positionals() == 0) fail("integrator: missing method (" + methods + ")");
    CompiledCommand cmd = current;
    const std::string& method = a.positional(0);
    if (!params::parse_name(params::kIntegratorNames, method, cmd.integrator))
      fail("integrator: unknown method '" + method + "' (expected " + methods + ")");
    cmd.dt = a.number_or("dt", cmd.dt);
    return SetCommand{SetCommand::What::Integrator, cmd};
  };
  CommandSpec c =
      single("integrator", form("", {params::join(params::names(params::kIntegratorNames), "|")},
                                {opt("dt", "DT", "integration.dt")}, "integration method and step", parse));
  // clang-format off
  c.details =
      "  dt  model time per step, in " + field_range("integration.dt").bounds() + " (default: keep the current step)\n";
  // clang-format on
  return c;
}

CommandSpec max_speed_command() {
  const auto parse = [](const Args& a, const CompiledCommand& current) -> Action {
    if (a.positionals() == 0) fail("max_speed: missing value (units per model time, 0 = off)");
    CompiledCommand cmd = current;
    cmd.max_speed = a.check_number("", a.positional(0), field_range("dynamics.max_speed"));
    return SetCommand{SetCommand::What::MaxSpeed, cmd};
  };
  CommandSpec c = single("max_speed", form("", {"V"}, {}, "speed limit (0 = off)", parse));
  // clang-format off
  c.details =
      "  V  speed limit in units per model time (" + field_range("dynamics.max_speed").bounds() + "; 0 = no limit), both laws\n";
  // clang-format on
  return c;
}

Action parse_law(const Args& a, const CompiledCommand& current) {
  const std::string laws = either(params::names(params::kLawNames));
  if (a.positionals() == 0) fail("law: missing law (" + laws + ")");
  CompiledCommand cmd = current;  // the shape (and its curve) is kept
  const std::string& law = a.positional(0);
  if (!params::parse_name(params::kLawNames, law, cmd.law))
    fail("law: unknown law '" + law + "' (expected " + laws + ")");
  if (cmd.law == core::Law::Paper) {
    for (const std::string& key : a.keys())
      if (a.has(key)) fail("law paper: " + key + " is a parameter of the arc law");
  } else {
    core::ArcParams& p = cmd.arc;
    p.k_normal = a.number_or("k_normal", p.k_normal);
    p.k_tangent = a.number_or("k_tangent", p.k_tangent);
    p.spacing = a.number_or("spacing", p.spacing);
  }
  return SetCommand{SetCommand::What::Law, cmd};
}

CommandSpec law_command() {
  // The parameters follow the last usage: they are the arc law's.
  CommandSpec c = single(
      "law", form("", params::names(params::kLawNames),
                  {opt("k_normal", "K", "dynamics.k_normal"), opt("k_tangent", "T", "dynamics.k_tangent"),
                   opt("spacing", "S", "dynamics.spacing")},
                  "control law", parse_law));
  // clang-format off
  c.details =
      "  Selects the control law; the shape is kept. paper: eq. 2 with the gains (see 'gains').\n"
      "  arc: arc-length slots, exact and evenly spaced (docs/LAW.md). Parameters not given keep\n"
      "  their current values.\n"
      "  k_normal   rate toward the curve, 1/model time (in " + field_range("dynamics.k_normal").bounds() +
      "; keep k_normal * dt <= 1)\n"
      "  k_tangent  fraction of the slot error taken per step along the curve (in " +
      field_range("dynamics.k_tangent").bounds() + ")\n"
      "  spacing    gap between agents on an unbounded curve such as the line " + in("dynamics.spacing") + "\n";
  // clang-format on
  return c;
}

// ---------------------------------------------------------------------------------------------
// safety: separation, keep-out zones, the fence

/// `safety separation D`.
Action parse_separation(const Args& a, const CompiledCommand& current) {
  if (a.positionals() == 0) fail(a.name() + ": missing separation D (shape units; 0 = off)");
  CompiledCommand cmd = current;
  cmd.min_separation = a.check_number("", a.positional(0), field_range("safety.min_separation"));
  return SetCommand{SetCommand::What::Safety, cmd};
}

/// `safety keep_out add circle X,Y R | add polygon "x,y;..." | remove K | clear`. Zones are kept in
/// the order they travel (circles first), which is the order `safety` numbers them.
Action parse_keep_out(const Args& a, const CompiledCommand& current) {
  const std::string verb = a.positionals() > 0 ? a.positional(0) : "";
  CompiledCommand cmd = current;
  std::vector<core::KeepOutZone>& zones = cmd.keep_out;
  const auto extra = [&a](std::size_t n) {
    if (a.positionals() > n) fail(a.name() + ": unexpected argument '" + a.positional(n) + "'");
  };
  if (verb == "clear") {
    extra(1);
    zones.clear();
  } else if (verb == "remove") {
    if (a.positionals() < 2) fail(a.name() + " remove: missing zone number K (as 'safety' lists them)");
    extra(2);
    const std::string& text = a.positional(1);
    const double k = a.check_number("remove K", text, params::any());
    if (zones.empty()) fail(a.name() + " remove: there is no keep-out zone");
    if (!(k >= 1.0) || k != std::floor(k) || k > static_cast<double>(zones.size()))
      fail(a.name() + " remove: K must be a zone number 1.." + std::to_string(zones.size()) +
           " (as 'safety' lists them), got " + text);
    zones.erase(zones.begin() + static_cast<std::ptrdiff_t>(k) - 1);
  } else if (verb == "add") {
    const std::string kind = a.positionals() > 1 ? a.positional(1) : "";
    const std::string name = a.name() + " add " + kind;
    core::KeepOutZone z;
    if (kind == "circle") {
      if (a.positionals() < 4) fail(name + ": expected the centre X,Y and the radius R");
      z.centre = a.check_vec2("add circle: centre", a.positional(2));
      z.radius = a.check_number("add circle: R", a.positional(3), params::any());
    } else if (kind == "polygon") {
      if (a.positionals() < 3) fail(name + ": missing vertices \"x,y;x,y;x,y\"");
      extra(3);
      z.kind = core::KeepOutZone::Kind::Polygon;
      z.vertices = a.check_points("add polygon", a.positional(2));
    } else {
      fail(a.name() + " add: expected circle X,Y R or polygon \"x,y;x,y;x,y\"" +
           (kind.empty() ? std::string() : ", got '" + kind + "'"));
    }
    const std::vector<std::string> problems = core::keep_out_problems(z);
    if (!problems.empty()) fail(name + ": " + params::join(problems, "; "));
    // Circles before polygons, as they travel (the agents number them alike).
    const auto at = z.kind == core::KeepOutZone::Kind::Circle
                        ? std::find_if(zones.begin(), zones.end(),
                                       [](const core::KeepOutZone& q) {
                                         return q.kind != core::KeepOutZone::Kind::Circle;
                                       })
                        : zones.end();
    zones.insert(at, z);
  } else {
    fail(a.name() + ": expected add circle X,Y R, add polygon \"x,y;...\", remove K or clear" +
         (verb.empty() ? std::string() : ", got '" + verb + "'"));
  }
  return SetCommand{SetCommand::What::Safety, cmd};
}

/// `safety fence box | polygon "x,y;..." [margin=M] [action=hold|stop|return]`: what is not given is
/// kept.
Action parse_fence(const Args& a, const CompiledCommand& current) {
  const std::string kind = a.positionals() > 0 ? a.positional(0) : "";
  CompiledCommand cmd = current;
  if (kind == "box") {
    if (a.positionals() > 1) fail(a.name() + " box: unexpected argument '" + a.positional(1) + "'");
    cmd.fence.clear();
  } else if (kind == "polygon") {
    if (a.positionals() < 2) fail(a.name() + " polygon: missing vertices \"x,y;x,y;x,y\"");
    cmd.fence = a.check_points("polygon", a.positional(1));
    const std::vector<std::string> problems = core::fence_problems(cmd.fence, cmd.workspace);
    if (!problems.empty()) fail(a.name() + " polygon: " + params::join(problems, "; "));
  } else {
    fail(a.name() + ": expected box or polygon \"x,y;x,y;...\"" +
         (kind.empty() ? std::string() : ", got '" + kind + "'"));
  }
  cmd.fence_margin = a.number_or("margin", cmd.fence_margin);
  if (a.has("action") && !params::parse_name(params::kBreachActionNames, a.raw("action"), cmd.breach_action))
    fail(a.name() + ": unknown action '" + a.raw("action") + "' (expected " +
         params::join(params::names(params::kBreachActionNames), "|") + ")");
  return SetCommand{SetCommand::What::Safety, cmd};
}

CommandSpec safety_command() {
  CommandSpec c;
  c.word = "safety";
  c.noun = "setting";
  c.expected = "separation, keep_out, fence or show";
  c.bare = "show";
  const std::string actions = params::join(params::names(params::kBreachActionNames), "|");
  c.forms = {
      form("separation", {"D"}, {}, "keep agents D apart (0 = off)", parse_separation),
      form("keep_out", {"add circle X,Y R", "add polygon \"x,y;x,y;x,y\"", "remove K", "clear"}, {},
           "keep-out zones", parse_keep_out),
      form("fence", {"box", "polygon \"x,y;x,y;x,y\""},
           {opt("margin", "M", "safety.fence_margin"), opt("action", actions, "safety.breach_action")},
           "geofence, its margin and breach action", parse_fence),
      form("show", {""}, {}, "the safety settings in force",
           [](const Args&, const CompiledCommand&) -> Action { return ShowSafety{}; }),
  };
  // clang-format off
  c.details =
      "  Changes the safety settings of the command in force and publishes it as a new epoch (the\n"
      "  shape and everything else kept); docs/SAFETY.md. 'safety' alone is 'safety show'.\n"
      "  separation D   smallest distance two agents keep at every step, shape units " + in("safety.min_separation") + ",\n"
      "                 0 = off\n"
      "  keep_out       zones no agent enters: add a circle (centre X,Y, radius R > 0) or a simple polygon\n"
      "                 (>= 3 vertices); remove zone K as 'safety' numbers them (circles first); clear all\n"
      "  fence box      the workspace box [-w, w]^2 is the fence (safety.workspace)\n"
      "  fence polygon  a convex polygon inside the workspace box (cut a dent out with keep_out instead)\n"
      "  margin=M       every step is kept M inside the fence, shape units " + in("safety.fence_margin") + "\n"
      "  action=A       what an agent found beyond the fence does: hold = it stops and the supervisor\n"
      "                 holds the swarm ('resume' releases); stop = that agent stops until the next\n"
      "                 command; return = it heads back inside through the safety filter\n"
      "  margin and action not given keep their values. A zone or fence with problems is refused,\n"
      "  and nothing is sent.\n";
  // clang-format on
  return c;
}

// ---------------------------------------------------------------------------------------------
// Publishing: start, hold, stop, resume

CommandSpec start_command() {
  const auto parse = [](const Args& a, const CompiledCommand&) -> Action {
    if (a.positionals() == 1 && a.positional(0) != "replace")
      fail("start: unexpected argument '" + a.positional(0) + "' (expected replace)");
    return StartScenario{a.positionals() == 1};
  };
  // clang-format off
  return single("start", form("", {"[replace]"}, {}, "publish the scenario of --config", parse),
                "  Publishes the command of the supervisor's --config file (shape, tracking, gains,\n"
                "  integrator) as a new epoch. The launcher runs it once every agent is heard. When a command\n"
                "  is in force already (published before this supervisor started, by it or by another\n"
                "  participant), plain 'start' keeps it and says so, unless the supervisor was started with\n"
                "  --command-on-start replace; 'start replace' publishes the scenario anyway.\n");
  // clang-format on
}

std::vector<CommandSpec> hold_commands() {
  // clang-format off
  return {
      single("hold", fixed("freeze the swarm where it is", Hold{false}),
             "  Every agent stops moving and keeps its position; model time stands still, so a tracked\n"
             "  centre does not move on either ('wait time' does not advance). Sent on the command topic as\n"
             "  a new epoch with the command in force: an agent that joins later holds too. While held, new\n"
             "  commands (shape, gains, start, ...) are taken but stay held until 'resume'. 'stop' is the\n"
             "  same.\n"),
      single("stop", fixed("emergency stop: the same as hold", Hold{true}),
             "  Emergency stop: exactly 'hold' (every agent stops at once and keeps its position, late\n"
             "  joiners too), under the word an operator reaches for. 'resume' releases it. ('track stop'\n"
             "  only ends tracking; the swarm keeps forming its shape.)\n"),
      single("resume", fixed("release a hold or stop", Resume{}),
             "  Publishes the command in force with the hold released (a new epoch): the swarm moves again\n"
             "  and re-converges. A tracked centre continues from where it was held. Without a hold in\n"
             "  force it changes nothing and sends nothing.\n"),
  };
  // clang-format on
}

// ---------------------------------------------------------------------------------------------
// Questions: status, show, metrics, progress

std::vector<CommandSpec> question_commands() {
  const auto metrics = [](const Args& a, const CompiledCommand&) -> Action {
    if (a.positionals() == 0) return ShowMetrics{};
    if (a.positional(0) != "json") fail("metrics: unexpected argument '" + a.positional(0) + "'");
    return ShowMetrics{true};
  };
  // clang-format off
  return {
      single("status", fixed("table of agents", Status{}),
             "  One row per agent heard: id, alive/DEAD/left, last seen, position, epoch followed,\n"
             "  its shape error and how many neighbours it hears.\n"),
      single("show", fixed("the command in force and its epoch", Show{}),
             "  The command in force: shape, tracking, law, gains, integrator, speed limit and safety\n"
             "  settings ('safety' alone), its epoch and who published it (this supervisor, or another\n"
             "  participant when the agents follow an epoch this supervisor did not publish), and how many\n"
             "  agents follow it.\n"),
      single("metrics", form("", {"", "json"}, {}, "latest formation metrics", metrics),
             "  Prints the latest metrics (shape error, gap CV, clusters, ...) as a table, 4 significant\n"
             "  digits, with units; `metrics json` prints them as one JSON object. With --json both print\n"
             "  the JSON object (and the metrics event on stdout).\n"),
  };
  // clang-format on
}

Action parse_progress(const Args& a, const CompiledCommand&) {
  const std::string mode = a.positionals() > 0 ? a.positional(0) : "";
  if ((mode == "on" || mode == "off") && a.positionals() == 1)
    return Progress{mode == "on" ? Progress::Mode::OnChange : Progress::Mode::Off, 0.0};
  if (mode == "every") {
    if (a.positionals() < 2) fail("progress every: missing interval S (wall seconds)");
    return Progress{Progress::Mode::Every, a.check_number("S", a.positional(1), params::above(0))};
  }
  fail("progress: expected on, off or every S");
}

CommandSpec progress_command() {
  // clang-format off
  return single("progress", form("", {"on", "off", "every S"}, {}, "when to print the progress line", parse_progress),
                "  The progress line (model time, agents, shape error, gap CV, ...). on (the default): printed\n"
                "  when something changed: the number of agents alive or following, the epoch, the converged\n"
                "  flag, the cluster count, or a metric by more than 10% of its last printed value (changes\n"
                "  smaller than 0.001 ignored); at most once a second. every S: every S wall seconds (> 0).\n"
                "  off: never. At a terminal it is printed above the line being typed.\n");
  // clang-format on
}

// ---------------------------------------------------------------------------------------------
// Blocking input: wait, sleep

/// Timeouts, durations and model times: >= 0.
constexpr params::Range kNonNegative = params::at_least(0);

Action wait_agents(const Args& a, const CompiledCommand&) {
  if (a.positionals() == 0) fail(a.name() + ": missing agent count N");
  const std::string& text = a.positional(0);
  const double n = a.check_number("N", text, params::any());
  if (!(n >= 1.0) || n != std::floor(n) || n > static_cast<double>(INT_MAX)) {
    fail(a.name() + ": N must be an integer >= 1, got " + text);
  }
  return WaitAgents{static_cast<int>(n), a.number_or("timeout", WaitAgents{}.timeout_s)};
}

Action wait_time(const Args& a, const CompiledCommand&) {
  if (a.positionals() == 0) fail(a.name() + ": missing model time T");
  const double when = a.check_number("T", a.positional(0), kNonNegative);
  return WaitTime{when, a.number_or("timeout", WaitTime{}.timeout_s)};
}

CommandSpec wait_command() {
  const ParamSpec timeout = opt_own("timeout", "S", kNonNegative, "s");
  CommandSpec c;
  c.word = "wait";
  c.noun = "condition";
  c.expected = "converged, agents or time";
  c.forms = {
      form("converged", {""}, {timeout}, "wait for convergence (S wall seconds)",
           [](const Args& a, const CompiledCommand&) -> Action {
             return WaitConverged{a.number_or("timeout", WaitConverged{}.timeout_s)};
           }),
      form("agents", {"N"}, {timeout}, "wait for N agents hearing each other", wait_agents),
      form("time", {"T"}, {timeout}, "wait for model time T (not seconds)", wait_time),
  };
  // clang-format off
  c.details =
      "  Holds further input until the condition holds or the timeout (wall seconds, >= 0;\n"
      "  default 60 for converged, 30 for agents, 600 for time) runs out. N is an integer >= 1;\n"
      "  T is model time since the current command was published (one paper iteration = dt),\n"
      "  counted by the agents: it holds until every agent on the command has reached T.\n"
      "  At a terminal, Ctrl-C cancels the wait.\n";
  // clang-format on
  return c;
}

CommandSpec sleep_command() {
  const auto parse = [](const Args& a, const CompiledCommand&) -> Action {
    if (a.positionals() == 0) fail("sleep: missing duration (seconds)");
    return Sleep{a.check_number("", a.positional(0), kNonNegative)};
  };
  // clang-format off
  return single("sleep", form("", {"S"}, {}, "pause input for S wall seconds", parse),
                "  Holds further input for S wall-clock seconds (>= 0). At a terminal, Ctrl-C cancels it.\n");
  // clang-format on
}

// ---------------------------------------------------------------------------------------------
// record, help, quit

CommandSpec record_command() {
  const auto start = [](const Args& a, const CompiledCommand&) -> Action {
    if (a.positionals() == 0 || a.positional(0).empty()) fail(a.name() + ": missing directory");
    return RecordStart{a.positional(0)};
  };
  CommandSpec c;
  c.word = "record";
  c.noun = "action";
  c.expected = "start DIR or stop";
  c.forms = {
      form("start", {"DIR"}, {}, "CSV recording", start),
      form("stop", {""}, {}, "", [](const Args&, const CompiledCommand&) -> Action { return RecordStop{}; }),
  };
  // clang-format off
  c.details =
      "  Writes DIR/metrics.csv, positions.csv, commands.csv and centre.csv (docs/RECORDING.md;\n"
      "  DIR is created; files are overwritten).\n"
      "  Quote DIR if it contains spaces. record stop closes the files (or says nothing is recording).\n";
  // clang-format on
  return c;
}

CommandSpec help_command() {
  const auto parse = [](const Args& a, const CompiledCommand&) -> Action {
    if (a.positionals() == 0) return Help{};
    const std::string& topic = a.positional(0);
    if (find_command(topic) == nullptr) fail("help: unknown command '" + topic + "'");
    return Help{topic};
  };
  // clang-format off
  CommandSpec c = single("help", form("", {"[COMMAND]"}, {}, "this list, or details", parse),
                         "  Without COMMAND, one line per command; with it, the details of that command.\n");
  // clang-format on
  c.offers_commands = true;
  return c;
}

CommandSpec quit_command() {
  // clang-format off
  CommandSpec c = single(
      "quit", fixed("stop the supervisor", Quit{}),
      "  Stops the supervisor (exit status 0, or 3 after a wait timed out). At a terminal, Ctrl-D on\n"
      "  an empty line does the same; Ctrl-C clears the line being typed or cancels a wait, and a\n"
      "  second Ctrl-C within 1 s on an empty line stops the supervisor with exit status 130.\n");
  // clang-format on
  c.aliases = {"exit"};
  return c;
}

/// The words of a usage: "on|off|every S" -> {"on|off|every", "S"}.
std::vector<std::string> usage_words(const std::string& usage) {
  std::istringstream in(usage);
  std::vector<std::string> out;
  for (std::string w; in >> w;) out.push_back(w);
  return out;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// The registry

const std::vector<CommandSpec>& command_specs() {
  static const std::vector<CommandSpec> table = [] {
    std::vector<CommandSpec> t = {shape_command(),      track_command(),     gains_command(),
                                  integrator_command(), max_speed_command(), law_command(),
                                  safety_command(),     start_command()};
    for (auto* group : {hold_commands, question_commands})
      for (CommandSpec& c : group()) t.push_back(std::move(c));
    for (auto* make :
         {progress_command, wait_command, sleep_command, record_command, help_command, quit_command})
      t.push_back(make());
    return t;
  }();
  return table;
}

const CommandSpec* find_command(std::string_view word) {
  for (const CommandSpec& c : command_specs()) {
    if (c.word == word) return &c;
    for (const std::string& alias : c.aliases)
      if (alias == word) return &c;
  }
  return nullptr;
}

std::size_t FormSpec::max_positionals() const {
  std::size_t n = 0;
  for (const std::string& u : usages) n = std::max(n, usage_words(u).size());
  return n;
}

std::vector<std::string> FormSpec::values() const {
  std::vector<std::string> out;
  for (const std::string& u : usages) {
    const std::vector<std::string> words = usage_words(u);
    if (words.empty()) continue;
    std::string first = words.front();  // "[json]", "on|off|every", "euler|rk4", "N"
    first.erase(std::remove_if(first.begin(), first.end(), [](char ch) { return ch == '[' || ch == ']'; }),
                first.end());
    std::istringstream alternatives(first);
    for (std::string v; std::getline(alternatives, v, '|');)
      if (!v.empty() && std::islower(static_cast<unsigned char>(v.front()))) out.push_back(v);
  }
  return out;
}

const FormSpec* CommandSpec::form(std::string_view sub) const {
  for (const FormSpec& f : forms)
    if (f.sub == sub) return &f;
  return nullptr;
}

std::string CommandSpec::words(const FormSpec& f) const { return f.sub.empty() ? word : word + " " + f.sub; }

std::vector<ParamSpec> CommandSpec::params(const FormSpec& f) const {
  std::vector<ParamSpec> all = f.params;
  all.insert(all.end(), shared.begin(), shared.end());
  return all;
}

}  // namespace shapeform::supervisor
