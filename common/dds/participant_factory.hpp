#pragma once
/// The ONE place DDS participants are made. Every participant of the project is built from a
/// TransportConfig profile by create_participant(); builtin transports are never used, so
/// traffic stays on loopback unless a profile explicitly asks for more.
/// Fast DDS types: for the dds library (Node, discovery), the benchmark's raw baseline and the tests;
/// processes get their participant from a dds::Node and describe it with dds/participant.hpp.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fastdds/dds/domain/qos/DomainParticipantQos.hpp>

#include "dds/locators.hpp"
#include "dds/participant.hpp"
#include "protocol/transport.hpp"

namespace shapeform::dds {

/// Guid prefix of discovery server id 0, as `fastdds discovery -i 0` uses.
inline constexpr const char* kDiscoveryServerPrefix = "44.53.00.5f.45.50.52.4f.53.49.4d.41";
/// Discovery-server client sync period, seconds (Fast DDS default 0.45 s; 0.1 s discovers faster).
inline constexpr double kDiscoveryServerSyncPeriod_s = 0.1;
/// Property names every participant of the project announces in discovery (propagated
/// participant properties): its host name and process id, so a tool can say where it runs.
inline constexpr const char* kHostProperty = "shapeform.host";
inline constexpr const char* kPidProperty = "shapeform.pid";

/// The participant QoS of a transport profile, built by hand (never the factory default, which an XML
/// file could change): builtin transports off, one UDPv4 descriptor, no shared memory.
///  - "loopback": UDPv4 whitelisted to 127.0.0.1; initial peer 127.0.0.1 port 0 expanded to
///    participant ids 0..max_participants-1; metatraffic and default unicast locators on 127.0.0.1,
///    no multicast locator at all (pure unicast on lo).
///  - "lan": UDPv4 whitelisted to `interfaces` (all when empty): every socket bound to them, multicast
///    sent and joined on them only; metatraffic and default unicast locators 0.0.0.0 (Fast DDS lists
///    each allowed interface's address). No `peers`: multicast discovery, metatraffic multicast
///    locator kMulticastGroup (port 7400 + 250 domain), which is also the initial peer. With `peers`:
///    unicast initial peers (port 0, ids 0..max_participants-1) and no multicast locator at all, so
///    nothing is sent to or joined on a group. List this host in `peers` too if local participants
///    must meet.
///  - "discovery-server": CLIENT of server id 0 at `discovery_server` "host:port" (host an IPv4
///    address or "localhost"); UDPv4 whitelisted to 127.0.0.1 when the host is a loopback address.
/// A participant whose port slot is taken moves to the next one, up to slot max_participants - 1
/// (builtin.mutation_tries; the library's default of 100 left the 102nd participant on a host deaf).
/// Lease and announcement period come from lease_s / announce_s; socket_buffer_bytes > 0 sets the
/// UDP send and receive buffer sizes (the kernel caps them at net.core.rmem_max / wmem_max).
/// Every participant announces its host name and process id in discovery (the propagated
/// properties kHostProperty and kPidProperty), for shapeform_topics.
/// multicast_data (loopback, lan without peers) changes no participant setting: see
/// data_multicast_locator(). static_edp replaces simple endpoint discovery by STATIC EDP with
/// static_edp_description(cfg), given inline ("data://"). security.enabled adds the DDS Security plugin properties of the enclave
/// (protocol/security.hpp: security_properties) and wraps the UDPv4 descriptor so that each authentication
/// handshake is sent to the participant it names only (dds/handshake_filter.hpp: with_directed_handshakes).
/// Pure: creates nothing.
/// Throws std::runtime_error naming the offending field (validate(): "transport.domain: must be in 0..232,
/// got 300").
eprosima::fastdds::dds::DomainParticipantQos participant_qos(const TransportConfig& cfg,
                                                             const std::string& name);

/// The STATIC EDP description (Fast DDS's <staticdiscovery> XML) every participant of a static_edp swarm
/// is given: one <participant> with a writer and a reader of every topic of the topic table, each with
/// its static_edp_user_id, topic and type name, key kind, reliability and durability (from writer_qos /
/// reader_qos) and the reader's own locators (reader_qos(id, cfg): the State multicast group when
/// multicast_data is set; none otherwise, so a peer sends to the reader's participant's default unicast
/// locators). Fast DDS 2.9 (EDPStatic, XMLEndpointParser::lookforReader) finds a peer's endpoint by its
/// user id alone, whatever the peer's participant name, so this one description covers every process
/// (agents, groups, supervisor, tools, bench) without knowing the swarm's members: a peer announces the
/// user id and entity id of each endpoint it has in its participant announcement. Pure; throws like
/// participant_qos().
std::string static_edp_description(const TransportConfig& cfg);

/// Creates a participant on cfg.domain from participant_qos(cfg, name). Never returns null:
/// throws SecurityError (protocol/security.hpp) when security is enabled and the enclave fails check_enclave()
/// or Fast DDS refuses it, never creating an unsecured participant instead; otherwise
/// std::runtime_error naming the problem, including a participant that got no unicast port
/// (every participant slot it may take, max_participants of them, is in use on this host: Fast DDS
/// itself would create it deaf). Free it with delete_participant().
/// `listener` (optional, outliving the participant) hears discovery and authentication from the first
/// announcement on; it is installed with an empty status mask, so it never hears endpoint statuses.
/// `user_data` (optional) is announced in the participant's USER_DATA (dds::Node: its process identity).
eprosima::fastdds::dds::DomainParticipant* create_participant(
    const TransportConfig& cfg, const std::string& name,
    eprosima::fastdds::dds::DomainParticipantListener* listener = nullptr,
    const std::vector<unsigned char>& user_data = {});

/// delete_contained_entities() then deletes the participant. Null is a no-op. Never throws.
void delete_participant(eprosima::fastdds::dds::DomainParticipant* participant);

}  // namespace shapeform::dds
