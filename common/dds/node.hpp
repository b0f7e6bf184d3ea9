#pragma once
/// RAII DDS node: one participant (from the transport profile), one publisher, one subscriber, the
/// project's topics created on demand, and typed Writer / Reader handles.
///
/// Threading: a Node and its handles are used from one thread of control (the process's loop); the only
/// other thread is Fast DDS's receive thread, which only appends to a Reader's mailbox.
/// Lifetime: handles may be destroyed before or after their Node; after the Node is gone they do nothing
/// (write() returns false, drain() returns what was already received).
/// Rebuild: Node::rebuild() replaces the participant and every endpoint behind the handles, which keep
/// working (same topic, QoS and mailbox) without being touched: see recover_if_stalled().
#include <array>
#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <fastdds/dds/core/status/PublicationMatchedStatus.hpp>
#include <fastdds/dds/core/status/SubscriptionMatchedStatus.hpp>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>

#include "dds/msg_traits.hpp"
#include "protocol/samples.hpp"
#include "dds/stall.hpp"
#include "protocol/transport.hpp"
#include "dds/topics.hpp"
#include "util/clock.hpp"

namespace shapeform::dds {

/// Instance state of a keyed sample as the reader saw it.
enum class InstanceState {
  Alive,     ///< the writer publishes this instance
  Disposed,  ///< the writer disposed it (clean agent exit): drop the agent now
  NoWriters  ///< no writer left for it (writer deleted / participant gone)
};

/// One sample as taken by a Reader.
template <class Msg>
struct Received {
  Msg msg;                          ///< the data; default-constructed when !valid_data
  std::int64_t receive_stamp_ns = 0;  ///< util::steady_ns() when taken in the listener
  bool valid_data = false;          ///< false for instance-state-only samples (dispose, no writers)
  InstanceState instance = InstanceState::Alive;
  /// Keyed types: the instance's id (from msg when valid, else remembered from an earlier valid sample
  /// of the same instance; -1 if never seen). Unkeyed types: -1.
  std::int32_t key_id = -1;
  /// The participant whose writer sent it (for NoWriters samples: the writer that left).
  SourceId source;
};

/// How many refused participants a Node remembers having reported (a flood of fake ones stays bounded).
inline constexpr std::size_t kRefusedRemembered = 4096;

/// Default bound of a Reader's mailbox; samples beyond it (nobody draining) are dropped and counted.
inline constexpr std::size_t kDefaultMailboxCapacity = 16384;

namespace detail {

/// What a Writer handle points at: its topic and the DataWriter serving it now. Node::rebuild()
/// replaces the DataWriter; the handle owns the slot, the Node only watches it (weak_ptr).
struct WriterSlot {
  TopicId topic;
  eprosima::fastdds::dds::DataWriter* writer = nullptr;
};

/// What a Reader handle points at: its topic, its listener (the mailbox) and the DataReader serving it now.
struct ReaderSlot {
  TopicId topic;
  eprosima::fastdds::dds::DataReaderListener* listener = nullptr;
  eprosima::fastdds::dds::DataReader* reader = nullptr;
};

/// The participants that DDS Security refused (failed authentication or join access control), as
/// the participant's listener hears them on Fast DDS's thread; the loop takes them.
class RefusedWatch final : public eprosima::fastdds::dds::DomainParticipantListener {
 public:
  void onParticipantAuthentication(eprosima::fastdds::dds::DomainParticipant* participant,
                                   eprosima::fastrtps::rtps::ParticipantAuthenticationInfo&& info) override;
  /// The participants refused since the last call (at most kRefusedRemembered; repeats possible).
  std::vector<SourceId> take();

 private:
  std::mutex mutex_;
  std::vector<SourceId> pending_;
};

/// The DDS entities of a Node. Shared with handles through weak_ptr so they can tell whether the
/// Node still exists.
struct Entities {
  eprosima::fastdds::dds::DomainParticipant* participant = nullptr;
  eprosima::fastdds::dds::Publisher* publisher = nullptr;
  eprosima::fastdds::dds::Subscriber* subscriber = nullptr;
  std::array<eprosima::fastdds::dds::Topic*, kAllTopics.size()> topics{};
  std::string name;
  TransportConfig transport;  ///< the profile the participant was built from (reader locators)
  /// Hears refused participants when security is enabled (set before the first participant, which
  /// it outlives: members go after ~Entities() deleted the participant).
  std::unique_ptr<RefusedWatch> refused;
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
/// The participant part of a writer's instance handle (a handle holds the writer's GUID).
SourceId source_of(const eprosima::fastdds::dds::InstanceHandle_t& writer);

/// The listener of one Reader: takes every sample into a mutex-protected mailbox. No maths here: it
/// runs on Fast DDS's receive thread.
template <class Msg>
class Mailbox final : public eprosima::fastdds::dds::DataReaderListener {
 public:
  explicit Mailbox(std::size_t capacity) : capacity_(capacity) {
    pending_.reserve(capacity < 256 ? capacity : 256);
  }

  void on_data_available(eprosima::fastdds::dds::DataReader* reader) override {
    namespace fdds = eprosima::fastdds::dds;
    Msg sample;
    fdds::SampleInfo info;
    while (is_ok(reader->take_next_sample(&sample, &info))) {
      const std::int64_t now = util::steady_ns();
      InstanceState state = InstanceState::Alive;
      if (info.instance_state == fdds::NOT_ALIVE_DISPOSED_INSTANCE_STATE) {
        state = InstanceState::Disposed;
      } else if (info.instance_state == fdds::NOT_ALIVE_NO_WRITERS_INSTANCE_STATE) {
        state = InstanceState::NoWriters;
      }
      std::lock_guard<std::mutex> lock(mutex_);
      std::int32_t key = -1;
      if constexpr (MsgTraits<Msg>::keyed) {
        // get_key_value() is unsupported in 2.9: remember handle -> id to name invalid samples, and
        // the writer last heard on each instance. (One map node per instance ever seen; nothing
        // allocated per sample.)
        if (info.valid_data) {
          key = MsgTraits<Msg>::key(sample);
          auto it = instances_.find(info.instance_handle);
          if (it == instances_.end()) it = instances_.emplace(info.instance_handle, Instance{key, {}}).first;
          it->second.writer = info.publication_handle;
        } else {
          const auto it = instances_.find(info.instance_handle);
          if (it != instances_.end()) key = it->second.key;
        }
      }
      if (pending_.size() >= capacity_) {
        ++overflowed_;
        continue;
      }
      // An invalid sample carries no data (take leaves `sample` as it was): hand out a default Msg.
      pending_.push_back(Received<Msg>{info.valid_data ? sample : Msg{}, now, info.valid_data, state, key,
                                       source_of(info.publication_handle)});
    }
  }

  /// A writer that left (deleted, or its participant gone or lost): every instance it was the last to
  /// publish is handed out as NoWriters. Fast DDS 2.9 sends no such sample itself, so without this a
  /// peer whose dispose was lost (best effort) would stay until the application's timeout.
  void on_subscription_matched(eprosima::fastdds::dds::DataReader*,
                               const eprosima::fastdds::dds::SubscriptionMatchedStatus& status) override {
    if constexpr (MsgTraits<Msg>::keyed) {
      if (status.current_count_change >= 0) return;
      const std::int64_t now = util::steady_ns();
      std::lock_guard<std::mutex> lock(mutex_);
      for (const auto& [handle, inst] : instances_) {
        if (inst.writer != status.last_publication_handle) continue;
        if (pending_.size() >= capacity_) {
          ++overflowed_;
          continue;
        }
        pending_.push_back(Received<Msg>{Msg{}, now, false, InstanceState::NoWriters, inst.key,
                                         source_of(inst.writer)});
      }
    }
  }

  /// Swaps the pending samples into out (out is cleared first; capacities are recycled).
  std::size_t drain(std::vector<Received<Msg>>& out) {
    out.clear();
    std::lock_guard<std::mutex> lock(mutex_);
    out.swap(pending_);
    return out.size();
  }

  std::uint64_t overflowed() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return overflowed_;
  }

 private:
  const std::size_t capacity_;
  mutable std::mutex mutex_;
  std::vector<Received<Msg>> pending_;
  std::uint64_t overflowed_ = 0;
  struct Instance {
    std::int32_t key;                                  ///< the id the instance carries
    eprosima::fastdds::dds::InstanceHandle_t writer;   ///< the writer of its newest sample
  };
  std::map<eprosima::fastdds::dds::InstanceHandle_t, Instance> instances_;
};

}  // namespace detail

/// Typed writer of one topic. Move-only; deletes its DataWriter when destroyed (if the Node still lives).
template <class Msg>
class Writer {
 public:
  Writer() = default;
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;
  Writer(Writer&& o) noexcept : entities_(std::move(o.entities_)), slot_(std::move(o.slot_)) {}
  Writer& operator=(Writer&& o) noexcept {
    if (this != &o) {
      reset();
      entities_ = std::move(o.entities_);
      slot_ = std::move(o.slot_);
    }
    return *this;
  }
  ~Writer() { reset(); }

  /// Publishes m. False when Fast DDS refuses it or the Node is gone.
  bool write(const Msg& m) {
    const auto e = entities_.lock();
    // DataWriter::write takes void*; it only reads the sample.
    return e && get() != nullptr && slot_->writer->write(const_cast<Msg*>(&m));
  }

  /// Disposes the instance with m's key (keyed topics only): readers see it NOT_ALIVE_DISPOSED at once.
  bool dispose(const Msg& m) {
    static_assert(MsgTraits<Msg>::keyed, "dispose() is for keyed topics only");
    const auto e = entities_.lock();
    return e && get() != nullptr &&
           detail::is_ok(slot_->writer->dispose(const_cast<Msg*>(&m), eprosima::fastdds::dds::HANDLE_NIL));
  }

  /// Number of matched readers now (-1 without a writer).
  int matched() const {
    const auto e = entities_.lock();
    if (!e || get() == nullptr) return -1;
    eprosima::fastdds::dds::PublicationMatchedStatus st;
    if (!detail::is_ok(slot_->writer->get_publication_matched_status(st))) return -1;
    return st.current_count;
  }

  bool valid() const { return get() != nullptr && !entities_.expired(); }
  /// The DataWriter serving this handle now (another one after Node::rebuild()).
  eprosima::fastdds::dds::DataWriter* get() const { return slot_ ? slot_->writer : nullptr; }

 private:
  friend class Node;
  Writer(std::weak_ptr<detail::Entities> e, std::shared_ptr<detail::WriterSlot> slot)
      : entities_(std::move(e)), slot_(std::move(slot)) {}
  void reset() noexcept {
    if (get() != nullptr) {
      if (const auto e = entities_.lock()) detail::delete_writer(*e, slot_->writer);
    }
    slot_.reset();
    entities_.reset();
  }

  std::weak_ptr<detail::Entities> entities_;
  std::shared_ptr<detail::WriterSlot> slot_;
};

/// Typed reader of one topic with a mailbox filled by the listener. Move-only; deletes its DataReader
/// when destroyed (if the Node still lives).
template <class Msg>
class Reader {
 public:
  Reader() = default;
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;
  Reader(Reader&& o) noexcept
      : entities_(std::move(o.entities_)), mailbox_(std::move(o.mailbox_)), slot_(std::move(o.slot_)) {}
  Reader& operator=(Reader&& o) noexcept {
    if (this != &o) {
      reset();
      entities_ = std::move(o.entities_);
      mailbox_ = std::move(o.mailbox_);
      slot_ = std::move(o.slot_);
    }
    return *this;
  }
  ~Reader() { reset(); }

  /// Moves every sample received since the last call into out (cleared first), oldest first.
  /// Never blocks on DDS; no allocation in steady state (the two buffers are swapped).
  std::size_t drain(std::vector<Received<Msg>>& out) {
    if (!mailbox_) {
      out.clear();
      return 0;
    }
    return mailbox_->drain(out);
  }

  /// Number of matched writers now (-1 without a reader).
  int matched() const {
    const auto e = entities_.lock();
    if (!e || get() == nullptr) return -1;
    eprosima::fastdds::dds::SubscriptionMatchedStatus st;
    if (!detail::is_ok(slot_->reader->get_subscription_matched_status(st))) return -1;
    return st.current_count;
  }

  /// Samples dropped because the mailbox was full (nobody drained).
  std::uint64_t overflowed() const { return mailbox_ ? mailbox_->overflowed() : 0; }

  bool valid() const { return get() != nullptr && !entities_.expired(); }
  /// The DataReader serving this handle now (another one after Node::rebuild()).
  eprosima::fastdds::dds::DataReader* get() const { return slot_ ? slot_->reader : nullptr; }

 private:
  friend class Node;
  void reset() noexcept {
    if (get() != nullptr) {
      if (const auto e = entities_.lock()) detail::delete_reader(*e, slot_->reader);
    }
    slot_.reset();
    entities_.reset();
    mailbox_.reset();  // after the DataReader: no callback can run any more
  }

  std::weak_ptr<detail::Entities> entities_;
  std::unique_ptr<detail::Mailbox<Msg>> mailbox_;
  std::shared_ptr<detail::ReaderSlot> slot_;
};

/// Owns a participant built by create_participant(cfg, name), one publisher and one subscriber; all
/// message types are registered at construction; topics are created on first use.
/// Throws std::runtime_error naming the entity (and topic) whose creation failed.
class Node {
 public:
  Node(const TransportConfig& cfg, const std::string& name);
  ~Node();  ///< deletes contained entities (endpoints, publisher, subscriber, topics), then the participant
  Node(const Node&) = delete;
  Node& operator=(const Node&) = delete;

  /// A writer on topic id with writer_qos(id). Msg must be the topic's type (else std::logic_error).
  template <class Msg>
  Writer<Msg> writer(TopicId id) {
    check_type(id, MsgTraits<Msg>::topic);
    auto slot = std::make_shared<detail::WriterSlot>(detail::WriterSlot{id, create_writer(id)});
    entities_->writers.push_back(slot);
    return Writer<Msg>(entities_, std::move(slot));
  }

  /// A reader on topic id with reader_qos(id, transport), its listener filling a mailbox of at most
  /// mailbox_capacity samples. Msg must be the topic's type (else std::logic_error).
  template <class Msg>
  Reader<Msg> reader(TopicId id, std::size_t mailbox_capacity = kDefaultMailboxCapacity) {
    check_type(id, MsgTraits<Msg>::topic);
    Reader<Msg> r;
    r.mailbox_ = std::make_unique<detail::Mailbox<Msg>>(mailbox_capacity);
    r.slot_ = std::make_shared<detail::ReaderSlot>(detail::ReaderSlot{id, r.mailbox_.get(), nullptr});
    r.slot_->reader = create_reader(id, r.mailbox_.get());
    r.entities_ = entities_;
    entities_->readers.push_back(r.slot_);
    return r;
  }

  eprosima::fastdds::dds::DomainParticipant* participant() const { return entities_->participant; }
  const std::string& name() const { return entities_->name; }
  /// This participant's identity, as its samples carry it in Received::source. A rebuild changes it;
  /// unknown while a rebuild has failed.
  SourceId source() const;
  /// With DDS Security: the participants refused (authentication failed: the participant listener;
  /// permissions failed: Fast DDS's log, dds/library_log.hpp) since the last call, each once (up to
  /// kRefusedRemembered of them); a warning is logged for each. Always empty without security.
  std::vector<SourceId> take_refused();

  /// Replaces the participant, publisher, subscriber and topics with new ones from the same transport
  /// profile (dds::create_participant) and recreates the endpoint of every live handle: same topic,
  /// QoS and mailbox, so the handles carry on untouched. The new participant has a new GUID, which
  /// every peer discovers like a late joiner. The old readers' listeners are detached first: their
  /// unmatching is this process leaving, not its peers. Throws like the constructor; the Node then has
  /// no participant (handles do nothing) until a later rebuild succeeds.
  void rebuild();

  /// The self-healing step, called once per loop tick by every process (period_s: the loop's period).
  /// When the last call was more than kStallMargin past its period ago (the process was stopped,
  /// debugged, suspended or starved) for longer than the peers' lease allows (stall_threshold_s()),
  /// its peers may have dropped it, and Fast DDS 2.9 may then never match it again (docs/RELIABILITY.md):
  /// the Node is rebuilt, a warning logged, and the stall in seconds returned. nullopt otherwise.
  /// A rebuild that throws is logged and retried on the next call.
  std::optional<double> recover_if_stalled(double period_s);

  /// Ends the process with `status` after deleting this participant's endpoints (peers unmatch them at
  /// once) but not the participant itself: no participant goodbye is sent, and each peer forgets the
  /// participant when its lease ends, on the peer's own event thread. Fast DDS 2.9 aborts a peer (assert in
  /// PDP.cpp check_remote_participant_liveliness) when it processes a goodbye while the lease timer of the
  /// same participant fires: its timer callback then finds the proxy already released. A large swarm
  /// stopping at once makes N x (N - 1) such removals (docs/BENCHMARKS.md, lever 11). Flushes stdio first.
  [[noreturn]] void exit_without_goodbye(int status);

 private:
  void open();  ///< creates participant, types, publisher and subscriber into entities_
  static void check_type(TopicId requested, TopicId of_type);
  eprosima::fastdds::dds::Topic* topic(TopicId id);
  eprosima::fastdds::dds::DataWriter* create_writer(TopicId id);
  eprosima::fastdds::dds::DataReader* create_reader(TopicId id,
                                                    eprosima::fastdds::dds::DataReaderListener* listener);

  std::shared_ptr<detail::Entities> entities_;
  StallWatch stall_;
  bool rebuild_pending_ = false;  ///< the last rebuild failed: retry on the next recover_if_stalled()
  double pending_stall_s_ = 0.0;
};

}  // namespace shapeform::dds
