#include "dds/participant_factory.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <vector>

#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/rtps/attributes/ServerAttributes.h>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastrtps/utils/IPLocator.h>
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include "dds/handshake_filter.hpp"
#include "dds/library_log.hpp"
#include "dds/locators.hpp"
#include "dds/topic_qos.hpp"
#include "util/ipv4.hpp"

namespace shapeform::dds {
namespace {

namespace fdds = eprosima::fastdds::dds;
namespace frtps = eprosima::fastrtps::rtps;

[[noreturn]] void fail(const std::string& what) { throw std::runtime_error(what); }

std::string quoted(const std::string& s) { return "\"" + s + "\""; }

template <class T>
std::string str(const T& v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

/// The UDP ports bound in this network namespace (/proc/self/net/udp), nullopt where /proc cannot tell
/// (not Linux). A hint only: the kernel lists the table a page at a time, and a reading taken while
/// sockets open and close can miss sockets bound all along (the unit test beside such churn: a check of
/// the new participant's ports read here refused it in 4 of 5 runs of 100 participants).
std::optional<std::set<std::uint32_t>> host_udp_ports() {
  std::ifstream udp("/proc/self/net/udp");
  if (!udp) return std::nullopt;
  std::set<std::uint32_t> ports;
  std::string line;
  std::getline(udp, line);  // header
  while (std::getline(udp, line)) {
    // sl local_address rem_address ...
    std::istringstream fields(line);
    std::string sl, local;
    if (!(fields >> sl >> local)) continue;
    const auto colon = local.find(':');
    if (colon != std::string::npos) ports.insert(static_cast<std::uint32_t>(std::strtoul(local.c_str() + colon + 1, nullptr, 16)));
  }
  return ports;
}

/// This process's own IPv4 UDP sockets, by inode, and the port each is bound to (getsockname of each
/// descriptor in /proc/self/fd): exact, whatever other processes do. nullopt where /proc cannot tell.
std::optional<std::map<std::uint64_t, std::uint32_t>> own_udp_sockets() {
  namespace fs = std::filesystem;
  std::map<std::uint64_t, std::uint32_t> sockets;
  std::error_code ec;
  for (fs::directory_iterator it("/proc/self/fd", ec), end; !ec && it != end; it.increment(ec)) {
    const int fd = std::atoi(it->path().filename().c_str());
    int type = 0;
    socklen_t type_len = sizeof type;
    if (getsockopt(fd, SOL_SOCKET, SO_TYPE, &type, &type_len) != 0 || type != SOCK_DGRAM) continue;
    sockaddr_in addr{};
    socklen_t addr_len = sizeof addr;
    struct stat st {};
    if (getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &addr_len) == 0 && addr.sin_family == AF_INET &&
        fstat(fd, &st) == 0)
      sockets[static_cast<std::uint64_t>(st.st_ino)] = ntohs(addr.sin_port);
  }
  if (ec) return std::nullopt;
  return sockets;
}

/// True when `after` holds a metatraffic and a user unicast port of `domain` (slots 0..249) on sockets
/// that `before` did not hold: the participant created in between can be reached. Sockets, not ports:
/// a port another socket of this process held before and let go may be the new participant's (a
/// loaded test closing sockets by the hundred saw that refused as no free port). The two need not be
/// of the same slot (processes starting together take them in different orders). Fast DDS 2.9 creates
/// a participant even when every port slot it tried was taken, and that participant silently hears nothing.
bool gained_unicast_ports(int domain, const std::map<std::uint64_t, std::uint32_t>& before,
                          const std::map<std::uint64_t, std::uint32_t>& after) {
  const std::uint32_t port0 = metatraffic_unicast_port0(domain);
  bool metatraffic = false, user = false;
  for (const auto& [socket, p] : after) {
    if (p < port0 || p >= port0 + 500 || before.count(socket) != 0) continue;
    ((p - port0) % 2 == 0 ? metatraffic : user) = true;
  }
  return metatraffic && user;
}

/// Gives the participant the unicast ports of the lowest participant slot no socket on this host holds,
/// where its locators leave the port to Fast DDS (port 0). Fast DDS 2.9 numbers a process's participants
/// 0, 1, 2, ... for good (a rebuilt one takes the next number: its GUID prefix is new) and binds the slot of
/// that number or the next free one, so a process that had rebuilt its participant max_participants times
/// would bind ports the peers' initial announcements never probe (slots 0..max_participants-1), and two
/// such would never meet. A process that binds the slot first moves this one to the next (mutation), as
/// before, and so does a slot taken that the reading of the host's ports missed (host_udp_ports). Nothing
/// changes where /proc cannot tell or every slot is taken.
void place_in_free_slot(const TransportConfig& cfg, fdds::DomainParticipantQos& pq) {
  frtps::LocatorList_t& meta = pq.wire_protocol().builtin.metatrafficUnicastLocatorList;
  frtps::LocatorList_t& user = pq.wire_protocol().default_unicast_locator_list;
  const auto port_unset = [](const frtps::LocatorList_t& list) {
    return !list.empty() && std::all_of(list.begin(), list.end(), [](const frtps::Locator_t& l) { return l.port == 0; });
  };
  if (!port_unset(meta) || !port_unset(user)) return;
  const auto bound = host_udp_ports();
  if (!bound) return;
  const std::uint32_t port0 = metatraffic_unicast_port0(cfg.domain);
  for (std::uint32_t slot = 0; slot < static_cast<std::uint32_t>(cfg.max_participants); ++slot) {
    const std::uint32_t meta_port = port0 + 2u * slot, user_port = meta_port + 1u;
    if (bound->count(meta_port) != 0 || bound->count(user_port) != 0) continue;
    for (frtps::Locator_t& l : meta) l.port = meta_port;
    for (frtps::Locator_t& l : user) l.port = user_port;
    return;
  }
}

/// lan_address() of each address, each once, in their order.
std::vector<std::string> unique_lan_addresses(const std::vector<std::string>& addresses) {
  std::vector<std::string> out;
  for (const std::string& a : addresses) {
    const std::string bound = lan_address(a);
    if (std::find(out.begin(), out.end(), bound) == out.end()) out.push_back(bound);
  }
  return out;
}

/// The lan profile's whitelist and locators.
void set_lan(const TransportConfig& cfg, eprosima::fastdds::rtps::UDPv4TransportDescriptor& udp,
             fdds::DomainParticipantQos& pq) {
  auto& builtin = pq.wire_protocol().builtin;
  // validate() checked every address. With a whitelist, Fast DDS 2.9 binds every socket to the listed
  // addresses, sends multicast from one socket per listed interface (IP_MULTICAST_IF) and joins groups
  // on the listed interfaces only (UDPv4Transport::OpenInputChannel, OpenOutputChannel). A 127.x
  // address is the loopback interface, whitelisted as 127.0.0.1 (lan_address).
  for (const std::string& address : unique_lan_addresses(cfg.interfaces)) {
    udp.interfaceWhiteList.push_back(address);
  }
  // 0.0.0.0 port 0: Fast DDS fills in the participant slot's port and expands the address to each
  // allowed interface's (NormalizeLocators), so peers learn only addresses of those interfaces (lo
  // alone, which NormalizeLocators never lists, gives its fallback 127.0.0.1).
  builtin.metatrafficUnicastLocatorList.push_back(udp_locator({0, 0, 0, 0}, 0));
  pq.wire_protocol().default_unicast_locator_list.push_back(udp_locator({0, 0, 0, 0}, 0));
  if (cfg.peers.empty()) {
    // Multicast discovery: announcements to and from the domain's discovery group (port filled in:
    // 7400 + 250 domain), which is also the initial peer (Fast DDS copies it when the list is empty).
    builtin.metatrafficMulticastLocatorList.push_back(udp_locator(kMulticastGroup, 0));
  } else {
    // Unicast only: no multicast metatraffic locator (Fast DDS would add the default group when both
    // metatraffic lists are empty, and route endpoint discovery to it); each peer probed over the
    // participant slots 0..max_participants-1 (port 0, maxInitialPeersRange).
    for (const std::string& peer : unique_lan_addresses(cfg.peers)) {
      std::array<std::uint8_t, 4> ip{};
      util::parse_ipv4(peer, ip);
      builtin.initialPeersList.push_back(udp_locator(ip, 0));
    }
  }
}

}  // namespace

fdds::DomainParticipantQos participant_qos(const TransportConfig& cfg, const std::string& name) {
  validate(cfg);

  // Built by hand: the library's default participant QoS would pick up XML profiles
  // and builtin transports (UDPv4 on every interface + SHM).
  fdds::DomainParticipantQos pq;
  pq.name(name);
  pq.transport().use_builtin_transports = false;

  auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
  udp->maxInitialPeersRange = static_cast<std::uint32_t>(cfg.max_participants);
  if (cfg.socket_buffer_bytes > 0) {
    udp->sendBufferSize = static_cast<std::uint32_t>(cfg.socket_buffer_bytes);
    udp->receiveBufferSize = static_cast<std::uint32_t>(cfg.socket_buffer_bytes);
  }

  auto& builtin = pq.wire_protocol().builtin;
  // A participant whose ports are taken moves to the next participant slot, at most mutation_tries
  // times (Fast DDS default 100: the 102nd participant of a domain on one host got no port at all).
  // Slots 0..max_participants-1 are the ones the initial peers probe.
  builtin.mutation_tries = static_cast<std::uint32_t>(cfg.max_participants - 1);
  builtin.discovery_config.leaseDuration = eprosima::fastrtps::Duration_t(cfg.lease_s);
  builtin.discovery_config.leaseDuration_announcementperiod =
      eprosima::fastrtps::Duration_t(cfg.announce_s);
  builtin.discovery_config.initial_announcements.count = static_cast<std::uint32_t>(cfg.initial_announcements);
  builtin.discovery_config.initial_announcements.period = eprosima::fastrtps::Duration_t(cfg.initial_announce_s);

  if (cfg.profile == kLoopback) {
    udp->interfaceWhiteList.push_back("127.0.0.1");
    // Port 0: expanded to the metatraffic unicast ports of participant ids 0..maxInitialPeersRange-1.
    builtin.initialPeersList.push_back(loopback_locator(0));
    // Unicast locators only: with no multicast locator nothing is sent to or joined on multicast.
    builtin.metatrafficUnicastLocatorList.push_back(loopback_locator(0));
    pq.wire_protocol().default_unicast_locator_list.push_back(loopback_locator(0));
  } else if (cfg.profile == kLan) {
    set_lan(cfg, *udp, pq);
  } else if (cfg.profile == kDiscoveryServer) {
    std::array<std::uint8_t, 4> server_ip{};
    std::uint16_t server_port = 0;
    parse_host_port(cfg.discovery_server, server_ip, server_port);  // validate() checked it
    if (server_ip[0] == 127) udp->interfaceWhiteList.push_back("127.0.0.1");
    builtin.discovery_config.discoveryProtocol = frtps::DiscoveryProtocol_t::CLIENT;
    builtin.discovery_config.discoveryServer_client_syncperiod =
        eprosima::fastrtps::Duration_t(kDiscoveryServerSyncPeriod_s);
    frtps::RemoteServerAttributes remote;
    if (!remote.ReadguidPrefix(kDiscoveryServerPrefix)) {
      fail(std::string("discovery server guid prefix does not parse: ") + kDiscoveryServerPrefix);
    }
    remote.metatrafficUnicastLocatorList.push_back(udp_locator(server_ip, server_port));
    builtin.discovery_config.m_DiscoveryServers.push_back(remote);
  }

  // Secured: the authentication handshakes go to the participant they name only (dds/handshake_filter.hpp).
  if (cfg.security.enabled) {
    pq.transport().user_transports.push_back(with_directed_handshakes(udp));
  } else {
    pq.transport().user_transports.push_back(udp);
  }

  if (cfg.static_edp) {
    // validate() refused it with a discovery server (whose clients keep simple EDP) and with security.
    builtin.discovery_config.use_SIMPLE_EndpointDiscoveryProtocol = false;
    builtin.discovery_config.use_STATIC_EndpointDiscoveryProtocol = true;
    builtin.discovery_config.static_edp_xml_config(("data://" + static_edp_description(cfg)).c_str());
  }

  // Where this participant runs, announced in discovery so that a tool can tell the operator.
  char host[256] = {};
  if (gethostname(host, sizeof host - 1) != 0) host[0] = '\0';
  auto& props = pq.properties().properties();
  props.emplace_back(kHostProperty, std::string(host), true);
  props.emplace_back(kPidProperty, std::to_string(getpid()), true);
  if (cfg.security.enabled) {
    for (const auto& [key, value] : security_properties(cfg.security)) props.emplace_back(key, value);
  }
  return pq;
}

std::string static_edp_description(const TransportConfig& cfg) {
  validate(cfg);
  const auto reliability = [](fdds::ReliabilityQosPolicyKind k) {
    return k == fdds::RELIABLE_RELIABILITY_QOS ? "RELIABLE_RELIABILITY_QOS" : "BEST_EFFORT_RELIABILITY_QOS";
  };
  const auto durability = [](fdds::DurabilityQosPolicyKind k) {
    switch (k) {
      case fdds::TRANSIENT_LOCAL_DURABILITY_QOS: return "TRANSIENT_LOCAL_DURABILITY_QOS";
      case fdds::TRANSIENT_DURABILITY_QOS: return "TRANSIENT_DURABILITY_QOS";
      case fdds::PERSISTENT_DURABILITY_QOS: return "PERSISTENT_DURABILITY_QOS";
      default: return "VOLATILE_DURABILITY_QOS";
    }
  };
  const auto locators = [](std::ostream& os, const char* tag, const frtps::LocatorList_t& list) {
    for (const frtps::Locator_t& loc : list) {
      os << "<" << tag << " address=\"" << frtps::IPLocator::ip_to_string(loc) << "\" port=\"" << loc.port
         << "\"/>";
    }
  };
  // The name is only a label: Fast DDS 2.9 matches a peer's endpoints by user id, whatever its name.
  std::ostringstream os;
  os << "<staticdiscovery><participant><name>shapeform</name>";
  for (const TopicId id : kAllTopics) {
    // A vehicle's topics are ROS 2's, whose robots announce them by simple discovery (transport.static_edp
    // is refused with vehicle.interface: ros2).
    if (is_vehicle_topic(id)) continue;
    const fdds::DataWriterQos w = writer_qos(id);
    const fdds::DataReaderQos r = reader_qos(id, cfg);
    const auto common = [&](std::int16_t user_id, fdds::ReliabilityQosPolicyKind rel,
                            fdds::DurabilityQosPolicyKind dur) {
      os << "<userId>" << user_id << "</userId><topicName>" << topic_name(id) << "</topicName><topicDataType>"
         << type_name(id) << "</topicDataType><topicKind>" << (is_keyed(id) ? "WITH_KEY" : "NO_KEY")
         << "</topicKind><reliabilityQos>" << reliability(rel) << "</reliabilityQos><durabilityQos>"
         << durability(dur) << "</durabilityQos>";
    };
    os << "<writer>";
    common(w.endpoint().user_defined_id, w.reliability().kind, w.durability().kind);
    locators(os, "unicastLocator", w.endpoint().unicast_locator_list);
    locators(os, "multicastLocator", w.endpoint().multicast_locator_list);
    os << "</writer><reader>";
    common(r.endpoint().user_defined_id, r.reliability().kind, r.durability().kind);
    locators(os, "unicastLocator", r.endpoint().unicast_locator_list);
    locators(os, "multicastLocator", r.endpoint().multicast_locator_list);
    os << "</reader>";
  }
  os << "</participant></staticdiscovery>";
  return os.str();
}

fdds::DomainParticipant* create_participant(const TransportConfig& cfg, const std::string& name,
                                            fdds::DomainParticipantListener* listener,
                                            const std::vector<unsigned char>& user_data) {
  if (cfg.security.enabled) {
    if (cfg.security.identity.empty()) {
      throw SecurityError("security: " + quoted(name) + " has no security.identity (set it to an enclave of " +
                          cfg.security.keystore + "/enclaves)");
    }
    check_enclave(cfg.security);  // the files named in the error, before Fast DDS says less
  }
  route_library_log();  // before the first participant: Fast DDS would print its errors on stdout
  fdds::DomainParticipantQos pq = participant_qos(cfg, name);
  place_in_free_slot(cfg, pq);
  if (!user_data.empty()) pq.user_data().data_vec(std::vector<eprosima::fastrtps::rtps::octet>(user_data.begin(), user_data.end()));
  // Invariant of the project: never builtin transports (they open every interface and SHM).
  if (pq.transport().use_builtin_transports || pq.transport().user_transports.empty()) {
    fail("create_participant: refusing a participant with builtin transports");
  }
  auto* factory = fdds::DomainParticipantFactory::get_instance();
  if (factory == nullptr) fail("create_participant: DomainParticipantFactory unavailable");
  const auto sockets_before = own_udp_sockets();
  fdds::DomainParticipant* participant =
      // Mask none: the listener hears the participant-level callbacks (discovery, authentication), which
      // no mask gates; with data_on_readers in its mask it would take every sample from the readers'
      // own listeners (DataReaderImpl asks the subscriber's, then the participant's, listener first).
      factory->create_participant(static_cast<fdds::DomainId_t>(cfg.domain), pq, listener, fdds::StatusMask::none());
  if (participant == nullptr && cfg.security.enabled) {
    // check_enclave() found the files sound: what is left is the permissions' content.
    throw SecurityError("security: Fast DDS refused the enclave " + enclave_dir(cfg.security) + " for " +
                        quoted(name) + " (see its log above): does permissions.xml grant the subject of cert.pem (" +
                        "CN=" + cfg.security.identity + " from scripts/make_keystore.sh) on domain " + str(cfg.domain) +
                        ", and is the grant's validity current?");
  }
  if (participant == nullptr) {
    fail("create_participant failed for " + quoted(name) + " on " + describe(cfg) +
         " (see Fast DDS log above; ports in use or bad interface address?)");
  }
  const auto sockets_after = own_udp_sockets();
  if (sockets_before && sockets_after && !gained_unicast_ports(cfg.domain, *sockets_before, *sockets_after)) {
    factory->delete_participant(participant);
    fail("create_participant: " + quoted(name) + " found no free participant port on domain " + str(cfg.domain) +
         ": this host already runs transport.max_participants (" + str(cfg.max_participants) +
         ") participants on it; raise transport.max_participants or use another domain" +
         (cfg.profile == kLan ? std::string(" (or transport.interfaces names no address of this host's interfaces)")
                              : std::string()));
  }
  return participant;
}

void delete_participant(fdds::DomainParticipant* participant) {
  if (participant == nullptr) return;
  // Children first (publishers, subscribers, their endpoints, topics), then the participant itself,
  // which announces its departure so peers drop it at once.
  participant->delete_contained_entities();
  fdds::DomainParticipantFactory::get_instance()->delete_participant(participant);
}

}  // namespace shapeform::dds
