#include "dds/locators.hpp"

#include <fastrtps/utils/IPLocator.h>

namespace shapeform::dds {

namespace frtps = eprosima::fastrtps::rtps;

std::string lan_address(const std::string& address) {
  return address.rfind("127.", 0) == 0 ? std::string("127.0.0.1") : address;
}

frtps::Locator_t udp_locator(const std::array<std::uint8_t, 4>& ip, std::uint32_t port) {
  frtps::Locator_t loc;
  loc.kind = LOCATOR_KIND_UDPv4;
  frtps::IPLocator::setIPv4(loc, ip[0], ip[1], ip[2], ip[3]);
  loc.port = port;
  return loc;
}

frtps::Locator_t loopback_locator(std::uint32_t port) { return udp_locator({127, 0, 0, 1}, port); }

std::uint32_t metatraffic_multicast_port(int domain) { return 7400u + 250u * static_cast<std::uint32_t>(domain); }

std::uint32_t user_multicast_port(int domain) { return 7400u + 250u * static_cast<std::uint32_t>(domain) + 1u; }

std::uint32_t metatraffic_unicast_port0(int domain) {
  return 7410u + 250u * static_cast<std::uint32_t>(domain);
}

frtps::Locator_t data_multicast_locator(const TransportConfig& cfg) {
  validate(cfg);
  return udp_locator(kMulticastGroup, user_multicast_port(cfg.domain));
}

}  // namespace shapeform::dds
