#include "protocol/transport.hpp"

#include <cmath>
#include <stdexcept>

#include "util/ipv4.hpp"

namespace shapeform::dds {
namespace {

namespace params = core::params;
using P = params::Param<TransportConfig>;

/// Largest max_participants accepted (ids probed per initial peer; about 100 participants per host is
/// the practical limit, and ids from 120 up use ports of the next domain's block).
constexpr int kMaxParticipantsLimit = 230;

template <class V, class Field>
P param(params::Type type, std::string key, std::string unit, params::Range range, std::string doc,
        std::string range_note, Field field) {
  return params::make<TransportConfig, V>(type, std::move(key), std::move(unit), range, std::move(doc), field,
                                          std::move(range_note));
}

/// What transport.discovery_server accepts, as the docs and the error both say it.
const std::string kHostPortRule = "host:port with host an IPv4 address or localhost and port 1..65535";
constexpr unsigned long kMaxPort = 65535;
/// Where transport.multicast_data works, as the docs and the error both say it.
const std::string kMulticastDataRule =
    "needs `profile: loopback`, `lan` without `peers`, or `discovery-server` with a server on "
    "`127.x`/`localhost`";

/// Where transport.static_edp works, as the docs and the errors say it.
const std::string kStaticEdpRule = "not with `profile: discovery-server` nor `security.enabled`";

std::vector<P> build_table() {
  using params::Type;
  const std::string ipv4_list = "list of IPv4 addresses (dotted quads)";
  std::vector<P> t;
  {
    P profile = param<std::string>(
        Type::Choice, "transport.profile", "", {}, "transport profile", "",
        [](auto& c) -> auto& { return c.profile; });
    for (const char* name : kProfiles) profile.choices.emplace_back(name);
    t.push_back(std::move(profile));
  }
  t.push_back(param<long long>(
      Type::Integer, "transport.domain", "", params::integers(0, kMaxDomainId), "DDS domain id", "",
      [](auto& c) -> auto& { return c.domain; }));
  t.push_back(param<long long>(
      Type::Integer, "transport.max_participants", "participants", params::integers(1, kMaxParticipantsLimit),
      "participant port slots of the domain on one host: a participant takes the first free one of slots "
      "0..max-1 (another process's participant holds each taken one), and with loopback or lan peers the "
      "initial peers probe exactly these; a participant that finds all taken is refused with an error (Fast "
      "DDS "
      "alone would create it deaf). At most this many processes (agents, supervisor, tools) per domain and "
      "host. "
      "Slots from 120 up use ports of the next domain's block",
      "", [](auto& c) -> auto& { return c.max_participants; }));
  t.push_back(param<std::vector<std::string>>(
      Type::TextList, "transport.interfaces", "", {},
      "lan: addresses of this host's interfaces to use (empty = all): every datagram, unicast or multicast, is "
      "sent from and received on these only, multicast groups are joined on these only; a 127.x address (in "
      "peers too) is the loopback interface, bound as 127.0.0.1 (Fast DDS binds only addresses an interface "
      "carries)",
      ipv4_list, [](auto& c) -> auto& { return c.interfaces; }));
  t.push_back(param<std::vector<std::string>>(
      Type::TextList, "transport.peers", "", {},
      "lan: unicast peer addresses, for networks without multicast: discovery probes participant slots "
      "0..max_participants-1 of each, and nothing is sent to or joined on a multicast group (list this "
      "host's own address too if its processes must meet). Empty = multicast discovery on 239.255.0.1, port "
      "7400 + 250 domain",
      ipv4_list, [](auto& c) -> auto& { return c.peers; }));
  t.push_back(param<std::string>(
      Type::Text, "transport.discovery_server", "", {}, "discovery-server: address of the server",
      kHostPortRule,
      [](auto& c) -> auto& { return c.discovery_server; }));
  t.push_back(param<double>(
      Type::Real, "transport.lease_s", "s", params::above(0),
      "participant lease duration: peers drop a participant they heard nothing from for this long (a killed "
      "process is dropped after it). A process whose loop stalled longer than `lease_s - announce_s` "
      "recreates its participant, which everyone discovers afresh (docs/RELIABILITY.md)",
      "",
      [](auto& c) -> auto& { return c.lease_s; }));
  t.push_back(param<double>(
      Type::Real, "transport.announce_s", "s", params::above(0),
      "participant announcement period (every message renews the lease; announcements also flow when "
      "nothing else does)",
      " and `< lease_s`", [](auto& c) -> auto& { return c.announce_s; }));
  t.push_back(param<long long>(
      Type::Integer, "transport.initial_announcements", "announcements", params::integers(0, 1000),
      "announcements a new participant sends every `initial_announce_s` before `announce_s` takes over (0: the "
      "first periodic one only); each goes to every participant slot probed and to every participant known",
      "", [](auto& c) -> auto& { return c.initial_announcements; }));
  t.push_back(param<double>(
      Type::Real, "transport.initial_announce_s", "s", params::above(0),
      "interval of the initial announcements", "",
      [](auto& c) -> auto& { return c.initial_announce_s; }));
  t.push_back(param<long long>(
      Type::Integer, "transport.socket_buffer_bytes", "bytes", params::integers(0, 2147483647),
      "UDP send/receive buffer size (0 = OS default); the kernel silently caps it at `net.core.rmem_max` / "
      "`wmem_max`",
      "", [](auto& c) -> auto& { return c.socket_buffer_bytes; }));
  t.push_back(param<bool>(
      Type::Bool, "transport.multicast_data", "", {},
      "readers of the state topics (`shapeform/state`, `shapeform/state_batch`) listen on the multicast group "
      "239.255.0.1, port 7400 + 250 domain + 1, "
      "instead of a unicast port, so a writer sends one datagram per sample instead of one per reader (the "
      "kernel or the switch fans it out); the group is joined and sent on the profile's interfaces only (`lo` "
      "for loopback and a discovery server on loopback, `transport.interfaces` for lan). Every other topic "
      "stays unicast",
      "; " + kMulticastDataRule,
      [](auto& c) -> auto& { return c.multicast_data; }));
  t.push_back(param<bool>(
      Type::Bool, "transport.static_edp", "", {},
      "static endpoint discovery (Fast DDS STATIC EDP): no endpoint-discovery traffic (SEDP: reliable, per pair of "
      "participants); each knows every endpoint a peer can have from one description made from the topic table, "
      "and which ones it has from its announcements. Every process of the swarm must set it alike",
      "; " + kStaticEdpRule, [](auto& c) -> auto& { return c.static_edp; }));
  t.push_back(param<bool>(
      Type::Bool, "security.enabled", "", {},
      "DDS Security: every participant authenticated (PKI-DH: certificates of the keystore's identity "
      "authority), access-controlled (signed permissions per identity: only the supervisor commands) and its "
      "discovery and data encrypted (AES-GCM); participants without valid keys are refused. A bad or missing key "
      "file stops the program with exit 2 (docs/SECURITY.md)",
      "; not with multicast discovery (`lan` without `transport.peers`), two or more `transport.interfaces`, "
      "nor `discovery-server`",
      [](auto& c) -> auto& { return c.security.enabled; }));
  t.push_back(param<std::string>(
      Type::Text, "security.keystore", "", {},
      "keystore folder in the sros2 layout (`scripts/make_keystore.sh DIR --agents N`); the process uses "
      "`DIR/enclaves/<security.identity>/`",
      "a folder; required when `security.enabled`", [](auto& c) -> auto& { return c.security.keystore; }));
  t.push_back(param<std::string>(
      Type::Text, "security.identity", "", {},
      "the enclave to use; empty = from the role: `supervisor`, `agent_K` (K = the agent id, or a group's "
      "first id), `viewer` (shapeform_view, shapeform_echo, shapeform_topics)",
      "empty or letters, digits, `_`, `-`, `.`", [](auto& c) -> auto& { return c.security.identity; }));
  return t;
}

std::string quoted(const std::string& s) { return "\"" + s + "\""; }

std::string list_text(const std::vector<std::string>& items) {
  std::string out = "[";
  for (std::size_t i = 0; i < items.size(); ++i) out += (i ? ", " : "") + quoted(items[i]);
  return out + "]";
}

}  // namespace

const std::vector<params::Param<TransportConfig>>& transport_table() {
  static const std::vector<P> table = build_table();
  return table;
}

bool parse_host_port(const std::string& text, std::array<std::uint8_t, 4>& ip, std::uint16_t& port) {
  const auto colon = text.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == text.size()) return false;
  const std::string host = text.substr(0, colon);
  if (!util::parse_ipv4(host == "localhost" ? "127.0.0.1" : host, ip)) return false;
  unsigned long value = 0;
  for (std::size_t i = colon + 1; i < text.size(); ++i) {
    const char ch = text[i];
    if (ch < '0' || ch > '9' || value > kMaxPort) return false;
    value = value * 10 + static_cast<unsigned long>(ch - '0');
  }
  if (value < 1 || value > kMaxPort) return false;
  port = static_cast<std::uint16_t>(value);
  return true;
}

std::vector<TransportProblem> transport_problems(const TransportConfig& cfg) {
  std::vector<TransportProblem> out;
  // Numbers against their declared ranges (finite first).
  for (const P& p : transport_table()) {
    const params::Value v = p.get(cfg);
    double x = 0.0;
    std::string got;
    if (p.type == params::Type::Real) {
      x = std::get<double>(v);
      got = params::format_number(x);
      if (!std::isfinite(x)) {
        out.push_back({p.key, "must be finite", got, ""});
        continue;
      }
    } else if (p.type == params::Type::Integer) {
      x = static_cast<double>(std::get<long long>(v));
      got = std::to_string(std::get<long long>(v));
    } else {
      continue;
    }
    if (!p.range.contains(x)) out.push_back({p.key, p.range.text(), got, ""});
  }
  bool known_profile = false;
  for (const char* name : kProfiles) known_profile = known_profile || cfg.profile == name;
  if (!known_profile) {
    out.push_back(
        {"transport.profile", "must be one of " + params::join({std::begin(kProfiles), std::end(kProfiles)}, ", "),
         quoted(cfg.profile), ""});
  }
  for (const auto& [key, list] :
       {std::pair{"transport.interfaces", &cfg.interfaces}, std::pair{"transport.peers", &cfg.peers}}) {
    for (const std::string& a : *list) {
      if (!util::is_ipv4(a)) {
        out.push_back(
            {key, "must be a list of IPv4 addresses (" + quoted(a) + " is not one)", list_text(*list), ""});
        break;
      }
    }
  }
  std::array<std::uint8_t, 4> ip{};
  std::uint16_t port = 0;
  if (!parse_host_port(cfg.discovery_server, ip, port)) {
    out.push_back({"transport.discovery_server",
                   "must be " + kHostPortRule,
                   quoted(cfg.discovery_server), ""});
  }
  if (std::isfinite(cfg.lease_s) && std::isfinite(cfg.announce_s) && cfg.lease_s > 0 && cfg.announce_s > 0 &&
      !(cfg.announce_s < cfg.lease_s)) {
    out.push_back({"transport.announce_s",
                   "must be < transport.lease_s (" + params::format_number(cfg.lease_s) + ")",
                   params::format_number(cfg.announce_s), "transport.lease_s"});
  }
  if (cfg.multicast_data && cfg.profile == kLan && !cfg.peers.empty()) {
    // The peers variant is for networks that carry no multicast: its participants join no group, so
    // state readers listening on one would hear nothing.
    out.push_back({"transport.multicast_data",
                   "cannot be used with transport.peers (lan with peers sends no multicast at all; remove the "
                   "peers for multicast discovery and data)",
                   "true", "transport.peers"});
  } else if (cfg.multicast_data && !cfg.on_loopback() && cfg.profile != kLan) {
    out.push_back({"transport.multicast_data",
                   "needs transport.profile loopback, lan without peers, or discovery-server with a server on "
                   "127.x (profile is " + cfg.profile + ")",
                   "true", "transport.profile"});
  }
  if (cfg.static_edp && cfg.profile == kDiscoveryServer) {
    // Fast DDS 2.9 builds a discovery-server client with simple endpoint discovery whatever the setting
    // (PDPClient), so its endpoints would never match those of static peers.
    out.push_back({"transport.static_edp",
                   "cannot be used with transport.profile discovery-server (its clients always use the "
                   "server's endpoint discovery; use loopback or lan)",
                   "true", "transport.profile"});
  } else if (cfg.static_edp && cfg.security.enabled) {
    // Fast DDS 2.9 matches static endpoints on every announcement of a participant
    // (PDPListener -> EDPStatic::assignRemoteEndpoints), not only once it is authenticated, and the
    // combination is untested upstream: refused rather than a secured swarm that might match too early.
    out.push_back({"transport.static_edp",
                   "cannot be used with security.enabled (Fast DDS 2.9 matches static endpoints outside "
                   "the authentication step; use simple endpoint discovery with security)",
                   "true", "security.enabled"});
  }
  if (cfg.security.enabled && cfg.security.keystore.empty()) {
    out.push_back({"security.keystore",
                   "must name a keystore folder when security.enabled is true (make one: "
                   "scripts/make_keystore.sh DIR --agents N)",
                   "\"\"", "security.enabled"});
  }
  if (cfg.security.enabled && cfg.profile == kDiscoveryServer) {
    // Measured with Fast DDS 2.9.1: a secured server announces a GUID prefix derived from its certificate,
    // not the well-known one its clients look for, so nobody meets; and clients and server then abort in
    // SecurityManager::encode_rtps_message. Refused rather than a swarm that never forms.
    out.push_back({"security.enabled",
                   "cannot be used with transport.profile discovery-server (Fast DDS 2.9.1 cannot secure a "
                   "discovery server: use loopback or lan, docs/SECURITY.md)",
                   "true", "transport.profile"});
  }
  if (cfg.security.enabled && cfg.profile == kLan && cfg.peers.empty()) {
    // Read in 2.9.1 and seen on the lab's hosts (docs/SECURITY.md, Deploying on real hosts): with
    // multicast discovery a participant hears announcements on two receive threads (the group's and its
    // unicast port's), and SecurityManager::match_builtin_endpoints fills one shared temporary proxy
    // without a lock, so two participants discovered at once can leave one's handshake endpoints
    // unmatched: that pair never authenticates. Fixed upstream in 2.9.2 (eProsima/Fast-DDS#3373).
    out.push_back({"security.enabled",
                   "cannot be used with multicast discovery (transport.profile lan without transport.peers): "
                   "Fast DDS 2.9.1 can leave pairs of secured participants that discover each other at the "
                   "same moment unable to authenticate; list every host's address in transport.peers "
                   "(docs/SECURITY.md, Deploying on real hosts)",
                   "true", "transport.peers"});
  } else if (cfg.security.enabled && cfg.profile == kLan && cfg.interfaces.size() > 1) {
    // The same race with unicast discovery: each address of the list is its own socket and receive
    // thread for the participant's port (seen with `ss` in a lab namespace; no list: one socket on all).
    out.push_back({"security.enabled",
                   "cannot be used with more than one address in transport.interfaces (each is a receive "
                   "thread of its own, and Fast DDS 2.9.1 can leave pairs of secured participants discovered "
                   "on two threads at once unable to authenticate); list one address, or none for all "
                   "interfaces (docs/SECURITY.md, Deploying on real hosts)",
                   "true", "transport.interfaces"});
  }
  if (!cfg.security.identity.empty() && !valid_identity(cfg.security.identity)) {
    out.push_back({"security.identity", "must be empty or an enclave name (letters, digits, _ - .)",
                   quoted(cfg.security.identity), ""});
  }
  return out;
}

void validate(const TransportConfig& cfg) {
  const auto problems = transport_problems(cfg);
  if (!problems.empty()) {
    const TransportProblem& p = problems.front();
    throw std::runtime_error(p.key + ": " + p.what + ", got " + p.got);
  }
}

}  // namespace shapeform::dds
