#pragma once
/// RAII DDS node: one participant (from the transport profile), one publisher, one subscriber, the
/// project's topics created on demand, and typed Writer / Reader handles.
///
/// No Fast DDS here: the entities are the dds library's (dds/node_entities.hpp), and Writer<Msg> and
/// Reader<Msg> are compiled there for each topic's message type (dds/endpoints.cpp, from the topic table),
/// so a process compiles against this API only.
///
/// Threading: a Node and its handles are used from one thread of control (the process's loop); the only
/// other thread is Fast DDS's receive thread, which only appends to a Reader's mailbox.
/// Lifetime: handles may be destroyed before or after their Node; after the Node is gone they do nothing
/// (write() returns false, drain() returns what was already received).
/// Rebuild: Node::rebuild() replaces the participant and every endpoint behind the handles, which keep
/// working (same topic, QoS and mailbox) without being touched: see recover().
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include "dds/msg_traits.hpp"
#include "dds/stall.hpp"
#include "dds/topics.hpp"
#include "protocol/samples.hpp"
#include "protocol/transport.hpp"

// The Fast DDS entities behind the handles, for the tests and the benchmark's baseline that reach them
// (get(), participant()); opaque here.
namespace eprosima::fastdds::dds {
class DomainParticipant;
class DataWriter;
class DataReader;
}  // namespace eprosima::fastdds::dds

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
struct Entities;    ///< the participant, publisher, subscriber, topics and live endpoints of a Node
struct WriterSlot;  ///< a Writer's topic and the DataWriter serving it now
struct ReaderSlot;  ///< a Reader's topic, listener and the DataReader serving it now
template <class Msg>
class Mailbox;  ///< a Reader's listener: the samples taken on Fast DDS's thread
}  // namespace detail

/// Typed writer of one topic. Move-only; deletes its DataWriter when destroyed (if the Node still lives).
/// Compiled in the dds library for each topic's message type (see the end of this file).
template <class Msg>
class Writer {
 public:
  Writer() = default;
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;
  Writer(Writer&& o) noexcept;
  Writer& operator=(Writer&& o) noexcept;
  ~Writer();

  /// Publishes m. False when Fast DDS refuses it or the Node is gone.
  bool write(const Msg& m);

  /// Disposes the instance with m's key (keyed topics only: a compile error otherwise): readers see it
  /// NOT_ALIVE_DISPOSED at once.
  template <class M = Msg>
  bool dispose(const M& m) {
    static_assert(std::is_same_v<M, Msg> && MsgTraits<M>::keyed, "dispose() is for keyed topics only");
    return dispose_instance(m);
  }

  /// Number of matched readers now (-1 without a writer).
  int matched() const;
  /// Waits up to `seconds` until every matched reader acknowledged what was written (reliable topics: a
  /// lost sample is resent meanwhile). False on timeout or without a writer.
  bool wait_acknowledged(double seconds);

  bool valid() const;
  /// The DataWriter serving this handle now (another one after Node::rebuild()).
  eprosima::fastdds::dds::DataWriter* get() const;

 private:
  friend class Node;
  Writer(std::weak_ptr<detail::Entities> e, std::shared_ptr<detail::WriterSlot> slot);
  bool dispose_instance(const Msg& m);
  void reset() noexcept;

  std::weak_ptr<detail::Entities> entities_;
  std::shared_ptr<detail::WriterSlot> slot_;
};

/// Typed reader of one topic with a mailbox filled by the listener. Move-only; deletes its DataReader
/// when destroyed (if the Node still lives). Compiled in the dds library for each topic's message type.
template <class Msg>
class Reader {
 public:
  Reader();  ///< reads nothing: drain() gives nothing
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;
  Reader(Reader&& o) noexcept;
  Reader& operator=(Reader&& o) noexcept;
  ~Reader();

  /// Moves every sample received since the last call into out (cleared first), oldest first.
  /// Never blocks on DDS; no allocation in steady state (the two buffers are swapped).
  std::size_t drain(std::vector<Received<Msg>>& out);

  /// Number of matched writers now (-1 without a reader).
  int matched() const;

  /// Samples dropped because the mailbox was full (nobody drained).
  std::uint64_t overflowed() const;

  bool valid() const;
  /// The DataReader serving this handle now (another one after Node::rebuild()).
  eprosima::fastdds::dds::DataReader* get() const;

 private:
  friend class Node;
  void reset() noexcept;

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
  /// name: the DDS topic's name for a vehicle's topic (dds::vehicle_topic_name), and only for one.
  template <class Msg>
  Writer<Msg> writer(TopicId id, const std::string& name = {});

  /// A reader on topic id with reader_qos(id, transport), its listener filling a mailbox of at most
  /// mailbox_capacity samples. Msg must be the topic's type (else std::logic_error). name: as writer's.
  template <class Msg>
  Reader<Msg> reader(TopicId id, std::size_t mailbox_capacity = kDefaultMailboxCapacity, const std::string& name = {});

  eprosima::fastdds::dds::DomainParticipant* participant() const;
  const std::string& name() const;
  /// This process's identity, as its samples carry it in Received::source everywhere: the GUID prefix
  /// of its first participant, kept across rebuilds (a rebuilt participant announces it).
  SourceId source() const;
  /// Where this participant's readers receive user data now, "address:port" each (for the logs: the
  /// port says which participant slot the process holds); empty before its first reader.
  std::string listening() const;
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

  /// Why a Node was rebuilt (recover()).
  struct Recovery {
    enum class Cause {
      Stall,  ///< this process's loop was late by `seconds` (stopped, debugged, suspended, starved)
      Split,  ///< it dropped `peer` for silence and heard it again `seconds` later (a partition, a
              ///< starved thread): the peer may not have dropped it in turn
    } cause = Cause::Stall;
    double seconds = 0.0;
    SourceId peer;  ///< Split: the peer (its participant's GUID prefix)
  };
  /// The self-healing step, called once per loop tick by every process (period_s: the loop's period).
  /// Fast DDS 2.9 may never match again a pair where one side dropped the other for silence and the
  /// other did not (docs/RELIABILITY.md, "Stalls, partitions and membership"), and one side of such a
  /// pair always knows: the one whose loop stalled for longer than the peers' lease allows
  /// (stall_threshold_s()), or the one that dropped a peer and heard it again soon after (SplitWatch).
  /// That side recreates its participant: the Node is rebuilt, a warning logged, and the cause
  /// returned; nullopt otherwise. A rebuild that throws is logged and retried on the next call.
  std::optional<Recovery> recover(double period_s);

  /// Ends the process with `status` after deleting this participant's endpoints (peers unmatch them at
  /// once) but not the participant itself: no participant goodbye is sent, and each peer forgets the
  /// participant when its lease ends, on the peer's own event thread. Fast DDS 2.9 aborts a peer (assert in
  /// PDP.cpp check_remote_participant_liveliness) when it processes a goodbye while the lease timer of the
  /// same participant fires: its timer callback then finds the proxy already released. A large swarm
  /// stopping at once makes N x (N - 1) such removals (docs/BENCHMARKS.md, lever 11). Flushes stdio first.
  [[noreturn]] void exit_without_goodbye(int status);

 private:
  void open();  ///< creates participant, types, publisher and subscriber into entities_
  /// The DDS name of an endpoint on row `requested` with Msg's row `of_type` and the caller's `name`;
  /// std::logic_error when the type is not the row's, or a name is missing (vehicle topic) or extra.
  static std::string endpoint_topic(TopicId requested, TopicId of_type, const std::string& name);

  std::shared_ptr<detail::Entities> entities_;
  StallWatch stall_;
  std::optional<Recovery> pending_;  ///< a rebuild that failed: retried on the next recover()
};

// Compiled once, in the dds library (dds/endpoints.cpp), for each topic's message type.
#define SHAPEFORM_EXTERN_ENDPOINTS(Id, name, Type, ...) \
  extern template class Writer<Type>;                   \
  extern template class Reader<Type>;
SHAPEFORM_TOPICS(SHAPEFORM_EXTERN_ENDPOINTS)
#undef SHAPEFORM_EXTERN_ENDPOINTS

}  // namespace shapeform::dds
