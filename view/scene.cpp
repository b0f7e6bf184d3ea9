#include "scene.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

#include "app/json.hpp"
#include "core/enum_names.hpp"

namespace shapeform::view {

namespace {

double round4(double v) { return std::round(v * 1e4) / 1e4; }
double round3(double v) { return std::round(v * 1e3) / 1e3; }

nlohmann::json point(const core::Vec2& x) { return nlohmann::json::array({round4(x.x()), round4(x.y())}); }

/// The chart's columns, in the order of every point of Scene::chart_ (new columns go at the end: the
/// page finds a column by name, a saved frame by position).
constexpr const char* kChartColumns[] = {"model_time",   "shape_error_mean", "gap_cv",
                                         "agents_alive", "min_separation",   "min_separation_run"};
constexpr std::size_t kChartWidth = sizeof(kChartColumns) / sizeof(kChartColumns[0]);

/// The run's safety figures of the metric table the page's safety line shows (docs/SAFETY.md).
constexpr const char* kSafetyFigures[] = {
    "min_separation_run", "min_separation_run_time", "filter_interventions", "deadlock_sidesteps",
    "promises_broken",    "agents_blocked",          "fence_breaches",       "agents_beyond_fence"};

/// The command's keep-out zones as the page draws them: {"circle": [cx, cy, r]} or
/// {"polygon": [[x, y], ...]}, exact (the filter's own numbers), in the command's order.
nlohmann::json zones_json(const std::vector<core::KeepOutZone>& zones) {
  nlohmann::json out = nlohmann::json::array();
  for (const core::KeepOutZone& z : zones) {
    if (z.kind == core::KeepOutZone::Kind::Circle) {
      out.push_back({{"circle", {z.centre.x(), z.centre.y(), z.radius}}});
    } else {
      nlohmann::json vertices = nlohmann::json::array();
      for (const core::Vec2& v : z.vertices) vertices.push_back({v.x(), v.y()});
      out.push_back({{"polygon", std::move(vertices)}});
    }
  }
  return out;
}

}  // namespace


Series::Series(std::size_t capacity, std::size_t width) : capacity_(std::max<std::size_t>(capacity, 4)), width_(width) {
  points_.reserve(capacity_);
}

void Series::push(const std::vector<double>& point) {
  if (point.size() != width_) throw std::invalid_argument("Series::push: wrong number of values");
  if (points_.size() >= capacity_) {
    // Keep points 0, 2, 4, ...: the history at half the density.
    std::size_t kept = 0;
    for (std::size_t i = 0; i < points_.size(); i += 2, ++kept) {
      if (kept != i) points_[kept] = std::move(points_[i]);
    }
    points_.resize(kept);
    ++generation_;
  }
  points_.push_back(point);
}

Scene::Scene(SceneParams p)
    : p_(p), centre_path_(p.centre_path_capacity, 2), chart_(p.chart_capacity, kChartWidth) {}

void Scene::on_state(std::int32_t id, const core::Vec2& x, double model_time, std::uint64_t epoch, double now_s) {
  AgentInfo& a = agents_[id];
  a.x = x;
  a.model_time = model_time;
  a.epoch = epoch;
  a.last_seen_s = now_s;
  a.departed = false;
  if (!a.trail.empty() && now_s < a.trail.back().first) full_next_ = true;  // time went back: the page starts anew
  if (a.trail.empty() || now_s - a.trail.back().first >= p_.trail_step_s || now_s < a.trail.back().first) {
    a.trail.emplace_back(now_s, x);
    ++a.trail_unsent;
  }
}

void Scene::on_status(std::int32_t id, int heard, double lateness_p99_us) {
  const auto it = agents_.find(id);
  if (it == agents_.end()) return;  // a status before any state: nothing to draw it at
  it->second.heard = heard;
  it->second.lateness_p99_us = lateness_p99_us;
}

void Scene::on_heading(std::int32_t id, double heading, double now_s) {
  const auto it = agents_.find(id);
  if (it == agents_.end() || !std::isfinite(heading)) return;  // a pose before any state: nothing to draw
  it->second.heading = heading;
  it->second.heading_seen_s = now_s;
}

void Scene::on_departed(std::int32_t id) {
  const auto it = agents_.find(id);
  if (it != agents_.end()) it->second.departed = true;
}

void Scene::on_command(const core::CompiledCommand& cmd, std::uint64_t epoch) {
  command_ = cmd;
  epoch_ = epoch;
  if (!cmd.tracking.enabled) centre_.reset();
}

void Scene::on_centre(const core::Vec2& c) {
  centre_ = c;
  const auto& pts = centre_path_.points();
  if (pts.empty() || std::hypot(pts.back()[0] - c.x(), pts.back()[1] - c.y()) >= 1e-3) centre_path_.push({c.x(), c.y()});
}

void Scene::on_metrics(double model_time, std::uint64_t epoch, int agents_alive, const core::Metrics& m,
                       bool converged) {
  if (epoch != chart_epoch_ || (metrics_time_ && model_time < *metrics_time_)) {
    chart_.clear();
    centre_path_.clear();
    chart_epoch_ = epoch;
  }
  if (!metrics_time_ || model_time != *metrics_time_ || chart_.size() == 0) {
    const auto nan = std::numeric_limits<double>::quiet_NaN();
    chart_.push({model_time, m.shape_error_mean.value_or(nan), m.gap_cv.value_or(nan),
                 static_cast<double>(agents_alive), m.min_separation.value_or(nan),
                 m.min_separation_run.value_or(nan)});
  }
  metrics_time_ = model_time;
  metrics_ = app::metrics_json(m);
  metrics_.erase("agents");
  metrics_["agents_alive"] = agents_alive;
  converged_ = converged;
}

void Scene::clear() {
  agents_.clear();
  command_.reset();
  epoch_ = 0;
  centre_.reset();
  centre_path_.clear();
  chart_.clear();
  chart_epoch_ = 0;
  metrics_time_.reset();
  metrics_ = nullptr;
  converged_ = false;
  full_next_ = true;
}

const char* Scene::state(const AgentInfo& a, double now_s) const {
  const double silent = now_s - a.last_seen_s;
  if (a.departed || silent > p_.dead_s) return "dead";
  return silent > p_.stale_s ? "stale" : "alive";
}

std::uint64_t Scene::min_epoch_followed(double now_s) const {
  std::uint64_t lo = 0;
  for (const auto& [id, a] : agents_) {
    if (a.epoch != 0 && std::strcmp(state(a, now_s), "alive") == 0 && (lo == 0 || a.epoch < lo)) lo = a.epoch;
  }
  return lo;
}

double Scene::model_time() const {
  if (metrics_time_) return *metrics_time_;
  double t = 0.0;
  for (const auto& [id, a] : agents_) t = std::max(t, a.model_time);
  return t;
}

nlohmann::json Scene::delta(double now_s) {
  ++seq_;
  nlohmann::json out = build(now_s, full_next_, true);
  full_next_ = false;
  return out;
}

nlohmann::json Scene::snapshot(double now_s) { return build(now_s, true, false); }

nlohmann::json Scene::build(double now_s, bool full, bool record) {
  using nlohmann::json;
  const double t = model_time();
  json agents = json::array();
  json trails = json::array();
  for (auto& [id, a] : agents_) {
    auto& tr = a.trail;
    // The page drops a point by its time as sent (rounded) by the same rule: both keep the same points.
    tr.erase(tr.begin(), std::find_if(tr.begin(), tr.end(),
                                      [&](const auto& p) { return round3(p.first) >= now_s - p_.trail_s; }));
    const bool fresh_heading = a.heading && now_s - a.heading_seen_s <= p_.dead_s;
    json row = json::array({id, round4(a.x.x()), round4(a.x.y()), state(a, now_s), a.model_time, a.epoch,
                            a.heard ? json(*a.heard) : json(nullptr),
                            a.lateness_p99_us && std::isfinite(*a.lateness_p99_us)
                                ? json(std::round(*a.lateness_p99_us * 10.0) / 10.0)
                                : json(nullptr),
                            fresh_heading ? json(round4(*a.heading)) : json(nullptr)});
    const std::size_t new_points = full ? tr.size() : std::min(a.trail_unsent, tr.size());
    for (std::size_t k = tr.size() - new_points; k < tr.size(); ++k) {
      trails.push_back(id);
      trails.push_back(round3(tr[k].first));
      trails.push_back(round4(tr[k].second.x()));
      trails.push_back(round4(tr[k].second.y()));
    }
    if (record) a.trail_unsent = 0;
    if (full || row != a.sent) {
      if (record) a.sent = row;
      agents.push_back(std::move(row));
    }
  }
  json out = json::object();
  out["seq"] = seq_;
  out["full"] = full;
  out["now_s"] = now_s;
  out["model_time"] = t;
  out["epoch"] = command_ ? epoch_ : chart_epoch_;  // a recording without commands.csv: the metrics' epoch
  out["converged"] = converged_;
  out["trail_s"] = p_.trail_s;
  out["agent_columns"] = {"id",    "x1",    "x2",          "state",  "model_time",
                          "epoch", "heard", "lateness_us", "heading"};
  out["agents"] = std::move(agents);
  out["trails"] = std::move(trails);

  // The command's parts: sent when they change (the outline moves with a tracked centre).
  json outline_json = nullptr;
  if (command_) {
    json pts = json::array();
    bool closed = false;
    for (const auto& x : core::outline(*command_, t, closed, p_.outline_points)) pts.push_back(point(x));
    outline_json = {{"points", std::move(pts)}, {"closed", command_->curve().closed()}};
  }
  // The safety filter's constraints (docs/SAFETY.md), drawn under the agents: the zones, and the fence
  // when the command sets one (safety.fence; without one the workspace box is the fence, not drawn).
  json keep_out = command_ ? zones_json(command_->keep_out) : json::array();
  json fence = nullptr;
  if (command_ && !command_->fence.empty()) {
    json pts = json::array();
    for (const auto& v : command_->fence) pts.push_back(json::array({v.x(), v.y()}));
    fence = {{"polygon", std::move(pts)},
             {"margin", command_->fence_margin},
             {"action", core::params::name_of(core::params::kBreachActionNames, command_->breach_action)}};
  }
  json min_separation = command_ ? command_->min_separation : 0.0;
  const auto changed = [&](const char* key, json& value, json& sent) {
    if (full || value != sent) {
      if (record) sent = value;
      out[key] = std::move(value);
    }
  };
  changed("outline", outline_json, sent_outline_);
  changed("keep_out", keep_out, sent_keep_out_);
  changed("fence", fence, sent_fence_);
  changed("min_separation", min_separation, sent_min_separation_);
  out["centre"] = centre_ ? point(*centre_) : json(nullptr);

  // The series: the points added since the previous delta, or all of them when the page's copy is stale.
  const auto series = [&](const Series& s, std::uint64_t& sent_generation, std::size_t& sent,
                          const auto& to_json) {
    const bool replace = full || s.generation() != sent_generation || s.size() < sent;
    json pts = json::array();
    for (std::size_t k = replace ? 0 : sent; k < s.size(); ++k) pts.push_back(to_json(s.points()[k]));
    if (record) {
      sent_generation = s.generation();
      sent = s.size();
    }
    return json{{"replace", replace}, {"points", std::move(pts)}};
  };
  out["centre_path"] =
      series(centre_path_, centre_path_sent_generation_, centre_path_sent_, [](const std::vector<double>& p) {
        return json::array({round4(p[0]), round4(p[1])});
      });
  json chart = series(chart_, chart_sent_generation_, chart_sent_, [](const std::vector<double>& p) {
    json row = json::array();
    for (const double v : p) row.push_back(std::isfinite(v) ? json(v) : json(nullptr));
    return row;
  });
  json columns = json::array();
  for (const char* c : kChartColumns) columns.push_back(c);
  chart["columns"] = std::move(columns);
  out["chart"] = std::move(chart);
  out["metrics"] = metrics_;
  json safety = json::object();
  for (const char* name : kSafetyFigures)
    safety[name] = metrics_.is_object() ? metrics_.at(name) : json(nullptr);
  out["safety"] = std::move(safety);
  return out;
}

}  // namespace shapeform::view
