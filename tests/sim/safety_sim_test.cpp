// The safety filter in the simulator (core::safety_filter through core::Swarm): from starts that force
// crossings and head-on meetings, no pair of agents ever comes closer than safety.min_separation, at
// any step, for both laws and every vehicle model; the same starts without the filter
// do come closer (so these tests fail without it); off, the filter leaves every bit as it was.
#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "config/config.hpp"
#include "core/fence.hpp"
#include "core/safety.hpp"
#include "simulation.hpp"

using namespace shapeform;
using core::Vec2;

namespace {

const std::string kSourceDir = SHAPEFORM_SOURCE_DIR;
constexpr double kPi = 3.14159265358979323846;
constexpr double kSeparation = 0.25;

/// A start that forces crossings, and the command (as --set settings) that makes them cross.
struct Start {
  std::string name;
  std::vector<Vec2> x;
  std::vector<std::string> sets;
};

std::vector<Vec2> on_circle(int n, double r) {
  std::vector<Vec2> x;
  for (int i = 0; i < n; ++i) x.emplace_back(r * std::cos(2 * kPi * i / n), r * std::sin(2 * kPi * i / n));
  return x;
}

/// Uniform in [-w, w]^2, each point at least d from the others (rejection, seeded).
std::vector<Vec2> dense(int n, double w, double d, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-w, w);
  std::vector<Vec2> x;
  while (static_cast<int>(x.size()) < n) {
    const double a = u(rng);
    const double b = u(rng);
    const Vec2 p(a, b);
    bool ok = true;
    for (const Vec2& q : x) ok = ok && (p - q).norm() >= d;
    if (ok) x.push_back(p);
  }
  return x;
}

/// Two groups in grids of spacing 0.5, left and right of the origin.
std::vector<Vec2> two_groups(int n) {
  std::vector<Vec2> x;
  const int side = static_cast<int>(std::ceil(std::sqrt(n / 2.0)));
  for (int i = 0; static_cast<int>(x.size()) < n; ++i) {
    const int g = i % 2, k = i / 2;
    x.emplace_back((g == 0 ? -6.0 : 6.0) + 0.5 * (k % side), 0.5 * (k / side) - 0.25 * side);
  }
  return x;
}

/// The five crossing starts for n agents.
std::vector<Start> starts(int n) {
  std::vector<Vec2> line;
  for (int i = 0; i < n; ++i) line.emplace_back(0.5 * (i - (n - 1) / 2.0), 0.0);
  return {
      // every pair (theta, -theta) meets head-on on the x1 axis
      {"circle folded onto a line", on_circle(n, 5.0), {"shape.kind=line", "shape.m=0", "shape.c=0"}},
      // every agent's closest point of the new line is the origin
      {"line turned by 90 degrees",
       line,
       {"shape.kind=line", "shape.m=0", "shape.c=0", "shape.rotation_deg=90"}},
      {"shrinking circle", on_circle(n, 7.0), {"shape.kind=circle", "shape.r0=3"}},
      {"dense random start",
       dense(n, 0.3 * std::sqrt(n), kSeparation, 7),
       {"shape.kind=circle", "shape.r0=4"}},
      // the groups meet head-on on the vertical line between them
      {"two groups meet head-on",
       two_groups(n),
       {"shape.kind=line", "shape.m=0", "shape.c=0", "shape.rotation_deg=90"}},
  };
}

/// A small indoor robot: a unicycle with limits, facing anywhere at the start.
const std::vector<std::string> kUnicycle = {"vehicle.model=unicycle", "vehicle.max_speed=0.5",
                                            "vehicle.max_yaw_rate=1", "vehicle.heading_spread_deg=180"};

/// A small robot as a point mass: it cannot stop within a step (0.5 m/s, 0.5 m/s^2).
const std::vector<std::string> kDoubleIntegrator = {"vehicle.model=double_integrator", "vehicle.max_speed=0.5",
                                                    "vehicle.max_accel=0.5"};

/// The law's scenario with the start's shape, the vehicle and the separation, run from the start.
sim::SimResult run(const std::string& law, const Start& s, const std::vector<std::string>& vehicle, double d,
                   long steps) {
  std::vector<std::string> sets = s.sets;
  sets.insert(sets.end(), vehicle.begin(), vehicle.end());
  sets.push_back("safety.min_separation=" + std::to_string(d));
  sets.push_back("sim.steps=" + std::to_string(steps));
  const config::Config cfg = config::load(
      kSourceDir + "/config/scenarios/" + (law == "arc" ? "arc_circle" : "circle") + ".yaml", sets);
  sim::SimOptions opt = sim::run_options(cfg.supervisor.converge, cfg.vehicle, cfg.swarm.seed);
  opt.separation = true;
  return sim::run_simulation(cfg.command, s.x, cfg.sim.steps, opt);
}

double start_separation(const std::vector<Vec2>& x) {
  double best = 1e300;
  for (std::size_t i = 0; i < x.size(); ++i)
    for (std::size_t j = i + 1; j < x.size(); ++j) best = std::min(best, (x[i] - x[j]).norm());
  return best;
}

}  // namespace

TEST_CASE("safety in the simulator: no pair ever comes closer than min_separation, from every crossing start",
          "[sim][safety]") {
  int filtered_runs = 0, unfiltered_below = 0, converged = 0;
  for (const int n : {12, 50}) {
    for (const Start& s : starts(n)) {
      REQUIRE(start_separation(s.x) >= kSeparation);
      for (const std::string law : {"paper", "arc"}) {
        for (const std::string model : {"integrator", "unicycle", "double_integrator"}) {
          INFO(s.name << ", N = " << n << ", law " << law << ", " << model);
          const std::vector<std::string> vehicle = model == "unicycle"            ? kUnicycle
                                                   : model == "double_integrator" ? kDoubleIntegrator
                                                                                  : std::vector<std::string>{};
          const long steps = model == "integrator" ? 400 : 600;
          const sim::SimResult on = run(law, s, vehicle, kSeparation, steps);
          REQUIRE(on.separation.min);
          CHECK(*on.separation.min >= kSeparation - 1e-9);
          CHECK(on.safety.outside == 0);
          CHECK(on.safety.broken == 0);  // nobody started closer, so nobody was ever found closer
          ++filtered_runs;
          converged += on.converged ? 1 : 0;
          const sim::SimResult off = run(law, s, vehicle, 0.0, steps);
          REQUIRE(off.separation.min);
          unfiltered_below += *off.separation.min < kSeparation ? 1 : 0;
          if (on.converged) CHECK(on.blocked_agents == 0);
          // The arc law forms every one of these shapes with the filter; no run the filter is on loses
          // the verdict the unfiltered run had (the paper's law at N = 50 packs agents closer than the
          // separation: it never converges there, and with the filter its verdict says "blocked").
          if (law == "arc") CHECK(on.converged);
          CHECK((on.converged || !off.converged));
          UNSCOPED_INFO(s.name << " N=" << n << " " << law << " " << model
                               << ": min " << *on.separation.min << " (off: " << *off.separation.min
                               << "), converged " << on.converged << " at " << on.converged_step.value_or(-1)
                               << " (off: " << off.converged << " at " << off.converged_step.value_or(-1)
                               << "), interventions " << on.safety.interventions << ", sidesteps "
                               << on.safety.sidesteps << ", verdict " << core::to_string(on.why));
        }
      }
    }
  }
  CHECK(filtered_runs == 60);
  // Without the filter most of these runs bring agents closer than the separation: the starts do force it.
  CHECK(unfiltered_below >= 25);
  CHECK(converged >= 30);
  WARN("runs converged with the filter: " << converged << " of " << filtered_runs
                                          << "; unfiltered runs below the separation: " << unfiltered_below);
}

TEST_CASE("safety in the simulator: off (0), every bit is the law's, and the batched kernel stays as it was",
          "[sim][safety]") {
  for (const std::string law : {"paper", "arc"}) {
    const Start s = starts(12)[2];
    const sim::SimResult a = run(law, s, {}, 0.0, 200);
    // The plain run, without the safety keys at all.
    const config::Config cfg =
        config::load(kSourceDir + "/config/scenarios/" + (law == "arc" ? "arc_circle" : "circle") + ".yaml",
                     {"shape.kind=circle", "shape.r0=3", "sim.steps=200"});
    CHECK_FALSE(core::filters(cfg.command));
    const sim::SimResult b = sim::run_simulation(cfg.command, s.x, 200);
    REQUIRE(a.final_positions.size() == b.final_positions.size());
    for (std::size_t i = 0; i < a.final_positions.size(); ++i) {
      CHECK(a.final_positions[i].x() == b.final_positions[i].x());
      CHECK(a.final_positions[i].y() == b.final_positions[i].y());
    }
    CHECK(a.safety.interventions == 0);
  }
  // The batched kernel applies only without the filter.
  core::CompiledCommand c;
  CHECK(core::batch_applies(c, {}));
  c.min_separation = 0.1;
  CHECK_FALSE(core::batch_applies(c, {}));
}

TEST_CASE("safety in the simulator: a keep-out zone on the way is never entered, the shape forms around it",
          "[sim][safety]") {
  for (const std::string law : {"paper", "arc"}) {
    for (const bool unicycle : {false, true}) {
      INFO("law " << law << (unicycle ? " unicycle" : " integrator"));
      // From a circle of radius 7 to one of radius 3: a disc, a triangle and an L (not convex) sit on
      // the straight ways of the agents at 0, 120 and 240 degrees.
      const std::string zones =
          "[{circle: [5, 0, 1]}, {polygon: [[-3.5, 3.8], [-1.5, 3.8], [-2.5, 5.2]]}, "
          "{polygon: [[-3, -5], [-3, -3.5], [-2.4, -3.5], [-2.4, -4.6], [-1.5, -4.6], [-1.5, -5]]}]";
      const std::vector<std::string> vehicle = unicycle ? kUnicycle : std::vector<std::string>{};
      Start s{"shrinking circle through zones",
              on_circle(12, 7.0),
              {"shape.kind=circle", "shape.r0=3", "safety.keep_out=" + zones}};
      const sim::SimResult r = run(law, s, vehicle, kSeparation, 500);
      CHECK(r.separation.zone_entries == 0);
      CHECK(r.separation.zone_depth <= 1e-9);
      CHECK(*r.separation.min >= kSeparation - 1e-9);
      CHECK(r.safety.interventions > 0);
      // Without the filter the same agents do cross the zones.
      const config::Config cfg =
          config::load(kSourceDir + "/config/scenarios/" + (law == "arc" ? "arc_circle" : "circle") + ".yaml",
                       {"shape.kind=circle", "shape.r0=3", "safety.keep_out=" + zones});
      const std::vector<core::ConvexZone> pieces = core::convex_pieces(cfg.command.keep_out);
      core::CompiledCommand free = cfg.command;
      free.keep_out.clear();
      core::Swarm swarm(free, s.x);
      sim::SimOptions opt;
      opt.vehicle = config::load(kSourceDir + "/config/scenarios/circle.yaml", vehicle).vehicle;
      swarm.set_vehicle(opt.vehicle, core::start_headings(opt.vehicle, 12, 1));
      long entries = 0;
      for (int k = 0; k < 500; ++k) {
        swarm.step();
        for (const Vec2& x : swarm.positions())
          for (const core::ConvexZone& z : pieces) entries += core::inside(z, x) ? 1 : 0;
      }
      CHECK(entries > 0);
    }
  }
}

TEST_CASE("safety in the simulator: an agent placed on top of another steps away, counted", "[sim][safety]") {
  std::vector<Vec2> x = on_circle(12, 4.0);
  x.push_back(x[0] + Vec2(0.05, 0.0));  // a late joiner on top of agent 0
  const Start s{"joiner on top", x, {"shape.kind=circle", "shape.r0=4"}};
  const sim::SimResult r = run("arc", s, {}, kSeparation, 300);
  CHECK(r.safety.broken > 0);
  REQUIRE(r.separation.min);
  CHECK(r.separation.step == 0);  // the start is the closest moment: from then on they only part
  CHECK(start_separation(r.final_positions) >= kSeparation - 1e-9);
}

TEST_CASE(
    "safety in the simulator: a fence that cuts through the circle is never left, the rest of the shape "
    "forms",
    "[sim][safety][fence]") {
  // The circle of radius 4 about the origin; the fence cuts it off at x1 = 2.5 (a slanted edge from
  // (2, -6) to (3, 6)) and the agents start inside it.
  const std::vector<Vec2> fence = {Vec2(-6, -6), Vec2(2, -6), Vec2(3, 6), Vec2(-6, 6)};
  for (const std::string law : {"paper", "arc"}) {
    for (const double margin : {0.0, 0.3}) {
      INFO("law " << law << ", margin " << margin);
      config::Config cfg =
          config::load(kSourceDir + "/config/scenarios/" + (law == "arc" ? "arc_circle" : "circle") + ".yaml",
                       {"shape.kind=circle", "shape.r0=4"});
      cfg.command.fence = fence;
      cfg.command.fence_margin = margin;
      REQUIRE(core::fence_problems(fence, cfg.command.workspace).empty());
      REQUIRE(core::filters(cfg.command));
      const std::vector<Vec2> start = dense(12, 2.0, kSeparation, 11);
      core::Swarm swarm(cfg.command, start);
      double worst = 0.0, worst_shrunk = 0.0;
      const std::vector<core::HalfPlane> inner = core::fence_half_planes(cfg.command);
      for (int k = 0; k < 400; ++k) {
        swarm.step();
        for (const Vec2& x : swarm.positions()) {
          worst = std::max(worst, core::beyond_fence(cfg.command, x));
          for (const core::HalfPlane& h : inner) worst_shrunk = std::max(worst_shrunk, h.n.dot(x) - h.b);
        }
      }
      CHECK(worst <= 1e-9);  // rounding: the filter's constraints hold to 1e-12 of their size
      CHECK(worst_shrunk <= 1e-9);
      CHECK(swarm.safety_counts().interventions > 0);
      // The agents the fence holds back sit on it; the others reach the circle (the arc law exactly; the
      // paper's law, pulled in by its cohesion term, within 0.5 after 400 steps).
      int on_circle = 0;
      const double band = law == "arc" ? 0.1 : 0.5;
      for (const Vec2& x : swarm.positions()) on_circle += std::abs(x.norm() - 4.0) < band ? 1 : 0;
      CHECK(on_circle >= 8);
      // Without the fence the same agents do cross the line.
      core::CompiledCommand free = cfg.command;
      free.fence.clear();
      free.fence_margin = 0.0;
      core::Swarm unfenced(free, start);
      double crossed = 0.0;
      for (int k = 0; k < 400; ++k) {
        unfenced.step();
        for (const Vec2& x : unfenced.positions())
          crossed = std::max(crossed, core::beyond_fence(cfg.command, x));
      }
      CHECK(crossed > 0.5);
    }
  }
}
