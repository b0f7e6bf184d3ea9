#include "console_parser.hpp"
#include "console_commands.hpp"

#include <catch2/catch.hpp>
#include <algorithm>
#include <vector>

#include "core/enum_names.hpp"
#include "core/params.hpp"

#include "shapes/shapes.hpp"
#include <sstream>
#include <string>
#include <variant>

using namespace shapeform;
using namespace shapeform::supervisor;

namespace {

/// A current command that differs from the defaults everywhere, so "unchanged" is observable.
core::CompiledCommand current_command() {
  core::Command c;
  c.shape.kind = core::ShapeKind::Ellipse;
  c.shape.a = 7.0;
  c.shape.b = 3.0;
  c.shape.centre = core::Vec2(1.5, -2.5);
  c.tracking.enabled = true;
  c.tracking.path.kind = core::CentrePath::Kind::Line;
  c.tracking.path.velocity = core::Vec2(0.1, 0.0);
  c.tracking.feedforward = true;
  c.gains = core::Gains{0.3, 1.5, 2.5, 1.1, 0.05};
  c.integrator = core::Integrator::RK4;
  c.dt = 0.5;
  c.max_speed = 2.0;
  return core::compile(c);
}

template <class T>
T parse_as(std::string_view line, const core::CompiledCommand& cur = current_command()) {
  const ParseResult r = parse_command(line, cur);
  INFO("line: " << line << "\nerror: " << r.error);
  REQUIRE(r.ok());
  REQUIRE(std::holds_alternative<T>(r.action));
  return std::get<T>(r.action);
}

core::CompiledCommand set_command(std::string_view line, SetCommand::What what) {
  const SetCommand s = parse_as<SetCommand>(line);
  CHECK(s.what == what);
  return s.command;
}

std::string error_of(std::string_view line) {
  const ParseResult r = parse_command(line, current_command());
  INFO("line: " << line);
  REQUIRE_FALSE(r.ok());
  CHECK(std::holds_alternative<NoOp>(r.action));
  CHECK(r.error.find('\n') == std::string::npos);
  return r.error;
}

void check_gains_equal(const core::Gains& a, const core::Gains& b) {
  CHECK(a.k1 == b.k1);
  CHECK(a.k2 == b.k2);
  CHECK(a.sigma == b.sigma);
  CHECK(a.beta == b.beta);
  CHECK(a.r == b.r);
}

/// Everything but the shape and tracking equals the current command.
void check_rest_unchanged(const core::CompiledCommand& c) {
  const core::CompiledCommand cur = current_command();
  check_gains_equal(c.gains, cur.gains);
  CHECK(c.integrator == cur.integrator);
  CHECK(c.dt == cur.dt);
  CHECK(c.max_speed == cur.max_speed);
}

/// Shape and tracking equal the current command.
void check_shape_unchanged(const core::CompiledCommand& c) {
  const core::CompiledCommand cur = current_command();
  CHECK(c.shape.kind == cur.shape.kind);
  CHECK(c.shape.a == cur.shape.a);
  CHECK(c.shape.b == cur.shape.b);
  CHECK(c.shape.centre == cur.shape.centre);
  CHECK(c.tracking.enabled == cur.tracking.enabled);
  CHECK(c.tracking.feedforward == cur.tracking.feedforward);
}

/// True when the command's curve is the one its shape compiles to (not a default or stale curve).
bool compiled_from_shape(const core::CompiledCommand& c) {
  const auto fresh = shapeform::shapes::compile_curve(c.shape);
  return fresh->closed() == c.curve().closed() && fresh->length() == c.curve().length();
}

}  // namespace

TEST_CASE("blank lines and comments are no-ops", "[supervisor][parser]") {
  for (const char* line : {"", "   ", "\t", "# comment", "   # shape circle r=-1", "#"}) {
    parse_as<NoOp>(line);
  }
}

TEST_CASE("a token starting with # ends the line", "[supervisor][parser]") {
  const core::CompiledCommand c = set_command("shape circle r=2 # r=-1 junk", SetCommand::What::Shape);
  CHECK(c.shape.r0 == 2.0);
}

TEST_CASE("shape line", "[supervisor][parser]") {
  const core::CompiledCommand c = set_command("shape line m=2 c=-1.5", SetCommand::What::Shape);
  CHECK(c.shape.kind == core::ShapeKind::Line);
  CHECK(c.shape.m == 2.0);
  CHECK(c.shape.c == -1.5);
  CHECK_FALSE(c.tracking.enabled);
  CHECK_FALSE(c.tracking.feedforward);
  check_rest_unchanged(c);
}

TEST_CASE("shape circle with and without centre", "[supervisor][parser]") {
  const core::CompiledCommand c = set_command("shape circle r=3", SetCommand::What::Shape);
  CHECK(c.shape.kind == core::ShapeKind::Circle);
  CHECK(c.shape.r0 == 3.0);
  CHECK(c.shape.centre == core::Vec2(0.0, 0.0));  // default 0, not the current centre
  CHECK_FALSE(c.tracking.enabled);
  check_rest_unchanged(c);

  const core::CompiledCommand d = set_command("shape circle cy=-4 r=0.5 cx=2", SetCommand::What::Shape);
  CHECK(d.shape.r0 == 0.5);
  CHECK(d.shape.centre == core::Vec2(2.0, -4.0));
  const core::CompiledCommand e = set_command("shape circle r=1 cx=3", SetCommand::What::Shape);
  CHECK(e.shape.centre == core::Vec2(3.0, 0.0));
}

TEST_CASE("shape ellipse and square", "[supervisor][parser]") {
  const core::CompiledCommand e = set_command("shape ellipse b=2 a=5 cx=1 cy=1", SetCommand::What::Shape);
  CHECK(e.shape.kind == core::ShapeKind::Ellipse);
  CHECK(e.shape.a == 5.0);
  CHECK(e.shape.b == 2.0);
  CHECK(e.shape.centre == core::Vec2(1.0, 1.0));
  CHECK_FALSE(e.tracking.enabled);
  check_rest_unchanged(e);

  const core::CompiledCommand s = set_command("shape square a=4.5", SetCommand::What::Shape);
  CHECK(s.shape.kind == core::ShapeKind::Square);
  CHECK(s.shape.a == 4.5);
  CHECK(s.shape.centre == core::Vec2(0.0, 0.0));
  check_rest_unchanged(s);
}

TEST_CASE("shape polar", "[supervisor][parser]") {
  const core::CompiledCommand c =
      set_command("shape polar r=\"4 + cos(5*phi)\" cx=1 cy=-1", SetCommand::What::Shape);
  CHECK(c.shape.kind == core::ShapeKind::Polar);
  CHECK(c.shape.r_expr == "4 + cos(5*phi)");
  CHECK(c.shape.centre == core::Vec2(1.0, -1.0));
  CHECK(c.shape.rotation == 0.0);
  CHECK(c.shape.scale == 1.0);
  CHECK_FALSE(c.tracking.enabled);
  check_rest_unchanged(c);
  // Compiled by the parser: r(0) = 5 from the centre.
  REQUIRE(compiled_from_shape(c));
  const core::Vec2 tip = core::target_point(c.shape, c.curve(), core::Vec2(21.0, -1.0));
  CHECK(tip.x() == Approx(6.0).epsilon(1e-6));
  CHECK(tip.y() == Approx(-1.0).epsilon(1e-9));
  // Unquoted (no spaces) works as well.
  CHECK(set_command("shape polar r=4+cos(5*phi)", SetCommand::What::Shape).shape.r_expr ==
        "4+cos(5*phi)");
}

TEST_CASE("shape parametric", "[supervisor][parser]") {
  const core::CompiledCommand c = set_command(
      "shape parametric x=\"4*cos(2*pi*s)\" y=\"2*sin(2*pi*s)\"", SetCommand::What::Shape);
  CHECK(c.shape.kind == core::ShapeKind::Parametric);
  CHECK(c.shape.x_expr == "4*cos(2*pi*s)");
  CHECK(c.shape.y_expr == "2*sin(2*pi*s)");
  CHECK(c.shape.closed);  // default on
  CHECK(c.shape.centre == core::Vec2(0.0, 0.0));
  REQUIRE(compiled_from_shape(c));
  CHECK(c.curve().closed());
  check_rest_unchanged(c);

  const core::CompiledCommand open = set_command(
      "shape parametric x=\"8*s - 4\" y=0 closed=off cx=2 cy=3", SetCommand::What::Shape);
  CHECK_FALSE(open.shape.closed);
  CHECK(open.shape.centre == core::Vec2(2.0, 3.0));
  REQUIRE(compiled_from_shape(open));
  CHECK_FALSE(open.curve().closed());
  CHECK(open.curve().length() == Approx(8.0).epsilon(1e-9));
}

TEST_CASE("shape implicit", "[supervisor][parser]") {
  const core::CompiledCommand c =
      set_command("shape implicit f=\"x^2/16 + y^2/4 - 1\" cy=2", SetCommand::What::Shape);
  CHECK(c.shape.kind == core::ShapeKind::Implicit);
  CHECK(c.shape.f_expr == "x^2/16 + y^2/4 - 1");
  CHECK(c.shape.centre == core::Vec2(0.0, 2.0));
  REQUIRE(compiled_from_shape(c));
  const core::Vec2 p = core::target_point(c.shape, c.curve(), core::Vec2(9.0, 2.0));
  CHECK(p.x() == Approx(4.0).epsilon(1e-6));
  CHECK(p.y() == Approx(2.0).epsilon(1e-6));
  check_rest_unchanged(c);
}

TEST_CASE("shape polygon", "[supervisor][parser]") {
  const core::CompiledCommand c = set_command("shape polygon points=\"-4,-3; 4,-3; 4,2; 0,5; -4,2\"",
                                      SetCommand::What::Shape);
  CHECK(c.shape.kind == core::ShapeKind::Polygon);
  CHECK(c.shape.vertices == std::vector<core::Vec2>{core::Vec2(-4, -3), core::Vec2(4, -3),
                                                    core::Vec2(4, 2), core::Vec2(0, 5),
                                                    core::Vec2(-4, 2)});
  CHECK(c.shape.closed);
  REQUIRE(compiled_from_shape(c));
  CHECK(c.curve().length() == Approx(8 + 5 + 5 + 5 + 5));
  check_rest_unchanged(c);

  const core::CompiledCommand open =
      set_command("shape polygon points=0,0;4,0;4,4 closed=off cx=1", SetCommand::What::Shape);
  CHECK_FALSE(open.shape.closed);
  CHECK(open.shape.vertices.size() == 3u);
  CHECK(open.shape.centre == core::Vec2(1.0, 0.0));
  REQUIRE(compiled_from_shape(open));
  CHECK(open.curve().length() == Approx(8.0));
  // Two points make an open polygon (a segment).
  CHECK(set_command("shape polygon points=0,0;1,0 closed=off", SetCommand::What::Shape)
            .shape.vertices.size() == 2u);
}

TEST_CASE("every shape takes rot (degrees) and scale", "[supervisor][parser]") {
  constexpr double kPi = 3.14159265358979323846;
  for (const std::string base : {"shape line m=1 c=0", "shape circle r=2", "shape ellipse a=3 b=1",
                                 "shape square a=1", "shape polar r=2",
                                 "shape parametric x=cos(2*pi*s) y=sin(2*pi*s)",
                                 "shape implicit f=x^2+y^2-1", "shape polygon points=0,0;1,0;0,1"}) {
    INFO(base);
    const core::CompiledCommand c = set_command(base + " rot=90 scale=2.5", SetCommand::What::Shape);
    CHECK(c.shape.rotation == Approx(kPi / 2));
    CHECK(c.shape.rotation == 90.0 * (kPi / 180.0));  // the config loader's conversion, bit for bit
    CHECK(c.shape.scale == 2.5);
    CHECK(compiled_from_shape(c));
    const core::CompiledCommand d = set_command(base, SetCommand::What::Shape);
    CHECK(d.shape.rotation == 0.0);  // defaults, not the current shape's
    CHECK(d.shape.scale == 1.0);
  }
  // The placement acts: an ellipse a=3 b=1 rotated by 90 degrees and doubled has its long axis on x2.
  const core::CompiledCommand e =
      set_command("shape ellipse a=3 b=1 rot=90 scale=2 cx=1", SetCommand::What::Shape);
  const core::Vec2 top = core::target_point(e.shape, e.curve(), core::Vec2(1.0, 20.0));
  CHECK(top.x() == Approx(1.0).margin(1e-9));
  CHECK(top.y() == Approx(6.0).epsilon(1e-9));
  CHECK(set_command("shape circle r=1 rot=-720.5", SetCommand::What::Shape).shape.rotation ==
        Approx(-720.5 * kPi / 180.0));
}

TEST_CASE("a new shape keeps nothing of the previous one", "[supervisor][parser]") {
  core::CompiledCommand cur = current_command();
  cur.shape.kind = core::ShapeKind::Polar;
  cur.shape.r_expr = "3";
  cur.shape.rotation = 1.0;
  cur.shape.scale = 3.0;
  cur.shape.vertices = {core::Vec2(1, 1)};
  const ParseResult r = parse_command("shape circle r=2", cur);
  REQUIRE(r.ok());
  const core::ShapeSpec& s = std::get<SetCommand>(r.action).command.shape;
  CHECK(s.kind == core::ShapeKind::Circle);
  CHECK(s.r_expr.empty());
  CHECK(s.vertices.empty());
  CHECK(s.rotation == 0.0);
  CHECK(s.scale == 1.0);
  const core::CompiledCommand& sc = std::get<SetCommand>(r.action).command;
  REQUIRE(compiled_from_shape(sc));
  CHECK(sc.curve().length() == Approx(2 * 3.14159265358979323846 * 2));
  // Tracking draws a plain circle too, freshly compiled.
  const ParseResult t = parse_command("track point at=0,0 r=1", cur);
  REQUIRE(t.ok());
  const core::ShapeSpec& ts = std::get<SetCommand>(t.action).command.shape;
  CHECK(ts.kind == core::ShapeKind::Circle);
  CHECK(ts.scale == 1.0);
  CHECK(ts.rotation == 0.0);
  const core::CompiledCommand& tc = std::get<SetCommand>(t.action).command;
  REQUIRE(compiled_from_shape(tc));
  CHECK(tc.curve().length() == Approx(2 * 3.14159265358979323846));
}

TEST_CASE("errors: shapes that do not compile", "[supervisor][parser]") {
  CHECK(error_of("shape polar r=\"4+foo\"") ==
        "shape polar: r(phi) = '4+foo': Unexpected token \"foo\" found at position 2.");
  const std::string unknown = error_of("shape polar r=\"4 + cos(5*theta)\"");
  CHECK(unknown.rfind("shape polar: r(phi) = '4 + cos(5*theta)': ", 0) == 0);
  CHECK(unknown.find("\"theta\"") != std::string::npos);
  CHECK(error_of("shape polar r=\"\"") == "shape polar: r(phi): empty expression");
  CHECK(error_of("shape polar r=\"1 + 2*cos(phi)\"")
            .rfind("shape polar: r(phi) must be finite and > 0 for every phi, got r(", 0) == 0);
  CHECK(error_of("shape parametric x=\"cos(2*pi*s)\" y=\"sin(2*pi*t)\"")
            .rfind("shape parametric: y(s) = 'sin(2*pi*t)': ", 0) == 0);
  CHECK(error_of("shape parametric x=\"1\" y=\"2\"") ==
        "shape parametric: curve has fewer than 2 distinct points");
  CHECK(error_of("shape implicit f=\"x^2+y^2+1\"") ==
        "shape implicit: implicit curve: f(x, y) = 0 has no real points in the box "
        "(f = 'x^2+y^2+1', box [-20, 20]^2 around the centre)");
  CHECK(error_of("shape implicit f=\"x^2+y^2-z\"")
            .rfind("shape implicit: f(x, y) = 'x^2+y^2-z': ", 0) == 0);
  CHECK(error_of("shape polygon points=\"0,0;1,0\"") ==
        "shape polygon: a closed polygon needs at least 3 vertices, got 2");
  CHECK(error_of("shape polygon points=\"0,0;1,0;1,0;0,1\"") ==
        "shape polygon: vertices 1 and 2 coincide (zero-length edge)");
  CHECK(error_of("shape polygon points=\"0,0;1,1;2,2\"") ==
        "shape polygon: the vertices are collinear (zero area)");
  CHECK(error_of("shape polygon points=\"\"") ==
        "shape polygon: a closed polygon needs at least 3 vertices, got 0");
}

TEST_CASE("errors: polygon points, closed, rot and scale", "[supervisor][parser]") {
  CHECK(error_of("shape polygon closed=on") == "shape polygon: missing parameter points");
  CHECK(error_of("shape polar cx=1") == "shape polar: missing parameter r");
  CHECK(error_of("shape parametric x=s") == "shape parametric: missing parameter y");
  CHECK(error_of("shape parametric y=s") == "shape parametric: missing parameter x");
  CHECK(error_of("shape implicit") == "shape implicit: missing parameter f");
  CHECK(error_of("shape polygon points=0,0;1") ==
        "shape polygon: points: point 2 must be x,y, got '1'");
  CHECK(error_of("shape polygon points=0,0;1,2,3") ==
        "shape polygon: points: point 2 must be x,y, got '1,2,3'");
  CHECK(error_of("shape polygon points=0,0;;1,1") ==
        "shape polygon: points: point 2 must be x,y, got ''");
  CHECK(error_of("shape polygon points=0,0;1,1;") ==
        "shape polygon: points: point 3 must be x,y, got ''");
  CHECK(error_of("shape polygon points=a,0;1,1;0,1") ==
        "shape polygon: points: point 1: not a number: 'a,0'");
  CHECK(error_of("shape polygon points=0,0;1,inf;0,1") ==
        "shape polygon: points: point 2 must be finite, got 1,inf");
  CHECK(error_of("shape polygon points=0,0;1,0;0,1 closed=yes") ==
        "shape polygon: closed must be on or off, got 'yes'");
  CHECK(error_of("shape parametric x=s y=s closed=1") ==
        "shape parametric: closed must be on or off, got '1'");
  CHECK(error_of("shape circle r=1 scale=0") == "shape circle: scale must be > 0, got 0");
  CHECK(error_of("shape circle r=1 scale=-2") == "shape circle: scale must be > 0, got -2");
  CHECK(error_of("shape polar r=4 scale=inf") == "shape polar: scale must be finite, got inf");
  CHECK(error_of("shape square a=1 rot=nan") == "shape square: rot must be finite, got nan");
  CHECK(error_of("shape square a=1 rot=ninety") == "shape square: rot: not a number: 'ninety'");
}

TEST_CASE("law: paper and arc, the shape kept", "[supervisor][parser]") {
  const core::CompiledCommand a = set_command("law arc", SetCommand::What::Law);
  CHECK(a.law == core::Law::Arc);
  const core::ArcParams defaults;
  CHECK(a.arc.k_normal == defaults.k_normal);  // not given: the current values
  CHECK(a.arc.k_tangent == defaults.k_tangent);
  CHECK(a.arc.spacing == defaults.spacing);
  check_shape_unchanged(a);
  check_rest_unchanged(a);

  const core::CompiledCommand b =
      set_command("law arc spacing=2 k_tangent=0.5 k_normal=1", SetCommand::What::Law);
  CHECK(b.law == core::Law::Arc);
  CHECK(b.arc.k_normal == 1.0);
  CHECK(b.arc.k_tangent == 0.5);
  CHECK(b.arc.spacing == 2.0);
  check_shape_unchanged(b);

  core::CompiledCommand cur = current_command();
  cur.law = core::Law::Arc;
  cur.arc = {0.25, 0.75, 3.0};
  const ParseResult r = parse_command("law arc k_normal=2", cur);
  REQUIRE(r.ok());
  const core::CompiledCommand c = std::get<SetCommand>(r.action).command;
  CHECK(c.arc.k_normal == 2.0);
  CHECK(c.arc.k_tangent == 0.75);
  CHECK(c.arc.spacing == 3.0);
  CHECK(&c.curve() == &cur.curve());  // the very same compiled shape
  const ParseResult p = parse_command("law paper", cur);
  REQUIRE(p.ok());
  const core::CompiledCommand d = std::get<SetCommand>(p.action).command;
  CHECK(d.law == core::Law::Paper);
  CHECK(d.arc.k_normal == 0.25);  // kept for a later `law arc`
  CHECK(&d.curve() == &cur.curve());
  CHECK(std::get<SetCommand>(p.action).what == SetCommand::What::Law);

  CHECK(set_command("law arc k_normal=10 k_tangent=1", SetCommand::What::Law).arc.k_normal == 10.0);
}

TEST_CASE("errors: law", "[supervisor][parser]") {
  CHECK(error_of("law arc k_normal=0") == "law: k_normal must be > 0, got 0");
  CHECK(error_of("law arc k_normal=10.5") == "law: k_normal must be <= 10, got 10.5");
  CHECK(error_of("law arc k_tangent=0") == "law: k_tangent must be > 0, got 0");
  CHECK(error_of("law arc k_tangent=1.5") == "law: k_tangent must be <= 1, got 1.5");
  CHECK(error_of("law arc spacing=-1") == "law: spacing must be > 0, got -1");
  CHECK(error_of("law arc spacing=nan") == "law: spacing must be finite, got nan");
  CHECK(error_of("law arc k_normal=fast") == "law: k_normal: not a number: 'fast'");
  CHECK(error_of("law paper spacing=2") == "law paper: spacing is a parameter of the arc law");
  CHECK(error_of("law paper k_normal=1") == "law paper: k_normal is a parameter of the arc law");
}

TEST_CASE("numbers: exponents, signs, hex; whitespace and quotes", "[supervisor][parser]") {
  CHECK(set_command("shape line m=-1e-3 c=+2.5E2", SetCommand::What::Shape).shape.m == -1e-3);
  CHECK(set_command("shape line m=0 c=+2.5E2", SetCommand::What::Shape).shape.c == 250.0);
  CHECK(set_command("shape circle r=0x10", SetCommand::What::Shape).shape.r0 == 16.0);
  CHECK(set_command("  shape \t circle   r=2  ", SetCommand::What::Shape).shape.r0 == 2.0);
  CHECK(set_command("shape circle r=\"3\"", SetCommand::What::Shape).shape.r0 == 3.0);
  // Underflow is a finite value (0 here), judged like any other.
  CHECK(set_command("shape line m=1e-400 c=0", SetCommand::What::Shape).shape.m == 0.0);
  CHECK(error_of("shape circle r=1e-400") == "shape circle: r must be > 0, got 1e-400");
}

TEST_CASE("track line", "[supervisor][parser]") {
  const core::CompiledCommand c =
      set_command("track line from=1,2 vel=0.5,-0.25 r=2 ff=on", SetCommand::What::Track);
  CHECK(c.shape.kind == core::ShapeKind::Circle);
  CHECK(c.shape.r0 == 2.0);
  CHECK(c.shape.centre == core::Vec2(1.0, 2.0));
  CHECK(c.tracking.enabled);
  CHECK(c.tracking.feedforward);
  CHECK(c.tracking.path.kind == core::CentrePath::Kind::Line);
  CHECK(c.tracking.path.point == core::Vec2(1.0, 2.0));
  CHECK(c.tracking.path.velocity == core::Vec2(0.5, -0.25));
  check_rest_unchanged(c);

  CHECK_FALSE(set_command("track line r=1 vel=0,0 from=0,0", SetCommand::What::Track)
                  .tracking.feedforward);  // ff defaults to off
  CHECK_FALSE(set_command("track line r=1 vel=0,0 from=0,0 ff=off", SetCommand::What::Track)
                  .tracking.feedforward);
}

TEST_CASE("track circle", "[supervisor][parser]") {
  const core::CompiledCommand c = set_command(
      "track circle radius=6 period=200 r=3 cx=1 cy=-1 phase=0.5 ff=on", SetCommand::What::Track);
  CHECK(c.shape.kind == core::ShapeKind::Circle);
  CHECK(c.shape.r0 == 3.0);
  CHECK(c.tracking.enabled);
  CHECK(c.tracking.feedforward);
  const core::CentrePath& p = c.tracking.path;
  CHECK(p.kind == core::CentrePath::Kind::Circle);
  CHECK(p.radius == 6.0);
  CHECK(p.period == 200.0);
  CHECK(p.origin == core::Vec2(1.0, -1.0));
  CHECK(p.phase == 0.5);
  // The shape starts at C(0) on the path.
  CHECK(c.shape.centre.x() == Approx(1.0 + 6.0 * std::cos(0.5)));
  CHECK(c.shape.centre.y() == Approx(-1.0 + 6.0 * std::sin(0.5)));
  check_rest_unchanged(c);

  const core::CompiledCommand d =
      set_command("track circle r=1 period=50 radius=2", SetCommand::What::Track);
  CHECK(d.tracking.path.origin == core::Vec2(0.0, 0.0));
  CHECK(d.tracking.path.phase == 0.0);
  CHECK_FALSE(d.tracking.feedforward);
  CHECK(d.shape.centre.x() == Approx(2.0));
  CHECK(d.shape.centre.y() == Approx(0.0).margin(1e-12));
}

TEST_CASE("track point and track stop", "[supervisor][parser]") {
  const core::CompiledCommand c = set_command("track point at=3,-4 r=1.5", SetCommand::What::Track);
  CHECK(c.shape.kind == core::ShapeKind::Circle);
  CHECK(c.shape.r0 == 1.5);
  CHECK(c.shape.centre == core::Vec2(3.0, -4.0));
  CHECK(c.tracking.enabled);
  CHECK_FALSE(c.tracking.feedforward);
  CHECK(c.tracking.path.kind == core::CentrePath::Kind::Fixed);
  CHECK(c.tracking.path.point == core::Vec2(3.0, -4.0));
  check_rest_unchanged(c);

  parse_as<TrackStop>("track stop");
}

TEST_CASE("gains: given ones change, others keep current values", "[supervisor][parser]") {
  const core::Gains cur = current_command().gains;
  const core::CompiledCommand a = set_command("gains k1=0.2", SetCommand::What::Gains);
  CHECK(a.gains.k1 == 0.2);
  CHECK(a.gains.k2 == cur.k2);
  CHECK(a.gains.sigma == cur.sigma);
  CHECK(a.gains.beta == cur.beta);
  CHECK(a.gains.r == cur.r);
  check_shape_unchanged(a);

  const core::CompiledCommand b =
      set_command("gains r=0 beta=0 sigma=1 k2=3 k1=0", SetCommand::What::Gains);
  check_gains_equal(b.gains, core::Gains{0.0, 3.0, 1.0, 0.0, 0.0});
  CHECK(b.integrator == core::Integrator::RK4);
  CHECK(b.max_speed == 2.0);
}

TEST_CASE("integrator and max_speed", "[supervisor][parser]") {
  const core::CompiledCommand a = set_command("integrator euler", SetCommand::What::Integrator);
  CHECK(a.integrator == core::Integrator::Euler);
  CHECK(a.dt == 0.5);  // kept
  check_shape_unchanged(a);
  const core::CompiledCommand b = set_command("integrator dt=0.25 rk4", SetCommand::What::Integrator);
  CHECK(b.integrator == core::Integrator::RK4);
  CHECK(b.dt == 0.25);
  CHECK(set_command("integrator euler dt=10", SetCommand::What::Integrator).dt == 10.0);

  const core::CompiledCommand c = set_command("max_speed 1.5", SetCommand::What::MaxSpeed);
  CHECK(c.max_speed == 1.5);
  check_shape_unchanged(c);
  CHECK(set_command("max_speed 0", SetCommand::What::MaxSpeed).max_speed == 0.0);
}

TEST_CASE("status, metrics, start, quit, exit", "[supervisor][parser]") {
  parse_as<Status>("status");
  CHECK_FALSE(parse_as<StartScenario>("start").replace);
  CHECK(parse_as<StartScenario>("start replace").replace);
  parse_as<ShowMetrics>("metrics");
  parse_as<Quit>("quit");
  parse_as<Quit>("exit");
}

TEST_CASE("wait converged and wait agents", "[supervisor][parser]") {
  CHECK(parse_as<WaitConverged>("wait converged").timeout_s == 60.0);
  CHECK(parse_as<WaitConverged>("wait converged timeout=5.5").timeout_s == 5.5);
  CHECK(parse_as<WaitConverged>("wait converged timeout=0").timeout_s == 0.0);
  const WaitAgents a = parse_as<WaitAgents>("wait agents 5");
  CHECK(a.count == 5);
  CHECK(a.timeout_s == 30.0);
  const WaitAgents b = parse_as<WaitAgents>("wait agents timeout=10 3");
  CHECK(b.count == 3);
  CHECK(b.timeout_s == 10.0);
  CHECK(parse_as<WaitAgents>("wait agents 1").count == 1);
  const WaitTime w = parse_as<WaitTime>("wait time 500 timeout=20");
  CHECK(w.model_time == 500.0);
  CHECK(w.timeout_s == 20.0);
  CHECK(parse_as<WaitTime>("wait time 5").timeout_s == 600.0);
  CHECK(error_of("wait time") == "wait time: missing model time T");
  CHECK(parse_as<WaitAgents>("wait agents 2.0").count == 2);
}

TEST_CASE("sleep, record, help", "[supervisor][parser]") {
  CHECK(parse_as<Sleep>("sleep 2.5").seconds == 2.5);
  CHECK(parse_as<Sleep>("sleep 0").seconds == 0.0);
  CHECK(parse_as<RecordStart>("record start out/run1").dir == "out/run1");
  CHECK(parse_as<RecordStart>("record start \"my runs/a b\"").dir == "my runs/a b");
  CHECK(parse_as<RecordStart>("record start \"a=b\"").dir == "a=b");
  parse_as<RecordStop>("record stop");
  CHECK(parse_as<Help>("help").topic.empty());
  CHECK(parse_as<Help>("help shape").topic == "shape");
  CHECK(parse_as<Help>("help exit").topic == "exit");
  CHECK(parse_as<Help>("help max_speed").topic == "max_speed");
}

TEST_CASE("quoted values keep spaces and '=' and are stripped", "[supervisor][parser]") {
  // A circle's r is a number: an expression is refused there (shape polar takes one).
  CHECK(error_of("shape circle r=\"4+cos(5*phi)\"") ==
        "shape circle: r: not a number: '4+cos(5*phi)'");
  CHECK(error_of("shape circle r=\"4 + 1\"") == "shape circle: r: not a number: '4 + 1'");
  CHECK(error_of("shape circle r=\"a=b\"") == "shape circle: r: not a number: 'a=b'");
  CHECK(error_of("shape circle r=\"2 # no comment\"") ==
        "shape circle: r: not a number: '2 # no comment'");
  CHECK(error_of("shape circle r=\"2") == "unterminated double quote");
  // A quoted '=' is text, not a key=value separator.
  CHECK(error_of("shape circle \"r=3\"") == "shape circle: unexpected argument 'r=3'");
}

TEST_CASE("errors: unknown command words", "[supervisor][parser]") {
  CHECK(error_of("shap circle r=1") == "unknown command 'shap' (try 'help')");
  CHECK(error_of("Shape circle r=1") == "unknown command 'Shape' (try 'help')");
  CHECK(error_of("r=1") == "unknown command 'r=1' (try 'help')");
  CHECK(error_of("shape") == "shape: expected a shape (line, circle, ellipse, square, polar, "
                              "parametric, implicit, polygon)");
  CHECK(error_of("shape r=1") == "shape: expected a shape (line, circle, ellipse, square, polar, "
                                 "parametric, implicit, polygon)");
  CHECK(error_of("shape hexagon a=1") ==
        "shape: unknown shape 'hexagon' (expected line, circle, ellipse, square, polar, "
        "parametric, implicit, polygon)");
  CHECK(error_of("law") == "law: missing law (paper or arc)");
  CHECK(error_of("law boids") == "law: unknown law 'boids' (expected paper or arc)");
  CHECK(error_of("law Arc") == "law: unknown law 'Arc' (expected paper or arc)");
  CHECK(error_of("track") == "track: expected line, circle, point or stop");
  CHECK(error_of("track spiral") ==
        "track: unknown path 'spiral' (expected line, circle, point, stop)");
  CHECK(error_of("wait") == "wait: expected converged, agents or time");
  CHECK(error_of("wait forever") ==
        "wait: unknown condition 'forever' (expected converged, agents, time)");
  CHECK(error_of("record") == "record: expected start DIR or stop");
  CHECK(error_of("record pause") == "record: unknown action 'pause' (expected start, stop)");
  CHECK(error_of("integrator rk5") == "integrator: unknown method 'rk5' (expected euler or rk4)");
  CHECK(error_of("help shap") == "help: unknown command 'shap'");
}

TEST_CASE("errors: missing parameters", "[supervisor][parser]") {
  CHECK(error_of("shape circle") == "shape circle: missing parameter r");
  CHECK(error_of("shape circle cx=1 cy=2") == "shape circle: missing parameter r");
  CHECK(error_of("shape line c=1") == "shape line: missing parameter m");
  CHECK(error_of("shape line m=1") == "shape line: missing parameter c");
  CHECK(error_of("shape ellipse a=1") == "shape ellipse: missing parameter b");
  CHECK(error_of("shape ellipse b=1") == "shape ellipse: missing parameter a");
  CHECK(error_of("shape square cx=1") == "shape square: missing parameter a");
  CHECK(error_of("track line vel=1,0 r=2") == "track line: missing parameter from");
  CHECK(error_of("track line from=1,0 r=2") == "track line: missing parameter vel");
  CHECK(error_of("track line from=1,0 vel=0,0") == "track line: missing parameter r");
  CHECK(error_of("track circle period=1 r=1") == "track circle: missing parameter radius");
  CHECK(error_of("track circle radius=1 r=1") == "track circle: missing parameter period");
  CHECK(error_of("track circle radius=1 period=1") == "track circle: missing parameter r");
  CHECK(error_of("track point r=1") == "track point: missing parameter at");
  CHECK(error_of("track point at=0,0") == "track point: missing parameter r");
  CHECK(error_of("gains") == "gains: expected at least one of k1, k2, sigma, beta, r");
  CHECK(error_of("integrator") == "integrator: missing method (euler or rk4)");
  CHECK(error_of("integrator dt=1") == "integrator: missing method (euler or rk4)");
  CHECK(error_of("max_speed") == "max_speed: missing value (units per model time, 0 = off)");
  CHECK(error_of("wait agents") == "wait agents: missing agent count N");
  CHECK(error_of("wait agents timeout=3") == "wait agents: missing agent count N");
  CHECK(error_of("sleep") == "sleep: missing duration (seconds)");
  CHECK(error_of("record start") == "record start: missing directory");
  CHECK(error_of("record start \"\"") == "record start: missing directory");
}

TEST_CASE("errors: unknown and duplicate parameters, stray arguments", "[supervisor][parser]") {
  CHECK(error_of("gains k3=1") ==
        "gains: unknown parameter 'k3' (expected k1, k2, sigma, beta, r)");
  CHECK(error_of("shape circle r=1 k=2") ==
        "shape circle: unknown parameter 'k' (expected r, cx, cy, rot, scale)");
  CHECK(error_of("shape line m=1 c=2 cx=0") ==
        "shape line: unknown parameter 'cx' (expected m, c, rot, scale)");
  CHECK(error_of("shape polar r=4 a=1") ==
        "shape polar: unknown parameter 'a' (expected r, cx, cy, rot, scale)");
  CHECK(error_of("shape parametric x=s y=s closed=on r=1") ==
        "shape parametric: unknown parameter 'r' (expected x, y, closed, cx, cy, rot, scale)");
  CHECK(error_of("shape implicit f=x closed=on") ==
        "shape implicit: unknown parameter 'closed' (expected f, cx, cy, rot, scale)");
  CHECK(error_of("shape polygon vertices=0,0;1,0;0,1") ==
        "shape polygon: unknown parameter 'vertices' (expected points, closed, cx, cy, rot, scale)");
  CHECK(error_of("law arc k1=1") ==
        "law: unknown parameter 'k1' (expected k_normal, k_tangent, spacing)");
  CHECK(error_of("law arc paper") == "law: unexpected argument 'paper'");
  CHECK(error_of("shape polar r=4 r=5") == "shape polar: duplicate parameter r");
  CHECK(error_of("track point at=0,0 r=1 vel=1,1") ==
        "track point: unknown parameter 'vel' (expected at, r, ff)");
  CHECK(error_of("wait converged t=1") ==
        "wait converged: unknown parameter 't' (expected timeout)");
  CHECK(error_of("status verbose=1") ==
        "status: unknown parameter 'verbose' (takes no key=value parameters)");
  CHECK(error_of("max_speed v=1") ==
        "max_speed: unknown parameter 'v' (takes no key=value parameters)");
  CHECK(error_of("track stop x=1") ==
        "track stop: unknown parameter 'x' (takes no key=value parameters)");

  CHECK(error_of("shape circle r=1 r=2") == "shape circle: duplicate parameter r");
  CHECK(error_of("gains k1=1 k2=1 k1=1") == "gains: duplicate parameter k1");
  CHECK(error_of("integrator rk4 dt=1 dt=2") == "integrator: duplicate parameter dt");

  CHECK(error_of("shape circle =5") == "shape circle: missing parameter name in '=5'");
  CHECK(error_of("shape circle 5") == "shape circle: unexpected argument '5'");
  CHECK(error_of("gains 0.1") == "gains: unexpected argument '0.1'");
  CHECK(error_of("integrator euler rk4") == "integrator: unexpected argument 'rk4'");
  CHECK(error_of("max_speed 1 2") == "max_speed: unexpected argument '2'");
  CHECK(error_of("wait agents 3 4") == "wait agents: unexpected argument '4'");
  CHECK(error_of("wait converged 10") == "wait converged: unexpected argument '10'");
  CHECK(error_of("sleep 1 2") == "sleep: unexpected argument '2'");
  CHECK(error_of("record start a b") == "record start: unexpected argument 'b'");
  CHECK(error_of("record stop now") == "record stop: unexpected argument 'now'");
  CHECK(error_of("track stop now") == "track stop: unexpected argument 'now'");
  CHECK(error_of("status now") == "status: unexpected argument 'now'");
  CHECK(error_of("metrics all") == "metrics: unexpected argument 'all'");
  CHECK(error_of("quit now") == "quit: unexpected argument 'now'");
  CHECK(error_of("start now") == "start: unexpected argument 'now' (expected replace)");
  CHECK(error_of("start replace now") == "start: unexpected argument 'now'");
  CHECK(error_of("start shape=circle") ==
        "start: unknown parameter 'shape' (takes no key=value parameters)");
  CHECK(error_of("exit 0") == "exit: unexpected argument '0'");
  CHECK(error_of("help shape circle") == "help: unexpected argument 'circle'");
}

TEST_CASE("errors: not a number", "[supervisor][parser]") {
  CHECK(error_of("shape circle r=abc") == "shape circle: r: not a number: 'abc'");
  CHECK(error_of("shape circle r=") == "shape circle: r: not a number: ''");
  CHECK(error_of("shape circle r=2x") == "shape circle: r: not a number: '2x'");
  CHECK(error_of("shape circle r=\" 2\"") == "shape circle: r: not a number: ' 2'");
  CHECK(error_of("shape circle r=1 cx=1,2") == "shape circle: cx: not a number: '1,2'");
  CHECK(error_of("gains sigma=1..2") == "gains: sigma: not a number: '1..2'");
  CHECK(error_of("integrator euler dt=fast") == "integrator: dt: not a number: 'fast'");
  CHECK(error_of("max_speed fast") == "max_speed: not a number: 'fast'");
  CHECK(error_of("sleep soon") == "sleep: not a number: 'soon'");
  CHECK(error_of("wait agents x") == "wait agents: N: not a number: 'x'");
  CHECK(error_of("wait converged timeout=1m") == "wait converged: timeout: not a number: '1m'");
  CHECK(error_of("track line from=a,2 vel=0,0 r=1") == "track line: from: not a number: 'a,2'");
  CHECK(error_of("track line from=1, vel=0,0 r=1") == "track line: from: not a number: '1,'");
  CHECK(error_of("track line from=1,2 vel=0,0 r=1 ff=maybe") ==
        "track line: ff must be on or off, got 'maybe'");
  CHECK(error_of("track point at=1,2 r=1 ff=ON") == "track point: ff must be on or off, got 'ON'");
  CHECK(error_of("track line from=1 vel=0,0 r=1") == "track line: from must be x,y, got '1'");
  CHECK(error_of("track line from=1,2,3 vel=0,0 r=1") ==
        "track line: from must be x,y, got '1,2,3'");
  CHECK(error_of("track point at= r=1") == "track point: at must be x,y, got ''");
}

TEST_CASE("errors: non-finite numbers", "[supervisor][parser]") {
  CHECK(error_of("shape circle r=nan") == "shape circle: r must be finite, got nan");
  CHECK(error_of("shape circle r=inf") == "shape circle: r must be finite, got inf");
  CHECK(error_of("shape circle r=1e999") == "shape circle: r must be finite, got 1e999");
  CHECK(error_of("shape circle r=1 cx=-inf") == "shape circle: cx must be finite, got -inf");
  CHECK(error_of("shape line m=NaN c=0") == "shape line: m must be finite, got NaN");
  CHECK(error_of("shape line m=0 c=infinity") == "shape line: c must be finite, got infinity");
  CHECK(error_of("gains k1=inf") == "gains: k1 must be finite, got inf");
  CHECK(error_of("track circle radius=1 period=1 r=1 phase=nan") ==
        "track circle: phase must be finite, got nan");
  CHECK(error_of("track line from=inf,0 vel=0,0 r=1") ==
        "track line: from must be finite, got inf,0");
  CHECK(error_of("track point at=0,nan r=1") == "track point: at must be finite, got 0,nan");
  CHECK(error_of("max_speed inf") == "max_speed must be finite, got inf");
  CHECK(error_of("sleep nan") == "sleep must be finite, got nan");
  CHECK(error_of("wait agents inf") == "wait agents: N must be finite, got inf");
  CHECK(error_of("wait converged timeout=inf") ==
        "wait converged: timeout must be finite, got inf");
  CHECK(error_of("integrator rk4 dt=nan") == "integrator: dt must be finite, got nan");
}

TEST_CASE("errors: out of range", "[supervisor][parser]") {
  CHECK(error_of("shape circle r=-2") == "shape circle: r must be > 0, got -2");
  CHECK(error_of("shape circle r=0") == "shape circle: r must be > 0, got 0");
  CHECK(error_of("shape circle r=-0") == "shape circle: r must be > 0, got -0");
  CHECK(error_of("shape ellipse a=0 b=1") == "shape ellipse: a must be > 0, got 0");
  CHECK(error_of("shape ellipse a=1 b=-1") == "shape ellipse: b must be > 0, got -1");
  CHECK(error_of("shape square a=-0.5") == "shape square: a must be > 0, got -0.5");
  CHECK(error_of("track line from=0,0 vel=0,0 r=0") == "track line: r must be > 0, got 0");
  CHECK(error_of("track circle radius=0 period=1 r=1") ==
        "track circle: radius must be > 0, got 0");
  CHECK(error_of("track circle radius=1 period=-5 r=1") ==
        "track circle: period must be > 0, got -5");
  CHECK(error_of("track point at=0,0 r=-1") == "track point: r must be > 0, got -1");
  CHECK(error_of("gains k1=-0.1") == "gains: k1 must be >= 0, got -0.1");
  CHECK(error_of("gains k2=-1") == "gains: k2 must be >= 0, got -1");
  CHECK(error_of("gains sigma=0") == "gains: sigma must be > 0, got 0");
  CHECK(error_of("gains beta=-1") == "gains: beta must be >= 0, got -1");
  CHECK(error_of("gains r=-0.1") == "gains: r must be >= 0, got -0.1");
  CHECK(error_of("integrator euler dt=0") == "integrator: dt must be > 0, got 0");
  CHECK(error_of("integrator euler dt=-1") == "integrator: dt must be > 0, got -1");
  CHECK(error_of("integrator euler dt=10.5") == "integrator: dt must be <= 10, got 10.5");
  CHECK(error_of("max_speed -1") == "max_speed must be >= 0, got -1");
  CHECK(error_of("sleep -0.5") == "sleep must be >= 0, got -0.5");
  CHECK(error_of("wait converged timeout=-1") == "wait converged: timeout must be >= 0, got -1");
  CHECK(error_of("wait agents 2 timeout=-1") == "wait agents: timeout must be >= 0, got -1");
  CHECK(error_of("wait agents 0") == "wait agents: N must be an integer >= 1, got 0");
  CHECK(error_of("wait agents -3") == "wait agents: N must be an integer >= 1, got -3");
  CHECK(error_of("wait agents 2.5") == "wait agents: N must be an integer >= 1, got 2.5");
  CHECK(error_of("wait agents 1e12") == "wait agents: N must be an integer >= 1, got 1e12");
}

TEST_CASE("the first problem in token order is reported", "[supervisor][parser]") {
  // Unknown parameters are found before values are read.
  CHECK(error_of("shape circle r=-1 q=1") ==
        "shape circle: unknown parameter 'q' (expected r, cx, cy, rot, scale)");
  // Parameters are checked before the shape is compiled.
  CHECK(error_of("shape polar r=\"4+foo\" scale=0") == "shape polar: scale must be > 0, got 0");
  CHECK(error_of("gains k1=-1 k1=2") == "gains: duplicate parameter k1");
}

TEST_CASE("an error leaves nothing to apply", "[supervisor][parser]") {
  const ParseResult r = parse_command("gains k1=1 k2=-1", current_command());
  CHECK_FALSE(r.ok());
  CHECK(std::holds_alternative<NoOp>(r.action));
  CHECK(r.error == "gains: k2 must be >= 0, got -1");
}

TEST_CASE("help text", "[supervisor][parser][help]") {
  const std::string overview = help_text();
  REQUIRE_FALSE(overview.empty());
  CHECK(overview.back() == '\n');
  for (const char* syntax : {"shape line m=M c=C",
                             "shape circle r=R [cx=X cy=Y]",
                             "shape ellipse a=A b=B",
                             "shape square a=A",
                             "shape polar r=\"EXPR\" [cx=X cy=Y]",
                             "shape parametric x=\"EXPR\" y=\"EXPR\" [closed=on|off]",
                             "shape implicit f=\"EXPR\"",
                             "shape polygon points=\"x,y;x,y;...\" [closed=on|off]",
                             "[rot=DEG] [scale=S]",
                             "law paper | law arc [k_normal=K] [k_tangent=T] [spacing=S]",
                             "track line from=X,Y vel=VX,VY r=R",
                             "track circle radius=RP period=T",
                             "track point at=X,Y r=R",
                             "track stop",
                             "gains [k1=K1] [k2=K2] [sigma=S] [beta=B] [r=R]",
                             "integrator euler|rk4 [dt=DT]",
                             "max_speed V",
                             "start",
                             "status",
                             "metrics",
                             "wait converged [timeout=S]",
                             "wait agents N [timeout=S]",
                             "sleep S",
                             "record start DIR",
                             "record stop",
                             "help [COMMAND]",
                             "quit | exit"}) {
    INFO(syntax);
    CHECK(overview.find(syntax) != std::string::npos);
  }
  // One short line per command variant.
  std::istringstream lines(overview);
  for (std::string line; std::getline(lines, line);) {
    INFO(line);
    CHECK(line.size() <= 100);
  }
  for (const char* word : {"shape", "track", "gains", "integrator", "max_speed", "law", "start",
                           "status", "metrics", "wait", "sleep", "record", "help", "quit", "exit"}) {
    INFO(word);
    CHECK(has_help(word));
    const std::string details = help_text(word);
    CHECK(details.rfind(word == std::string("exit") ? "quit" : word, 0) == 0);
    CHECK(details.back() == '\n');
    CHECK(details != overview);
  }
  CHECK(help_text("gains").find("sigma") != std::string::npos);
  CHECK(help_text("law").find("k_tangent") != std::string::npos);
  CHECK(help_text("shape").find("rot ") != std::string::npos);
  CHECK(help_text("shape").find("points ") != std::string::npos);
  CHECK(help_text("exit") == help_text("quit"));
  CHECK_FALSE(has_help("shap"));
  CHECK_FALSE(has_help(""));
  CHECK(help_text("nope") == "no help for 'nope' (try 'help')\n");
}

TEST_CASE("help examples parse", "[supervisor][parser][help]") {
  // Concrete forms of the documented syntax all parse.
  for (const char* line : {"shape line m=-1 c=5",
                           "shape circle r=4 cx=0 cy=0",
                           "shape ellipse a=4 b=2 cx=1 cy=1",
                           "shape square a=4 cx=0 cy=0",
                           "shape polar r=\"4+cos(5*phi)\" cx=0 cy=0",
                           "shape polar r=\"4 + cos(5*phi)\" rot=18 scale=0.5",
                           "shape parametric x=\"4*cos(2*pi*s)\" y=\"2*sin(2*pi*s)\" closed=on",
                           "shape parametric x=\"8*s - 4\" y=\"(8*s - 4)^2 / 4\" closed=off cx=1",
                           "shape implicit f=\"x^4 + y^4 - 256\" cx=0 cy=0",
                           "shape polygon points=\"-4,-3;4,-3;4,2;0,5;-4,2\" closed=on",
                           "shape polygon points=\"0,0;4,0;4,4\" closed=off rot=45 scale=2",
                           "shape square a=4 rot=45",
                           "law paper",
                           "law arc",
                           "law arc k_normal=0.5 k_tangent=1 spacing=1",
                           "track line from=0,0 vel=0.05,0 r=3 ff=off",
                           "track circle radius=6 period=200 r=3 cx=0 cy=0 phase=0 ff=on",
                           "track point at=1,1 r=2 ff=on",
                           "track stop",
                           "gains k1=0.1 k2=2 sigma=3.5 beta=1.2 r=0.1",
                           "integrator rk4 dt=1",
                           "max_speed 0",
                           "start",
                           "status",
                           "metrics",
                           "wait converged timeout=10",
                           "wait agents 8 timeout=5",
                           "sleep 1",
                           "record start runs/x",
                           "record stop",
                           "help",
                           "help track",
                           "quit",
                           "exit"}) {
    const ParseResult r = parse_command(line, core::CompiledCommand{});
    INFO(line << ": " << r.error);
    CHECK(r.ok());
    CHECK_FALSE(std::holds_alternative<NoOp>(r.action));
  }
}

TEST_CASE("show, metrics json, progress", "[supervisor][parser]") {
  parse_as<Show>("show");
  CHECK_FALSE(parse_as<ShowMetrics>("metrics").json);
  CHECK(parse_as<ShowMetrics>("metrics json").json);
  CHECK(error_of("metrics csv") == "metrics: unexpected argument 'csv'");
  CHECK(error_of("show all") == "show: unexpected argument 'all'");
  CHECK(parse_as<Progress>("progress on").mode == Progress::Mode::OnChange);
  CHECK(parse_as<Progress>("progress off").mode == Progress::Mode::Off);
  const Progress p = parse_as<Progress>("progress every 0.2");
  CHECK(p.mode == Progress::Mode::Every);
  CHECK(p.every_s == 0.2);
  CHECK(error_of("progress") == "progress: expected on, off or every S");
  CHECK(error_of("progress on 2") == "progress: expected on, off or every S");
  CHECK(error_of("progress every") == "progress every: missing interval S (wall seconds)");
  CHECK(error_of("progress every 0") == "progress: S must be > 0, got 0");
}

TEST_CASE("help states each wait's unit, and the new commands", "[supervisor][parser][help]") {
  const std::string overview = help_text();
  CHECK(overview.find("wait converged [timeout=S]                                  wait for convergence (S wall seconds)") !=
        std::string::npos);
  CHECK(overview.find("wait time T [timeout=S]                                     wait for model time T (not seconds)") !=
        std::string::npos);
  CHECK(overview.find("sleep S                                                     pause input for S wall seconds") !=
        std::string::npos);
  for (const char* syntax : {"show ", "metrics [json]", "progress on|off|every S"}) {
    INFO(syntax);
    CHECK(overview.find(syntax) != std::string::npos);
  }
  CHECK(help_text("wait").find("timeout (wall seconds") != std::string::npos);
  CHECK(help_text("wait").find("T is model time") != std::string::npos);
  CHECK(help_text("quit").find("130") != std::string::npos);
  CHECK(help_text("progress").find("10%") != std::string::npos);
  for (const char* word : {"show", "progress"}) CHECK(has_help(word));
}

TEST_CASE("the registry's parameters are what the parser accepts", "[supervisor][parser][complete]") {
  // Every shape kind has its form, in the order of the kind names, and every form's keys are exactly
  // those the parser names when it refuses an unknown one.
  const CommandSpec* shape = find_command("shape");
  REQUIRE(shape != nullptr);
  std::vector<std::string> kinds;
  for (const FormSpec& f : shape->forms) kinds.push_back(f.sub);
  CHECK(kinds == core::params::names(core::params::kShapeKindNames));
  for (const CommandSpec& c : command_specs()) {
    for (const FormSpec& f : c.forms) {
      const std::string words = c.words(f);
      INFO(words);
      std::vector<std::string> keys;
      for (const ParamSpec& p : c.params(f)) keys.push_back(p.key);
      const ParseResult r = parse_command(words + " zzz=1", current_command());
      REQUIRE_FALSE(r.ok());
      if (keys.empty()) {
        CHECK(r.error.find("takes no key=value parameters") != std::string::npos);
      } else {
        CHECK(r.error.find("unknown parameter 'zzz' (expected " + core::params::join(keys, ", ") + ")") !=
              std::string::npos);
      }
    }
  }
}

TEST_CASE("Tab completion: commands, second words, values, parameter names", "[supervisor][parser][complete]") {
  using V = std::vector<std::string>;
  const auto cands = [](std::string_view line) { return complete(line).candidates; };
  CHECK(cands("sh") == V{"shape", "show"});
  CHECK(cands("qu") == V{"quit"});
  CHECK(cands("e") == V{"exit"});
  CHECK(complete("sh").start == 0);
  const std::vector<std::string> words = command_words();
  CHECK(cands("") == [&] {
    V sorted = words;
    std::sort(sorted.begin(), sorted.end());
    return sorted;
  }());
  for (const char* w : {"shape", "track", "wait", "record", "metrics", "progress", "show", "quit", "exit", "help"})
    CHECK(std::find(words.begin(), words.end(), w) != words.end());
  CHECK(cands("shape c") == V{"circle"});
  CHECK(cands("shape p") == V{"parametric", "polar", "polygon"});
  CHECK(complete("shape p").start == 6);
  CHECK(cands("shape circle ") == V{"cx=", "cy=", "r=", "rot=", "scale="});
  CHECK(cands("shape circle r=4 ") == V{"cx=", "cy=", "rot=", "scale="});  // a given key is not offered again
  CHECK(cands("shape circle r=4 s") == V{"scale="});
  CHECK(cands("shape circle r=") == V{});  // a value: nothing to offer
  CHECK(cands("shape polar r=\"4 + c") == V{});  // inside quotes
  CHECK(cands("track ") == V{"circle", "line", "point", "stop"});
  CHECK(cands("track circle ra") == V{"radius="});
  CHECK(cands("wait ") == V{"agents", "converged", "time"});
  CHECK(cands("wait converged ") == V{"timeout="});
  CHECK(cands("wait agents 3 t") == V{"timeout="});
  CHECK(cands("record s") == V{"start", "stop"});
  CHECK(cands("law ") == V{"arc", "k_normal=", "k_tangent=", "paper", "spacing="});
  CHECK(cands("law arc k_t") == V{"k_tangent="});
  CHECK(cands("integrator ") == V{"dt=", "euler", "rk4"});
  CHECK(cands("gains k") == V{"k1=", "k2="});
  CHECK(cands("metrics ") == V{"json"});
  CHECK(cands("start ") == V{"replace"});
  CHECK(cands("progress ") == V{"every", "off", "on"});
  CHECK(cands("help sh") == V{"shape", "show"});
  CHECK(cands("bogus ") == V{});
}

TEST_CASE("hold, stop (its emergency alias) and resume", "[supervisor][parser][hold]") {
  CHECK_FALSE(parse_as<Hold>("hold").emergency);
  CHECK(parse_as<Hold>("stop").emergency);
  parse_as<Resume>("resume");
  parse_as<Hold>("  stop   # emergency");
  CHECK(error_of("hold now") == "hold: unexpected argument 'now'");
  CHECK(error_of("stop all=1") == "stop: unknown parameter 'all' (takes no key=value parameters)");
  CHECK(error_of("resume 2") == "resume: unexpected argument '2'");
  // `track stop` is not `stop`: it only ends tracking.
  parse_as<TrackStop>("track stop");
  // Commands typed while held build on the held command: they stay held until `resume`.
  core::CompiledCommand held = current_command();
  held.hold = true;
  CHECK(parse_as<SetCommand>("shape circle r=3", held).command.hold);
  CHECK(parse_as<SetCommand>("gains k1=0.2", held).command.hold);
  CHECK(parse_as<SetCommand>("track point at=1,1 r=2", held).command.hold);
  CHECK_FALSE(parse_as<SetCommand>("shape circle r=3").command.hold);
  // Help: one overview line each; stop's page says it is hold's alias; resume's what it releases.
  const std::string overview = help_text();
  for (const char* syntax : {"\nhold ", "\nstop ", "\nresume "}) {
    INFO(syntax);
    CHECK(overview.find(syntax) != std::string::npos);
  }
  for (const char* word : {"hold", "stop", "resume"}) {
    INFO(word);
    CHECK(has_help(word));
    CHECK(help_text(word).rfind(word, 0) == 0);
    const ParseResult r = parse_command(std::string("help ") + word, current_command());
    CHECK(r.ok());
  }
  CHECK(help_text("stop").find("exactly 'hold'") != std::string::npos);
  CHECK(help_text("hold").find("late") != std::string::npos);
  CHECK(help_text("resume").find("re-converges") != std::string::npos);
}

TEST_CASE("console: a command outside the envelope is refused, naming the value", "[console][envelope]") {
  CHECK(error_of("gains k1=1e300").rfind("gains: dynamics.k1 = 1e+300: the step gain", 0) == 0);
  CHECK(error_of("gains k2=1e300").rfind("gains: dynamics.k2 = 1e+300: the step gain", 0) == 0);
  CHECK(error_of("shape circle r=4 cx=1e300")
            .rfind("shape: shape.centre = (1e+300, 0): the shape's centre gets 1e+300 units from the origin", 0) == 0);
  CHECK(error_of("shape implicit f=\"sin(x*50)*sin(y*50)-0.5\"").find("more than 16 separate pieces") !=
        std::string::npos);
  // The bound is on the step gain k2 dt sigma^(-2 beta): here dt 0.5, sigma 2.5, beta 1.1 (0.0665 k2).
  CHECK(parse_as<SetCommand>("gains k2=100").command.gains.k2 == 100);
  CHECK(error_of("gains k2=200").rfind("gains: dynamics.k2 = 200: the step gain k2 dt sigma^(-2 beta) is 13.", 0) == 0);
}

namespace {

/// The current command with a circle and a triangle to keep out, a fence and its settings.
core::CompiledCommand guarded_command() {
  core::Command c = current_command();
  core::KeepOutZone circle;
  circle.centre = core::Vec2(5, 0);
  circle.radius = 1;
  core::KeepOutZone triangle;
  triangle.kind = core::KeepOutZone::Kind::Polygon;
  triangle.vertices = {core::Vec2(0, 0), core::Vec2(1, 0), core::Vec2(0, 1)};
  c.keep_out = {circle, triangle};
  c.fence = {core::Vec2(-20, -20), core::Vec2(20, -20), core::Vec2(0, 20)};
  c.fence_margin = 0.5;
  c.breach_action = core::BreachAction::Stop;
  c.min_separation = 0.25;
  return core::compile(c);
}

core::CompiledCommand safety_set(std::string_view line,
                                 const core::CompiledCommand& cur = guarded_command()) {
  const SetCommand s = parse_as<SetCommand>(line, cur);
  CHECK(s.what == SetCommand::What::Safety);
  check_shape_unchanged(s.command);
  check_rest_unchanged(s.command);
  return s.command;
}

}  // namespace

TEST_CASE("safety: every form changes its setting and keeps the rest of the command",
          "[supervisor][parser][safety]") {
  using core::Vec2;
  const core::CompiledCommand g = guarded_command();
  CHECK(safety_set("safety separation 0.5").min_separation == 0.5);
  CHECK(safety_set("safety separation 0").min_separation == 0.0);
  CHECK(safety_set("safety separation 0.5").keep_out == g.keep_out);
  // keep_out: circles go before the polygons (the order they travel in and 'safety' numbers them)
  const core::CompiledCommand a = safety_set("safety keep_out add circle -3,4 2");
  REQUIRE(a.keep_out.size() == 3);
  CHECK(a.keep_out[1].kind == core::KeepOutZone::Kind::Circle);
  CHECK(a.keep_out[1].centre == Vec2(-3, 4));
  CHECK(a.keep_out[1].radius == 2.0);
  CHECK(a.keep_out[2] == g.keep_out[1]);
  const core::CompiledCommand p = safety_set("safety keep_out add polygon \"2,2; 4,2; 3,5\"");
  REQUIRE(p.keep_out.size() == 3);
  CHECK(p.keep_out[2].vertices == std::vector<Vec2>{Vec2(2, 2), Vec2(4, 2), Vec2(3, 5)});
  const core::CompiledCommand r = safety_set("safety keep_out remove 1");
  REQUIRE(r.keep_out.size() == 1);
  CHECK(r.keep_out[0] == g.keep_out[1]);
  CHECK(safety_set("safety keep_out remove 2").keep_out == std::vector<core::KeepOutZone>{g.keep_out[0]});
  CHECK(safety_set("safety keep_out clear").keep_out.empty());
  // fence: margin and action kept unless given
  const core::CompiledCommand box = safety_set("safety fence box");
  CHECK(box.fence.empty());
  CHECK(box.fence_margin == 0.5);
  CHECK(box.breach_action == core::BreachAction::Stop);
  const core::CompiledCommand poly =
      safety_set("safety fence polygon \"-9,-9;9,-9;9,9;-9,9\" margin=1 action=return");
  CHECK(poly.fence == std::vector<Vec2>{Vec2(-9, -9), Vec2(9, -9), Vec2(9, 9), Vec2(-9, 9)});
  CHECK(poly.fence_margin == 1.0);
  CHECK(poly.breach_action == core::BreachAction::Return);
  CHECK(poly.keep_out == g.keep_out);
  CHECK(safety_set("safety fence box action=hold").breach_action == core::BreachAction::Hold);
  CHECK(safety_set("safety fence box margin=0").fence_margin == 0.0);
  // Questions: the word alone, or show.
  parse_as<ShowSafety>("safety");
  parse_as<ShowSafety>("safety show");
}

TEST_CASE("safety: bad lines are refused naming what was wrong, and publish nothing",
          "[supervisor][parser][safety]") {
  CHECK(error_of("safety separation") == "safety separation: missing separation D (shape units; 0 = off)");
  CHECK(error_of("safety separation -1") == "safety separation must be >= 0, got -1");
  CHECK(error_of("safety separation x") == "safety separation: not a number: 'x'");
  CHECK(error_of("safety bogus") ==
        "safety: unknown setting 'bogus' (expected separation, keep_out, fence, show)");
  CHECK(error_of("safety keep_out") ==
        "safety keep_out: expected add circle X,Y R, add polygon \"x,y;...\", remove K or clear");
  CHECK(error_of("safety keep_out add square 1,1 1") ==
        "safety keep_out add: expected circle X,Y R or polygon \"x,y;x,y;x,y\", got 'square'");
  CHECK(error_of("safety keep_out add circle 1,1") ==
        "safety keep_out add circle: expected the centre X,Y and the radius R");
  CHECK(error_of("safety keep_out add circle 1 2") ==
        "safety keep_out: add circle: centre must be x,y, got '1'");
  CHECK(error_of("safety keep_out add circle 1,1 0") ==
        "safety keep_out add circle: circle radius must be > 0");
  CHECK(error_of("safety keep_out add circle 1,1 r") == "safety keep_out: add circle: R: not a number: 'r'");
  CHECK(error_of("safety keep_out add polygon \"0,0;1,1;1,0;0,1\"") ==
        "safety keep_out add polygon: polygon edges 0 and 2 cross (the polygon must be simple)");
  CHECK(error_of("safety keep_out add polygon \"0,0;1,1\"") ==
        "safety keep_out add polygon: polygon needs >= 3 vertices, got 2");
  CHECK(error_of("safety keep_out remove 1") == "safety keep_out remove: there is no keep-out zone");
  const ParseResult far = parse_command("safety keep_out remove 3", guarded_command());
  CHECK(far.error == "safety keep_out remove: K must be a zone number 1..2 (as 'safety' lists them), got 3");
  CHECK(std::holds_alternative<NoOp>(far.action));
  CHECK(parse_command("safety keep_out remove 1.5", guarded_command()).error ==
        "safety keep_out remove: K must be a zone number 1..2 (as 'safety' lists them), got 1.5");
  CHECK(error_of("safety keep_out clear now") == "safety keep_out: unexpected argument 'now'");
  CHECK(error_of("safety fence") == "safety fence: expected box or polygon \"x,y;x,y;...\"");
  CHECK(error_of("safety fence circle") ==
        "safety fence: expected box or polygon \"x,y;x,y;...\", got 'circle'");
  CHECK(error_of("safety fence polygon") == "safety fence polygon: missing vertices \"x,y;x,y;x,y\"");
  CHECK(error_of("safety fence polygon \"0,0;4,0;4,1;1,1;1,4;0,4\"") ==
        "safety fence polygon: a fence must be convex (it turns back at vertex 3); cut the rest out with "
        "safety.keep_out");
  CHECK(
      error_of("safety fence polygon \"0,0;2000,0;0,1\"") ==
      "safety fence polygon: fence vertex 1 (2000, 0) is outside the workspace [-w, w]^2 (safety.workspace = "
      "1000): move it in or widen safety.workspace");
  CHECK(error_of("safety fence polygon \"0,0;x,0;0,1\"") ==
        "safety fence: polygon: point 2: not a number: 'x,0'");
  CHECK(error_of("safety fence box margin=-1") == "safety fence: margin must be >= 0, got -1");
  CHECK(error_of("safety fence box action=land") ==
        "safety fence: unknown action 'land' (expected hold|stop|return)");
  CHECK(error_of("safety fence box radius=1") ==
        "safety fence: unknown parameter 'radius' (expected margin, action)");
}
