// The safety filter (core/safety.hpp): the exact 2-D QP against brute force, the buffered Voronoi
// half-planes and their stale margins, keep-out zones, a neighbour on top, and the deadlock sidestep.
#include "core/safety.hpp"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <random>

#include "core/fence.hpp"

using namespace shapeform::core;

namespace {

constexpr double kPi = 3.14159265358979323846;

Vec2 random_vec(std::mt19937_64& rng, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  const double a = u(rng);
  const double b = u(rng);
  return {a, b};
}

bool feasible(const Vec2& p, const std::vector<HalfPlane>& h, const Vec2& c, double r, double tol) {
  for (const HalfPlane& k : h)
    if (k.n.dot(p) > k.b + tol) return false;
  return r <= 0.0 || (p - c).norm() <= r + tol;
}

/// The brute-force answer: every candidate of the KKT conditions (w; its projection on each line and on
/// the circle; each pair of lines' intersection; each line's intersections with the circle; c), the
/// feasible one nearest w.
Vec2 brute_force(const Vec2& w, const std::vector<HalfPlane>& h, const Vec2& c, double r) {
  std::vector<Vec2> cand = {w, c};
  for (const HalfPlane& k : h) cand.push_back(w - (k.n.dot(w) - k.b) * k.n);
  if (r > 0.0 && (w - c).norm() > 0.0) cand.push_back(c + r * (w - c).normalized());
  for (std::size_t i = 0; i < h.size(); ++i) {
    for (std::size_t j = i + 1; j < h.size(); ++j) {
      const double det = h[i].n.x() * h[j].n.y() - h[i].n.y() * h[j].n.x();
      if (std::abs(det) < 1e-12) continue;
      cand.emplace_back((h[i].b * h[j].n.y() - h[j].b * h[i].n.y()) / det,
                        (h[i].n.x() * h[j].b - h[j].n.x() * h[i].b) / det);
    }
    if (r > 0.0) {
      const Vec2 foot = c - (h[i].n.dot(c) - h[i].b) * h[i].n;
      const double q = r * r - (foot - c).squaredNorm();
      if (q >= 0.0) {
        const Vec2 u(-h[i].n.y(), h[i].n.x());
        cand.push_back(foot + std::sqrt(q) * u);
        cand.push_back(foot - std::sqrt(q) * u);
      }
    }
  }
  Vec2 best = c;
  for (const Vec2& p : cand)
    if (feasible(p, h, c, r, 1e-9) && (p - w).norm() < (best - w).norm()) best = p;
  return best;
}

/// A random instance: c, half-planes that all hold c (some through it), a disc (sometimes none), w.
struct Instance {
  Vec2 c, w;
  std::vector<HalfPlane> h;
  double r;
};
Instance random_instance(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Instance in;
  in.c = random_vec(rng, 3.0);
  const int m = static_cast<int>(u(rng) * 12);
  for (int k = 0; k < m; ++k) {
    const double a = 2 * kPi * u(rng);
    HalfPlane hp;
    hp.n = Vec2(std::cos(a), std::sin(a));
    hp.b = hp.n.dot(in.c) + (u(rng) < 0.2 ? 0.0 : 2.0 * u(rng));
    in.h.push_back(hp);
  }
  in.r = u(rng) < 0.3 ? 0.0 : 0.1 + 2.0 * u(rng);
  in.w = in.c + random_vec(rng, 4.0);
  return in;
}

/// Whether p is inside a simple polygon (ray casting; on the boundary either way).
bool in_polygon(const std::vector<Vec2>& v, const Vec2& p) {
  bool in = false;
  for (std::size_t i = 0, j = v.size() - 1; i < v.size(); j = i++)
    if ((v[i].y() > p.y()) != (v[j].y() > p.y()) &&
        p.x() < (v[j].x() - v[i].x()) * (p.y() - v[i].y()) / (v[j].y() - v[i].y()) + v[i].x())
      in = !in;
  return in;
}

/// How deep p is inside a zone (0 outside or on its boundary).
double reference_depth(const KeepOutZone& z, const Vec2& p) {
  if (z.kind == KeepOutZone::Kind::Circle) return std::max(0.0, z.radius - (p - z.centre).norm());
  if (!in_polygon(z.vertices, p)) return 0.0;
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < z.vertices.size(); ++i) {
    const Vec2 a = z.vertices[i], b = z.vertices[(i + 1) % z.vertices.size()];
    const double t = std::clamp((p - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
    best = std::min(best, (a + t * (b - a) - p).norm());
  }
  return best;
}

KeepOutZone circle(double x, double y, double r) {
  KeepOutZone z;
  z.centre = Vec2(x, y);
  z.radius = r;
  return z;
}
KeepOutZone polygon(std::vector<Vec2> v) {
  KeepOutZone z;
  z.kind = KeepOutZone::Kind::Polygon;
  z.vertices = std::move(v);
  return z;
}

/// An L-shaped (non-convex) polygon, clockwise.
KeepOutZone l_shape() {
  return polygon({Vec2(0, 0), Vec2(0, 3), Vec2(1, 3), Vec2(1, 1), Vec2(3, 1), Vec2(3, 0)});
}

}  // namespace

TEST_CASE("safety: the QP's answer is the brute force's (random instances)", "[safety]") {
  std::mt19937_64 rng(11);
  int moved = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const Instance in = random_instance(rng);
    const Vec2 p = closest_feasible(in.w, in.h, in.c, in.r);
    const Vec2 q = brute_force(in.w, in.h, in.c, in.r);
    INFO("trial " << trial);
    REQUIRE(feasible(p, in.h, in.c, in.r, 1e-9));
    CHECK((p - in.w).norm() <= (q - in.w).norm() + 1e-9);  // no feasible candidate is nearer
    CHECK((p - q).norm() <= 1e-6);                         // the optimum is unique
    moved += (p - in.w).norm() > 1e-9 ? 1 : 0;
  }
  CHECK(moved > 5000);  // most instances do constrain w
}

TEST_CASE("safety: no sampled feasible point is nearer w than the QP's answer", "[safety]") {
  std::mt19937_64 rng(12);
  for (int trial = 0; trial < 300; ++trial) {
    const Instance in = random_instance(rng);
    const Vec2 p = closest_feasible(in.w, in.h, in.c, in.r);
    const double best = (p - in.w).norm();
    for (int s = 0; s < 2000; ++s) {
      const Vec2 q = in.c + random_vec(rng, 5.0);
      if (feasible(q, in.h, in.c, in.r, 0.0)) REQUIRE((q - in.w).norm() >= best - 1e-9);
    }
  }
}

TEST_CASE("safety: a feasible wanted point is returned bit for bit", "[safety]") {
  const std::vector<HalfPlane> h = {{Vec2(1, 0), 1.0}};
  const Vec2 w(0.1 / 3, -0.7);
  const Vec2 p = closest_feasible(w, h, Vec2::Zero(), 0.0);
  CHECK(p.x() == w.x());
  CHECK(p.y() == w.y());
}

TEST_CASE("safety: the buffered Voronoi half-planes of two agents are d apart and hold both agents",
          "[safety]") {
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int trial = 0; trial < 2000; ++trial) {
    const double d = 0.05 + u(rng);
    const Vec2 xi = random_vec(rng, 3.0);
    const double a = 2 * kPi * u(rng);
    const Vec2 xj = xi + (d + 3.0 * u(rng)) * Vec2(std::cos(a), std::sin(a));
    bool bi = true, bj = true;
    const HalfPlane hi = separation_half_plane(0, xi, {1, xj, 0.0, 0.0}, d, bi);
    const HalfPlane hj = separation_half_plane(1, xj, {0, xi, 0.0, 0.0}, d, bj);
    CHECK_FALSE(bi);
    CHECK_FALSE(bj);
    CHECK(hi.contains(xi, 1e-12));
    CHECK(hj.contains(xj, 1e-12));
    CHECK(hi.n.dot(hj.n) == Approx(-1.0));
    // The lines' distance is d: any point of one and any point of the other are >= d apart.
    CHECK(-hj.b - hi.b == Approx(d).margin(1e-12));
    // Random points of both half-planes, near the agents: never closer than d.
    for (int s = 0; s < 50; ++s) {
      const Vec2 p = xi + random_vec(rng, 2.0), q = xj + random_vec(rng, 2.0);
      if (hi.contains(p) && hj.contains(q)) CHECK((p - q).norm() >= d - 1e-12);
    }
  }
}

TEST_CASE("safety: a stale sample's margin shrinks the half-plane by max_speed * age", "[safety]") {
  const Vec2 xi(0, 0), xj(3, 0);
  bool broken = false;
  const HalfPlane fresh = separation_half_plane(0, xi, {1, xj, 0.0, 2.0}, 1.0, broken);
  CHECK(fresh.b == Approx(1.0));  // (3 - 1) / 2
  const HalfPlane stale = separation_half_plane(0, xi, {1, xj, 0.25, 2.0}, 1.0, broken);
  CHECK(stale.b == Approx(0.5));  // less 2 * 0.25
  // A margin past the agent's half of the gap leaves "do not approach": the line through x.
  const HalfPlane old = separation_half_plane(0, xi, {1, xj, 2.0, 2.0}, 1.0, broken);
  CHECK(old.b == 0.0);
  CHECK_FALSE(broken);
  // An unknown speed or age (NaN, inf) too.
  const HalfPlane unknown =
      separation_half_plane(0, xi, {1, xj, std::numeric_limits<double>::infinity(), 1.0}, 1.0, broken);
  CHECK(unknown.b == 0.0);
}

TEST_CASE("safety: stale neighbours moving at their bound toward the agent are never reached", "[safety]") {
  // The neighbour's true position may be anywhere within max_speed * age of its sample; the agent's
  // step stays out of reach of every such position by d.
  std::mt19937_64 rng(14);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int trial = 0; trial < 2000; ++trial) {
    const double d = 0.2 + u(rng), speed = u(rng), age = u(rng);
    const Vec2 x = random_vec(rng, 2.0);
    const Vec2 sample = x + (d + 2.0 * speed * age + 4.0 * u(rng)) * Vec2(1, 0);
    SafetyParams p;
    p.min_separation = d;
    SafetyState st;
    const Vec2 wanted = x + random_vec(rng, 4.0);
    const SafetyOutcome f = safety_filter(p, st, 0, x, wanted, {{1, sample, age, speed}}, {});
    // The neighbour, moved by up to speed * age, then taking its own half step: stays beyond the midline.
    const double mid = 0.5 * (x.x() + sample.x());
    CHECK(f.x.x() <= mid - 0.5 * d - speed * age + 1e-9);
  }
}

TEST_CASE("safety: two agents on one point are told apart by their ids and step away from each other",
          "[safety]") {
  SafetyParams p;
  p.min_separation = 1.0;
  p.max_step = 0.3;
  SafetyState s0, s1;
  const Vec2 x(2, 2);
  const SafetyOutcome a = safety_filter(p, s0, 0, x, x + Vec2(0.1, 0), {{1, x, 0, 0}}, {});
  const SafetyOutcome b = safety_filter(p, s1, 1, x, x + Vec2(0.1, 0), {{0, x, 0, 0}}, {});
  CHECK(a.broken == 1);
  CHECK(b.broken == 1);
  CHECK(a.x.x() == Approx(x.x() - 0.3));  // the largest step the speed disc allows, away
  CHECK(b.x.x() == Approx(x.x() + 0.3));
  CHECK((a.x - b.x).norm() > 0.5);
}

TEST_CASE("safety: a neighbour closer than d: the agent steps straight away, never closer", "[safety]") {
  SafetyParams p;
  p.min_separation = 1.0;
  p.max_step = 0.2;
  SafetyState st;
  const Vec2 x(0, 0), on_top(0.3, 0.0);
  // The law wants to go right through it.
  const SafetyOutcome f = safety_filter(p, st, 0, x, Vec2(2, 0), {{1, on_top, 0, 0}}, {});
  CHECK(f.broken == 1);
  CHECK(f.intervened);
  CHECK(f.x.x() == Approx(-0.2));
  CHECK(f.x.y() == Approx(0.0).margin(1e-12));
  CHECK((f.x - on_top).norm() > (x - on_top).norm());
}

TEST_CASE("safety: keep_out_problems names what is wrong with a zone", "[safety]") {
  CHECK(keep_out_problems(circle(0, 0, 1)).empty());
  CHECK(keep_out_problems(circle(0, 0, 0)) == std::vector<std::string>{"circle radius must be > 0"});
  CHECK(keep_out_problems(l_shape()).empty());
  CHECK(keep_out_problems(polygon({Vec2(0, 0), Vec2(1, 0)})) ==
        std::vector<std::string>{"polygon needs >= 3 vertices, got 2"});
  CHECK(keep_out_problems(polygon({Vec2(0, 0), Vec2(1, 0), Vec2(2, 0)})) ==
        std::vector<std::string>{"polygon vertices are all on one line (no area)"});
  CHECK(keep_out_problems(polygon({Vec2(0, 0), Vec2(1, 1), Vec2(1, 0), Vec2(0, 1)})) ==
        std::vector<std::string>{"polygon edges 0 and 2 cross (the polygon must be simple)"});
  CHECK(keep_out_problems(polygon({Vec2(0, 0), Vec2(0, 0), Vec2(1, 0), Vec2(0, 1)})) ==
        std::vector<std::string>{"polygon vertices 0 and 1 are equal"});
}

TEST_CASE("safety: a non-convex polygon's convex pieces cover it exactly", "[safety]") {
  const KeepOutZone l = l_shape();
  const std::vector<ConvexZone> pieces = convex_pieces({l});
  CHECK(pieces.size() == 4);  // 6 vertices: 4 triangles
  std::mt19937_64 rng(15);
  for (int s = 0; s < 20000; ++s) {
    const Vec2 p = Vec2(1.5, 1.5) + random_vec(rng, 2.0);
    bool any = false;
    for (const ConvexZone& z : pieces) any = any || inside(z, p);
    CHECK(any == in_polygon(l.vertices, p));
  }
  const std::vector<ConvexZone> square =
      convex_pieces({polygon({Vec2(0, 0), Vec2(0, 1), Vec2(1, 1), Vec2(1, 0)})});
  REQUIRE(square.size() == 1);  // convex: kept whole (turned counter-clockwise)
  CHECK(square[0].vertices[1] == Vec2(1, 1));
}

TEST_CASE("safety: a step never enters a keep-out zone, nor crosses one on its way", "[safety]") {
  const std::vector<KeepOutZone> zones = {circle(-3, 0, 1), l_shape(),
                                          polygon({Vec2(-1, -4), Vec2(1, -4), Vec2(0, -2.5)})};
  const std::vector<ConvexZone> pieces = convex_pieces(zones);
  std::mt19937_64 rng(16);
  SafetyParams p;
  int intervened = 0;
  for (int trial = 0; trial < 5000; ++trial) {
    const Vec2 x = random_vec(rng, 5.0);
    bool out = true;
    for (const ConvexZone& z : pieces) out = out && !inside(z, x);
    if (!out) continue;
    SafetyState st;
    const SafetyOutcome f = safety_filter(p, st, 0, x, x + random_vec(rng, 3.0), {}, pieces);
    intervened += f.intervened ? 1 : 0;
    // The whole straight segment from x to the answer: outside every zone (on a boundary at most).
    for (int k = 0; k <= 20; ++k) {
      const Vec2 q = x + (k / 20.0) * (f.x - x);
      for (const KeepOutZone& z : zones) {
        CHECK(reference_depth(z, q) <= 1e-9);
        CHECK(depth(z, q) == Approx(reference_depth(z, q)).margin(1e-12));
      }
    }
  }
  CHECK(intervened > 200);
}

TEST_CASE("safety: an agent inside a zone goes no deeper", "[safety]") {
  const std::vector<ConvexZone> pieces = convex_pieces({circle(0, 0, 2)});
  SafetyParams p;
  SafetyState st;
  const SafetyOutcome f = safety_filter(p, st, 0, Vec2(1, 0), Vec2(0, 0), {}, pieces);
  CHECK(f.inside_zones == 1);
  CHECK(f.x.norm() >= 1.0 - 1e-12);
}

TEST_CASE("safety: two agents head-on are held, sidestep to their right, pass, and keep d all along",
          "[safety]") {
  // Each wants to reach the other's start; a symmetric deadlock for the plain filter.
  SafetyParams p;
  p.min_separation = 1.0;
  p.max_step = 0.2;
  Vec2 x[2] = {Vec2(-3, 0), Vec2(3, 0)};
  const Vec2 goal[2] = {Vec2(3, 0), Vec2(-3, 0)};
  SafetyState st[2];
  int sidesteps = 0;
  double closest = 1e9;
  for (int k = 0; k < 400; ++k) {
    Vec2 next[2];
    for (int i = 0; i < 2; ++i) {
      const Vec2 step = goal[i] - x[i];
      const Vec2 wanted = x[i] + (step.norm() > 0.2 ? Vec2(0.2 * step.normalized()) : step);
      const SafetyOutcome f = safety_filter(p, st[i], i, x[i], wanted, {{1 - i, x[1 - i], 0, 0}}, {});
      sidesteps += f.sidestep_started ? 1 : 0;
      next[i] = f.x;
    }
    x[0] = next[0];
    x[1] = next[1];
    closest = std::min(closest, (x[0] - x[1]).norm());
  }
  CHECK(closest >= 1.0 - 1e-9);
  CHECK(sidesteps >= 2);
  CHECK((x[0] - goal[0]).norm() < 1e-6);  // both arrived
  CHECK((x[1] - goal[1]).norm() < 1e-6);
}

TEST_CASE("safety: two agents seeing each other a step late, too near for any step, back off and pass",
          "[safety]") {
  // Within d + margin of each other's stale states: the stale disc leaves no room, so both would stand
  // still for ever; backing off (while sidestepping) opens the gap, and then they pass to their right.
  for (const bool back_off : {true, false}) {
    CAPTURE(back_off);
    SafetyParams p;
    p.min_separation = 0.25;
    p.max_step = 0.1;
    Vec2 x[2] = {Vec2(-0.15, 0), Vec2(0.15, 0)};
    Vec2 seen[2] = {x[0], x[1]};  // what the other heard: the state of one step earlier
    const Vec2 goal[2] = {Vec2(2, 0), Vec2(-2, 0)};
    SafetyState st[2];
    double closest = 1e9;
    for (int k = 0; k < 600; ++k) {
      Vec2 next[2];
      for (int i = 0; i < 2; ++i) {
        const Vec2 step = goal[i] - x[i];
        const Vec2 wanted = x[i] + (step.norm() > 0.1 ? Vec2(0.1 * step.normalized()) : step);
        // The neighbour one step old: a margin of one step (0.1) at speed 0.1 per unit age.
        SafetyNeighbour j{1 - i, seen[1 - i], 1.0, 0.1};
        if (!back_off) j.age_s = 1e9;  // an unknown margin: no direction is safe, it stands still
        next[i] = safety_filter(p, st[i], i, x[i], wanted, {j}, {}).x;
      }
      seen[0] = x[0];
      seen[1] = x[1];
      x[0] = next[0];
      x[1] = next[1];
      closest = std::min(closest, (x[0] - x[1]).norm());
    }
    CHECK(closest >= 0.25 - 1e-9);
    if (back_off) {
      CHECK((x[0] - goal[0]).norm() < 1e-6);  // both arrived
      CHECK((x[1] - goal[1]).norm() < 1e-6);
    } else {
      CHECK(x[0] == Vec2(-0.15, 0));
      CHECK(x[1] == Vec2(0.15, 0));
    }
  }
}

TEST_CASE("safety: without the sidestep the head-on pair stays held (the test above needs it)", "[safety]") {
  SafetyParams p;
  p.min_separation = 1.0;
  p.max_step = 0.2;
  p.stuck_steps = 0;  // no sidestep
  Vec2 x[2] = {Vec2(-3, 0), Vec2(3, 0)};
  SafetyState st[2];
  for (int k = 0; k < 400; ++k) {
    Vec2 next[2];
    for (int i = 0; i < 2; ++i) {
      const Vec2 wanted = x[i] + Vec2(i == 0 ? 0.2 : -0.2, 0);
      next[i] = safety_filter(p, st[i], i, x[i], wanted, {{1 - i, x[1 - i], 0, 0}}, {}).x;
    }
    x[0] = next[0];
    x[1] = next[1];
  }
  CHECK((x[0] - x[1]).norm() == Approx(1.0));
  CHECK(st[0].held > 300);
}

TEST_CASE("safety: drive_safely lands every vehicle model in its cell (or stops a unicycle there)",
          "[safety]") {
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int inside_count = 0, trials = 0;
  for (VehicleModel model : {VehicleModel::Integrator, VehicleModel::Unicycle}) {
    for (Steering steering : {Steering::Exact, Steering::Linearised}) {
      for (int trial = 0; trial < 1000; ++trial) {
        VehicleParams vp;
        vp.model = model;
        vp.steering = steering;
        vp.max_speed = 0.5 + u(rng);
        vp.max_yaw_rate = 0.5 + 2 * u(rng);
        VehicleState s = vehicle_start(random_vec(rng, 2.0), 2 * kPi * u(rng));
        SafetyParams p;
        p.min_separation = 0.5;
        SafetyState st;
        const Vec2 other = s.x + (0.6 + u(rng)) * Vec2(std::cos(7 * u(rng)), std::sin(7 * u(rng)));
        const Vec2 wanted = s.x + random_vec(rng, 1.0);
        const SafetyOutcome f = safety_filter(p, st, 0, s.x, wanted, {{1, other, 0, 0}}, {});
        bool outside = true;
        const StepResult r = drive_safely(vp, s, {wanted, Vec2::Zero(), false}, f, 1.0, 1000.0, outside);
        CHECK_FALSE(outside);
        CHECK(f.in_cell(r.x));
        inside_count += f.in_cell(r.x) ? 1 : 0;
        ++trials;
      }
    }
  }
  CHECK(inside_count == trials);
}

TEST_CASE("safety: agents walked into zones for many steps (pushed onto their faces) never get in",
          "[safety]") {
  // The filter puts agents exactly on a zone's face; from there the next steps must still keep out
  // (a face's line, not a noisy direction to a nearest point at distance 0).
  const std::vector<KeepOutZone> zones = {circle(-3, 0, 1), l_shape(),
                                          polygon({Vec2(-1, -4), Vec2(1, -4), Vec2(0, -2.5)})};
  const std::vector<ConvexZone> pieces = convex_pieces(zones);
  std::mt19937_64 rng(18);
  SafetyParams p;
  p.max_step = 0.2;
  int on_face = 0;
  for (int trial = 0; trial < 500; ++trial) {
    Vec2 x = random_vec(rng, 5.0);
    bool out = true;
    for (const KeepOutZone& z : zones) out = out && reference_depth(z, x) == 0.0;
    if (!out) continue;
    const Vec2 goal = random_vec(rng, 3.0);
    SafetyState st;
    for (int k = 0; k < 80; ++k) {
      const Vec2 step = goal - x;
      const Vec2 wanted = x + (step.norm() > 0.2 ? Vec2(0.2 * step.normalized()) : step);
      const SafetyOutcome f = safety_filter(p, st, 0, x, wanted, {}, pieces);
      for (int s = 1; s <= 10; ++s)
        for (const KeepOutZone& z : zones) {
          INFO("x " << x.transpose() << " -> " << f.x.transpose() << " wanted " << wanted.transpose()
                    << " zone " << (&z - zones.data()));
          REQUIRE(reference_depth(z, x + (s / 10.0) * (f.x - x)) <= 1e-9);
        }
      x = f.x;
      for (const KeepOutZone& z : zones) {
        bool touching = false;
        for (std::size_t i = 0; i < z.vertices.size(); ++i) {
          const Vec2 a = z.vertices[i], b = z.vertices[(i + 1) % z.vertices.size()];
          const double t = std::clamp((x - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
          touching = touching || (a + t * (b - a) - x).norm() < 1e-9;
        }
        on_face += touching ? 1 : 0;
      }
    }
  }
  CHECK(on_face > 100);  // the case this test is about did happen
}

namespace {

/// n agents on a circle of radius 3 swap to the antipodes (every pair's way crosses the centre), each
/// seeing the others' positions `delay` steps old, with the margin max_speed * age; the smallest
/// pairwise distance over every step and whether all arrived.
std::pair<double, bool> antipodal_swap(int n, int delay, double d, double speed, int steps) {
  std::vector<Vec2> x, goal;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * kPi * i / n + 0.01 * i;  // slightly off symmetry
    x.emplace_back(3 * std::cos(a), 3 * std::sin(a));
    goal.push_back(-x.back());
  }
  std::vector<std::vector<Vec2>> history(static_cast<std::size_t>(delay) + 1, x);  // [0] newest
  std::vector<SafetyState> st(static_cast<std::size_t>(n));
  SafetyParams p;
  p.min_separation = d;
  p.max_step = speed;  // dt = 1
  double closest = 1e9;
  for (int k = 0; k < steps; ++k) {
    const std::vector<Vec2>& seen = history.back();  // `delay` steps old
    std::vector<Vec2> next(x.size());
    for (int i = 0; i < n; ++i) {
      std::vector<SafetyNeighbour> nb;
      for (int j = 0; j < n; ++j)
        if (j != i) nb.push_back({j, seen[static_cast<std::size_t>(j)], static_cast<double>(delay), speed});
      const Vec2 step = goal[i] - x[i];
      const Vec2 wanted = x[i] + (step.norm() > speed ? Vec2(speed * step.normalized()) : step);
      next[i] = safety_filter(p, st[i], i, x[i], wanted, nb, {}).x;
    }
    x = next;
    history.insert(history.begin(), x);
    history.pop_back();
    for (int i = 0; i < n; ++i)
      for (int j = i + 1; j < n; ++j) closest = std::min(closest, (x[i] - x[j]).norm());
  }
  bool arrived = true;
  for (int i = 0; i < n; ++i) arrived = arrived && (x[i] - goal[i]).norm() < 1e-6;
  return {closest, arrived};
}

}  // namespace

TEST_CASE(
    "safety: neighbours' states one to three steps old, with the margin max_speed * age: the separation "
    "holds",
    "[safety]") {
  // Every agent sees the others `delay` steps late: the half-planes of two agents then come from two
  // different views; the stale discs keep the pair d apart all the same.
  int arrived_runs = 0;
  for (const int delay : {0, 1, 2, 3}) {
    for (const int n : {4, 8, 12, 16}) {
      INFO("delay " << delay << " steps, " << n << " agents");
      const auto [closest, arrived] = antipodal_swap(n, delay, 0.5, 0.1, 1500);
      CHECK(closest >= 0.5 - 1e-9);
      arrived_runs += arrived ? 1 : 0;
      WARN("delay " << delay << ", n " << n << ": closest " << closest << ", all arrived " << arrived);
    }
  }
  CHECK(arrived_runs >= 1);
}

TEST_CASE("safety: no step leaves the fence shrunk by its margin, nor crosses out on its way",
          "[safety][fence]") {
  Command c;
  c.fence = {Vec2(-4, -3), Vec2(3, -4), Vec2(5, 1), Vec2(0, 5), Vec2(-5, 2)};
  c.fence_margin = 0.5;
  const std::vector<ConvexZone> pieces = convex_pieces({circle(0, 0, 1)});
  std::mt19937_64 rng(31);
  for (const bool box : {false, true}) {
    Command cmd = c;
    if (box) cmd.fence.clear(), cmd.workspace = 4.0;
    SafetyParams p = safety_params(cmd, {});
    p.max_step = 2.0;
    const std::vector<HalfPlane> inner = fence_half_planes(cmd);
    int steps = 0, intervened = 0;
    for (int trial = 0; trial < 3000; ++trial) {
      // A walk of a few steps from a point inside the shrunk fence, wanting to go anywhere.
      Vec2 x = random_vec(rng, 5.0);
      bool in = true;
      for (const HalfPlane& h : inner) in = in && h.contains(x);
      if (!in || x.norm() <= 1.0) continue;
      SafetyState st;
      for (int k = 0; k < 5; ++k, ++steps) {
        const SafetyOutcome f = safety_filter(p, st, 0, x, x + random_vec(rng, 4.0), {}, pieces);
        intervened += f.intervened ? 1 : 0;
        for (int j = 0; j <= 10; ++j)
          for (const HalfPlane& h : inner) CHECK(h.contains(x + (j / 10.0) * (f.x - x), 1e-9));
        CHECK(beyond_fence(cmd, f.x) == 0.0);
        x = f.x;
      }
    }
    CHECK(steps > 1000);
    CHECK(intervened > steps / 4);
  }
}

TEST_CASE("safety: an agent outside the fence is never pushed further out, and always has a step",
          "[safety][fence]") {
  Command c;
  c.fence = {Vec2(-4, -3), Vec2(3, -4), Vec2(5, 1), Vec2(0, 5), Vec2(-5, 2)};
  c.fence_margin = 0.5;
  std::mt19937_64 rng(32);
  for (const bool box : {false, true}) {
    Command cmd = c;
    if (box) cmd.fence.clear(), cmd.workspace = 4.0;
    const SafetyParams p = safety_params(cmd, {});
    const std::vector<HalfPlane> inner = fence_half_planes(cmd);
    int outside = 0;
    for (int trial = 0; trial < 3000; ++trial) {
      const Vec2 x = random_vec(rng, 9.0);
      if (beyond_fence(cmd, x) == 0.0) continue;
      ++outside;
      SafetyState st;
      const SafetyOutcome f = safety_filter(p, st, 0, x, x + random_vec(rng, 4.0), {}, {});
      CHECK(f.in_cell(f.x));
      // Past no side further than it was (n . p <= max(b, n . x)); with the box's right angles that
      // is no further from the fence either.
      for (const HalfPlane& h : inner) CHECK(h.n.dot(f.x) <= std::max(h.b, h.n.dot(x)) + 1e-9);
      if (box) CHECK(beyond_fence(cmd, f.x) <= beyond_fence(cmd, x) + 1e-9);
      // Wanting to go back to the return point, it gets there (no other constraint binds).
      SafetyState back;
      const Vec2 home = fence_return_point(cmd, x);
      CHECK((safety_filter(p, back, 0, x, home, {}, {}).x - home).norm() < 1e-9);
    }
    CHECK(outside > 1000);
  }
}

TEST_CASE("safety: an agent inside a zone set over it steps out by the shortest way and stays out", "[safety]") {
  KeepOutZone z;
  z.centre = Vec2(0, 0);
  z.radius = 1.0;
  const auto pieces = convex_pieces({z});
  SafetyParams p;
  p.max_step = 0.2;
  SafetyState state;
  Vec2 x(0.3, 0.0);
  // The law wants it to stay where it is (its slot is inside the zone).
  for (int k = 0; k < 10; ++k) {
    const SafetyOutcome f = safety_filter(p, state, 0, x, x, {}, pieces);
    CHECK((f.x - x).norm() <= 0.2 + 1e-12);
    if (k < 4) CHECK(f.x.x() > x.x());  // straight out, along the radius
    x = f.x;
  }
  CHECK(x.norm() >= 1.0 - 1e-9);
  CHECK(std::abs(x.y()) < 1e-12);
}

// ---- Double integrators: braking segments --------------------------------------------------------

TEST_CASE("braking: the displacement is where braking steps stop, and one step leaves the rest of it",
          "[safety][braking]") {
  std::mt19937_64 rng(31);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (const double a : {0.0, 0.05, 0.5, 2.0})
    for (const double h : {0.05, 0.5, 1.0})
      for (int trial = 0; trial < 200; ++trial) {
        CAPTURE(a, h, trial);
        const Vec2 v0 = random_vec(rng, 1.0);
        // Step as drive() moves a double integrator told to brake, to a stop.
        VehicleParams vp;
        vp.model = VehicleModel::DoubleIntegrator;
        vp.max_speed = 2.0;
        vp.max_accel = a;
        VehicleState s = vehicle_start(Vec2(1, 2), 0.0);
        s.velocity = v0;
        const Vec2 e0 = braking_displacement(v0, a, h);
        int k = 0;
        for (; k < 10000 && s.velocity.norm() > 0.0; ++k) {
          const Vec2 before = s.x;
          const Vec2 vb = braking_velocity(s.velocity, a, h);
          const Vec2 rest = braking_displacement(s.velocity, a, h);
          drive(vp, s, {before + h * vb, vb / 1.0, false}, h, 1e6);
          CHECK((s.velocity - vb).norm() <= 1e-12);
          // The step and what is left of the braking add up to the braking before it.
          CHECK((s.x - before + braking_displacement(s.velocity, a, h) - rest).norm() <= 1e-9);
        }
        REQUIRE(s.velocity.norm() == 0.0);
        CHECK((s.x - Vec2(1, 2) - e0).norm() <= 1e-9 * (1.0 + e0.norm()));
        if (a == 0.0) CHECK(k == 1);
      }
}

TEST_CASE("braking: the displacement changes at most braking_lipschitz times the velocity's change",
          "[safety][braking]") {
  std::mt19937_64 rng(32);
  double worst = 0.0;
  for (const double a : {0.0, 0.1, 0.5, 3.0})
    for (const double h : {0.05, 0.5})
      for (int trial = 0; trial < 20000; ++trial) {
        const double vmax = 1.0;
        Vec2 v0 = random_vec(rng, 1.0), v1 = v0 + random_vec(rng, trial % 2 ? 0.01 : 1.0);
        if (v0.norm() > vmax) v0 *= vmax / v0.norm();
        if (v1.norm() > vmax) v1 *= vmax / v1.norm();
        if (v1 == v0) continue;
        const double ratio = (braking_displacement(v1, a, h) - braking_displacement(v0, a, h)).norm() / (v1 - v0).norm();
        const double bound = braking_lipschitz(vmax, a, h);
        CHECK(ratio <= bound * (1.0 + 1e-9));
        worst = std::max(worst, ratio / bound);
      }
  CHECK(worst > 0.5);  // the bound is not loose by more than a factor of 2
}

TEST_CASE("braking: braking_reach bounds how far a segment's ends move, and is small for a slow vehicle",
          "[safety][braking]") {
  std::mt19937_64 rng(33);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  double worst = 0.0;
  for (const double a : {0.0, 0.05, 0.5})
    for (const double h : {0.1, 1.0})
      for (int trial = 0; trial < 3000; ++trial) {
        VehicleParams vp;
        vp.model = VehicleModel::DoubleIntegrator;
        vp.max_speed = 0.5;
        vp.max_accel = a;
        VehicleState s = vehicle_start(Vec2(1, 2), 0.0);
        const double s0 = vp.max_speed * u(rng) * u(rng);  // many slow starts
        s.velocity = random_vec(rng, 1.0);
        if (s.velocity.norm() > 0.0) s.velocity *= s0 / s.velocity.norm();
        const Vec2 x0 = s.x, end0 = s.x + braking_displacement(s.velocity, a, h);
        const int steps = 1 + trial % 8;
        // Pushed hard in one direction (the far reach) or any way (turns and brakes).
        const Vec2 push = random_vec(rng, 1.0).normalized();
        for (int k = 1; k <= steps; ++k) {
          const Vec2 want = trial % 3 ? Vec2(push * vp.max_speed * 2.0) : random_vec(rng, 2.0 * vp.max_speed);
          drive(vp, s, {s.x + h * want, want, false}, h, 1e6);
          const double reach = braking_reach(s0, k, vp.max_speed, a, h);
          CAPTURE(a, h, trial, k, s0, reach);
          const double moved = std::max((s.x - x0).norm(), (s.x + braking_displacement(s.velocity, a, h) - end0).norm());
          CHECK(moved <= reach * (1.0 + 1e-9) + 1e-12);
          if (reach > 0.0) worst = std::max(worst, moved / reach);
          // From full speed it is the bound for a neighbour of unknown speed, or less.
          CHECK(braking_reach(vp.max_speed, k, vp.max_speed, a, h) <=
                k * (2.0 * vp.max_speed + 0.5 * a * h) * h * (1.0 + 1e-12));
        }
      }
  CHECK(worst > 0.5);  // not loose by more than a factor of 2
  // Linear between whole steps; a vehicle at rest with a small acceleration limit barely moves.
  const double r1 = braking_reach(0.1, 1.0, 0.5, 0.05, 1.0), r2 = braking_reach(0.1, 2.0, 0.5, 0.05, 1.0);
  CHECK(braking_reach(0.1, 1.5, 0.5, 0.05, 1.0) == Approx(0.5 * (r1 + r2)));
  CHECK(braking_reach(0.0, 2.0, 0.5, 0.05, 1.0) < 0.2 * braking_reach(0.5, 2.0, 0.5, 0.05, 1.0));
  CHECK(braking_reach(0.0, 0.0, 0.5, 0.05, 1.0) == 0.0);
  CHECK(std::isinf(braking_reach(0.1, 1.0, std::numeric_limits<double>::infinity(), 0.0, 1.0)));
}

namespace {
/// A small robot as a point mass: 0.5 m/s, 0.5 m/s^2.
VehicleParams point_mass() {
  VehicleParams vp;
  vp.model = VehicleModel::DoubleIntegrator;
  vp.max_speed = 0.5;
  vp.max_accel = 0.5;
  return vp;
}

/// The filter's settings for point_mass() at steps of dt: d = 0.25, with braking segments or not.
SafetyParams point_mass_filter(double dt, bool segments) {
  SafetyParams p;
  p.min_separation = 0.25;
  p.max_step = point_mass().max_speed * dt;
  p.braking = segments;
  return p;
}

/// n double integrators from rest, each sent to a goal through the others, the filter on (with braking
/// segments when `segments`), synchronous states; returns the smallest distance of two after any step
/// and counts the steps whose vehicle left its cell.
double braking_swarm(const std::vector<Vec2>& start, const std::vector<Vec2>& goal, bool segments, int steps,
                     int& outside, std::vector<Vec2>* end = nullptr) {
  const VehicleParams vp = point_mass();
  const double dt = 0.1, h = dt;
  const SafetyParams p = point_mass_filter(dt, segments);
  const std::size_t n = start.size();
  std::vector<VehicleState> v;
  for (const Vec2& x : start) v.push_back(vehicle_start(x, 0.0));
  std::vector<SafetyState> st(n);
  double low = 1e9;
  outside = 0;
  for (int k = 0; k < steps; ++k) {
    std::vector<Vec2> e(n);
    for (std::size_t i = 0; i < n; ++i) e[i] = segments ? braking_displacement(v[i].velocity, vp.max_accel, h) : Vec2::Zero();
    std::vector<VehicleState> next = v;
    for (std::size_t i = 0; i < n; ++i) {
      std::vector<SafetyNeighbour> nb;
      for (std::size_t j = 0; j < n; ++j)
        if (j != i) nb.push_back({static_cast<std::int32_t>(j), v[j].x, 0.0, 0.0, e[j]});
      const Vec2 step = goal[i] - v[i].x;
      const Vec2 wanted = v[i].x + (step.norm() > p.max_step ? Vec2(p.max_step * step.normalized()) : step);
      const SafetyOutcome f = safety_filter(p, st[i], static_cast<std::int32_t>(i), v[i].x, wanted, nb, {}, e[i]);
      bool out = false;
      drive_safely(vp, next[i], {wanted, (wanted - v[i].x) / dt, false}, f, dt, 1e6, out);
      outside += out ? 1 : 0;
    }
    v = next;
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = i + 1; j < n; ++j) low = std::min(low, (v[i].x - v[j].x).norm());
  }
  if (end)
    for (const auto& s : v) end->push_back(s.x);
  return low;
}
}  // namespace

TEST_CASE("safety: double integrators crossing at speed keep d with braking segments, not with positions alone",
          "[safety][braking]") {
  std::mt19937_64 rng(33);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int old_below = 0, trials = 0, arrived = 0;
  for (int trial = 0; trial < 40; ++trial) {
    CAPTURE(trial);
    // Agents on a circle sent to their antipodes (every path through the centre), or a random swap.
    const int n = 2 + trial % 5;
    const double r = 1.0 + 2.0 * u(rng), phase = 2 * kPi * u(rng);
    std::vector<Vec2> start, goal;
    for (int i = 0; i < n; ++i) {
      const Vec2 at(std::cos(phase + 2 * kPi * i / n), std::sin(phase + 2 * kPi * i / n));
      start.push_back(r * at);
      goal.push_back(-r * at + (trial % 2 ? random_vec(rng, 0.2) : Vec2::Zero()));
    }
    int outside = 0;
    std::vector<Vec2> end;
    CHECK(braking_swarm(start, goal, true, 600, outside, &end) >= 0.25 - 1e-9);
    CHECK(outside == 0);
    bool all = true;
    for (int i = 0; i < n; ++i) all = all && (end[i] - goal[i]).norm() < 0.05;
    arrived += all ? 1 : 0;
    int old_outside = 0;
    old_below += braking_swarm(start, goal, false, 600, old_outside) < 0.25 - 1e-9 ? 1 : 0;
    ++trials;
  }
  // Cells of positions alone let the vehicles' momentum carry them closer (the test needs segments).
  CHECK(old_below >= trials / 4);
  // The sidestep still resolves the head-on meetings: most swaps complete.
  CHECK(arrived >= trials / 2);
  WARN("double integrators: " << arrived << " of " << trials << " swaps completed; positions-only cells went below d in "
                              << old_below);
}

TEST_CASE("safety: a double integrator with stale, blurred neighbours too near backs away or brakes, and keeps its cell",
          "[safety][braking]") {
  SafetyParams p;
  p.min_separation = 0.25;
  p.max_step = 0.05;
  p.braking = true;
  SafetyState st;
  const Vec2 x(0, 0), brake(0.2, 0);
  // The neighbour's segment is 0.3 beyond the own one's end: with a margin of 0.1 there is (0.3 - 0.1 -
  // 0.25) / 2 < 0 room: brake only.
  const SafetyOutcome f = safety_filter(p, st, 0, x, Vec2(1, 0), {{1, Vec2(0.5, 0), 0.1, 0.5, Vec2(0.1, 0), 0.05}}, {}, brake);
  // One such neighbour, whose true segment is beyond the margin: back away from it, in the own
  // segment's shadow (two such: brake).
  CHECK_FALSE(f.still);
  CHECK(f.away == Vec2(1, 0));
  CHECK(f.holds(Vec2(0.05, 0), Vec2(0.2, 0)));         // braking: on the old segment
  CHECK(f.holds(Vec2(-0.05, 0), Vec2(0.1, 0)));        // backing away along it
  CHECK_FALSE(f.holds(Vec2(0.05, 0), Vec2(0.21, 0)));  // a step that would stop further on
  CHECK_FALSE(f.holds(Vec2(0.05, 0), Vec2(0.1, 0.01)));  // or off its line
  const SafetyOutcome two = safety_filter(p, st, 0, x, Vec2(1, 0),
                                          {{1, Vec2(0.5, 0), 0.1, 0.5, Vec2(0.1, 0), 0.05},
                                           {2, Vec2(-0.3, 0), 0.1, 0.5, Vec2(-0.1, 0), 0.05}},
                                          {}, brake);
  CHECK(two.still);
  CHECK(two.holds(Vec2(0.05, 0), Vec2(0.2, 0)));
  CHECK_FALSE(two.holds(Vec2(-0.05, 0), Vec2(0.1, 0)));
  // With room (margin 0.01): the new segment may grow by (0.3 - 0.01 - 0.25) / 2 = 0.02 beyond the old.
  const SafetyOutcome g = safety_filter(p, st, 0, x, Vec2(1, 0), {{1, Vec2(0.5, 0), 0.01, 0.5, Vec2(0.1, 0), 0.005}}, {}, brake);
  CHECK_FALSE(g.still);
  CHECK(g.grow == Approx(0.02));
  CHECK(g.holds(Vec2(0.05, 0), Vec2(0.1, 0.019)));
  CHECK_FALSE(g.holds(Vec2(0.05, 0), Vec2(0.1, 0.021)));
  // and toward the neighbour only up to its half-plane, 0.5 (0.3 - 0.25) - 0.01 = 0.015 beyond.
  CHECK(g.holds(Vec2(0.05, 0), Vec2(0.214, 0)));
  CHECK_FALSE(g.holds(Vec2(0.05, 0), Vec2(0.216, 0)));
}

TEST_CASE("safety: a double integrator's filtered velocity against the nearest safe one (brute force)",
          "[safety][braking]") {
  // The velocity drive_safely takes (on the way from braking to the law's) against the safe velocity
  // nearest the law's among a fine grid of every velocity the vehicle can take: how much more it changes
  // the law's velocity than the best (docs/SAFETY.md quotes the figures).
  std::mt19937_64 rng(34);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const VehicleParams vp = point_mass();
  const double dt = 0.5, h = dt;
  const SafetyParams p = point_mass_filter(dt, true);
  std::vector<double> excess;  // |ours - law| - |best - law|, in units of the reachable disc's radius a h
  int cut = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    VehicleState s = vehicle_start(Vec2::Zero(), 0.0);
    s.velocity = random_vec(rng, 0.3);
    const Vec2 e = braking_displacement(s.velocity, vp.max_accel, h);
    // A neighbour (braking segment of its own) at least d from the own segment, at rest or moving.
    SafetyNeighbour j{1, Vec2::Zero(), 0.0, 0.0};
    for (;;) {
      j.x = random_vec(rng, 0.8);
      j.brake = braking_displacement(random_vec(rng, 0.3), vp.max_accel, h);
      const Vec2 ends[2] = {j.x, j.x + j.brake};
      double gap = 1e9;
      for (int k = 0; k <= 20; ++k)
        for (const Vec2& q : ends) gap = std::min(gap, (s.x + (k / 20.0) * e - q).norm());
      if (gap >= 0.26) break;
    }
    // Mostly toward the neighbour, where the filter has something to cut.
    const Vec2 wanted = s.x + 0.3 * (j.x - s.x).normalized() + random_vec(rng, 0.15);
    SafetyState st;
    const SafetyOutcome f = safety_filter(p, st, 0, s.x, wanted, {j}, {}, e);
    VehicleState law = s, ours = s;
    drive(vp, law, {f.x, (f.x - s.x) / dt, false}, dt, 1e6);
    bool outside = true;
    drive_safely(vp, ours, {wanted, Vec2::Zero(), false}, f, dt, 1e6, outside);
    REQUIRE_FALSE(outside);
    REQUIRE(f.holds(ours.x, ours.x + braking_displacement(ours.velocity, vp.max_accel, h)));
    if ((ours.velocity - law.velocity).norm() < 1e-12) continue;
    ++cut;
    // Every velocity within a h of v0 (and max_speed), on a 201 x 201 grid.
    const double r = vp.max_accel * h;
    double best = (ours.velocity - law.velocity).norm();
    for (int a = -100; a <= 100; ++a)
      for (int b = -100; b <= 100; ++b) {
        const Vec2 v1 = s.velocity + (r / 100.0) * Vec2(a, b);
        if ((v1 - s.velocity).norm() > r || v1.norm() > vp.max_speed) continue;
        const Vec2 x1 = s.x + 0.5 * h * (s.velocity + v1);
        if (f.holds(x1, x1 + braking_displacement(v1, vp.max_accel, h)))
          best = std::min(best, (v1 - law.velocity).norm());
      }
    excess.push_back(((ours.velocity - law.velocity).norm() - best) / r);
  }
  REQUIRE(cut > 100);
  std::sort(excess.begin(), excess.end());
  const auto at = [&](double q) { return excess[static_cast<std::size_t>(q * static_cast<double>(excess.size() - 1))]; };
  // The grid's spacing is 0.01 a h: the search is as good as the brute force to about that (the
  // straight way from braking alone was 0.82 a h off at worst).
  CHECK(excess.back() < 0.02);
  WARN("double integrator, " << excess.size() << " cut velocities: excess over the best / (a h): median " << at(0.5)
                             << ", 90 % " << at(0.9) << ", max " << excess.back());
}

TEST_CASE("safety: two double integrators seeing each other a step late back off when too near, and pass",
          "[safety][braking]") {
  // As agent processes see them: the other's state of one step earlier, its velocity the mean of its
  // step before that (blurred by braking_lipschitz * a h / 2), its segment's ends at most 2 vmax + a h / 2
  // per unit age. Without backing off two such agents within the margins freeze for ever.
  VehicleParams vp;
  vp.model = VehicleModel::DoubleIntegrator;
  vp.max_speed = 0.1;
  vp.max_accel = 0.05;
  const double h = 1.0;
  SafetyParams p;
  p.min_separation = 0.25;
  p.max_step = 0.1;
  p.braking = true;
  const double blur = braking_lipschitz(vp.max_speed, vp.max_accel, h) * 0.5 * vp.max_accel * h;
  const double ends = 2.0 * vp.max_speed + 0.5 * vp.max_accel * h;
  // 0.3 apart: beyond d, within d + the margins (0.29), so neither segment may grow.
  VehicleState s[2] = {vehicle_start(Vec2(-0.15, 0.01), 0.0), vehicle_start(Vec2(0.15, -0.01), 0.0)};
  Vec2 seen[2] = {s[0].x, s[1].x}, seen_v[2] = {Vec2::Zero(), Vec2::Zero()}, last_mean[2] = {Vec2::Zero(), Vec2::Zero()};
  const Vec2 goal[2] = {Vec2(2, 0), Vec2(-2, 0)};
  SafetyState st[2];
  double closest = 1e9;
  int backed = 0, outside = 0;
  for (int k = 0; k < 1500; ++k) {
    VehicleState next[2] = {s[0], s[1]};
    for (int i = 0; i < 2; ++i) {
      const Vec2 step = goal[i] - s[i].x;
      const Vec2 wanted = s[i].x + (step.norm() > 0.1 ? Vec2(0.1 * step.normalized()) : step);
      const SafetyNeighbour j{1 - i, seen[1 - i], 1.0, ends, braking_displacement(seen_v[1 - i], vp.max_accel, h), blur};
      const SafetyOutcome f = safety_filter(p, st[i], i, s[i].x, wanted, {j}, {},
                                            braking_displacement(s[i].velocity, vp.max_accel, h));
      backed += f.away != Vec2::Zero() ? 1 : 0;
      bool out = false;
      drive_safely(vp, next[i], {wanted, (wanted - s[i].x) / h, false}, f, h, 1e6, out);
      outside += out ? 1 : 0;
    }
    // Next step's view: the state before this step (one step old by then), with the mean velocity of
    // the step that ended there.
    for (int i = 0; i < 2; ++i) {
      seen[i] = s[i].x;
      seen_v[i] = last_mean[i];
      last_mean[i] = (next[i].x - s[i].x) / h;
    }
    s[0] = next[0];
    s[1] = next[1];
    closest = std::min(closest, (s[0].x - s[1].x).norm());
  }
  CHECK(closest >= 0.25 - 1e-9);
  CHECK(outside == 0);
  CHECK(backed > 0);
  CHECK((s[0].x - goal[0]).norm() < 0.01);  // both arrived
  CHECK((s[1].x - goal[1]).norm() < 0.01);
}
