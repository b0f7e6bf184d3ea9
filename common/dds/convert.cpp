#include "dds/convert.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

#include "core/envelope.hpp"
#include "core/metric_table.hpp"
#include "core/command_table.hpp"
#include "core/enum_names.hpp"
#include "core/params.hpp"
#include "shapes/shapes.hpp"
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
  /// A ShapeCommand number: finite and within the range the command table declares for `field`.
  void ranged(const char* field, double v) {
    if (!finite(field, v)) return;
    const core::params::Range& range = core::params::wire_range(field);
    if (!range.contains(v)) add(field, range.text() + ", got " + util::format_g10(v));
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

/// A received string as a message quotes it: at most util::kQuoteMax characters of it.
std::string quoted(const std::string& s) { return "\"" + util::excerpt(s) + "\""; }

/// " (line|circle|...)": the names a ShapeCommand enumeration field accepts.
template <class E, std::size_t N>
std::string accepted(const core::params::Name<E> (&table)[N]) {
  return " (" + core::params::join(core::params::names(table), "|") + ")";
}

/// A received metric: negative (-1) or non-finite values are undefined.
template <class Optional, class T>
Optional defined_or_null(T v) {
  if (!std::isfinite(static_cast<double>(v)) || v < 0) return std::nullopt;
  return static_cast<typename Optional::value_type>(v);
}

}  // namespace

msg::ShapeCommand to_msg(const core::Command& cmd, const CommandId& id, const std::string& issuer_name) {
  msg::ShapeCommand m;
  m.epoch(id.epoch);
  m.issuer(id.issuer.prefix);
  m.issuer_name(issuer_name);
  const core::ShapeSpec& s = cmd.shape;
  m.shape_kind(std::string(core::to_string(s.kind)));
  m.m(s.m);
  m.c(s.c);
  m.r0(s.r0);
  m.a(s.a);
  m.b(s.b);
  m.cx(s.centre.x());
  m.cy(s.centre.y());
  m.rotation(s.rotation);
  m.scale(s.scale);
  m.r_expr(s.r_expr);
  m.x_expr(s.x_expr);
  m.y_expr(s.y_expr);
  m.f_expr(s.f_expr);
  std::vector<double> flat;
  flat.reserve(2 * s.vertices.size());
  for (const core::Vec2& v : s.vertices) {
    flat.push_back(v.x());
    flat.push_back(v.y());
  }
  m.vertices(std::move(flat));
  m.closed(s.closed);

  const core::Tracking& t = cmd.tracking;
  m.tracking(t.enabled);
  m.path_kind(std::string(core::to_string(t.path.kind)));
  m.path_px(t.path.point.x());
  m.path_py(t.path.point.y());
  m.path_vx(t.path.velocity.x());
  m.path_vy(t.path.velocity.y());
  m.path_ox(t.path.origin.x());
  m.path_oy(t.path.origin.y());
  m.path_radius(t.path.radius);
  m.path_period(t.path.period);
  m.path_phase(t.path.phase);
  m.feedforward(t.feedforward);

  m.k1(cmd.gains.k1);
  m.k2(cmd.gains.k2);
  m.sigma(cmd.gains.sigma);
  m.beta(cmd.gains.beta);
  m.r(cmd.gains.r);
  m.max_speed(cmd.max_speed);

  m.integrator(std::string(core::to_string(cmd.integrator)));
  m.dt(cmd.dt);
  m.law(std::string(core::to_string(cmd.law)));
  m.k_normal(cmd.arc.k_normal);
  m.k_tangent(cmd.arc.k_tangent);
  m.spacing(cmd.arc.spacing);
  m.hold(cmd.hold);
  m.workspace(cmd.workspace);
  return m;
}

bool from_msg(const msg::ShapeCommand& m, core::CompiledCommand& out, std::string& error) {
  Problems p("command");
  core::Command c;

  if (!core::parse_shape_kind(m.shape_kind(), c.shape.kind)) {
    p.add("shape_kind", "unknown shape " + quoted(m.shape_kind()) +
                            accepted(core::params::kShapeKindNames));
  }
  p.ranged("m", m.m());
  p.ranged("c", m.c());
  p.ranged("r0", m.r0());
  p.ranged("a", m.a());
  p.ranged("b", m.b());
  p.ranged("cx", m.cx());
  p.ranged("cy", m.cy());
  c.shape.m = m.m();
  c.shape.c = m.c();
  c.shape.r0 = m.r0();
  c.shape.a = m.a();
  c.shape.b = m.b();
  c.shape.centre = core::Vec2(m.cx(), m.cy());
  p.ranged("rotation", m.rotation());
  p.ranged("scale", m.scale());
  c.shape.rotation = m.rotation();
  c.shape.scale = m.scale();
  c.shape.r_expr = m.r_expr();
  c.shape.x_expr = m.x_expr();
  c.shape.y_expr = m.y_expr();
  c.shape.f_expr = m.f_expr();
  const std::vector<double>& flat = m.vertices();
  if (flat.size() % 2 != 0) {
    p.add("vertices", "must hold x, y pairs (an even count), got " + std::to_string(flat.size()) +
                          " numbers");
  } else {
    for (std::size_t i = 0; i < flat.size(); ++i) p.finite("vertices[" + std::to_string(i) + "]", flat[i]);
    c.shape.vertices.reserve(flat.size() / 2);
    for (std::size_t i = 0; i + 1 < flat.size(); i += 2)
      c.shape.vertices.emplace_back(flat[i], flat[i + 1]);
  }
  c.shape.closed = m.closed();

  c.tracking.enabled = m.tracking();
  if (!core::parse_path_kind(m.path_kind(), c.tracking.path.kind)) {
    p.add("path_kind", "unknown path " + quoted(m.path_kind()) + accepted(core::params::kPathKindNames));
  }
  p.ranged("path_px", m.path_px());
  p.ranged("path_py", m.path_py());
  p.ranged("path_vx", m.path_vx());
  p.ranged("path_vy", m.path_vy());
  p.ranged("path_ox", m.path_ox());
  p.ranged("path_oy", m.path_oy());
  p.ranged("path_radius", m.path_radius());
  p.ranged("path_period", m.path_period());
  p.ranged("path_phase", m.path_phase());
  c.tracking.path.point = core::Vec2(m.path_px(), m.path_py());
  c.tracking.path.velocity = core::Vec2(m.path_vx(), m.path_vy());
  c.tracking.path.origin = core::Vec2(m.path_ox(), m.path_oy());
  c.tracking.path.radius = m.path_radius();
  c.tracking.path.period = m.path_period();
  c.tracking.path.phase = m.path_phase();
  c.tracking.feedforward = m.feedforward();

  p.ranged("k1", m.k1());
  p.ranged("k2", m.k2());
  p.ranged("sigma", m.sigma());
  p.ranged("beta", m.beta());
  p.ranged("r", m.r());
  p.ranged("max_speed", m.max_speed());
  c.gains.k1 = m.k1();
  c.gains.k2 = m.k2();
  c.gains.sigma = m.sigma();
  c.gains.beta = m.beta();
  c.gains.r = m.r();
  c.max_speed = m.max_speed();

  if (!core::parse_integrator(m.integrator(), c.integrator)) {
    p.add("integrator", "unknown integrator " + quoted(m.integrator()) + accepted(core::params::kIntegratorNames));
  }
  p.ranged("dt", m.dt());
  c.dt = m.dt();
  if (!core::parse_law(m.law(), c.law)) p.add("law", "unknown law " + quoted(m.law()) + accepted(core::params::kLawNames));
  p.ranged("k_normal", m.k_normal());
  p.ranged("k_tangent", m.k_tangent());
  p.ranged("spacing", m.spacing());
  c.arc.k_normal = m.k_normal();
  c.arc.k_tangent = m.k_tangent();
  c.arc.spacing = m.spacing();
  c.hold = m.hold();
  p.ranged("workspace", m.workspace());
  c.workspace = m.workspace();

  if (!p.empty()) {
    error = p.joined();
    return false;
  }
  // Only a well-formed command is compiled: a shape that cannot be built is refused as a whole.
  core::CompiledCommand compiled;
  try {
    compiled = shapes::compile(c);
  } catch (const core::ShapeError& e) {
    error = "command: " + util::excerpt(e.what(), util::kLineMax);  // it quotes the received expression
    return false;
  }
  // A command that could carry the swarm out of its workspace is refused as a whole, too.
  for (const core::EnvelopeProblem& e : core::envelope_problems(compiled)) p.add(e.wire, e.text);
  if (!p.empty()) {
    error = p.joined();
    return false;
  }
  out = std::move(compiled);
  return true;
}

bool from_msg(const msg::ShapeCommand& m, const SourceId& source, CommandSample& out, std::string& error) {
  core::CompiledCommand cmd;
  const bool ok = from_msg(m, cmd, error);
  if (m.epoch() == 0) error = "command.epoch: must be >= 1, got 0" + (ok ? std::string() : "; " + error);
  if (!ok || m.epoch() == 0) return false;
  out.command = std::move(cmd);
  out.id.epoch = m.epoch();
  out.id.issuer.prefix = m.issuer();
  if (!out.id.issuer.known()) out.id.issuer = source;
  out.issuer_name.clear();
  for (const char ch : m.issuer_name().substr(0, kIssuerNameMax))
    out.issuer_name += (static_cast<unsigned char>(ch) < 0x20 || ch == 0x7f) ? '?' : ch;
  return true;
}

namespace {
/// Whether a state passes every check of valid_state, decided without building any message: a
/// receiver takes every agent's state each tick, and nearly all are fine. A state near a limit, or
/// wrong, goes through the checks that name the field.
bool plainly_valid(const msg::AgentState& s) {
  const auto within = [](double v) { return std::abs(v) <= kStateLimit; };  // false for NaN
  const double speed2 = s.vx() * s.vx() + s.vy() * s.vy();
  return s.id() >= 0 && s.id() <= kMaxAgentId && s.model_time() >= 0.0 && s.model_time() <= kModelTimeLimit &&
         within(s.x()) && within(s.y()) && within(s.prev_x()) && within(s.prev_y()) && std::isfinite(s.arc()) &&
         std::isfinite(s.prev_arc()) && speed2 <= 0.98 * kStateLimit * kStateLimit;
}
}  // namespace

bool valid_state(const msg::AgentState& s, std::string& why) {
  if (plainly_valid(s)) return true;
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

namespace {
/// A valid AgentState -> StateSample.
StateSample to_sample(const msg::AgentState& m) {
  StateSample out;
  out.id = m.id();
  out.seq = m.seq();
  out.stamp_ns = m.stamp_ns();
  out.command = CommandId{m.epoch(), SourceId{m.issuer()}};
  out.model_time = m.model_time();
  out.x = core::Vec2(m.x(), m.y());
  out.v = core::Vec2(m.vx(), m.vy());
  out.arc = m.has_arc() ? std::optional<double>(m.arc()) : std::nullopt;
  out.prev_x = core::Vec2(m.prev_x(), m.prev_y());
  out.prev_arc = m.has_arc() ? std::optional<double>(m.prev_arc()) : std::nullopt;
  return out;
}
}  // namespace

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
  if (!valid_state(m, why)) return false;
  out = to_sample(m);
  return true;
}

msg::AgentStateBatch to_msg(const std::vector<StateSample>& states) {
  msg::AgentStateBatch m;
  m.first_id(states.empty() ? 0 : states.front().id);
  m.states().reserve(states.size());
  for (const StateSample& s : states) m.states().push_back(to_msg(s));
  return m;
}

bool from_msg(const msg::AgentStateBatch& m, std::vector<StateSample>& out, std::string& why) {
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
  if (all.empty()) {
    std::vector<std::int32_t> ids;
    ids.reserve(states.size());
    for (const auto& s : states) ids.push_back(s.id());
    std::sort(ids.begin(), ids.end());
    const auto dup = std::adjacent_find(ids.begin(), ids.end());
    if (dup != ids.end()) all = "state_batch.states: id " + std::to_string(*dup) + " appears twice";
  }
  if (!all.empty()) {
    why = all;
    return false;
  }
  out.clear();
  out.reserve(states.size());
  for (const auto& s : states) out.push_back(to_sample(s));
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
  return m;
}

bool from_msg(const msg::AgentStatus& m, StatusSample& out, std::string& why) {
  if (m.id() < 0 || m.id() > kMaxAgentId) {
    why = "status.id: must be in 0.." + std::to_string(kMaxAgentId) + ", got " + std::to_string(m.id());
    return false;
  }
  out = StatusSample{m.id(),           m.stamp_ns(),        m.ticks(),         m.overruns(),
                     m.lateness_max_us(), m.lateness_p99_us(), m.neighbours_heard(), m.stale_dropped(),
                     m.samples_rejected(), m.samples_received(), m.samples_lost(), m.age_p50_us(),
                     m.age_p99_us(),    m.cpu_percent(),     m.rss_mb(),        m.epoch()};
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
