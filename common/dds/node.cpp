#include "dds/node.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>

#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/qos/PublisherQos.hpp>
#include <fastdds/dds/subscriber/qos/SubscriberQos.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <fastdds/dds/topic/qos/TopicQos.hpp>
#include <fastrtps/utils/IPLocator.h>

#include "dds/library_log.hpp"
#include "dds/node_entities.hpp"
#include "dds/participant_factory.hpp"
#include "dds/topic_qos.hpp"
#include "shapeform/msg/all_pubsub_types.h"  // every idl/*.idl's PubSubType, generated
#include "util/log.hpp"
#include "util/text.hpp"

namespace shapeform::dds {

namespace fdds = eprosima::fastdds::dds;
using eprosima::fastrtps::types::ReturnCode_t;

namespace detail {

Entities::~Entities() {
  // delete_contained_entities removes endpoints, publisher, subscriber and topics (children before
  // parents), then the participant goes and announces its departure.
  delete_participant(participant);
}

void delete_writer(Entities& e, fdds::DataWriter* w) noexcept {
  if (e.publisher != nullptr && w != nullptr) e.publisher->delete_datawriter(w);
}

void delete_reader(Entities& e, fdds::DataReader* r) noexcept {
  if (e.subscriber != nullptr && r != nullptr) {
    r->set_listener(nullptr);
    e.subscriber->delete_datareader(r);
  }
}

bool is_ok(const ReturnCode_t& rc) { return rc == ReturnCode_t::RETCODE_OK; }

SourceId source_of(const fdds::InstanceHandle_t& writer) {
  return prefix_of(eprosima::fastrtps::rtps::iHandle2GUID(writer).guidPrefix);
}

SourceId prefix_of(const eprosima::fastrtps::rtps::GuidPrefix_t& p) {
  SourceId s;
  std::copy(std::begin(p.value), std::end(p.value), s.prefix.begin());
  return s;
}

ParticipantWatch::ParticipantWatch(const TransportConfig& cfg)
    : split_(SplitWatch::window_for(cfg), SplitWatch::kGraceS, cfg.security.enabled) {}

void ParticipantWatch::onParticipantAuthentication(fdds::DomainParticipant* /*participant*/,
                                                   eprosima::fastrtps::rtps::ParticipantAuthenticationInfo&& info) {
  using Status = eprosima::fastrtps::rtps::ParticipantAuthenticationInfo::AUTHENTICATION_STATUS;
  const SourceId peer = prefix_of(info.guid.guidPrefix);
  std::lock_guard<std::mutex> lock(mutex_);
  if (info.status == Status::AUTHORIZED_PARTICIPANT) {
    split_.authenticated(peer);
    return;
  }
  split_.removed(peer);  // refused: never a peer to be half-matched with
  if (refused_.size() < kRefusedRemembered) refused_.push_back(peer);  // reported once
}

void ParticipantWatch::on_participant_discovery(fdds::DomainParticipant* participant,
                                                eprosima::fastrtps::rtps::ParticipantDiscoveryInfo&& info) {
  using Status = eprosima::fastrtps::rtps::ParticipantDiscoveryInfo::DISCOVERY_STATUS;
  const SourceId peer = prefix_of(info.info.m_guid.guidPrefix);
  if (participant != nullptr && info.info.m_guid.guidPrefix == participant->guid().guidPrefix) return;
  const std::int64_t now = boot_ns();
  std::lock_guard<std::mutex> lock(mutex_);
  switch (info.status) {
    case Status::DISCOVERED_PARTICIPANT: {
      if (const auto after = split_.discovered(peer, now))
        util::log_info("participant " + to_string(peer) + " announced itself again " + util::format_g10(*after) +
                       " s after its drop");
      const auto& data = info.info.m_userData.data_vec();
      const std::size_t tag = kIdentityTag.size();
      if (data.size() == tag + 12 && std::equal(kIdentityTag.begin(), kIdentityTag.end(), data.begin())) {
        SourceId identity;
        std::copy(data.begin() + static_cast<std::ptrdiff_t>(tag), data.end(), identity.prefix.begin());
        if (identity.known() && identity != peer) {
          // Bounded: GUID prefixes are never reused, so a forgotten entry only costs a peer rebuilt
          // long ago its identity in a late sample.
          if (identity_of_.size() >= kRefusedRemembered) identity_of_.clear();
          identity_of_[peer] = identity;
          any_alias_.store(true, std::memory_order_release);
        }
      }
      break;
    }
    case Status::DROPPED_PARTICIPANT:
      // Rare in a healthy swarm; logged so that a pair left unmatched after one can be told apart.
      util::log_info("participant " + to_string(peer) + " dropped: nothing heard from it for the lease");
      split_.dropped(peer, now);
      break;
    case Status::REMOVED_PARTICIPANT:
      split_.removed(peer);
      break;
    default:
      break;
  }
}

void ParticipantWatch::on_subscriber_discovery(fdds::DomainParticipant* /*participant*/,
                                               eprosima::fastrtps::rtps::ReaderDiscoveryInfo&& info) {
  if (info.status == eprosima::fastrtps::rtps::ReaderDiscoveryInfo::DISCOVERED_READER) endpoint_of(info.info.guid());
}

void ParticipantWatch::on_publisher_discovery(fdds::DomainParticipant* /*participant*/,
                                              eprosima::fastrtps::rtps::WriterDiscoveryInfo&& info) {
  if (info.status == eprosima::fastrtps::rtps::WriterDiscoveryInfo::DISCOVERED_WRITER) endpoint_of(info.info.guid());
}

void ParticipantWatch::endpoint_of(const eprosima::fastrtps::rtps::GUID_t& endpoint) {
  const SourceId peer = prefix_of(endpoint.guidPrefix);
  std::lock_guard<std::mutex> lock(mutex_);
  split_.endpoint(peer);
}

std::vector<SourceId> ParticipantWatch::take_refused() {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<SourceId> out;
  out.swap(refused_);
  return out;
}

std::optional<SplitWatch::Split> ParticipantWatch::split_due(std::int64_t now_ns) {
  std::lock_guard<std::mutex> lock(mutex_);
  return split_.due(now_ns);
}

void ParticipantWatch::rebuilt(const SourceId& now, const SourceId& identity) {
  std::lock_guard<std::mutex> lock(mutex_);
  split_.clear();
  if (!now.known() || now == identity) return;
  identity_of_[now] = identity;  // our own samples, as our readers hear them
  any_alias_.store(true, std::memory_order_release);
}

SourceId ParticipantWatch::identity(const SourceId& participant) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = identity_of_.find(participant);
  return it == identity_of_.end() ? participant : it->second;
}

}  // namespace detail

namespace {

/// Registers the type of topic id (`pubsub`, taken over) on p; checks its generated name is the table's.
void register_type(fdds::DomainParticipant* p, fdds::TopicDataType* pubsub, TopicId id, const std::string& node) {
  fdds::TypeSupport type(pubsub);
  if (!detail::is_ok(type.register_type(p))) {
    throw std::runtime_error("register_type failed for " + type.get_type_name() + " (node " + node + ")");
  }
  const char* expected = type_name(id);
  if (type.get_type_name() != expected) {
    throw std::logic_error("dds: generated type name " + type.get_type_name() +
                           " differs from the topic table's " + expected);
  }
}

/// Every topic's type, registered on p.
void register_types(fdds::DomainParticipant* p, const std::string& node) {
#define SHAPEFORM_REGISTER_TYPE(Id, name, Type, ...) \
  register_type(p, new Type##PubSubType(), TopicId::Id, node);
  SHAPEFORM_TOPICS(SHAPEFORM_REGISTER_TYPE)
#undef SHAPEFORM_REGISTER_TYPE
}

}  // namespace

Node::Node(const TransportConfig& cfg, const std::string& name)
    : entities_(std::make_shared<detail::Entities>()) {
  // Any throw below destroys entities_, which deletes whatever was created so far.
  entities_->name = name;
  entities_->transport = cfg;
  entities_->watch = std::make_unique<detail::ParticipantWatch>(cfg);
  open();
  entities_->identity = detail::prefix_of(entities_->participant->guid().guidPrefix);
}

void Node::open() {
  detail::Entities& e = *entities_;
  const std::string& name = e.name;
  // A rebuilt participant announces the process's identity (its first participant's GUID prefix).
  std::vector<unsigned char> user_data;
  if (e.identity.known()) {
    const std::string_view tag = detail::ParticipantWatch::kIdentityTag;
    user_data.resize(tag.size() + e.identity.prefix.size());
    const auto rest = std::copy(tag.begin(), tag.end(), user_data.begin());
    std::copy(e.identity.prefix.begin(), e.identity.prefix.end(), rest);
  }
  e.participant = create_participant(e.transport, name, e.watch.get(), user_data);

  register_types(e.participant, name);

  // Constructed QoS (not *_QOS_DEFAULT, which XML profiles could change).
  e.publisher = e.participant->create_publisher(fdds::PublisherQos());
  if (e.publisher == nullptr) throw std::runtime_error("create_publisher failed (node " + name + ")");
  e.subscriber = e.participant->create_subscriber(fdds::SubscriberQos());
  if (e.subscriber == nullptr) {
    throw std::runtime_error("create_subscriber failed (node " + name + ")");
  }
}

void Node::rebuild() {
  detail::Entities& e = *entities_;
  const auto live = [](auto& slots) {
    const auto gone = [](const auto& w) { return w.expired(); };
    slots.erase(std::remove_if(slots.begin(), slots.end(), gone), slots.end());
  };
  live(e.writers);
  live(e.readers);
  // Detach the mailboxes first: deleting the old readers unmatches every peer's writer, which would
  // hand out a NoWriters sample for every agent heard, as if all of them had left.
  for (const auto& w : e.readers)
    if (const auto slot = w.lock(); slot->reader != nullptr) slot->reader->set_listener(nullptr);
  delete_participant(e.participant);  // its children too; peers hear it leave at once
  e.participant = nullptr;
  e.publisher = nullptr;
  e.subscriber = nullptr;
  e.topics.clear();
  for (const auto& w : e.writers) w.lock()->writer = nullptr;
  for (const auto& w : e.readers) w.lock()->reader = nullptr;

  open();
  e.watch->rebuilt(detail::prefix_of(e.participant->guid().guidPrefix), e.identity);
  for (const auto& w : e.writers) {
    const auto slot = w.lock();
    slot->writer = detail::create_writer(e, slot->topic, slot->name);
  }
  for (const auto& w : e.readers) {
    const auto slot = w.lock();
    slot->reader = detail::create_reader(e, slot->topic, slot->name, slot->listener);
  }
}

std::optional<Node::Recovery> Node::recover(double period_s) {
  if (!pending_) {
    if (const auto stall = stall_.check(boot_ns(), period_s, stall_threshold_s(entities_->transport)))
      pending_ = Recovery{Recovery::Cause::Stall, *stall, {}};
    else if (const auto split = entities_->watch->split_due(boot_ns()))
      pending_ = Recovery{Recovery::Cause::Split, split->unheard_s, split->peer};
    else
      return std::nullopt;
  }
  try {
    rebuild();
  } catch (const std::exception& ex) {
    util::log_error("recreating the participant failed (retrying next tick): " + std::string(ex.what()));
    return std::nullopt;
  }
  const Recovery done = *pending_;
  pending_.reset();
  char text[300];
  const std::string now = to_string(detail::prefix_of(entities_->participant->guid().guidPrefix)) + " (on " +
                          listening() + ")";
  if (done.cause == Recovery::Cause::Stall)
    std::snprintf(text, sizeof text,
                  "stalled for %.2f s (longer than the lease allows, %.2f s): participant recreated as %s, "
                  "rediscovering",
                  done.seconds, stall_threshold_s(entities_->transport), now.c_str());
  else
    std::snprintf(text, sizeof text,
                  "participant %s dropped for silence was heard again %.2f s later (it may not have dropped this "
                  "one): participant recreated as %s, rediscovering",
                  to_string(done.peer).c_str(), done.seconds, now.c_str());
  util::log_warn(text);
  return done;
}

SourceId Node::source() const { return entities_->identity; }

std::string Node::listening() const {
  std::vector<fdds::DataReader*> readers;
  if (entities_->subscriber == nullptr || !detail::is_ok(entities_->subscriber->get_datareaders(readers)) || readers.empty())
    return {};
  eprosima::fastrtps::rtps::LocatorList_t locators;
  if (!detail::is_ok(readers.front()->get_listening_locators(locators))) return {};
  std::string out;
  for (const auto& l : locators) {
    if (!out.empty()) out += ",";
    out += eprosima::fastrtps::rtps::IPLocator::ip_to_string(l) + ":" + std::to_string(l.port);
  }
  return out;
}

std::vector<SourceId> Node::take_refused() {
  if (!entities_->transport.security.enabled) return {};
  std::vector<SourceId> heard = entities_->watch->take_refused();
  for (const SourceId& s : take_permission_refusals()) heard.push_back(s);
  std::vector<SourceId> refused;
  auto& reported = entities_->refused_reported;
  for (const SourceId& s : heard) {
    if (reported.count(s) != 0) continue;
    if (reported.size() >= kRefusedRemembered) reported.clear();
    reported.insert(s);
    refused.push_back(s);
    util::log_warn("security: participant " + to_string(s) +
                   " refused (no valid certificate of this swarm's authority, or permissions that do not verify)");
  }
  return refused;
}

Node::~Node() = default;

fdds::DomainParticipant* Node::participant() const { return entities_->participant; }
const std::string& Node::name() const { return entities_->name; }

void Node::exit_without_goodbye(int status) {
  if (entities_->participant != nullptr) entities_->participant->delete_contained_entities();
  std::fflush(nullptr);
  std::_Exit(status);
}  // entities_ (the last owner) deletes everything; handles only hold weak_ptrs

std::string Node::endpoint_topic(TopicId requested, TopicId of_type, const std::string& name) {
  if (requested != of_type) {
    throw std::logic_error(std::string("dds: topic ") + topic_name(requested) + " carries " +
                           type_name(requested) + ", not " + type_name(of_type));
  }
  if (is_vehicle_topic(requested) == name.empty()) {
    throw std::logic_error(std::string("dds: topic ") + topic_name(requested) +
                           (name.empty() ? " is a vehicle's: name it (dds::vehicle_topic_name)"
                                         : " has a fixed name: do not name it"));
  }
  return name.empty() ? topic_name(requested) : name;
}

namespace {

fdds::Topic* topic(detail::Entities& e, TopicId id, const std::string& name) {
  if (e.participant == nullptr) {
    throw std::runtime_error("no participant for topic " + name + " (node " + e.name + ": its rebuild failed)");
  }
  fdds::Topic*& slot = e.topics[name];
  if (slot == nullptr) {
    slot = e.participant->create_topic(name, type_name(id), fdds::TopicQos());
    if (slot == nullptr) {
      e.topics.erase(name);
      throw std::runtime_error("create_topic failed for topic " + name + " (node " + e.name + ")");
    }
  } else if (slot->get_type_name() != type_name(id)) {
    throw std::runtime_error("topic " + name + " carries " + slot->get_type_name() + " in node " + e.name +
                             ", not " + type_name(id) + ": give the two their own names");
  }
  return slot;
}

/// The error of an endpoint Fast DDS refused: with security, its likely cause (the enclave's permissions).
[[noreturn]] void endpoint_failed(const detail::Entities& e, const char* what, const std::string& name) {
  const std::string line = std::string(what) + " failed for topic " + name + " (node " + e.name + ")";
  if (e.transport.security.enabled) {
    throw SecurityError("security: " + line + ": the permissions of enclave " + e.transport.security.identity +
                        " (" + enclave_dir(e.transport.security) + "/permissions.xml) do not allow " +
                        (std::string(what) == "create_datawriter" ? "publishing" : "subscribing to") + " " +
                        name + "; run this program with its own role's identity (security.identity)");
  }
  throw std::runtime_error(line);
}

}  // namespace

namespace detail {

fdds::DataWriter* create_writer(Entities& e, TopicId id, const std::string& name) {
  fdds::DataWriter* w = e.publisher->create_datawriter(topic(e, id, name), writer_qos(id));
  if (w == nullptr) endpoint_failed(e, "create_datawriter", name);
  return w;
}

fdds::DataReader* create_reader(Entities& e, TopicId id, const std::string& name,
                                fdds::DataReaderListener* listener) {
  const fdds::StatusMask mask = fdds::StatusMask::data_available() << fdds::StatusMask::subscription_matched();
  fdds::DataReader* r =
      e.subscriber->create_datareader(topic(e, id, name), reader_qos(id, e.transport), listener, mask);
  if (r == nullptr) endpoint_failed(e, "create_datareader", name);
  return r;
}

}  // namespace detail

}  // namespace shapeform::dds
