// shapeform_agent: one agent of the swarm as a standalone process on Fast DDS.
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <iostream>

#include "agent_logic.hpp"
#include "agent_node.hpp"
#include "config/config.hpp"

int main(int argc, char** argv) {
  using namespace shapeform;
  CLI::App app{"shapeform_agent: one agent process; follows the supervisor's commands over DDS."};
  int id = -1;
  std::string config_path, start;
  std::vector<std::string> sets;
  int domain = -1;
  std::string seed;
  app.add_option("--id", id, "agent id, 0..9999 (unique in the swarm)")->required();
  app.add_option("--config", config_path, "YAML config (default: built-in defaults)");
  app.add_option("--domain", domain, "DDS domain id 0..232 (overrides transport.domain)");
  auto* start_opt = app.add_option("--start", start, "starting position x,y");
  app.add_option("--seed", seed, "seeded start: position `id` of the uniform start of swarm.agents")
      ->excludes(start_opt);
  app.add_option("--set", sets, "override any config key: dotted.key=value (repeatable)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::cerr << "shapeform_agent: " << e.what() << '\n';
    return 2;
  }
  if (id < 0 || id > 9999) {
    std::cerr << "shapeform_agent: --id must be in 0..9999, got " << id << '\n';
    return 2;
  }
  const auto cfg = agent::load_config("shapeform_agent", config_path, sets,
                                      app.count("--domain") ? std::optional<int>(domain) : std::nullopt,
                                      app.count("--seed") ? std::optional<std::string>(seed) : std::nullopt);
  if (!cfg) return 2;

  core::Vec2 x0;
  if (!start.empty()) {
    double a = 0, b = 0;
    char extra = 0;
    if (std::sscanf(start.c_str(), "%lf,%lf%c", &a, &b, &extra) != 2 || !std::isfinite(a) || !std::isfinite(b) ||
        std::abs(a) > 1e6 || std::abs(b) > 1e6) {
      std::cerr << "shapeform_agent: --start: expected two finite numbers x,y, got '" << start << "'\n";
      return 2;
    }
    x0 = core::Vec2(a, b);
  } else {
    x0 = agent::seeded_start(id, cfg->swarm.agents, cfg->swarm.seed, cfg->swarm.init_half_width);
  }
  return agent::run_agent(id, x0, *cfg);
}
