// The paper's model on its own scenarios: facts of the model with its published parameters
// (Euler dt = 1, starts uniform in [-5,5]^2), as medians over 20 seeds.
#include <catch2/catch.hpp>
#include <algorithm>
#include <functional>

#include "config/config.hpp"
#include "simulation.hpp"

using namespace shapeform;

namespace {
config::Config scenario(const std::string& name, std::vector<std::string> sets = {}) {
  return config::load(std::string(SHAPEFORM_SOURCE_DIR) + "/config/scenarios/" + name + ".yaml", sets);
}

struct Runs {
  std::vector<sim::SimResult> r;
  double median(const std::function<double(const core::Metrics&)>& f) const {
    std::vector<double> v;
    for (const auto& x : r) v.push_back(f(x.metrics));
    std::sort(v.begin(), v.end());
    const auto n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
  }
  double min(const std::function<double(const core::Metrics&)>& f) const {
    double m = 1e300;
    for (const auto& x : r) m = std::min(m, f(x.metrics));
    return m;
  }
  double max(const std::function<double(const core::Metrics&)>& f) const {
    double m = -1e300;
    for (const auto& x : r) m = std::max(m, f(x.metrics));
    return m;
  }
};

Runs run_seeds(const config::Config& c, long steps, int seeds = 20) {
  Runs out;
  for (int s = 1; s <= seeds; ++s) {
    const auto start = core::uniform_start(c.swarm.agents, static_cast<std::uint64_t>(s), 5.0);
    out.r.push_back(sim::run_simulation(c.command, start, steps));
  }
  return out;
}

const auto err = [](const core::Metrics& m) { return m.shape_error_mean.value(); };
const auto gap = [](const core::Metrics& m) { return m.gap_cv.value_or(1e9); };
const auto minsep = [](const core::Metrics& m) { return m.min_separation.value(); };
const auto extent = [](const core::Metrics& m) { return m.extent.value(); };
const auto clusters = [](const core::Metrics& m) { return static_cast<double>(m.clusters.value()); };
}  // namespace

TEST_CASE("circle, 12 agents: the ring settles inside r0 (radius about 3.83)", "[sim][paper]") {
  const Runs r = run_seeds(scenario("circle"), 500);
  CHECK(r.median(err) >= 0.16);
  CHECK(r.median(err) <= 0.18);
  CHECK(r.median(gap) <= 0.10);
  CHECK(r.min(minsep) >= 1.5);
  CHECK(r.min(clusters) == 12);
}

TEST_CASE("circle, 10 agents: plateau error 0.036-0.042", "[sim][paper]") {
  const Runs r = run_seeds(scenario("circle", {"swarm.agents=10"}), 500);
  CHECK(r.median(err) >= 0.036);
  CHECK(r.median(err) <= 0.042);
}

TEST_CASE("ellipse and square, 12 agents", "[sim][paper]") {
  const Runs e = run_seeds(scenario("ellipse"), 500);
  CHECK(e.median(err) >= 0.35);
  CHECK(e.median(err) <= 0.55);
  CHECK(e.median(gap) <= 0.12);
  const Runs s = run_seeds(scenario("square"), 500);
  CHECK(s.median(err) >= 0.30);
  CHECK(s.median(err) <= 0.45);
  CHECK(s.median(gap) <= 0.05);
}

TEST_CASE("line: 12 agents on the line keep spreading, 20 stay compact", "[sim][paper]") {
  const Runs l12 = run_seeds(scenario("line"), 500);
  CHECK(l12.median(err) <= 1e-3);
  CHECK(l12.median(extent) >= 60);
  CHECK(l12.median(extent) <= 95);
  // Still growing: the extent at 500 is well above the extent at 250.
  const Runs l12_half = run_seeds(scenario("line"), 250);
  CHECK(l12.median(extent) > 1.5 * l12_half.median(extent));
  const Runs l20 = run_seeds(scenario("line", {"swarm.agents=20"}), 1000);
  CHECK(l20.median(extent) <= 3.0);
}

TEST_CASE("repulsion study: without repulsion the agents clump", "[sim][paper][repulsion]") {
  for (const std::string shape : {"ellipse", "square"}) {
    INFO(shape);
    const Runs with = run_seeds(scenario(shape), 200);
    const Runs without = run_seeds(scenario(shape + "_no_repulsion"), 200);
    CHECK(without.median(gap) >= 1.0);
    CHECK(without.median(gap) >= 10 * with.median(gap));
    CHECK(with.min(clusters) == 12);
    CHECK(run_seeds(scenario(shape), 1000).min(clusters) == 12);  // with r = 0.1 all 12 stay apart
    const Runs without_long = run_seeds(scenario(shape + "_no_repulsion"), 1000);
    // Medians over 20 seeds, as the claim is stated: a few seeds leave two clumps on opposite sides of
    // the square, where cohesion at distance 12 is too weak to pull them together.
    CHECK(without_long.median(clusters) == 1);
  }
}

TEST_CASE("tracking without feed-forward: the swarm trails the centre as a blob", "[sim][paper][tracking]") {
  const auto ce = [](const core::Metrics& m) { return m.centroid_error.value(); };
  const auto re = [](const core::Metrics& m) { return m.ring_error.value(); };
  const Runs line = run_seeds(scenario("track_line"), 200);
  CHECK(line.median(ce) >= 4.0);
  CHECK(line.median(ce) <= 5.2);
  CHECK(line.median(re) >= 2.1);
  CHECK(line.median(re) <= 3.2);
  const Runs circ = run_seeds(scenario("track_circle"), 200);
  CHECK(circ.median(ce) >= 4.0);
  CHECK(circ.median(ce) <= 4.9);
  CHECK(circ.median(re) >= 2.1);
  CHECK(circ.median(re) <= 3.2);
}

TEST_CASE("RK4 with dt = 0.05 removes Euler's chatter", "[sim][paper][rk4]") {
  const config::Config c = scenario("circle", {"integration.integrator=rk4", "integration.dt=0.05"});
  const Runs r = run_seeds(c, 10000);  // t = 500, 20 seeds like the other claims
  CHECK(r.median(gap) <= 0.005);
  CHECK(r.median(err) >= 0.16);  // the same off-shape plateau: a fact of the model, not of Euler
  CHECK(r.median(err) <= 0.18);
}

TEST_CASE("the simulator is deterministic by seed", "[sim]") {
  const config::Config c = scenario("square");
  const auto a = sim::run_simulation(c.command, core::uniform_start(12, 42), 100);
  const auto b = sim::run_simulation(c.command, core::uniform_start(12, 42), 100);
  const auto d = sim::run_simulation(c.command, core::uniform_start(12, 43), 100);
  CHECK(a.final_positions == b.final_positions);
  CHECK(a.final_positions != d.final_positions);
}

TEST_CASE("one agent alone goes straight to the shape", "[sim][singular]") {
  const config::Config c = scenario("circle", {"swarm.agents=1"});
  const auto r = sim::run_simulation(c.command, {core::Vec2(0, 0)}, 200);  // starts at the centre
  CHECK(*r.metrics.shape_error_mean < 1e-6);
  CHECK(r.final_positions[0].y() == 0.0);  // it left along (1, 0)
  CHECK_FALSE(r.metrics.gap_cv);
}
