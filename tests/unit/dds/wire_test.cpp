// Unit tests of common/dds/wire: every topic's CDR bytes (as Fast DDS sends them) and omgidl schema.
#include "dds/wire.hpp"
#include "protocol/samples.hpp"

#include <catch2/catch.hpp>
#include <cstring>
#include <string>
#include <vector>

namespace shapeform {
namespace {

/// Little-endian writer of XCDR1 by hand: alignment counted from the start of the body (after the
/// 4-byte encapsulation header), each primitive aligned to its size, padding bytes zero.
struct HandCdr {
  std::vector<std::uint8_t> bytes{0x00, 0x01, 0x00, 0x00};  // CDR_LE, options 0
  void align(std::size_t n) {
    while ((bytes.size() - 4) % n != 0) bytes.push_back(0);
  }
  template <class T>
  void put(T v) {
    align(sizeof(T));
    std::uint8_t raw[sizeof(T)];
    std::memcpy(raw, &v, sizeof(T));  // the test host is little endian (x86-64, arm64)
    bytes.insert(bytes.end(), raw, raw + sizeof(T));
  }
};

msg::AgentState a_state() {
  msg::AgentState m;
  m.id(7);
  m.seq(123456789012ULL);
  m.stamp_ns(-5);
  m.epoch(3);
  for (std::size_t i = 0; i < 12; ++i) m.issuer()[i] = static_cast<std::uint8_t>(0xA0 + i);
  m.model_time(1.25);
  m.x(-2.5);
  m.y(0.125);
  m.vx(1e-3);
  m.vy(-4.0);
  m.has_arc(true);
  m.arc(9.75);
  m.prev_x(-2.4);
  m.prev_y(0.1);
  m.prev_arc(9.5);
  return m;
}

TEST_CASE("to_cdr of an AgentState is its XCDR1 bytes as written by hand, behind the CDR_LE header",
          "[dds][wire]") {
  HandCdr h;
  h.put<std::int32_t>(7);
  h.put<std::uint64_t>(123456789012ULL);  // aligned to 8: 4 padding bytes before it
  h.put<std::int64_t>(-5);
  h.put<std::uint64_t>(3);
  for (std::uint8_t i = 0; i < 12; ++i) h.put<std::uint8_t>(static_cast<std::uint8_t>(0xA0 + i));
  for (double d : {1.25, -2.5, 0.125, 1e-3, -4.0}) h.put<double>(d);  // model_time after 4 padding bytes
  h.put<std::uint8_t>(1);                                             // has_arc
  for (double d : {9.75, -2.4, 0.1, 9.5}) h.put<double>(d);           // arc after 7 padding bytes
  REQUIRE(h.bytes.size() == 4 + 128);
  CHECK(dds::to_cdr(a_state()) == h.bytes);
  CHECK(dds::from_cdr<msg::AgentState>(h.bytes) == a_state());
}

TEST_CASE("every topic's message round-trips through to_cdr and from_cdr", "[dds][wire]") {
  for (const dds::TopicId id : dds::kAllTopics) {
    CAPTURE(dds::topic_name(id));
    dds::visit_topic(id, [](auto tag) {
      using Msg = typename decltype(tag)::type;
      const Msg empty{};
      const auto bytes = dds::to_cdr(empty);
      REQUIRE(bytes.size() >= 4);
      CHECK(bytes[0] == 0x00);
      CHECK(bytes[1] == 0x01);  // CDR little endian
      CHECK(dds::from_cdr<Msg>(bytes) == empty);
      CHECK(dds::to_cdr(dds::from_cdr<Msg>(bytes)) == bytes);
      return 0;
    });
  }
}

TEST_CASE("a batch of kBatchStatesPerDatagram states fits one UDP datagram, one of kMaxBatchStates does not",
          "[dds][wire]") {
  // Fast DDS 2.9's UDP message is at most 65,500 bytes; the RTPS header (20), INFO_TS (12) and the DATA
  // submessage's header with the key hash in its inline QoS (about 60) take a few hundred at most.
  constexpr std::size_t kMessage = 65500, kRtpsOverhead = 300;
  msg::AgentStateBatch batch;
  batch.first_id(0);
  batch.states().assign(dds::kBatchStatesPerDatagram, a_state());
  CHECK(dds::to_cdr(batch).size() + kRtpsOverhead <= kMessage);
  batch.states().assign(dds::kMaxBatchStates, a_state());
  CHECK(dds::to_cdr(batch).size() > kMessage);  // fragmented unless agent.batch_max_states cuts it
}

TEST_CASE("a status batch of kBatchStatusesPerDatagram fits one UDP datagram, a tenth more does not", "[dds][wire]") {
  constexpr std::size_t kMessage = 65500, kRtpsOverhead = 300;
  msg::AgentStatusBatch batch;
  batch.first_id(0);
  batch.statuses().assign(dds::kBatchStatusesPerDatagram, msg::AgentStatus());
  CHECK(dds::to_cdr(batch).size() + kRtpsOverhead <= kMessage);
  // The constant is near the limit, not far below it: 1.1 times as many would not fit.
  batch.statuses().assign(dds::kBatchStatusesPerDatagram * 11 / 10 + 20, msg::AgentStatus());
  CHECK(dds::to_cdr(batch).size() > kMessage);
}

TEST_CASE("a batch with states and a command with strings and sequences round-trip", "[dds][wire]") {
  msg::AgentStateBatch batch;
  batch.first_id(7);
  batch.states().push_back(a_state());
  batch.states().push_back(a_state());
  batch.states()[1].id(8);
  const auto bytes = dds::to_cdr(batch);
  CHECK(bytes.size() == 4 + 4 + 4 + 2 * 128);  // first_id, sequence length, then each state aligned to 8
  CHECK(dds::from_cdr<msg::AgentStateBatch>(bytes) == batch);
  msg::ShapeCommand c;
  c.epoch(4);
  c.shape_kind("polygon");
  c.vertices({0.0, 0.0, 1.0, 0.0, 0.0, 1.0});
  c.keep_out_circles({1.0, 2.0, 0.5});
  c.issuer_name("shapeform_supervisor on host pid 1");
  CHECK(dds::from_cdr<msg::ShapeCommand>(dds::to_cdr(c)) == c);
}

TEST_CASE("to_cdr into a reused buffer gives the bytes of a fresh one, shorter payloads after longer ones",
          "[dds][wire]") {
  msg::AgentStateBatch big;
  big.first_id(7);
  for (int i = 0; i < 5; ++i) big.states().push_back(a_state());
  msg::ShapeCommand c;
  c.shape_kind("polygon");
  c.vertices({0.0, 0.0, 1.0, 0.0, 0.0, 1.0});
  std::vector<std::uint8_t> buffer;
  dds::to_cdr(big, buffer);
  CHECK(buffer == dds::to_cdr(big));
  dds::to_cdr(a_state(), buffer);  // shorter: nothing of the batch is left behind
  CHECK(buffer.size() == 4 + 128);
  CHECK(buffer == dds::to_cdr(a_state()));
  dds::to_cdr(c, buffer);
  CHECK(dds::from_cdr<msg::ShapeCommand>(buffer) == c);
}

TEST_CASE("from_cdr refuses bytes that are not the message, naming the type", "[dds][wire]") {
  auto bytes = dds::to_cdr(a_state());
  bytes.resize(40);
  CHECK_THROWS_WITH(dds::from_cdr<msg::AgentState>(bytes),
                    Catch::Matchers::Contains("shapeform::msg::AgentState"));
  CHECK_THROWS_AS(dds::from_cdr<msg::AgentState>({0x00, 0x01}), dds::CdrError);
}

TEST_CASE("every topic has its omgidl schema: the fully qualified type and the IDL with its includes inlined",
          "[dds][wire]") {
  for (const dds::TopicId id : dds::kAllTopics) {
    const dds::TopicSchema& s = dds::topic_schema(id);
    CAPTURE(dds::topic_name(id));
    CHECK(s.name == dds::type_name(id));
    CHECK(s.encoding == "omgidl");
    CHECK(s.message_encoding == "cdr");
    CHECK(s.text.find("#include") == std::string_view::npos);
    const std::string leaf = s.name.substr(s.name.rfind("::") + 2);
    CHECK(s.text.find("struct " + leaf) != std::string_view::npos);
  }
  // AgentStateBatch uses AgentState: its definition comes first, once.
  const std::string_view batch = dds::topic_schema(dds::TopicId::StateBatch).text;
  const auto state_at = batch.find("struct AgentState\n");
  REQUIRE(state_at != std::string_view::npos);
  CHECK(batch.find("struct AgentState\n", state_at + 1) == std::string_view::npos);
  CHECK(state_at < batch.find("struct AgentStateBatch"));
  // Odometry uses Time, Header, Point, Quaternion, Pose, ...: each defined once, before its users.
  const std::string_view odom = dds::topic_schema(dds::TopicId::Odom).text;
  CHECK(odom.find("struct Time_") < odom.find("struct Header_"));
  CHECK(odom.find("struct Point_") < odom.find("struct Pose_"));
  CHECK(odom.find("struct Pose_") < odom.find("struct PoseWithCovariance_"));
  CHECK(odom.find("struct Pose_") == odom.rfind("struct Pose_"));
}

}  // namespace
}  // namespace shapeform
