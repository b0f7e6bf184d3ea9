#pragma once
/// Every topic's message as it travels: its schema (the fully qualified type name and the `omgidl` text
/// of its IDL, every type it uses included) and its serialized payload exactly as Fast DDS puts it in
/// RTPS (4-byte encapsulation header CDR_LE + XCDR1 body, the generated PubSubType's serialize): what
/// MCAP calls message encoding `cdr` with schema encoding `omgidl`, and what a Foxglove WebSocket channel
/// of encoding `cdr` carries. Generic over the topic table (dds/topic_table.hpp): no per-topic code. No
/// Fast DDS header here.
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "dds/msg_traits.hpp"

namespace shapeform::dds {

/// A topic's schema, as MCAP's Schema record and Foxglove's advertise need it.
struct TopicSchema {
  std::string name;           ///< the fully qualified IDL type, e.g. "shapeform::msg::AgentState"
  std::string_view encoding;  ///< "omgidl"
  std::string_view text;      ///< the IDL text (idl/X.idl with its includes inlined in dependency order)
  std::string_view message_encoding;  ///< "cdr"
};

/// The schema of topic id (from the type column of the topic table and the embedded idl/ files).
/// Throws std::logic_error when the type has no IDL file (a build without it).
const TopicSchema& topic_schema(TopicId id);

/// A payload from_cdr could not read (too short, a sequence past the end...).
struct CdrError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// msg serialized as Fast DDS sends it: encapsulation header (00 01 00 00: CDR little endian) + XCDR1.
/// Declared for every topic's type (MsgTraits); defined in wire.cpp for each row of the topic table.
template <class Msg>
std::vector<std::uint8_t> to_cdr(const Msg& msg);
/// The same into out (resized to the payload; no allocation once out has held a payload as large):
/// for a loop that serializes every sample it records.
template <class Msg>
void to_cdr(const Msg& msg, std::vector<std::uint8_t>& out);

/// The message of bytes as to_cdr gives them (either endianness, as Fast DDS reads them). Throws
/// CdrError naming the type when the bytes are not one.
template <class Msg>
Msg from_cdr(const std::vector<std::uint8_t>& bytes);

}  // namespace shapeform::dds
