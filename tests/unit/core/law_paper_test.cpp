#include <catch2/catch.hpp>
#include <cmath>

#include "core/law.hpp"
#include "core/law_paper.hpp"

using namespace shapeform::core;

namespace {
double kernel(double d2, const Gains& g) { return std::pow(g.sigma * g.sigma + d2, -g.beta); }
}  // namespace

TEST_CASE("cohesion term is the paper's foraging sum", "[law]") {
  Gains g;
  const Vec2 xi(1, 2);
  const std::vector<Neighbour> nbrs = {{1, Vec2(4, 6)}, {2, Vec2(-2, 2)}};
  const Vec2 d1 = Vec2(3, 4), d2 = Vec2(-3, 0);
  const Vec2 expected = 0.1 * (d1 * kernel(25, g) + d2 * kernel(9, g));
  CHECK((cohesion_term(xi, nbrs, g) - expected).norm() < 1e-15);
  // Linear in k1, zero with no neighbours.
  g.k1 = 0.3;
  CHECK((cohesion_term(xi, nbrs, g) - 3 * expected).norm() < 1e-14);
  CHECK(cohesion_term(xi, {}, g).norm() == 0.0);
}

TEST_CASE("attraction term pulls toward the target with the paper's kernel", "[law]") {
  Gains g;
  const Vec2 xi(0, 0), xt(3, 4);
  CHECK((attraction_term(xi, xt, g) - 2.0 * kernel(25, g) * xt).norm() < 1e-15);
  CHECK(attraction_term(xt, xt, g).norm() == 0.0);
  // Its magnitude k2 d / (sigma^2 + d^2)^beta peaks and then decays for beta > 1/2.
  const double near = attraction_term(Vec2(0, 0), Vec2(3, 0), g).norm();
  const double far = attraction_term(Vec2(0, 0), Vec2(300, 0), g).norm();
  CHECK(far < near);
}

TEST_CASE("repulsion: magnitude r, away from the nearest neighbour", "[law]") {
  Gains g;
  const Vec2 xi(0, 0);
  const std::vector<Neighbour> nbrs = {{5, Vec2(3, 0)}, {6, Vec2(0, -1)}, {7, Vec2(10, 10)}};
  REQUIRE(nearest_neighbour(xi, nbrs) == 1);
  const Vec2 rep = repulsion_term(0, xi, nbrs, g);
  CHECK((rep - Vec2(0, 0.1)).norm() < 1e-15);
  g.r = 0;
  CHECK(repulsion_term(0, xi, nbrs, g).norm() == 0.0);
}

TEST_CASE("nearest-neighbour ties go to the lowest agent id", "[law]") {
  const Vec2 xi(0, 0);
  const std::vector<Neighbour> nbrs = {{9, Vec2(1, 0)}, {4, Vec2(0, 1)}, {6, Vec2(-1, 0)}};
  REQUIRE(nearest_neighbour(xi, nbrs) == 1);  // id 4
  const Vec2 rep = repulsion_term(0, xi, nbrs, Gains{});
  CHECK((rep - Vec2(0, -0.1)).norm() < 1e-15);
  CHECK(nearest_neighbour(xi, {}) == -1);
}

TEST_CASE("coincident agents separate along distinct deterministic directions", "[law][singular]") {
  Gains g;
  const Vec2 p(1, 1);
  for (int a = 0; a < 50; ++a)
    for (int b = a + 1; b < 50; ++b) {
      const Vec2 va = repulsion_term(a, p, {{b, p}}, g);
      const Vec2 vb = repulsion_term(b, p, {{a, p}}, g);
      REQUIRE(std::isfinite(va.norm()));
      CHECK(va.norm() == Approx(g.r));
      CHECK((va - vb).norm() > 1e-3);  // they move apart
    }
  CHECK((escape_direction(3) - escape_direction(3)).norm() == 0.0);
  // Two coincident agents in a full step end up apart, and nothing is NaN.
  const CompiledCommand cmd;
  const std::vector<Neighbour> to_b = {{1, p}}, to_a = {{0, p}};
  const Vec2 a1 = agent_step(cmd, 0, p, to_b, 0).x;
  const Vec2 b1 = agent_step(cmd, 1, p, to_a, 0).x;
  CHECK(std::isfinite(a1.norm()));
  CHECK((a1 - b1).norm() > 0.05);
}

TEST_CASE("the law is the sum of its three terms; N = 1 has no neighbour terms", "[law]") {
  Gains g;
  const Vec2 xi(0.3, -1.2), xt(4, 0);
  const std::vector<Neighbour> nbrs = {{1, Vec2(2, 2)}, {2, Vec2(-1, 0.5)}};
  const Vec2 sum = cohesion_term(xi, nbrs, g) + attraction_term(xi, xt, g) + repulsion_term(0, xi, nbrs, g);
  CHECK((paper_velocity(0, xi, nbrs, xt, g) - sum).norm() < 1e-15);
  CHECK((paper_velocity(0, xi, {}, xt, g) - attraction_term(xi, xt, g)).norm() == 0.0);
}
