#include "app/json.hpp"

#include <cmath>
#include <string>
#include <type_traits>
#include <variant>
#include <vector>

#include "core/metric_table.hpp"
#include "core/command_table.hpp"
#include "core/params.hpp"

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

namespace {

/// Every parameter of `table` read from obj, nested by the dots of its key ("agent.rate_hz" ->
/// {"agent": {"rate_hz": ...}}); rotation in degrees, choices by name.
template <class T>
nlohmann::json table_json(const std::vector<core::params::Param<T>>& table, const T& obj) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& p : table) {
    nlohmann::json value = std::visit(
        [](const auto& v) -> nlohmann::json {
          using V = std::decay_t<decltype(v)>;
          if constexpr (std::is_same_v<V, core::Vec2>) {
            return {v.x(), v.y()};
          } else if constexpr (std::is_same_v<V, std::vector<core::Vec2>>) {
            nlohmann::json list = nlohmann::json::array();
            for (const auto& x : v) list.push_back({x.x(), x.y()});
            return list;
          } else if constexpr (std::is_same_v<V, std::vector<core::KeepOutZone>>) {
            nlohmann::json list = nlohmann::json::array();
            for (const auto& z : v) {
              if (z.kind == core::KeepOutZone::Kind::Circle) {
                list.push_back(nlohmann::json{{"circle", nlohmann::json::array({z.centre.x(), z.centre.y(), z.radius})}});
              } else {
                nlohmann::json poly = nlohmann::json::array();
                for (const auto& x : z.vertices) poly.push_back({x.x(), x.y()});
                list.push_back(nlohmann::json{{"polygon", poly}});
              }
            }
            return list;
          } else {
            return v;
          }
        },
        p.get(obj));
    if (p.degrees) value = value.get<double>() / core::params::kRadPerDeg;
    std::string pointer = "/" + p.key;  // "agent.rate_hz" -> "/agent/rate_hz"
    for (char& ch : pointer)
      if (ch == '.') ch = '/';
    j[nlohmann::json::json_pointer(pointer)] = std::move(value);
  }
  return j;
}

}  // namespace

nlohmann::json config_json(const config::Config& c) { return table_json(config::config_table(), c); }

nlohmann::json command_json(const core::Command& c) { return table_json(core::params::command_table(), c); }

nlohmann::json recovered_json(bool split, double seconds, const std::string& peer) {
  if (!split) return {{"cause", "stall"}, {"stall_s", seconds}};
  return {{"cause", "split"}, {"peer", peer}, {"unheard_s", seconds}};
}

}  // namespace shapeform::app
