#pragma once
/// The DDS transport description and its one validator. No Fast DDS headers: the config loader fills
/// and checks a TransportConfig without linking Fast DDS, and the participant factory
/// (dds/participant.hpp) builds every participant from one.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/params.hpp"
#include "protocol/security.hpp"

namespace shapeform::dds {

/// Largest valid DDS domain id (ports 7400 + 250 d must stay below 65536).
inline constexpr int kMaxDomainId = 232;

/// The transport profiles, by the names config files and TransportConfig::profile use.
inline constexpr const char* kLoopback = "loopback";
inline constexpr const char* kLan = "lan";
inline constexpr const char* kDiscoveryServer = "discovery-server";
inline constexpr const char* kProfiles[] = {kLoopback, kLan, kDiscoveryServer};

/// What the one participant factory builds every participant from: the DDS transport profile and the
/// participant's security.
struct TransportConfig {
  std::string profile = kLoopback;      ///< one of kProfiles
  int domain = 0;                       ///< DDS domain id, 0..kMaxDomainId
  int max_participants = 120;           ///< participant ids probed by loopback initial peers
  /// lan: IPv4 addresses of this host's interfaces to use (empty = all); nothing is sent from, received on
  /// or joined on any other interface.
  std::vector<std::string> interfaces;
  /// lan: unicast peer addresses (no multicast at all, for networks without it); empty = multicast
  /// discovery on 239.255.0.1.
  std::vector<std::string> peers;
  std::string discovery_server = "127.0.0.1:11811";  ///< discovery-server: host:port
  double lease_s = 2.0;                              ///< participant lease duration
  double announce_s = 0.5;                           ///< participant announcement period
  /// Announcements a new participant sends at `initial_announce_s` intervals before the period
  /// announce_s takes over (Fast DDS's initial announcements; its defaults: 5 at 0.1 s).
  int initial_announcements = 5;
  double initial_announce_s = 0.1;  ///< interval of the initial announcements
  int socket_buffer_bytes = 0;                       ///< UDP send/receive buffer size; 0 = OS default
  /// State-topic readers listen on the multicast group 239.255.0.1 (the domain's user multicast port)
  /// instead of a unicast port: a writer sends one datagram per sample instead of one per reader.
  /// Loopback profile or discovery-server with a server on 127.x / localhost (whitelist 127.0.0.1, so
  /// the group stays on lo), or lan without peers (the group on `interfaces` only). Off by default.
  bool multicast_data = false;
  /// Fast DDS STATIC endpoint discovery: no SEDP; every participant knows every endpoint of the swarm
  /// from one description generated from the topic table (dds::static_edp_description) and learns which
  /// ones a peer has from its participant announcement. Every process of the swarm must set it alike.
  /// Not with the discovery-server profile or security (the validator refuses). Off by default.
  bool static_edp = false;
  /// DDS Security (keys security.*): off, or every participant of the process authenticated,
  /// access-controlled and encrypted with one enclave of a keystore.
  SecurityConfig security;

  /// Whether every participant's traffic stays on lo: the loopback profile, or a discovery server on
  /// 127.x / localhost. multicast_data needs it, or lan without peers (the validator checks).
  bool on_loopback() const {
    return profile == kLoopback ||
           (profile == kDiscoveryServer &&
            (discovery_server.rfind("127.", 0) == 0 || discovery_server.rfind("localhost:", 0) == 0));
  }
};

/// `cfg` with security.identity filled in when empty: the process's role and id ("supervisor",
/// "agent_3", "viewer"), the enclave it uses when security is enabled.
inline TransportConfig with_identity(TransportConfig cfg, const std::string& default_identity) {
  if (cfg.security.identity.empty()) cfg.security.identity = default_identity;
  return cfg;
}

/// The transport's keys ("transport.profile", ..., "security.enabled", ...): type, unit, range and description of each field,
/// its default read from TransportConfig{}. The config loader reads, emits and documents them from it.
const std::vector<core::params::Param<TransportConfig>>& transport_table();

/// One problem of a transport description.
struct TransportProblem {
  std::string key;      ///< the field's key, e.g. "transport.peers"
  std::string what;     ///< e.g. "must be a list of IPv4 addresses (\"foo\" is not one)"
  std::string got;      ///< the offending value as text
  std::string related;  ///< the other key of a relation ("transport.lease_s" for announce_s), or ""
};

/// Every problem of cfg, in the table's key order: each number within its declared range, the profile
/// known, interfaces and peers IPv4 addresses, discovery_server "host:port" (host an IPv4 address or
/// localhost, port 1..65535), announce_s < lease_s, multicast_data only on loopback (or a discovery
/// server on it) or lan without peers, static_edp neither with the discovery-server profile nor with
/// security, security.keystore given when security.enabled and the profile not discovery-server,
/// security.identity empty or a valid enclave name. Empty when valid.
std::vector<TransportProblem> transport_problems(const TransportConfig& cfg);

/// "host:port" with host an IPv4 literal or "localhost" (read as 127.0.0.1) and port 1..65535
/// (decimal digits only). False for anything else.
bool parse_host_port(const std::string& text, std::array<std::uint8_t, 4>& ip, std::uint16_t& port);

/// Throws std::runtime_error "<key>: <what>, got <value>" for the first problem of cfg, e.g.
/// "transport.domain: must be in 0..232, got 300".
void validate(const TransportConfig& cfg);

}  // namespace shapeform::dds
