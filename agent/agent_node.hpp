#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "config/config.hpp"
#include "core/types.hpp"

namespace shapeform::agent {

/// The agent executables' configuration: the file at `path` (empty: the defaults) with the `sets`
/// overrides, then --domain and --seed when given. Problems go to stderr as "prog: problem"; nullopt
/// then (exit status 2).
std::optional<config::Config> load_config(const std::string& prog, const std::string& path,
                                          std::vector<std::string> sets, std::optional<int> domain,
                                          std::optional<std::string> seed);

/// Runs the agent's fixed-rate loop on DDS until SIGINT/SIGTERM. Returns the process exit status
/// (0 clean stop, 1 runtime failure such as a participant that cannot be created).
int run_agent(std::int32_t id, const core::Vec2& start, const config::Config& cfg);

/// The same loop hosting several agents in one process (one participant, one state writer for all of
/// their instances, one reader whose samples every hosted agent takes in), like a ROS 2 component
/// container. Each hosted agent has its own AgentLogic and publishes its own AgentState and
/// AgentStatus; the process figures in the status (CPU, RSS) are the process's divided by ids.size().
/// ids and starts have the same, non-zero length; ids are distinct.
int run_agents(const std::vector<std::int32_t>& ids, const std::vector<core::Vec2>& starts,
               const config::Config& cfg);

}  // namespace shapeform::agent
