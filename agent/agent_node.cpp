// DDS wiring of the agent: drain inputs into AgentLogic, step, publish. No maths here.
#include "agent_node.hpp"

#include <cmath>
#include <sstream>

#include "agent_logic.hpp"
#include "dds/convert.hpp"
#include "dds/node.hpp"
#include "dds/participant.hpp"
#include "shapeform/msg/AgentState.h"
#include "shapeform/msg/AgentStatus.h"
#include "shapeform/msg/ShapeCommand.h"
#include "shapeform/msg/TrackingTarget.h"
#include "util/log.hpp"
#include "util/proc_stats.hpp"
#include "util/rate_loop.hpp"
#include "util/signals.hpp"
#include "util/stats.hpp"

namespace shapeform::agent {

namespace {
bool finite_target(const msg::TrackingTarget& t) {
  for (double v : {t.model_time(), t.cx(), t.cy(), t.vx(), t.vy()})
    if (!std::isfinite(v) || std::abs(v) > dds::kStateLimit) return false;
  return true;
}
}  // namespace

int run_agent(std::int32_t id, const core::Vec2& start, const config::Config& cfg) {
  util::log_init("agent", id);
  util::install_stop_signals();
  const double period_s = 1.0 / cfg.agent.rate_hz;
  const auto timeout_ns = static_cast<std::int64_t>(cfg.agent.neighbour_timeout_periods * period_s * 1e9);
  AgentLogic logic(id, start, timeout_ns);
  {
    std::ostringstream s;
    s << "start (" << start.x() << ", " << start.y() << "), " << cfg.agent.rate_hz << " Hz, "
      << dds::describe(cfg.transport) << ", neighbour timeout " << cfg.agent.neighbour_timeout_periods
      << " periods";
    util::log_info(s.str());
  }

  try {
    dds::Node node(cfg.transport, "shapeform_agent_" + std::to_string(id));
    auto state_writer = node.writer<msg::AgentState>(dds::TopicId::State);
    auto status_writer = node.writer<msg::AgentStatus>(dds::TopicId::Status);
    auto state_reader = node.reader<msg::AgentState>(dds::TopicId::State);
    auto command_reader = node.reader<msg::ShapeCommand>(dds::TopicId::Command);
    auto target_reader = node.reader<msg::TrackingTarget>(dds::TopicId::Target);

    std::vector<dds::Received<msg::AgentState>> states;
    std::vector<dds::Received<msg::ShapeCommand>> commands;
    std::vector<dds::Received<msg::TrackingTarget>> targets;
    std::vector<double> ages_us;
    ages_us.reserve(4096);
    util::ThrottledLog throttled(5.0);
    util::CpuMeter cpu;
    util::RateLoop loop(cfg.agent.rate_hz);
    const auto status_every = std::max<std::uint64_t>(1, static_cast<std::uint64_t>(std::llround(cfg.agent.rate_hz / cfg.agent.status_rate_hz)));
    msg::AgentState out;
    out.id(id);
    std::uint64_t seq = 0, ticks = 0;
    int heard_logged = -1;

    while (loop.wait_next(util::stop_flag())) {
      const std::int64_t now = util::steady_ns();
      command_reader.drain(commands);
      for (const auto& c : commands) {
        if (!c.valid_data) continue;
        core::Command cmd;
        std::string error;
        if (!dds::from_msg(c.msg, cmd, error)) {
          logic.count_rejected();
          util::log_warn("command epoch " + std::to_string(c.msg.epoch()) + " rejected: " + error);
          continue;
        }
        if (logic.on_command(cmd, c.msg.epoch()))
          util::log_info("following command epoch " + std::to_string(c.msg.epoch()) + ": " + c.msg.shape_kind() +
                         (cmd.tracking.enabled ? " (tracking)" : ""));
      }
      target_reader.drain(targets);
      for (const auto& t : targets) {
        if (!t.valid_data) continue;
        if (!finite_target(t.msg)) {
          logic.count_rejected();
          throttled.warn("target", "tracking target rejected: non-finite or absurd value");
          continue;
        }
        logic.on_target({t.msg.epoch(), t.msg.model_time(), core::Vec2(t.msg.cx(), t.msg.cy()),
                         core::Vec2(t.msg.vx(), t.msg.vy())});
      }
      state_reader.drain(states);
      for (const auto& s : states) {
        if (!s.valid_data) {
          if (s.instance != dds::InstanceState::Alive && s.key_id >= 0) logic.on_gone(s.key_id);
          continue;
        }
        std::string why;
        if (!dds::valid_state(s.msg, why)) {
          logic.count_rejected();
          throttled.warn("state", "state sample rejected: " + why);
          continue;
        }
        if (s.msg.id() == id) continue;
        logic.on_state(s.msg.id(), core::Vec2(s.msg.x(), s.msg.y()), s.msg.seq(), s.receive_stamp_ns);
        if (ages_us.size() < ages_us.capacity()) ages_us.push_back(static_cast<double>(s.receive_stamp_ns - s.msg.stamp_ns()) * 1e-3);
      }
      logic.drop_stale(now);
      logic.step();

      out.seq(++seq);
      out.stamp_ns(util::steady_ns());
      out.epoch(logic.epoch());
      out.model_time(logic.model_time());
      out.x(logic.position().x());
      out.y(logic.position().y());
      out.vx(logic.velocity().x());
      out.vy(logic.velocity().y());
      state_writer.write(out);

      if (logic.neighbours() != heard_logged && ticks % static_cast<std::uint64_t>(cfg.agent.rate_hz) == 0) {
        heard_logged = logic.neighbours();
        util::log_info("hearing " + std::to_string(heard_logged) + " neighbours");
      }
      if (++ticks % status_every == 0) {
        const util::LoopStats ls = loop.stats();
        const AgentCounters& k = logic.counters();
        msg::AgentStatus st;
        st.id(id);
        st.stamp_ns(util::steady_ns());
        st.ticks(ls.ticks);
        st.overruns(ls.overruns);
        st.lateness_max_us(ls.lateness_max_us);
        st.lateness_p99_us(ls.lateness_p99_us);
        st.neighbours_heard(logic.neighbours());
        st.stale_dropped(k.stale_dropped);
        st.samples_rejected(k.samples_rejected);
        st.samples_received(k.samples_received);
        st.samples_lost(k.samples_lost);
        st.age_p50_us(util::percentile(ages_us, 50).value_or(-1));
        st.age_p99_us(util::percentile(ages_us, 99).value_or(-1));
        st.cpu_percent(cpu.percent());
        st.rss_mb(util::rss_mb());
        st.epoch(logic.epoch());
        status_writer.write(st);
        ages_us.clear();
      }
    }
    // Leave cleanly: dispose our instance so the others drop us at once, then delete the entities.
    state_writer.dispose(out);
    util::log_info("stopping after " + std::to_string(ticks) + " ticks (signal " +
                   std::to_string(util::stop_signal()) + ")");
  } catch (const std::exception& e) {
    util::log_error(e.what());
    return 1;
  }
  return 0;
}

}  // namespace shapeform::agent
