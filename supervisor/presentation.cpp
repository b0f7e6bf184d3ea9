#include "presentation.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "app/json.hpp"
#include "core/metric_table.hpp"
#include "core/params.hpp"

namespace shapeform::supervisor {

namespace {

std::string fmt_opt(const std::optional<double>& v, const char* f = "%.4f") {
  if (!v) return "-";
  char b[32];
  std::snprintf(b, sizeof b, f, *v);
  return b;
}

std::string count_or_dash(const std::optional<int>& v) { return v ? std::to_string(*v) : "-"; }

template <class T>
nlohmann::json or_null(const std::optional<T>& v) {
  return v ? nlohmann::json(*v) : nlohmann::json(nullptr);
}

std::optional<long long> settle_step(const Summary& s) {
  if (!s.settle_time) return std::nullopt;
  return std::llround(*s.settle_time / s.command.dt);
}

/// The shape's kind and the parameters that define it, as the console spells them
/// ("circle r=4", "polygon 5 vertices closed").
std::string shape_parameters(const core::ShapeSpec& s) {
  std::ostringstream o;
  o << core::to_string(s.kind);
  switch (s.kind) {
    case core::ShapeKind::Line: o << " m=" << s.m << " c=" << s.c; break;
    case core::ShapeKind::Circle: o << " r=" << s.r0; break;
    case core::ShapeKind::Ellipse: o << " a=" << s.a << " b=" << s.b; break;
    case core::ShapeKind::Square: o << " a=" << s.a; break;
    case core::ShapeKind::Polar: o << " r=\"" << s.r_expr << '"'; break;
    case core::ShapeKind::Parametric: o << " x=\"" << s.x_expr << "\" y=\"" << s.y_expr << '"'; break;
    case core::ShapeKind::Implicit: o << " f=\"" << s.f_expr << '"'; break;
    case core::ShapeKind::Polygon: o << " " << s.vertices.size() << " vertices"; break;
  }
  if (s.kind == core::ShapeKind::Parametric || s.kind == core::ShapeKind::Polygon) o << (s.closed ? " closed" : " open");
  return o.str();
}

}  // namespace

std::string describe_command(const core::CompiledCommand& c) {
  std::ostringstream o;
  const auto& s = c.shape;
  o << shape_parameters(s);
  if (s.rotation != 0.0) o << " rotated " << s.rotation / core::params::kRadPerDeg << " deg";
  if (s.scale != 1.0) o << " scaled " << s.scale;
  if (c.tracking.enabled)
    o << ", tracking on a " << core::to_string(c.tracking.path.kind) << " path"
      << (c.tracking.feedforward ? " with feed-forward" : "");
  else if (c.curve().closed())
    o << " centre (" << s.centre.x() << ", " << s.centre.y() << ")";
  if (c.law == core::Law::Arc) {
    o << "; law arc k_normal=" << c.arc.k_normal << " k_tangent=" << c.arc.k_tangent;
    if (s.kind == core::ShapeKind::Line) o << " spacing=" << c.arc.spacing;
  }
  o << "; k1=" << c.gains.k1 << " k2=" << c.gains.k2 << " sigma=" << c.gains.sigma << " beta=" << c.gains.beta
    << " r=" << c.gains.r << ", " << core::to_string(c.integrator) << " dt=" << c.dt;
  if (c.max_speed > 0) o << ", max_speed=" << c.max_speed;
  if (c.hold) o << "; HELD: every agent keeps its position ('resume' releases)";
  return o.str();
}

std::vector<AgentRow> agent_rows(const SwarmMonitor& monitor, std::int64_t now_ns, double model_time) {
  const auto& cmd = monitor.command();
  const std::optional<core::ShapeSpec> shape =
      cmd ? std::optional<core::ShapeSpec>(core::shape_at(*cmd, model_time)) : std::nullopt;
  std::vector<AgentRow> rows;
  rows.reserve(monitor.agents().size());
  for (const auto& [id, a] : monitor.agents()) {
    AgentRow r;
    r.id = id;
    r.alive = monitor.alive(a, now_ns);
    r.departed = a.departed;
    r.last_seen_s = static_cast<double>(now_ns - a.last_seen_ns) * 1e-9;
    r.x = a.x;
    r.epoch = a.command.epoch;
    if (shape && a.command == monitor.command_id()) r.shape_error = (a.x - core::target_point(*shape, cmd->curve(), a.x)).norm();
    r.neighbours_heard = a.neighbours_heard;
    const dds::StatusSample& st = a.status;
    if (st.epoch == monitor.epoch() && st.epoch != 0) {
      if (st.beyond_fence) r.safety = "beyond the fence";
      else if (st.blocked)
        r.safety = st.blocked_by >= 0    ? "held by " + std::to_string(st.blocked_by)
                   : st.blocked_by <= -2 ? "held by zone " + std::to_string(-1 - st.blocked_by)
                                         : "held by the fence";
    }
    rows.push_back(r);
  }
  return rows;
}

std::string status_table(const std::vector<AgentRow>& rows) {
  std::ostringstream o;
  char line[200];
  std::snprintf(line, sizeof line, "%6s %-6s %10s %10s %10s %6s %11s %6s  %s\n", "agent", "alive", "last_seen",
                "x1", "x2", "epoch", "shape_error", "heard", "safety");
  o << line;
  for (const AgentRow& r : rows) {
    std::snprintf(line, sizeof line, "%6d %-6s %9.2fs %10.4f %10.4f %6llu %11s %6s  %s\n", r.id,
                  r.alive ? "yes" : (r.departed ? "left" : "DEAD"), r.last_seen_s, r.x.x(), r.x.y(), static_cast<unsigned long long>(r.epoch),
                  fmt_opt(r.shape_error).c_str(), count_or_dash(r.neighbours_heard).c_str(), r.safety.c_str());
    o << line;
  }
  if (rows.empty()) o << "(no agent heard yet)\n";
  return o.str();
}

nlohmann::json status_json(const std::vector<AgentRow>& rows, std::uint64_t epoch, double model_time) {
  nlohmann::json agents = nlohmann::json::array();
  for (const AgentRow& r : rows)
    agents.push_back({{"id", r.id},
                      {"alive", r.alive},
                      {"state", r.alive ? "alive" : (r.departed ? "left" : "dead")},
                      {"last_seen_s", r.last_seen_s},
                      {"x", r.x.x()},
                      {"y", r.x.y()},
                      {"epoch", r.epoch},
                      {"shape_error", or_null(r.shape_error)},
                      {"neighbours_heard", or_null(r.neighbours_heard)},
                      {"safety", r.safety}});
  return {{"event", "status"}, {"epoch", epoch}, {"model_time", model_time}, {"agents", std::move(agents)}};
}

std::string progress_line(const SwarmMonitor::Sample& s, const core::Command& current) {
  const core::Metrics& m = s.metrics;
  std::ostringstream o;
  o << "t=" << fmt_opt(s.model_time, "%.0f") << " agents=" << s.alive << " following=" << s.following
    << " shape_error=" << fmt_opt(m.shape_error_mean) << " max=" << fmt_opt(m.shape_error_max)
    << " gap_cv=" << fmt_opt(m.gap_cv) << " min_sep=" << fmt_opt(m.min_separation)
    << " clusters=" << count_or_dash(m.clusters);
  if (m.centroid_error) o << " centroid_error=" << fmt_opt(m.centroid_error) << " ring_error=" << fmt_opt(m.ring_error);
  if (current.law == core::Law::Arc || !m.shape_error_mean || m.curve_error_mean != m.shape_error_mean)
    o << " curve_error=" << fmt_opt(m.curve_error_mean, "%.2e") << " arc_gap_cv=" << fmt_opt(m.arc_gap_cv, "%.2e");
  o << (s.converged ? " converged" : "");
  return o.str();
}

nlohmann::json metrics_answer(const SwarmMonitor::Sample& s, std::uint64_t epoch) {
  nlohmann::json j = app::metrics_json(s.metrics);
  j["epoch"] = epoch;
  j["model_time"] = s.model_time;
  j["converged"] = s.converged;
  j["verdict"] = core::to_string(s.why);
  return j;
}

std::string metrics_table(const SwarmMonitor::Sample& s, std::uint64_t epoch) {
  std::ostringstream o;
  o << "epoch " << epoch << ", model time t=" << fmt_opt(s.model_time, "%.4g") << ", " << s.alive << " agents alive, "
    << s.following << " following, " << (s.converged ? std::string("converged") : std::string("not converged (") + core::to_string(s.why) + ")") << '\n';
  char line[160];
  for (const core::MetricInfo& info : core::kMetricTable) {
    const std::optional<double> v = info.get(s.metrics);
    const std::string value = !v ? "-" : info.count ? std::to_string(std::llround(*v)) : fmt_opt(v, "%.4g");
    const std::string unit = info.unit == "1" ? "" : "  " + std::string(info.unit);  // "1": a ratio
    std::snprintf(line, sizeof line, "  %-17s %11s%s\n", std::string(info.name).c_str(), value.c_str(), unit.c_str());
    o << line;
  }
  return o.str();
}

void ProgressFilter::every(double seconds) {
  mode_ = Mode::Every;
  every_ns_ = static_cast<std::int64_t>(std::min(seconds, 1e9) * 1e9);
}

bool ProgressFilter::changed(const SwarmMonitor::Sample& s, std::uint64_t epoch) const {
  if (!last_) return true;
  const SwarmMonitor::Sample& l = *last_;
  if (s.alive != l.alive || s.following != l.following || epoch != last_epoch_ || s.converged != l.converged)
    return true;
  for (const core::MetricInfo& info : core::kMetricTable) {
    const std::optional<double> a = info.get(l.metrics);
    const std::optional<double> b = info.get(s.metrics);
    if (a.has_value() != b.has_value()) return true;
    if (!a) continue;
    if (info.count ? *a != *b : std::abs(*b - *a) > std::max(kRelTol * std::abs(*a), kAbsFloor)) return true;
  }
  return false;
}

bool ProgressFilter::due(const SwarmMonitor::Sample& s, std::uint64_t epoch, std::int64_t now_ns) {
  bool print = false;
  switch (mode_) {
    case Mode::Off: print = false; break;
    case Mode::Every: print = !last_ || now_ns - last_ns_ >= every_ns_; break;
    case Mode::OnChange: print = (!last_ || now_ns - last_ns_ >= kMinIntervalNs) && changed(s, epoch); break;
  }
  if (print) {
    last_ = s;
    last_epoch_ = epoch;
    last_ns_ = now_ns;
  }
  return print;
}

std::string show_text(const ShowInfo& info) {
  const core::Command& c = info.command;
  const core::ShapeSpec& sh = c.shape;
  std::ostringstream o;
  if (info.epoch == 0) {
    o << "no command in force yet; below is this supervisor's --config scenario (`start` publishes it)\n";
    if (info.agents_epoch != 0)
      o << "the agents follow epoch " << info.agents_epoch << ", published by another participant (not heard yet)\n";
  } else {
    o << "epoch " << info.epoch << ", published by "
      << (info.own ? std::string("this supervisor ") : info.publisher + " (another participant), learnt ")
      << fmt_opt(info.published_s_ago, "%.1f") << " s ago; " << info.following << " of " << info.alive
      << " agents follow it\n";
    if (info.superseded != 0)
      o << "this supervisor's epoch " << info.superseded << " was superseded by it\n";
    if (info.agents_epoch > info.epoch)
      o << "some agents follow epoch " << info.agents_epoch << ", not heard on the command topic yet\n";
  }
  std::ostringstream shape;
  shape << shape_parameters(sh);
  if (sh.kind != core::ShapeKind::Line) shape << " centre (" << sh.centre.x() << ", " << sh.centre.y() << ")";
  shape << " rot=" << sh.rotation / core::params::kRadPerDeg << " deg scale=" << sh.scale;
  o << "  shape       " << shape.str() << '\n';
  o << "  tracking    ";
  if (c.tracking.enabled)
    o << "on a " << core::to_string(c.tracking.path.kind) << " path, feed-forward "
      << (c.tracking.feedforward ? "on" : "off") << '\n';
  else
    o << "off\n";
  o << "  law         " << core::to_string(c.law);
  if (c.law == core::Law::Arc)
    o << " k_normal=" << c.arc.k_normal << " k_tangent=" << c.arc.k_tangent << " spacing=" << c.arc.spacing;
  o << "\n  gains       k1=" << c.gains.k1 << " k2=" << c.gains.k2 << " sigma=" << c.gains.sigma
    << " beta=" << c.gains.beta << " r=" << c.gains.r << '\n';
  o << "  integrator  " << core::to_string(c.integrator) << " dt=" << c.dt << '\n';
  o << "  max_speed   ";
  if (c.max_speed > 0) o << c.max_speed << '\n';
  else o << "off\n";
  o << safety_lines(c);
  return o.str();
}

std::string safety_lines(const core::Command& c) {
  std::ostringstream o;
  const auto points = [](const std::vector<core::Vec2>& v) {
    std::ostringstream p;
    p << "(";
    for (std::size_t i = 0; i < v.size(); ++i) p << (i == 0 ? "" : "; ") << v[i].x() << ", " << v[i].y();
    p << ")";
    return p.str();
  };
  o << "  separation  ";
  if (c.min_separation > 0)
    o << c.min_separation << '\n';
  else
    o << "off\n";
  o << "  keep_out    ";
  if (c.keep_out.empty())
    o << "none\n";
  else
    o << c.keep_out.size() << (c.keep_out.size() == 1 ? " zone\n" : " zones\n");
  for (std::size_t k = 0; k < c.keep_out.size(); ++k) {
    const core::KeepOutZone& z = c.keep_out[k];
    o << "    " << k + 1 << "  ";
    if (z.kind == core::KeepOutZone::Kind::Circle)
      o << "circle centre (" << z.centre.x() << ", " << z.centre.y() << ") r=" << z.radius << '\n';
    else
      o << "polygon " << points(z.vertices) << '\n';
  }
  o << "  fence       ";
  if (c.fence.empty())
    o << "box [" << -c.workspace << ", " << c.workspace << "]^2 (safety.workspace)\n";
  else
    o << "polygon " << points(c.fence) << '\n';
  o << "  margin      " << c.fence_margin << '\n';
  o << "  breach      " << core::to_string(c.breach_action) << '\n';
  return o.str();
}

nlohmann::json summary_json(const Summary& s) {
  const double t = s.sample.model_time;
  nlohmann::json j = app::metrics_json(s.sample.metrics);
  j["event"] = "summary";
  j["name"] = s.name;
  j["shape"] = std::string(core::to_string(s.command.shape.kind));
  j["law"] = std::string(core::to_string(s.command.law));
  j["tracking"] = s.command.tracking.enabled;
  j["epoch"] = s.epoch;
  j["model_time"] = t;
  j["dt"] = s.command.dt;
  j["steps"] = static_cast<long>(std::llround(t / s.command.dt));
  j["agents_seen"] = s.agents_seen;
  j["converged"] = s.sample.converged;
  j["verdict"] = core::to_string(s.sample.why);
  j["settle_step"] = or_null(settle_step(s));
  if (!s.command.tracking.enabled) {
    j.erase("centroid_error");
    j.erase("ring_error");
  }
  auto& ids = j["final_ids"] = nlohmann::json::array();
  auto& fp = j["final_positions"] = nlohmann::json::array();
  for (const auto& [id, x] : s.final_positions) {
    ids.push_back(id);
    fp.push_back({x.x(), x.y()});
  }
  j["final_model_times"] = s.final_model_times;  // each agent's own model time
  j["samples_rejected"] = s.samples_rejected;
  j["commands_refused"] = s.commands_refused;
  j["recording"] = or_null(s.recording);
  j["exit_status"] = s.exit_status;
  return j;
}

std::string summary_text(const Summary& s) {
  const core::Metrics& m = s.sample.metrics;
  const auto settle = settle_step(s);
  std::ostringstream o;
  o << "summary: epoch " << s.epoch << ", " << s.sample.alive << " agents, t=" << fmt_opt(s.sample.model_time, "%.0f")
    << (s.sample.converged ? std::string(", converged") : std::string(", not converged (") + core::to_string(s.sample.why) + ")") << "\n  shape_error_mean=" << fmt_opt(m.shape_error_mean)
    << " shape_error_max=" << fmt_opt(m.shape_error_max) << " gap_cv=" << fmt_opt(m.gap_cv)
    << " min_separation=" << fmt_opt(m.min_separation) << " clusters=" << count_or_dash(m.clusters)
    << " settle_step=" << (settle ? std::to_string(*settle) : "-");
  o << " curve_error_mean=" << fmt_opt(m.curve_error_mean, "%.3g") << " arc_gap_cv=" << fmt_opt(m.arc_gap_cv, "%.3g");
  if (m.centroid_error) o << " centroid_error=" << fmt_opt(m.centroid_error) << " ring_error=" << fmt_opt(m.ring_error);
  o << '\n';
  if (s.recording) o << "  recording: " << *s.recording << '\n';
  return o.str();
}

}  // namespace shapeform::supervisor
