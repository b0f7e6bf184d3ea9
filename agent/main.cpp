// shapeform_agent: one agent of the swarm as a standalone process on Fast DDS.
#include <cmath>
#include <cstdio>

#include "agent_logic.hpp"
#include "agent_node.hpp"
#include "app/app.hpp"
#include "protocol/samples.hpp"

int main(int argc, char** argv) {
  using namespace shapeform;
  app::App app("shapeform_agent", "shapeform_agent: one agent process; follows the supervisor's commands over DDS.");
  int id = -1;
  std::string start, seed;
  agent::AgentOptions opt;
  app.cli().add_option("--id", id, "agent id, 0.." + std::to_string(agent::kMaxAgentId) + " (unique in the swarm)")
      ->required();
  app.add_config_options();
  auto* start_opt = app.cli().add_option("--start", start, "starting position x,y");
  app.cli()
      .add_option("--seed", seed, "seeded start: position `id` of the uniform start of swarm.agents")
      ->excludes(start_opt);
  app.cli().add_flag("--json", opt.json, "machine output: JSON lines on stdout (status, command, rejected)");
  if (const auto rc = app.parse(argc, argv)) return *rc;
  if (id < 0 || id > agent::kMaxAgentId)
    return app.usage_error("--id must be in 0.." + std::to_string(agent::kMaxAgentId) + ", got " + std::to_string(id));
  // The loader checks the seed (64-bit, >= 0).
  const auto cfg = app.load_config(app.given("--seed") ? std::vector<std::string>{"swarm.seed=" + seed}
                                                        : std::vector<std::string>{});
  if (!cfg) return app::kExitUsage;

  core::Vec2 x0;
  if (!start.empty()) {
    double a = 0, b = 0;
    char extra = 0;
    if (std::sscanf(start.c_str(), "%lf,%lf%c", &a, &b, &extra) != 2 || !std::isfinite(a) || !std::isfinite(b) ||
        std::abs(a) > dds::kStateLimit || std::abs(b) > dds::kStateLimit)
      return app.usage_error("--start: expected two finite numbers x,y, got '" + start + "'");
    x0 = core::Vec2(a, b);
  } else {
    x0 = agent::seeded_start(id, cfg->swarm.agents, cfg->swarm.seed, cfg->swarm.init_half_width);
  }
  return agent::run_agents({id}, {x0}, *cfg, opt);
}
