#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <string>
#include <utility>

#include "core/metrics.hpp"

using namespace shapeform::core;

namespace {
CompiledCommand circle_cmd(double r0 = 4.0) {
  Command c;
  c.shape.kind = ShapeKind::Circle;
  c.shape.r0 = r0;
  return compile(c);
}
std::vector<Vec2> ring(int n, double radius, Vec2 centre = Vec2::Zero(), double phase = 0.3) {
  std::vector<Vec2> x;
  for (int i = 0; i < n; ++i) {
    const double a = phase + 2 * M_PI * i / n;
    x.push_back(centre + radius * Vec2(std::cos(a), std::sin(a)));
  }
  return x;
}
}  // namespace

TEST_CASE("an evenly spaced ring on the circle: zero error, gap CV 0", "[metrics]") {
  const Metrics m = compute_metrics(circle_cmd(), ring(12, 4.0), 0);
  REQUIRE(m.shape_error_mean);
  CHECK(*m.shape_error_mean < 1e-12);
  CHECK(*m.shape_error_max < 1e-12);
  CHECK(*m.gap_cv < 1e-12);
  CHECK(*m.nn_cv < 1e-12);
  CHECK(*m.min_separation == Approx(2 * 4.0 * std::sin(M_PI / 12)));
  CHECK(*m.extent == Approx(8.0));
  CHECK(*m.clusters == 12);
  CHECK_FALSE(m.centroid_error);  // not tracking
}

TEST_CASE("a ring of radius 3.83 on r0 = 4 has shape error 0.17", "[metrics]") {
  const Metrics m = compute_metrics(circle_cmd(), ring(12, 3.83), 0);
  CHECK(*m.shape_error_mean == Approx(0.17));
  CHECK(*m.shape_error_max == Approx(0.17));
}

TEST_CASE("two equal clusters have gap CV 1 and count as 2", "[metrics]") {
  // Four agents: two at angle 0, two at angle pi (ordered by angle: 0, 0, pi, pi).
  // Gaps 0, 8, 0, 8: mean 4, std 4, CV 1.
  std::vector<Vec2> x = {Vec2(4, 0), Vec2(4, 0), Vec2(-4, 0), Vec2(-4, 0)};
  const Metrics m = compute_metrics(circle_cmd(), x, 0);
  CHECK(*m.gap_cv == Approx(1.0));
  CHECK(*m.clusters == 2);
  CHECK(*m.min_separation == 0.0);
  CHECK(*m.extent == Approx(8.0));
  // Nearest-neighbour distances are all 0: their CV is undefined, not 0.
  CHECK_FALSE(m.nn_cv);
}

TEST_CASE("line gaps are ordered along the line", "[metrics]") {
  Command line;
  line.shape.kind = ShapeKind::Line;
  line.shape.m = 0;
  line.shape.c = 1;
  const CompiledCommand c = compile(line);
  // Positions given out of order: 3, 0, 1 along x. Gaps 1 and 2: CV = 0.5 / 1.5.
  std::vector<Vec2> x = {Vec2(3, 1), Vec2(0, 1), Vec2(1, 1)};
  const auto gaps = consecutive_gaps(c.shape, c.curve(), x);
  REQUIRE(gaps.size() == 2);
  const Metrics m = compute_metrics(c, x, 0);
  CHECK(*m.gap_cv == Approx(1.0 / 3.0));
  CHECK(*m.shape_error_mean < 1e-12);
}

TEST_CASE("closed gaps wrap around", "[metrics]") {
  // Three agents at angles 0, 90, 180 degrees on radius 1: gaps sqrt2, sqrt2, 2.
  const CompiledCommand c = circle_cmd(1.0);
  std::vector<Vec2> x = {Vec2(0, 1), Vec2(1, 0), Vec2(-1, 0)};
  const auto gaps = consecutive_gaps(c.shape, c.curve(), x);
  REQUIRE(gaps.size() == 3);
  double sum = 0;
  for (double g : gaps) sum += g;
  CHECK(sum == Approx(2 * std::sqrt(2.0) + 2));
}

TEST_CASE("undefined metrics are null, never 0 or NaN", "[metrics]") {
  const Metrics none = compute_metrics(circle_cmd(), {}, 0);
  CHECK(none.agents == 0);
  CHECK_FALSE(none.shape_error_mean);
  CHECK_FALSE(none.clusters);

  const Metrics one = compute_metrics(circle_cmd(), {Vec2(1, 1)}, 0);
  CHECK(one.shape_error_mean);
  CHECK_FALSE(one.gap_cv);
  CHECK_FALSE(one.nn_cv);
  CHECK_FALSE(one.min_separation);
  CHECK_FALSE(one.extent);
  CHECK(*one.clusters == 1);

  const std::vector<Vec2> same(5, Vec2(2, 2));
  const Metrics merged = compute_metrics(circle_cmd(), same, 0);
  CHECK_FALSE(merged.gap_cv);
  CHECK_FALSE(merged.nn_cv);
  CHECK(*merged.min_separation == 0.0);
  CHECK(*merged.clusters == 1);
  CHECK_FALSE(coefficient_of_variation({}));
  CHECK(*coefficient_of_variation({1.0}) == 0.0);  // two agents on a line: one gap, evenly spaced
  CHECK_FALSE(coefficient_of_variation({0.0}));    // ... unless they are on one point
  CHECK(*coefficient_of_variation({1.0, 3.0}) == Approx(0.5));
}

TEST_CASE("tracking metrics: centroid and ring errors about C(t)", "[metrics][tracking]") {
  CompiledCommand c = circle_cmd(2.0);
  c.tracking.enabled = true;
  c.tracking.path.kind = CentrePath::Kind::Line;
  c.tracking.path.point = Vec2(-10, -10);
  c.tracking.path.velocity = Vec2(0.1, 0.1);
  // At t = 50 the centre is (-5, -5). A ring of radius 2.5 around (-4, -5).
  const Metrics m = compute_metrics(c, ring(10, 2.5, Vec2(-4, -5)), 50);
  CHECK(*m.centroid_error == Approx(1.0));
  CHECK(*m.ring_error > 0.0);
  const Metrics on = compute_metrics(c, ring(10, 2.0, Vec2(-5, -5)), 50);
  CHECK(*on.centroid_error < 1e-12);
  CHECK(*on.ring_error < 1e-12);
  CHECK(*on.shape_error_mean < 1e-12);
  // The ring as drawn: r0 = 2 at scale 1.5 is a ring of radius 3.
  c.shape.scale = 1.5;
  const Metrics scaled = compute_metrics(c, ring(10, 3.0, Vec2(-5, -5)), 50);
  CHECK(*scaled.ring_error < 1e-12);
  CHECK(*scaled.shape_error_mean < 1e-12);
  // Another tracked shape has no ring: its shape error says how far the agents are from it.
  c.shape.kind = ShapeKind::Square;
  c.shape.a = 2.0;
  c = compile(c);  // a new shape: a new curve
  const Metrics square = compute_metrics(c, ring(10, 2.0, Vec2(-5, -5)), 50);
  CHECK(square.centroid_error);
  CHECK_FALSE(square.ring_error);
}

TEST_CASE("cluster counting is single linkage at 0.05", "[metrics]") {
  // A chain with links of 0.04 is one cluster even though its ends are 0.12 apart.
  CHECK(count_clusters({Vec2(0, 0), Vec2(0.04, 0), Vec2(0.08, 0), Vec2(0.12, 0)}) == 1);
  CHECK(count_clusters({Vec2(0, 0), Vec2(0.06, 0)}) == 2);
}

namespace {
/// The pairwise figures by comparing every pair, as compute_metrics did before its grid.
struct Brute {
  std::vector<double> nn;
  double extent = 0.0;
  int clusters = 0;
};
Brute brute(const std::vector<Vec2>& x) {
  Brute b;
  b.nn.assign(x.size(), std::numeric_limits<double>::infinity());
  std::vector<int> parent(x.size());
  std::iota(parent.begin(), parent.end(), 0);
  const auto find = [&](int i) {
    while (parent[static_cast<std::size_t>(i)] != i) i = parent[static_cast<std::size_t>(i)];
    return i;
  };
  b.clusters = static_cast<int>(x.size());
  for (std::size_t i = 0; i < x.size(); ++i)
    for (std::size_t j = i + 1; j < x.size(); ++j) {
      const double d = (x[i] - x[j]).norm();
      b.nn[i] = std::min(b.nn[i], d);
      b.nn[j] = std::min(b.nn[j], d);
      b.extent = std::max(b.extent, d);
      if (d <= kClusterLink) {
        const int a = find(static_cast<int>(i)), c = find(static_cast<int>(j));
        if (a != c) {
          parent[static_cast<std::size_t>(a)] = c;
          --b.clusters;
        }
      }
    }
  return b;
}
}  // namespace

TEST_CASE("nearest distances, clusters and extent equal comparing every pair, to the bit", "[metrics][pairwise]") {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<std::pair<std::string, std::vector<Vec2>>> swarms;
  for (const int n : {2, 3, 7, 64, 500}) {
    std::vector<Vec2> x;
    for (int i = 0; i < n; ++i) x.emplace_back(10 * u(rng), 10 * u(rng));
    swarms.emplace_back("uniform " + std::to_string(n), x);
  }
  for (const int n : {12, 100, 1000, 1001})
    swarms.emplace_back("ring " + std::to_string(n), ring(n, 4.0, Vec2(3, -2), 0.0));
  {  // tight clumps far apart, chains just under and over the cluster link, duplicates, an outlier
    std::vector<Vec2> x;
    for (int c = 0; c < 6; ++c)
      for (int i = 0; i < 40; ++i) x.emplace_back(100.0 * c + 0.02 * g(rng), -50.0 * c + 0.02 * g(rng));
    for (int i = 0; i < 30; ++i) x.emplace_back(7.0 + 0.049 * i, 7.0);
    for (int i = 0; i < 30; ++i) x.emplace_back(7.0 + 0.051 * i, 9.0);
    for (int i = 0; i < 5; ++i) x.emplace_back(1.5, 1.5);
    x.emplace_back(1e6, -1e6);
    swarms.emplace_back("clumps, chains, duplicates, outlier", x);
  }
  {  // a line (the hull degenerates), and a line with one point off it
    std::vector<Vec2> x;
    for (int i = 0; i < 300; ++i) x.emplace_back(0.1 * i, 5.0 - 0.1 * i);
    swarms.emplace_back("line", x);
    x.emplace_back(3.0, 3.0);
    swarms.emplace_back("line and one", x);
  }
  {  // a square's lattice: many equal distances, parallel hull edges
    std::vector<Vec2> x;
    for (int i = 0; i < 30; ++i)
      for (int j = 0; j < 30; ++j) x.emplace_back(0.5 * i, 0.5 * j);
    swarms.emplace_back("lattice", x);
  }
  for (const auto& [name, x] : swarms) {
    INFO(name);
    const Brute b = brute(x);
    CHECK(nearest_distances(x) == b.nn);
    CHECK(largest_distance(x) == b.extent);
    CHECK(count_clusters(x) == b.clusters);
    // compute_metrics skips the linking pass when no pair is within the link: the same count.
    CHECK(compute_metrics(circle_cmd(), x, 0.0).clusters == b.clusters);
  }
  {  // every pair just over the link, and one pair just under it
    std::vector<Vec2> x;
    for (int i = 0; i < 50; ++i) x.emplace_back(kClusterLink * (1 + 1e-12) * i, 0.0);
    CHECK(compute_metrics(circle_cmd(), x, 0.0).clusters == brute(x).clusters);
    x.emplace_back(x.back().x() + kClusterLink * (1 - 1e-12), 0.0);
    CHECK(compute_metrics(circle_cmd(), x, 0.0).clusters == brute(x).clusters);
    CHECK(brute(x).clusters == 50);
  }
  CHECK(largest_distance({}) == 0.0);
  CHECK(largest_distance({Vec2(1, 1), Vec2(1, 1)}) == 0.0);
  CHECK(nearest_distances({Vec2(1, 1)}) == std::vector<double>{std::numeric_limits<double>::infinity()});
  CHECK(count_clusters({}) == 0);
}

TEST_CASE("nearest squared distances to queries equal comparing every pair, to the bit", "[metrics][pairwise]") {
  // A group process's agents (the queries, at their new positions, each with its id) against every
  // state it holds (the points, its own agents' among them): inside the points' box, outside it, far
  // away, on a point, with and without a point of their own id.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const auto brute = [](const std::vector<Vec2>& p, const std::vector<std::int32_t>& pid, const std::vector<Vec2>& q,
                        const std::vector<std::int32_t>& qid) {
    std::vector<double> best(q.size(), std::numeric_limits<double>::infinity());
    for (std::size_t k = 0; k < q.size(); ++k)
      for (std::size_t i = 0; i < p.size(); ++i) {
        if (pid[i] == qid[k]) continue;
        const double dx = p[i].x() - q[k].x(), dy = p[i].y() - q[k].y();
        best[k] = std::min(best[k], dx * dx + dy * dy);
      }
    return best;
  };
  std::vector<std::pair<std::string, std::vector<Vec2>>> sets;
  for (const int n : {1, 2, 50, 1000}) {
    std::vector<Vec2> x;
    for (int i = 0; i < n; ++i) x.emplace_back(10 * u(rng), 10 * u(rng));
    sets.emplace_back("uniform " + std::to_string(n), x);
  }
  sets.emplace_back("ring 1000", ring(1000, 4.0, Vec2(3, -2), 0.0));
  {
    std::vector<Vec2> x;
    for (int i = 0; i < 300; ++i) x.emplace_back(0.1 * i, 5.0 - 0.1 * i);
    for (int i = 0; i < 5; ++i) x.emplace_back(1.5, 1.5);
    x.emplace_back(1e6, -1e6);
    sets.emplace_back("line, duplicates, outlier", x);
  }
  for (const auto& [name, p] : sets) {
    INFO(name);
    std::vector<std::int32_t> pid(p.size());
    std::iota(pid.begin(), pid.end(), 100);
    std::vector<Vec2> q;
    std::vector<std::int32_t> qid;
    for (std::size_t i = 0; i < p.size(); i += 7) {  // hosted agents: their own point, moved a little
      q.push_back(p[i] + Vec2(0.01 * u(rng), 0.01 * u(rng)));
      qid.push_back(pid[i]);
    }
    q.push_back(p.front());  // on a point, not its own
    qid.push_back(-1);
    q.emplace_back(30.0, 30.0);  // outside the box
    qid.push_back(pid.back());
    q.emplace_back(-2e6, 5e5);  // far outside
    qid.push_back(-2);
    CHECK(nearest_squared(p, pid, q, qid) == brute(p, pid, q, qid));
  }
  // Nobody else: infinity.
  CHECK(nearest_squared({Vec2(1, 1)}, {4}, {Vec2(2, 2)}, {4}) ==
        std::vector<double>{std::numeric_limits<double>::infinity()});
  CHECK(nearest_squared({}, {}, {Vec2(2, 2)}, {4}) == std::vector<double>{std::numeric_limits<double>::infinity()});
  CHECK(nearest_squared({Vec2(1, 1)}, {4}, {}, {}).empty());
}

TEST_CASE("settling: first step after which error stays on its plateau", "[metrics][settle]") {
  std::vector<double> err;
  std::vector<std::optional<double>> cv;
  for (int k = 0; k <= 300; ++k) {
    err.push_back(0.17 + 3.0 * std::exp(-k / 20.0) + ((k % 2) ? 0.005 : -0.005));  // chatter
    cv.push_back(k < 150 ? 0.5 : 0.05);
  }
  // Error band 0.02 is reached at k ~ 20 ln(3 / 0.015) = 106, but gap CV only from 150.
  auto s = settle_index(err, cv);
  REQUIRE(s);
  CHECK(*s == 150);
  for (auto& v : cv) v = 0.05;
  s = settle_index(err, cv);
  REQUIRE(s);
  CHECK(*s >= 100);
  CHECK(*s <= 110);
  // Still moving at the end: not settled.
  err.back() = 5.0;
  CHECK_FALSE(settle_index(err, cv));
  CHECK_FALSE(settle_index({}, {}));
}

TEST_CASE("online convergence detector holds for the hold time", "[metrics][settle]") {
  ConvergenceDetector::Params p;
  p.hold = 10;
  ConvergenceDetector d(p);
  for (int k = 0; k < 30; ++k) {
    d.add(k, 2.0 - 0.1 * k, 0.05);  // still falling fast
    CHECK_FALSE(d.converged());
  }
  int first = -1;
  for (int k = 30; k < 60; ++k) {
    d.add(k, 0.17 + ((k % 2) ? 0.004 : -0.004), 0.05);
    if (d.converged() && first < 0) first = k;
  }
  CHECK(first == 40);
  d.add(60, 0.17, std::nullopt);  // undefined gap CV resets
  CHECK_FALSE(d.converged());
  d.add(61, 0.17, 0.5);  // gap CV over the threshold
  CHECK_FALSE(d.converged());
}

TEST_CASE("verdict: once converged, a falling error keeps it and a rise ends it", "[metrics][verdict]") {
  ConvergenceDetector::Params p;
  p.hold = 10;
  ConvergenceDetector d(p);
  d.set_command(circle_cmd(4.0));
  for (int k = 0; k < 20; ++k) d.add(k, 0.17, 0.05, 4.0);
  REQUIRE(d.converged());
  // Closer to the shape, by more than the band (0.02) within the span, in steps and creeping: still
  // converged at every sample.
  for (int k = 20; k < 40; ++k) {
    d.add(k, k < 25 ? 0.17 - 0.012 * (k - 19) : 0.11 - 0.003 * (k - 25), 0.05, 4.0);
    CHECK(d.converged());
  }
  // Before it was converged a fall of that size is not steady: a new detector waits for the span.
  ConvergenceDetector fresh(p);
  fresh.set_command(circle_cmd(4.0));
  int unsteady = 0;
  for (int k = 0; k < 20; ++k) {
    fresh.add(k, 0.2 - 0.003 * k, 0.05, 4.0);
    CHECK_FALSE(fresh.converged());
    unsteady += fresh.why() == ConvergenceDetector::Why::Unsteady;
  }
  CHECK(unsteady >= 2);
  // A rise within the band above the span's lowest error keeps it; by more than the band ends it.
  const double low = 0.11 - 0.003 * 14;
  d.add(40, low + 0.015, 0.05, 4.0);
  CHECK(d.converged());
  d.add(41, low + 0.025, 0.05, 4.0);
  CHECK_FALSE(d.converged());
  CHECK(d.why() == ConvergenceDetector::Why::Unsteady);
  // Judged anew from there: converged again after a whole span.
  for (int k = 42; k < 51; ++k) {
    d.add(k, low + 0.025, 0.05, 4.0);
    CHECK_FALSE(d.converged());
  }
  d.add(51, low + 0.025, 0.05, 4.0);
  CHECK(d.converged());
}

TEST_CASE("verdict: off the shape, however steady, is not converged", "[metrics][verdict]") {
  ConvergenceDetector::Params p;
  p.hold = 10;
  ConvergenceDetector d(p);
  d.set_command(circle_cmd(4.0));
  CHECK(d.on_shape() == Approx(0.8));  // max(0.5, 0.2 x 4)
  for (int k = 0; k < 60; ++k) {
    d.add(k, 32.0, 0.05, 40.0);  // the 20-wide start: steady, even, 32 units off
    CHECK_FALSE(d.converged());
  }
  CHECK(d.why() == ConvergenceDetector::Why::OffShape);
  for (int k = 60; k < 80; ++k) d.add(k, 0.17, 0.05, 4.0);
  CHECK(d.converged());
  // A new command is judged anew: its own size's bound, from nothing.
  d.set_command(circle_cmd(1.0));
  CHECK_FALSE(d.converged());
  CHECK(d.on_shape() == Approx(0.5));  // the absolute floor
  CompiledCommand scaled = circle_cmd(2.0);
  scaled.shape.scale = 10;
  CHECK(on_shape_bound(scaled, p) == Approx(4.0));
}

TEST_CASE("verdict: a formation on its shape that keeps growing is not converged", "[metrics][verdict]") {
  ConvergenceDetector::Params p;
  p.hold = 50;
  Command line;
  line.shape.kind = ShapeKind::Line;
  ConvergenceDetector d(p);
  d.set_command(compile(line));
  // The paper's 8 agents on the line: on it, evenly spaced, spread growing 0.1 per model time.
  for (int k = 0; k < 300; ++k) {
    d.add(k, 1e-6, 0.01, 40.0 + 0.1 * k);
    CHECK_FALSE(d.converged());
  }
  CHECK(d.why() == ConvergenceDetector::Why::Growing);
  // It stops growing (chatter of 0.1 about a fixed spread): growth is judged over the last `hold`,
  // so the span must first be clear of the growth (about 345), then last `hold` on its own.
  int first = -1;
  for (int k = 300; k < 450; ++k) {
    d.add(k, 1e-6, 0.01, 70.0 + ((k % 2) ? 0.05 : -0.05));
    if (d.converged() && first < 0) first = k;
  }
  CHECK(first >= 390);
  CHECK(first <= 400);
  CHECK(spread({Vec2(0, 0), Vec2(6, 8)}) == Approx(5.0));
  CHECK_FALSE(spread({}));
}
