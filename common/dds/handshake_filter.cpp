#include "dds/handshake_filter.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cstring>

#include <fastdds/rtps/transport/ChainingTransport.h>
#include <fastdds/rtps/transport/ChainingTransportDescriptor.h>

namespace shapeform::dds {
namespace {

namespace frtps = eprosima::fastdds::rtps;

// RTPS 2.x submessage ids (OMG DDSI-RTPS 2.3, 9.4.5.1.1) and the parts of them read here.
constexpr std::uint8_t kPad = 0x01;
constexpr std::uint8_t kInfoTs = 0x09;
constexpr std::uint8_t kInfoDst = 0x0e;
constexpr std::uint8_t kData = 0x15;
constexpr std::uint8_t kVendorSpecific = 0x80;  // ids 0x80..0xff: a receiver skips them (Fast DDS's
                                                // statistics build appends one to every datagram)
constexpr std::uint8_t kFlagLittleEndian = 0x01;
constexpr std::uint8_t kDataFlagInlineQos = 0x02;
constexpr std::uint8_t kDataFlagData = 0x04;
constexpr std::uint16_t kPidSentinel = 0x0001;
constexpr std::size_t kHeaderSize = 20;  // "RTPS", version, vendor id, GUID prefix
constexpr std::size_t kPrefixSize = 12;
// ENTITYID_P2P_BUILTIN_PARTICIPANT_STATELESS_WRITER: the writer of authentication handshakes.
constexpr std::array<std::uint8_t, 4> kStatelessWriter{0x00, 0x02, 0x01, 0xc3};
// In the DATA's serialized payload: the 4-byte encapsulation, then ParticipantGenericMessage's
// message_identity and related_message_identity (GUID + int64 each), then destination_participant_key.
constexpr std::size_t kDestinationOffset = 4 + 2 * (16 + 8);

using Prefix = std::array<std::uint8_t, kPrefixSize>;

std::uint16_t u16(const std::uint8_t* p, bool little_endian) {
  return little_endian ? static_cast<std::uint16_t>(p[0] | (p[1] << 8))
                       : static_cast<std::uint16_t>((p[0] << 8) | p[1]);
}

bool is_unknown(const Prefix& prefix) {
  return std::all_of(prefix.begin(), prefix.end(), [](std::uint8_t b) { return b == 0; });
}

/// The destination participant's GUID prefix of a stateless writer's DATA submessage (its body, `size`
/// bytes), or false when it is not such a DATA or does not parse.
bool handshake_destination(const std::uint8_t* body, std::size_t size, std::uint8_t flags, Prefix& destination) {
  const bool le = flags & kFlagLittleEndian;
  // extraFlags(2) octetsToInlineQos(2) readerId(4) writerId(4) writerSN(8)
  if (size < 20 || !std::equal(kStatelessWriter.begin(), kStatelessWriter.end(), body + 8)) return false;
  std::size_t pos = 4 + std::size_t{u16(body + 2, le)};
  if (flags & kDataFlagInlineQos) {  // a parameter list, up to PID_SENTINEL
    for (;;) {
      if (pos + 4 > size) return false;
      const std::uint16_t pid = u16(body + pos, le);
      const std::size_t length = u16(body + pos + 2, le);
      pos += 4 + length;
      if (pid == kPidSentinel) break;
    }
  }
  if (!(flags & kDataFlagData) || pos + kDestinationOffset + kPrefixSize > size) return false;
  std::copy_n(body + pos + kDestinationOffset, kPrefixSize, destination.begin());
  return true;
}

std::atomic<std::uint64_t> g_dropped{0};
std::atomic<std::uint64_t> g_misdirected_received{0};

class DirectedHandshakeTransport : public frtps::ChainingTransport {
 public:
  explicit DirectedHandshakeTransport(const frtps::ChainingTransportDescriptor& descriptor)
      : ChainingTransport(descriptor) {}

  frtps::TransportDescriptorInterface* get_configuration() override {
    return low_level_transport_->get_configuration();
  }

  bool send(eprosima::fastrtps::rtps::SenderResource* low_sender_resource,
            const eprosima::fastrtps::rtps::octet* send_buffer, std::uint32_t send_buffer_size,
            eprosima::fastrtps::rtps::LocatorsIterator* destination_locators_begin,
            eprosima::fastrtps::rtps::LocatorsIterator* destination_locators_end,
            const std::chrono::steady_clock::time_point& timeout) override {
    if (is_misdirected_handshake(send_buffer, send_buffer_size)) {
      g_dropped.fetch_add(1, std::memory_order_relaxed);
      return true;  // "sent": the participant it was addressed to would have discarded it
    }
    return low_sender_resource->send(send_buffer, send_buffer_size, destination_locators_begin,
                                     destination_locators_end, timeout);
  }

  void receive(frtps::TransportReceiverInterface* next_receiver, const eprosima::fastrtps::rtps::octet* receive_buffer,
               std::uint32_t receive_buffer_size, const eprosima::fastrtps::rtps::Locator_t& local_locator,
               const eprosima::fastrtps::rtps::Locator_t& remote_locator) override {
    if (is_misdirected_handshake(receive_buffer, receive_buffer_size)) {
      g_misdirected_received.fetch_add(1, std::memory_order_relaxed);
    }
    next_receiver->OnDataReceived(receive_buffer, receive_buffer_size, local_locator, remote_locator);
  }
};

struct DirectedHandshakeDescriptor : frtps::ChainingTransportDescriptor {
  using ChainingTransportDescriptor::ChainingTransportDescriptor;
  frtps::TransportInterface* create_transport() const override { return new DirectedHandshakeTransport(*this); }
};

}  // namespace

bool is_misdirected_handshake(const std::uint8_t* datagram, std::size_t size) {
  if (datagram == nullptr || size < kHeaderSize || std::memcmp(datagram, "RTPS", 4) != 0) return false;
  Prefix info_dst{};  // unknown until an INFO_DST: "every participant"
  int misdirected = 0;
  std::size_t pos = kHeaderSize;
  while (pos < size) {
    if (size - pos < 4) return false;
    const std::uint8_t id = datagram[pos];
    const std::uint8_t flags = datagram[pos + 1];
    const std::size_t available = size - pos - 4;
    std::size_t length = u16(datagram + pos + 2, flags & kFlagLittleEndian);
    // octetsToNextHeader 0: the submessage runs to the end of the message (but for PAD and INFO_TS).
    if (length == 0 && id != kPad && id != kInfoTs) length = available;
    if (length > available) return false;
    const std::uint8_t* body = datagram + pos + 4;
    if (id == kInfoDst) {
      if (length < kPrefixSize) return false;
      std::copy_n(body, kPrefixSize, info_dst.begin());
    } else if (id == kData) {
      Prefix destination{};
      if (!handshake_destination(body, length, flags, destination)) return false;
      if (is_unknown(info_dst) || is_unknown(destination) || destination == info_dst) return false;
      ++misdirected;
    } else if (id != kInfoTs && id != kPad && id < kVendorSpecific) {
      return false;
    }
    pos += 4 + length;
  }
  return misdirected > 0;
}

std::shared_ptr<frtps::TransportDescriptorInterface> with_directed_handshakes(
    std::shared_ptr<frtps::TransportDescriptorInterface> low) {
  return std::make_shared<DirectedHandshakeDescriptor>(std::move(low));
}

HandshakeFilterCounts handshake_filter_counts() {
  return {g_dropped.load(std::memory_order_relaxed), g_misdirected_received.load(std::memory_order_relaxed)};
}

}  // namespace shapeform::dds
