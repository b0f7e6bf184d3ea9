#include "core/envelope.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <string>

#include "core/law.hpp"

using namespace shapeform::core;

namespace {
/// The problems' texts, one string.
std::string problems_of(const CompiledCommand& c) { return envelope_text(envelope_problems(c)); }
/// The keys of the problems, one string ("dynamics.k1 shape.centre").
std::string keys_of(const CompiledCommand& c) {
  std::string s;
  for (const auto& p : envelope_problems(c)) s += (s.empty() ? "" : " ") + p.key;
  return s;
}
CompiledCommand circle(double r0 = 4.0, Vec2 centre = Vec2::Zero()) {
  Command c;
  c.shape.r0 = r0;
  c.shape.centre = centre;
  return compile(c);
}
}  // namespace

TEST_CASE("envelope: the defaults and the paper's scenarios are inside it", "[envelope]") {
  CHECK(envelope_problems(CompiledCommand()).empty());
  CHECK(envelope_problems(circle(4.0, Vec2(30, -20))).empty());
  Command sq;
  sq.shape.kind = ShapeKind::Square;
  sq.shape.a = 5;
  CHECK(envelope_problems(compile(sq)).empty());
  Command line;
  line.shape.kind = ShapeKind::Line;  // m = -1, c = 5: its foot is 3.5 from the origin
  CHECK(envelope_problems(compile(line)).empty());
}

TEST_CASE("envelope: a shape placed or sized out of the workspace is refused, naming key and value",
          "[envelope]") {
  // The centre of the finding: `shape circle r=4 cx=1e300` (its norm would overflow: still named).
  const CompiledCommand far = circle(4.0, Vec2(1e300, 0));
  CHECK(keys_of(far) == "shape.centre");
  CHECK(problems_of(far).rfind(
            "shape.centre = (1e+300, 0): the shape's centre gets 1e+300 units from the origin, "
            "outside the workspace (safety.workspace = 1000)",
            0) == 0);
  // Inside by its centre, outside by its reach: the radius is named, or the scale when scaled.
  CHECK(keys_of(circle(4.0, Vec2(997, 0))) == "shape.r0");
  CHECK(problems_of(circle(4.0, Vec2(997, 0))).find("shape.r0 = 4: the shape reaches 1001 units") == 0);
  CompiledCommand big = circle(4.0);
  big.shape.scale = 300;  // reach 1200
  CHECK(keys_of(big) == "shape.scale");
  // The square's reach is its corner (a sqrt 2), not its half side.
  Command sq;
  sq.shape.kind = ShapeKind::Square;
  sq.shape.a = 800;
  CHECK(keys_of(compile(sq)) == "shape.a");
  sq.shape.a = 700;  // corner at 990
  CHECK(envelope_problems(compile(sq)).empty());
  // A smaller workspace refuses what the default accepts; a larger one accepts it.
  CompiledCommand c = circle(4.0, Vec2(30, 0));
  c.workspace = 20;
  CHECK(keys_of(c) == "shape.centre");
  c = circle(4.0, Vec2(997, 0));
  c.workspace = 2000;
  CHECK(envelope_problems(c).empty());
}

TEST_CASE("envelope: a tracked path must stay inside the workspace", "[envelope]") {
  CompiledCommand c = circle();
  c.tracking.enabled = true;
  c.tracking.path.kind = CentrePath::Kind::Circle;
  c.tracking.path.origin = Vec2(900, 0);
  c.tracking.path.radius = 50;  // the centre gets 950 out, the circle 954: inside
  CHECK(envelope_problems(c).empty());
  c.tracking.path.radius = 100;  // the centre at the edge, the circle 4 beyond
  CHECK(keys_of(c) == "shape.r0");
  c.tracking.path.origin = Vec2(990, 0);
  CHECK(keys_of(c) == "tracking.origin");
  CHECK(problems_of(c).find("tracking.origin = (990, 0) with tracking.radius = 100: ") == 0);
  c.tracking.path.kind = CentrePath::Kind::Line;  // judged at C(0): the clamp stops it at the edge later
  c.tracking.path.point = Vec2(0, -2000);
  c.tracking.path.velocity = Vec2(0, 1);
  CHECK(keys_of(c) == "tracking.point");
  c.tracking.path.point = Vec2(0, 0);
  CHECK(envelope_problems(c).empty());
}

TEST_CASE("envelope: gains whose steps overshoot without bound are refused", "[envelope]") {
  CompiledCommand c;
  c.gains.k1 = 1e300;
  CHECK(keys_of(c) == "dynamics.k1");
  CHECK(problems_of(c).rfind("dynamics.k1 = 1e+300: the step gain k1 dt sigma^(-2 beta) is ", 0) == 0);
  c = CompiledCommand();
  c.gains.k2 = 1e300;
  CHECK(keys_of(c) == "dynamics.k2");
  // The bound: k2 dt sigma^(-2 beta) <= 10 with a speed limit, <= 2 without one.
  c = CompiledCommand();
  c.gains.sigma = 1;
  c.gains.beta = 0;
  c.gains.k2 = 10;
  CHECK(envelope_problems(c).empty());
  c.gains.k2 = 10.5;
  CHECK(keys_of(c) == "dynamics.k2");
  c.gains.k2 = 3;
  CHECK(envelope_problems(c).empty());
  c.max_speed = 0;
  CHECK(keys_of(c) == "dynamics.k2");
  CHECK(problems_of(c).find("must be <= 2 without a speed limit") != std::string::npos);
  c.gains.k2 = 2;
  c.dt = 0.5;  // the step gain scales with dt
  c.gains.k2 = 4;
  CHECK(envelope_problems(c).empty());
  // A zero gain is off, whatever sigma^(-2 beta) is.
  c = CompiledCommand();
  c.gains.k1 = 0;
  c.gains.sigma = 1e-200;
  c.gains.beta = 10;
  CHECK(keys_of(c) == "dynamics.k2");
  // The arc law: k_normal dt.
  c = CompiledCommand();
  c.law = Law::Arc;
  c.gains.k1 = 1e300;  // unused by the arc law
  c.arc.k_normal = 10;
  c.dt = 1.5;
  CHECK(keys_of(c) == "dynamics.k_normal");
}

TEST_CASE("agent_step never leaves the workspace, and a swarm at its edge comes back", "[envelope][law]") {
  CompiledCommand c = circle();
  c.max_speed = 0;   // let the law take as large a step as it likes
  c.gains.k2 = 1e6;  // outside the envelope: as if it had been accepted
  c.workspace = 50;
  Vec2 x(3, 1);
  int clamped = 0;
  for (int k = 0; k < 40; ++k) {
    const StepResult r = agent_step(c, 0, x, {}, k);
    CHECK(std::abs(r.x.x()) <= 50);
    CHECK(std::abs(r.x.y()) <= 50);
    CHECK(r.v.allFinite());
    clamped += r.clamped ? 1 : 0;
    x = r.x;
  }
  CHECK(clamped > 0);
  // A step that is not finite is not taken.
  CompiledCommand inf = circle();
  inf.gains.k2 = 1e308;
  inf.gains.sigma = 0.01;
  inf.gains.beta = 10;  // K(0.1) = 1e20: the velocity overflows
  inf.max_speed = 0;
  const StepResult r = agent_step(inf, 0, Vec2(4.1, 0), {}, 0);
  CHECK(r.clamped);
  CHECK(r.x == Vec2(4.1, 0));
  CHECK(r.v == Vec2::Zero());
  // Commanded back (the default gains), an agent held at the corner returns to the circle (the
  // paper's attraction fades as d^(1 - 2 beta): from a near corner, so that the test stays short).
  CompiledCommand back = circle();
  back.workspace = 10;
  x = Vec2(10, 10);
  for (int k = 0; k < 3000; ++k) x = agent_step(back, 0, x, {}, k).x;
  CHECK(std::abs(x.norm() - 4.0) < 0.5);
}

TEST_CASE("a default speed limit that binds in no paper scenario", "[envelope]") {
  CHECK(Command().max_speed == 10.0);
  CHECK(Command().workspace == 1000.0);
  CHECK(Command().workspace <= kWorkspaceMax);
}
