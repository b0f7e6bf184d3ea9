#include "app/metrics_json.hpp"

#include <cmath>

#include "core/metric_table.hpp"

namespace shapeform::app {

nlohmann::json metrics_json(const core::Metrics& m) {
  nlohmann::json j;
  j["agents"] = m.agents;
  for (const core::MetricInfo& info : core::kMetricTable) {
    const std::optional<double> v = info.get(m);
    nlohmann::json& field = j[std::string(info.name)];
    if (!v) field = nullptr;
    else if (info.count) field = std::llround(*v);
    else field = *v;
  }
  return j;
}

}  // namespace shapeform::app
