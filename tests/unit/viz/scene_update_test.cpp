// Unit tests of common/viz/scene_update: the foxglove.SceneUpdate and PosesInFrame of a snapshot, checked
// against the schemas the channels advertise, and how fast a frame of 1000 agents is made.
#include "viz/scene_update.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <nlohmann/json.hpp>
#include <string>

namespace shapeform {
namespace {

using nlohmann::json;

/// Every key of `value` is a property of `schema`, recursively, and every number/string/bool/array
/// has the schema's type: what Foxglove's reader of a jsonschema channel relies on.
void check_against(const json& value, const json& schema, const std::string& path) {
  CAPTURE(path);
  if (schema.contains("oneOf")) {
    REQUIRE(value.is_number_integer());
    bool found = false;
    for (const auto& c : schema["oneOf"]) found = found || c["const"] == value;
    CHECK(found);
    return;
  }
  const std::string type = schema.at("type");
  if (type == "object") {
    REQUIRE(value.is_object());
    for (const auto& [k, v] : value.items()) {
      REQUIRE(schema["properties"].contains(k));
      check_against(v, schema["properties"][k], path + "." + k);
    }
    // Foxglove's messages carry every field: nothing the schema names is missing.
    for (const auto& [k, v] : schema["properties"].items()) CHECK(value.contains(k));
  } else if (type == "array") {
    REQUIRE(value.is_array());
    for (std::size_t i = 0; i < value.size(); ++i)
      check_against(value[i], schema["items"], path + "[" + std::to_string(i) + "]");
  } else if (type == "number") {
    CHECK(value.is_number());
  } else if (type == "integer") {
    CHECK(value.is_number_integer());
  } else if (type == "string") {
    CHECK(value.is_string());
  } else if (type == "boolean") {
    CHECK(value.is_boolean());
  } else {
    FAIL("unknown schema type " + type);
  }
}

viz::SceneSnapshot a_snapshot() {
  viz::SceneSnapshot s;
  s.agents.push_back({3, core::Vec2(1.0, -2.0), viz::AgentLook::Alive, 0.5});
  s.agents.push_back({4, core::Vec2(0.1, 0.2), viz::AgentLook::Stale, std::nullopt});
  s.agents.push_back({9, core::Vec2(-1.0 / 3.0, 2.5), viz::AgentLook::Dead, std::nullopt});
  s.outline = {core::Vec2(1, 0), core::Vec2(0, 1), core::Vec2(-1, 0), core::Vec2(0, -1)};
  s.outline_closed = true;
  core::KeepOutZone circle;
  circle.centre = core::Vec2(2, 2);
  circle.radius = 0.5;
  core::KeepOutZone square;
  square.kind = core::KeepOutZone::Kind::Polygon;
  square.vertices = {core::Vec2(-3, -3), core::Vec2(-2, -3), core::Vec2(-2, -2)};
  s.keep_out = {circle, square};
  s.fence = {core::Vec2(-5, -5), core::Vec2(5, -5), core::Vec2(5, 5), core::Vec2(-5, 5)};
  s.fence_margin = 0.5;
  s.centre = core::Vec2(0.25, -0.75);
  return s;
}

const json& entity(const json& update, const std::string& id) {
  for (const auto& e : update["entities"]) {
    if (e["id"] == id) return e;
  }
  FAIL("no entity " + id);
  static const json none;
  return none;
}

TEST_CASE("the scene's channels: SceneUpdate and PosesInFrame as json with their JSON Schemas", "[viz]") {
  const auto& ch = viz::scene_channels();
  REQUIRE(ch.size() == 2);
  CHECK(ch[viz::kSceneChannel].schema_name == "foxglove.SceneUpdate");
  CHECK(ch[viz::kPosesChannel].schema_name == "foxglove.PosesInFrame");
  for (const auto& c : ch) {
    CHECK(c.schema_encoding == "jsonschema");
    CHECK(c.message_encoding == "json");
    const json schema = json::parse(c.schema);
    CHECK(schema["title"] == c.schema_name);
  }
}

TEST_CASE("a SceneUpdate has every field of the schema, frame shapeform, spheres coloured by state",
          "[viz]") {
  const viz::SceneSnapshot s = a_snapshot();
  const std::uint64_t stamp = 12'345'678'901ULL;
  const json u = json::parse(viz::scene_update_json(s, stamp));
  check_against(u, json::parse(viz::scene_channels()[viz::kSceneChannel].schema), "SceneUpdate");
  REQUIRE(u["entities"].size() == std::size(viz::kEntities));
  for (const auto& e : u["entities"]) {
    CHECK(e["frame_id"] == "shapeform");
    CHECK(e["timestamp"]["sec"] == 12);
    CHECK(e["timestamp"]["nsec"] == 345'678'901);
  }
  const json& spheres = entity(u, "agents")["spheres"];
  REQUIRE(spheres.size() == 3);
  // Positions exact (shortest round-trip text), in the plane.
  CHECK(spheres[2]["pose"]["position"]["x"].get<double>() == -1.0 / 3.0);
  CHECK(spheres[0]["pose"]["position"]["y"] == -2.0);
  CHECK(spheres[0]["pose"]["position"]["z"] == 0.0);
  const auto rgba = [](const json& c) { return std::vector<double>{c["r"], c["g"], c["b"], c["a"]}; };
  const auto expect = [](viz::AgentLook l) {
    const auto c = viz::agent_colour(l);
    return std::vector<double>{c.r, c.g, c.b, c.a};
  };
  CHECK(rgba(spheres[0]["color"]) == expect(viz::AgentLook::Alive));
  CHECK(rgba(spheres[1]["color"]) == expect(viz::AgentLook::Stale));
  CHECK(rgba(spheres[2]["color"]) == expect(viz::AgentLook::Dead));
  CHECK(expect(viz::AgentLook::Alive) != expect(viz::AgentLook::Stale));
  CHECK(expect(viz::AgentLook::Stale) != expect(viz::AgentLook::Dead));
  // One arrow: only agent 3's heading is known; its orientation is the heading about z.
  const json& arrows = entity(u, "headings")["arrows"];
  REQUIRE(arrows.size() == 1);
  CHECK(arrows[0]["pose"]["position"]["x"] == 1.0);
  CHECK(arrows[0]["pose"]["orientation"]["z"].get<double>() == Approx(std::sin(0.25)));
  CHECK(arrows[0]["pose"]["orientation"]["w"].get<double>() == Approx(std::cos(0.25)));
  // The outline: one closed line through the 4 points.
  const json& outline = entity(u, "outline")["lines"];
  REQUIRE(outline.size() == 1);
  CHECK(outline[0]["type"] == 1);
  CHECK(outline[0]["points"].size() == 4);
  // Zones: a circle as a loop of points at its radius, the triangle as its 3 corners.
  const json& zones = entity(u, "keep_out")["lines"];
  REQUIRE(zones.size() == 2);
  for (const auto& p : zones[0]["points"]) {
    CHECK(std::hypot(p["x"].get<double>() - 2.0, p["y"].get<double>() - 2.0) == Approx(0.5));
  }
  CHECK(zones[1]["points"].size() == 3);
  // The fence and, with a margin, the fence shrunk by it.
  const json& fence = entity(u, "fence")["lines"];
  REQUIRE(fence.size() == 2);
  CHECK(fence[0]["points"].size() == 4);
  REQUIRE(fence[1]["points"].size() == 4);
  for (const auto& p : fence[1]["points"]) {
    CHECK(std::abs(p["x"].get<double>()) == Approx(4.5));
    CHECK(std::abs(p["y"].get<double>()) == Approx(4.5));
  }
  const json& centre = entity(u, "centre")["spheres"];
  REQUIRE(centre.size() == 1);
  CHECK(centre[0]["pose"]["position"]["x"] == 0.25);
}

TEST_CASE("an empty snapshot still sends every entity, empty, so the last frame's drawing is replaced",
          "[viz]") {
  const json u = json::parse(viz::scene_update_json(viz::SceneSnapshot{}, 0));
  check_against(u, json::parse(viz::scene_channels()[viz::kSceneChannel].schema), "SceneUpdate");
  REQUIRE(u["entities"].size() == std::size(viz::kEntities));
  CHECK(entity(u, "agents")["spheres"].empty());
  CHECK(entity(u, "outline")["lines"].empty());
  CHECK(entity(u, "centre")["spheres"].empty());
}

TEST_CASE("PosesInFrame: one pose per agent, the heading's orientation or identity", "[viz]") {
  const json p = json::parse(viz::poses_json(a_snapshot(), 1'500'000'000ULL));
  check_against(p, json::parse(viz::scene_channels()[viz::kPosesChannel].schema), "PosesInFrame");
  CHECK(p["frame_id"] == "shapeform");
  REQUIRE(p["poses"].size() == 3);
  CHECK(p["poses"][0]["orientation"]["z"].get<double>() == Approx(std::sin(0.25)));
  CHECK(p["poses"][1]["orientation"]["w"] == 1.0);
  CHECK(p["timestamp"]["sec"] == 1);
  CHECK(p["timestamp"]["nsec"] == 500'000'000);
}

// Its cost is measured by scripts/bench_foxglove.py (docs/BENCHMARKS.md), not asserted here.
TEST_CASE("a SceneUpdate of 1000 agents draws each of them once, with its heading where known", "[viz]") {
  viz::SceneSnapshot s = a_snapshot();
  s.agents.clear();
  for (int i = 0; i < 1000; ++i) {
    s.agents.push_back({i, core::Vec2(std::cos(i * 0.01) * 7.123456789, std::sin(i * 0.01) * 3.3),
                        viz::AgentLook::Alive, i % 2 ? std::optional<double>(i * 0.001) : std::nullopt});
  }
  const json out = json::parse(viz::scene_update_json(s, 7));
  const json& spheres = out["entities"][0]["spheres"];
  REQUIRE(spheres.size() == 1000);
  CHECK(spheres[999]["pose"]["position"]["x"].get<double>() == s.agents[999].x.x());
  CHECK(spheres[999]["pose"]["position"]["y"].get<double>() == s.agents[999].x.y());
  CHECK(entity(out, "headings")["arrows"].size() == 500);  // the odd ids
}

}  // namespace
}  // namespace shapeform
