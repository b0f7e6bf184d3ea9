// What the traffic tools print: topics as a table and JSON, samples as JSON lines.
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <string>

#include "app/json.hpp"
#include "core/metric_table.hpp"
#include "traffic_json.hpp"

namespace shapeform {
namespace {

dds::EndpointSeen endpoint(const std::string& participant, const char* rel, const char* dur, int pid = 42) {
  dds::EndpointSeen e;
  e.participant = participant;
  e.host = "box";
  e.pid = pid;
  e.reliability = rel;
  e.durability = dur;
  e.type = "shapeform::msg::ShapeCommand";
  e.guid = "01.0f.aa|0.0.1.3";
  return e;
}

dds::TopicSeen command_topic() {
  dds::TopicSeen t;
  t.name = "shapeform/command";
  t.types = {"shapeform::msg::ShapeCommand"};
  t.writers = {endpoint("shapeform_supervisor", "reliable", "transient_local")};
  t.readers = {endpoint("shapeform_agent_0", "reliable", "transient_local"),
               endpoint("shapeform_agent_1", "reliable", "transient_local", -1)};
  return t;
}

}  // namespace

TEST_CASE("topics as JSON: one object per topic, every endpoint with its QoS", "[tools][topics]") {
  const nlohmann::json j = tools::topic_json(command_topic());
  CHECK(j["event"] == "topic");
  CHECK(j["name"] == "shapeform/command");
  CHECK(j["types"] == nlohmann::json({"shapeform::msg::ShapeCommand"}));
  REQUIRE(j["writers"].size() == 1);
  REQUIRE(j["readers"].size() == 2);
  const nlohmann::json& w = j["writers"][0];
  CHECK(w["participant"] == "shapeform_supervisor");
  CHECK(w["host"] == "box");
  CHECK(w["pid"] == 42);
  CHECK(w["reliability"] == "reliable");
  CHECK(w["durability"] == "transient_local");
  CHECK(w["type"] == "shapeform::msg::ShapeCommand");
  CHECK(w["guid"] == "01.0f.aa|0.0.1.3");
  CHECK(j["readers"][1]["pid"].is_null());  // not announced
}

TEST_CASE("topics as a table: a line per topic, a line per endpoint, columns aligned", "[tools][topics]") {
  CHECK(tools::topics_table({}) == "no topics seen\n");
  dds::TopicSeen state;
  state.name = "shapeform/state";
  state.types = {"shapeform::msg::AgentState"};
  state.writers = {endpoint("shapeform_agent_0", "best_effort", "volatile")};
  const std::string table = tools::topics_table({command_topic(), state});
  CHECK(table ==
        "shapeform/command  shapeform::msg::ShapeCommand  (1 writer, 2 readers)\n"
        "  W  reliable     transient_local  shapeform_supervisor  box pid 42\n"
        "  R  reliable     transient_local  shapeform_agent_0     box pid 42\n"
        "  R  reliable     transient_local  shapeform_agent_1     box\n"
        "shapeform/state  shapeform::msg::AgentState  (1 writer, 0 readers)\n"
        "  W  best_effort  volatile         shapeform_agent_0     box pid 42\n");
}

TEST_CASE("a state sample: every field, through the project's conversion", "[tools][echo]") {
  dds::StateSample s;
  s.id = 3;
  s.seq = 17;
  s.stamp_ns = 123456789;
  s.command = dds::CommandId{2, dds::SourceId{{1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0x2a}}};
  s.model_time = 41.5;
  s.x = core::Vec2(1.25, -2.5);
  s.v = core::Vec2(0.5, 0.25);
  s.arc = 3.75;
  s.prev_x = core::Vec2(1.0, -2.0);
  s.prev_arc = 3.5;
  nlohmann::json j;
  std::string why;
  REQUIRE(tools::sample_json(dds::to_msg(s), j, why));
  CHECK(j == nlohmann::json({{"id", 3}, {"seq", 17}, {"stamp_ns", 123456789}, {"epoch", 2},
                             {"issuer", "01.00.00.00.00.00.00.00.00.00.00.2a"}, {"model_time", 41.5},
                             {"x", {1.25, -2.5}}, {"v", {0.5, 0.25}}, {"arc", 3.75}, {"prev_x", {1.0, -2.0}},
                             {"prev_arc", 3.5}}));
  s.arc.reset();
  REQUIRE(tools::sample_json(dds::to_msg(s), j, why));
  CHECK(j["arc"].is_null());
  CHECK(j["prev_arc"].is_null());
  // A sample the conversion refuses: an echo line that says why.
  msg::AgentState bad = dds::to_msg(s);
  bad.x(std::numeric_limits<double>::quiet_NaN());
  CHECK_FALSE(tools::sample_json(bad, j, why));
  CHECK(why.find("state.x") != std::string::npos);
  dds::Received<msg::AgentState> r{bad, 0, true, dds::InstanceState::Alive, 3, {}};
  const nlohmann::json line = tools::echo_line("shapeform/state", r);
  CHECK_FALSE(line.contains("source"));  // unknown writer: not invented
  CHECK(line["event"] == "rejected");
  CHECK(line["topic"] == "shapeform/state");
  CHECK(line["why"].get<std::string>().find("state.x") != std::string::npos);
}

TEST_CASE("echo lines: a sample, a disposed instance, a writer gone", "[tools][echo]") {
  dds::StatusSample st;
  st.id = 4;
  st.ticks = 100;
  st.neighbours_heard = 11;
  st.cpu_percent = 2.5;
  st.epoch = 7;
  dds::Received<msg::AgentStatus> r{dds::to_msg(st), 0, true, dds::InstanceState::Alive, 4, {}};
  r.source.prefix[0] = 0x01;
  r.source.prefix[11] = 0x2a;
  nlohmann::json line = tools::echo_line("shapeform/status", r);
  CHECK(line["source"] == "01.00.00.00.00.00.00.00.00.00.00.2a");
  CHECK(line["event"] == "sample");
  CHECK(line["topic"] == "shapeform/status");
  CHECK(line["data"]["id"] == 4);
  CHECK(line["data"]["ticks"] == 100);
  CHECK(line["data"]["neighbours_heard"] == 11);
  CHECK(line["data"]["cpu_percent"] == 2.5);
  CHECK(line["data"]["epoch"] == 7);
  CHECK(line["data"]["vehicle"] == "internal");
  CHECK(line["data"].size() == 21);  // every field of AgentStatus
  r.valid_data = false;
  r.instance = dds::InstanceState::Disposed;
  line = tools::echo_line("shapeform/status", r);
  CHECK(line == nlohmann::json({{"event", "disposed"}, {"topic", "shapeform/status"}, {"id", 4},
                               {"source", "01.00.00.00.00.00.00.00.00.00.00.2a"}}));
  r.instance = dds::InstanceState::NoWriters;
  CHECK(tools::echo_line("shapeform/status", r)["event"] == "no_writers");
}

TEST_CASE("a command sample: its epoch and every key of the command table", "[tools][echo]") {
  core::Command c;
  c.shape.kind = core::ShapeKind::Square;
  c.shape.a = 5;
  c.hold = true;
  nlohmann::json j;
  std::string why;
  REQUIRE(tools::sample_json(dds::to_msg(c, 9, "shapeform_supervisor on h pid 1"), j, why));
  CHECK(j["epoch"] == 9);
  CHECK(j["issuer"] == "00.00.00.00.00.00.00.00.00.00.00.00");  // as sent: none filled in
  CHECK(j["issuer_name"] == "shapeform_supervisor on h pid 1");
  CHECK(j["shape"]["kind"] == "square");
  CHECK(j["shape"]["a"] == 5.0);
  CHECK(j["dynamics"]["hold"] == true);
  nlohmann::json expected = app::command_json(c);
  expected["epoch"] = 9;
  expected["issuer"] = j["issuer"];
  expected["issuer_name"] = j["issuer_name"];
  CHECK(j == expected);
  msg::ShapeCommand bad = dds::to_msg(c, 9);
  bad.dt(50);
  CHECK_FALSE(tools::sample_json(bad, j, why));
  CHECK(why == "command.dt: must be in (0, 10], got 50");
}

TEST_CASE("a target and a metrics sample", "[tools][echo]") {
  nlohmann::json j;
  std::string why;
  REQUIRE(tools::sample_json(dds::to_msg(dds::TargetSample{3, 12.5, core::Vec2(1, 2), core::Vec2(0.5, 0), 99}), j, why));
  CHECK(j == nlohmann::json({{"epoch", 3}, {"issuer", "00.00.00.00.00.00.00.00.00.00.00.00"}, {"model_time", 12.5}, {"centre", {1.0, 2.0}}, {"velocity", {0.5, 0.0}},
                             {"stamp_ns", 99}}));
  core::Metrics m;
  m.agents = 12;
  m.shape_error_mean = 0.25;
  REQUIRE(tools::sample_json(dds::to_msg(m, 4, 80.0, 1234, true), j, why));
  CHECK(j["epoch"] == 4);
  CHECK(j["model_time"] == 80.0);
  CHECK(j["stamp_ns"] == 1234);
  CHECK(j["converged"] == true);
  CHECK(j["agents"] == 12);
  CHECK(j["shape_error_mean"] == 0.25);
  for (const core::MetricInfo& info : core::kMetricTable) CHECK(j.contains(std::string(info.name)));
}

TEST_CASE("echo lines: a vehicle's pose and command, through the ROS 2 conversion", "[tools][echo]") {
  dds::PoseSample p;
  p.x = {1.5, -2.0};
  p.yaw = 0.75;
  p.frame_id = "map";
  p.child_frame_id = "robot_3/base_link";
  p.stamp_ns = 1'700'000'000'123'456'789;
  p.has_twist = true;
  p.vx = 0.4;
  p.wz = -0.1;
  dds::ros2::Odometry odom;
  dds::to_msg(p, odom);
  dds::Received<dds::ros2::Odometry> r{odom, 0, true, dds::InstanceState::Alive, -1, {}};
  nlohmann::json line = tools::echo_line("rt/robot_3/odom", r);
  REQUIRE(line["event"] == "sample");
  CHECK(line["data"]["x"] == nlohmann::json({1.5, -2.0}));
  CHECK(line["data"]["yaw"].get<double>() == Approx(0.75).margin(1e-15));
  CHECK(line["data"]["frame_id"] == "map");
  CHECK(line["data"]["stamp_ns"] == p.stamp_ns);
  CHECK(line["data"]["child_frame_id"] == "robot_3/base_link");
  CHECK(line["data"]["v"] == nlohmann::json({0.4, 0.0}));
  // A pose that is not a rotation is refused with the field named.
  odom.pose().pose().orientation().w(0.0);
  odom.pose().pose().orientation().z(0.0);
  r.msg = odom;
  line = tools::echo_line("rt/robot_3/odom", r);
  CHECK(line["event"] == "rejected");
  CHECK(line["why"].get<std::string>().rfind("odom.pose.orientation: not a rotation", 0) == 0);

  dds::VelocitySample v{0.5, 0.0, 0.25, 42, "robot_3/base_link"};
  dds::ros2::TwistStamped t;
  dds::to_msg(v, t);
  dds::Received<dds::ros2::TwistStamped> c{t, 0, true, dds::InstanceState::Alive, -1, {}};
  CHECK(tools::echo_line("rt/robot_3/cmd_vel", c)["data"] ==
        nlohmann::json({{"vx", 0.5}, {"vy", 0.0}, {"wz", 0.25}, {"stamp_ns", 42}, {"frame_id", "robot_3/base_link"}}));
}

}  // namespace shapeform
