// shapeform_sim: the headless simulator. Prints ONE JSON object on stdout.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iostream>

#include "simulation.hpp"
#include "app/app.hpp"
#include "app/json.hpp"
#include "core/enum_names.hpp"
#include "core/params.hpp"
#include "record/recorder.hpp"

int main(int argc, char** argv) {
  using namespace shapeform;
  app::App app("shapeform_sim",
                "shapeform_sim: N agents of the configured law (" + core::params::join(core::params::names(core::params::kLawNames), " or ") + ") in one process, no DDS. Prints one JSON object.");
  CLI::App& cli = app.cli();
  std::string init_path, csv_path, positions_path, record_dir, integrator;
  std::uint64_t epoch = 1;
  double outline_time = -1.0;
  int agents = 0;
  std::string seed, steps;  // checked by the config loader (as swarm.seed and sim.steps)
  double dt = 0.0;
  bool verbose = false;
  std::string kernel = "auto";
  int outline = 0;
  int threads = 1;
  app.add_config_options("scenario YAML file (default: built-in defaults)", false);
  cli.add_option("--agents", agents, "number of agents (overrides swarm.agents)");
  cli.add_option("--seed", seed, "seed of the uniform start (overrides swarm.seed)");
  cli.add_option("--steps", steps, "number of steps (overrides sim.steps)");
  cli.add_option("--dt", dt, "model time per step (overrides integration.dt)");
  cli.add_option("--integrator", integrator,
                 core::params::join(core::params::names(core::params::kIntegratorNames), " | ") +
                     " (overrides integration.integrator)");
  cli.add_option("--init", init_path, "CSV of starting positions, one x1,x2 row per agent");
  cli.add_option("--record", record_dir,
                 "record every step into this folder, in the supervisor's layout (metrics, positions, command, "
                 "tracked centre: docs/RECORDING.md)")
      ->check(app::writable_dir());
  cli.add_option("--epoch", epoch, "the command's epoch in the --record files (default 1)")
      ->check(CLI::Range(std::uint64_t{1}, std::uint64_t{1} << 53));
  cli.add_option("--csv", csv_path, "write per-step metrics (step,model_time,<metrics>) to this CSV file")
      ->check(app::writable_file());
  cli.add_option("--positions", positions_path, "write per-step positions (step,agent,x1,x2) to this CSV file")
      ->check(app::writable_file());
  cli.add_flag("--verbose", verbose, "print the effective configuration on stderr");
  cli.add_option("--kernel", kernel,
                 "auto | agent (each agent through agent_step, as agent processes) | batch (paper law + Euler: "
                 "each pair once, vectorised for this CPU); auto = batch from 64 agents")
      ->check(CLI::IsMember({"auto", "agent", "batch"}));
  cli.add_option("--threads", threads,
                 "threads of the batched kernel's pair pass (each takes an equal share of the pairs; the sums' "
                 "rounding depends on it)")
      ->check(CLI::Range(1, 64));
  cli.add_option("--outline", outline, "add `outline`: this many points along the shape at the final time")
      ->check(CLI::Range(0, 100000));
  cli.add_option("--outline-time", outline_time,
                 "draw the outline at this model time instead of the final one (a tracked shape moves); with "
                 "--steps 0 and --init, the commanded shape around recorded positions")
      ->check(CLI::Range(0.0, 1e15));
  if (const auto rc = app.parse(argc, argv)) return *rc;

  // Flags are overrides like any other, so the one validation applies to them.
  std::vector<std::string> sets;
  if (app.given("--agents")) sets.push_back("swarm.agents=" + std::to_string(agents));
  if (app.given("--seed")) sets.push_back("swarm.seed=" + seed);
  if (app.given("--steps")) sets.push_back("sim.steps=" + steps);
  if (app.given("--dt")) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "integration.dt=%.17g", dt);
    sets.push_back(buf);
  }
  if (app.given("--integrator")) sets.push_back("integration.integrator=" + integrator);
  const auto loaded = app.load_config(sets);
  if (!loaded) return app::kExitUsage;
  const config::Config& cfg = *loaded;
  const auto fail = [&](const std::string& msg) { return app.usage_error(msg); };
  if (verbose) std::cerr << config::to_yaml(cfg);

  std::vector<core::Vec2> start;
  if (!init_path.empty()) {
    try {
      start = sim::read_positions_csv(init_path);
    } catch (const std::exception& e) {
      return fail(e.what());
    }
    if (app.given("--agents") && static_cast<int>(start.size()) != agents)
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
  opt.converge = cv;
  opt.kernel = kernel == "agent"   ? core::Kernel::Agent
               : kernel == "batch" ? core::Kernel::Batch
                                   : sim::auto_kernel(static_cast<int>(start.size()));
  opt.batch.threads = threads;

  record::Recorder recorder;
  if (!record_dir.empty()) {
    try {
      recorder.open(record_dir);
    } catch (const std::exception& e) {
      return fail(std::string("--record: ") + e.what());
    }
    opt.recorder = &recorder;
    opt.epoch = epoch;
  }
  const core::CompiledCommand& cmd = cfg.command;
  const sim::SimResult r = sim::run_simulation(cmd, start, cfg.sim.steps, opt);
  recorder.close();
  if (recorder.write_errors() != 0) {
    std::cerr << "shapeform_sim: --record " << record_dir << ": " << recorder.write_errors() << " failed writes"
              << std::endl;
    return 1;  // a runtime failure
  }

  nlohmann::json j = app::metrics_json(r.metrics);
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
  j["converged"] = r.converged;
  j["verdict"] = core::to_string(r.why);
  if (!cmd.tracking.enabled) {
    j.erase("centroid_error");
    j.erase("ring_error");
  }
  if (outline > 0) {
    const core::ShapeSpec s = core::shape_at(cmd, outline_time >= 0 ? outline_time : r.model_time);
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
