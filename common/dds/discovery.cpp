#include "dds/discovery.hpp"

#include <algorithm>
#include <chrono>
#include <map>
#include <mutex>
#include <sstream>
#include <thread>
#include <tuple>
#include <cstdlib>

#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fastdds/rtps/participant/ParticipantDiscoveryInfo.h>
#include <fastdds/rtps/reader/ReaderDiscoveryInfo.h>
#include <fastdds/rtps/writer/WriterDiscoveryInfo.h>
#include <fastrtps/utils/IPLocator.h>

#include "dds/participant_factory.hpp"

namespace shapeform::dds {
namespace {

namespace fdds = eprosima::fastdds::dds;
namespace frtps = eprosima::fastrtps::rtps;

template <class T>
std::string text(const T& v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

std::string reliability_name(fdds::ReliabilityQosPolicyKind k) {
  return k == fdds::RELIABLE_RELIABILITY_QOS ? "reliable" : "best_effort";
}

std::string durability_name(fdds::DurabilityQosPolicyKind k) {
  switch (k) {
    case fdds::VOLATILE_DURABILITY_QOS: return "volatile";
    case fdds::TRANSIENT_LOCAL_DURABILITY_QOS: return "transient_local";
    case fdds::TRANSIENT_DURABILITY_QOS: return "transient";
    case fdds::PERSISTENT_DURABILITY_QOS: return "persistent";
  }
  return "?";
}

struct Participant {
  std::string name, host;
  int pid = -1;
};

struct Endpoint {
  std::string topic;
  bool writer = false;
  frtps::GuidPrefix_t participant;
  EndpointSeen seen;  ///< participant, host and pid filled at the end
};

/// Collects what discovery reports. Runs on Fast DDS's threads: it only copies, under a mutex.
class Collector final : public fdds::DomainParticipantListener {
 public:
  void on_participant_discovery(fdds::DomainParticipant*, frtps::ParticipantDiscoveryInfo&& info) override {
    const frtps::ParticipantProxyData& d = info.info;
    std::lock_guard<std::mutex> lock(mutex_);
    if (info.status == frtps::ParticipantDiscoveryInfo::REMOVED_PARTICIPANT ||
        info.status == frtps::ParticipantDiscoveryInfo::DROPPED_PARTICIPANT) {
      participants_.erase(d.m_guid.guidPrefix);
      for (auto it = endpoints_.begin(); it != endpoints_.end();)
        it = it->second.participant == d.m_guid.guidPrefix ? endpoints_.erase(it) : std::next(it);
      return;
    }
    Participant p;
    p.name = d.m_participantName.to_string();
    for (auto it = d.m_properties.begin(); it != d.m_properties.end(); ++it) {
      if (it->first() == kHostProperty) p.host = it->second();
      if (it->first() == kPidProperty) p.pid = std::atoi(it->second().c_str());
    }
    if (p.host.empty()) {
      // Another vendor (or an older build): the address it is reached at says where it runs.
      for (const frtps::Locator_t& loc : d.metatraffic_locators.unicast) {
        p.host = frtps::IPLocator::ip_to_string(loc);
        break;
      }
    }
    participants_[d.m_guid.guidPrefix] = p;
  }

  void on_publisher_discovery(fdds::DomainParticipant*, frtps::WriterDiscoveryInfo&& info) override {
    const frtps::WriterProxyData& d = info.info;
    endpoint(info.status == frtps::WriterDiscoveryInfo::REMOVED_WRITER, true, d.guid(), d.topicName().to_string(), d.typeName().to_string(), d.m_qos.m_reliability.kind,
             d.m_qos.m_durability.kind);
  }

  void on_subscriber_discovery(fdds::DomainParticipant*, frtps::ReaderDiscoveryInfo&& info) override {
    const frtps::ReaderProxyData& d = info.info;
    endpoint(info.status == frtps::ReaderDiscoveryInfo::REMOVED_READER, false, d.guid(), d.topicName().to_string(),
             d.typeName().to_string(), d.m_qos.m_reliability.kind, d.m_qos.m_durability.kind);
  }

  /// The topics seen so far, sorted.
  std::vector<TopicSeen> topics() const {
    std::lock_guard<std::mutex> lock(mutex_);
    std::map<std::string, TopicSeen> by_name;
    for (const auto& [guid, e] : endpoints_) {
      TopicSeen& t = by_name[e.topic];
      t.name = e.topic;
      EndpointSeen s = e.seen;
      const auto p = participants_.find(e.participant);
      if (p != participants_.end()) {
        s.participant = p->second.name;
        s.host = p->second.host;
        s.pid = p->second.pid;
      }
      if (std::find(t.types.begin(), t.types.end(), s.type) == t.types.end()) t.types.push_back(s.type);
      (e.writer ? t.writers : t.readers).push_back(std::move(s));
    }
    std::vector<TopicSeen> out;
    for (auto& [name, t] : by_name) {
      const auto order = [](const EndpointSeen& a, const EndpointSeen& b) {
        return std::tie(a.participant, a.guid) < std::tie(b.participant, b.guid);
      };
      std::sort(t.writers.begin(), t.writers.end(), order);
      std::sort(t.readers.begin(), t.readers.end(), order);
      std::sort(t.types.begin(), t.types.end());
      out.push_back(std::move(t));
    }
    return out;
  }

 private:
  void endpoint(bool removed, bool writer, const frtps::GUID_t& guid, std::string topic, std::string type,
                fdds::ReliabilityQosPolicyKind reliability, fdds::DurabilityQosPolicyKind durability) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (removed) {
      endpoints_.erase(guid);
      return;
    }
    Endpoint e;
    e.topic = std::move(topic);
    e.writer = writer;
    e.participant = guid.guidPrefix;
    e.seen.type = std::move(type);
    e.seen.reliability = reliability_name(reliability);
    e.seen.durability = durability_name(durability);
    e.seen.guid = text(guid);
    endpoints_[guid] = std::move(e);
  }

  mutable std::mutex mutex_;
  std::map<frtps::GuidPrefix_t, Participant> participants_;
  std::map<frtps::GUID_t, Endpoint> endpoints_;
};

}  // namespace

std::vector<TopicSeen> discover_topics(const TransportConfig& cfg, const std::string& name, double wait_s,
                                       const std::atomic<bool>* stop) {
  Collector collector;
  fdds::DomainParticipant* participant = create_participant(cfg, name, &collector);
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(wait_s);
  while (std::chrono::steady_clock::now() < end && !(stop != nullptr && stop->load())) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::vector<TopicSeen> topics = collector.topics();
  // The participant goes before the listener it calls.
  delete_participant(participant);
  return topics;
}

}  // namespace shapeform::dds
