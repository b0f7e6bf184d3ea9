// shapeform_bench_baseline: the floor the agents are measured against. A bare Fast DDS publisher and
// subscriber of the AgentState topic with the agents' payload, QoS, transport and rate, and nothing
// else: no mailbox, no neighbour table, no control law. The listener takes each sample and books its
// data age and sequence gap in place; the loop writes one AgentState per tick.
//
// It publishes AgentStatus exactly as shapeform_agent does (same fields, same meaning, same rate), so
// the benchmark reads both kinds of process with one probe and one set of formulas.
//
// The participant comes from the project's one factory (dds::create_participant), so the transport
// profile and the loopback rule are the agents' own.
#include <algorithm>
#include <array>
#include <cstdint>
#include <iostream>
#include <mutex>
#include <string>
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
#include "dds/participant.hpp"
#include "dds/topics.hpp"
#include "shapeform/msg/AgentStatePubSubTypes.h"
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

/// Books every AgentState sample on the receive thread: age, sequence gaps, last heard.
class StateListener final : public fdds::DataReaderListener {
 public:
  explicit StateListener(std::int32_t self) : self_(self) {
    ages_us_.reserve(kAgeCapacity);
    last_seq_.fill(0);
    last_seen_ns_.fill(0);
  }

  void on_data_available(fdds::DataReader* reader) override {
    fdds::SampleInfo info;
    while (reader->take_next_sample(&sample_, &info) == eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;
      const std::int64_t now = util::steady_ns();
      const std::int32_t id = sample_.id();
      if (id == self_ || id < 0 || static_cast<std::size_t>(id) >= kMaxIds) continue;
      const auto slot = static_cast<std::size_t>(id);
      std::lock_guard<std::mutex> lock(mutex_);
      const std::uint64_t seq = sample_.seq();
      if (last_seq_[slot] != 0 && seq <= last_seq_[slot]) continue;  // duplicate or reordered
      if (last_seq_[slot] != 0) lost_ += seq - last_seq_[slot] - 1;
      last_seq_[slot] = seq;
      last_seen_ns_[slot] = now;
      ++received_;
      if (ages_us_.size() < ages_us_.capacity()) ages_us_.push_back(static_cast<double>(now - sample_.stamp_ns()) * 1e-3);
    }
  }

  struct Snapshot {
    std::uint64_t received = 0;
    std::uint64_t lost = 0;
    int heard = 0;
  };

  /// Counters now, the number of peers heard within timeout_ns, and this period's ages (swapped out).
  Snapshot snapshot(std::int64_t now, std::int64_t timeout_ns, std::vector<double>& ages_out) {
    Snapshot s;
    ages_out.clear();
    std::lock_guard<std::mutex> lock(mutex_);
    s.received = received_;
    s.lost = lost_;
    for (std::size_t i = 0; i < kMaxIds; ++i)
      if (last_seen_ns_[i] != 0 && now - last_seen_ns_[i] <= timeout_ns) ++s.heard;
    ages_out.swap(ages_us_);
    if (ages_us_.capacity() < kAgeCapacity) ages_us_.reserve(kAgeCapacity);
    return s;
  }

 private:
  const std::int32_t self_;
  msg::AgentState sample_;  // take buffer, reused (receive thread only)
  std::mutex mutex_;
  std::vector<double> ages_us_;
  std::array<std::uint64_t, kMaxIds> last_seq_{};
  std::array<std::int64_t, kMaxIds> last_seen_ns_{};
  std::uint64_t received_ = 0;
  std::uint64_t lost_ = 0;
};

template <class PubSub>
void register_type(fdds::DomainParticipant* p) {
  fdds::TypeSupport type(new PubSub());
  if (type.register_type(p) != eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK)
    throw std::runtime_error("register_type failed for " + type.get_type_name());
}

int run(std::int32_t id, const config::Config& cfg) {
  util::log_init("baseline", id);
  util::install_stop_signals();
  util::log_info(std::to_string(cfg.agent.rate_hz) + " Hz, " + sdds::describe(cfg.transport));

  fdds::DomainParticipant* participant = nullptr;
  try {
    participant = sdds::create_participant(sdds::with_identity(cfg.transport, "agent_" + std::to_string(id)),
                                              "shapeform_bench_baseline_" + std::to_string(id));
    register_type<msg::AgentStatePubSubType>(participant);
    register_type<msg::AgentStatusPubSubType>(participant);
    auto* state_topic = participant->create_topic(sdds::topic_name(sdds::TopicId::State),
                                                  sdds::type_name(sdds::TopicId::State), fdds::TopicQos());
    auto* status_topic = participant->create_topic(sdds::topic_name(sdds::TopicId::Status),
                                                   sdds::type_name(sdds::TopicId::Status), fdds::TopicQos());
    auto* publisher = participant->create_publisher(fdds::PublisherQos());
    auto* subscriber = participant->create_subscriber(fdds::SubscriberQos());
    if (!state_topic || !status_topic || !publisher || !subscriber)
      throw std::runtime_error("create_topic/publisher/subscriber failed");
    auto* state_writer = publisher->create_datawriter(state_topic, sdds::writer_qos(sdds::TopicId::State));
    auto* status_writer = publisher->create_datawriter(status_topic, sdds::writer_qos(sdds::TopicId::Status));
    StateListener listener(id);
    auto* state_reader = subscriber->create_datareader(state_topic, sdds::reader_qos(sdds::TopicId::State, cfg.transport), &listener,
                                                       fdds::StatusMask::data_available());
    if (!state_writer || !status_writer || !state_reader) throw std::runtime_error("create endpoint failed");

    const double period_s = 1.0 / cfg.agent.rate_hz;
    const auto timeout_ns = static_cast<std::int64_t>(cfg.agent.neighbour_timeout_periods * period_s * 1e9);
    const auto status_every = std::max<std::uint64_t>(
        1, static_cast<std::uint64_t>(std::llround(cfg.agent.rate_hz / cfg.agent.status_rate_hz)));
    util::RateLoop loop(cfg.agent.rate_hz);
    util::CpuMeter cpu;
    std::vector<double> ages;
    ages.reserve(kAgeCapacity);
    msg::AgentState out;
    out.id(id);
    std::uint64_t seq = 0, ticks = 0;
    while (loop.wait_next(util::stop_flag())) {
      out.seq(++seq);
      out.stamp_ns(util::steady_ns());
      state_writer->write(&out);
      if (++ticks % status_every == 0) {
        const std::int64_t now = util::steady_ns();
        const auto snap = listener.snapshot(now, timeout_ns, ages);
        sdds::StatusSample st = sdds::process_status(now, loop.stats(), ages, cpu.percent(), util::rss_mb());
        st.id = id;
        st.neighbours_heard = snap.heard;
        st.samples_received = snap.received;
        st.samples_lost = snap.lost;
        msg::AgentStatus wire = sdds::to_msg(st);
        status_writer->write(&wire);
      }
    }
    state_writer->dispose(&out, fdds::HANDLE_NIL);
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
                "shapeform_bench_baseline: bare AgentState pub/sub at the agents' rate and transport (benchmark floor).");
  int id = -1;
  app.cli().add_option("--id", id, "process id, 0..9999 (unique in the run)")->required();
  app.add_config_options("YAML config (agent.rate_hz, agent.status_rate_hz, transport.*)");
  if (const auto rc = app.parse(argc, argv)) return *rc;
  if (id < 0 || id > 9999) return app.usage_error("--id must be in 0..9999, got " + std::to_string(id));
  const auto cfg = app.load_config();
  if (!cfg) return shapeform::app::kExitUsage;
  return run(id, *cfg);
}
