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
///  - name         the DDS topic name; a vehicle's topics (ROS 2's names, `rt/` + the vehicle's namespace +
///                 the topic) hold the placeholder {ns}, and a process names each one it uses from its
///                 config (vehicle.namespace, vehicle.cmd_topic, vehicle.pose_topic: docs/ROBOTS.md)
///  - Type         the message type: shapeform::msg::X from idl/X.idl, or a ROS 2 type
///                 PKG::msg::dds_::X_ from idl/ros2/PKG/msg/X.idl; its spelling is its registered name
///  - reliability  Reliability::BestEffort or Reliable (KEEP_LAST 1 everywhere)
///  - durability   Durability::Volatile or TransientLocal
///  - key          KEY(field): keyed by the int32 field (one instance per value, readers lift
///                 max_instances); NO_KEY: one instance
///  - multicast    true: with transport.multicast_data its readers listen on the data multicast group
///                 (the high-rate all-to-all topics only)
///  - publishers   the roles of DDS Security (role::kAgent, kSupervisor, kViewer, kVehicle) allowed to publish
///  - readers      the roles allowed to subscribe
///  - publisher_doc, rate_doc  who publishes and how often, for README.md's table
/// Rows are never reordered: a row's index gives its endpoints' user ids of static endpoint discovery
/// (static_edp_user_id), which peers of an older build look up. Add a topic at the end.
// clang-format off
#define SHAPEFORM_TOPICS(X)                                                                                      \
  X(State, "shapeform/state", shapeform::msg::AgentState, BestEffort, Volatile, KEY(id), true,                                   \
    role::kAgent, role::kAgent | role::kSupervisor | role::kViewer,                                              \
    "every agent of a one-agent process", "every control tick (`agent.rate_hz`, 50 Hz)")                         \
  X(StateBatch, "shapeform/state_batch", shapeform::msg::AgentStateBatch, BestEffort, Volatile, KEY(first_id), true,             \
    role::kAgent, role::kAgent | role::kSupervisor | role::kViewer,                                              \
    "every `shapeform_agent_group` process (`agent.batch_state`, default true)",                                  \
    "every control tick: one sample per process, one `AgentState` per hosted agent")                             \
  X(Command, "shapeform/command", shapeform::msg::ShapeCommand, Reliable, TransientLocal, NO_KEY, false,                         \
    role::kSupervisor, role::kAgent | role::kSupervisor | role::kViewer,                                         \
    "the supervisor; every agent re-offers the command it follows",                                              \
    "on `start` and on every change (a new epoch); an agent when the command it follows changes; late joiners "  \
    "get the newest at once")                                                                                     \
  X(Target, "shapeform/target", shapeform::msg::TrackingTarget, BestEffort, Volatile, NO_KEY, false,                             \
    role::kSupervisor, role::kAgent | role::kViewer,                                                             \
    "the supervisor, while tracking and not held", "`supervisor.target_rate_hz` (50 Hz)")                        \
  X(Metrics, "shapeform/metrics", shapeform::msg::SwarmMetrics, Reliable, Volatile, NO_KEY, false,                               \
    role::kSupervisor, role::kViewer,                                                                            \
    "the supervisor", "`supervisor.metrics_rate_hz` (10 Hz)")                                                    \
  X(Status, "shapeform/status", shapeform::msg::AgentStatus, Reliable, Volatile, KEY(id), false,                                 \
    role::kAgent, role::kSupervisor | role::kViewer,                                                             \
    "every agent of a one-agent process", "`agent.status_rate_hz` (1 Hz)")                                       \
  X(CmdVel, "rt/{ns}/cmd_vel", geometry_msgs::msg::dds_::Twist_, Reliable, Volatile, NO_KEY, false,              \
    role::kAgent, role::kVehicle | role::kViewer,                                                                             \
    "every agent with `vehicle.interface: ros2` (`vehicle.cmd_type: twist`, the default), to its vehicle",       \
    "every control tick")                                                                                         \
  X(CmdVelStamped, "rt/{ns}/cmd_vel", geometry_msgs::msg::dds_::TwistStamped_, Reliable, Volatile, NO_KEY,       \
    false, role::kAgent, role::kVehicle | role::kViewer,                                                                   \
    "every agent with `vehicle.interface: ros2` and `vehicle.cmd_type: twist_stamped`", "every control tick")    \
  X(Odom, "rt/{ns}/odom", nav_msgs::msg::dds_::Odometry_, BestEffort, Volatile, NO_KEY, false,                   \
    role::kVehicle, role::kAgent | role::kViewer,                                                                \
    "each robot's driver (`shapeform_vehicle` here); read with `vehicle.pose_type: odometry`, the default",     \
    "the driver's (`vehicle_sim.pose_rate_hz`, 50 Hz)")                                                          \
  X(Pose, "rt/{ns}/pose", geometry_msgs::msg::dds_::PoseStamped_, BestEffort, Volatile, NO_KEY, false,           \
    role::kVehicle, role::kAgent | role::kViewer,                                                                \
    "motion capture or localisation; read with `vehicle.pose_type: pose_stamped`", "the source's")          \
  X(Ros2Agents, "rt/shapeform/agents", geometry_msgs::msg::dds_::PoseArray_, Reliable, Volatile, NO_KEY, false,  \
    role::kSupervisor, role::kViewer,                                                                            \
    "the supervisor with `ros2.mirror: true` (docs/ROS2.md): every alive agent's pose, ascending id",            \
    "`ros2.rate_hz` (10 Hz)")                                                                                     \
  X(Ros2Markers, "rt/shapeform/markers", visualization_msgs::msg::dds_::MarkerArray_, Reliable, Volatile, NO_KEY, \
    false, role::kSupervisor, role::kViewer,                                                                     \
    "the supervisor with `ros2.mirror: true`: agents, ids, outline, keep-out zones, fence, centre, commands",    \
    "`ros2.rate_hz` (10 Hz)")                                                                                     \
  X(StatusBatch, "shapeform/status_batch", shapeform::msg::AgentStatusBatch, Reliable, Volatile, KEY(first_id),   \
    false, role::kAgent, role::kSupervisor | role::kViewer,                                                      \
    "every `shapeform_agent_group` process (`agent.batch_state`, default true)",                                  \
    "`agent.status_rate_hz` (1 Hz): one sample per process and period, one `AgentStatus` per hosted agent")
// clang-format on

/// The key column, read by the expansions: the field's name ("" without a key), and a function giving
/// the key's value of a message (the int32 field; -1 without a key).
#define SHAPEFORM_TOPIC_KEY_NAME(key) SHAPEFORM_TOPIC_KEY_NAME_##key
#define SHAPEFORM_TOPIC_KEY_NAME_KEY(field) #field
#define SHAPEFORM_TOPIC_KEY_NAME_NO_KEY ""
#define SHAPEFORM_TOPIC_KEY_GETTER(key) SHAPEFORM_TOPIC_KEY_GETTER_##key
#define SHAPEFORM_TOPIC_KEY_GETTER_KEY(field) [](const auto& message) { return std::int32_t{message.field()}; }
#define SHAPEFORM_TOPIC_KEY_GETTER_NO_KEY [](const auto&) { return std::int32_t{-1}; }
