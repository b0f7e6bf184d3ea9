#include "dds/topics.hpp"

#include <stdexcept>
#include <string>

namespace shapeform::dds {

static_assert(kTopicTable.size() == kAllTopics.size());

const TopicInfo& topic_info(TopicId id) {
  const auto k = static_cast<std::size_t>(id);
  if (k >= kTopicTable.size()) throw std::logic_error("dds: unknown TopicId " + std::to_string(k));
  return kTopicTable[k];
}

std::int16_t static_edp_user_id(TopicId id, bool writer) {
  const auto k = static_cast<std::size_t>(&topic_info(id) - kTopicTable.data());  // the row's index
  return static_cast<std::int16_t>(2 * k + (writer ? 1 : 2));
}

const char* topic_name(TopicId id) { return topic_info(id).name; }
const char* type_name(TopicId id) { return topic_info(id).type; }
bool is_keyed(TopicId id) { return topic_info(id).key[0] != '\0'; }

std::string message_name(TopicId id) {
  std::string t = type_name(id);
  constexpr std::string_view own = "shapeform::msg::";
  if (t.compare(0, own.size(), own) == 0) return t.substr(own.size());
  // PKG::msg::dds_::X_ -> PKG/msg/X
  const auto replace = [&t](std::string_view from, std::string_view to) {
    for (auto at = t.find(from); at != std::string::npos; at = t.find(from, at + to.size())) t.replace(at, from.size(), to);
  };
  replace("::dds_::", "/");
  replace("::", "/");
  if (!t.empty() && t.back() == '_') t.pop_back();
  return t;
}

bool is_vehicle_topic(TopicId id) { return std::string_view(topic_name(id)).find("{ns}") != std::string_view::npos; }

std::string vehicle_topic_name(const std::string& ns, const std::string& topic) {
  if (!topic.empty() && topic.front() == '/') return "rt" + topic;
  return "rt/" + ns + "/" + topic;
}

std::optional<TopicId> find_topic(std::string_view name) {
  for (const TopicInfo& t : kTopicTable)
    if (name == t.name) return t.id;
  // A vehicle's topic: the first row whose pattern matches, {ns} standing for one or more characters.
  for (const TopicInfo& t : kTopicTable) {
    const std::string_view pattern = t.name;
    const auto at = pattern.find("{ns}");
    if (at == std::string_view::npos) continue;
    const std::string_view head = pattern.substr(0, at), tail = pattern.substr(at + 4);
    if (name.size() > head.size() + tail.size() && name.substr(0, head.size()) == head &&
        name.substr(name.size() - tail.size()) == tail)
      return t.id;
  }
  return std::nullopt;
}

}  // namespace shapeform::dds
