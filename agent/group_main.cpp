// shapeform_agent_group: several agents in one process (like a ROS 2 component container). Same loop,
// same AgentLogic, same topics as shapeform_agent; one participant instead of one per agent, so a host
// carries far fewer DDS deliveries (see docs/BENCHMARKS.md).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <iostream>
#include <set>

#include "agent_logic.hpp"
#include "agent_node.hpp"
#include "config/config.hpp"

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
    if (a < 0 || b > 9999 || a > b) {
      error = "ids must be in 0..9999 with first <= last, got '" + part + "'";
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
  CLI::App app{"shapeform_agent_group: several agents in one process; each follows the supervisor's commands over DDS."};
  std::string ids_text, config_path;
  std::vector<std::string> sets;
  int domain = -1;
  std::string seed;
  app.add_option("--ids", ids_text, "agent ids hosted here: 0-49, or 0,3,5, or 0-9,20-29 (unique in the swarm)")
      ->required();
  app.add_option("--config", config_path, "YAML config (default: built-in defaults)");
  app.add_option("--domain", domain, "DDS domain id 0..232 (overrides transport.domain)");
  app.add_option("--seed", seed, "seeded start: agent i starts at position i of the uniform start of swarm.agents");
  app.add_option("--set", sets, "override any config key: dotted.key=value (repeatable)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::cerr << "shapeform_agent_group: " << e.what() << '\n';
    return 2;
  }
  std::vector<std::int32_t> ids;
  std::string error;
  if (!parse_ids(ids_text, ids, error)) {
    std::cerr << "shapeform_agent_group: --ids: " << error << '\n';
    return 2;
  }
  const auto cfg = agent::load_config("shapeform_agent_group", config_path, sets,
                                      app.count("--domain") ? std::optional<int>(domain) : std::nullopt,
                                      app.count("--seed") ? std::optional<std::string>(seed) : std::nullopt);
  if (!cfg) return 2;
  std::vector<core::Vec2> starts;
  for (const auto id : ids)
    starts.push_back(agent::seeded_start(id, cfg->swarm.agents, cfg->swarm.seed, cfg->swarm.init_half_width));
  return agent::run_agents(ids, starts, *cfg);
}
