#pragma once
/// What is on a domain: every topic some participant writes or reads, with its writers and readers,
/// as DDS discovery tells them (shapeform_topics). No Fast DDS types in this header.
#include <atomic>
#include <string>
#include <vector>

#include "protocol/transport.hpp"

namespace shapeform::dds {

/// One writer or reader of a topic, as its participant announced it.
struct EndpointSeen {
  std::string participant;  ///< the participant's name ("shapeform_agent_3"); "" when it gave none
  std::string host;         ///< host name it announced (our participants do), else its first unicast address
  int pid = -1;             ///< process id it announced; -1 when it did not (another vendor)
  std::string reliability;  ///< "reliable" | "best_effort"
  std::string durability;   ///< "volatile" | "transient_local" | "transient" | "persistent"
  std::string type;         ///< registered type name
  std::string guid;         ///< the endpoint's GUID, as Fast DDS prints it
};

/// One topic seen on the domain.
struct TopicSeen {
  std::string name;
  std::vector<std::string> types;  ///< every type name its endpoints use (one, unless they disagree)
  std::vector<EndpointSeen> writers, readers;  ///< sorted by participant, then guid
};

/// Joins cfg's domain as participant `name` (create_participant: the transport profiles), listens
/// wait_s seconds (returning early when `stop` becomes true), and returns every topic any other
/// participant writes or reads, sorted by name. Endpoints that left during the wait are not listed.
/// Creates no topic, writer or reader. Throws std::runtime_error like create_participant.
std::vector<TopicSeen> discover_topics(const TransportConfig& cfg, const std::string& name, double wait_s,
                                       const std::atomic<bool>* stop = nullptr);

}  // namespace shapeform::dds
