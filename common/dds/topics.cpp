#include "dds/topics.hpp"

#include <stdexcept>

#include "dds/locators.hpp"

namespace shapeform::dds {
namespace {

namespace fdds = eprosima::fastdds::dds;

struct TopicRow {
  TopicId id;
  const char* name;
  const char* type;
  bool keyed;
  fdds::ReliabilityQosPolicyKind reliability;
  fdds::DurabilityQosPolicyKind durability;
};

// clang-format off
constexpr TopicRow kTable[] = {
  {TopicId::State,   "shapeform/state",   "shapeform::msg::AgentState",     true,
   fdds::BEST_EFFORT_RELIABILITY_QOS, fdds::VOLATILE_DURABILITY_QOS},
  {TopicId::StateBatch, "shapeform/state_batch", "shapeform::msg::AgentStateBatch", true,
   fdds::BEST_EFFORT_RELIABILITY_QOS, fdds::VOLATILE_DURABILITY_QOS},
  {TopicId::Command, "shapeform/command", "shapeform::msg::ShapeCommand",   false,
   fdds::RELIABLE_RELIABILITY_QOS,    fdds::TRANSIENT_LOCAL_DURABILITY_QOS},
  {TopicId::Target,  "shapeform/target",  "shapeform::msg::TrackingTarget", false,
   fdds::BEST_EFFORT_RELIABILITY_QOS, fdds::VOLATILE_DURABILITY_QOS},
  {TopicId::Metrics, "shapeform/metrics", "shapeform::msg::SwarmMetrics",   false,
   fdds::RELIABLE_RELIABILITY_QOS,    fdds::VOLATILE_DURABILITY_QOS},
  {TopicId::Status,  "shapeform/status",  "shapeform::msg::AgentStatus",    true,
   fdds::RELIABLE_RELIABILITY_QOS,    fdds::VOLATILE_DURABILITY_QOS},
};
// clang-format on

const TopicRow& row(TopicId id) {
  for (const TopicRow& r : kTable) {
    if (r.id == id) return r;
  }
  throw std::logic_error("dds: unknown TopicId " + std::to_string(static_cast<int>(id)));
}

/// KEEP_LAST 1; keyed topics: one slot per instance, any number of instances.
void set_history(const TopicRow& r, fdds::HistoryQosPolicy& history,
                 fdds::ResourceLimitsQosPolicy& limits) {
  history.kind = fdds::KEEP_LAST_HISTORY_QOS;
  history.depth = 1;
  if (r.keyed) {
    limits.max_instances = 0;  // 0 = unlimited
    limits.max_samples = 0;    // unlimited, consistent with max_instances * max_samples_per_instance
    limits.max_samples_per_instance = 1;
  }
}

}  // namespace

std::int16_t static_edp_user_id(TopicId id, bool writer) {
  const auto k = static_cast<std::size_t>(&row(id) - kTable);  // the row's index in the table
  return static_cast<std::int16_t>(2 * k + (writer ? 1 : 2));
}

const char* topic_name(TopicId id) { return row(id).name; }
const char* type_name(TopicId id) { return row(id).type; }

std::optional<TopicId> find_topic(std::string_view name) {
  for (const TopicRow& r : kTable)
    if (name == r.name) return r.id;
  return std::nullopt;
}
bool is_keyed(TopicId id) { return row(id).keyed; }

fdds::DataWriterQos writer_qos(TopicId id) {
  const TopicRow& r = row(id);
  fdds::DataWriterQos q;  // constructed, not DATAWRITER_QOS_DEFAULT (XML profiles could change that)
  q.reliability().kind = r.reliability;
  q.durability().kind = r.durability;
  set_history(r, q.history(), q.resource_limits());
  if (r.reliability == fdds::RELIABLE_RELIABILITY_QOS) {
    q.reliable_writer_qos().times.heartbeatPeriod = eprosima::fastrtps::Duration_t(kHeartbeatPeriod_s);
  }
  q.data_sharing().off();  // AUTO by default in 2.9: would use shared memory for bounded unkeyed types
  q.endpoint().user_defined_id = static_edp_user_id(id, true);
  return q;
}

fdds::DataReaderQos reader_qos(TopicId id) {
  const TopicRow& r = row(id);
  fdds::DataReaderQos q;
  q.reliability().kind = r.reliability;
  q.durability().kind = r.durability;
  set_history(r, q.history(), q.resource_limits());
  q.data_sharing().off();
  q.endpoint().user_defined_id = static_edp_user_id(id, false);
  return q;
}

fdds::DataReaderQos reader_qos(TopicId id, const TransportConfig& transport) {
  fdds::DataReaderQos q = reader_qos(id);
  if (transport.multicast_data && (id == TopicId::State || id == TopicId::StateBatch)) {
    // Only the high-rate all-to-all topics: low-rate reliable topics stay unicast, so their heartbeats
    // and acknowledgements do not reach every process.
    q.endpoint().multicast_locator_list.push_back(data_multicast_locator(transport));
  }
  return q;
}

}  // namespace shapeform::dds
