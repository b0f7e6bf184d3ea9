#include "traffic_json.hpp"

#include <algorithm>
#include <optional>
#include <sstream>

#include "app/json.hpp"

namespace shapeform::tools {
namespace {

nlohmann::json vec(const core::Vec2& v) { return {v.x(), v.y()}; }

template <class T>
nlohmann::json or_null(const std::optional<T>& v) {
  return v ? nlohmann::json(*v) : nlohmann::json(nullptr);
}

nlohmann::json endpoint_json(const dds::EndpointSeen& e) {
  return {{"participant", e.participant}, {"host", e.host},
          {"pid", e.pid >= 0 ? nlohmann::json(e.pid) : nlohmann::json(nullptr)},
          {"reliability", e.reliability}, {"durability", e.durability},
          {"type", e.type}, {"guid", e.guid}};
}

std::string plural(std::size_t n, const char* word) {
  return std::to_string(n) + " " + word + (n == 1 ? "" : "s");
}

}  // namespace

nlohmann::json topic_json(const dds::TopicSeen& t) {
  nlohmann::json writers = nlohmann::json::array(), readers = nlohmann::json::array();
  for (const auto& e : t.writers) writers.push_back(endpoint_json(e));
  for (const auto& e : t.readers) readers.push_back(endpoint_json(e));
  return {{"event", "topic"}, {"name", t.name}, {"types", t.types},
          {"writers", std::move(writers)}, {"readers", std::move(readers)}};
}

std::string topics_table(const std::vector<dds::TopicSeen>& topics) {
  if (topics.empty()) return "no topics seen\n";
  // Column widths over every endpoint, so the rows of all topics line up.
  std::size_t wr = 0, wd = 0, wp = 0;
  for (const auto& t : topics)
    for (const auto* list : {&t.writers, &t.readers})
      for (const auto& e : *list) {
        wr = std::max(wr, e.reliability.size());
        wd = std::max(wd, e.durability.size());
        wp = std::max(wp, e.participant.size());
      }
  const auto pad = [](const std::string& s, std::size_t w) { return s + std::string(w - std::min(w, s.size()), ' '); };
  std::ostringstream o;
  for (const auto& t : topics) {
    std::string types;
    for (const auto& ty : t.types) types += (types.empty() ? "" : " | ") + ty;
    o << t.name << "  " << types << "  (" << plural(t.writers.size(), "writer") << ", "
      << plural(t.readers.size(), "reader") << ")\n";
    for (const auto* list : {&t.writers, &t.readers})
      for (const auto& e : *list) {
        o << "  " << (list == &t.writers ? "W" : "R") << "  " << pad(e.reliability, wr) << "  " << pad(e.durability, wd)
          << "  " << pad(e.participant.empty() ? "?" : e.participant, wp) << "  " << (e.host.empty() ? "?" : e.host);
        if (e.pid >= 0) o << " pid " << e.pid;
        if (t.types.size() > 1) o << "  " << e.type;
        o << "\n";
      }
  }
  return o.str();
}

namespace {
nlohmann::json state_json(const dds::StateSample& s) {
  return {{"id", s.id},
         {"seq", s.seq},
         {"stamp_ns", s.stamp_ns},
         {"epoch", s.command.epoch},
         {"issuer", dds::to_string(s.command.issuer)},
         {"model_time", s.model_time},
         {"x", vec(s.x)},
         {"v", vec(s.v)},
         {"arc", or_null(s.arc)},
         {"prev_x", vec(s.prev_x)},
         {"prev_arc", or_null(s.prev_arc)}};
}
}  // namespace

bool sample_json(const msg::AgentState& m, nlohmann::json& out, std::string& why) {
  dds::StateSample s;
  if (!dds::from_msg(m, s, why)) return false;
  out = state_json(s);
  return true;
}

bool sample_json(const msg::AgentStateBatch& m, nlohmann::json& out, std::string& why) {
  std::vector<dds::StateSample> states;
  if (!dds::from_msg(m, states, why)) return false;
  nlohmann::json list = nlohmann::json::array();
  for (const auto& s : states) list.push_back(state_json(s));
  out = {{"first_id", m.first_id()}, {"states", std::move(list)}};
  return true;
}

bool sample_json(const msg::ShapeCommand& m, nlohmann::json& out, std::string& why) {
  core::CompiledCommand c;
  if (!dds::from_msg(m, c, why)) return false;
  out = {{"epoch", m.epoch()}, {"issuer", dds::to_string(dds::SourceId{m.issuer()})}, {"issuer_name", m.issuer_name()}};
  out.update(app::command_json(c));
  return true;
}

bool sample_json(const msg::TrackingTarget& m, nlohmann::json& out, std::string& why) {
  dds::TargetSample t;
  if (!dds::from_msg(m, t, why)) return false;
  out = {{"epoch", t.command.epoch},
         {"issuer", dds::to_string(t.command.issuer)},
         {"model_time", t.model_time},
         {"centre", vec(t.centre)},
         {"velocity", vec(t.velocity)},
         {"stamp_ns", t.stamp_ns}};
  return true;
}

bool sample_json(const msg::SwarmMetrics& m, nlohmann::json& out, std::string&) {
  // Every value is accepted: undefined (negative or non-finite) metrics read as null.
  out = {{"epoch", m.epoch()}, {"model_time", m.model_time()}, {"stamp_ns", m.stamp_ns()}, {"converged", m.converged()}};
  out.update(app::metrics_json(dds::from_msg(m)));
  return true;
}

namespace {
nlohmann::json status_json(const dds::StatusSample& s) {
  return {{"id", s.id},
          {"stamp_ns", s.stamp_ns},
          {"ticks", s.ticks},
          {"overruns", s.overruns},
          {"lateness_max_us", s.lateness_max_us},
          {"lateness_p99_us", s.lateness_p99_us},
          {"neighbours_heard", s.neighbours_heard},
          {"stale_dropped", s.stale_dropped},
          {"samples_rejected", s.samples_rejected},
          {"samples_received", s.samples_received},
          {"samples_lost", s.samples_lost},
          {"age_p50_us", s.age_p50_us},
          {"age_p99_us", s.age_p99_us},
          {"cpu_percent", s.cpu_percent},
          {"rss_mb", s.rss_mb},
          {"epoch", s.epoch},
          {"vehicle", dds::to_string(s.vehicle)},
          {"poses_refused", s.poses_refused},
          {"commands_saturated", s.commands_saturated},
          {"control_latency_p50_us", s.control_latency_p50_us},
          {"control_latency_p99_us", s.control_latency_p99_us}};
}
}  // namespace

bool sample_json(const msg::AgentStatus& m, nlohmann::json& out, std::string& why) {
  dds::StatusSample s;
  if (!dds::from_msg(m, s, why)) return false;
  out = status_json(s);
  return true;
}

bool sample_json(const msg::AgentStatusBatch& m, nlohmann::json& out, std::string& why) {
  std::vector<dds::StatusSample> statuses;
  if (!dds::from_msg(m, statuses, why)) return false;
  nlohmann::json list = nlohmann::json::array();
  for (const auto& s : statuses) list.push_back(status_json(s));
  out = {{"first_id", m.first_id()}, {"statuses", std::move(list)}};
  return true;
}

namespace {
nlohmann::json velocity_json(const dds::VelocitySample& v) { return {{"vx", v.vx}, {"vy", v.vy}, {"wz", v.wz}}; }

nlohmann::json pose_json(const dds::PoseSample& p) {
  nlohmann::json j = {{"x", vec(p.x)}, {"yaw", p.yaw}, {"frame_id", p.frame_id}, {"stamp_ns", p.stamp_ns}};
  if (p.has_twist) {
    j["v"] = {p.vx, p.vy};
    j["wz"] = p.wz;
    j["child_frame_id"] = p.child_frame_id;
  }
  return j;
}

template <class Msg, class Sample>
bool through(const Msg& m, nlohmann::json& out, std::string& why, nlohmann::json (*json)(const Sample&)) {
  Sample s;
  if (!dds::from_msg(m, s, why)) return false;
  out = json(s);
  return true;
}
}  // namespace

bool sample_json(const dds::ros2::Twist& m, nlohmann::json& out, std::string& why) {
  return through(m, out, why, velocity_json);
}

bool sample_json(const dds::ros2::TwistStamped& m, nlohmann::json& out, std::string& why) {
  dds::VelocitySample v;
  if (!dds::from_msg(m, v, why)) return false;
  out = velocity_json(v);
  out["stamp_ns"] = v.stamp_ns;
  out["frame_id"] = v.frame_id;
  return true;
}

bool sample_json(const dds::ros2::Odometry& m, nlohmann::json& out, std::string& why) {
  return through(m, out, why, pose_json);
}

bool sample_json(const dds::ros2::PoseStamped& m, nlohmann::json& out, std::string& why) {
  return through(m, out, why, pose_json);
}

bool sample_json(const dds::ros2::PoseArray& m, nlohmann::json& out, std::string&) {
  nlohmann::json poses = nlohmann::json::array();
  for (const auto& p : m.poses()) {
    const auto& q = p.orientation();
    const std::optional<double> yaw = dds::yaw_of(q.x(), q.y(), q.z(), q.w());
    poses.push_back({{"x", {p.position().x(), p.position().y()}},
                     {"z", p.position().z()},
                     {"yaw", yaw ? nlohmann::json(*yaw) : nlohmann::json(nullptr)}});
  }
  out = {{"frame_id", m.header().frame_id()},
         {"stamp_ns", dds::stamp_ns(m.header().stamp().sec(), m.header().stamp().nanosec())},
         {"poses", std::move(poses)}};
  return true;
}

bool sample_json(const dds::ros2::MarkerArray& m, nlohmann::json& out, std::string&) {
  nlohmann::json markers = nlohmann::json::array();
  for (const auto& k : m.markers()) {
    nlohmann::json points = nlohmann::json::array();
    for (const auto& p : k.points()) points.push_back({p.x(), p.y(), p.z()});
    const auto& x = k.pose().position();
    markers.push_back({{"ns", k.ns()},
                       {"id", k.id()},
                       {"type", k.type()},
                       {"action", k.action()},
                       {"frame_id", k.header().frame_id()},
                       {"stamp_ns", dds::stamp_ns(k.header().stamp().sec(), k.header().stamp().nanosec())},
                       {"position", {x.x(), x.y(), x.z()}},
                       {"points", std::move(points)},
                       {"text", k.text()}});
  }
  out = {{"markers", std::move(markers)}};
  return true;
}

}  // namespace shapeform::tools
