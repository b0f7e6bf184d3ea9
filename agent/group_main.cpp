// shapeform_agent_group: several agents in one process (like a ROS 2 component container). Same loop,
// same AgentLogic, same topics as shapeform_agent; one participant instead of one per agent, so a host
// carries far fewer DDS deliveries (see docs/BENCHMARKS.md).
#include <string>
#include <vector>

#include "agent_logic.hpp"
#include "agent_node.hpp"
#include "app/app.hpp"

int main(int argc, char** argv) {
  using namespace shapeform;
  app::App app("shapeform_agent_group",
                "shapeform_agent_group: several agents in one process; each follows the supervisor's commands over DDS.");
  std::string ids_text, seed;
  agent::AgentOptions opt;
  app.cli()
      .add_option("--ids", ids_text, "agent ids hosted here: 0-49, or 0,3,5, or 0-9,20-29 (unique in the swarm)")
      ->required();
  app.add_config_options();
  app.cli().add_option("--seed", seed,
                       "seeded start: agent i starts at position i of the uniform start of swarm.agents");
  app.cli().add_flag("--json", opt.json, "machine output: JSON lines on stdout (status, command, rejected)");
  if (const auto rc = app.parse(argc, argv)) return *rc;
  std::vector<std::int32_t> ids;
  std::string error;
  if (!app::parse_id_list(ids_text, agent::kMaxAgentId, 1000, ids, error)) return app.usage_error("--ids: " + error);
  const auto cfg = app.load_config(app.given("--seed") ? std::vector<std::string>{"swarm.seed=" + seed}
                                                        : std::vector<std::string>{});
  if (!cfg) return app::kExitUsage;
  std::vector<core::Vec2> starts;
  for (const auto id : ids)
    starts.push_back(agent::seeded_start(id, cfg->swarm.agents, cfg->swarm.seed, cfg->swarm.init_half_width));
  return agent::run_agents(ids, starts, *cfg, opt);
}
