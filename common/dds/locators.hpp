#pragma once
/// RTPS locators and the well-known ports of a domain (RTPS 2.2 9.6.1.1: PB 7400, DG 250), for the
/// participant factory (its locator lists) and the topic table (the State readers' multicast group).
#include <array>
#include <cstdint>
#include <string>

#include <fastdds/rtps/common/Locator.h>

#include "protocol/transport.hpp"

namespace shapeform::dds {

/// The project's one multicast group (administratively scoped, Fast DDS's default): lan's multicast
/// discovery on port 7400 + 250 domain, State samples on port 7400 + 250 domain + 1 when
/// transport.multicast_data is on. Joined and sent on the profile's interfaces only.
inline constexpr std::array<std::uint8_t, 4> kMulticastGroup = {239, 255, 0, 1};

/// The address the lan profile gives Fast DDS for a configured address (an interface or a peer): the
/// address itself, but 127.0.0.1 for any 127.x. Fast DDS 2.9 keeps only whitelist entries that are
/// addresses assigned to an interface (UDPv4Transport's constructor; with none left it binds
/// 192.0.2.0 and the participant gets no port), and `lo` carries 127.0.0.1 alone, though the kernel
/// delivers all of 127.0.0.0/8 on it: 127.0.0.2 is the loopback interface, reached as 127.0.0.1.
std::string lan_address(const std::string& address);

/// A UDPv4 locator of ip:port.
eprosima::fastrtps::rtps::Locator_t udp_locator(const std::array<std::uint8_t, 4>& ip, std::uint32_t port);
/// 127.0.0.1:port.
eprosima::fastrtps::rtps::Locator_t loopback_locator(std::uint32_t port);

/// RTPS well-known discovery multicast port of a domain: PB + DG * domain + d0 = 7400 + 250 d.
std::uint32_t metatraffic_multicast_port(int domain);
/// RTPS well-known user-data multicast port of a domain: PB + DG * domain + d2 = 7400 + 250 d + 1.
std::uint32_t user_multicast_port(int domain);
/// RTPS metatraffic unicast port of participant slot 0 of a domain: PB + DG * domain + d1 = 7400 + 250 d + 10.
/// Slot k has it at + 2k and its user unicast port right after (d3 = 11).
std::uint32_t metatraffic_unicast_port0(int domain);

/// The multicast locator readers of the State topic listen on when cfg.multicast_data is set:
/// 239.255.0.1:(7400 + 250 domain + 1), the domain's user multicast port. A writer whose matched readers
/// share it sends each sample once (UDPTransportInterface::select_locators) and the kernel fans it out;
/// it is joined and sent on the whitelisted interfaces only (lo for loopback, transport.interfaces for
/// lan). Such readers
/// advertise no unicast locator: a writer switching from the group to the unicast locator of its last
/// reader would send to a locator Fast DDS 2.9 never registered and abort on an assert
/// (statistics/rtps/messages/OutputTrafficManager.hpp:87). Throws like participant_qos().
eprosima::fastrtps::rtps::Locator_t data_multicast_locator(const TransportConfig& cfg);

}  // namespace shapeform::dds
