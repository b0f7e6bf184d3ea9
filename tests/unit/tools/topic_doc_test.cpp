// The topic table against the IDL files, and what is generated from it into the docs and the keystore.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>

#include "dds/topics.hpp"
#include "topic_doc.hpp"

namespace shapeform {
namespace {

/// The text of an IDL file without its // comments.
std::string idl_code(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::ostringstream code;
  for (std::string line; std::getline(in, line);) code << line.substr(0, line.find("//")) << "\n";
  return code.str();
}

/// Each struct of an IDL file, and whether it is annotated @final.
std::map<std::string, bool> idl_structs(const std::filesystem::path& path) {
  static const std::regex kStruct(R"((@final\s+)?struct\s+(\w+))");
  std::map<std::string, bool> out;
  const std::string code = idl_code(path);
  for (std::sregex_iterator it(code.begin(), code.end(), kStruct), end; it != end; ++it)
    out[(*it)[2].str()] = (*it)[1].matched;
  return out;
}

}  // namespace

TEST_CASE("every IDL type has a row of the topic table and every row an IDL type", "[tools][topics]") {
  std::set<std::string> files, rows;
  for (const auto& entry : std::filesystem::directory_iterator(std::string(SHAPEFORM_SOURCE_DIR) + "/idl")) {
    if (entry.path().extension() != ".idl") continue;
    const std::string name = entry.path().stem().string();
    files.insert(name);
    const auto structs = idl_structs(entry.path());
    INFO("idl/" << name << ".idl declares the struct " << name << ", the type of one topic");
    CHECK(structs.count(name) == 1);
    for (const auto& [type, final_] : structs) {
      INFO("idl/" << name << ".idl: struct " << type << " is @final (the wire contract: XCDR1)");
      CHECK(final_);
    }
  }
  std::size_t own_rows = 0;
  for (const dds::TopicInfo& t : dds::kTopicTable) {
    if (std::string(t.name).rfind("rt/", 0) == 0) continue;  // ROS 2's topics: idl/ros2 (below)
    rows.insert(dds::message_name(t.id));
    ++own_rows;
  }
  CHECK(files == rows);  // a file without a row, or a row without a file (idl/Type.idl)
  CHECK(rows.size() == own_rows);  // one row per type
}

TEST_CASE("ROS 2's rows (a vehicle's, the mirror's) are ROS 2 types, each from its IDL file under idl/ros2",
          "[tools][topics]") {
  int vehicle_rows = 0, ros2_rows = 0;
  for (const dds::TopicInfo& t : dds::kTopicTable) {
    if (std::string(t.name).rfind("rt/", 0) != 0) continue;  // ROS 2's prefix
    ++ros2_rows;
    const std::string message = dds::message_name(t.id);  // geometry_msgs/msg/Twist
    INFO(t.type << " from idl/ros2/" << message << ".idl");
    if (dds::is_vehicle_topic(t.id)) {
      ++vehicle_rows;
      CHECK(std::string(t.name).rfind("rt/{ns}/", 0) == 0);  // the vehicle's namespace
    } else {
      CHECK(std::string(t.name).rfind("rt/shapeform/", 0) == 0);  // the mirror's (docs/ROS2.md)
    }
    const auto structs = idl_structs(std::string(SHAPEFORM_SOURCE_DIR) + "/idl/ros2/" + message + ".idl");
    const std::string name = message.substr(message.rfind('/') + 1) + "_";  // Twist_
    REQUIRE(structs.count(name) == 1);
    CHECK(structs.at(name));
    // The registered name is ROS 2's: PKG::msg::dds_::X_.
    CHECK(std::string(t.type) ==
          message.substr(0, message.find('/')) + "::msg::dds_::" + name);
    CHECK(!dds::is_keyed(t.id));  // ROS 2's topics have no key
  }
  CHECK(vehicle_rows == 4);
  CHECK(ros2_rows == 6);
  CHECK(dds::vehicle_topic_name("robot_3", "cmd_vel") == "rt/robot_3/cmd_vel");
  CHECK(dds::vehicle_topic_name("robot_3", "/mocap/pose") == "rt/mocap/pose");
  CHECK(dds::find_topic("rt/robot_3/odom") == dds::TopicId::Odom);
  CHECK(dds::find_topic("rt/robot_3/cmd_vel") == dds::TopicId::CmdVel);
  CHECK(dds::find_topic("rt//odom") == std::nullopt);
}

TEST_CASE("the topic table: ids in row order, names unique, types named after their IDL struct",
          "[tools][topics]") {
  std::set<std::string> names;
  for (std::size_t k = 0; k < dds::kTopicTable.size(); ++k) {
    const dds::TopicInfo& t = dds::kTopicTable[k];
    CHECK(static_cast<std::size_t>(t.id) == k);
    CHECK(dds::kAllTopics[k] == t.id);
    CHECK(names.insert(std::string(t.name) + " " + t.type).second);
    if (!dds::is_vehicle_topic(t.id)) CHECK(dds::find_topic(t.name) == t.id);
    if (std::string(t.name).rfind("rt/", 0) != 0)  // ROS 2's rows: the test above
      CHECK(std::string(t.type) == "shapeform::msg::" + dds::message_name(t.id));
    CHECK(t.publishers != 0);                      // somebody may publish it...
    CHECK((t.readers & dds::role::kViewer) != 0);  // ...and the read-only monitors may read it
  }
}

TEST_CASE("the generated tables and rules follow the rows", "[tools][topics]") {
  const std::string readme = tools::topics_markdown();
  CHECK(readme.find("| `shapeform/state` | `AgentState` (key `id`) | best effort, volatile | ") !=
        std::string::npos);
  CHECK(readme.find("| `shapeform/command` | `ShapeCommand` | reliable, transient-local | ") !=
        std::string::npos);
  const std::string access = tools::access_markdown();
  CHECK(access.find("| `viewer` | nothing | every topic |") != std::string::npos);
  CHECK(access.find("| `supervisor` | `shapeform/command`, `shapeform/target`, `shapeform/metrics`, "
                    "`rt/shapeform/agents`, `rt/shapeform/markers` | ") != std::string::npos);
  const std::string rules = tools::keystore_rules();
  CHECK(rules.rfind("rules() {", 0) == 0);
  CHECK(rules.find("    viewer)\n      echo '<subscribe><topics><topic>shapeform/state</topic>") !=
        std::string::npos);
  CHECK(rules.find("<publish><topics><topic>shapeform/state</topic><topic>shapeform/state_batch</topic>"
                   "<topic>shapeform/status</topic><topic>rt/*/cmd_vel</topic><topic>shapeform/status_batch</topic>"
                   "</topics></publish>") != std::string::npos);
  // A vehicle's topics: its namespace as a wildcard; a vehicle publishes its pose and reads its commands.
  CHECK(rules.find("    vehicle)\n      echo '<publish><topics><topic>rt/*/odom</topic><topic>rt/*/pose</topic>"
                   "</topics></publish>'\n      echo '<subscribe><topics><topic>rt/*/cmd_vel</topic></topics>") !=
        std::string::npos);
  const std::string doc = "x\n<!-- BEGIN GENERATED topics: access -->\nold\n<!-- END GENERATED -->\n";
  CHECK(tools::regenerate_topic_doc(doc) ==
        "x\n<!-- BEGIN GENERATED topics: access -->\n" + access + "<!-- END GENERATED -->\n");
  CHECK_THROWS_AS(tools::regenerate_topic_doc("# BEGIN GENERATED topics: nope\n# END GENERATED\n"),
                  std::invalid_argument);
}

}  // namespace shapeform
