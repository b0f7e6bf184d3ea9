#pragma once
/// The Fast DDS QoS of each topic, built from the topic table (dds/topics.hpp). For the dds library (its
/// Node, the participant factory's static description), the benchmark's raw Fast DDS baseline and the
/// tests; processes never see it. Writers and readers are only ever created with writer_qos() /
/// reader_qos(), so both sides always match.
#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>

#include "dds/topics.hpp"
#include "protocol/transport.hpp"

namespace shapeform::dds {

/// Writer QoS of a topic (data sharing always off; KEEP_LAST 1 everywhere; endpoint user id
/// static_edp_user_id(id, true), which only static endpoint discovery reads), reliability and
/// durability from its row:
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

/// reader_qos(id), plus, when transport.multicast_data is set and the topic's row says multicast (State,
/// StateBatch), the State multicast locator (data_multicast_locator) as the reader's only locator.
eprosima::fastdds::dds::DataReaderQos reader_qos(TopicId id, const TransportConfig& transport);

/// Heartbeat period of reliable writers, seconds (Fast DDS default 3 s).
inline constexpr double kHeartbeatPeriod_s = 0.5;

}  // namespace shapeform::dds
