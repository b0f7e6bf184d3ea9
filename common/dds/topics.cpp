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

std::optional<TopicId> find_topic(std::string_view name) {
  for (const TopicInfo& t : kTopicTable)
    if (name == t.name) return t.id;
  return std::nullopt;
}

}  // namespace shapeform::dds
