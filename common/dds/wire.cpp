#include "dds/wire.hpp"

#include <fastcdr/Cdr.h>
#include <fastcdr/FastBuffer.h>
#include <fastdds/rtps/common/SerializedPayload.h>

#include <array>
#include <cstring>

#include "dds/idl_files.hpp"
#include "shapeform/msg/all_pubsub_types.h"  // every idl/*.idl's PubSubType, generated

namespace shapeform::dds {
namespace {

TopicSchema make_schema(TopicId id) {
  const std::string key = message_name(id);
  for (const IdlFile& f : idl_files()) {
    if (f.key == key) return TopicSchema{type_name(id), "omgidl", f.text, "cdr"};
  }
  throw std::logic_error("dds: no IDL file idl/" + key + ".idl embedded for topic " + topic_name(id));
}

}  // namespace

const TopicSchema& topic_schema(TopicId id) {
  static const auto schemas = [] {
    std::array<TopicSchema, kAllTopics.size()> all;
    for (std::size_t i = 0; i < kAllTopics.size(); ++i) all[i] = make_schema(kAllTopics[i]);
    return all;
  }();
  return schemas.at(static_cast<std::size_t>(id));
}

// One definition of each per row of the topic table: the encapsulation header and the XCDR1 body, as the
// type's generated PubSubType writes them for the DataWriter (from_cdr reads with the PubSubType).
#define SHAPEFORM_WIRE(Id, name, Type, ...)                                                               \
  template <>                                                                                             \
  void to_cdr<Type>(const Type& msg, std::vector<std::uint8_t>& out) {                                    \
    /* as Type##PubSubType::serialize writes it, without its payload and key buffers */                   \
    out.assign(4 + Type::getCdrSerializedSize(msg), 0); /* padding bytes zero, as in a fresh payload */   \
    eprosima::fastcdr::FastBuffer buffer(reinterpret_cast<char*>(out.data()), out.size());                \
    using eprosima::fastcdr::Cdr;                                                                         \
    Cdr cdr(buffer, Cdr::DEFAULT_ENDIAN, Cdr::DDS_CDR);                                                   \
    cdr.serialize_encapsulation();                                                                        \
    msg.serialize(cdr);                                                                                   \
    out.resize(cdr.getSerializedDataLength());                                                            \
  }                                                                                                       \
  template <>                                                                                             \
  std::vector<std::uint8_t> to_cdr<Type>(const Type& msg) {                                               \
    std::vector<std::uint8_t> out;                                                                        \
    to_cdr(msg, out);                                                                                     \
    return out;                                                                                           \
  }                                                                                                       \
  template <>                                                                                             \
  Type from_cdr<Type>(const std::vector<std::uint8_t>& bytes) {                                           \
    Type##PubSubType type;                                                                                \
    eprosima::fastrtps::rtps::SerializedPayload_t payload(static_cast<std::uint32_t>(bytes.size()));      \
    if (!bytes.empty()) std::memcpy(payload.data, bytes.data(), bytes.size());                            \
    payload.length = static_cast<std::uint32_t>(bytes.size());                                            \
    Type msg;                                                                                             \
    bool ok = bytes.size() >= 4;                                                                          \
    try {                                                                                                 \
      ok = ok && type.deserialize(&payload, &msg);                                                        \
    } catch (...) { /* fastcdr's exceptions: a malformed payload */                                       \
      ok = false;                                                                                         \
    }                                                                                                     \
    if (!ok)                                                                                              \
      throw CdrError(std::string("dds: ") + std::to_string(bytes.size()) + " bytes are no CDR " + #Type + \
                     " (too short or malformed)");                                                        \
    return msg;                                                                                           \
  }
SHAPEFORM_TOPICS(SHAPEFORM_WIRE)
#undef SHAPEFORM_WIRE

}  // namespace shapeform::dds
