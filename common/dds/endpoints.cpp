// The typed handles of dds/node.hpp (Writer<Msg>, Reader<Msg>, Node::writer / Node::reader), compiled
// here once for each topic's message type of the topic table, so no process compiles Fast DDS code.
#include <map>
#include <mutex>

#include <fastdds/dds/core/status/PublicationMatchedStatus.hpp>
#include <fastdds/dds/core/status/SubscriptionMatchedStatus.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>

#include "dds/node.hpp"
#include "dds/node_entities.hpp"
#include "util/clock.hpp"

namespace shapeform::dds {

namespace fdds = eprosima::fastdds::dds;

namespace detail {

/// The listener of one Reader: takes every sample into a mutex-protected mailbox. No maths here: it
/// runs on Fast DDS's receive thread. Nothing is allocated per sample in steady state: each sample is
/// taken into a slot the reader consumed earlier, reusing its buffers (drain() hands the consumer's
/// last vector back as spare slots).
template <class Msg>
class Mailbox final : public fdds::DataReaderListener {
 public:
  explicit Mailbox(std::size_t capacity) : capacity_(capacity) {
    pending_.reserve(capacity < 256 ? capacity : 256);
  }

  void on_data_available(fdds::DataReader* reader) override {
    fdds::SampleInfo info;
    // Each sample is taken straight into its slot (under the mutex: drain() only swaps vectors), into
    // the buffers a consumed sample left there; one that finds the mailbox full into a scratch one.
    for (;;) {
      std::lock_guard<std::mutex> lock(mutex_);
      Received<Msg>* slot = next_slot();
      Msg& into = slot != nullptr ? slot->msg : overflow_;
      if (!is_ok(reader->take_next_sample(&into, &info))) {
        if (slot != nullptr) --count_;
        return;
      }
      if (slot == nullptr) ++overflowed_;
      std::int32_t key = -1;
      if constexpr (MsgTraits<Msg>::keyed) {
        // get_key_value() is unsupported in 2.9: remember handle -> id to name invalid samples, and
        // the writer last heard on each instance. (One map node per instance ever seen; nothing
        // allocated per sample.)
        if (info.valid_data) {
          key = MsgTraits<Msg>::key(into);
          auto it = instances_.find(info.instance_handle);
          if (it == instances_.end()) it = instances_.emplace(info.instance_handle, Instance{key, {}}).first;
          it->second.writer = info.publication_handle;
        } else {
          const auto it = instances_.find(info.instance_handle);
          if (it != instances_.end()) key = it->second.key;
        }
      }
      if (slot == nullptr) continue;
      // An invalid sample carries no data (take leaves the message as it was): hand out a default Msg.
      if (!info.valid_data) slot->msg = Msg{};
      slot->receive_stamp_ns = util::steady_ns();
      slot->valid_data = info.valid_data;
      slot->instance = info.instance_state == fdds::NOT_ALIVE_DISPOSED_INSTANCE_STATE     ? InstanceState::Disposed
                       : info.instance_state == fdds::NOT_ALIVE_NO_WRITERS_INSTANCE_STATE ? InstanceState::NoWriters
                                                                                          : InstanceState::Alive;
      slot->key_id = key;
      slot->source = source_of(info.publication_handle);
    }
  }

  /// A writer that left (deleted, or its participant gone or lost): every instance it was the last to
  /// publish is handed out as NoWriters. Fast DDS 2.9 sends no such sample itself, so without this a
  /// peer whose dispose was lost (best effort) would stay until the application's timeout.
  void on_subscription_matched(fdds::DataReader*, const fdds::SubscriptionMatchedStatus& status) override {
    if constexpr (MsgTraits<Msg>::keyed) {
      if (status.current_count_change >= 0) return;
      const std::int64_t now = util::steady_ns();
      std::lock_guard<std::mutex> lock(mutex_);
      for (const auto& [handle, inst] : instances_) {
        if (inst.writer != status.last_publication_handle) continue;
        Received<Msg>* slot = next_slot();
        if (slot == nullptr) {
          ++overflowed_;
          continue;
        }
        *slot = Received<Msg>{Msg{}, now, false, InstanceState::NoWriters, inst.key, source_of(inst.writer)};
      }
    }
  }

  /// Swaps the pending samples into out; out's previous elements (consumed by the caller) become the
  /// spare slots the listener fills next, so their buffers are reused.
  std::size_t drain(std::vector<Received<Msg>>& out) {
    std::size_t n = 0;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      out.swap(pending_);
      n = count_;
      count_ = 0;
    }
    // Spare slots not filled this time: dropped (rare: only when fewer samples came than before).
    out.resize(n);
    return n;
  }

  std::uint64_t overflowed() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return overflowed_;
  }

 private:
  /// The next slot to fill (under mutex_): a spare one if there is, else a new one; nullptr when the
  /// mailbox is full.
  Received<Msg>* next_slot() {
    if (count_ >= capacity_) return nullptr;
    if (count_ == pending_.size()) pending_.emplace_back();
    return &pending_[count_++];
  }

  const std::size_t capacity_;
  mutable std::mutex mutex_;
  /// pending_[0, count_): received, not drained yet; the rest: spare slots.
  std::vector<Received<Msg>> pending_;
  std::size_t count_ = 0;
  Msg overflow_;  ///< where a sample the full mailbox has no slot for is taken (and dropped)
  std::uint64_t overflowed_ = 0;
  struct Instance {
    std::int32_t key;               ///< the id the instance carries
    fdds::InstanceHandle_t writer;  ///< the writer of its newest sample
  };
  std::map<fdds::InstanceHandle_t, Instance> instances_;
};

}  // namespace detail

// Writer<Msg>

template <class Msg>
Writer<Msg>::Writer(std::weak_ptr<detail::Entities> e, std::shared_ptr<detail::WriterSlot> slot)
    : entities_(std::move(e)), slot_(std::move(slot)) {}

template <class Msg>
Writer<Msg>::Writer(Writer&& o) noexcept : entities_(std::move(o.entities_)), slot_(std::move(o.slot_)) {}

template <class Msg>
Writer<Msg>& Writer<Msg>::operator=(Writer&& o) noexcept {
  if (this != &o) {
    reset();
    entities_ = std::move(o.entities_);
    slot_ = std::move(o.slot_);
  }
  return *this;
}

template <class Msg>
Writer<Msg>::~Writer() {
  reset();
}

template <class Msg>
bool Writer<Msg>::write(const Msg& m) {
  const auto e = entities_.lock();
  // DataWriter::write takes void*; it only reads the sample.
  return e && get() != nullptr && slot_->writer->write(const_cast<Msg*>(&m));
}

template <class Msg>
bool Writer<Msg>::dispose_instance(const Msg& m) {
  const auto e = entities_.lock();
  return e && get() != nullptr &&
         detail::is_ok(slot_->writer->dispose(const_cast<Msg*>(&m), fdds::HANDLE_NIL));
}

template <class Msg>
int Writer<Msg>::matched() const {
  const auto e = entities_.lock();
  if (!e || get() == nullptr) return -1;
  fdds::PublicationMatchedStatus st;
  if (!detail::is_ok(slot_->writer->get_publication_matched_status(st))) return -1;
  return st.current_count;
}

template <class Msg>
bool Writer<Msg>::wait_acknowledged(double seconds) {
  const auto e = entities_.lock();
  if (!e || get() == nullptr) return false;
  return detail::is_ok(get()->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(seconds)));
}

template <class Msg>
bool Writer<Msg>::valid() const {
  return get() != nullptr && !entities_.expired();
}

template <class Msg>
fdds::DataWriter* Writer<Msg>::get() const {
  return slot_ ? slot_->writer : nullptr;
}

template <class Msg>
void Writer<Msg>::reset() noexcept {
  if (get() != nullptr) {
    if (const auto e = entities_.lock()) detail::delete_writer(*e, slot_->writer);
  }
  slot_.reset();
  entities_.reset();
}

// Reader<Msg>

template <class Msg>
Reader<Msg>::Reader() = default;  // here, where the Mailbox is complete

template <class Msg>
Reader<Msg>::Reader(Reader&& o) noexcept
    : entities_(std::move(o.entities_)), mailbox_(std::move(o.mailbox_)), slot_(std::move(o.slot_)) {}

template <class Msg>
Reader<Msg>& Reader<Msg>::operator=(Reader&& o) noexcept {
  if (this != &o) {
    reset();
    entities_ = std::move(o.entities_);
    mailbox_ = std::move(o.mailbox_);
    slot_ = std::move(o.slot_);
  }
  return *this;
}

template <class Msg>
Reader<Msg>::~Reader() {
  reset();
}

template <class Msg>
std::size_t Reader<Msg>::drain(std::vector<Received<Msg>>& out) {
  if (!mailbox_) {
    out.clear();
    return 0;
  }
  const std::size_t n = mailbox_->drain(out);
  // Samples of a peer's rebuilt participant are its process's (its first participant's prefix).
  if (const auto e = entities_.lock(); e && e->watch && e->watch->any_alias())
    for (Received<Msg>& r : out) r.source = e->watch->identity(r.source);
  return n;
}

template <class Msg>
int Reader<Msg>::matched() const {
  const auto e = entities_.lock();
  if (!e || get() == nullptr) return -1;
  fdds::SubscriptionMatchedStatus st;
  if (!detail::is_ok(slot_->reader->get_subscription_matched_status(st))) return -1;
  return st.current_count;
}

template <class Msg>
std::uint64_t Reader<Msg>::overflowed() const {
  return mailbox_ ? mailbox_->overflowed() : 0;
}

template <class Msg>
bool Reader<Msg>::valid() const {
  return get() != nullptr && !entities_.expired();
}

template <class Msg>
fdds::DataReader* Reader<Msg>::get() const {
  return slot_ ? slot_->reader : nullptr;
}

template <class Msg>
void Reader<Msg>::reset() noexcept {
  if (get() != nullptr) {
    if (const auto e = entities_.lock()) detail::delete_reader(*e, slot_->reader);
  }
  slot_.reset();
  entities_.reset();
  mailbox_.reset();  // after the DataReader: no callback can run any more
}

// Node's factories of handles

template <class Msg>
Writer<Msg> Node::writer(TopicId id, const std::string& name) {
  std::string topic = endpoint_topic(id, MsgTraits<Msg>::topic, name);
  fdds::DataWriter* w = detail::create_writer(*entities_, id, topic);
  auto slot = std::make_shared<detail::WriterSlot>(detail::WriterSlot{id, std::move(topic), w});
  entities_->writers.push_back(slot);
  return Writer<Msg>(entities_, std::move(slot));
}

template <class Msg>
Reader<Msg> Node::reader(TopicId id, std::size_t mailbox_capacity, const std::string& name) {
  std::string topic = endpoint_topic(id, MsgTraits<Msg>::topic, name);
  Reader<Msg> r;
  r.mailbox_ = std::make_unique<detail::Mailbox<Msg>>(mailbox_capacity);
  r.slot_ = std::make_shared<detail::ReaderSlot>(detail::ReaderSlot{id, std::move(topic), r.mailbox_.get(), nullptr});
  r.slot_->reader = detail::create_reader(*entities_, id, r.slot_->name, r.mailbox_.get());
  r.entities_ = entities_;
  entities_->readers.push_back(r.slot_);
  return r;
}

// One of each for every row of the topic table.
#define SHAPEFORM_INSTANTIATE_ENDPOINTS(Id, name, Type, ...)                 \
  template class Writer<Type>;                                               \
  template class Reader<Type>;                                               \
  template Writer<Type> Node::writer<Type>(TopicId, const std::string&); \
  template Reader<Type> Node::reader<Type>(TopicId, std::size_t, const std::string&);
SHAPEFORM_TOPICS(SHAPEFORM_INSTANTIATE_ENDPOINTS)
#undef SHAPEFORM_INSTANTIATE_ENDPOINTS

}  // namespace shapeform::dds
