#include "config/config.hpp"

#include "core/command_table.hpp"

#include <catch2/catch.hpp>
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "shapes/shapes.hpp"
#include "util/text.hpp"

#include <sys/stat.h>

using shapeform::config::Config;
using shapeform::config::ConfigError;
using shapeform::config::load;
using shapeform::config::load_string;
using shapeform::config::to_yaml;
namespace core = shapeform::core;
namespace config = shapeform::config;

namespace {
/// True when the command's curve is the one its shape compiles to (not a default or stale curve).
bool compiled_from_shape(const core::CompiledCommand& c) {
  const auto fresh = shapeform::shapes::compile_curve(c.shape);
  return fresh->closed() == c.curve().closed() && fresh->length() == c.curve().length();
}


const std::string kSourceDir = SHAPEFORM_SOURCE_DIR;

/// The loader's degrees -> radians factor (shape.rotation_deg).
constexpr double kRadPerDeg = 3.14159265358979323846 / 180.0;

std::string scenario(const std::string& name) {
  return kSourceDir + "/config/scenarios/" + name + ".yaml";
}

/// The problems load_string reports (fails the test when it does not throw).
std::vector<std::string> problems_of(const std::string& text,
                                     const std::vector<std::string>& overrides = {}) {
  try {
    load_string(text, overrides);
  } catch (const ConfigError& e) {
    return e.problems();
  }
  FAIL("expected a ConfigError for:\n" << text);
  return {};
}

/// The single problem reported.
std::string problem_of(const std::string& text, const std::vector<std::string>& overrides = {}) {
  const auto p = problems_of(text, overrides);
  REQUIRE(p.size() == 1);
  return p[0];
}

std::vector<std::string> problems_of_load(const std::string& path,
                                          const std::vector<std::string>& overrides = {}) {
  try {
    load(path, overrides);
  } catch (const ConfigError& e) {
    return e.problems();
  }
  FAIL("expected a ConfigError for " << path);
  return {};
}

void require_vec(const core::Vec2& v, double x1, double x2) {
  CHECK(v.x() == x1);
  CHECK(v.y() == x2);
}

/// Every key of the config table equal (a key the table gains is compared too).
void require_equal(const Config& a, const Config& b) {
  for (const auto& p : shapeform::config::config_table()) {
    INFO(p.key);
    CHECK(p.get(a) == p.get(b));
  }
}

/// The paper's dynamics and step, shared by every scenario.
void require_paper_dynamics(const Config& c, double r = 0.1) {
  CHECK(c.command.gains.k1 == 0.1);
  CHECK(c.command.gains.k2 == 2.0);
  CHECK(c.command.gains.sigma == 3.5);
  CHECK(c.command.gains.beta == 1.2);
  CHECK(c.command.gains.r == r);
  CHECK(c.command.integrator == core::Integrator::Euler);
  CHECK(c.command.dt == 1.0);
}

/// A file in the system's temporary folder, removed at the end of the test.
struct TempFile {
  explicit TempFile(const std::string& text) { std::ofstream(path) << text; }
  ~TempFile() { std::remove(path.c_str()); }
  std::string path =
      (std::filesystem::temp_directory_path() / "shapeform_config_test_syntax.yaml").string();
};

}  // namespace

// ----------------------------------------------------------------------------------------------
// Defaults and scenario files

TEST_CASE("no file gives the struct defaults and needs no schema_version") {
  const Config c = load("");
  require_equal(c, Config{});
  CHECK(c.name == "circle");
  CHECK(c.swarm.agents == 12);
  CHECK(c.command.shape.kind == core::ShapeKind::Circle);
  CHECK(c.command.shape.r0 == 4.0);
  CHECK(c.transport.profile == "loopback");
  CHECK(c.transport.discovery_server == "127.0.0.1:11811");
}

TEST_CASE("a file with only schema_version gives the defaults") {
  require_equal(load_string("schema_version: 1\n"), Config{});
}

TEST_CASE("empty sections and empty lists keep their defaults") {
  const Config c = load_string("schema_version: 1\nshape:\ntransport:\n  peers:\n");
  require_equal(c, Config{});
}

TEST_CASE("config/default.yaml loads to exactly the defaults") {
  require_equal(load(kSourceDir + "/config/default.yaml"), Config{});
}

TEST_CASE("config/large_swarm.sets loads as --set overrides") {
  // The launcher and the benchmark pass these lines as --set overrides; a renamed key would stop both.
  std::ifstream in(kSourceDir + "/config/large_swarm.sets");
  REQUIRE(in.good());
  std::vector<std::string> sets;
  int min_agents = 0, min_secured_agents = 0;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    if (line.rfind("min_agents=", 0) == 0) min_agents = std::stoi(line.substr(11));
    else if (line.rfind("min_secured_agents=", 0) == 0) min_secured_agents = std::stoi(line.substr(19));
    else sets.push_back(line);
  }
  CHECK(min_agents >= 2);
  // A secured swarm needs them earlier (docs/SECURITY.md, Cost), never later.
  CHECK(min_secured_agents >= 2);
  CHECK(min_secured_agents <= min_agents);
  REQUIRE(sets.size() >= 5);
  const Config large = load("", sets);  // an unknown key or a bad value throws, naming it
  CHECK(large.agent.idle_rate_hz > 0);
  CHECK(large.agent.idle_rate_hz < large.agent.rate_hz);
  CHECK(large.agent.leave_by_lease);
  CHECK(large.transport.multicast_data);
  CHECK(large.transport.lease_s > Config{}.transport.lease_s);
}

TEST_CASE("scenario line.yaml") {
  const Config c = load(scenario("line"));
  CHECK(c.name == "line");
  CHECK(c.swarm.agents == 12);
  CHECK(c.command.shape.kind == core::ShapeKind::Line);
  CHECK(c.command.shape.m == -1.0);
  CHECK(c.command.shape.c == 5.0);
  CHECK_FALSE(c.command.tracking.enabled);
  CHECK(c.sim.steps == 500);
  require_paper_dynamics(c);
}

TEST_CASE("scenario circle.yaml") {
  const Config c = load(scenario("circle"));
  CHECK(c.name == "circle");
  CHECK(c.swarm.agents == 12);
  CHECK(c.command.shape.kind == core::ShapeKind::Circle);
  CHECK(c.command.shape.r0 == 4.0);
  require_vec(c.command.shape.centre, 0.0, 0.0);
  CHECK(c.sim.steps == 500);
  require_paper_dynamics(c);
}

TEST_CASE("scenarios ellipse.yaml and ellipse_no_repulsion.yaml") {
  for (const auto& [name, r] :
       {std::pair{"ellipse", 0.1}, std::pair{"ellipse_no_repulsion", 0.0}}) {
    INFO(name);
    const Config c = load(scenario(name));
    CHECK(c.name == name);
    CHECK(c.swarm.agents == 12);
    CHECK(c.command.shape.kind == core::ShapeKind::Ellipse);
    CHECK(c.command.shape.a == 4.0);
    CHECK(c.command.shape.b == 2.0);
    CHECK(c.sim.steps == 500);
    require_paper_dynamics(c, r);
  }
}

TEST_CASE("scenarios square.yaml and square_no_repulsion.yaml") {
  for (const auto& [name, r] : {std::pair{"square", 0.1}, std::pair{"square_no_repulsion", 0.0}}) {
    INFO(name);
    const Config c = load(scenario(name));
    CHECK(c.name == name);
    CHECK(c.swarm.agents == 12);
    CHECK(c.command.shape.kind == core::ShapeKind::Square);
    CHECK(c.command.shape.a == 5.0);
    CHECK(c.sim.steps == 500);
    require_paper_dynamics(c, r);
  }
}

TEST_CASE("scenario track_line.yaml") {
  const Config c = load(scenario("track_line"));
  CHECK(c.name == "track_line");
  CHECK(c.swarm.agents == 10);
  CHECK(c.command.shape.kind == core::ShapeKind::Circle);
  CHECK(c.command.shape.r0 == 2.0);
  CHECK(c.command.tracking.enabled);
  CHECK(c.command.tracking.path.kind == core::CentrePath::Kind::Line);
  require_vec(c.command.tracking.path.point, -10.0, -10.0);
  require_vec(c.command.tracking.path.velocity, 0.1, 0.1);
  CHECK(c.sim.steps == 200);
  require_paper_dynamics(c);
}

TEST_CASE("scenario track_circle.yaml") {
  const Config c = load(scenario("track_circle"));
  CHECK(c.name == "track_circle");
  CHECK(c.swarm.agents == 10);
  CHECK(c.command.shape.kind == core::ShapeKind::Circle);
  CHECK(c.command.shape.r0 == 2.0);
  CHECK(c.command.tracking.enabled);
  const auto& p = c.command.tracking.path;
  CHECK(p.kind == core::CentrePath::Kind::Circle);
  require_vec(p.origin, 0.0, 0.0);
  CHECK(p.radius == 6.0);
  CHECK(p.period == 200.0);
  CHECK(p.phase == 0.0);
  CHECK(c.sim.steps == 200);
  require_paper_dynamics(c);
}

/// The arc law with its documented parameters.
void require_arc_law(const Config& c) {
  CHECK(c.command.law == core::Law::Arc);
  CHECK(c.command.arc.k_normal == 0.5);
  CHECK(c.command.arc.k_tangent == 1.0);
  CHECK(c.command.arc.spacing == 1.0);
}

TEST_CASE("scenarios arc_circle, arc_ellipse, arc_square, arc_line") {
  const Config circle = load(scenario("arc_circle"));
  CHECK(circle.command.shape.kind == core::ShapeKind::Circle);
  CHECK(circle.command.shape.r0 == 4.0);
  const Config ellipse = load(scenario("arc_ellipse"));
  CHECK(ellipse.command.shape.kind == core::ShapeKind::Ellipse);
  CHECK(ellipse.command.shape.a == 4.0);
  CHECK(ellipse.command.shape.b == 2.0);
  const Config square = load(scenario("arc_square"));
  CHECK(square.command.shape.kind == core::ShapeKind::Square);
  CHECK(square.command.shape.a == 5.0);
  const Config line = load(scenario("arc_line"));
  CHECK(line.command.shape.kind == core::ShapeKind::Line);
  CHECK(line.command.shape.m == -1.0);
  CHECK(line.command.shape.c == 5.0);
  for (const Config* c : {&circle, &ellipse, &square, &line}) {
    INFO(c->name);
    CHECK(c->name.rfind("arc_", 0) == 0);
    CHECK(c->swarm.agents == 12);
    CHECK(c->sim.steps == 300);
    CHECK_FALSE(c->command.tracking.enabled);
    require_paper_dynamics(*c);  // the paper's gains stay in the file, unused by the arc law
    require_arc_law(*c);
    CHECK(compiled_from_shape(c->command));
  }
}

TEST_CASE("scenarios polar_star, polygon, implicit: compiled at load") {
  const Config star = load(scenario("polar_star"));
  CHECK(star.name == "polar_star");
  CHECK(star.command.shape.kind == core::ShapeKind::Polar);
  CHECK(star.command.shape.r_expr == "4 + cos(5*phi)");
  REQUIRE(compiled_from_shape(star.command));
  // r(0) = 5 and r(pi/5) = 3: the radial target of far points lands on the star.
  const core::Vec2 tip = core::target_point(star.command.shape, star.command.curve(), core::Vec2(20.0, 0.0));
  CHECK(tip.x() == Approx(5.0).epsilon(1e-6));
  CHECK(tip.y() == Approx(0.0).margin(1e-9));

  const Config poly = load(scenario("polygon"));
  CHECK(poly.name == "polygon");
  CHECK(poly.command.shape.kind == core::ShapeKind::Polygon);
  CHECK(poly.command.shape.closed);
  CHECK(poly.command.shape.vertices ==
        std::vector<core::Vec2>{core::Vec2(-4, -3), core::Vec2(4, -3), core::Vec2(4, 2),
                                core::Vec2(0, 5), core::Vec2(-4, 2)});
  REQUIRE(compiled_from_shape(poly.command));
  CHECK(poly.command.curve().length() == Approx(8 + 5 + 2 * 5 + 5));

  const Config imp = load(scenario("implicit"));
  CHECK(imp.name == "implicit");
  CHECK(imp.command.shape.kind == core::ShapeKind::Implicit);
  CHECK(imp.command.shape.f_expr == "x^4 + y^4 - 256");
  REQUIRE(compiled_from_shape(imp.command));
  const core::Vec2 side = core::target_point(imp.command.shape, imp.command.curve(), core::Vec2(7.0, 0.0));
  CHECK(side.x() == Approx(4.0).epsilon(1e-6));
  CHECK(side.y() == Approx(0.0).margin(1e-6));

  for (const Config* c : {&star, &poly, &imp}) {
    INFO(c->name);
    CHECK(c->swarm.agents == 12);
    CHECK(c->sim.steps == 300);
    require_arc_law(*c);
  }
}

TEST_CASE("scenarios track_line_ff and track_circle_ff: the tracking scenarios with feed-forward") {
  for (const std::string base : {"track_line", "track_circle"}) {
    INFO(base);
    const Config plain = load(scenario(base));
    const Config ff = load(scenario(base + "_ff"));
    CHECK(ff.name == base + "_ff");
    CHECK_FALSE(plain.command.tracking.feedforward);
    CHECK(ff.command.tracking.feedforward);
    Config same = ff;
    same.name = plain.name;
    same.command.tracking.feedforward = false;
    require_equal(same, plain);  // nothing else differs
  }
}

TEST_CASE("every key is read") {
  const Config c = load_string(R"(schema_version: 1
name: everything
swarm: {agents: 7, seed: 18446744073709551615, init_half_width: 2.5}
shape: {kind: ellipse, m: 0.5, c: -2, r0: 3, a: 6, b: 1.5, centre: [1, -2]}
tracking: {enabled: true, path: circle, point: [1, 2], velocity: [3, 4], origin: [5, 6],
           radius: 0, period: 10, phase: -1.5, feedforward: true}
dynamics: {k1: 0, k2: 1, sigma: 0.5, beta: 0, r: 0.25, max_speed: 2}
integration: {integrator: rk4, dt: 0.5}
sim: {steps: 0}
agent: {rate_hz: 1000, neighbour_timeout_periods: 1, status_rate_hz: 0.5}
supervisor: {metrics_rate_hz: 5, target_rate_hz: 20, agent_timeout_s: 0.5, flush_s: 2,
             converge: {band_abs: 0, band_rel: 0, gap_cv_max: 0.3, hold: 0}}
transport: {profile: lan, domain: 232, max_participants: 230, interfaces: [192.168.1.2],
            peers: [192.168.1.3, 192.168.1.4], discovery_server: "10.0.0.9:1",
            lease_s: 10, announce_s: 9.5, socket_buffer_bytes: 2147483647}
)");
  CHECK(c.name == "everything");
  CHECK(c.swarm.agents == 7);
  CHECK(c.swarm.seed == UINT64_MAX);
  CHECK(c.swarm.init_half_width == 2.5);
  CHECK(c.command.shape.kind == core::ShapeKind::Ellipse);
  CHECK(c.command.shape.m == 0.5);
  CHECK(c.command.shape.c == -2.0);
  CHECK(c.command.shape.r0 == 3.0);
  CHECK(c.command.shape.a == 6.0);
  CHECK(c.command.shape.b == 1.5);
  require_vec(c.command.shape.centre, 1.0, -2.0);
  const auto& t = c.command.tracking;
  CHECK(t.enabled);
  CHECK(t.feedforward);
  CHECK(t.path.kind == core::CentrePath::Kind::Circle);
  require_vec(t.path.point, 1.0, 2.0);
  require_vec(t.path.velocity, 3.0, 4.0);
  require_vec(t.path.origin, 5.0, 6.0);
  CHECK(t.path.radius == 0.0);
  CHECK(t.path.period == 10.0);
  CHECK(t.path.phase == -1.5);
  CHECK(c.command.gains.k1 == 0.0);
  CHECK(c.command.gains.k2 == 1.0);
  CHECK(c.command.gains.sigma == 0.5);
  CHECK(c.command.gains.beta == 0.0);
  CHECK(c.command.gains.r == 0.25);
  CHECK(c.command.max_speed == 2.0);
  CHECK(c.command.integrator == core::Integrator::RK4);
  CHECK(c.command.dt == 0.5);
  CHECK(c.sim.steps == 0);
  CHECK(c.agent.rate_hz == 1000.0);
  CHECK(c.agent.neighbour_timeout_periods == 1.0);
  CHECK(c.agent.status_rate_hz == 0.5);
  CHECK(c.supervisor.metrics_rate_hz == 5.0);
  CHECK(c.supervisor.target_rate_hz == 20.0);
  CHECK(c.supervisor.agent_timeout_s == 0.5);
  CHECK(c.supervisor.flush_s == 2.0);
  CHECK(c.supervisor.converge.band_abs == 0.0);
  CHECK(c.supervisor.converge.band_rel == 0.0);
  CHECK(c.supervisor.converge.gap_cv_max == 0.3);
  CHECK(c.supervisor.converge.hold == 0.0);
  CHECK(c.transport.profile == "lan");
  CHECK(c.transport.domain == 232);
  CHECK(c.transport.max_participants == 230);
  CHECK(c.transport.interfaces == std::vector<std::string>{"192.168.1.2"});
  CHECK(c.transport.peers == std::vector<std::string>{"192.168.1.3", "192.168.1.4"});
  CHECK(c.transport.discovery_server == "10.0.0.9:1");
  CHECK(c.transport.lease_s == 10.0);
  CHECK(c.transport.announce_s == 9.5);
  CHECK(c.transport.socket_buffer_bytes == 2147483647);
}

TEST_CASE("the shape's placement, equations, vertices and the law's keys are read") {
  const Config c = load_string(R"yaml(schema_version: 1
shape:
  kind: polar
  r_expr: "2 + 0.5*cos(3*phi)"
  x_expr: "cos(2*pi*s)"
  y_expr: sin(2*pi*s)
  f_expr: "x^2 + y^2 - 4"
  vertices: [[0, 0], [1.5, 0], [0, 2]]
  closed: false
  rotation_deg: 90
  scale: 2
  centre: [1, 1]
dynamics: {law: arc, k_normal: 10, k_tangent: 0.25, spacing: 0.5}
)yaml");
  const auto& s = c.command.shape;
  CHECK(s.kind == core::ShapeKind::Polar);
  CHECK(s.r_expr == "2 + 0.5*cos(3*phi)");
  CHECK(s.x_expr == "cos(2*pi*s)");
  CHECK(s.y_expr == "sin(2*pi*s)");
  CHECK(s.f_expr == "x^2 + y^2 - 4");
  CHECK(s.vertices ==
        std::vector<core::Vec2>{core::Vec2(0, 0), core::Vec2(1.5, 0), core::Vec2(0, 2)});
  CHECK_FALSE(s.closed);
  CHECK(s.rotation == Approx(3.14159265358979323846 / 2));  // degrees in the file, radians inside
  CHECK(s.scale == 2.0);
  CHECK(c.command.law == core::Law::Arc);
  CHECK(c.command.arc.k_normal == 10.0);
  CHECK(c.command.arc.k_tangent == 0.25);
  CHECK(c.command.arc.spacing == 0.5);
  // Compiled and placed: r(0) = 2.5, rotated by 90 degrees, scaled by 2, about (1, 1).
  REQUIRE(compiled_from_shape(c.command));
  const core::Vec2 p = core::target_point(s, c.command.curve(), core::Vec2(1.0, 30.0));
  CHECK(p.x() == Approx(1.0).margin(1e-9));
  CHECK(p.y() == Approx(1.0 + 2 * 2.5).epsilon(1e-6));

  SECTION("defaults: no rotation, scale 1, closed, paper law") {
    const Config d = load("");
    CHECK(d.command.shape.rotation == 0.0);
    CHECK(d.command.shape.scale == 1.0);
    CHECK(d.command.shape.closed);
    CHECK(d.command.shape.vertices.empty());
    CHECK(d.command.shape.r_expr.empty());
    CHECK(d.command.law == core::Law::Paper);
    CHECK(d.command.arc.k_normal == 0.5);
    CHECK(d.command.arc.k_tangent == 1.0);
    CHECK(d.command.arc.spacing == 1.0);
    REQUIRE(compiled_from_shape(d.command));  // the default circle is compiled too
  }
  SECTION("every kind compiles, expressions of other kinds are not looked at") {
    const Config par = load("", {"shape.kind=parametric", "shape.x_expr=3*cos(2*pi*s)",
                                 "shape.y_expr=2*sin(2*pi*s)", "shape.f_expr=junk(",
                                 "shape.r_expr=-1"});
    REQUIRE(compiled_from_shape(par.command));
    CHECK(par.command.curve().closed());
    const Config open = load("", {"shape.kind=polygon", "shape.vertices=[[0, 0], [4, 0]]",
                                  "shape.closed=false"});
    REQUIRE(compiled_from_shape(open.command));
    CHECK_FALSE(open.command.curve().closed());
    CHECK(open.command.curve().length() == Approx(4.0));
    const Config imp = load("", {"shape.kind=implicit", "shape.f_expr=x^2/16 + y^2/4 - 1"});
    REQUIRE(compiled_from_shape(imp.command));
    const Config circle = load("", {"shape.r_expr=4+foo", "shape.vertices=[[0, 0]]"});
    CHECK(circle.command.shape.kind == core::ShapeKind::Circle);
  }
}

TEST_CASE("a shape that does not compile is reported at the key that holds it") {
  CHECK(problem_of("schema_version: 1\nshape:\n  kind: polar\n  centre: [0, 0]\n"
                   "  r_expr: \"4+foo\"\n") ==
        "shape.r_expr: polar: r(phi) = '4+foo': Unexpected token \"foo\" found at position 2. "
        "(line 5)");
  SECTION("unknown variable") {
    const std::string p =
        problem_of("schema_version: 1\nshape:\n  kind: polar\n  r_expr: 4 + cos(5*theta)\n");
    CHECK(p.rfind("shape.r_expr: polar: r(phi) = '4 + cos(5*theta)': ", 0) == 0);
    CHECK(p.find("\"theta\"") != std::string::npos);
    CHECK(p.substr(p.size() - 9) == " (line 4)");
  }
  SECTION("parametric: the faulty coordinate is named") {
    const std::string p = problem_of(
        "schema_version: 1\nshape:\n  kind: parametric\n  x_expr: cos(2*pi*s)\n"
        "  y_expr: sin(2*pi*t)\n");
    CHECK(p.rfind("shape.y_expr: parametric: y(s) = 'sin(2*pi*t)': ", 0) == 0);
    CHECK(p.substr(p.size() - 9) == " (line 5)");
    const std::string q = problem_of(
        "schema_version: 1\nshape:\n  kind: parametric\n  x_expr: cos(2*pi*s\n"
        "  y_expr: sin(2*pi*s)\n");
    CHECK(q.rfind("shape.x_expr: parametric: x(s) = 'cos(2*pi*s': ", 0) == 0);
    CHECK(q.substr(q.size() - 9) == " (line 4)");
  }
  SECTION("a missing expression") {
    CHECK(problem_of("schema_version: 1\nshape: {kind: implicit}\n") ==
          "shape.f_expr: implicit: f(x, y): empty expression");
    CHECK(problem_of("schema_version: 1\nshape: {kind: polar, r_expr: \"  \"}\n") ==
          "shape.r_expr: polar: r(phi): empty expression (line 2)");
  }
  SECTION("implicit curve with no real points") {
    CHECK(problem_of("schema_version: 1\nshape:\n  kind: implicit\n  f_expr: x^2+y^2+1\n") ==
          "shape.f_expr: implicit curve: f(x, y) = 0 has no real points in the box "
          "(f = 'x^2+y^2+1', box [-20, 20]^2 around the centre) (line 4)");
  }
  SECTION("polar radius not > 0 everywhere") {
    const std::string p =
        problem_of("schema_version: 1\nshape:\n  kind: polar\n  r_expr: 1 + 2*cos(phi)\n");
    CHECK(p.rfind("shape.r_expr: polar: r(phi) must be finite and > 0 for every phi, got r(", 0) ==
          0);
    CHECK(p.substr(p.size() - 9) == " (line 4)");
  }
  SECTION("degenerate polygons") {
    CHECK(problem_of("schema_version: 1\nshape:\n  kind: polygon\n  vertices: [[0, 0], [1, 0]]\n") ==
          "shape.vertices: polygon: a closed polygon needs at least 3 vertices, got 2 (line 4)");
    const std::string open = problem_of(
        "schema_version: 1\nshape:\n  kind: polygon\n  closed: false\n  vertices: [[0, 0]]\n");
    CHECK(open.rfind("shape.vertices: polygon: a", 0) == 0);
    CHECK(open.find(" open polygon needs at least 2 vertices, got 1 (line 5)") != std::string::npos);
    CHECK(problem_of("schema_version: 1\nshape:\n  kind: polygon\n"
                     "  vertices: [[0, 0], [1, 0], [1, 0], [0, 1]]\n") ==
          "shape.vertices: polygon: vertices 1 and 2 coincide (zero-length edge) (line 4)");
    CHECK(problem_of("schema_version: 1\nshape:\n  kind: polygon\n"
                     "  vertices: [[0, 0], [1, 1], [2, 2]]\n") ==
          "shape.vertices: polygon: the vertices are collinear (zero area) (line 4)");
    CHECK(problem_of("schema_version: 1\nshape: {kind: polygon}\n") ==
          "shape.vertices: polygon: a closed polygon needs at least 3 vertices, got 0");
  }
  SECTION("an override is marked --set") {
    CHECK(problem_of("schema_version: 1\nshape:\n  kind: polar\n  r_expr: \"4\"\n",
                     {"shape.r_expr=4+foo"}) ==
          "shape.r_expr: polar: r(phi) = '4+foo': Unexpected token \"foo\" found at position 2. "
          "(--set)");
  }
  SECTION("reported together with the other sections' problems") {
    const auto p = problems_of(
        "schema_version: 1\nshape: {kind: polar, r_expr: \"4+foo\"}\ndynamics: {k_tangent: 2}\n");
    REQUIRE(p.size() == 2);
    CHECK(p[0] == "dynamics.k_tangent: must be in (0, 1], got 2 (line 3)");
    CHECK(p[1].rfind("shape.r_expr: polar: r(phi) = '4+foo'", 0) == 0);
  }
  SECTION("not compiled when the shape's own keys are wrong: only those are reported") {
    CHECK(problem_of("schema_version: 1\nshape: {kind: polar, r_expr: \"4+foo\", scale: 0}\n") ==
          "shape.scale: must be > 0, got 0 (line 2)");
    CHECK(problem_of("schema_version: 1\nshape: {kind: polygon, vertices: [[0, 0], [1]]}\n") ==
          "shape.vertices[1]: expected a list of 2 numbers [x1, x2], got a list of 1 (line 2)");
  }
}

TEST_CASE("the new keys' types and ranges are checked") {
  const auto one = [](const std::string& section, const std::string& key, const std::string& v) {
    return problem_of("schema_version: 1\n" + section + ":\n  " + key + ": " + v + "\n");
  };
  CHECK(one("shape", "scale", "0") == "shape.scale: must be > 0, got 0 (line 3)");
  CHECK(one("shape", "scale", "-2") == "shape.scale: must be > 0, got -2 (line 3)");
  CHECK(one("shape", "rotation_deg", ".nan") ==
        "shape.rotation_deg: must be finite, got .nan (line 3)");
  CHECK(one("shape", "rotation_deg", "ninety") ==
        "shape.rotation_deg: expected a number, got \"ninety\" (line 3)");
  CHECK(one("shape", "closed", "yes") ==
        "shape.closed: expected true or false, got \"yes\" (line 3)");
  CHECK(one("shape", "r_expr", "[1, 2]") == "shape.r_expr: expected a string, got a list (line 3)");
  CHECK(one("shape", "f_expr", "{x: 1}") == "shape.f_expr: expected a string, got a map (line 3)");
  CHECK(one("shape", "vertices", "5") ==
        "shape.vertices: expected a list of [x, y] pairs, got 5 (line 3)");
  CHECK(one("shape", "vertices", "[[1, 2], [3, x]]") ==
        "shape.vertices[1][1]: expected a number, got \"x\" (line 3)");
  CHECK(one("shape", "vertices", "[[1, 2], 3]") ==
        "shape.vertices[1]: expected a list of 2 numbers [x1, x2], got 3 (line 3)");
  CHECK(one("shape", "vertices", "[[1, .inf]]") ==
        "shape.vertices[0][1]: must be finite, got .inf (line 3)");
  CHECK(problem_of("schema_version: 1\nshape:\n  vertices:\n    - [0, 0]\n    - [1, 2, 3]\n") ==
        "shape.vertices[1]: expected a list of 2 numbers [x1, x2], got a list of 3 (line 5)");
  CHECK(one("dynamics", "k_normal", "0") == "dynamics.k_normal: must be in (0, 10], got 0 (line 3)");
  CHECK(one("dynamics", "k_normal", "10.5") ==
        "dynamics.k_normal: must be in (0, 10], got 10.5 (line 3)");
  CHECK(one("dynamics", "k_tangent", "0") ==
        "dynamics.k_tangent: must be in (0, 1], got 0 (line 3)");
  CHECK(one("dynamics", "k_tangent", "1.01") ==
        "dynamics.k_tangent: must be in (0, 1], got 1.01 (line 3)");
  CHECK(one("dynamics", "spacing", "0") == "dynamics.spacing: must be > 0, got 0 (line 3)");
  CHECK(one("dynamics", "spacing", "-1") == "dynamics.spacing: must be > 0, got -1 (line 3)");
  CHECK(one("dynamics", "law", "\"\"") ==
        "dynamics.law: must be one of paper, arc, got \"\" (line 3)");
  CHECK(problem_of("schema_version: 1\n", {"dynamics.law=Arc"}) ==
        "dynamics.law: must be one of paper, arc, got \"Arc\" (--set)");
  // Boundaries included.
  CHECK(load("", {"dynamics.k_tangent=1", "dynamics.k_normal=10"}).command.arc.k_tangent == 1.0);
  CHECK(load("", {"shape.vertices="}).command.shape.vertices.empty());
}

// ----------------------------------------------------------------------------------------------
// Problems, one kind at a time

TEST_CASE("unknown keys are reported with their line at every level") {
  CHECK(problem_of("schema_version: 1\nshape:\n  kind: circle\n  radius: 3\n") ==
        "shape.radius: unknown key (line 4)");
  CHECK(problem_of("schema_version: 1\ncontrol: {sigma: 1}\n") == "control: unknown key (line 2)");
  CHECK(problem_of("schema_version: 1\nsupervisor:\n  converge:\n    holdd: 3\n") ==
        "supervisor.converge.holdd: unknown key (line 4)");
}

TEST_CASE("duplicate keys are reported") {
  CHECK(problem_of("schema_version: 1\nsim:\n  steps: 5\n  steps: 6\n") ==
        "sim.steps: duplicate key (line 4)");
}

TEST_CASE("wrong types are reported") {
  CHECK(problem_of("schema_version: 1\nswarm:\n  agents: many\n") ==
        "swarm.agents: expected an integer, got \"many\" (line 3)");
  CHECK(problem_of("schema_version: 1\nswarm:\n  agents: 3.5\n") ==
        "swarm.agents: expected an integer, got 3.5 (line 3)");
  CHECK(problem_of("schema_version: 1\nsim: {steps: 1e3}\n") ==
        "sim.steps: expected an integer, got 1e3 (line 2)");
  CHECK(problem_of("schema_version: 1\ndynamics:\n  sigma: big\n") ==
        "dynamics.sigma: expected a number, got \"big\" (line 3)");
  CHECK(problem_of("schema_version: 1\ndynamics:\n  sigma: \"3.5\"\n") ==
        "dynamics.sigma: expected a number, got \"3.5\" (line 3)");
  CHECK(problem_of("schema_version: 1\ndynamics:\n  sigma: [1, 2]\n") ==
        "dynamics.sigma: expected a number, got a list (line 3)");
  CHECK(problem_of("schema_version: 1\ndynamics:\n  sigma:\n") ==
        "dynamics.sigma: expected a number, got null (line 3)");
  CHECK(problem_of("schema_version: 1\nshape:\n  centre: {x: 1, y: 2}\n") ==
        "shape.centre: expected a list of 2 numbers [x1, x2], got a map (line 3)");
  CHECK(problem_of("schema_version: 1\nshape:\n  centre: [1, 2, 3]\n") ==
        "shape.centre: expected a list of 2 numbers [x1, x2], got a list of 3 (line 3)");
  CHECK(problem_of("schema_version: 1\nshape:\n  centre: [1, x]\n") ==
        "shape.centre[1]: expected a number, got \"x\" (line 3)");
  CHECK(problem_of("schema_version: 1\ntracking: {enabled: yes}\n") ==
        "tracking.enabled: expected true or false, got \"yes\" (line 2)");
  CHECK(problem_of("schema_version: 1\nshape: 5\n") == "shape: expected a map, got 5 (line 2)");
  CHECK(problem_of("schema_version: 1\nname: [a, b]\n") ==
        "name: expected a string, got a list (line 2)");
  CHECK(problem_of("schema_version: 1\ntransport:\n  peers: 10.0.0.1\n") ==
        "transport.peers: expected a list of strings, got \"10.0.0.1\" (line 3)");
  CHECK(problem_of("schema_version: 1\ntransport:\n  peers:\n    - 10.0.0.1\n    - {a: 1}\n") ==
        "transport.peers[1]: expected a string, got a map (line 5)");
}

TEST_CASE("unknown names are reported with the allowed ones") {
  CHECK(problem_of("schema_version: 1\nshape:\n  kind: hexagon\n") ==
        "shape.kind: must be one of line, circle, ellipse, square, polar, parametric, implicit, "
        "polygon, got \"hexagon\" (line 3)");
  CHECK(problem_of("schema_version: 1\ndynamics:\n  law: boids\n") ==
        "dynamics.law: must be one of paper, arc, got \"boids\" (line 3)");
  CHECK(problem_of("schema_version: 1\ntracking:\n  path: spiral\n") ==
        "tracking.path: must be one of fixed, line, circle, got \"spiral\" (line 3)");
  CHECK(problem_of("schema_version: 1\nintegration:\n  integrator: rk45\n") ==
        "integration.integrator: must be one of euler, rk4, got \"rk45\" (line 3)");
  CHECK(problem_of("schema_version: 1\ntransport:\n  profile: wan\n") ==
        "transport.profile: must be one of loopback, lan, discovery-server, got \"wan\" (line 3)");
}

TEST_CASE("out-of-range values are reported with the range") {
  const auto one = [](const std::string& section, const std::string& key, const std::string& v) {
    return problem_of("schema_version: 1\n" + section + ":\n  " + key + ": " + v + "\n");
  };
  CHECK(one("dynamics", "sigma", "-1") == "dynamics.sigma: must be > 0, got -1 (line 3)");
  CHECK(one("dynamics", "sigma", "0") == "dynamics.sigma: must be > 0, got 0 (line 3)");
  CHECK(one("dynamics", "beta", "-0.1") == "dynamics.beta: must be >= 0, got -0.1 (line 3)");
  CHECK(one("dynamics", "r", "-1") == "dynamics.r: must be >= 0, got -1 (line 3)");
  CHECK(one("dynamics", "k1", "-1") == "dynamics.k1: must be >= 0, got -1 (line 3)");
  CHECK(one("dynamics", "max_speed", "-2") == "dynamics.max_speed: must be >= 0, got -2 (line 3)");
  CHECK(one("swarm", "agents", "0") == "swarm.agents: must be in 1..10000, got 0 (line 3)");
  // One agent per id 0..kMaxAgentId: 10000 agents fit (the benchmark's largest row), 10001 do not.
  CHECK(load_string("schema_version: 1\nswarm:\n  agents: 10000\n").swarm.agents == 10000);
  CHECK(one("swarm", "agents", "10001") == "swarm.agents: must be in 1..10000, got 10001 (line 3)");
  CHECK(one("swarm", "agents", "99999999999999999999") ==
        "swarm.agents: must be in 1..10000, got 99999999999999999999 (line 3)");
  CHECK(one("swarm", "seed", "-1") == "swarm.seed: must be >= 0, got -1 (line 3)");
  CHECK(one("swarm", "init_half_width", "0") ==
        "swarm.init_half_width: must be > 0, got 0 (line 3)");
  CHECK(one("shape", "r0", "0") == "shape.r0: must be > 0, got 0 (line 3)");
  CHECK(one("shape", "b", "-2") == "shape.b: must be > 0, got -2 (line 3)");
  CHECK(one("tracking", "radius", "-1") == "tracking.radius: must be >= 0, got -1 (line 3)");
  CHECK(one("tracking", "period", "0") == "tracking.period: must be > 0, got 0 (line 3)");
  CHECK(one("integration", "dt", "0") == "integration.dt: must be in (0, 10], got 0 (line 3)");
  CHECK(one("integration", "dt", "10.5") ==
        "integration.dt: must be in (0, 10], got 10.5 (line 3)");
  CHECK(one("sim", "steps", "-1") == "sim.steps: must be in 0..10000000, got -1 (line 3)");
  CHECK(one("sim", "steps", "10000001") ==
        "sim.steps: must be in 0..10000000, got 10000001 (line 3)");
  CHECK(one("agent", "rate_hz", "0") == "agent.rate_hz: must be in (0, 1000], got 0 (line 3)");
  CHECK(one("agent", "rate_hz", "1001") ==
        "agent.rate_hz: must be in (0, 1000], got 1001 (line 3)");
  CHECK(one("agent", "neighbour_timeout_periods", "0.5") ==
        "agent.neighbour_timeout_periods: must be >= 1, got 0.5 (line 3)");
  CHECK(one("agent", "status_rate_hz", "0") == "agent.status_rate_hz: must be in (0, 1000], got 0 (line 3)");
  CHECK(one("supervisor", "metrics_rate_hz", "-10") ==
        "supervisor.metrics_rate_hz: must be in (0, 1000], got -10 (line 3)");
  CHECK(one("supervisor", "agent_timeout_s", "0") ==
        "supervisor.agent_timeout_s: must be > 0, got 0 (line 3)");
  CHECK(one("supervisor", "flush_s", "0") == "supervisor.flush_s: must be > 0, got 0 (line 3)");
  CHECK(one("transport", "domain", "233") ==
        "transport.domain: must be in 0..232, got 233 (line 3)");
  CHECK(one("transport", "max_participants", "0") ==
        "transport.max_participants: must be in 1..230, got 0 (line 3)");
  CHECK(one("transport", "lease_s", "0") == "transport.lease_s: must be > 0, got 0 (line 3)");
  CHECK(one("transport", "socket_buffer_bytes", "-1") ==
        "transport.socket_buffer_bytes: must be in 0..2147483647, got -1 (line 3)");
  CHECK(problem_of("schema_version: 1\nsupervisor:\n  converge:\n    gap_cv_max: 0\n") ==
        "supervisor.converge.gap_cv_max: must be > 0, got 0 (line 4)");
  CHECK(problem_of("schema_version: 1\nsupervisor:\n  converge:\n    hold: -1\n") ==
        "supervisor.converge.hold: must be >= 0, got -1 (line 4)");
}

TEST_CASE("multicast_data is off by default, read as a bool, and needs loopback or lan without peers") {
  CHECK_FALSE(load_string("schema_version: 1\n").transport.multicast_data);
  const Config c = load_string("schema_version: 1\ntransport:\n  multicast_data: true\n");
  CHECK(c.transport.multicast_data);
  CHECK(c.transport.profile == "loopback");
  CHECK(load("", {"transport.multicast_data=true"}).transport.multicast_data);
  CHECK(to_yaml(c).find("multicast_data: true") != std::string::npos);
  CHECK(load_string(to_yaml(c)).transport.multicast_data);
  CHECK(problem_of("schema_version: 1\ntransport:\n  multicast_data: 3\n").find("transport.multicast_data:") == 0);
  CHECK(load_string("schema_version: 1\ntransport:\n  profile: lan\n  multicast_data: true\n")
            .transport.multicast_data);
  CHECK(problem_of("schema_version: 1\ntransport:\n  profile: lan\n  peers: [10.0.0.2]\n  multicast_data: true\n") ==
        "transport.multicast_data: cannot be used with transport.peers (lan with peers sends no multicast at all; "
        "remove the peers for multicast discovery and data), got true (line 5)");
  CHECK(problem_of("schema_version: 1\ntransport:\n  profile: discovery-server\n  discovery_server: 10.0.0.5:11811\n"
                   "  multicast_data: true\n")
            .find("transport.multicast_data: needs") == 0);
  CHECK(load_string("schema_version: 1\ntransport:\n  profile: discovery-server\n  multicast_data: true\n")
            .transport.multicast_data);  // default server 127.0.0.1:11811
}

TEST_CASE("static_edp is off by default, read as a bool, and refused with a discovery server or security") {
  CHECK_FALSE(load_string("schema_version: 1\n").transport.static_edp);
  const Config c = load_string("schema_version: 1\ntransport:\n  static_edp: true\n");
  CHECK(c.transport.static_edp);
  CHECK(load("", {"transport.static_edp=true"}).transport.static_edp);
  CHECK(to_yaml(c).find("static_edp: true") != std::string::npos);
  CHECK(load_string(to_yaml(c)).transport.static_edp);
  CHECK(problem_of("schema_version: 1\ntransport:\n  static_edp: yes please\n").find("transport.static_edp:") == 0);
  CHECK(load_string("schema_version: 1\ntransport:\n  profile: lan\n  peers: [10.0.0.2]\n  static_edp: true\n")
            .transport.static_edp);
  CHECK(load_string("schema_version: 1\ntransport:\n  multicast_data: true\n  static_edp: true\n").transport.static_edp);
  CHECK(problem_of("schema_version: 1\ntransport:\n  profile: discovery-server\n  static_edp: true\n") ==
        "transport.static_edp: cannot be used with transport.profile discovery-server (its clients always use the "
        "server's endpoint discovery; use loopback or lan), got true (line 4)");
  CHECK(problem_of("schema_version: 1\ntransport:\n  static_edp: true\nsecurity:\n  enabled: true\n"
                   "  keystore: /tmp/ks\n")
            .find("transport.static_edp: cannot be used with security.enabled") == 0);
}

TEST_CASE("initial announcements: Fast DDS's defaults, a count and a positive interval") {
  const Config d = load_string("schema_version: 1\n");
  CHECK(d.transport.initial_announcements == 5);
  CHECK(d.transport.initial_announce_s == 0.1);
  const Config c = load("", {"transport.initial_announcements=20", "transport.initial_announce_s=0.25"});
  CHECK(c.transport.initial_announcements == 20);
  CHECK(c.transport.initial_announce_s == 0.25);
  CHECK(load_string(to_yaml(c)).transport.initial_announcements == 20);
  CHECK(problem_of("schema_version: 1\ntransport:\n  initial_announcements: -1\n").find("transport.initial_announcements:") == 0);
  CHECK(problem_of("schema_version: 1\ntransport:\n  initial_announce_s: 0\n").find("transport.initial_announce_s:") == 0);
}

TEST_CASE("transport interfaces and peers are IPv4 addresses") {
  CHECK(problem_of("schema_version: 1\ntransport:\n  interfaces: [192.168.1.2, foo]\n") ==
        "transport.interfaces: must be a list of IPv4 addresses (\"foo\" is not one), got a list (line 3)");
  CHECK(problem_of("schema_version: 1\ntransport:\n  peers: [999.1.1.1]\n").find("transport.peers: must be a list of "
                                                                                 "IPv4 addresses") == 0);
  CHECK(load("", {"transport.peers=[10.0.0.2, 10.0.0.3]"}).transport.peers ==
        std::vector<std::string>{"10.0.0.2", "10.0.0.3"});
}

TEST_CASE("announce_s must be below lease_s") {
  CHECK(problem_of("schema_version: 1\ntransport:\n  lease_s: 1\n  announce_s: 1\n") ==
        "transport.announce_s: must be < transport.lease_s (1), got 1 (line 4)");
  CHECK(problem_of("schema_version: 1\ntransport:\n  lease_s: 0.25\n") ==
        "transport.lease_s: must be > transport.announce_s (0.5), got 0.25 (line 3)");
}

TEST_CASE("discovery_server must be host and port") {
  for (const std::string bad :
       {"localhost", ":11811", "10.0.0.1:0", "10.0.0.1:65536", "10.0.0.1:port", "10.0.0.1:", "server.local:11811",
        "10.0.0:11811", "10.0.0.256:11811", "10..0.1:11811", "10.0.0.1.2:11811"}) {
    INFO(bad);
    CHECK(problem_of("schema_version: 1\ntransport: {discovery_server: \"" + bad + "\"}\n") ==
          "transport.discovery_server: must be host:port with host an IPv4 address or localhost and port "
          "1..65535, got \"" + bad +
              "\" (line 2)");
  }
  CHECK(load_string("schema_version: 1\ntransport: {discovery_server: \"10.1.2.3:65535\"}\n")
            .transport.discovery_server == "10.1.2.3:65535");
  CHECK(load_string("schema_version: 1\ntransport: {discovery_server: \"localhost:11811\"}\n")
            .transport.discovery_server == "localhost:11811");
}

TEST_CASE("every bounded key is checked against the range the table declares") {
  namespace params = core::params;
  int checked = 0;
  for (const auto& p : shapeform::config::config_table()) {
    if ((p.type != params::Type::Real && p.type != params::Type::Integer) || !p.range.bounded() ||
        p.key == "schema_version")
      continue;
    INFO(p.key);
    const params::Range& r = p.range;
    // Just outside the lower end (or the upper one when the range has no lower end).
    const double outside = r.lo != -params::kInf ? (r.lo_open ? r.lo : r.lo - 1) : (r.hi_open ? r.hi : r.hi + 1);
    const std::string text = p.type == params::Type::Integer ? std::to_string(static_cast<long long>(outside))
                                                             : params::format_number(outside);
    CHECK(problem_of("schema_version: 1\n", {p.key + "=" + text}) == p.key + ": " + r.text() + ", got " + text + " (--set)");
    ++checked;
  }
  CHECK(checked >= 30);
  // integration.dt is bounded (0, 10] in the file, as on the command topic and in the console.
  CHECK(problem_of("schema_version: 1\nintegration:\n  dt: 50\n") ==
        "integration.dt: must be in (0, 10], got 50 (line 3)");
}

TEST_CASE("config/default.yaml lists every key of the table") {
  std::ifstream in(kSourceDir + "/config/default.yaml");
  std::stringstream text;
  text << in.rdbuf();
  for (const auto& p : shapeform::config::config_table()) {
    const auto dot = p.key.rfind('.');
    const std::string leaf = dot == std::string::npos ? p.key : p.key.substr(dot + 1);
    INFO(p.key);
    CHECK(text.str().find(leaf + ":") != std::string::npos);
  }
}

TEST_CASE("non-finite numbers are rejected") {
  CHECK(problem_of("schema_version: 1\ndynamics:\n  k1: .nan\n") ==
        "dynamics.k1: must be finite, got .nan (line 3)");
  CHECK(problem_of("schema_version: 1\nshape:\n  m: .inf\n") ==
        "shape.m: must be finite, got .inf (line 3)");
  CHECK(problem_of("schema_version: 1\nshape:\n  c: -.inf\n") ==
        "shape.c: must be finite, got -.inf (line 3)");
  CHECK(problem_of("schema_version: 1\ntracking:\n  phase: 1e999\n") ==
        "tracking.phase: must be finite, got 1e999 (line 3)");
  CHECK(problem_of("schema_version: 1\ntracking:\n  point: [0, .NaN]\n") ==
        "tracking.point[1]: must be finite, got .NaN (line 3)");
  CHECK(problem_of("schema_version: 1\ndynamics:\n  k2: -.nan\n") ==
        "dynamics.k2: must be finite, got -.nan (line 3)");
}

TEST_CASE("schema_version is required in a file and must be 1") {
  CHECK(problem_of("name: x\n") == "schema_version: missing (required, must be 1)");
  CHECK(problem_of("") == "schema_version: missing (required, must be 1)");
  CHECK(problem_of("schema_version: 2\n") == "schema_version: must be 1, got 2 (line 1)");
  CHECK(problem_of("name: x\nschema_version: one\n") ==
        "schema_version: expected an integer, got \"one\" (line 2)");
}

TEST_CASE("a missing or unreadable file is reported") {
  const auto missing = problems_of_load("/nonexistent/shapeform.yaml");
  REQUIRE(missing.size() == 1);
  CHECK(missing[0] ==
        "config file '/nonexistent/shapeform.yaml': cannot open (No such file or directory): give the path of a "
        "YAML config file");
  const auto dir = problems_of_load(kSourceDir + "/config");
  REQUIRE(dir.size() == 1);
  CHECK(dir[0] == "config file '" + kSourceDir +
                      "/config': is a directory, not a regular file: give the path of a YAML config file");
}

TEST_CASE("a config that is not a regular file is refused at once, without reading it") {
  // A device that never ends: reading it used to take 2 GB and abort.
  CHECK(problems_of_load("/dev/zero") ==
        std::vector<std::string>{"config file '/dev/zero': is a character device, not a regular file: give the path "
                                 "of a YAML config file"});
  // A FIFO nobody writes: opening it for reading used to block for ever.
  const std::string fifo = (std::filesystem::temp_directory_path() / "shapeform_config_test.fifo").string();
  std::remove(fifo.c_str());
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  const auto p = problems_of_load(fifo);
  std::remove(fifo.c_str());
  CHECK(p == std::vector<std::string>{"config file '" + fifo +
                                      "': is a FIFO, not a regular file: give the path of a YAML config file"});
}

TEST_CASE("a config file above 1 MiB is refused; one at the limit is read") {
  const TempFile at_limit("schema_version: 1\n#" + std::string(config::kMaxFileBytes - 20, 'x') + "\n");
  REQUIRE(std::filesystem::file_size(at_limit.path) <= config::kMaxFileBytes);
  CHECK_NOTHROW(load(at_limit.path));
  const TempFile big("schema_version: 1\n#" + std::string(config::kMaxFileBytes, 'x') + "\n");
  const auto p = problems_of_load(big.path);
  REQUIRE(p.size() == 1);
  CHECK(p[0] == "config file '" + big.path + "': " + std::to_string(config::kMaxFileBytes + 20) +
                    " bytes, more than the 1048576 (1 MiB) a config may hold: give the path of a YAML config file");
}

TEST_CASE("a second YAML document is an error naming its line") {
  const std::string fix = ": a config holds one document (remove the '---' line and what follows it, or split the file)";
  CHECK(problem_of("schema_version: 1\n---\nname: x\n") ==
        "config file '<string>': a second YAML document starts at line 2" + fix);
  CHECK(problem_of("---\nschema_version: 1\n# note\n---\n") ==
        "config file '<string>': a second YAML document starts at line 4" + fix);
  CHECK(problem_of("schema_version: 1\n...\nname: x\n") ==
        "config file '<string>': a second YAML document starts at line 3" + fix);
  // One document, with its optional start and end markers, is fine.
  CHECK(load_string("%YAML 1.2\n---\nschema_version: 1\nname: x\n...\n").name == "x");
}

TEST_CASE("every rate key has an upper bound") {
  for (const auto& p : config::config_table()) {
    if (p.key.size() < 3 || p.key.compare(p.key.size() - 3, 3, "_hz") != 0) continue;
    INFO(p.key);
    CHECK(p.range.hi <= 1000.0);
    const auto [section, leaf] = std::pair(p.key.substr(0, p.key.find('.')), p.key.substr(p.key.find('.') + 1));
    CHECK(problem_of("schema_version: 1\n" + section + ":\n  " + leaf + ": 1e9\n") ==
          p.key + ": must be in (0, 1000], got 1e9 (line 3)");
    CHECK_NOTHROW(load_string("schema_version: 1\n" + section + ":\n  " + leaf + ": 1000\n"));
  }
}

TEST_CASE("a problem quotes at most about 200 characters of the offending input") {
  const std::string huge(1'000'000, 'q');
  for (const std::string& text : {"schema_version: 1\nname: [" + huge + "]\n",  // a value
                                  "schema_version: 1\n" + huge + ": 1\n",       // a key
                                  "schema_version: 1\nshape:\n  kind: " + huge + "\n"}) {
    const auto p = problems_of(text);
    REQUIRE(p.size() == 1);
    CHECK(p[0].size() <= shapeform::util::kLineMax + 40);
  }
  // A quoted string keeps one escape per special character.
  CHECK(problem_of("schema_version: 1\nagent:\n  rate_hz: \"a\\nb\\\"c\"\n") ==
        "agent.rate_hz: expected a number, got \"a\\nb\\\"c\" (line 3)");
  const auto set = problems_of("schema_version: 1\n", {"agent.rate_hz=" + huge});
  REQUIRE(set.size() == 1);
  CHECK(set[0].size() <= shapeform::util::kLineMax + 40);
  CHECK(set[0].find("agent.rate_hz: expected a number, got \"qqq") == 0);
}

TEST_CASE("a YAML syntax error is reported with its line") {
  const TempFile f("schema_version: 1\nshape:\n  centre: [1, 2\nsim: {steps: 3}\n");
  const auto p = problems_of_load(f.path);
  REQUIRE(p.size() == 1);
  CHECK(p[0] == "config file '" + f.path +
                    "': YAML syntax error at line 4: end of sequence flow not found");
}

TEST_CASE("the top level must be a map") {
  CHECK(problem_of("- 1\n- 2\n") ==
        "config file '<string>': top level must be a map, got a list (line 1)");
}

TEST_CASE("every problem is collected and not only the first") {
  const std::string text = R"(schema_version: 1
swarm:
  agents: many
  colour: red
dynamics:
  sigma: -1
  beta: .nan
shape: {kind: blob, centre: [1]}
transport: {domain: 300}
)";
  const std::vector<std::string> expected = {
      "swarm.colour: unknown key (line 4)",
      "swarm.agents: expected an integer, got \"many\" (line 3)",
      "shape.kind: must be one of line, circle, ellipse, square, polar, parametric, implicit, "
      "polygon, got \"blob\" (line 8)",
      "shape.centre: expected a list of 2 numbers [x1, x2], got a list of 1 (line 8)",
      "dynamics.sigma: must be > 0, got -1 (line 6)",
      "dynamics.beta: must be finite, got .nan (line 7)",
      "transport.domain: must be in 0..232, got 300 (line 9)",
  };
  CHECK(problems_of(text) == expected);
  try {
    load_string(text);
  } catch (const ConfigError& e) {
    std::string joined;
    for (const auto& p : expected) joined += (joined.empty() ? "" : "\n") + p;
    CHECK(std::string(e.what()) == joined);
  }
}

// ----------------------------------------------------------------------------------------------
// --set overrides

TEST_CASE("overrides replace file values and lists in order") {
  const Config c =
      load(scenario("ellipse"), {"dynamics.r=0", "shape.centre=[1, -2]", "shape.kind=square",
                                 "shape.a=3", "shape.a=6", "transport.peers=[10.0.0.2, 10.0.0.3]"});
  CHECK(c.command.gains.r == 0.0);
  require_vec(c.command.shape.centre, 1.0, -2.0);
  CHECK(c.command.shape.kind == core::ShapeKind::Square);
  CHECK(c.command.shape.a == 6.0);
  CHECK(c.transport.peers == std::vector<std::string>{"10.0.0.2", "10.0.0.3"});
  CHECK(c.command.gains.sigma == 3.5);  // untouched keys keep the file's values
  CHECK(c.name == "ellipse");
}

TEST_CASE("overrides work without a file and create missing sections") {
  const Config c = load("", {"tracking.enabled=true", "supervisor.converge.hold=20", "name=run 7"});
  CHECK(c.command.tracking.enabled);
  CHECK(c.supervisor.converge.hold == 20.0);
  CHECK(c.name == "run 7");
  CHECK(load("", {"schema_version=1"}).schema_version == 1);
}

TEST_CASE("an override may replace a whole section") {
  const Config c =
      load_string("schema_version: 1\nswarm: {agents: 5, seed: 9}\n", {"swarm={agents: 3}"});
  CHECK(c.swarm.agents == 3);
  CHECK(c.swarm.seed == 1);
}

TEST_CASE("an override fills a section left empty in the file") {
  CHECK(load_string("schema_version: 1\nshape:\n", {"shape.r0=2"}).command.shape.r0 == 2.0);
}

TEST_CASE("malformed overrides are reported") {
  CHECK(problem_of("schema_version: 1\n", {"shape.radius=3"}) ==
        "--set shape.radius=3: unknown key shape.radius");
  CHECK(problem_of("schema_version: 1\n", {"shape.kind"}) ==
        "--set shape.kind: expected dotted.key=value");
  CHECK(problem_of("schema_version: 1\n", {"=3"}) == "--set =3: expected dotted.key=value");
  CHECK(problem_of("schema_version: 1\n", {"nosuch=1"}) == "--set nosuch=1: unknown key nosuch");
  CHECK(problem_of("schema_version: 1\n", {"shape.centre.x=1"}) ==
        "--set shape.centre.x=1: unknown key shape.centre.x");
  CHECK(problem_of("schema_version: 1\n", {"shape.centre=[1, 2"}) ==
        "--set shape.centre=[1, 2: YAML syntax error: end of sequence flow not found");
}

TEST_CASE("a bad override value is marked --set instead of a line") {
  CHECK(problem_of("schema_version: 1\ndynamics:\n  sigma: 3.5\n", {"dynamics.sigma=-1"}) ==
        "dynamics.sigma: must be > 0, got -1 (--set)");
  CHECK(problem_of("schema_version: 1\n", {"shape.centre=[1]"}) ==
        "shape.centre: expected a list of 2 numbers [x1, x2], got a list of 1 (--set)");
  CHECK(problem_of("schema_version: 1\n", {"swarm={agents: 0}"}) ==
        "swarm.agents: must be in 1..10000, got 0 (--set)");
  const auto p = problems_of_load("", {"swarm.agents=many", "schema_version=2"});
  CHECK(p == std::vector<std::string>{"schema_version: must be 1, got 2 (--set)",
                                      "swarm.agents: expected an integer, got \"many\" (--set)"});
}

TEST_CASE("override problems and file problems are reported together") {
  const auto p = problems_of("schema_version: 1\nshape:\n  r0: -4\n", {"bad", "dynamics.r=-1"});
  CHECK(p == std::vector<std::string>{"--set bad: expected dotted.key=value",
                                      "shape.r0: must be > 0, got -4 (line 3)",
                                      "dynamics.r: must be >= 0, got -1 (--set)"});
}

TEST_CASE("an override does not write through a YAML alias") {
  const Config c = load_string("schema_version: 1\ntracking:\n  point: &p [1, 1]\n  origin: *p\n",
                               {"tracking.point=[2, 2]"});
  require_vec(c.command.tracking.path.point, 2.0, 2.0);
  require_vec(c.command.tracking.path.origin, 1.0, 1.0);
}

// ----------------------------------------------------------------------------------------------
// to_yaml

TEST_CASE("to_yaml of the defaults loads back to the defaults") {
  require_equal(load_string(to_yaml(Config{})), Config{});
}

TEST_CASE("to_yaml round-trips every field") {
  Config c;
  c.name = "true";  // would read back as a boolean if not quoted
  c.swarm.agents = 999;
  c.swarm.seed = 12345678901234567890ULL;
  c.swarm.init_half_width = 0.1 + 0.2;  // not a short decimal: needs every digit
  c.command.shape.kind = core::ShapeKind::Line;
  c.command.shape.m = -1.0 / 3.0;
  c.command.shape.c = 1e-300;
  c.command.shape.r0 = 1e20;
  c.command.shape.a = 7;
  c.command.shape.b = 0.7;
  c.command.shape.centre = core::Vec2(-1.5, 2.25);
  c.command.shape.rotation = -37.5 * kRadPerDeg;  // as the loader computes it from degrees
  c.command.shape.scale = 0.1 + 0.2;
  // Texts YAML would misread unless quoted (the line kind compiles none of them).
  c.command.shape.r_expr = "- 1";
  c.command.shape.x_expr = "#not a comment";
  c.command.shape.y_expr = "true";
  c.command.shape.f_expr = "x: y, [z]";
  c.command.shape.vertices = {core::Vec2(-1.5, 2.0), core::Vec2(1e-300, 1.0 / 3.0)};
  c.command.shape.closed = false;
  c.command.law = core::Law::Arc;
  c.command.arc = {0.75, 0.3, 2.5};
  c.command.tracking.enabled = true;
  c.command.tracking.feedforward = true;
  c.command.tracking.path.kind = core::CentrePath::Kind::Line;
  c.command.tracking.path.point = core::Vec2(-10, -10);
  c.command.tracking.path.velocity = core::Vec2(0.1, 0.1);
  c.command.tracking.path.origin = core::Vec2(3, 4);
  c.command.tracking.path.radius = 0;
  c.command.tracking.path.period = 123.456;
  c.command.tracking.path.phase = 3.141592653589793;
  c.command.gains = {0.01, 3.0, 1.25, 0.0, 0.0};
  c.command.integrator = core::Integrator::RK4;
  c.command.dt = 0.05;
  c.command.max_speed = 1.5;
  c.sim.steps = 10000000;
  c.agent = {200.0, 2.5, 4.0};
  c.supervisor.metrics_rate_hz = 25;
  c.supervisor.target_rate_hz = 100;
  c.supervisor.agent_timeout_s = 2.5;
  c.supervisor.flush_s = 0.25;
  c.supervisor.converge = {0.5, 0.25, 0.2, 12.5};
  c.transport.profile = "discovery-server";
  c.transport.domain = 17;
  c.transport.max_participants = 4;
  c.transport.interfaces = {"127.0.0.1", "10.0.0.1"};
  c.transport.peers = {"10.0.0.2", "192.168.7.1"};
  c.transport.discovery_server = "10.20.30.40:7400";
  c.transport.lease_s = 5;
  c.transport.announce_s = 1;
  c.transport.socket_buffer_bytes = 1 << 20;

  const std::string text = to_yaml(c);
  INFO(text);
  const Config back = load_string(text);
  require_equal(back, c);
  CHECK(to_yaml(back) == text);
}

TEST_CASE("to_yaml round-trips the equation shapes and polygons") {
  for (const std::string name : {"polar_star", "polygon", "implicit", "arc_line"}) {
    INFO(name);
    const Config c = load(scenario(name));
    const std::string text = to_yaml(c);
    INFO(text);
    const Config back = load_string(text);
    require_equal(back, c);
    CHECK(compiled_from_shape(back.command));
    CHECK(to_yaml(back) == text);
  }
  Config c;
  c.command.shape.kind = core::ShapeKind::Parametric;
  c.command.shape.x_expr = "4*cos(2*pi*s)";
  c.command.shape.y_expr = "-2*sin(2*pi*s)";
  c.command.shape.closed = true;
  for (const double deg : {0.0, 30.0, 90.0, -45.0, 359.9, 1e-7, 12345.678}) {
    INFO(deg);
    c.command.shape.rotation = deg * kRadPerDeg;
    const std::string text = to_yaml(c);
    CHECK(text.find("  rotation_deg: ") != std::string::npos);
    require_equal(load_string(text), c);  // the very same radians
  }
  // Degrees written as the user wrote them.
  c.command.shape.rotation = 30.0 * kRadPerDeg;
  CHECK(to_yaml(c).find("  rotation_deg: 30.0\n") != std::string::npos);
  // A rotation not set from degrees comes back within rounding.
  c.command.shape.rotation = 1.0;
  CHECK(load_string(to_yaml(c)).command.shape.rotation == Approx(1.0).epsilon(1e-15));
}

TEST_CASE("to_yaml writes the documented schema") {
  const std::string text = to_yaml(load(scenario("track_line")));
  CHECK(text.rfind("schema_version: 1\nname: track_line\n", 0) == 0);
  CHECK(text.find("  centre: [0.0, 0.0]\n") != std::string::npos);
  CHECK(text.find("  point: [-10.0, -10.0]\n") != std::string::npos);
  CHECK(text.find("  r: 0.1\n") != std::string::npos);
  CHECK(text.find("  interfaces: []\n") != std::string::npos);
  CHECK(text.find("  discovery_server: 127.0.0.1:11811\n") != std::string::npos);
  CHECK(text.find("  rotation_deg: 0.0\n  scale: 1.0\n") != std::string::npos);
  CHECK(text.find("  r_expr: \"\"\n") != std::string::npos);
  CHECK(text.find("  vertices: []\n  closed: true\n") != std::string::npos);
  CHECK(text.find("  law: paper\n  k_normal: 0.5\n  k_tangent: 1.0\n  spacing: 1.0\n") !=
        std::string::npos);
  const std::string poly = to_yaml(load(scenario("polygon")));
  CHECK(poly.find("  vertices: [[-4.0, -3.0], [4.0, -3.0], [4.0, 2.0], [0.0, 5.0], [-4.0, 2.0]]\n") !=
        std::string::npos);
  CHECK(poly.find("  law: arc\n") != std::string::npos);
}

TEST_CASE("a config outside the envelope is refused at the key and line that carry it", "[config][envelope]") {
  CHECK(problems_of("schema_version: 1\ndynamics:\n  k1: 1.0e+300\n") ==
        std::vector<std::string>{"dynamics.k1 = 1e+300: the step gain k1 dt sigma^(-2 beta) is 4.945801632282963e+298, "
                                 "must be <= 10 (a step overshoots its target 9 times over: nothing a formation can "
                                 "follow) (line 3)"});
  const auto centre = problems_of("schema_version: 1\n", {"shape.centre=[1e300, 0]"});
  REQUIRE(centre.size() == 1);
  CHECK(centre[0].rfind("shape.centre = (1e+300, 0): the shape's centre gets 1e+300 units from the origin, outside "
                        "the workspace (safety.workspace = 1000) (--set)",
                        0) == 0);
  // A larger workspace takes the same shape.
  CHECK_NOTHROW(load_string("schema_version: 1\nshape: {centre: [2000, 0]}\nsafety: {workspace: 3000}\n"));
  const auto implicit = problems_of("schema_version: 1\nshape:\n  kind: implicit\n  f_expr: sin(x*50)*sin(y*50)-0.5\n");
  REQUIRE(implicit.size() == 1);
  CHECK(implicit[0].rfind("shape.f_expr: implicit curve: f(x, y) = 0 falls into more than 16 separate pieces", 0) == 0);
}

// ---------------------------------------------------------------------------------------------
// command_settings: a recording's commands.csv

namespace {
std::vector<std::string> as_sets(const std::vector<std::pair<std::string, std::string>>& settings) {
  std::vector<std::string> out;
  for (const auto& [key, value] : settings) out.push_back(key + "=" + value);
  return out;
}

/// Every command field equal, bit for bit (the curve is compiled from the shape, checked apart).
void require_same_command(const core::Command& a, const core::Command& b) {
  for (const auto& p : core::params::command_table()) {
    INFO(p.key);
    CHECK(p.get(a) == p.get(b));
  }
}
}  // namespace

TEST_CASE("command_settings names every command key once, in table order") {
  const auto settings = config::command_settings(Config{}.command);
  const auto& table = core::params::command_table();
  REQUIRE(settings.size() == table.size());
  for (std::size_t i = 0; i < table.size(); ++i) CHECK(settings[i].first == table[i].key);
  const std::vector<std::string> sections = {"shape", "tracking", "dynamics", "integration", "safety"};
  for (const auto& [key, value] : settings) {
    INFO(key);
    CHECK(std::find(sections.begin(), sections.end(), key.substr(0, key.find('.'))) != sections.end());
    CHECK(value.find('\n') == std::string::npos);  // one line each: a --set argument
  }
}

TEST_CASE("command_settings round-trips every shipped scenario's command through --set") {
  for (const auto& entry : std::filesystem::directory_iterator(kSourceDir + "/config/scenarios")) {
    INFO(entry.path().string());
    const Config c = load(entry.path().string());
    const Config back = load("", as_sets(config::command_settings(c.command)));
    require_same_command(c.command, back.command);
    CHECK(compiled_from_shape(back.command));
    CHECK(config::command_settings(back.command) == config::command_settings(c.command));
  }
}

TEST_CASE("config/robots: the robots' scenarios load as docs/ROBOTS.md says (ros2, one law step per tick)") {
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(kSourceDir + "/config/robots")) {
    INFO(entry.path().string());
    const Config c = load(entry.path().string());
    ++files;
    CHECK(c.vehicle_link.ros2());
    CHECK(c.vehicle.max_speed > 0.0);
    CHECK(c.vehicle.seconds_per_model_time * c.agent.rate_hz * c.command.dt == Approx(1.0));
  }
  CHECK(files >= 1);
}

TEST_CASE("command_settings round-trips held commands, rotations, expressions and polygons") {
  const std::vector<std::vector<std::string>> cases = {
      {"dynamics.hold=true", "shape.rotation_deg=33.3", "shape.centre=[0.1, -2]"},
      {"shape.kind=polar", "shape.r_expr=1 + 0.3*cos(3*phi)"},
      {"shape.kind=parametric", "shape.x_expr=cos(2*pi*s)", "shape.y_expr=0.5*sin(2*pi*s)"},
      {"shape.kind=polygon", "shape.vertices=[[0, 0], [2, 0], [1, 1.5]]", "shape.closed=true"},
      {"tracking.enabled=true", "tracking.path=circle", "tracking.radius=2", "tracking.period=100",
       "tracking.phase=0.1", "dynamics.law=arc", "integration.integrator=rk4", "integration.dt=0.5"},
  };
  for (const auto& sets : cases) {
    INFO(sets.front());
    const Config c = load("", sets);
    const Config back = load("", as_sets(config::command_settings(c.command)));
    require_same_command(c.command, back.command);
  }
  const auto settings = config::command_settings(load("", {"dynamics.hold=true"}).command);
  CHECK(std::find(settings.begin(), settings.end(), std::make_pair(std::string("dynamics.hold"), std::string("true"))) !=
        settings.end());
}

TEST_CASE("vehicle keys: the robot's own, read from the file, checked at the key", "[config][vehicle]") {
  const Config d;
  CHECK(d.vehicle.model == core::VehicleModel::Integrator);
  CHECK(core::moves_as_law(d.vehicle));  // the default moves agents as before
  const Config c = load_string(
      "schema_version: 1\nvehicle:\n  model: unicycle\n  steering: linearised\n  max_speed: 0.5\n"
      "  max_yaw_rate: 1.5\n  max_accel: 2\n  offset: 0.3\n  seconds_per_model_time: 0.02\n"
      "  initial_heading_deg: 90\n  heading_spread_deg: 180\n");
  CHECK(c.vehicle.model == core::VehicleModel::Unicycle);
  CHECK(c.vehicle.steering == core::Steering::Linearised);
  CHECK(c.vehicle.max_speed == 0.5);
  CHECK(c.vehicle.max_yaw_rate == 1.5);
  CHECK(c.vehicle.max_accel == 2.0);
  CHECK(c.vehicle.offset == 0.3);
  CHECK(c.vehicle.seconds_per_model_time == 0.02);
  CHECK(c.vehicle.initial_heading == 90 * kRadPerDeg);
  CHECK(c.vehicle.heading_spread == 180 * kRadPerDeg);
  // Not the command's: a vehicle leaves the command (and so the wire) as it was.
  CHECK(shapeform::config::command_settings(c.command) == shapeform::config::command_settings(d.command));
  // to_yaml writes what loads back.
  const Config back = load_string(to_yaml(c));
  CHECK(back.vehicle.initial_heading == c.vehicle.initial_heading);
  CHECK(back.vehicle.model == c.vehicle.model);

  const auto one = [](const std::string& key, const std::string& v) {
    return problem_of("schema_version: 1\nvehicle:\n  " + key + ": " + v + "\n");
  };
  CHECK(one("model", "car") == "vehicle.model: must be one of integrator, double_integrator, unicycle, got \"car\" (line 3)");
  CHECK(one("steering", "pid") == "vehicle.steering: must be one of exact, linearised, got \"pid\" (line 3)");
  CHECK(one("offset", "0") == "vehicle.offset: must be > 0, got 0 (line 3)");
  CHECK(one("max_speed", "-1") == "vehicle.max_speed: must be >= 0, got -1 (line 3)");
  CHECK(one("max_yaw_rate", ".inf") == "vehicle.max_yaw_rate: must be finite, got .inf (line 3)");
  CHECK(one("max_accel", "-0.1") == "vehicle.max_accel: must be >= 0, got -0.1 (line 3)");
  CHECK(one("seconds_per_model_time", "0") == "vehicle.seconds_per_model_time: must be > 0, got 0 (line 3)");
  CHECK(one("heading_spread_deg", "200") == "vehicle.heading_spread_deg: must be in [0, 180], got 200 (line 3)");
  CHECK(one("wheels", "2") == "vehicle.wheels: unknown key (line 3)");
  CHECK(problem_of("schema_version: 1\n", {"vehicle.model=Unicycle"}) ==
        "vehicle.model: must be one of integrator, double_integrator, unicycle, got \"Unicycle\" (--set)");
}

TEST_CASE("vehicle.interface ros2: what it needs of the other keys, each refused at its key with the fix",
          "[config][vehicle][ros2]") {
  const Config d;
  CHECK(d.vehicle_link.interface == config::VehicleLink::Interface::Internal);
  CHECK_FALSE(d.vehicle_link.ros2());
  const std::string ros2 = "schema_version: 1\nvehicle:\n  interface: ros2\n";
  // max_speed left at its default 0: a robot has a top speed.
  CHECK(problem_of(ros2) ==
        "vehicle.max_speed: must be > 0 with vehicle.interface: ros2 (a robot has a top speed: commands are "
        "held to "
        "it and a pose that moves faster is refused), got 0");
  // ... or given as 0: at its line, its value said once.
  CHECK(problem_of(ros2 + "  max_speed: 0\n") ==
        "vehicle.max_speed: must be > 0 with vehicle.interface: ros2 (a robot has a top speed: commands are "
        "held to "
        "it and a pose that moves faster is refused), got 0 (line 4)");
  CHECK(problem_of("schema_version: 1\n", {"vehicle.interface=ros2", "vehicle.max_speed=0"}) ==
        "vehicle.max_speed: must be > 0 with vehicle.interface: ros2 (a robot has a top speed: commands are "
        "held to "
        "it and a pose that moves faster is refused), got 0 (--set)");
  const Config ok = load_string(ros2 + "  max_speed: 1.5\n");
  CHECK(ok.vehicle_link.ros2());
  CHECK(ok.vehicle.max_speed == 1.5);
  // Lockstep: a robot moves in real time.
  CHECK(problem_of(ros2 + "  max_speed: 1\nagent:\n  sync: lockstep\n") ==
        "agent.sync: must be free with vehicle.interface: ros2 (a robot moves in real time: it cannot wait "
        "for its "
        "neighbours' steps), got \"lockstep\" (line 6)");
  // Static endpoint discovery: a ROS 2 robot announces its topics by simple discovery.
  CHECK(problem_of(ros2 + "  max_speed: 1\n", {"transport.static_edp=true"}) ==
        "transport.static_edp: must be false with vehicle.interface: ros2 (a ROS 2 robot announces its "
        "topics by "
        "simple discovery), got true (--set)");
  // All three at once: every one reported.
  const auto all = problems_of(
      "schema_version: 1\n", {"vehicle.interface=ros2", "agent.sync=lockstep", "transport.static_edp=true"});
  REQUIRE(all.size() == 3);
  CHECK(all[0].rfind("vehicle.max_speed: must be > 0 with vehicle.interface: ros2", 0) == 0);
  CHECK(all[1].rfind("agent.sync: must be free with vehicle.interface: ros2", 0) == 0);
  CHECK(all[2].rfind("transport.static_edp: must be false with vehicle.interface: ros2", 0) == 0);
  // The internal vehicle needs none of it.
  CHECK_NOTHROW(load_string("schema_version: 1\n", {"agent.sync=lockstep", "transport.static_edp=true"}));
}

TEST_CASE("vehicle.namespace and the topic names: ROS 2 names, checked whatever the interface",
          "[config][vehicle][ros2]") {
  const auto ns = [](const std::string& v) {
    return problem_of("schema_version: 1\nvehicle:\n  namespace: '" + v + "'\n");
  };
  const std::string rule =
      "vehicle.namespace: must be letters, digits, '_' and '/' with {id} (each agent drives its own robot: "
      "robot_{id})";
  CHECK(ns("robot") == rule + ", got \"robot\" (line 3)");            // every agent on one robot
  CHECK(ns("robot-{id}") == rule + ", got \"robot-{id}\" (line 3)");  // '-' is not in a ROS 2 name
  CHECK(ns("robot {id}") == rule + ", got \"robot {id}\" (line 3)");
  CHECK(ns("robot_{id}/") == rule + ", got \"robot_{id}/\" (line 3)");
  CHECK(ns("fleet//robot_{id}") == rule + ", got \"fleet//robot_{id}\" (line 3)");
  CHECK(ns("robot_{ID}") == rule + ", got \"robot_{ID}\" (line 3)");
  CHECK(ns("") == rule + ", got \"\" (line 3)");
  CHECK(problem_of("schema_version: 1\n", {"vehicle.namespace=r.{id}"}) == rule + ", got \"r.{id}\" (--set)");
  for (const std::string good : {"robot_{id}", "fleet_a/robot_{id}", "{id}_bot", "/robot_{id}", "r{id}_{id}"})
    CHECK(load_string("schema_version: 1\nvehicle:\n  namespace: '" + good + "'\n").vehicle_link.ns == good);

  const auto topic = [](const std::string& key, const std::string& v) {
    return problem_of("schema_version: 1\nvehicle:\n  " + key + ": '" + v + "'\n");
  };
  for (const std::string key : {"cmd_topic", "pose_topic"}) {
    const std::string rule_of =
        "vehicle." + key + ": must be a ROS 2 topic name (letters, digits, '_' and '/', {id} for the agent's id)";
    CHECK(topic(key, "cmd vel") == rule_of + ", got \"cmd vel\" (line 3)");
    CHECK(topic(key, "odom!") == rule_of + ", got \"odom!\" (line 3)");
    CHECK(topic(key, "a//b") == rule_of + ", got \"a//b\" (line 3)");
    CHECK(topic(key, "odom/") == rule_of + ", got \"odom/\" (line 3)");
    CHECK(topic(key, "/") == rule_of + ", got \"/\" (line 3)");
    CHECK(topic(key, "") == rule_of + ", got \"\" (line 3)");
    CHECK(topic(key, "{ID}/odom") == rule_of + ", got \"{ID}/odom\" (line 3)");
    for (const std::string good : {"cmd_vel", "/diff_drive/odom", "base/odom_1", "/vrpn_mocap/robot_{id}/pose"})
      CHECK_NOTHROW(load_string("schema_version: 1\n", {"vehicle." + key + "=" + good}));
  }
  CHECK(problem_of("schema_version: 1\nvehicle:\n  frame: ''\n") ==
        "vehicle.frame: must name the swarm's frame (map, world, ...), got \"\" (line 3)");
  CHECK(problem_of("schema_version: 1\nvehicle_sim:\n  child_frame: ''\n") ==
        "vehicle_sim.child_frame: must name the robot's frame, got \"\" (line 3)");
}

TEST_CASE("VehicleLink::namespace_of replaces every {id} by the id", "[config][vehicle][ros2]") {
  config::VehicleLink v;
  CHECK(v.namespace_of(3) == "robot_3");
  CHECK(v.namespace_of(0) == "robot_0");
  CHECK(v.namespace_of(9999) == "robot_9999");
  v.ns = "fleet_{id}/robot_{id}";
  CHECK(v.namespace_of(12) == "fleet_12/robot_12");
  v.ns = "{id}{id}{id}";
  CHECK(v.namespace_of(7) == "777");
  CHECK(v.namespace_of(10) == "101010");
  v.ns = "r{id}_{i}";
  CHECK(v.namespace_of(5) == "r5_{i}");
  // ROS 2 namespaces are absolute: a leading '/' names the same one (its topics rt/robot_4/...).
  v.ns = "/robot_{id}";
  CHECK(v.namespace_of(4) == "robot_4");
  // From the file.
  const Config c = load_string("schema_version: 1\nvehicle:\n  namespace: 'site_b/bot_{id}'\n");
  CHECK(c.vehicle_link.namespace_of(21) == "site_b/bot_21");
}

TEST_CASE("safety.min_separation and safety.keep_out: read, written back, and refused naming the key, the value "
          "and the line",
          "[config][safety]") {
  CHECK(load_string("schema_version: 1\n").command.min_separation == 0.0);
  CHECK(load_string("schema_version: 1\n").command.keep_out.empty());
  const Config c = load_string(R"(schema_version: 1
safety:
  min_separation: 0.25
  keep_out: [{polygon: [[0, 0], [1, 0], [0, 1]]}, {circle: [5, 0, 1.5]}]
)");
  CHECK(c.command.min_separation == 0.25);
  REQUIRE(c.command.keep_out.size() == 2);
  // circles first, as they travel on the wire
  CHECK(c.command.keep_out[0].kind == shapeform::core::KeepOutZone::Kind::Circle);
  CHECK(c.command.keep_out[0].centre == shapeform::core::Vec2(5, 0));
  CHECK(c.command.keep_out[0].radius == 1.5);
  CHECK(c.command.keep_out[1].vertices.size() == 3);
  CHECK(load_string(to_yaml(c)).command.keep_out == c.command.keep_out);
  CHECK(load("", {"safety.keep_out=[{circle: [1, 2, 3]}]"}).command.keep_out.size() == 1);
  CHECK(problem_of("schema_version: 1\nsafety:\n  min_separation: -1\n") ==
        "safety.min_separation: must be >= 0, got -1 (line 3)");
  CHECK(problem_of("schema_version: 1\nsafety:\n  keep_out: [{circle: [0, 0, 0]}]\n") ==
        "safety.keep_out[0].circle[2]: must be > 0, got 0 (line 3)");
  CHECK(problem_of("schema_version: 1\nsafety:\n  keep_out: [{circle: [0, 0]}]\n") ==
        "safety.keep_out[0].circle: expected [cx, cy, r] (centre and radius), got a list (line 3)");
  CHECK(problem_of("schema_version: 1\nsafety:\n  keep_out: [{square: [0, 0]}]\n") ==
        "safety.keep_out[0]: unknown zone \"square\", expected {circle: [cx, cy, r]} or {polygon: [[x, y], ...]}, "
        "got \"square\" (line 3)");
  CHECK(problem_of("schema_version: 1\nsafety:\n  keep_out: [{polygon: [[0, 0], [1, 1], [1, 0], [0, 1]]}]\n") ==
        "safety.keep_out[0].polygon: polygon edges 0 and 2 cross (the polygon must be simple), got a list (line 3)");
  CHECK(problem_of("schema_version: 1\nsafety:\n  keep_out: {circle: [0, 0, 1]}\n") ==
        "safety.keep_out: expected a list of zones, got a map (line 3)");
}

TEST_CASE(
    "safety.fence, safety.fence_margin and safety.breach_action: read, written back, and refused naming the "
    "key, the value, the fix and the line",
    "[config][safety]") {
  using shapeform::core::BreachAction;
  using shapeform::core::Vec2;
  const Config d = load_string("schema_version: 1\n");
  CHECK(d.command.fence.empty());  // the workspace box
  CHECK(d.command.fence_margin == 0.0);
  CHECK(d.command.breach_action == BreachAction::Hold);
  const Config c = load_string(R"(schema_version: 1
safety:
  fence: [[-8, -8], [8, -8], [8, 6], [0, 9], [-8, 6]]
  fence_margin: 0.5
  breach_action: return
)");
  REQUIRE(c.command.fence.size() == 5);
  CHECK(c.command.fence[3] == Vec2(0, 9));
  CHECK(c.command.fence_margin == 0.5);
  CHECK(c.command.breach_action == BreachAction::Return);
  const Config back = load_string(to_yaml(c));
  CHECK(back.command.fence == c.command.fence);
  CHECK(back.command.fence_margin == 0.5);
  CHECK(back.command.breach_action == BreachAction::Return);
  CHECK(load("", {"safety.fence=[[0, 0], [1, 0], [0, 1]]", "safety.breach_action=stop"})
            .command.breach_action == BreachAction::Stop);
  CHECK(problem_of("schema_version: 1\nsafety:\n  fence_margin: -1\n") ==
        "safety.fence_margin: must be >= 0, got -1 (line 3)");
  CHECK_THAT(problem_of("schema_version: 1\nsafety:\n  breach_action: land\n"),
             Catch::StartsWith("safety.breach_action: ") && Catch::Contains("land") &&
                 Catch::Contains("hold") && Catch::Contains("return"));
  // Not convex: the key, the value and the fix.
  CHECK(
      problem_of("schema_version: 1\nsafety:\n  fence: [[0, 0], [4, 0], [4, 1], [1, 1], [1, 4], [0, 4]]\n") ==
      "safety.fence = [[0, 0], [4, 0], [4, 1], [1, 1], [1, 4], [0, 4]]: a fence must be convex (it turns "
      "back at "
      "vertex 3); cut the rest out with safety.keep_out (line 3)");
  CHECK(
      problem_of("schema_version: 1\nsafety:\n  fence: [[0, 0], [1, 1], [1, 0], [0, 1]]\n") ==
      "safety.fence = [[0, 0], [1, 1], [1, 0], [0, 1]]: fence edges 0 and 2 cross (the fence must be simple) "
      "(line 3)");
  CHECK(problem_of("schema_version: 1\nsafety:\n  fence: [[0, 0], [1, 0]]\n") ==
        "safety.fence = [[0, 0], [1, 0]]: fence needs >= 3 vertices, got 2 (line 3)");
  // The whole envelope: a fence inside the workspace.
  CHECK(problem_of("schema_version: 1\nsafety:\n  workspace: 10\n  fence: [[0, 0], [20, 0], [0, 5]]\n") ==
        "safety.fence = [[0, 0], [20, 0], [0, 5]]: fence vertex 1 (20, 0) is outside the workspace [-w, w]^2 "
        "(safety.workspace = 10): move it in or widen safety.workspace (line 4)");
}
