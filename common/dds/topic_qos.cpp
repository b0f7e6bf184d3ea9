#include "dds/topic_qos.hpp"

#include "dds/locators.hpp"

namespace shapeform::dds {
namespace {

namespace fdds = eprosima::fastdds::dds;

fdds::ReliabilityQosPolicyKind reliability(const TopicInfo& t) {
  return t.reliability == Reliability::Reliable ? fdds::RELIABLE_RELIABILITY_QOS
                                                : fdds::BEST_EFFORT_RELIABILITY_QOS;
}

fdds::DurabilityQosPolicyKind durability(const TopicInfo& t) {
  return t.durability == Durability::TransientLocal ? fdds::TRANSIENT_LOCAL_DURABILITY_QOS
                                                    : fdds::VOLATILE_DURABILITY_QOS;
}

/// KEEP_LAST 1; keyed topics: one slot per instance, any number of instances.
void set_history(TopicId id, fdds::HistoryQosPolicy& history, fdds::ResourceLimitsQosPolicy& limits) {
  history.kind = fdds::KEEP_LAST_HISTORY_QOS;
  history.depth = 1;
  if (is_keyed(id)) {
    limits.max_instances = 0;  // 0 = unlimited
    limits.max_samples = 0;    // unlimited, consistent with max_instances * max_samples_per_instance
    limits.max_samples_per_instance = 1;
  }
}

}  // namespace

fdds::DataWriterQos writer_qos(TopicId id) {
  const TopicInfo& t = topic_info(id);
  fdds::DataWriterQos q;  // constructed, not DATAWRITER_QOS_DEFAULT (XML profiles could change that)
  q.reliability().kind = reliability(t);
  q.durability().kind = durability(t);
  set_history(id, q.history(), q.resource_limits());
  if (t.reliability == Reliability::Reliable) {
    q.reliable_writer_qos().times.heartbeatPeriod = eprosima::fastrtps::Duration_t(kHeartbeatPeriod_s);
  }
  q.data_sharing().off();  // AUTO by default in 2.9: would use shared memory for bounded unkeyed types
  if (!is_vehicle_topic(id)) q.endpoint().user_defined_id = static_edp_user_id(id, true);
  return q;
}

fdds::DataReaderQos reader_qos(TopicId id) {
  const TopicInfo& t = topic_info(id);
  fdds::DataReaderQos q;
  q.reliability().kind = reliability(t);
  q.durability().kind = durability(t);
  set_history(id, q.history(), q.resource_limits());
  q.data_sharing().off();
  if (!is_vehicle_topic(id)) q.endpoint().user_defined_id = static_edp_user_id(id, false);
  return q;
}

fdds::DataReaderQos reader_qos(TopicId id, const TransportConfig& transport) {
  fdds::DataReaderQos q = reader_qos(id);
  if (transport.multicast_data && topic_info(id).multicast) {
    // Only the high-rate all-to-all topics: low-rate reliable topics stay unicast, so their heartbeats
    // and acknowledgements do not reach every process.
    q.endpoint().multicast_locator_list.push_back(data_multicast_locator(transport));
  }
  return q;
}

}  // namespace shapeform::dds
