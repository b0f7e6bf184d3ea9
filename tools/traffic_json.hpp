#pragma once
/// What the traffic tools print, as pure functions: a domain's topics (shapeform_topics) as a table
/// or JSON, and one JSON line per sample of a topic (shapeform_echo). A sample is read through the
/// project's conversion (dds::from_msg, which validates it) into its plain struct, then written
/// with every field: one to-JSON per message, here and nowhere else.
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "dds/convert.hpp"
#include "dds/convert_ros2.hpp"
#include "dds/ros2_mirror.hpp"
#include "dds/discovery.hpp"
#include "dds/node.hpp"

namespace shapeform::tools {

/// {"event": "topic", "name", "types": [...], "writers": [...], "readers": [...]}, each endpoint
/// {"participant", "host", "pid" (null when unknown), "reliability", "durability", "type", "guid"}.
nlohmann::json topic_json(const dds::TopicSeen& t);

/// The human listing: per topic a line "NAME  TYPE  (W writers, R readers)", then one line per
/// endpoint: W or R, reliability, durability, participant, host and pid. "no topics seen" when empty.
std::string topics_table(const std::vector<dds::TopicSeen>& topics);

/// Every field of a sample, from the plain struct its from_msg gives (ids and counters as integers,
/// vectors as [x, y], undefined optionals as null); a state batch: {"first_id", "states": [each state
/// as one AgentState]}, a status batch {"first_id", "statuses": [each as one AgentStatus]}. The command: {"epoch", then its keys as the
/// config file nests them (app::command_json)}; the metrics: {"epoch", "model_time", "stamp_ns",
/// "converged", then app::metrics_json}.
/// False (with `why`) when from_msg refuses the sample.
bool sample_json(const msg::AgentState& m, nlohmann::json& out, std::string& why);
bool sample_json(const msg::AgentStateBatch& m, nlohmann::json& out, std::string& why);
bool sample_json(const msg::ShapeCommand& m, nlohmann::json& out, std::string& why);
bool sample_json(const msg::TrackingTarget& m, nlohmann::json& out, std::string& why);
bool sample_json(const msg::SwarmMetrics& m, nlohmann::json& out, std::string& why);
bool sample_json(const msg::AgentStatus& m, nlohmann::json& out, std::string& why);
bool sample_json(const msg::AgentStatusBatch& m, nlohmann::json& out, std::string& why);
/// A vehicle's topics (ROS 2's types): {"vx", "vy", "wz"} (+ "stamp_ns", "frame_id" when stamped);
/// a pose {"x": [x, y], "yaw", "frame_id", "stamp_ns"} (+ "v": [vx, vy], "wz", "child_frame_id" for
/// Odometry).
bool sample_json(const dds::ros2::Twist& m, nlohmann::json& out, std::string& why);
bool sample_json(const dds::ros2::TwistStamped& m, nlohmann::json& out, std::string& why);
bool sample_json(const dds::ros2::Odometry& m, nlohmann::json& out, std::string& why);
bool sample_json(const dds::ros2::PoseStamped& m, nlohmann::json& out, std::string& why);
/// The ROS 2 mirror's topics (dds/ros2_mirror.hpp), written as they are (nothing to refuse): a PoseArray
/// {"frame_id", "stamp_ns", "poses": [{"x": [x, y], "z", "yaw" (null when not a rotation)}, ...]}; a
/// MarkerArray {"markers": [{"ns", "id", "type", "action", "frame_id", "stamp_ns", "position": [x, y, z],
/// "points": [[x, y, z], ...], "text"}, ...]}.
bool sample_json(const dds::ros2::PoseArray& m, nlohmann::json& out, std::string& why);
bool sample_json(const dds::ros2::MarkerArray& m, nlohmann::json& out, std::string& why);

/// One line of shapeform_echo for a sample taken from `topic`:
///  {"event": "sample", "topic", "data": sample_json} for valid data;
///  {"event": "rejected", "topic", "why"} when the conversion refuses it;
///  {"event": "disposed" | "no_writers", "topic", "id"} for an instance that left (keyed topics);
/// each with "source": the writer's participant (GUID prefix) when known.
template <class Msg>
nlohmann::json echo_line(const char* topic, const dds::Received<Msg>& r) {
  nlohmann::json line = {{"topic", topic}};
  if (r.source.known()) line["source"] = dds::to_string(r.source);
  if (!r.valid_data) {
    line["event"] = r.instance == dds::InstanceState::Disposed ? "disposed" : "no_writers";
    line["id"] = r.key_id;
    return line;
  }
  nlohmann::json data;
  std::string why;
  if (sample_json(r.msg, data, why)) {
    line["event"] = "sample";
    line["data"] = std::move(data);
  } else {
    line["event"] = "rejected";
    line["why"] = why;
  }
  return line;
}

}  // namespace shapeform::tools
