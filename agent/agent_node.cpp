// DDS wiring of the agent: drain inputs into AgentLogic, step, publish. No maths here.
// One process hosts one agent (shapeform_agent) or several (shapeform_agent_group); the loop is the same.
#include "agent_node.hpp"

#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>
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

/// Data ages kept per status period (the rest of a period's samples are not booked).
constexpr std::size_t kAgeCapacity = 4096;
}  // namespace

int run_agent(std::int32_t id, const core::Vec2& start, const config::Config& cfg) {
  return run_agents({id}, {start}, cfg);
}

std::optional<config::Config> load_config(const std::string& prog, const std::string& path,
                                          std::vector<std::string> sets, std::optional<int> domain,
                                          std::optional<std::string> seed) {
  if (domain) sets.push_back("transport.domain=" + std::to_string(*domain));
  if (seed) sets.push_back("swarm.seed=" + *seed);  // the loader checks it (64-bit, >= 0)
  try {
    return config::load(path, sets);
  } catch (const config::ConfigError& e) {
    for (const auto& p : e.problems()) std::cerr << prog << ": " << p << '\n';
    return std::nullopt;
  }
}

int run_agents(const std::vector<std::int32_t>& ids, const std::vector<core::Vec2>& starts,
               const config::Config& cfg) {
  const bool group = ids.size() > 1;
  if (group) {
    util::log_init("agent-group " + std::to_string(ids.front()) + ".." + std::to_string(ids.back()));
  } else {
    util::log_init("agent", ids.front());
  }
  util::install_stop_signals();
  const double period_s = 1.0 / cfg.agent.rate_hz;
  const auto timeout_ns = static_cast<std::int64_t>(cfg.agent.neighbour_timeout_periods * period_s * 1e9);
  std::vector<std::unique_ptr<AgentLogic>> logics;
  logics.reserve(ids.size());
  for (std::size_t k = 0; k < ids.size(); ++k) logics.push_back(std::make_unique<AgentLogic>(ids[k], starts[k], timeout_ns, cfg.agent.lockstep,
                                                 static_cast<int>(std::lround(5.0 * cfg.agent.rate_hz))));
  {
    std::ostringstream s;
    if (group) {
      s << ids.size() << " agents in one process, ";
    } else {
      s << "start (" << starts.front().x() << ", " << starts.front().y() << "), ";
    }
    s << cfg.agent.rate_hz << " Hz, " << dds::describe(cfg.transport) << ", neighbour timeout "
      << cfg.agent.neighbour_timeout_periods << " periods";
    util::log_info(s.str());
  }

  try {
    const std::string node_name = group ? "shapeform_agent_group_" + std::to_string(ids.front())
                                        : "shapeform_agent_" + std::to_string(ids.front());
    dds::Node node(cfg.transport, node_name);
    auto state_writer = node.writer<msg::AgentState>(dds::TopicId::State);
    auto status_writer = node.writer<msg::AgentStatus>(dds::TopicId::Status);
    auto state_reader = node.reader<msg::AgentState>(dds::TopicId::State);
    auto command_reader = node.reader<msg::ShapeCommand>(dds::TopicId::Command);
    auto target_reader = node.reader<msg::TrackingTarget>(dds::TopicId::Target);

    std::vector<dds::Received<msg::AgentState>> states;
    std::vector<dds::Received<msg::ShapeCommand>> commands;
    std::vector<dds::Received<msg::TrackingTarget>> targets;
    std::vector<double> ages_us;
    ages_us.reserve(kAgeCapacity);
    util::ThrottledLog throttled(5.0);
    util::CpuMeter cpu;
    util::RateLoop loop(cfg.agent.rate_hz);
    const auto log_every = std::max<std::uint64_t>(1, static_cast<std::uint64_t>(std::llround(cfg.agent.rate_hz)));  // ~1 s
    const auto status_every = std::max<std::uint64_t>(1, static_cast<std::uint64_t>(std::llround(cfg.agent.rate_hz / cfg.agent.status_rate_hz)));
    const double share = 1.0 / static_cast<double>(ids.size());  // of the process figures, per agent
    std::vector<msg::AgentState> outs(ids.size());
    for (std::size_t k = 0; k < ids.size(); ++k) outs[k].id(ids[k]);
    std::uint64_t seq = 0, ticks = 0;
    int heard_logged = -1;

    while (loop.wait_next(util::stop_flag())) {
      const std::int64_t now = util::steady_ns();
      command_reader.drain(commands);
      for (const auto& c : commands) {
        if (!c.valid_data) continue;
        core::CompiledCommand cmd;
        std::string error;
        if (!dds::from_msg(c.msg, cmd, error)) {
          for (auto& l : logics) l->count_rejected();
          util::log_warn("command epoch " + std::to_string(c.msg.epoch()) + " rejected: " + error);
          continue;
        }
        bool adopted = false;
        for (auto& l : logics) adopted = l->on_command(cmd, c.msg.epoch()) || adopted;
        if (adopted)
          util::log_info("following command epoch " + std::to_string(c.msg.epoch()) + ": " + c.msg.shape_kind() +
                         (cmd.tracking.enabled ? " (tracking)" : ""));
      }
      target_reader.drain(targets);
      for (const auto& t : targets) {
        if (!t.valid_data) continue;
        if (!finite_target(t.msg)) {
          for (auto& l : logics) l->count_rejected();
          throttled.warn("target", "tracking target rejected: non-finite or absurd value");
          continue;
        }
        const TargetSample ts{t.msg.epoch(), t.msg.model_time(), core::Vec2(t.msg.cx(), t.msg.cy()),
                              core::Vec2(t.msg.vx(), t.msg.vy())};
        for (auto& l : logics) l->on_target(ts, t.receive_stamp_ns);
      }
      state_reader.drain(states);
      for (const auto& s : states) {
        if (!s.valid_data) {
          if (s.instance != dds::InstanceState::Alive && s.key_id >= 0)
            for (auto& l : logics) l->on_gone(s.key_id);
          continue;
        }
        std::string why;
        if (!dds::valid_state(s.msg, why)) {
          for (auto& l : logics) l->count_rejected();
          throttled.warn("state", "state sample rejected: " + why);
          continue;
        }
        const core::Vec2 x(s.msg.x(), s.msg.y());
        const std::optional<double> arc = s.msg.has_arc() ? std::optional<double>(s.msg.arc()) : std::nullopt;
        for (auto& l : logics)  // own id ignored
          l->on_state(s.msg.id(), x, s.msg.seq(), s.receive_stamp_ns, s.msg.epoch(), arc, s.msg.model_time(),
                      core::Vec2(s.msg.prev_x(), s.msg.prev_y()),
                      s.msg.has_arc() ? std::optional<double>(s.msg.prev_arc()) : std::nullopt);
        // Data age of samples from agents hosted elsewhere (a process's own samples are not a delivery).
        const bool hosted = std::find(ids.begin(), ids.end(), s.msg.id()) != ids.end();
        if (!hosted && ages_us.size() < ages_us.capacity())
          ages_us.push_back(static_cast<double>(s.receive_stamp_ns - s.msg.stamp_ns()) * 1e-3);
      }
      ++seq;
      const std::int64_t stamp = util::steady_ns();
      for (std::size_t k = 0; k < logics.size(); ++k) {
        AgentLogic& l = *logics[k];
        const bool had_target = l.following_target();
        l.drop_stale(now);
        if (k == 0 && had_target && !l.following_target())
          util::log_warn("tracking target unheard for 1 s: the centre follows the command's path on this agent's clock");
        l.step();
        msg::AgentState& out = outs[k];
        out.seq(seq);
        out.stamp_ns(stamp);
        out.epoch(l.epoch());
        out.model_time(l.model_time());
        out.x(l.position().x());
        out.y(l.position().y());
        out.vx(l.velocity().x());
        out.vy(l.velocity().y());
        // The arc law's agents share their arc lengths so that nobody projects everyone else.
        const std::optional<double> arc = l.command().law == core::Law::Arc ? l.arc() : std::nullopt;
        out.has_arc(arc.has_value());
        out.arc(arc.value_or(0.0));
        out.prev_x(l.previous_position().x());
        out.prev_y(l.previous_position().y());
        out.prev_arc(l.previous_arc().value_or(arc.value_or(0.0)));
        state_writer.write(out);
      }

      int heard = logics.front()->neighbours();
      for (const auto& l : logics) heard = std::min(heard, l->neighbours());
      if (heard != heard_logged && ticks % log_every == 0) {
        heard_logged = heard;
        util::log_info(std::string(group ? "every hosted agent hears at least " : "hearing ") + std::to_string(heard) +
                       " neighbours");
      }
      if (++ticks % status_every == 0) {
        const util::LoopStats ls = loop.stats();
        const double age_p50 = util::percentile(ages_us, 50).value_or(-1);
        const double age_p99 = util::percentile(ages_us, 99).value_or(-1);
        const double cpu_percent = cpu.percent() * share;
        const double rss = util::rss_mb() * share;
        msg::AgentStatus st;
        st.stamp_ns(util::steady_ns());
        st.ticks(ls.ticks);
        st.overruns(ls.overruns);
        st.lateness_max_us(ls.lateness_max_us);
        st.lateness_p99_us(ls.lateness_p99_us);
        st.age_p50_us(age_p50);
        st.age_p99_us(age_p99);
        st.cpu_percent(cpu_percent);
        st.rss_mb(rss);
        for (const auto& l : logics) {
          const AgentCounters& k = l->counters();
          st.id(l->id());
          st.neighbours_heard(l->neighbours());
          st.stale_dropped(k.stale_dropped);
          st.samples_rejected(k.samples_rejected);
          st.samples_received(k.samples_received);
          st.samples_lost(k.samples_lost);
          st.epoch(l->epoch());
          status_writer.write(st);
        }
        ages_us.clear();
      }
    }
    // Leave cleanly: dispose our instances so the others drop us at once, then delete the entities.
    for (const auto& out : outs) state_writer.dispose(out);
    util::log_info("stopping after " + std::to_string(ticks) + " ticks (signal " +
                   std::to_string(util::stop_signal()) + ")");
  } catch (const std::exception& e) {
    util::log_error(e.what());
    return 1;
  }
  return 0;
}

}  // namespace shapeform::agent
