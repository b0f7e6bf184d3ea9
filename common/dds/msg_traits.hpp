#pragma once
/// Compile-time facts about each generated message type: its PubSubType, its topic, its key.
#include <cstdint>

#include "dds/topics.hpp"
#include "shapeform/msg/AgentStateBatchPubSubTypes.h"
#include "shapeform/msg/AgentStatePubSubTypes.h"
#include "shapeform/msg/AgentStatusPubSubTypes.h"
#include "shapeform/msg/ShapeCommandPubSubTypes.h"
#include "shapeform/msg/SwarmMetricsPubSubTypes.h"
#include "shapeform/msg/TrackingTargetPubSubTypes.h"

namespace shapeform::dds {

/// Specialised for every message type; using another type with Node is a compile error.
template <class Msg>
struct MsgTraits;

template <>
struct MsgTraits<msg::AgentState> {
  using PubSubType = msg::AgentStatePubSubType;
  static constexpr TopicId topic = TopicId::State;
  static constexpr bool keyed = true;
  static std::int32_t key(const msg::AgentState& m) { return m.id(); }
};

template <>
struct MsgTraits<msg::AgentStateBatch> {
  using PubSubType = msg::AgentStateBatchPubSubType;
  static constexpr TopicId topic = TopicId::StateBatch;
  static constexpr bool keyed = true;
  static std::int32_t key(const msg::AgentStateBatch& m) { return m.first_id(); }
};

template <>
struct MsgTraits<msg::ShapeCommand> {
  using PubSubType = msg::ShapeCommandPubSubType;
  static constexpr TopicId topic = TopicId::Command;
  static constexpr bool keyed = false;
  static std::int32_t key(const msg::ShapeCommand&) { return -1; }
};

template <>
struct MsgTraits<msg::TrackingTarget> {
  using PubSubType = msg::TrackingTargetPubSubType;
  static constexpr TopicId topic = TopicId::Target;
  static constexpr bool keyed = false;
  static std::int32_t key(const msg::TrackingTarget&) { return -1; }
};

template <>
struct MsgTraits<msg::SwarmMetrics> {
  using PubSubType = msg::SwarmMetricsPubSubType;
  static constexpr TopicId topic = TopicId::Metrics;
  static constexpr bool keyed = false;
  static std::int32_t key(const msg::SwarmMetrics&) { return -1; }
};

template <>
struct MsgTraits<msg::AgentStatus> {
  using PubSubType = msg::AgentStatusPubSubType;
  static constexpr TopicId topic = TopicId::Status;
  static constexpr bool keyed = true;
  static std::int32_t key(const msg::AgentStatus& m) { return m.id(); }
};

}  // namespace shapeform::dds
