#pragma once
/// The Fast DDS entities behind a dds::Node and its handles (dds/node.hpp), for the dds library's own
/// sources (node.cpp, endpoints.cpp) and the tests: processes never include this.
#include <atomic>
#include <map>
#include <memory>
#include <optional>
#include <mutex>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>

#include "dds/stall.hpp"
#include "dds/topics.hpp"
#include "protocol/samples.hpp"
#include "protocol/transport.hpp"

namespace shapeform::dds::detail {

/// What a Writer handle points at: its topic and the DataWriter serving it now. Node::rebuild()
/// replaces the DataWriter; the handle owns the slot, the Node only watches it (weak_ptr).
struct WriterSlot {
  TopicId topic;
  std::string name;  ///< the DDS topic's name: the row's, or a vehicle's (dds::vehicle_topic_name)
  eprosima::fastdds::dds::DataWriter* writer = nullptr;
};

/// What a Reader handle points at: its topic, its listener (the mailbox) and the DataReader serving it now.
struct ReaderSlot {
  TopicId topic;
  std::string name;  ///< the DDS topic's name
  eprosima::fastdds::dds::DataReaderListener* listener = nullptr;
  eprosima::fastdds::dds::DataReader* reader = nullptr;
};

/// What the participant's listener hears on Fast DDS's threads, for the loop to take:
/// - the participants DDS Security refused (failed authentication or join access control);
/// - the participants this one dropped for silence and heard again soon after (dds::SplitWatch), when
///   this process should recreate its participant;
/// - each peer's process identity: a participant that a process recreated announces its first
///   participant's GUID prefix in USER_DATA (kIdentityTag), and samples from it are attributed to that
///   identity, so a process keeps one identity across rebuilds.
class ParticipantWatch final : public eprosima::fastdds::dds::DomainParticipantListener {
 public:
  explicit ParticipantWatch(const TransportConfig& cfg);

  void onParticipantAuthentication(eprosima::fastdds::dds::DomainParticipant* participant,
                                   eprosima::fastrtps::rtps::ParticipantAuthenticationInfo&& info) override;
  void on_participant_discovery(eprosima::fastdds::dds::DomainParticipant* participant,
                                eprosima::fastrtps::rtps::ParticipantDiscoveryInfo&& info) override;
  void on_subscriber_discovery(eprosima::fastdds::dds::DomainParticipant* participant,
                               eprosima::fastrtps::rtps::ReaderDiscoveryInfo&& info) override;
  void on_publisher_discovery(eprosima::fastdds::dds::DomainParticipant* participant,
                              eprosima::fastrtps::rtps::WriterDiscoveryInfo&& info) override;

  /// The participants refused since the last call (at most kRefusedRemembered; repeats possible).
  std::vector<SourceId> take_refused();
  /// A peer this process may be half-matched with (SplitWatch::due), nullopt if none.
  std::optional<SplitWatch::Split> split_due(std::int64_t now_ns);
  /// After a rebuild: no history with anyone, and samples of the new participant `now` are `identity`'s.
  void rebuilt(const SourceId& now, const SourceId& identity);
  /// The process identity behind a writer's participant (itself when it announced none).
  SourceId identity(const SourceId& participant);
  /// Whether any participant heard announced another identity (identity() is then worth calling).
  bool any_alias() const { return any_alias_.load(std::memory_order_acquire); }

  /// USER_DATA of a rebuilt participant: this tag, then the 12 bytes of its process identity.
  static constexpr std::string_view kIdentityTag = "sfid";

 private:
  void endpoint_of(const eprosima::fastrtps::rtps::GUID_t& endpoint);  ///< a peer's endpoint announced

  std::mutex mutex_;
  std::vector<SourceId> refused_;
  SplitWatch split_;
  std::map<SourceId, SourceId> identity_of_;  ///< participant -> process identity, where they differ
  std::atomic<bool> any_alias_{false};
};

/// The DDS entities of a Node. Shared with handles through weak_ptr so they can tell whether the
/// Node still exists.
struct Entities {
  eprosima::fastdds::dds::DomainParticipant* participant = nullptr;
  eprosima::fastdds::dds::Publisher* publisher = nullptr;
  eprosima::fastdds::dds::Subscriber* subscriber = nullptr;
  std::map<std::string, eprosima::fastdds::dds::Topic*> topics;  ///< by name, created on first use
  std::string name;
  TransportConfig transport;  ///< the profile the participant was built from (reader locators)
  /// The participant's listener (set before the first participant, which it outlives: members go after
  /// ~Entities() deleted the participant).
  std::unique_ptr<ParticipantWatch> watch;
  /// This process's identity: its first participant's GUID prefix (unknown until it exists).
  SourceId identity;
  /// The refused participants reported so far (each once: a refused peer retries its handshake for ever);
  /// at most kRefusedRemembered, then forgotten and reported again.
  std::set<SourceId> refused_reported;
  /// The live handles' endpoints, recreated by Node::rebuild() on the new participant.
  std::vector<std::weak_ptr<WriterSlot>> writers;
  std::vector<std::weak_ptr<ReaderSlot>> readers;

  Entities() = default;
  Entities(const Entities&) = delete;
  Entities& operator=(const Entities&) = delete;
  /// delete_contained_entities() + delete_participant().
  ~Entities();
};

void delete_writer(Entities& e, eprosima::fastdds::dds::DataWriter* w) noexcept;
void delete_reader(Entities& e, eprosima::fastdds::dds::DataReader* r) noexcept;
bool is_ok(const eprosima::fastrtps::types::ReturnCode_t& rc);
SourceId prefix_of(const eprosima::fastrtps::rtps::GuidPrefix_t& prefix);
/// The participant part of a writer's instance handle (a handle holds the writer's GUID).
SourceId source_of(const eprosima::fastdds::dds::InstanceHandle_t& writer);

/// A DataWriter on the topic `name` of row id, with writer_qos(id). Throws naming the topic (with
/// security: the enclave's permissions) when Fast DDS refuses it, or when the Node has no participant.
eprosima::fastdds::dds::DataWriter* create_writer(Entities& e, TopicId id, const std::string& name);
/// A DataReader on the topic `name` of row id with reader_qos(id, e.transport), `listener` hearing data
/// and matching.
eprosima::fastdds::dds::DataReader* create_reader(Entities& e, TopicId id, const std::string& name,
                                                  eprosima::fastdds::dds::DataReaderListener* listener);

}  // namespace shapeform::dds::detail
