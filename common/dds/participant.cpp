#include "dds/participant.hpp"

#include <sstream>

#include "dds/locators.hpp"
#include "protocol/security.hpp"

namespace shapeform::dds {

std::string describe(const TransportConfig& cfg) {
  std::ostringstream os;
  if (cfg.profile == kLoopback) {
    os << "loopback (UDPv4 127.0.0.1 only, unicast discovery of ids 0.." << (cfg.max_participants - 1)
       << ")";
  } else if (cfg.profile == kLan) {
    os << "lan (UDPv4 on ";
    if (cfg.interfaces.empty()) {
      os << "all interfaces";
    } else {
      for (std::size_t i = 0; i < cfg.interfaces.size(); ++i) {
        const std::string bound = lan_address(cfg.interfaces[i]);
        os << (i ? "," : "") << cfg.interfaces[i] << (bound != cfg.interfaces[i] ? " (lo, as " + bound + ")" : "");
      }
    }
    if (cfg.peers.empty()) {
      os << ", multicast discovery on 239.255.0.1:" << metatraffic_multicast_port(cfg.domain) << ")";
    } else {
      os << ", unicast peers ";
      for (std::size_t i = 0; i < cfg.peers.size(); ++i) os << (i ? "," : "") << cfg.peers[i];
      os << " ids 0.." << (cfg.max_participants - 1) << ", no multicast)";
    }
  } else if (cfg.profile == kDiscoveryServer) {
    os << "discovery-server (client of " << cfg.discovery_server << ")";
  } else {
    os << "unknown profile \"" << cfg.profile << "\"";
  }
  os << ", domain " << cfg.domain << ", lease " << cfg.lease_s << " s, announce " << cfg.announce_s
     << " s";
  const TransportConfig defaults;
  if (cfg.initial_announcements != defaults.initial_announcements || cfg.initial_announce_s != defaults.initial_announce_s)
    os << ", " << cfg.initial_announcements << " initial announcements every " << cfg.initial_announce_s << " s";
  if (cfg.socket_buffer_bytes > 0) os << ", socket buffers " << cfg.socket_buffer_bytes << " B";
  if (cfg.multicast_data) os << ", state on multicast 239.255.0.1:" << user_multicast_port(cfg.domain);
  if (cfg.static_edp) os << ", static endpoint discovery";
  if (cfg.security.enabled) os << ", " << describe(cfg.security);
  return os.str();
}

}  // namespace shapeform::dds
