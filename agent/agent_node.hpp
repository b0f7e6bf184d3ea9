#pragma once
#include <cstdint>

#include "config/config.hpp"
#include "core/types.hpp"

namespace shapeform::agent {

/// Runs the agent's fixed-rate loop on DDS until SIGINT/SIGTERM. Returns the process exit status
/// (0 clean stop, 1 runtime failure such as a participant that cannot be created).
int run_agent(std::int32_t id, const core::Vec2& start, const config::Config& cfg);

}  // namespace shapeform::agent
