#include <catch2/catch.hpp>
#include <string>

#include "app/json.hpp"
#include "config/config.hpp"
#include "core/command_table.hpp"

using namespace shapeform;

namespace {
/// The JSON value at a dotted config key ("agent.rate_hz").
const nlohmann::json& at_key(const nlohmann::json& j, const std::string& key) {
  std::string pointer = "/" + key;
  for (char& ch : pointer)
    if (ch == '.') ch = '/';
  return j.at(nlohmann::json::json_pointer(pointer));
}
}  // namespace

TEST_CASE("config JSON carries every key of the config table, nested by section", "[app][json]") {
  const config::Config c = config::load("", {"agent.rate_hz=40", "transport.lease_s=3", "shape.kind=square",
                                             "shape.rotation_deg=30", "dynamics.law=arc", "shape.centre=[1, -2]"});
  const nlohmann::json j = app::config_json(c);
  for (const auto& p : config::config_table()) {
    INFO(p.key);
    CHECK_NOTHROW(at_key(j, p.key));
  }
  CHECK(j["agent"]["rate_hz"] == 40.0);
  CHECK(j["transport"]["lease_s"] == 3.0);
  CHECK(j["transport"]["profile"] == "loopback");
  CHECK(j["shape"]["kind"] == "square");  // choices by name
  CHECK(j["dynamics"]["law"] == "arc");
  CHECK(j["shape"]["rotation_deg"].get<double>() == Approx(30.0));  // degrees, as the file spells it
  CHECK(j["shape"]["centre"] == nlohmann::json({1.0, -2.0}));
  CHECK(j["schema_version"] == config::kSchemaVersion);
}

TEST_CASE("config JSON follows the config, not the defaults", "[app][json]") {
  const nlohmann::json a = app::config_json(config::load("", {}));
  const nlohmann::json b = app::config_json(config::load("", {"swarm.agents=7"}));
  CHECK(a["swarm"]["agents"] == config::Config{}.swarm.agents);
  CHECK(b["swarm"]["agents"] == 7);
  CHECK(a != b);
}

TEST_CASE("command JSON: every key of the command table, as the config nests it", "[app][json]") {
  const config::Config c = config::load("", {"shape.kind=ellipse", "shape.rotation_deg=45", "dynamics.hold=true",
                                             "tracking.enabled=true", "integration.dt=0.5"});
  const nlohmann::json j = app::command_json(c.command);
  for (const auto& p : core::params::command_table()) {
    INFO(p.key);
    CHECK_NOTHROW(at_key(j, p.key));
  }
  CHECK(j["shape"]["kind"] == "ellipse");
  CHECK(j["shape"]["rotation_deg"].get<double>() == Approx(45.0));
  CHECK(j["dynamics"]["hold"] == true);
  CHECK(j["tracking"]["enabled"] == true);
  CHECK(j["integration"]["dt"] == 0.5);
  // The command part of the config's JSON, exactly.
  const nlohmann::json whole = app::config_json(c);
  for (const auto& [section, value] : j.items()) CHECK(whole[section] == value);
}
