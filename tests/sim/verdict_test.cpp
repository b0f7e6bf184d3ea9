// The verdict (core::ConvergenceDetector through run_simulation) on the paper's own scenarios: the
// paper's law is called converged where it forms its shapes, and not where the issue found the old
// verdict lying (a 20-wide start, the growing line).
#include <catch2/catch.hpp>

#include "config/config.hpp"
#include "simulation.hpp"

using namespace shapeform;
using Why = core::ConvergenceDetector::Why;

namespace {
config::Config scenario(const std::string& name, std::vector<std::string> sets = {}) {
  return config::load(std::string(SHAPEFORM_SOURCE_DIR) + "/config/scenarios/" + name + ".yaml", sets);
}
sim::SimResult run(const config::Config& c, long steps, std::uint64_t seed) {
  sim::SimOptions opt;
  opt.converge = c.supervisor.converge;
  return sim::run_simulation(c.command, core::uniform_start(c.swarm.agents, seed, c.swarm.init_half_width),
                             steps, opt);
}
}  // namespace

TEST_CASE("verdict: the paper's circle and square converge", "[sim][verdict]") {
  // The circle on every seed. The square's plateau wanders by more than the steadiness band now and
  // then (the band, unchanged here, restarts the 50 model time span): most seeds at any one time.
  for (const char* name : {"circle", "square"}) {
    const config::Config c = scenario(name);
    int converged = 0;
    for (std::uint64_t seed = 1; seed <= 20; ++seed) {
      const sim::SimResult r = run(c, 1000, seed);
      INFO(name << " seed " << seed << " error " << r.metrics.shape_error_mean.value() << " verdict "
                << core::to_string(r.why));
      CHECK((r.converged || r.why == Why::Holding || r.why == Why::Unsteady));
      converged += r.converged ? 1 : 0;
    }
    CHECK(converged >= (std::string(name) == "circle" ? 20 : 15));
  }
}

TEST_CASE("verdict: the paper's plateaus are on their shapes, with a margin", "[sim][verdict]") {
  // The ellipse's error wanders (0.35 to 0.55) and is seldom steady for 50 model time: it must still
  // never be called off its shape.
  for (const char* name : {"circle", "ellipse", "square"}) {
    const config::Config c = scenario(name);
    const double bound = core::on_shape_bound(c.command, c.supervisor.converge);
    for (std::uint64_t seed = 1; seed <= 20; ++seed) {
      const sim::SimResult r = run(c, 1000, seed);
      INFO(name << " seed " << seed);
      CHECK(*r.metrics.shape_error_mean <= bound / 1.4);
      CHECK(r.why != Why::OffShape);
    }
  }
  CHECK(core::on_shape_bound(scenario("circle").command, {}) == Approx(0.8));
  CHECK(core::on_shape_bound(scenario("ellipse").command, {}) == Approx(0.8));
  CHECK(core::on_shape_bound(scenario("square").command, {}) == Approx(1.0));
}

TEST_CASE("verdict: a 20-wide start, off its circle for good, is not converged", "[sim][verdict]") {
  const config::Config c = scenario("circle", {"swarm.init_half_width=20"});
  const sim::SimResult r = run(c, 2000, c.swarm.seed);
  CHECK(*r.metrics.shape_error_mean > 10);
  CHECK_FALSE(r.converged);
  CHECK(r.why == Why::OffShape);
}

TEST_CASE("verdict: eight agents on the paper's line keep growing: not converged", "[sim][verdict]") {
  const config::Config c = scenario("line", {"swarm.agents=8"});
  const sim::SimResult r = run(c, 2000, c.swarm.seed);
  CHECK(*r.metrics.shape_error_mean < 1e-6);  // every agent on the line, evenly spaced ...
  CHECK(*r.metrics.gap_cv < 0.05);
  CHECK_FALSE(r.converged);  // ... and the line still growing
  CHECK(r.why == Why::Growing);
}
