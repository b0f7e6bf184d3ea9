// shapeform_agent_group: several agents in one process (like a ROS 2 component container). Same loop,
// same AgentLogic, same topics as shapeform_agent; one participant instead of one per agent, so a host
// carries far fewer DDS deliveries (see docs/BENCHMARKS.md).
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <set>

#include "agent_logic.hpp"
#include "agent_node.hpp"
#include "app/app.hpp"

namespace {

/// "0-49", "3", "0-9,20-29" -> ids; false with a message on a bad list.
bool parse_ids(const std::string& text, std::vector<std::int32_t>& ids, std::string& error) {
  std::set<std::int32_t> seen;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    const std::size_t comma = std::min(text.find(',', pos), text.size());
    const std::string part = text.substr(pos, comma - pos);
    long a = -1, b = -1;
    char extra = 0;
    if (std::sscanf(part.c_str(), "%ld-%ld%c", &a, &b, &extra) == 2) {
    } else if (std::sscanf(part.c_str(), "%ld%c", &a, &extra) == 1) {
      b = a;
    } else {
      error = "expected ids like 0-49 or 0,5,7, got '" + part + "'";
      return false;
    }
    if (a < 0 || b > shapeform::agent::kMaxAgentId || a > b) {
      error = "ids must be in 0.." + std::to_string(shapeform::agent::kMaxAgentId) + " with first <= last, got '" + part + "'";
      return false;
    }
    for (long i = a; i <= b; ++i) {
      if (!seen.insert(static_cast<std::int32_t>(i)).second) {
        error = "id " + std::to_string(i) + " listed twice";
        return false;
      }
      ids.push_back(static_cast<std::int32_t>(i));
    }
    pos = comma + 1;
  }
  if (ids.size() > 1000) {
    error = "at most 1000 agents per process, got " + std::to_string(ids.size());
    return false;
  }
  return !ids.empty();
}

}  // namespace

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
  if (!parse_ids(ids_text, ids, error)) return app.usage_error("--ids: " + error);
  const auto cfg = app.load_config(app.given("--seed") ? std::vector<std::string>{"swarm.seed=" + seed}
                                                        : std::vector<std::string>{});
  if (!cfg) return app::kExitUsage;
  std::vector<core::Vec2> starts;
  for (const auto id : ids)
    starts.push_back(agent::seeded_start(id, cfg->swarm.agents, cfg->swarm.seed, cfg->swarm.init_half_width));
  return agent::run_agents(ids, starts, *cfg, opt);
}
