#pragma once
/// The topic table as the program reads it: names, types, keys, QoS kinds and access of the project's
/// topics, all from their one declaration (dds/topic_table.hpp). No Fast DDS here: the QoS built from
/// the table is the dds library's own (dds/topic_qos.hpp), so both sides of a topic always match.
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "dds/topic_table.hpp"

namespace shapeform::dds {

/// The roles of DDS Security, as bits (a row of the table names several): every enclave that
/// scripts/make_keystore.sh makes is of one role, and its permissions are the role's.
namespace role {
inline constexpr unsigned kAgent = 1u << 0;       ///< agent processes: enclaves agent_0, agent_1, ...
inline constexpr unsigned kSupervisor = 1u << 1;  ///< the supervisor (and rival supervisors)
inline constexpr unsigned kViewer = 1u << 2;      ///< read-only monitors: view, echo, topics, the bench probe
inline constexpr unsigned kVehicle = 1u << 3;     ///< robot drivers: shapeform_vehicle (enclave vehicle)
}  // namespace role

/// A role as the keystore names its enclaves.
struct RoleInfo {
  unsigned bit;
  const char* enclave;       ///< for people: "agent_K", "supervisor", "viewer"
  const char* enclave_glob;  ///< the shell pattern of its enclave names: "agent_*", "supervisor", "viewer"
};
inline constexpr RoleInfo kRoles[] = {{role::kAgent, "agent_K", "agent_*"},
                                      {role::kSupervisor, "supervisor", "supervisor"},
                                      {role::kViewer, "viewer", "viewer"},
                                      {role::kVehicle, "vehicle", "vehicle"}};

enum class Reliability { BestEffort, Reliable };
enum class Durability { Volatile, TransientLocal };

#define SHAPEFORM_TOPIC_ENUMERATOR(Id, ...) Id,
/// One per row of the table, in its order.
enum class TopicId { SHAPEFORM_TOPICS(SHAPEFORM_TOPIC_ENUMERATOR) };
#undef SHAPEFORM_TOPIC_ENUMERATOR

#define SHAPEFORM_TOPIC_ID(Id, ...) TopicId::Id,
inline constexpr std::array kAllTopics{SHAPEFORM_TOPICS(SHAPEFORM_TOPIC_ID)};
#undef SHAPEFORM_TOPIC_ID

/// One row of the table (dds/topic_table.hpp says what each column means).
struct TopicInfo {
  TopicId id;
  const char* name;     ///< "shapeform/state"; "rt/{ns}/cmd_vel": a vehicle's topic (vehicle_topic_name)
  const char* type;     ///< "shapeform::msg::AgentState": the registered type name
  Reliability reliability;
  Durability durability;
  const char* key;      ///< the key field ("id"), "" for an unkeyed topic
  bool multicast;       ///< readers on the data multicast group when transport.multicast_data is set
  unsigned publishers;  ///< role bits
  unsigned readers;     ///< role bits
  const char* publisher_doc;
  const char* rate_doc;
};

#define SHAPEFORM_TOPIC_INFO(Id, name, Type, reliability, durability, key, multicast, publishers, readers, \
                             publisher_doc, rate_doc)                                                      \
  TopicInfo{TopicId::Id,                                                                                   \
            name,                                                                                          \
            #Type,                                                                                         \
            Reliability::reliability,                                                                      \
            Durability::durability,                                                                        \
            SHAPEFORM_TOPIC_KEY_NAME(key),                                                                 \
            multicast,                                                                                     \
            publishers,                                                                                    \
            readers,                                                                                       \
            publisher_doc,                                                                                 \
            rate_doc},
/// The rows, in TopicId order.
inline constexpr std::array kTopicTable{SHAPEFORM_TOPICS(SHAPEFORM_TOPIC_INFO)};
#undef SHAPEFORM_TOPIC_INFO

/// The row of a topic (std::logic_error for a value outside the enumeration).
const TopicInfo& topic_info(TopicId id);

/// DDS topic name: "shapeform/state", "shapeform/state_batch", "shapeform/command", "shapeform/target",
/// "shapeform/metrics", "shapeform/status", "shapeform/status_batch", a vehicle's.
const char* topic_name(TopicId id);

/// The topic named `name` ("shapeform/state"; a vehicle's, "rt/robot_3/odom", by the first row whose
/// pattern it matches), or nullopt.
std::optional<TopicId> find_topic(std::string_view name);

/// Registered type name of the topic's message, e.g. "shapeform::msg::AgentState",
/// "geometry_msgs::msg::dds_::Twist_".
const char* type_name(TopicId id);

/// The message as people name it: "AgentState" (idl/AgentState.idl), "geometry_msgs/msg/Twist" (a ROS 2
/// type, idl/ros2/geometry_msgs/msg/Twist.idl).
std::string message_name(TopicId id);

/// Whether the topic is a vehicle's (ROS 2's names: one topic per vehicle namespace, its row's name a
/// pattern with {ns}).
bool is_vehicle_topic(TopicId id);

/// A vehicle's topic as ROS 2 names it: "rt/" + ns + "/" + topic ("rt/robot_3/cmd_vel"); a topic that
/// starts with '/' is absolute (no namespace). No check here: config validates the parts.
std::string vehicle_topic_name(const std::string& ns, const std::string& topic);

/// True for keyed topics: State and Status (one instance per agent, @key id), StateBatch and
/// StatusBatch (one per process, @key first_id).
bool is_keyed(TopicId id);

/// The endpoint's user id of static endpoint discovery (transport.static_edp), from the topic's row in
/// the table: writer 2 k + 1, reader 2 k + 2 for row k. Unique over topics and directions, as Fast DDS
/// 2.9 wants them in one description (it looks a peer's endpoint up by this id alone).
std::int16_t static_edp_user_id(TopicId id, bool writer);

}  // namespace shapeform::dds
