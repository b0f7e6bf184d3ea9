#include "executor.hpp"

#include <exception>
#include <ostream>
#include <variant>

#include "app/json.hpp"
#include "console_parser.hpp"
#include "util/clock.hpp"

namespace shapeform::supervisor {

Executor::Executor(const core::CompiledCommand& scenario, bool replace_on_start, ExecutorParts parts)
    : scenario_(scenario), replace_on_start_(replace_on_start), p_(parts) {}

void Executor::operator()(const Action& a, std::int64_t now_ns) {
  std::visit([&](const auto& action) { execute(action, now_ns); }, a);
}

// ---------------------------------------------------------------------------------------------
// Commands

void Executor::execute(const SetCommand& a, std::int64_t now_ns) { p_.authority.publish(a.command, now_ns); }

void Executor::execute(const StartScenario& a, std::int64_t now_ns) {
  CommandAuthority& auth = p_.authority;
  if (!a.replace && !replace_on_start_ && auth.foreign_in_force(now_ns)) {
    // The operator's last command outlives a supervisor restart: it is not replaced unasked.
    p_.out.human() << "start: epoch " << (auth.epoch() != 0 ? auth.epoch() : p_.monitor.max_epoch_seen())
                   << " of " << (auth.has_command() ? auth.publisher() : std::string("another participant"))
                   << " is in force; kept ('start replace' publishes the --config scenario)" << std::endl;
    nlohmann::json j = auth.in_force_json();
    j["kept"] = true;
    p_.out.event("start_kept", j);
    return;
  }
  core::CompiledCommand c = scenario_;
  c.hold = c.hold || auth.current().hold;  // only `resume` releases a hold
  auth.publish(c, now_ns);
}

void Executor::execute(const Hold&, std::int64_t now_ns) {
  // The tracked path restarts where the agents are (a no-op when already held: model time stands
  // still then), so that `resume` continues from here.
  core::CompiledCommand c = p_.authority.current();
  if (c.tracking.enabled)
    c.tracking.path = core::advanced(c.tracking.path, p_.authority.metrics_time(now_ns));
  c.hold = true;
  p_.authority.publish(c, now_ns);
}

void Executor::execute(const Resume&, std::int64_t now_ns) {
  if (!p_.authority.current().hold) {
    p_.out.human() << "resume: nothing is held" << std::endl;
    return;
  }
  core::CompiledCommand c = p_.authority.current();
  c.hold = false;
  p_.authority.publish(c, now_ns);
}

void Executor::execute(const TrackStop&, std::int64_t now_ns) {
  core::CompiledCommand c = p_.authority.current();
  if (c.tracking.enabled) c.shape.centre = core::centre_at(c.tracking.path, p_.authority.model_time(now_ns));
  c.tracking.enabled = false;
  p_.authority.publish(c, now_ns);
}

// ---------------------------------------------------------------------------------------------
// Questions

void Executor::execute(const Status&, std::int64_t now_ns) {
  const double t = p_.authority.model_time(now_ns);
  const auto rows = agent_rows(p_.monitor, now_ns, t);
  p_.out.human() << status_table(rows) << std::flush;
  nlohmann::json j = status_json(rows, p_.authority.epoch(), t);
  j.update(p_.authority.in_force_json());
  p_.out.event("status", j);
}

void Executor::execute(const ShowMetrics& a, std::int64_t now_ns) {
  // A query: the detector sees only the metrics ticks.
  const SwarmMonitor::Sample sample = p_.monitor.measure(p_.authority.metrics_time(now_ns), now_ns);
  nlohmann::json j = metrics_answer(sample, p_.authority.epoch());
  j.update(p_.authority.in_force_json());
  // With --json the human copy stays the JSON object (scripts filter it like the event).
  if (a.json || p_.out.json())
    p_.out.human() << j.dump() << std::endl;
  else
    p_.out.human() << metrics_table(sample, p_.authority.epoch()) << std::flush;
  p_.out.event("metrics", j);
}

void Executor::execute(const Show&, std::int64_t now_ns) {
  const ShowInfo info = show_info(now_ns);
  p_.out.human() << show_text(info) << std::flush;
  nlohmann::json j = p_.authority.in_force_json();
  j["command"] = app::command_json(info.command);
  j["superseded"] = info.superseded != 0 ? nlohmann::json(info.superseded) : nlohmann::json();
  j["following"] = info.following;
  j["alive"] = info.alive;
  p_.out.event("show", j);
}

void Executor::execute(const ShowSafety&, std::int64_t) {
  const core::Command& c = p_.authority.current();
  p_.out.human() << (p_.authority.epoch() == 0 ? "no command in force yet; the --config scenario's:\n" : "")
                 << safety_lines(c) << std::flush;
  nlohmann::json j = p_.authority.in_force_json();
  j["safety"] = app::command_json(c)["safety"];
  p_.out.event("safety", j);
}

ShowInfo Executor::show_info(std::int64_t now_ns) const {
  const CommandAuthority& auth = p_.authority;
  ShowInfo info;
  info.command = auth.current();
  info.epoch = auth.epoch();
  info.own = auth.own();
  info.publisher = auth.publisher();
  info.superseded = auth.own() ? 0 : auth.superseded();  // once it commands again, its old loss is history
  info.published_s_ago = auth.since_epoch_s(now_ns);
  info.agents_epoch = p_.monitor.max_epoch_seen();
  info.alive = p_.monitor.alive_count(now_ns);
  info.following = p_.monitor.following_count(now_ns);
  return info;
}

void Executor::execute(const Progress& a, std::int64_t) {
  if (a.mode == Progress::Mode::Off)
    p_.progress.off();
  else if (a.mode == Progress::Mode::Every)
    p_.progress.every(a.every_s);
  else
    p_.progress.on_change();
}

void Executor::execute(const Help& a, std::int64_t) { p_.out.human() << help_text(a.topic) << std::flush; }

// ---------------------------------------------------------------------------------------------
// Input: waits and quit

void Executor::execute(const WaitConverged& a, std::int64_t now_ns) {
  p_.input.block(Wait(a, now_ns, p_.authority.id()));
}
void Executor::execute(const WaitAgents& a, std::int64_t now_ns) {
  p_.input.block(Wait(a, now_ns, p_.authority.id()));
}
void Executor::execute(const WaitTime& a, std::int64_t now_ns) {
  p_.input.block(Wait(a, now_ns, p_.authority.id()));
}
void Executor::execute(const Sleep& a, std::int64_t now_ns) {
  p_.input.block(Wait(a, now_ns, p_.authority.id()));
}
void Executor::execute(const Quit&, std::int64_t) { p_.input.quit(); }

// ---------------------------------------------------------------------------------------------
// Recording

void Executor::start_recording(const std::string& dir, std::int64_t now_ns) {
  // Closes the current recording only once the new one is open; run.mcap's log times are Unix times.
  p_.recorder.open(dir, util::system_ns() - (now_ns - p_.authority.start_ns()));
  p_.authority.record_command(now_ns);  // a recording begins with the command its rows are measured against
  p_.out.event("record", {{"dir", dir}, {"open", true}});
}

void Executor::execute(const RecordStart& a, std::int64_t now_ns) {
  try {
    start_recording(a.dir, now_ns);
    p_.out.human() << "recording into " << a.dir << std::endl;
  } catch (const std::exception& e) {
    p_.out.errors() << "record start: " << e.what() << std::endl;
  }
}

void Executor::execute(const RecordStop&, std::int64_t) {
  if (p_.recorder.is_open()) {
    p_.out.human() << "recording stopped: " << p_.recorder.dir().string() << std::endl;
    p_.out.event("record", {{"dir", p_.recorder.dir().string()}, {"open", false}});
  } else {
    p_.out.human() << "record stop: nothing is being recorded" << std::endl;
  }
  p_.recorder.close();
}

}  // namespace shapeform::supervisor
