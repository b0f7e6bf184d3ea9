// The geofence (core/fence.hpp): its problems, how far a point is beyond it, the point an agent returns
// to, and its half-planes shrunk by the margin.
#include "core/fence.hpp"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <string>

#include "core/safety.hpp"

using namespace shapeform::core;

namespace {

/// The problems joined, for matching.
std::string problems(const std::vector<Vec2>& fence, double workspace = 1000.0) {
  std::string s;
  for (const std::string& p : fence_problems(fence, workspace)) s += p + "; ";
  return s;
}

Command fenced(std::vector<Vec2> fence, double margin = 0.0) {
  Command c;
  c.fence = std::move(fence);
  c.fence_margin = margin;
  return c;
}

/// A pentagon, counter-clockwise.
const std::vector<Vec2> kPentagon = {Vec2(-4, -3), Vec2(3, -4), Vec2(5, 1), Vec2(0, 5), Vec2(-5, 2)};

Vec2 random_vec(std::mt19937_64& rng, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  const double a = u(rng);
  const double b = u(rng);
  return {a, b};
}

bool in_half_planes(const std::vector<HalfPlane>& hs, const Vec2& p, double tol) {
  return std::all_of(hs.begin(), hs.end(), [&](const HalfPlane& h) { return h.contains(p, tol); });
}

}  // namespace

TEST_CASE("fence: a usable fence has no problems, either way round", "[fence]") {
  CHECK(fence_problems({}, 1000.0).empty());  // the workspace box
  CHECK(fence_problems(kPentagon, 1000.0).empty());
  std::vector<Vec2> clockwise = kPentagon;
  std::reverse(clockwise.begin(), clockwise.end());
  CHECK(fence_problems(clockwise, 1000.0).empty());
  // A vertex on the straight line between its neighbours is a straight corner, not a dent.
  CHECK(fence_problems({Vec2(0, 0), Vec2(1, 0), Vec2(2, 0), Vec2(2, 2)}, 1000.0).empty());
  // On the workspace's edge is inside it.
  CHECK(fence_problems({Vec2(-10, -10), Vec2(10, -10), Vec2(0, 10)}, 10.0).empty());
}

TEST_CASE("fence: fence_problems names what is wrong, in words an operator can act on", "[fence]") {
  CHECK_THAT(problems({Vec2(0, 0), Vec2(1, 0)}), Catch::Contains("fence needs >= 3 vertices, got 2"));
  CHECK_THAT(problems({Vec2(0, 0), Vec2(1, NAN), Vec2(0, 1)}),
             Catch::Contains("fence vertices must be finite"));
  CHECK_THAT(problems({Vec2(0, 0), Vec2(0, 0), Vec2(1, 0), Vec2(0, 1)}),
             Catch::Contains("fence vertices 0 and 1 are equal"));
  CHECK_THAT(problems({Vec2(0, 0), Vec2(1, 1), Vec2(2, 2)}), Catch::Contains("all on one line"));
  CHECK_THAT(problems({Vec2(0, 0), Vec2(1, 1), Vec2(1, 0), Vec2(0, 1)}),
             Catch::Contains("fence edges 0 and 2 cross (the fence must be simple)"));
  // An L: simple, but not convex.
  const std::vector<Vec2> l = {Vec2(0, 0), Vec2(4, 0), Vec2(4, 1), Vec2(1, 1), Vec2(1, 4), Vec2(0, 4)};
  CHECK_THAT(problems(l), Catch::Contains("a fence must be convex") && Catch::Contains("safety.keep_out"));
  CHECK(fence_problems(l, 1000.0).size() == 1);
  // A spike that doubles back along its edge.
  CHECK_THAT(problems({Vec2(0, 0), Vec2(2, 0), Vec2(1, 0), Vec2(1, 2)}), !Catch::Equals(""));
  // Inside the workspace box, every vertex.
  CHECK(
      problems(kPentagon, 4.5) ==
      "fence vertices 2 (5, 1), 3 (0, 5), 4 (-5, 2) are outside the workspace [-w, w]^2 (safety.workspace = "
      "4.5): move them in or widen safety.workspace; ");
  CHECK(problems({Vec2(-1, -1), Vec2(1, -1), Vec2(0, 6)}, 5.0) ==
        "fence vertex 2 (0, 6) is outside the workspace [-w, w]^2 (safety.workspace = 5): move it in or "
        "widen safety.workspace; ");
}

TEST_CASE("fence: beyond_fence is the distance outside the box or the polygon, 0 inside or on it",
          "[fence]") {
  Command box;
  box.workspace = 10.0;
  CHECK(beyond_fence(box, Vec2(0, 0)) == 0.0);
  CHECK(beyond_fence(box, Vec2(10, -10)) == 0.0);  // on the corner
  CHECK(beyond_fence(box, Vec2(13, 2)) == Approx(3.0));
  CHECK(beyond_fence(box, Vec2(-13, -14)) == Approx(5.0));  // beyond a corner: to the corner
  // The margin does not change what a breach is.
  box.fence_margin = 2.0;
  CHECK(beyond_fence(box, Vec2(9, 0)) == 0.0);
  const Command square = fenced({Vec2(0, 0), Vec2(0, 2), Vec2(2, 2), Vec2(2, 0)});  // clockwise
  CHECK(beyond_fence(square, Vec2(1, 1)) == 0.0);
  CHECK(beyond_fence(square, Vec2(1, 2)) == 0.0);
  CHECK(beyond_fence(square, Vec2(1, 2.5)) == Approx(0.5));
  CHECK(beyond_fence(square, Vec2(-3, -4)) == Approx(5.0));
  // The polygon's fence, not the box's.
  const Command tri = fenced({Vec2(0, 0), Vec2(4, 0), Vec2(0, 4)});
  CHECK(beyond_fence(tri, Vec2(3, 3)) == Approx(std::sqrt(2.0)));
  CHECK(beyond_fence(tri, Vec2(1, 1)) == 0.0);
}

TEST_CASE("fence: the return point is the nearest point at least the margin inside", "[fence]") {
  const Command square = fenced({Vec2(0, 0), Vec2(10, 0), Vec2(10, 10), Vec2(0, 10)}, 1.0);
  CHECK(fence_return_point(square, Vec2(5, 5)) == Vec2(5, 5));  // far enough inside: x itself
  CHECK((fence_return_point(square, Vec2(12, 5)) - Vec2(9, 5)).norm() < 1e-12);
  CHECK((fence_return_point(square, Vec2(9.5, 5)) - Vec2(9, 5)).norm() < 1e-12);  // inside, within the margin
  CHECK((fence_return_point(square, Vec2(-3, 14)) - Vec2(1, 9)).norm() < 1e-12);  // beyond a corner
  // The box when no polygon is given.
  Command box;
  box.workspace = 10.0;
  box.fence_margin = 0.5;
  CHECK((fence_return_point(box, Vec2(20, 0)) - Vec2(9.5, 0)).norm() < 1e-12);
  // Random points: the answer holds every shrunk half-plane, and no sampled point of the shrunk fence is
  // nearer.
  const Command pent = fenced(kPentagon, 0.75);
  const std::vector<HalfPlane> hs = fence_half_planes(pent);
  std::mt19937_64 rng(27);
  std::vector<Vec2> inner;
  while (inner.size() < 2000) {
    const Vec2 q = random_vec(rng, 6.0);
    if (in_half_planes(hs, q, 0.0)) inner.push_back(q);
  }
  for (int k = 0; k < 300; ++k) {
    const Vec2 x = random_vec(rng, 12.0);
    const Vec2 r = fence_return_point(pent, x);
    CHECK(in_half_planes(hs, r, 1e-9));
    for (const Vec2& q : inner) CHECK((q - x).norm() >= (r - x).norm() - 1e-9);
    if (in_half_planes(hs, x, 0.0)) CHECK(r == x);
  }
}

TEST_CASE("fence: a fence thinner than twice its margin returns to its deepest points", "[fence]") {
  // 10 by 1, margin 2: nothing is 2 inside; the deepest points are the mid-line y = 0, x in [-4.5, 4.5].
  const Command thin = fenced({Vec2(-5, -0.5), Vec2(5, -0.5), Vec2(5, 0.5), Vec2(-5, 0.5)}, 2.0);
  const Vec2 r = fence_return_point(thin, Vec2(10, 3));
  CHECK(r.x() == Approx(4.5).margin(1e-6));
  CHECK(r.y() == Approx(0.0).margin(1e-6));
  const Vec2 mid = fence_return_point(thin, Vec2(1, 0.4));
  CHECK(mid.x() == Approx(1.0).margin(1e-6));
  CHECK(mid.y() == Approx(0.0).margin(1e-6));
}

TEST_CASE("fence: the half-planes are the fence's sides (or the box's) moved in by the margin", "[fence]") {
  Command box;
  box.workspace = 10.0;
  box.fence_margin = 1.5;
  const std::vector<HalfPlane> b = fence_half_planes(box);
  REQUIRE(b.size() == 4);
  for (const HalfPlane& h : b) {
    CHECK(h.b == 8.5);
    CHECK(std::abs(h.n.x()) + std::abs(h.n.y()) == 1.0);
  }
  std::vector<Vec2> clockwise = kPentagon;
  std::reverse(clockwise.begin(), clockwise.end());
  const std::vector<HalfPlane> p = fence_half_planes(fenced(clockwise, 0.5));
  REQUIRE(p.size() == 5);
  for (const HalfPlane& h : p) {
    CHECK(h.n.norm() == Approx(1.0));
    CHECK(h.contains(Vec2(0, 0)));  // outward normals: the inside holds them all
    double on = -1e300;             // the side's line, 0.5 out from the shrunk one, touches the fence
    for (const Vec2& v : kPentagon) {
      CHECK(h.n.dot(v) <= h.b + 0.5 + 1e-12);
      on = std::max(on, h.n.dot(v));
    }
    CHECK(on == Approx(h.b + 0.5));
  }
}

TEST_CASE("fence: a fence or a margin sends the steps through the filter", "[fence]") {
  Command c;
  CHECK_FALSE(filters(c));
  c.fence_margin = 0.1;
  CHECK(filters(c));
  c = fenced(kPentagon);
  CHECK(filters(c));
  CHECK(safety_params(c, {}).fence.size() == 5);
  CHECK(safety_params(Command(), {}).fence.size() == 4);  // the workspace box, as before
}
