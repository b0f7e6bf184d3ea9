// shapeform_bench_baseline: the floor the agents are measured against. A bare Fast DDS publisher and
// subscriber of the agents' state topic with their payload, QoS, transport and rate, and nothing
// else: no mailbox, no neighbour table, no control law. The listener takes each sample and books its
// data age and sequence gap in place; the loop writes one sample per tick.
//
// Two shapes, as the agents have: `--id i`, one AgentState per tick on shapeform/state (as
// shapeform_agent); `--ids 0-99`, one AgentStateBatch per tick carrying every listed id on
// shapeform/state_batch (as shapeform_agent_group), each element booked as one agent's sample; more
// ids than agent.batch_max_states go in several samples per tick, cut as the group cuts them.
//
// It publishes its statuses exactly as shapeform_agent and shapeform_agent_group do (same fields, same
// meaning, same rate: one AgentStatus per period, or one AgentStatusBatch per period carrying every
// listed id), so the benchmark reads both kinds of process with one probe and one set of formulas.
//
// The participant comes from the project's one factory (dds::create_participant), so the transport
// profile and the loopback rule are the agents' own.
#include <algorithm>
#include <array>
#include <cstdint>
#include <iostream>
#include <mutex>
#include <string>
#include <type_traits>
#include <vector>

#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/publisher/qos/PublisherQos.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/subscriber/qos/SubscriberQos.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <fastdds/dds/topic/qos/TopicQos.hpp>

#include "dds/convert.hpp"
#include "dds/participant_factory.hpp"
#include "dds/topic_qos.hpp"
#include "shapeform/msg/AgentStateBatchPubSubTypes.h"
#include "shapeform/msg/AgentStatePubSubTypes.h"
#include "shapeform/msg/AgentStatusBatchPubSubTypes.h"
#include "shapeform/msg/AgentStatusPubSubTypes.h"
#include "app/app.hpp"
#include "util/log.hpp"
#include "util/proc_stats.hpp"
#include "util/rate_loop.hpp"
#include "util/signals.hpp"
#include "util/stats.hpp"

namespace {

namespace fdds = eprosima::fastdds::dds;
namespace sdds = shapeform::dds;
namespace msg = shapeform::msg;
namespace util = shapeform::util;
namespace config = shapeform::config;

/// Largest agent id the listener books (agent ids are 0..9999).
constexpr std::size_t kMaxIds = 10000;
/// Data ages kept per status period (the agent keeps 4096 too).
constexpr std::size_t kAgeCapacity = 4096;

/// Books every received agent state (an AgentState, or one element of an AgentStateBatch): data age,
/// sequence gaps, last heard, per sending agent id. Receive thread and loop share it under a mutex.
class Ledger {
 public:
  explicit Ledger(const std::vector<std::int32_t>& hosted) {
    ages_us_.reserve(kAgeCapacity);
    for (const auto id : hosted) hosted_[static_cast<std::size_t>(id)] = true;
  }

  /// One state of agent `id` with sequence `seq`, stamped `stamp_ns`, taken at `now`. The process's
  /// own ids are booked too (a co-hosted agent hears it, as in shapeform_agent_group), but only
  /// states from other processes give a data age.
  void book(std::int32_t id, std::uint64_t seq, std::int64_t stamp_ns, std::int64_t now) {
    if (id < 0 || static_cast<std::size_t>(id) >= kMaxIds) return;
    const auto slot = static_cast<std::size_t>(id);
    if (last_seq_[slot] != 0 && seq <= last_seq_[slot]) return;  // duplicate or reordered
    if (last_seq_[slot] != 0) {
      lost_[slot] += seq - last_seq_[slot] - 1;
      all_.lost += seq - last_seq_[slot] - 1;
    }
    last_seq_[slot] = seq;
    last_seen_ns_[slot] = now;
    ++received_[slot];
    ++all_.received;
    ids_seen_ = std::max(ids_seen_, slot + 1);
    if (!hosted_[slot] && ages_us_.size() < ages_us_.capacity())
      ages_us_.push_back(static_cast<double>(now - stamp_ns) * 1e-3);
  }

  std::mutex& mutex() { return mutex_; }

  struct Snapshot {
    std::uint64_t received = 0;  ///< every agent's states booked
    std::uint64_t lost = 0;
    int heard = 0;               ///< agents heard within the timeout
  };

  /// For the agents selves[k], k = phase, phase + every, ...: the counters now and the number of other
  /// agents heard within timeout_ns (one pass over the ids heard so far, then each agent's own figures
  /// taken out), into out (cleared first).
  void snapshot(const std::vector<std::int32_t>& selves, std::size_t phase, std::size_t every, std::int64_t now,
                std::int64_t timeout_ns, std::vector<Snapshot>& out) {
    out.clear();
    std::lock_guard<std::mutex> lock(mutex_);
    const auto fresh = [&](std::size_t i) { return last_seen_ns_[i] != 0 && now - last_seen_ns_[i] <= timeout_ns; };
    Snapshot all = all_;
    for (std::size_t i = 0; i < ids_seen_; ++i)
      if (fresh(i)) ++all.heard;
    for (std::size_t k = phase; k < selves.size(); k += every) {
      const auto i = static_cast<std::size_t>(selves[k]);
      out.push_back({all.received - received_[i], all.lost - lost_[i], all.heard - (fresh(i) ? 1 : 0)});
    }
  }

  /// This status period's ages (swapped out).
  void take_ages(std::vector<double>& out) {
    out.clear();
    std::lock_guard<std::mutex> lock(mutex_);
    out.swap(ages_us_);
    if (ages_us_.capacity() < kAgeCapacity) ages_us_.reserve(kAgeCapacity);
  }

 private:
  std::mutex mutex_;
  std::vector<double> ages_us_;
  std::array<bool, kMaxIds> hosted_{};
  std::array<std::uint64_t, kMaxIds> last_seq_{};
  std::array<std::int64_t, kMaxIds> last_seen_ns_{};
  std::array<std::uint64_t, kMaxIds> received_{};
  std::array<std::uint64_t, kMaxIds> lost_{};
  Snapshot all_;              ///< received and lost, summed over every id
  std::size_t ids_seen_ = 0;  ///< one past the largest id booked
};

/// Takes each sample of Msg (AgentState or AgentStateBatch) on the receive thread into the ledger.
template <class Msg>
class StateListener final : public fdds::DataReaderListener {
 public:
  explicit StateListener(Ledger& ledger) : ledger_(ledger) {}

  void on_data_available(fdds::DataReader* reader) override {
    fdds::SampleInfo info;
    while (reader->take_next_sample(&sample_, &info) == eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;
      const std::int64_t now = util::steady_ns();
      std::lock_guard<std::mutex> lock(ledger_.mutex());
      if constexpr (std::is_same_v<Msg, msg::AgentStateBatch>) {
        for (const auto& s : sample_.states()) ledger_.book(s.id(), s.seq(), s.stamp_ns(), now);
      } else {
        ledger_.book(sample_.id(), sample_.seq(), sample_.stamp_ns(), now);
      }
    }
  }

 private:
  Ledger& ledger_;
  Msg sample_;  // take buffer, reused (receive thread only)
};

template <class PubSub>
void register_type(fdds::DomainParticipant* p) {
  fdds::TypeSupport type(new PubSub());
  if (type.register_type(p) != eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK)
    throw std::runtime_error("register_type failed for " + type.get_type_name());
}

/// `ids`: one id publishes AgentState (as shapeform_agent) unless `batch`; with `batch`, one
/// AgentStateBatch of all of them per tick (as shapeform_agent_group).
int run(const std::vector<std::int32_t>& ids, bool batch, const config::Config& cfg) {
  const std::int32_t first = ids.front();
  util::log_init("baseline", first);
  util::install_stop_signals();
  util::log_info(std::to_string(cfg.agent.rate_hz) + " Hz, " + sdds::describe(cfg.transport) +
                 (batch ? ", " + std::to_string(ids.size()) + " agents in one AgentStateBatch per tick" : ""));

  fdds::DomainParticipant* participant = nullptr;
  try {
    participant = sdds::create_participant(sdds::with_identity(cfg.transport, "agent_" + std::to_string(first)),
                                              "shapeform_bench_baseline_" + std::to_string(first));
    const sdds::TopicId state_id = batch ? sdds::TopicId::StateBatch : sdds::TopicId::State;
    if (batch) register_type<msg::AgentStateBatchPubSubType>(participant);
    else register_type<msg::AgentStatePubSubType>(participant);
    const sdds::TopicId status_id = batch ? sdds::TopicId::StatusBatch : sdds::TopicId::Status;
    if (batch) register_type<msg::AgentStatusBatchPubSubType>(participant);
    else register_type<msg::AgentStatusPubSubType>(participant);
    auto* state_topic = participant->create_topic(sdds::topic_name(state_id), sdds::type_name(state_id), fdds::TopicQos());
    auto* status_topic =
        participant->create_topic(sdds::topic_name(status_id), sdds::type_name(status_id), fdds::TopicQos());
    auto* publisher = participant->create_publisher(fdds::PublisherQos());
    auto* subscriber = participant->create_subscriber(fdds::SubscriberQos());
    if (!state_topic || !status_topic || !publisher || !subscriber)
      throw std::runtime_error("create_topic/publisher/subscriber failed");
    auto* state_writer = publisher->create_datawriter(state_topic, sdds::writer_qos(state_id));
    auto* status_writer = publisher->create_datawriter(status_topic, sdds::writer_qos(status_id));
    Ledger ledger(ids);
    StateListener<msg::AgentState> single_listener(ledger);
    StateListener<msg::AgentStateBatch> batch_listener(ledger);
    fdds::DataReaderListener* listener = batch ? static_cast<fdds::DataReaderListener*>(&batch_listener) : &single_listener;
    auto* state_reader = subscriber->create_datareader(state_topic, sdds::reader_qos(state_id, cfg.transport), listener,
                                                       fdds::StatusMask::data_available());
    if (!state_writer || !status_writer || !state_reader) throw std::runtime_error("create endpoint failed");

    const std::int64_t timeout_ns = cfg.agent.neighbour_timeout_ns();
    const auto status_every = std::max<std::uint64_t>(
        1, static_cast<std::uint64_t>(std::llround(cfg.agent.rate_hz / cfg.agent.status_rate_hz)));
    const double share = 1.0 / static_cast<double>(ids.size());  // of the process figures, per agent
    util::RateLoop loop(cfg.agent.rate_hz);
    util::CpuMeter cpu;
    std::vector<double> ages;
    ages.reserve(kAgeCapacity);
    msg::AgentState one;
    one.id(first);
    // As shapeform_agent_group cuts them: one sample (instance) per part of agent.batch_max_states.
    std::vector<msg::AgentStateBatch> parts;
    for (const auto& [begin, end] : sdds::batch_ranges(ids.size(), static_cast<std::size_t>(cfg.agent.batch_max_states))) {
      msg::AgentStateBatch& many = parts.emplace_back();
      many.first_id(ids[begin]);
      for (std::size_t k = begin; k < end; ++k) {
        msg::AgentState e;
        e.id(ids[k]);
        many.states().push_back(e);
      }
    }
    std::uint64_t seq = 0, ticks = 0;
    std::vector<Ledger::Snapshot> snaps;
    std::vector<sdds::StatusSample> statuses;  // this period's, one per id
    msg::AgentStatusBatch status_batch;        // reused
    while (loop.wait_next(util::stop_flag())) {
      ++seq;
      const std::int64_t stamp = util::steady_ns();
      if (batch) {
        for (auto& many : parts) {
          for (auto& e : many.states()) {
            e.seq(seq);
            e.stamp_ns(stamp);
          }
          state_writer->write(&many);
        }
      } else {
        one.seq(seq);
        one.stamp_ns(stamp);
        state_writer->write(&one);
      }
      // As shapeform_agent and shapeform_agent_group: every status once per period, a batch's in one
      // AgentStatusBatch (one sample per part of kBatchStatusesPerDatagram).
      if (++ticks % status_every == 0) {
        ledger.take_ages(ages);
        sdds::StatusSample st = sdds::process_status(util::steady_ns(), loop.stats(), ages, cpu.percent() * share,
                                                     util::rss_mb() * share);
        st.stamp_ns = util::steady_ns();
        ledger.snapshot(ids, 0, 1, st.stamp_ns, timeout_ns, snaps);
        statuses.clear();
        for (std::size_t k = 0; k < ids.size(); ++k) {
          st.id = ids[k];
          st.neighbours_heard = snaps[k].heard;
          st.samples_received = snaps[k].received;
          st.samples_lost = snaps[k].lost;
          statuses.push_back(st);
        }
        if (batch) {
          for (const auto& [begin, end] : sdds::batch_ranges(statuses.size(), sdds::kBatchStatusesPerDatagram)) {
            sdds::to_msg(statuses, begin, end, status_batch);
            status_writer->write(&status_batch);
          }
        } else {
          msg::AgentStatus wire = sdds::to_msg(statuses.front());
          status_writer->write(&wire);
        }
      }
    }
    if (batch)
      for (auto& many : parts) state_writer->dispose(&many, fdds::HANDLE_NIL);
    else state_writer->dispose(&one, fdds::HANDLE_NIL);
    state_reader->set_listener(nullptr);
    util::log_info("stopping after " + std::to_string(ticks) + " ticks");
    sdds::delete_participant(participant);
  } catch (const std::exception& e) {
    util::log_error(e.what());
    sdds::delete_participant(participant);
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  shapeform::app::App app("shapeform_bench_baseline",
                "shapeform_bench_baseline: bare agent-state pub/sub at the agents' rate and transport (benchmark floor).");
  int id = -1;
  std::string ids_text;
  auto* id_opt = app.cli().add_option("--id", id, "one agent: process id, 0..9999 (unique in the run); AgentState per tick");
  app.cli()
      .add_option("--ids", ids_text,
                  "several agents as shapeform_agent_group hosts them (0-99, or 0,3,5): one AgentStateBatch per tick")
      ->excludes(id_opt);
  app.add_config_options("YAML config (agent.rate_hz, agent.status_rate_hz, transport.*)");
  if (const auto rc = app.parse(argc, argv)) return *rc;
  std::vector<std::int32_t> ids;
  if (app.given("--ids")) {
    std::string error;
    if (!shapeform::app::parse_id_list(ids_text, static_cast<int>(kMaxIds) - 1, 1000, ids, error))
      return app.usage_error("--ids: " + error);
  } else {
    if (!app.given("--id")) return app.usage_error("give --id N (one agent) or --ids LIST (a group)");
    if (id < 0 || id > 9999) return app.usage_error("--id must be in 0..9999, got " + std::to_string(id));
    ids.push_back(id);
  }
  const auto cfg = app.load_config();
  if (!cfg) return shapeform::app::kExitUsage;
  return run(ids, app.given("--ids"), *cfg);
}
