#include "topic_doc.hpp"

#include <algorithm>
#include <stdexcept>
#include <vector>

#include "dds/topics.hpp"
#include "util/text.hpp"

namespace shapeform::tools {
namespace {

std::string code(const std::string& s) { return "`" + s + "`"; }

std::string qos(const dds::TopicInfo& t) {
  return std::string(t.reliability == dds::Reliability::Reliable ? "reliable" : "best effort") + ", " +
         (t.durability == dds::Durability::TransientLocal ? "transient-local" : "volatile");
}

/// The topic's name as DDS Security's permissions match it: a vehicle's pattern with {ns} as `*`.
std::string permission_name(const dds::TopicInfo& t) {
  std::string name = t.name;
  if (const auto at = name.find("{ns}"); at != std::string::npos) name.replace(at, 4, "*");
  return name;
}

/// The names of the topics whose role bits (`publishers` or `readers`) hold `role`, in table order,
/// each through `item`, joined by `separator`.
template <class Item>
std::string topics_of(unsigned role, unsigned dds::TopicInfo::*bits, Item item, const char* separator = "") {
  std::string out;
  std::vector<std::string> seen;  // rows that share a name (cmd_vel's two types) are one topic here
  for (const dds::TopicInfo& t : dds::kTopicTable) {
    if ((t.*bits & role) == 0) continue;
    const std::string name = permission_name(t);
    if (std::find(seen.begin(), seen.end(), name) != seen.end()) continue;
    seen.push_back(name);
    out += (out.empty() ? "" : separator) + item(name);
  }
  return out;
}

/// A cell of the access table: the topics a role may publish (or read), "nothing" or "every topic".
std::string access_cell(unsigned role, unsigned dds::TopicInfo::*bits) {
  std::size_t n = 0;
  for (const dds::TopicInfo& t : dds::kTopicTable) n += (t.*bits & role) != 0 ? 1 : 0;
  if (n == 0) return "nothing";
  if (n == dds::kTopicTable.size()) return "every topic";
  return topics_of(role, bits, code, ", ");
}

/// One `echo '<KIND><topics>...</topics></KIND>'` line of rules(), or nothing without a topic.
std::string rule_line(unsigned role, unsigned dds::TopicInfo::*bits, const char* kind) {
  const std::string topics =
      topics_of(role, bits, [](const std::string& name) { return "<topic>" + name + "</topic>"; });
  if (topics.empty()) return "";
  return std::string("      echo '<") + kind + "><topics>" + topics + "</topics></" + kind + ">'\n";
}

}  // namespace

std::string topics_markdown() {
  std::string out = "| topic | type | QoS | publisher | rate |\n|---|---|---|---|---|\n";
  for (const dds::TopicInfo& t : dds::kTopicTable) {
    const std::string key = t.key[0] != '\0' ? " (key " + code(t.key) + ")" : "";
    out += "| " + code(t.name) + " | " + code(dds::message_name(t.id)) + key + " | " + qos(t) + " | " + t.publisher_doc +
           " | " + t.rate_doc + " |\n";
  }
  return out;
}

std::string access_markdown() {
  std::string out = "| role | publishes | subscribes to |\n|---|---|---|\n";
  for (const dds::RoleInfo& r : dds::kRoles) {
    out += "| " + code(r.enclave) + " | " + access_cell(r.bit, &dds::TopicInfo::publishers) + " | " +
           access_cell(r.bit, &dds::TopicInfo::readers) + " |\n";
  }
  return out;
}

std::string keystore_rules() {
  std::string out = "rules() { # NAME -> the allow rules of its role\n  case \"$1\" in\n";
  for (const dds::RoleInfo& r : dds::kRoles) {
    out += std::string("    ") + r.enclave_glob + ")\n" +
           rule_line(r.bit, &dds::TopicInfo::publishers, "publish") +
           rule_line(r.bit, &dds::TopicInfo::readers, "subscribe") + "      ;;\n";
  }
  return out + "  esac\n}\n";
}

std::string regenerate_topic_doc(const std::string& text) {
  return util::regenerate_blocks(text, "BEGIN GENERATED topics: ", "END GENERATED",
                                 [](const std::string& section) {
                                   if (section == "table") return topics_markdown();
                                   if (section == "access") return access_markdown();
                                   if (section == "permissions") return keystore_rules();
                                   throw std::invalid_argument("unknown section '" + section +
                                                               "' (expected table, access or permissions)");
                                 });
}

}  // namespace shapeform::tools
