#pragma once
/// Compile-time facts about each topic's message type, from the topic table (dds/topic_table.hpp): its
/// topic and its key; and visit_topic(), which hands a topic's message type to generic code, so no
/// code of the project switches over topics by hand. No Fast DDS here (the generated message types are
/// plain types on fastcdr).
#include <cstdint>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "dds/topics.hpp"
#include "shapeform/msg/all.h"  // every idl/*.idl's type, generated (idl/CMakeLists.txt)

namespace shapeform::dds {

/// Specialised for every topic's message type; using another type with Node is a compile error.
template <class Msg>
struct MsgTraits;

#define SHAPEFORM_MSG_TRAITS(Id, name, Type, reliability, durability, key_column, ...)                \
  template <>                                                                                         \
  struct MsgTraits<Type> {                                                                               \
    static constexpr TopicId topic = TopicId::Id;                                                     \
    static constexpr bool keyed = SHAPEFORM_TOPIC_KEY_NAME(key_column)[0] != '\0';                    \
    static std::int32_t key(const Type& m)      { return SHAPEFORM_TOPIC_KEY_GETTER(key_column)(m); } \
  };
SHAPEFORM_TOPICS(SHAPEFORM_MSG_TRAITS)
#undef SHAPEFORM_MSG_TRAITS

/// A message type as a value: visit_topic's argument names the type as `typename decltype(tag)::type`.
template <class Msg>
struct MsgType {
  using type = Msg;
};

/// Calls f(MsgType<Msg>{}) with the message type of topic id and returns what it returns (every
/// topic's call must return the same type). Throws std::logic_error for a value outside TopicId.
template <class F>
auto visit_topic(TopicId id, F&& f) {
  switch (id) {
#define SHAPEFORM_VISIT_TOPIC(Id, name, Type, ...) \
  case TopicId::Id:                                \
    return f(MsgType<Type>{});
    SHAPEFORM_TOPICS(SHAPEFORM_VISIT_TOPIC)
#undef SHAPEFORM_VISIT_TOPIC
  }
  throw std::logic_error("dds: unknown TopicId " + std::to_string(static_cast<int>(id)));
}

}  // namespace shapeform::dds
