#pragma once
/// Authentication messages sent only to the participant they are for.
///
/// Fast DDS 2.9.1's DDS Security sends every authentication handshake message (request, reply, final,
/// and each resend, about 4.7 kB with the certificates) from its participant stateless writer
/// (entity 0x000201c3) to EVERY participant it has discovered, one datagram each, although the message
/// names its one destination (ParticipantGenericMessage::destination_participant_key); every other
/// participant parses it and discards it. A swarm of N secured processes so sends N - 1 datagrams per
/// handshake message, N^3 in all, and on a busy host the resends of lost ones feed on themselves
/// (docs/SECURITY.md, "Cost"). The writer has no data filter the DDS API can reach, so the project
/// filters below it, in a transport: each datagram the stateless writer sends carries an INFO_DST
/// submessage naming the participant it goes to; a datagram whose handshake names another destination
/// is not sent. What is sent is unchanged, byte for byte.
#include <cstddef>
#include <cstdint>
#include <memory>

namespace eprosima::fastdds::rtps {
struct TransportDescriptorInterface;
}

namespace shapeform::dds {

/// True when `datagram` is an RTPS message that carries only authentication handshake DATA of the
/// participant stateless writer (entity 0x000201c3, besides INFO_TS, INFO_DST, PAD and vendor-specific submessages), and
/// each of them names a destination participant (destination_participant_key, not unknown) other than
/// the INFO_DST in effect: the participant this datagram goes to would only discard it. False for
/// anything else, including a datagram this parser does not fully understand (truncated, fragmented,
/// protected): such a datagram is sent as it is. Pure.
bool is_misdirected_handshake(const std::uint8_t* datagram, std::size_t size);

/// `low` (the profile's UDPv4 descriptor) wrapped in a transport that drops the datagrams
/// is_misdirected_handshake() finds and passes everything else through, unchanged, to and from `low`.
/// The factory uses it for secured participants.
std::shared_ptr<eprosima::fastdds::rtps::TransportDescriptorInterface> with_directed_handshakes(
    std::shared_ptr<eprosima::fastdds::rtps::TransportDescriptorInterface> low);

/// Counts of this process's directed-handshake transports since it started (for tests and logs):
/// datagrams not sent because they were misdirected, and datagrams received that were misdirected
/// (a sender without the filter).
struct HandshakeFilterCounts {
  std::uint64_t dropped = 0;
  std::uint64_t misdirected_received = 0;
};
HandshakeFilterCounts handshake_filter_counts();

}  // namespace shapeform::dds
