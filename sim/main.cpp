// shapeform_sim: the headless simulator. Prints ONE JSON object on stdout.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "simulation.hpp"
#include "app/app.hpp"
#include "app/json.hpp"
#include "core/enum_names.hpp"
#include "core/params.hpp"
#include "core/safety.hpp"
#include "record/recorder.hpp"
#include "util/clock.hpp"

namespace shapeform {
namespace {

/// What the command line gives besides the config.
struct Args {
  std::string init_path, csv_path, positions_path, record_dir, integrator;
  std::uint64_t epoch = 1;
  double outline_time = -1.0;
  int agents = 0;
  std::string seed, steps;  // checked by the config loader (as swarm.seed and sim.steps)
  double dt = 0.0;
  bool verbose = false;
  bool separation = false;
  std::string kernel = "auto";
  int outline = 0;
  int threads = 1;
};

void add_options(app::App& app, Args& a) {
  CLI::App& cli = app.cli();
  app.add_config_options("scenario YAML file (default: built-in defaults)", false);
  cli.add_option("--agents", a.agents, "number of agents (overrides swarm.agents)");
  cli.add_option("--seed", a.seed, "seed of the uniform start (overrides swarm.seed)");
  cli.add_option("--steps", a.steps, "number of steps (overrides sim.steps)");
  cli.add_option("--dt", a.dt, "model time per step (overrides integration.dt)");
  cli.add_option("--integrator", a.integrator,
                 core::params::join(core::params::names(core::params::kIntegratorNames), " | ") +
                     " (overrides integration.integrator)");
  cli.add_option("--init", a.init_path, "CSV of starting positions, one x1,x2 row per agent");
  cli.add_option("--record", a.record_dir,
                 "record every step into this folder, in the supervisor's layout (metrics, positions, command, "
                 "tracked centre as CSV files, and run.mcap: docs/RECORDING.md)")
      ->check(app::writable_dir());
  cli.add_option("--epoch", a.epoch, "the command's epoch in the --record files (default 1)")
      ->check(CLI::Range(std::uint64_t{1}, std::uint64_t{1} << 53));
  cli.add_option("--csv", a.csv_path, "write per-step metrics (step,model_time,<metrics>) to this CSV file")
      ->check(app::writable_file());
  cli.add_option("--positions", a.positions_path, "write per-step positions (step,agent,x1,x2) to this CSV file")
      ->check(app::writable_file());
  cli.add_flag("--verbose", a.verbose, "print the effective configuration on stderr");
  cli.add_flag("--separation", a.separation,
               "track the smallest pairwise distance at every step into `safety` (O(N^2) per step; always on "
               "with safety.min_separation > 0 or safety.keep_out)");
  cli.add_option("--kernel", a.kernel,
                 "auto | agent (each agent through agent_step, as agent processes) | batch (paper law + Euler, "
                 "vehicle.model integrator: each pair once, vectorised for this CPU); auto = batch from 64 agents "
                 "where it applies")
      ->check(CLI::IsMember({"auto", "agent", "batch"}));
  cli.add_option("--threads", a.threads,
                 "threads of the batched kernel's pair pass (each takes an equal share of the pairs; the sums' "
                 "rounding depends on it)")
      ->check(CLI::Range(1, 64));
  cli.add_option("--outline", a.outline, "add `outline`: this many points along the shape at the final time")
      ->check(CLI::Range(0, 100000));
  cli.add_option("--outline-time", a.outline_time,
                 "draw the outline at this model time instead of the final one (a tracked shape moves); with "
                 "--steps 0 and --init, the commanded shape around recorded positions")
      ->check(CLI::Range(0.0, 1e15));
}

/// The flags as config overrides like any other, so the one validation applies to them.
std::vector<std::string> flag_overrides(const app::App& app, const Args& a) {
  std::vector<std::string> sets;
  if (app.given("--agents")) sets.push_back("swarm.agents=" + std::to_string(a.agents));
  if (app.given("--seed")) sets.push_back("swarm.seed=" + a.seed);
  if (app.given("--steps")) sets.push_back("sim.steps=" + a.steps);
  if (app.given("--dt")) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "integration.dt=%.17g", a.dt);
    sets.push_back(buf);
  }
  if (app.given("--integrator")) sets.push_back("integration.integrator=" + a.integrator);
  return sets;
}

/// The start: --init's positions, or the config's uniform start. Throws std::runtime_error naming the
/// problem.
std::vector<core::Vec2> start_positions(const app::App& app, const Args& a, const config::Config& cfg) {
  if (a.init_path.empty()) return core::uniform_start(cfg.swarm.agents, cfg.swarm.seed, cfg.swarm.init_half_width);
  std::vector<core::Vec2> start = sim::read_positions_csv(a.init_path);
  if (app.given("--agents") && static_cast<int>(start.size()) != a.agents)
    throw std::runtime_error("--agents " + std::to_string(a.agents) + " does not match the " +
                             std::to_string(start.size()) + " positions in --init " + a.init_path);
  return start;
}

/// The files a run writes besides its JSON (--csv, --positions, --record), open for the run.
struct Outputs {
  std::ofstream csv, pos;
  record::Recorder recorder;

  /// Opens what `a` asks for into opt; throws std::runtime_error naming the flag.
  void open(const Args& a, sim::SimOptions& opt) {
    if (!a.csv_path.empty()) {
      csv.open(a.csv_path);
      if (!csv) throw std::runtime_error("--csv " + a.csv_path + ": cannot open for writing");
      opt.metrics_csv = &csv;
    }
    if (!a.positions_path.empty()) {
      pos.open(a.positions_path);
      if (!pos) throw std::runtime_error("--positions " + a.positions_path + ": cannot open for writing");
      opt.positions_csv = &pos;
    }
    if (!a.record_dir.empty()) {
      try {
        recorder.open(a.record_dir, util::system_ns());  // run.mcap's log times: Unix time from here
      } catch (const std::exception& e) {
        throw std::runtime_error(std::string("--record: ") + e.what());
      }
      opt.recorder = &recorder;
      opt.epoch = a.epoch;
    }
  }
};

sim::SimOptions sim_options(const Args& a, const config::Config& cfg, int agents) {
  sim::SimOptions opt = sim::run_options(cfg.supervisor.converge, cfg.vehicle, cfg.swarm.seed);
  opt.kernel = a.kernel == "agent"   ? core::Kernel::Agent
               : a.kernel == "batch" ? core::Kernel::Batch
                                     : sim::auto_kernel(agents, cfg.vehicle);
  if (a.kernel == "batch" && core::filters(cfg.command))
    throw std::runtime_error("--kernel batch: the batched kernel steps agents without the safety filter, and "
                             "safety.min_separation is " + core::params::format_number(cfg.command.min_separation) +
                             " with " + std::to_string(cfg.command.keep_out.size()) +
                             " keep-out zones: use --kernel agent or auto, or set safety.min_separation=0 and "
                             "safety.keep_out=[]");
  if (a.kernel == "batch" && cfg.vehicle.model != core::VehicleModel::Integrator)
    throw std::runtime_error("--kernel batch: the batched kernel moves agents as the integrator model only, and "
                             "vehicle.model is " + std::string(core::to_string(cfg.vehicle.model)) +
                             ": use --kernel agent or auto");
  opt.separation = a.separation;
  opt.batch.threads = a.threads;
  return opt;
}

/// `points` + 1 points along the commanded shape at model time t; an infinite line is drawn over the
/// stretch the agents span, with a margin.
nlohmann::json outline_json(const core::CompiledCommand& cmd, double t, int points,
                            const std::vector<core::Vec2>& positions) {
  const core::ShapeSpec s = core::shape_at(cmd, t);
  const core::Curve* curve = &cmd.curve();
  double lo = 0, hi = s.scale * curve->length();  // world units, as closest_point's s
  if (!std::isfinite(hi)) {
    lo = 1e300, hi = -1e300;
    for (const auto& p : positions) {
      const double a = core::closest_point(s, *curve, p).s;
      lo = std::min(lo, a - 2.0), hi = std::max(hi, a + 2.0);
    }
  }
  nlohmann::json ol = nlohmann::json::array();
  for (int k = 0; k <= points; ++k) {
    const core::Vec2 p = core::to_world(s, curve->at((lo + (hi - lo) * k / points) / s.scale));
    ol.push_back({p.x(), p.y()});
  }
  return ol;
}

/// The one JSON object the program prints.
nlohmann::json result_json(const Args& a, const config::Config& cfg, const sim::SimOptions& opt,
                           const sim::SimResult& r) {
  const core::CompiledCommand& cmd = cfg.command;
  nlohmann::json j = app::metrics_json(r.metrics);
  j["name"] = cfg.name;
  j["shape"] = std::string(core::to_string(cmd.shape.kind));
  j["tracking"] = cmd.tracking.enabled;
  j["steps"] = r.steps;
  j["dt"] = cmd.dt;
  j["model_time"] = r.model_time;
  j["integrator"] = std::string(core::to_string(cmd.integrator));
  j["law"] = std::string(core::to_string(cmd.law));
  j["kernel"] = opt.kernel == core::Kernel::Batch && core::batch_applies(cmd, opt.vehicle) ? "batch" : "agent";
  j["vehicle"] = std::string(core::to_string(opt.vehicle.model));
  j["max_step"] = r.max_step;
  j["seed"] = a.init_path.empty() ? nlohmann::json(cfg.swarm.seed) : nlohmann::json(nullptr);
  j["init"] = a.init_path.empty() ? nlohmann::json(nullptr) : nlohmann::json(a.init_path);
  j["settle_step"] = r.settle_step ? nlohmann::json(*r.settle_step) : nlohmann::json(nullptr);
  j["converged"] = r.converged;
  j["verdict"] = core::to_string(r.why);
  if (!cmd.tracking.enabled) {
    j.erase("centroid_error");
    j.erase("ring_error");
  }
  if (a.outline > 0)
    j["outline"] = outline_json(cmd, a.outline_time >= 0 ? a.outline_time : r.model_time, a.outline, r.final_positions);
  if (opt.separation || core::filters(cmd)) {
    // Run-long figures (not metrics of one snapshot): the smallest distance over every step, the
    // filter's counts, and who holds whom at the end.
    const sim::SeparationRecord& s = r.separation;
    nlohmann::json by = nlohmann::json::array();
    for (std::size_t i = 0; i < r.blocked_by.size(); ++i) {
      const std::int64_t b = r.blocked_by[i];
      if (b == -1) continue;
      by.push_back(b >= 0 ? nlohmann::json{{"agent", i}, {"neighbour", b}} : nlohmann::json{{"agent", i}, {"zone", -2 - b}});
    }
    j["safety"] = {
        {"filter", core::filters(cmd)},
        {"min_separation_setting", cmd.min_separation},
        {"keep_out_zones", cmd.keep_out.size()},
        {"run_min_separation", s.min ? nlohmann::json(*s.min) : nlohmann::json(nullptr)},
        {"run_min_step", s.min ? nlohmann::json(s.step) : nlohmann::json(nullptr)},
        {"run_min_time", s.min ? nlohmann::json(s.model_time) : nlohmann::json(nullptr)},
        {"zone_entries", s.zone_entries},
        {"zone_depth", s.zone_depth},
        {"interventions", r.safety.interventions},
        {"sidesteps", r.safety.sidesteps},
        {"broken", r.safety.broken},
        {"held", r.safety.held},
        {"vehicle_outside", r.safety.outside},
        {"blocked_agents", r.blocked_agents},
        {"blocked_by", by},
    };
  }
  j["converged_step"] = r.converged_step ? nlohmann::json(*r.converged_step) : nlohmann::json(nullptr);
  auto& fp = j["final_positions"] = nlohmann::json::array();
  for (const auto& p : r.final_positions) fp.push_back({p.x(), p.y()});
  if (opt.vehicle.model == core::VehicleModel::Unicycle) {
    auto& fh = j["final_headings"] = nlohmann::json::array();  // rad, of each agent's vehicle
    for (const auto& v : r.final_vehicles) fh.push_back(v.heading);
  }
  return j;
}

int run(int argc, char** argv) {
  app::App app("shapeform_sim",
               "shapeform_sim: N agents of the configured law (" +
                   core::params::join(core::params::names(core::params::kLawNames), " or ") +
                   ") in one process, no DDS. Prints one JSON object.");
  Args a;
  add_options(app, a);
  if (const auto rc = app.parse(argc, argv)) return *rc;
  const auto loaded = app.load_config(flag_overrides(app, a));
  if (!loaded) return app::kExitUsage;
  const config::Config& cfg = *loaded;
  if (a.verbose) std::cerr << config::to_yaml(cfg);
  std::vector<core::Vec2> start;
  sim::SimOptions opt;
  Outputs out;
  try {
    start = start_positions(app, a, cfg);
    opt = sim_options(a, cfg, static_cast<int>(start.size()));
    out.open(a, opt);
  } catch (const std::exception& e) {
    return app.usage_error(e.what());
  }
  const sim::SimResult r = sim::run_simulation(cfg.command, start, cfg.sim.steps, opt);
  out.recorder.close();
  if (out.recorder.write_errors() != 0) {
    std::cerr << "shapeform_sim: --record " << a.record_dir << ": " << out.recorder.write_errors()
              << " failed writes" << std::endl;
    return 1;  // a runtime failure
  }
  std::cout << result_json(a, cfg, opt, r).dump() << std::endl;
  return 0;
}

}  // namespace
}  // namespace shapeform

int main(int argc, char** argv) { return shapeform::run(argc, argv); }
