#pragma once
/// The ONE declaration of the project's topics: a topic is its IDL file (idl/Type.idl, @final) and one
/// row here. Everything else that names topics is derived from this list: TopicId and kAllTopics, the
/// topic table's accessors (dds/topics.hpp), MsgTraits and visit_topic (dds/msg_traits.hpp), the type
/// registration and the readers and writers instantiated in the dds library, the QoS (dds/topic_qos.hpp),
/// the static endpoint discovery description, shapeform_echo's dispatch, and, through
/// scripts/gen_topic_docs.sh (ctests fail while they are stale), the topic table of README.md, the
/// access table of docs/SECURITY.md and the permissions of scripts/make_keystore.sh.
///
/// X(Id, name, Type, reliability, durability, key, multicast, publishers, readers, publisher_doc, rate_doc):
///  - Id           TopicId::Id
///  - name         the DDS topic name
///  - Type         the message type, shapeform::msg::Type, from idl/Type.idl
///  - reliability  Reliability::BestEffort or Reliable (KEEP_LAST 1 everywhere)
///  - durability   Durability::Volatile or TransientLocal
///  - key          KEY(field): keyed by the int32 field (one instance per value, readers lift
///                 max_instances); NO_KEY: one instance
///  - multicast    true: with transport.multicast_data its readers listen on the data multicast group
///                 (the high-rate all-to-all topics only)
///  - publishers   the roles of DDS Security (role::kAgent, kSupervisor, kViewer) allowed to publish
///  - readers      the roles allowed to subscribe
///  - publisher_doc, rate_doc  who publishes and how often, for README.md's table
/// Rows are never reordered: a row's index gives its endpoints' user ids of static endpoint discovery
/// (static_edp_user_id), which peers of an older build look up. Add a topic at the end.
// clang-format off
#define SHAPEFORM_TOPICS(X)                                                                                      \
  X(State, "shapeform/state", AgentState, BestEffort, Volatile, KEY(id), true,                                   \
    role::kAgent, role::kAgent | role::kSupervisor | role::kViewer,                                              \
    "every agent of a one-agent process", "every control tick (`agent.rate_hz`, 50 Hz)")                         \
  X(StateBatch, "shapeform/state_batch", AgentStateBatch, BestEffort, Volatile, KEY(first_id), true,             \
    role::kAgent, role::kAgent | role::kSupervisor | role::kViewer,                                              \
    "every `shapeform_agent_group` process (`agent.batch_state`, default true)",                                  \
    "every control tick: one sample per process, one `AgentState` per hosted agent")                             \
  X(Command, "shapeform/command", ShapeCommand, Reliable, TransientLocal, NO_KEY, false,                         \
    role::kSupervisor, role::kAgent | role::kSupervisor | role::kViewer,                                         \
    "the supervisor; every agent re-offers the command it follows",                                              \
    "on `start` and on every change (a new epoch); an agent when the command it follows changes; late joiners "  \
    "get the newest at once")                                                                                     \
  X(Target, "shapeform/target", TrackingTarget, BestEffort, Volatile, NO_KEY, false,                             \
    role::kSupervisor, role::kAgent | role::kViewer,                                                             \
    "the supervisor, while tracking and not held", "`supervisor.target_rate_hz` (50 Hz)")                        \
  X(Metrics, "shapeform/metrics", SwarmMetrics, Reliable, Volatile, NO_KEY, false,                               \
    role::kSupervisor, role::kViewer,                                                                            \
    "the supervisor", "`supervisor.metrics_rate_hz` (10 Hz)")                                                    \
  X(Status, "shapeform/status", AgentStatus, Reliable, Volatile, KEY(id), false,                                 \
    role::kAgent, role::kSupervisor | role::kViewer,                                                             \
    "every agent", "`agent.status_rate_hz` (1 Hz)")
// clang-format on

/// The key column, read by the expansions: the field's name ("" without a key), and a function giving
/// the key's value of a message (the int32 field; -1 without a key).
#define SHAPEFORM_TOPIC_KEY_NAME(key) SHAPEFORM_TOPIC_KEY_NAME_##key
#define SHAPEFORM_TOPIC_KEY_NAME_KEY(field) #field
#define SHAPEFORM_TOPIC_KEY_NAME_NO_KEY ""
#define SHAPEFORM_TOPIC_KEY_GETTER(key) SHAPEFORM_TOPIC_KEY_GETTER_##key
#define SHAPEFORM_TOPIC_KEY_GETTER_KEY(field) [](const auto& message) { return std::int32_t{message.field()}; }
#define SHAPEFORM_TOPIC_KEY_GETTER_NO_KEY [](const auto&) { return std::int32_t{-1}; }
