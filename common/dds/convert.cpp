#include "dds/convert.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

#include "core/metric_table.hpp"
#include "util/text.hpp"

namespace shapeform::dds {
namespace {

/// Collects problems of one message, "prefix.field: problem".
class Problems {
 public:
  explicit Problems(const char* prefix) : prefix_(prefix) {}

  bool finite(const std::string& field, double v) {
    if (std::isfinite(v)) return true;
    add(field, "must be finite, got " + util::format_g10(v));
    return false;
  }
  /// |v| (or what `what` names) at most kStateLimit: the bound of every received position and speed.
  void within_limit(const std::string& field, const std::string& what, double v) {
    if (std::abs(v) > kStateLimit)
      add(field, what + " must be <= " + util::format_g10(kStateLimit) + ", got " + util::format_g10(v));
  }
  void add(const std::string& field, const std::string& problem) {
    list_.push_back(std::string(prefix_) + "." + field + ": " + problem);
  }
  bool empty() const { return list_.empty(); }
  std::string joined() const {
    std::string s;
    for (const auto& p : list_) s += (s.empty() ? "" : "; ") + p;
    return s;
  }

 private:
  const char* prefix_;
  std::vector<std::string> list_;
};

/// A received metric: negative (-1) or non-finite values are undefined.
template <class Optional, class T>
Optional defined_or_null(T v) {
  if (!std::isfinite(static_cast<double>(v)) || v < 0) return std::nullopt;
  return static_cast<typename Optional::value_type>(v);
}

}  // namespace

namespace {
/// Whether a state with these fields passes every check of valid_state, decided without building any
/// message: a receiver takes every agent's state each tick, and nearly all are fine. A state near a
/// limit, or wrong, goes through the checks that name the field.
bool plainly_valid(std::int32_t id, double model_time, double x, double y, double prev_x, double prev_y, double arc,
                   double prev_arc, double vx, double vy) {
  const auto within = [](double v) { return std::abs(v) <= kStateLimit; };  // false for NaN
  const double speed2 = vx * vx + vy * vy;
  return id >= 0 && id <= kMaxAgentId && model_time >= 0.0 && model_time <= kModelTimeLimit && within(x) &&
         within(y) && within(prev_x) && within(prev_y) && std::isfinite(arc) && std::isfinite(prev_arc) &&
         speed2 <= 0.98 * kStateLimit * kStateLimit;
}

/// m -> out (every field read once from the generated accessors, which are not inlined), and whether m
/// plainly passes valid_state (the function above).
bool convert(const msg::AgentState& m, StateSample& out) {
  const double x = m.x(), y = m.y(), vx = m.vx(), vy = m.vy(), prev_x = m.prev_x(), prev_y = m.prev_y();
  const double arc = m.arc(), prev_arc = m.prev_arc(), model_time = m.model_time();
  const bool has_arc = m.has_arc();
  out.id = m.id();
  out.seq = m.seq();
  out.stamp_ns = m.stamp_ns();
  out.command = CommandId{m.epoch(), SourceId{m.issuer()}};
  out.model_time = model_time;
  out.x = core::Vec2(x, y);
  out.v = core::Vec2(vx, vy);
  out.arc = has_arc ? std::optional<double>(arc) : std::nullopt;
  out.prev_x = core::Vec2(prev_x, prev_y);
  out.prev_arc = has_arc ? std::optional<double>(prev_arc) : std::nullopt;
  return plainly_valid(out.id, model_time, x, y, prev_x, prev_y, arc, prev_arc, vx, vy);
}
}  // namespace

bool valid_state(const msg::AgentState& s, std::string& why) {
  if (plainly_valid(s.id(), s.model_time(), s.x(), s.y(), s.prev_x(), s.prev_y(), s.arc(), s.prev_arc(), s.vx(), s.vy()))
    return true;
  Problems p("state");
  if (s.id() < 0 || s.id() > kMaxAgentId)
    p.add("id", "must be in 0.." + std::to_string(kMaxAgentId) + ", got " + std::to_string(s.id()));
  if (p.finite("model_time", s.model_time()) && !(s.model_time() >= 0.0 && s.model_time() <= kModelTimeLimit))
    p.add("model_time", "must be in [0, " + util::format_g10(kModelTimeLimit) + "], got " +
                            util::format_g10(s.model_time()));
  const bool fx = p.finite("x", s.x());
  const bool fy = p.finite("y", s.y());
  const bool fvx = p.finite("vx", s.vx());
  const bool fvy = p.finite("vy", s.vy());
  p.finite("arc", s.arc());
  const bool fpx = p.finite("prev_x", s.prev_x());
  const bool fpy = p.finite("prev_y", s.prev_y());
  p.finite("prev_arc", s.prev_arc());
  if (fpx) p.within_limit("prev_x", "|prev_x|", s.prev_x());
  if (fpy) p.within_limit("prev_y", "|prev_y|", s.prev_y());
  if (fx) p.within_limit("x", "|x|", s.x());
  if (fy) p.within_limit("y", "|y|", s.y());
  if (fvx && fvy) p.within_limit("v", "speed", std::hypot(s.vx(), s.vy()));
  if (!p.empty()) {
    why = p.joined();
    return false;
  }
  return true;
}

StateSample to_sample(const msg::AgentState& m) {
  StateSample out;
  convert(m, out);
  return out;
}

msg::AgentState to_msg(const StateSample& s) {
  msg::AgentState m;
  m.id(s.id);
  m.seq(s.seq);
  m.stamp_ns(s.stamp_ns);
  m.epoch(s.command.epoch);
  m.issuer(s.command.issuer.prefix);
  m.model_time(s.model_time);
  m.x(s.x.x());
  m.y(s.x.y());
  m.vx(s.v.x());
  m.vy(s.v.y());
  m.has_arc(s.arc.has_value());
  m.arc(s.arc.value_or(0.0));
  m.prev_x(s.prev_x.x());
  m.prev_y(s.prev_x.y());
  m.prev_arc(s.arc ? s.prev_arc.value_or(*s.arc) : 0.0);
  return m;
}

bool from_msg(const msg::AgentState& m, StateSample& out, std::string& why) {
  StateSample converted;
  if (!convert(m, converted) && !valid_state(m, why)) return false;
  out = converted;
  return true;
}

msg::AgentStateBatch to_msg(const std::vector<StateSample>& states) { return to_msg(states, 0, states.size()); }

msg::AgentStateBatch to_msg(const std::vector<StateSample>& states, std::size_t begin, std::size_t end) {
  msg::AgentStateBatch m;
  to_msg(states, begin, end, m);
  return m;
}

void to_msg(const std::vector<StateSample>& states, std::size_t begin, std::size_t end, msg::AgentStateBatch& out) {
  end = std::min(end, states.size());
  begin = std::min(begin, end);
  out.first_id(begin < end ? states[begin].id : 0);
  out.states().resize(end - begin);  // a reused message keeps its capacity
  for (std::size_t k = begin; k < end; ++k) out.states()[k - begin] = to_msg(states[k]);
}

std::vector<std::pair<std::size_t, std::size_t>> batch_ranges(std::size_t count, std::size_t max_states) {
  std::vector<std::pair<std::size_t, std::size_t>> out;
  if (count == 0) return out;
  const std::size_t parts = (count + std::max<std::size_t>(max_states, 1) - 1) / std::max<std::size_t>(max_states, 1);
  const std::size_t base = count / parts, longer = count % parts;  // the first `longer` parts get one more
  std::size_t begin = 0;
  for (std::size_t k = 0; k < parts; ++k) {
    const std::size_t end = begin + base + (k < longer ? 1 : 0);
    out.emplace_back(begin, end);
    begin = end;
  }
  return out;
}

bool from_msg(const msg::AgentStateBatch& m, std::vector<StateSample>& out, std::string& why) {
  // Each field read once: the elements converted into a reused list, checked on the values read. A
  // batch that is not plainly fine (an element near a limit or wrong, ids not ascending, a wrong
  // first_id) goes through valid_batch, which decides it and names what is wrong.
  const auto& states = m.states();
  if (states.empty() || states.size() > kMaxBatchStates) return valid_batch(m, why);  // refused for its size
  thread_local std::vector<StateSample> converted;
  converted.resize(states.size());
  bool plain = true;
  for (std::size_t k = 0; k < states.size(); ++k) {
    plain = convert(states[k], converted[k]) && plain;
    if (k > 0 && converted[k].id <= converted[k - 1].id) plain = false;
  }
  if (plain && m.first_id() != converted.front().id) plain = false;
  if (!plain && !valid_batch(m, why)) return false;
  out.swap(converted);
  return true;
}

bool valid_batch(const msg::AgentStateBatch& m, std::string& why) {
  Problems p("state_batch");
  const auto& states = m.states();
  if (states.empty() || states.size() > kMaxBatchStates)
    p.add("states", "must hold 1 to " + std::to_string(kMaxBatchStates) + " states, got " +
                        std::to_string(states.size()));
  else if (m.first_id() != states.front().id())
    p.add("first_id", "must be the id of states[0] (" + std::to_string(states.front().id()) + "), got " +
                          std::to_string(m.first_id()));
  if (!p.empty()) {
    why = p.joined();
    return false;
  }
  std::string all;
  for (std::size_t k = 0; k < states.size(); ++k) {
    std::string one;
    if (!valid_state(states[k], one)) {
      // Name the element: "state.x: ..." -> "state_batch.states[3].x: ..." (built only on a refusal).
      const std::string element = "state_batch.states[" + std::to_string(k) + "]";
      for (std::size_t at = 0; (at = one.find("state.", at)) != std::string::npos;) {
        if (at == 0 || (at >= 2 && one.compare(at - 2, 2, "; ") == 0)) {
          one.replace(at, 5, element);
          at += element.size();
        } else {
          at += 6;
        }
      }
      all += (all.empty() ? "" : "; ") + one;
    }
  }
  // Distinct ids: a batch naming one agent twice is malformed (checked on the valid ids only).
  // Ascending ids (as every group publishes them) are distinct without sorting.
  const bool ascending =
      std::adjacent_find(states.begin(), states.end(), [](const auto& a, const auto& b) { return a.id() >= b.id(); }) ==
      states.end();
  if (all.empty() && !ascending) {
    thread_local std::vector<std::int32_t> ids;  // reused: one batch per publisher and tick comes here
    ids.clear();
    for (const auto& s : states) ids.push_back(s.id());
    std::sort(ids.begin(), ids.end());
    const auto dup = std::adjacent_find(ids.begin(), ids.end());
    if (dup != ids.end()) all = "state_batch.states: id " + std::to_string(*dup) + " appears twice";
  }
  if (!all.empty()) {
    why = all;
    return false;
  }
  return true;
}

void to_msg(const std::vector<StatusSample>& statuses, std::size_t begin, std::size_t end, msg::AgentStatusBatch& out) {
  out.first_id(statuses.at(begin).id);
  auto& list = out.statuses();
  list.clear();
  for (std::size_t k = begin; k < end; ++k) list.push_back(to_msg(statuses[k]));
}

bool from_msg(const msg::AgentStatusBatch& m, std::vector<StatusSample>& out, std::string& why) {
  const auto& list = m.statuses();
  if (list.empty() || list.size() > kMaxBatchStates) {
    why = "status_batch.statuses: must hold 1 to " + std::to_string(kMaxBatchStates) + " statuses, got " +
          std::to_string(list.size());
    return false;
  }
  if (m.first_id() != list.front().id()) {
    why = "status_batch.first_id: must be the id of statuses[0] (" + std::to_string(list.front().id()) + "), got " +
          std::to_string(m.first_id());
    return false;
  }
  std::vector<StatusSample> converted(list.size());
  std::string all;
  for (std::size_t k = 0; k < list.size(); ++k) {
    std::string one;
    if (!from_msg(list[k], converted[k], one)) {
      // "status.id: ..." -> "status_batch.statuses[3].id: ..."
      all += (all.empty() ? "" : "; ") + ("status_batch.statuses[" + std::to_string(k) + "]") + one.substr(6);
    }
  }
  if (all.empty()) {
    std::vector<std::int32_t> ids;
    ids.reserve(converted.size());
    for (const auto& s : converted) ids.push_back(s.id);
    std::sort(ids.begin(), ids.end());
    if (const auto dup = std::adjacent_find(ids.begin(), ids.end()); dup != ids.end())
      all = "status_batch.statuses: id " + std::to_string(*dup) + " appears twice";
  }
  if (!all.empty()) {
    why = all;
    return false;
  }
  out = std::move(converted);
  return true;
}

msg::TrackingTarget to_msg(const TargetSample& t) {
  msg::TrackingTarget m;
  m.epoch(t.command.epoch);
  m.issuer(t.command.issuer.prefix);
  m.model_time(t.model_time);
  m.cx(t.centre.x());
  m.cy(t.centre.y());
  m.vx(t.velocity.x());
  m.vy(t.velocity.y());
  m.stamp_ns(t.stamp_ns);
  return m;
}

bool from_msg(const msg::TrackingTarget& m, TargetSample& out, std::string& why) {
  Problems p("target");
  const std::pair<const char*, double> fields[] = {
      {"model_time", m.model_time()}, {"cx", m.cx()}, {"cy", m.cy()}, {"vx", m.vx()}, {"vy", m.vy()}};
  for (const auto& [name, v] : fields)
    if (p.finite(name, v)) p.within_limit(name, "|" + std::string(name) + "|", v);
  if (!p.empty()) {
    why = p.joined();
    return false;
  }
  out = TargetSample{CommandId{m.epoch(), SourceId{m.issuer()}}, m.model_time(), core::Vec2(m.cx(), m.cy()), core::Vec2(m.vx(), m.vy()), m.stamp_ns()};
  return true;
}

msg::AgentStatus to_msg(const StatusSample& s) {
  msg::AgentStatus m;
  m.id(s.id);
  m.stamp_ns(s.stamp_ns);
  m.ticks(s.ticks);
  m.overruns(s.overruns);
  m.lateness_max_us(s.lateness_max_us);
  m.lateness_p99_us(s.lateness_p99_us);
  m.neighbours_heard(s.neighbours_heard);
  m.stale_dropped(s.stale_dropped);
  m.samples_rejected(s.samples_rejected);
  m.samples_received(s.samples_received);
  m.samples_lost(s.samples_lost);
  m.age_p50_us(s.age_p50_us);
  m.age_p99_us(s.age_p99_us);
  m.cpu_percent(s.cpu_percent);
  m.rss_mb(s.rss_mb);
  m.epoch(s.epoch);
  m.vehicle(static_cast<std::uint8_t>(s.vehicle));
  m.poses_refused(s.poses_refused);
  m.commands_saturated(s.commands_saturated);
  m.control_latency_p50_us(s.control_latency_p50_us);
  m.control_latency_p99_us(s.control_latency_p99_us);
  m.min_gap(s.min_gap);
  m.min_gap_time(s.min_gap_time);
  m.filter_interventions(s.filter_interventions);
  m.deadlock_sidesteps(s.deadlock_sidesteps);
  m.promises_broken(s.promises_broken);
  m.blocked(s.blocked);
  m.blocked_by(s.blocked_by);
  m.beyond_fence(s.beyond_fence);
  m.fence_breaches(s.fence_breaches);
  return m;
}

bool from_msg(const msg::AgentStatus& m, StatusSample& out, std::string& why) {
  if (m.id() < 0 || m.id() > kMaxAgentId) {
    why = "status.id: must be in 0.." + std::to_string(kMaxAgentId) + ", got " + std::to_string(m.id());
    return false;
  }
  if (m.vehicle() > static_cast<std::uint8_t>(VehicleHealth::PoseLost)) {
    why = "status.vehicle: must be 0..3, got " + std::to_string(m.vehicle());
    return false;
  }
  out = StatusSample{m.id(),           m.stamp_ns(),        m.ticks(),         m.overruns(),
                     m.lateness_max_us(), m.lateness_p99_us(), m.neighbours_heard(), m.stale_dropped(),
                     m.samples_rejected(), m.samples_received(), m.samples_lost(), m.age_p50_us(),
                     m.age_p99_us(),    m.cpu_percent(),     m.rss_mb(),        m.epoch(),
                     static_cast<VehicleHealth>(m.vehicle()), m.poses_refused(), m.commands_saturated(),
                     m.control_latency_p50_us(), m.control_latency_p99_us(),
                     m.min_gap(),       m.min_gap_time(),    m.filter_interventions(), m.deadlock_sidesteps(),
                     m.promises_broken(), m.blocked(),       m.blocked_by(),    m.beyond_fence(),
                     m.fence_breaches()};
  if (!std::isfinite(out.min_gap) || (out.min_gap < 0.0 && out.min_gap != -1.0) || !std::isfinite(out.min_gap_time)) {
    why = "status.min_gap: must be >= 0 or -1 (none) with a finite min_gap_time, got " + std::to_string(out.min_gap);
    return false;
  }
  return true;
}

msg::SwarmMetrics to_msg(const core::Metrics& m, std::uint64_t epoch, double model_time,
                         std::int64_t stamp_ns, bool converged) {
  msg::SwarmMetrics w;
  w.epoch(epoch);
  w.model_time(model_time);
  w.stamp_ns(stamp_ns);
  w.agents_alive(m.agents);
#define SHAPEFORM_METRIC_TO_WIRE(name, unit, description) w.name(m.name.value_or(-1));
  SHAPEFORM_METRICS(SHAPEFORM_METRIC_TO_WIRE)
#undef SHAPEFORM_METRIC_TO_WIRE
  w.converged(converged);
  return w;
}

core::Metrics from_msg(const msg::SwarmMetrics& w) {
  core::Metrics m;
  m.agents = w.agents_alive();
#define SHAPEFORM_METRIC_FROM_WIRE(name, unit, description) m.name = defined_or_null<decltype(m.name)>(w.name());
  SHAPEFORM_METRICS(SHAPEFORM_METRIC_FROM_WIRE)
#undef SHAPEFORM_METRIC_FROM_WIRE
  return m;
}

}  // namespace shapeform::dds
