#pragma once
/// The ONE topic table of the project: topic names, their types and their QoS. Writers and readers are
/// only ever created with writer_qos() / reader_qos() so both sides always match.
#include <array>
#include <cstdint>
#include <optional>
#include <string_view>

#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>

#include "protocol/transport.hpp"

namespace shapeform::dds {

enum class TopicId { State, StateBatch, Command, Target, Metrics, Status };

inline constexpr std::array<TopicId, 6> kAllTopics = {TopicId::State,   TopicId::StateBatch, TopicId::Command,
                                                      TopicId::Target,  TopicId::Metrics,    TopicId::Status};

/// DDS topic name: "shapeform/state", "shapeform/state_batch", "shapeform/command", "shapeform/target",
/// "shapeform/metrics", "shapeform/status".
const char* topic_name(TopicId id);

/// The topic named `name` ("shapeform/state"), or nullopt.
std::optional<TopicId> find_topic(std::string_view name);

/// Registered type name of the topic's message, e.g. "shapeform::msg::AgentState".
const char* type_name(TopicId id);

/// True for keyed topics: State and Status (one instance per agent, @key id), StateBatch (one per
/// process, @key first_id).
bool is_keyed(TopicId id);

/// The endpoint's user id of static endpoint discovery (transport.static_edp), from the topic's row in
/// the table: writer 2 k + 1, reader 2 k + 2 for row k. Unique over topics and directions, as Fast DDS
/// 2.9 wants them in one description (it looks a peer's endpoint up by this id alone).
std::int16_t static_edp_user_id(TopicId id, bool writer);

/// Writer QoS of a topic (data sharing always off; KEEP_LAST 1 everywhere; endpoint user id
/// static_edp_user_id(id, true), which only static endpoint discovery reads):
///  - State:   BEST_EFFORT, VOLATILE        (every agent tick)
///  - StateBatch: BEST_EFFORT, VOLATILE     (every tick of a process hosting several agents)
///  - Command: RELIABLE, TRANSIENT_LOCAL    (late joiners get the newest command)
///  - Target:  BEST_EFFORT, VOLATILE
///  - Metrics: RELIABLE, VOLATILE
///  - Status:  RELIABLE, VOLATILE
/// Keyed topics allow unlimited instances (max_instances = max_samples = 0, 1 sample per instance).
/// Reliable writers send a heartbeat every kHeartbeatPeriod_s so a lost sample is repaired quickly.
eprosima::fastdds::dds::DataWriterQos writer_qos(TopicId id);

/// Reader QoS of a topic: the same reliability, durability and history as the writer, user id
/// static_edp_user_id(id, false). Keyed readers
/// lift max_instances (Fast DDS default 10 would silently hide agents 11 and up).
eprosima::fastdds::dds::DataReaderQos reader_qos(TopicId id);

/// reader_qos(id), plus, when transport.multicast_data is set and id is State or StateBatch, the State
/// multicast locator (data_multicast_locator) as the reader's only locator.
eprosima::fastdds::dds::DataReaderQos reader_qos(TopicId id, const TransportConfig& transport);

/// Heartbeat period of reliable writers, seconds (Fast DDS default 3 s).
inline constexpr double kHeartbeatPeriod_s = 0.5;

}  // namespace shapeform::dds
