#pragma once
#include <cstdint>
#include <vector>

#include "config/config.hpp"
#include "core/types.hpp"

namespace shapeform::agent {

struct AgentOptions {
  /// Machine output on stdout, one JSON object per line with an "event" key: "status" once per status
  /// period per hosted agent (the AgentStatus numbers and its position x, y), "command" when a command is adopted,
  /// "rejected" when a sample is refused (throttled like the log), "recovered" (app::recovered_json: its
  /// cause, stall or split) when the process recreated its participant (dds::Node::recover), "duplicate" when
  /// another participant publishes a hosted id ({id, source: this participant, other, action:
  /// exit|keep}). Logs stay on stderr.
  bool json = false;
};

/// Runs the agents' fixed-rate loop on DDS until SIGINT/SIGTERM; returns the process exit status
/// (0 clean stop, 1 runtime failure such as a participant that cannot be created, 2 an id already in
/// use: see IdentityGuard; the agents listen agent.identity_grace_s before their first publication).
/// One process hosts one agent (shapeform_agent) or several (shapeform_agent_group, like a ROS 2
/// component container): one participant, one state writer for all of their instances, one reader
/// whose samples every hosted agent takes in. Each hosted agent has its own AgentLogic and publishes
/// its own AgentState and AgentStatus; the process figures in the status (CPU, RSS) are the
/// process's divided by ids.size(). ids and starts have the same, non-zero length; ids are distinct.
int run_agents(const std::vector<std::int32_t>& ids, const std::vector<core::Vec2>& starts,
               const config::Config& cfg, const AgentOptions& opt = {});

}  // namespace shapeform::agent
