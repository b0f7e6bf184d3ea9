// shapeform_sim: the headless simulator. Prints ONE JSON object on stdout.
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iostream>

#include "config/config.hpp"
#include "simulation.hpp"

namespace {
int fail(const std::string& msg) {
  std::cerr << "shapeform_sim: " << msg << '\n';
  return 2;
}
}  // namespace

int main(int argc, char** argv) {
  using namespace shapeform;
  CLI::App app{"shapeform_sim: N agents of the configured law (paper or arc) in one process, no DDS. Prints one JSON object."};
  std::string config_path, init_path, csv_path, positions_path, integrator;
  std::vector<std::string> sets;
  int agents = 0;
  std::string seed, steps;  // checked by the config loader (as swarm.seed and sim.steps)
  double dt = 0.0;
  bool verbose = false;
  std::string kernel = "auto";
  int outline = 0;
  app.add_option("--config", config_path, "scenario YAML file (default: built-in defaults)");
  app.add_option("--agents", agents, "number of agents (overrides swarm.agents)");
  app.add_option("--seed", seed, "seed of the uniform start (overrides swarm.seed)");
  app.add_option("--steps", steps, "number of steps (overrides sim.steps)");
  app.add_option("--dt", dt, "model time per step (overrides integration.dt)");
  app.add_option("--integrator", integrator, "euler | rk4 (overrides integration.integrator)");
  app.add_option("--init", init_path, "CSV of starting positions, one x1,x2 row per agent");
  app.add_option("--set", sets, "override any config key: dotted.key=value (repeatable)");
  app.add_option("--csv", csv_path, "write per-step metrics to this CSV file");
  app.add_option("--positions", positions_path, "write per-step positions (step,agent,x1,x2) to this CSV file");
  app.add_flag("--verbose", verbose, "print the effective configuration on stderr");
  app.add_option("--kernel", kernel,
                 "auto | agent (each agent through agent_step, as agent processes) | batch (paper law + Euler: "
                 "each pair once, vectorised); auto = batch from 64 agents")
      ->check(CLI::IsMember({"auto", "agent", "batch"}));
  app.add_option("--outline", outline, "add `outline`: this many points along the shape at the final time")
      ->check(CLI::Range(0, 100000));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    return fail(e.what());
  }

  // Flags are overrides like any other, so the one validation applies to them.
  if (app.count("--agents")) sets.push_back("swarm.agents=" + std::to_string(agents));
  if (app.count("--seed")) sets.push_back("swarm.seed=" + seed);
  if (app.count("--steps")) sets.push_back("sim.steps=" + steps);
  if (app.count("--dt")) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "integration.dt=%.17g", dt);
    sets.push_back(buf);
  }
  if (app.count("--integrator")) sets.push_back("integration.integrator=" + integrator);

  config::Config cfg;
  try {
    cfg = config::load(config_path, sets);
  } catch (const config::ConfigError& e) {
    for (const auto& p : e.problems()) std::cerr << "shapeform_sim: " << p << '\n';
    return 2;
  }
  if (verbose) std::cerr << config::to_yaml(cfg);

  std::vector<core::Vec2> start;
  if (!init_path.empty()) {
    try {
      start = sim::read_positions_csv(init_path);
    } catch (const std::exception& e) {
      return fail(e.what());
    }
    if (app.count("--agents") && static_cast<int>(start.size()) != agents)
      return fail("--agents " + std::to_string(agents) + " does not match the " +
                  std::to_string(start.size()) + " positions in --init " + init_path);
  } else {
    start = core::uniform_start(cfg.swarm.agents, cfg.swarm.seed, cfg.swarm.init_half_width);
  }

  std::ofstream csv, pos;
  sim::SimOptions opt;
  if (!csv_path.empty()) {
    csv.open(csv_path);
    if (!csv) return fail("--csv " + csv_path + ": cannot open for writing");
    opt.metrics_csv = &csv;
  }
  if (!positions_path.empty()) {
    pos.open(positions_path);
    if (!pos) return fail("--positions " + positions_path + ": cannot open for writing");
    opt.positions_csv = &pos;
  }
  const auto& cv = cfg.supervisor.converge;
  opt.settle = {cv.band_abs, cv.band_rel, cv.gap_cv_max};
  opt.kernel = kernel == "agent"   ? core::Kernel::Agent
               : kernel == "batch" ? core::Kernel::Batch
                                   : sim::auto_kernel(static_cast<int>(start.size()));

  const core::CompiledCommand& cmd = cfg.command;
  sim::SimResult r;
  try {
    r = sim::run_simulation(cmd, start, cfg.sim.steps, opt);
  } catch (const core::ShapeError& e) {
    return fail(e.what());
  }

  nlohmann::json j = sim::metrics_json(r.metrics);
  j["name"] = cfg.name;
  j["shape"] = std::string(core::to_string(cmd.shape.kind));
  j["tracking"] = cmd.tracking.enabled;
  j["steps"] = r.steps;
  j["dt"] = cmd.dt;
  j["model_time"] = r.model_time;
  j["integrator"] = std::string(core::to_string(cmd.integrator));
  j["law"] = std::string(core::to_string(cmd.law));
  j["kernel"] = opt.kernel == core::Kernel::Batch && cmd.law == core::Law::Paper && cmd.integrator == core::Integrator::Euler
                    ? "batch" : "agent";
  j["max_step"] = r.max_step;
  j["seed"] = init_path.empty() ? nlohmann::json(cfg.swarm.seed) : nlohmann::json(nullptr);
  j["init"] = init_path.empty() ? nlohmann::json(nullptr) : nlohmann::json(init_path);
  j["settle_step"] = r.settle_step ? nlohmann::json(*r.settle_step) : nlohmann::json(nullptr);
  if (!cmd.tracking.enabled) {
    j.erase("centroid_error");
    j.erase("ring_error");
  }
  if (outline > 0) {
    const core::ShapeSpec s = core::shape_at(cmd, r.model_time);
    const core::Curve* curve = &cmd.curve();
    // The line is infinite: draw the stretch the agents span, with a margin.
    double lo = 0, hi = s.scale * curve->length();  // world units, as closest_point's s
    if (!std::isfinite(hi)) {
      lo = 1e300, hi = -1e300;
      for (const auto& p : r.final_positions) {
        const double a = core::closest_point(s, *curve, p).s;
        lo = std::min(lo, a - 2.0), hi = std::max(hi, a + 2.0);
      }
    }
    auto& ol = j["outline"] = nlohmann::json::array();
    for (int k = 0; k <= outline; ++k) {
      const core::Vec2 p = core::to_world(s, curve->at((lo + (hi - lo) * k / outline) / s.scale));
      ol.push_back({p.x(), p.y()});
    }
  }
  auto& fp = j["final_positions"] = nlohmann::json::array();
  for (const auto& p : r.final_positions) fp.push_back({p.x(), p.y()});
  std::cout << j.dump() << std::endl;
  return 0;
}
