// Unit tests of the Foxglove server's pure pieces (view/foxglove_protocol) and of the scene's snapshot
// for it (view/foxglove_scene).
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>

#include "core/command.hpp"
#include "core/compiled_command.hpp"
#include "foxglove_protocol.hpp"
#include "foxglove_scene.hpp"

namespace shapeform {
namespace {

using nlohmann::json;
namespace fg = view::foxglove;

std::vector<fg::AdvertisedChannel> two_channels() {
  std::vector<fg::AdvertisedChannel> out;
  for (std::size_t i = 0; i < viz::scene_channels().size(); ++i)
    out.push_back({static_cast<std::uint32_t>(i + 1), viz::scene_channels()[i]});
  return out;
}

TEST_CASE("the subprotocol: the client's first Foxglove one, none when it asks for neither",
          "[view][foxglove]") {
  CHECK(fg::choose_subprotocol({"foxglove.sdk.v1"}) == "foxglove.sdk.v1");
  CHECK(fg::choose_subprotocol({"foxglove.websocket.v1"}) == "foxglove.websocket.v1");
  CHECK(fg::choose_subprotocol({"x", "foxglove.websocket.v1", "foxglove.sdk.v1"}) == "foxglove.websocket.v1");
  CHECK_FALSE(fg::choose_subprotocol({}));
  CHECK_FALSE(fg::choose_subprotocol({"foxglove.websocket.v2", "chat"}));
}

TEST_CASE("message data: opcode 1, subscription id and timestamp little endian, then the payload",
          "[view][foxglove]") {
  const std::string f = fg::message_data(0x04030201u, 0x0C0B0A0908070605ull, "{}");
  REQUIRE(f.size() == fg::kMessageDataHeader + 2);
  const unsigned char want[] = {0x01, 0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07,
                                0x08, 0x09, 0x0A, 0x0B, 0x0C, '{',  '}'};
  CHECK(std::memcmp(f.data(), want, sizeof want) == 0);
}

TEST_CASE("serverInfo is read-only and advertise carries each channel's schema and encodings",
          "[view][foxglove]") {
  const json info = json::parse(fg::server_info_json("shapeform_view", "s1"));
  CHECK(info["op"] == "serverInfo");
  CHECK(info["capabilities"].empty());  // no clientPublish, parameters, services
  CHECK(info["sessionId"] == "s1");
  const json ad = json::parse(fg::advertise_json(two_channels()));
  CHECK(ad["op"] == "advertise");
  REQUIRE(ad["channels"].size() == 2);
  CHECK(ad["channels"][0]["id"] == 1);
  CHECK(ad["channels"][0]["topic"] == "shapeform/scene");
  CHECK(ad["channels"][0]["encoding"] == "json");
  CHECK(ad["channels"][0]["schemaName"] == "foxglove.SceneUpdate");
  CHECK(ad["channels"][0]["schemaEncoding"] == "jsonschema");
  CHECK(ad["channels"][0]["schema"] == std::string(viz::scene_channels()[0].schema));
  const json st = json::parse(fg::status_json(fg::StatusLevel::Error, "no"));
  CHECK(st == json{{"op", "status"}, {"level", 2}, {"message", "no"}});
}

TEST_CASE("client ops: subscribe and unsubscribe parsed, others unsupported, bad ones invalid with a reason",
          "[view][foxglove]") {
  auto op = fg::parse_client_op(
      R"({"op":"subscribe","subscriptions":[{"id":7,"channelId":1},{"id":8,"channelId":2}]})");
  REQUIRE(op.kind == fg::ClientOp::Kind::Subscribe);
  CHECK(op.subscribe == std::vector<std::pair<std::uint32_t, std::uint32_t>>{{7, 1}, {8, 2}});
  op = fg::parse_client_op(R"({"op":"unsubscribe","subscriptionIds":[7]})");
  REQUIRE(op.kind == fg::ClientOp::Kind::Unsubscribe);
  CHECK(op.unsubscribe == std::vector<std::uint32_t>{7});
  op = fg::parse_client_op(R"({"op":"advertise","channels":[]})");
  CHECK(op.kind == fg::ClientOp::Kind::Unsupported);
  CHECK(op.op == "advertise");
  for (const char* bad :
       {"not json", "[1]", R"({"x":1})", R"({"op":"subscribe"})",
        R"({"op":"subscribe","subscriptions":[{"id":-1,"channelId":1}]})",
        R"({"op":"subscribe","subscriptions":[{"id":1}]})", R"({"op":"unsubscribe","subscriptionIds":["a"]})",
        R"({"op":"subscribe","subscriptions":[{"id":4294967296,"channelId":1}]})"}) {
    CAPTURE(bad);
    op = fg::parse_client_op(bad);
    CHECK(op.kind == fg::ClientOp::Kind::Invalid);
    CHECK_FALSE(op.error.empty());
  }
}

TEST_CASE("subscriptions: per channel, unknown channels and reused ids refused, unsubscribe forgets",
          "[view][foxglove]") {
  fg::Subscriptions s;
  const auto channels = two_channels();
  CHECK(s.subscribe({{1, 1}, {2, 1}, {3, 2}}, channels).empty());
  CHECK(s.of_channel(1) == std::vector<std::uint32_t>{1, 2});  // one channel twice: both subscriptions get it
  CHECK(s.count(2) == 1);
  auto problems = s.subscribe({{4, 99}, {1, 2}}, channels);
  REQUIRE(problems.size() == 2);
  CHECK_THAT(problems[0], Catch::Matchers::Contains("channel 99 is not advertised"));
  CHECK_THAT(problems[1], Catch::Matchers::Contains("subscription 1"));
  CHECK(s.size() == 3);
  CHECK(s.unsubscribe({1, 3}).empty());
  CHECK(s.of_channel(1) == std::vector<std::uint32_t>{2});
  CHECK(s.count(2) == 0);
  problems = s.unsubscribe({42});
  REQUIRE(problems.size() == 1);
  CHECK_THAT(problems[0], Catch::Matchers::Contains("42"));
}

TEST_CASE("the Foxglove snapshot of a scene: looks by age, headings only when fresh, the command's drawing",
          "[view][foxglove]") {
  view::SceneParams p;
  p.stale_s = 0.3;
  p.dead_s = 1.0;
  view::Scene scene(p);
  scene.on_state(1, core::Vec2(1, 2), 5.0, 1, 10.0);
  scene.on_state(2, core::Vec2(3, 4), 5.0, 1, 9.5);
  scene.on_state(3, core::Vec2(5, 6), 5.0, 1, 8.0);
  scene.on_heading(1, 0.5, 10.0);
  scene.on_heading(2, 1.5, 8.5);  // older than dead_s at 10: not drawn
  core::Command cmd;
  core::KeepOutZone z;
  z.centre = core::Vec2(9, 9);
  z.radius = 1.0;
  cmd.keep_out = {z};
  cmd.fence = {core::Vec2(-20, -20), core::Vec2(20, -20), core::Vec2(20, 20), core::Vec2(-20, 20)};
  cmd.fence_margin = 1.0;
  scene.on_command(core::compile(cmd), 1);
  scene.on_centre(core::Vec2(0.5, 0.25));
  const viz::SceneSnapshot s = view::foxglove_snapshot(scene, 10.0);
  REQUIRE(s.agents.size() == 3);
  CHECK(s.agents[0].look == viz::AgentLook::Alive);
  CHECK(s.agents[1].look == viz::AgentLook::Stale);
  CHECK(s.agents[2].look == viz::AgentLook::Dead);
  CHECK(s.agents[0].heading == 0.5);
  CHECK_FALSE(s.agents[1].heading);
  CHECK(s.agents[2].x == core::Vec2(5, 6));
  CHECK(s.outline.size() == static_cast<std::size_t>(p.outline_points));  // the default circle, closed
  CHECK(s.outline_closed);
  CHECK(s.keep_out == cmd.keep_out);
  CHECK(s.fence == cmd.fence);
  CHECK(s.fence_margin == 1.0);
  REQUIRE(s.centre);
  CHECK(*s.centre == core::Vec2(0.5, 0.25));
}

}  // namespace
}  // namespace shapeform
