#pragma once
/// The programs' machine output as JSON, from the project's declared tables: metrics from the one
/// metric table (core/metric_table.hpp), the configuration from the config table. Used by every
/// program that prints JSON: the simulator, the supervisor and the agents.
#include <nlohmann/json.hpp>

#include "config/config.hpp"
#include "core/metrics.hpp"

namespace shapeform::app {

/// {"agents": N, <every metric of core::kMetricTable>: value or null when undefined}; counts are
/// JSON integers.
nlohmann::json metrics_json(const core::Metrics& m);

/// The effective configuration, one JSON object per section as the YAML file nests it
/// ({"agent": {"rate_hz": 50, ...}, "transport": {"lease_s": 2, ...}, ...}), every key of the config
/// table; shape.rotation_deg in degrees, choices by name.
nlohmann::json config_json(const config::Config& c);

/// A command as config_json nests its keys ({"shape": {"kind": "circle", ...}, "tracking": {...},
/// "dynamics": {...}, "integration": {...}}), every key of the command table.
nlohmann::json command_json(const core::Command& c);

/// The "recovered" event of a process that recreated its participant (dds::Node::recover): after a
/// stall {"cause": "stall", "stall_s": s}; after a split {"cause": "split", "peer": prefix, "unheard_s": s}.
nlohmann::json recovered_json(bool split, double seconds, const std::string& peer);

}  // namespace shapeform::app
