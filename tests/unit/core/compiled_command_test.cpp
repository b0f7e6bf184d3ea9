// A compiled command: the plain command and the curve compiled once from its shape.
#include <catch2/catch.hpp>
#include <cmath>
#include <stdexcept>

#include "core/compiled_command.hpp"

using namespace shapeform::core;

TEST_CASE("the default compiled command is the default command with its circle", "[compiled]") {
  const CompiledCommand c;
  const Command plain;
  CHECK(c.shape.kind == plain.shape.kind);
  CHECK(c.shape.r0 == plain.shape.r0);
  CHECK(c.curve().closed());
  CHECK(c.curve().length() == Approx(2 * M_PI * plain.shape.r0));
}

TEST_CASE("compile keeps every field of the command and builds its shape's curve", "[compiled]") {
  Command cmd;
  cmd.shape.kind = ShapeKind::Polygon;
  cmd.shape.vertices = {Vec2(0, 0), Vec2(4, 0), Vec2(4, 3)};
  cmd.gains.k2 = 3.0;
  cmd.law = Law::Arc;
  cmd.dt = 0.5;
  cmd.max_speed = 0.2;
  const CompiledCommand c = compile(cmd);
  CHECK(c.shape.vertices == cmd.shape.vertices);
  CHECK(c.gains.k2 == 3.0);
  CHECK(c.law == Law::Arc);
  CHECK(c.dt == 0.5);
  CHECK(c.max_speed == 0.2);
  CHECK(c.curve().length() == Approx(12.0));
  // Copies share the curve; a new placement keeps it right (it is in the shape's local frame).
  CompiledCommand moved = c;
  CHECK(&moved.curve() == &c.curve());
  moved.shape.centre = Vec2(10, 0);
  CHECK((target_point(moved.shape, moved.curve(), Vec2(12, -1)) - Vec2(12, 0)).norm() < 1e-12);
}

TEST_CASE("compile refuses what core cannot build", "[compiled]") {
  Command bad;
  bad.shape.r0 = -1;
  CHECK_THROWS_AS(compile(bad), ShapeError);
  Command polar;
  polar.shape.kind = ShapeKind::Polar;
  polar.shape.r_expr = "4";
  CHECK_THROWS_WITH(compile(polar), Catch::Contains("shapes::compile"));
  CHECK_THROWS_AS(CompiledCommand(Command{}, nullptr), std::invalid_argument);
}
