#pragma once
/// core::Metrics as JSON, from the one metric table (core/metric_table.hpp). Used by every program
/// that prints metrics: the simulator, the supervisor's `metrics` command and exit summary.
#include <nlohmann/json.hpp>

#include "core/metrics.hpp"

namespace shapeform::app {

/// {"agents": N, <every metric of core::kMetricTable>: value or null when undefined}; counts are
/// JSON integers.
nlohmann::json metrics_json(const core::Metrics& m);

}  // namespace shapeform::app
