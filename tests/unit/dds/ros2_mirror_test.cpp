// Unit tests of common/dds/ros2_mirror: the ROS 2 mirror's PoseArray and MarkerArray built from a scene,
// the scene built from a command, the topics' rows, and the PoseArray's bytes on the wire compared with
// bytes written by hand from the ROS 2 layout (geometry_msgs/PoseArray) and the XCDR1 rules.
#include "dds/ros2_mirror.hpp"

#include <fastrtps/rtps/common/SerializedPayload.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "dds/topics.hpp"
#include "geometry_msgs/msg/PoseArrayPubSubTypes.h"
#include "visualization_msgs/msg/MarkerArrayPubSubTypes.h"

namespace shapeform {
namespace {

constexpr double kPi = 3.14159265358979323846;

dds::MirrorScene a_scene() {
  dds::MirrorScene s;
  s.stamp_ns = 1'700'000'000'123'456'789;
  s.frame_id = "world";
  // Out of order on purpose: the messages are in ascending id.
  s.agents = {{7, core::Vec2(1.0, 2.0), core::Vec2(0.0, 0.5)},
              {2, core::Vec2(-3.0, 0.25), core::Vec2(0.0, 0.0)},
              {4, core::Vec2(0.5, -1.5), core::Vec2(-1.0, 0.0)}};
  return s;
}

const dds::ros2::Marker* find(const dds::ros2::MarkerArray& a, const std::string& ns, std::int32_t id) {
  for (const auto& m : a.markers())
    if (m.ns() == ns && m.id() == id) return &m;
  return nullptr;
}

std::size_t count_ns(const dds::ros2::MarkerArray& a, const std::string& ns) {
  std::size_t n = 0;
  for (const auto& m : a.markers()) n += m.ns() == ns ? 1 : 0;
  return n;
}

// ------------------------------------------------------------------------------------------------
// The PoseArray

TEST_CASE("the agents' PoseArray: header, ascending ids, positions, heading of the velocity",
          "[dds][ros2_mirror]") {
  dds::ros2::PoseArray p;
  dds::build_agents(a_scene(), p);
  CHECK(p.header().frame_id() == "world");
  CHECK(p.header().stamp().sec() == 1'700'000'000);
  CHECK(p.header().stamp().nanosec() == 123'456'789u);
  REQUIRE(p.poses().size() == 3);
  // id 2, 4, 7
  CHECK(p.poses()[0].position().x() == -3.0);
  CHECK(p.poses()[0].position().y() == 0.25);
  CHECK(p.poses()[1].position().x() == 0.5);
  CHECK(p.poses()[2].position().y() == 2.0);
  for (const auto& pose : p.poses()) CHECK(pose.position().z() == 0.0);
  // At rest: identity. Moving -x: yaw pi. Moving +y: yaw pi/2. Rotations about z only, unit norm.
  const auto& q0 = p.poses()[0].orientation();
  CHECK((q0.x() == 0.0 && q0.y() == 0.0 && q0.z() == 0.0 && q0.w() == 1.0));
  const auto& q1 = p.poses()[1].orientation();
  CHECK(std::abs(2 * std::atan2(q1.z(), q1.w())) == Approx(kPi));
  const auto& q2 = p.poses()[2].orientation();
  CHECK(2 * std::atan2(q2.z(), q2.w()) == Approx(kPi / 2));
  for (const auto& pose : p.poses()) {
    const auto& q = pose.orientation();
    CHECK(q.x() * q.x() + q.y() * q.y() + q.z() * q.z() + q.w() * q.w() == Approx(1.0));
  }
  // A second build replaces, never appends.
  dds::MirrorScene fewer = a_scene();
  fewer.agents.pop_back();
  dds::build_agents(fewer, p);
  CHECK(p.poses().size() == 2);
}

TEST_CASE("a stamp before the epoch's second rounds down with nanosec in [0, 1e9)", "[dds][ros2_mirror]") {
  dds::MirrorScene s = a_scene();
  s.stamp_ns = -1;  // never sent by the supervisor (system clock), but the conversion must hold
  dds::ros2::PoseArray p;
  dds::build_agents(s, p);
  CHECK(p.header().stamp().sec() == -1);
  CHECK(p.header().stamp().nanosec() == 999'999'999u);
}

// ------------------------------------------------------------------------------------------------
// The MarkerArray

TEST_CASE(
    "markers: DELETEALL first, then per agent a sphere and its id as text, every one framed and stamped",
    "[dds][ros2_mirror]") {
  dds::ros2::MarkerArray a;
  dds::build_markers(a_scene(), a);
  REQUIRE(!a.markers().empty());
  CHECK(a.markers().front().action() == dds::ros2::kDeleteAll);
  CHECK(a.markers().size() == 1 + 2 * 3);  // no command: no outline, zones, fence, centre; no commands
  for (const auto& m : a.markers()) {
    CHECK(m.header().frame_id() == "world");
    CHECK(m.header().stamp().sec() == 1'700'000'000);
    CHECK(m.header().stamp().nanosec() == 123'456'789u);
    CHECK(m.lifetime().sec() == 0);
    CHECK(m.lifetime().nanosec() == 0u);
    CHECK(m.pose().orientation().w() == 1.0);
  }
  // Ascending ids, sphere then text per agent.
  const std::vector<std::int32_t> ids = {2, 4, 7};
  for (std::size_t k = 0; k < ids.size(); ++k) {
    const auto& sphere = a.markers()[1 + 2 * k];
    const auto& text = a.markers()[2 + 2 * k];
    CHECK(sphere.ns() == "agents");
    CHECK(sphere.id() == ids[k]);
    CHECK(sphere.type() == dds::ros2::kSphere);
    CHECK(sphere.action() == dds::ros2::kAdd);
    CHECK(sphere.scale().x() == 0.2);
    CHECK(sphere.color().a() == 1.0f);
    CHECK(text.ns() == "agent_ids");
    CHECK(text.id() == ids[k]);
    CHECK(text.type() == dds::ros2::kTextViewFacing);
    CHECK(text.text() == std::to_string(ids[k]));
    CHECK(text.pose().position().x() == sphere.pose().position().x());
    CHECK(text.pose().position().z() > sphere.pose().position().z());  // above it
    CHECK(text.scale().z() > 0.0);
  }
  const auto* seven = find(a, "agents", 7);
  REQUIRE(seven);
  CHECK(seven->pose().position().x() == 1.0);
  CHECK(seven->pose().position().y() == 2.0);
}

TEST_CASE("markers: outline, zones and fence as closed line strips, the centre, commands as arrows",
          "[dds][ros2_mirror]") {
  dds::MirrorScene s = a_scene();
  s.outline = dds::Polyline{{{1, 0}, {0, 1}, {-1, 0}, {0, -1}}, true};
  core::KeepOutZone circle;
  circle.centre = core::Vec2(5, 5);
  circle.radius = 2;
  s.keep_out.push_back(dds::zone_outline(circle, 16));
  core::KeepOutZone square;
  square.kind = core::KeepOutZone::Kind::Polygon;
  square.vertices = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  s.keep_out.push_back(dds::zone_outline(square));
  s.fence = dds::Polyline{{{-10, -10}, {10, -10}, {10, 10}, {-10, 10}}, true};
  s.centre = core::Vec2(0.5, -0.5);
  s.commands = true;
  dds::ros2::MarkerArray a;
  dds::build_markers(s, a);
  CHECK(a.markers().size() == 1 + 6 + 1 + 2 + 1 + 1 + 3);

  const auto* outline = find(a, "outline", 0);
  REQUIRE(outline);
  CHECK(outline->type() == dds::ros2::kLineStrip);
  CHECK(outline->scale().x() == s.line_width);
  REQUIRE(outline->points().size() == 5);  // closed: the first point again at the end
  CHECK(outline->points().front().x() == outline->points().back().x());
  CHECK(outline->points().front().y() == outline->points().back().y());

  REQUIRE(count_ns(a, "keep_out") == 2);
  const auto* c = find(a, "keep_out", 0);
  REQUIRE(c);
  REQUIRE(c->points().size() == 17);
  for (const auto& p : c->points()) CHECK(std::hypot(p.x() - 5, p.y() - 5) == Approx(2.0));
  CHECK(c->points().front().x() == c->points().back().x());
  const auto* sq = find(a, "keep_out", 1);
  REQUIRE(sq);
  REQUIRE(sq->points().size() == 5);
  CHECK(sq->points()[2].x() == 1.0);
  CHECK(sq->points()[2].y() == 1.0);
  CHECK(sq->color().r() > sq->color().g());  // red

  const auto* fence = find(a, "fence", 0);
  REQUIRE(fence);
  CHECK(fence->points().size() == 5);
  CHECK(fence->type() == dds::ros2::kLineStrip);

  const auto* centre = find(a, "centre", 0);
  REQUIRE(centre);
  CHECK(centre->type() == dds::ros2::kSphere);
  CHECK(centre->pose().position().x() == 0.5);
  CHECK(centre->pose().position().y() == -0.5);

  REQUIRE(count_ns(a, "commands") == 3);
  const auto* arrow = find(a, "commands", 4);  // at (0.5, -1.5), velocity (-1, 0)
  REQUIRE(arrow);
  CHECK(arrow->type() == dds::ros2::kArrow);
  REQUIRE(arrow->points().size() == 2);
  CHECK(arrow->points()[0].x() == 0.5);
  CHECK(arrow->points()[1].x() == -0.5);
  CHECK(arrow->points()[1].y() == -1.5);

  // Colours are visible (alpha 1) and the kinds are told apart.
  for (const auto& m : a.markers())
    if (m.action() == dds::ros2::kAdd) CHECK(m.color().a() == 1.0f);
  CHECK((outline->color().g() != fence->color().g() || outline->color().r() != fence->color().r()));
}

TEST_CASE("the scene of a command: outline on the shape, zones, fence only when set, centre when tracking",
          "[dds][ros2_mirror]") {
  core::Command cmd;  // the paper's circle
  cmd.keep_out.push_back(core::KeepOutZone{core::KeepOutZone::Kind::Circle, core::Vec2(3, 3), 1.0, {}});
  const core::CompiledCommand compiled = core::compile(cmd);
  dds::MirrorScene s = dds::mirror_scene({}, &compiled, 0.0, 42, "map", false);
  CHECK(s.stamp_ns == 42);
  CHECK(s.frame_id == "map");
  REQUIRE(s.outline);
  CHECK(s.outline->closed);
  CHECK(s.outline->points.size() == 240);
  // Every outline point lies on the circle of the command (its centre, radius scale x r0).
  const double r = cmd.shape.scale * cmd.shape.r0;
  for (const core::Vec2& p : s.outline->points)
    CHECK((p - cmd.shape.centre).norm() == Approx(r).epsilon(1e-6));
  CHECK(s.keep_out.size() == 1);
  CHECK(!s.fence);  // the workspace box is not drawn
  CHECK(!s.centre);
  CHECK(s.agent_diameter == 0.2);

  cmd.fence = {{-8, -8}, {8, -8}, {8, 8}, {-8, 8}};
  cmd.min_separation = 0.5;
  cmd.tracking.enabled = true;
  const core::CompiledCommand tracked = core::compile(cmd);
  s = dds::mirror_scene({}, &tracked, 0.0, 42, "map", true);
  REQUIRE(s.fence);
  CHECK(s.fence->points.size() == 4);
  CHECK(s.fence->closed);
  REQUIRE(s.centre);
  CHECK(*s.centre == core::centre_at(cmd.tracking.path, 0.0));
  CHECK(s.agent_diameter == 0.5);
  CHECK(s.commands);

  s = dds::mirror_scene({{1, core::Vec2(1, 1), core::Vec2::Zero()}}, nullptr, 0.0, 42, "map", false);
  CHECK(!s.outline);
  CHECK(s.keep_out.empty());
  CHECK(s.agents.size() == 1);
}

// ------------------------------------------------------------------------------------------------
// Names and QoS of the rows; the bytes on the wire

TEST_CASE("the mirror's topics: ROS 2 names, registered type names, reliable volatile",
          "[dds][ros2_mirror]") {
  const dds::TopicInfo& agents = dds::topic_info(dds::TopicId::Ros2Agents);
  CHECK(std::string(agents.name) == "rt/shapeform/agents");
  CHECK(std::string(agents.type) == "geometry_msgs::msg::dds_::PoseArray_");
  CHECK(agents.reliability == dds::Reliability::Reliable);
  CHECK(agents.durability == dds::Durability::Volatile);
  CHECK(!dds::is_keyed(dds::TopicId::Ros2Agents));
  CHECK(!dds::is_vehicle_topic(dds::TopicId::Ros2Agents));
  CHECK(dds::find_topic("rt/shapeform/agents") == dds::TopicId::Ros2Agents);
  CHECK(dds::message_name(dds::TopicId::Ros2Agents) == "geometry_msgs/msg/PoseArray");
  const dds::TopicInfo& markers = dds::topic_info(dds::TopicId::Ros2Markers);
  CHECK(std::string(markers.name) == "rt/shapeform/markers");
  CHECK(std::string(markers.type) == "visualization_msgs::msg::dds_::MarkerArray_");
  CHECK(markers.reliability == dds::Reliability::Reliable);
  CHECK(markers.durability == dds::Durability::Volatile);
  CHECK(dds::find_topic("rt/shapeform/markers") == dds::TopicId::Ros2Markers);
  // The generated types register under the names rmw_fastrtps gives them.
  CHECK(std::string(geometry_msgs::msg::dds_::PoseArray_PubSubType().getName()) ==
        "geometry_msgs::msg::dds_::PoseArray_");
  CHECK(std::string(visualization_msgs::msg::dds_::MarkerArray_PubSubType().getName()) ==
        "visualization_msgs::msg::dds_::MarkerArray_");
}

void put_u32(std::vector<unsigned char>& b, std::uint32_t v) {
  for (int k = 0; k < 4; ++k) b.push_back(static_cast<unsigned char>(v >> (8 * k)));
}
void put_f64(std::vector<unsigned char>& b, double v) {
  std::uint64_t u;
  std::memcpy(&u, &v, 8);
  for (int k = 0; k < 8; ++k) b.push_back(static_cast<unsigned char>(u >> (8 * k)));
}

template <class PubSub, class Msg>
std::vector<unsigned char> serialize(const Msg& m) {
  PubSub type;
  eprosima::fastrtps::rtps::SerializedPayload_t payload(
      type.getSerializedSizeProvider(const_cast<Msg*>(&m))());
  REQUIRE(type.serialize(const_cast<Msg*>(&m), &payload));
  return std::vector<unsigned char>(payload.data, payload.data + payload.length);
}

TEST_CASE("a PoseArray_ on the wire is geometry_msgs/PoseArray in XCDR1, byte for byte",
          "[dds][ros2_mirror]") {
  dds::MirrorScene s;
  s.stamp_ns = 5'000'000'007;  // sec 5, nanosec 7
  s.frame_id = "map";          // 3 characters + NUL: the sequence's length ends at 20, doubles start at 24
  s.agents = {{0, core::Vec2(1.5, -2.0), core::Vec2::Zero()},
              {1, core::Vec2(3.0, 4.0), core::Vec2(0.0, 1.0)}};
  dds::ros2::PoseArray p;
  dds::build_agents(s, p);
  const std::vector<unsigned char> got = serialize<geometry_msgs::msg::dds_::PoseArray_PubSubType>(p);

  std::vector<unsigned char> want = {0x00, 0x01, 0x00, 0x00};  // encapsulation: CDR, little endian
  // Alignment counts from the byte after the encapsulation.
  put_u32(want, 5);  // 0: header.stamp.sec (int32)
  put_u32(want, 7);  // 4: header.stamp.nanosec (uint32)
  put_u32(want, 4);  // 8: header.frame_id: length with the NUL
  for (char c : std::string("map")) want.push_back(static_cast<unsigned char>(c));
  want.push_back(0);                              // 12..15: "map\0"
  put_u32(want, 2);                               // 16: poses: sequence length
  for (int k = 0; k < 4; ++k) want.push_back(0);  // 20: padding to 8 for the first double
  // pose 1 moves +y: yaw pi/2, the quaternion (0, 0, sin pi/4, cos pi/4)
  for (double v : {1.5, -2.0, 0.0, 0.0, 0.0, 0.0, 1.0}) put_f64(want, v);  // 24: pose 0
  for (double v : {3.0, 4.0, 0.0, 0.0, 0.0, std::sin(kPi / 4), std::cos(kPi / 4)}) put_f64(want, v);  // 80
  REQUIRE(got.size() == want.size());  // 4 + 136
  CHECK(got == want);

  // And back: the generated type reads what the layout says.
  geometry_msgs::msg::dds_::PoseArray_PubSubType type;
  eprosima::fastrtps::rtps::SerializedPayload_t payload(static_cast<std::uint32_t>(want.size()));
  std::memcpy(payload.data, want.data(), want.size());
  payload.length = static_cast<std::uint32_t>(want.size());
  dds::ros2::PoseArray read;
  REQUIRE(type.deserialize(&payload, &read));
  CHECK(read == p);
}

TEST_CASE("a MarkerArray_ round-trips through its generated type with every field", "[dds][ros2_mirror]") {
  dds::MirrorScene s = a_scene();
  s.outline = dds::Polyline{{{1, 0}, {0, 1}, {-1, 0}}, false};
  s.commands = true;
  dds::ros2::MarkerArray a;
  dds::build_markers(s, a);
  a.markers()[1].colors().push_back(a.markers()[1].color());
  a.markers()[1].texture_resource("embedded://t");
  a.markers()[1].texture().data().push_back(0xAB);
  a.markers()[1].uv_coordinates().resize(1);
  a.markers()[1].mesh_file().filename("m.stl");
  a.markers()[1].mesh_use_embedded_materials(true);
  const std::vector<unsigned char> bytes =
      serialize<visualization_msgs::msg::dds_::MarkerArray_PubSubType>(a);
  visualization_msgs::msg::dds_::MarkerArray_PubSubType type;
  eprosima::fastrtps::rtps::SerializedPayload_t payload(static_cast<std::uint32_t>(bytes.size()));
  std::memcpy(payload.data, bytes.data(), bytes.size());
  payload.length = static_cast<std::uint32_t>(bytes.size());
  dds::ros2::MarkerArray read;
  REQUIRE(type.deserialize(&payload, &read));
  CHECK(read == a);
}

}  // namespace
}  // namespace shapeform
