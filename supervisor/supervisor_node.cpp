// DDS wiring of the supervisor: one fixed-rate loop that drains agent states, publishes the tracking
// target, computes/publishes/records metrics, and runs console and script commands between ticks.
// What it prints is composed in presentation.cpp.
#include "supervisor_node.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <set>

#include <unistd.h>

#include <nlohmann/json.hpp>

#include "app/json.hpp"
#include "console_input.hpp"
#include "console_parser.hpp"
#include "protocol/command_arbiter.hpp"
#include "dds/convert.hpp"
#include "dds/node.hpp"
#include "dds/participant.hpp"
#include "dds/state_input.hpp"
#include "presentation.hpp"
#include "record/recorder.hpp"
#include "swarm_monitor.hpp"
#include "util/log.hpp"
#include "util/proc_stats.hpp"
#include "util/rate_loop.hpp"
#include "util/signals.hpp"
#include "util/text.hpp"

namespace shapeform::supervisor {

namespace {

/// Where the supervisor's output goes. Without --json: human text on stdout. With --json: the same
/// text on stderr, and on stdout only JSON lines, one event each.
class Output {
 public:
  explicit Output(bool json) : json_(json), human_(json ? std::cerr : std::cout) {}
  bool json() const { return json_; }
  std::ostream& human() { return human_; }
  /// With --json, `j` with "event": name as one line on stdout.
  void event(const char* name, nlohmann::json j) {
    if (!json_) return;
    j["event"] = name;
    std::cout << j.dump() << std::endl;
  }

 private:
  bool json_;
  std::ostream& human_;
};

std::string fmt(double v, const char* f) {
  char b[32];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

/// The name of a blocking action in the "wait" event.
const char* wait_name(const Action& a) {
  if (std::holds_alternative<WaitConverged>(a)) return "converged";
  if (std::holds_alternative<WaitAgents>(a)) return "agents";
  if (std::holds_alternative<WaitTime>(a)) return "time";
  return "sleep";
}

/// The running supervisor. One thread of control; Fast DDS threads only fill reader mailboxes.
class Supervisor {
 public:
  Supervisor(const config::Config& cfg, const SupervisorOptions& opt)
      : cfg_(cfg),
        opt_(opt),
        out_(opt.json),
        // Agents publish once per period: never call one dead before it missed 3 periods (of
        // agent.idle_rate_hz while it follows no command yet).
        monitor_(static_cast<std::int64_t>(std::max(cfg.supervisor.agent_timeout_s, 3.0 / cfg.agent.rate_hz) * 1e9),
                 cfg.supervisor.converge, cfg.agent.lockstep,
                 static_cast<std::int64_t>(3.0 / cfg.agent.idle_state_rate_hz() * 1e9)),
        recorder_(cfg.supervisor.flush_s),
        current_(cfg.command) {}

  int run();

 private:
  /// One period of the loop.
  void tick(std::int64_t now, bool metrics_due) {
    recover_from_stall();
    drain(now);
    report_membership(now);
    publish_target(now);
    if (metrics_due) metrics_tick(now);
    run_input(now);
  }
  /// The epoch of the command in force (0: none known).
  std::uint64_t epoch() const { return arbiter_.id().epoch; }
  /// Whether the command in force is this supervisor's own publication.
  bool own() const { return arbiter_.has_command() && arbiter_.id().issuer == own_issuer_; }
  /// Who published the command in force, in words ("" when none).
  std::string publisher() const;
  /// {"epoch", "issuer", "publisher", "own"} of the command in force, for the JSON events.
  nlohmann::json in_force_json() const;
  /// Seconds since the supervisor started: a recording's wall_s.
  double wall_s(std::int64_t now) const { return static_cast<double>(now - start_ns_) * 1e-9; }
  /// Model time of the epoch in force by the supervisor's clock; it stands still while held.
  double model_time(std::int64_t now) const {
    if (epoch() == 0 || current_.hold) return 0.0;
    return static_cast<double>(now - epoch_start_ns_) * 1e-9 * cfg_.agent.rate_hz * current_.dt;
  }
  /// The model time the metrics are taken at: the supervisor's clock, or, in lockstep, where the agents
  /// are (the slowest agent on the command: the others are at most one step ahead).
  double metrics_time(std::int64_t now) const {
    if (cfg_.agent.lockstep)
      if (const auto t = monitor_.min_following_model_time(now)) return *t;
    return model_time(now);
  }
  /// Validates the whole --script before anything is sent; false (reported) on a bad line.
  bool load_script();
  void open_dds();
  /// After a stall longer than the peers' lease the participant is recreated (dds::Node); participants
  /// DDS Security refused are reported ("refused" events).
  void recover_from_stall();
  void drain(std::int64_t now);
  /// Takes in the command topic: another participant's command that wins the order is the one in
  /// force from now (learnt); an absurd epoch jump is refused and counted.
  void drain_commands(std::int64_t now);
  /// The arbiter adopted another participant's command: measure against it, say so, end the waits
  /// that were on the command it replaced.
  void learnt(std::int64_t now);
  /// `start`: whether a command is in force that this supervisor did not publish (it then keeps it).
  bool foreign_command_in_force(std::int64_t now) const;
  /// --json: an "agent" event for every agent that became alive or stopped being alive.
  void report_membership(std::int64_t now);
  /// Whether a sample of agent id from `source` is the agent's own (SwarmMonitor::claim); the first
  /// sample of another participant on an id in use is reported (log line, "duplicate" event).
  bool owned(std::int32_t id, const dds::SourceId& source, std::int64_t now);
  void publish_target(std::int64_t now);
  void metrics_tick(std::int64_t now);
  void publish_command(const core::CompiledCommand& cmd, std::int64_t now);
  /// Handles Ctrl-C, runs input lines, tells the console whether the loop is busy.
  void run_input(std::int64_t now);
  /// Runs input lines until one blocks (wait, sleep) or none is available.
  void run_lines(std::int64_t now);
  /// Ctrl-C at the console: cancels the wait (and the script), or arms / performs the quit.
  void interrupt(std::int64_t now);
  /// The `show` answer.
  ShowInfo show_info(std::int64_t now) const;
  /// Executes one parsed action; a blocking one becomes pending_.
  void execute(const Action& a, std::int64_t now);
  /// The pending action's outcome: nullopt while it blocks, else whether it succeeded (false: timed out).
  std::optional<bool> wait_outcome(const Action& a, std::int64_t now);
  void start_recording(const std::string& dir, std::int64_t now);
  /// commands.csv: the command in force (when one is) from now.
  void record_command(std::int64_t now);
  Summary summary(std::int64_t now) const;

  const config::Config& cfg_;
  SupervisorOptions opt_;
  Output out_;
  SwarmMonitor monitor_;
  record::Recorder recorder_;
  /// The command in force, as this supervisor knows it: its own or another participant's, heard on
  /// the command topic (the publisher's sample, or the copy every agent re-offers).
  dds::CommandArbiter arbiter_;
  core::CompiledCommand current_;  ///< the arbiter's command (or the config's, before any)
  std::int64_t epoch_start_ns_ = 0;  ///< when the command in force was published (own) or learnt
  bool clock_synced_ = true;         ///< false: a learnt command whose model clock is still to take from the agents
  std::uint64_t own_epoch_ = 0;      ///< the epoch this supervisor published last (0: none yet)
  std::uint64_t superseded_ = 0;     ///< own_epoch_ once another participant's command replaced it
  std::uint64_t commands_refused_ = 0;
  std::uint64_t last_refused_epoch_ = 0;
  std::string own_name_;             ///< how this supervisor names itself in its commands
  /// The issuer of its commands: its first participant's GUID prefix, kept when a stall recreates the
  /// participant, so that its commands stay its own (and keep their order) for it and for the agents.
  dds::SourceId own_issuer_;
  std::int64_t start_ns_ = util::steady_ns();

  std::unique_ptr<dds::Node> node_;
  dds::Writer<msg::ShapeCommand> command_writer_;
  dds::Writer<msg::TrackingTarget> target_writer_;
  dds::Writer<msg::SwarmMetrics> metrics_writer_;
  dds::StateInput state_input_;  ///< shapeform/state and shapeform/state_batch
  dds::Reader<msg::AgentStatus> status_reader_;
  dds::Reader<msg::ShapeCommand> command_reader_;
  std::vector<dds::Received<msg::ShapeCommand>> commands_;
  std::vector<dds::StateItem> states_;
  std::vector<dds::Received<msg::AgentStatus>> statuses_;
  std::uint64_t rejected_ = 0;
  util::ThrottledLog throttled_{5.0};
  std::set<std::int32_t> alive_ids_;  ///< --json: the agents reported alive

  std::unique_ptr<ScriptSource> script_;
  std::unique_ptr<ConsoleInput> console_;
  std::optional<Action> pending_;
  std::int64_t pending_deadline_ns_ = 0;
  dds::CommandId pending_on_;  ///< the command in force when the pending wait began
  bool quit_ = false;
  int exit_status_ = kExitOk;
  ProgressFilter progress_;
  std::int64_t armed_quit_ns_ = -1;  ///< when Ctrl-C last found nothing to cancel (-1: not armed)
};

std::string Supervisor::publisher() const {
  if (!arbiter_.has_command()) return "";
  if (own()) return own_name_;
  return dds::describe_issuer(arbiter_.current().issuer_name, arbiter_.id().issuer);
}

nlohmann::json Supervisor::in_force_json() const {
  return {{"epoch", epoch()},
          {"issuer", arbiter_.has_command() ? nlohmann::json(dds::to_string(arbiter_.id().issuer)) : nlohmann::json()},
          {"publisher", arbiter_.has_command() ? nlohmann::json(publisher()) : nlohmann::json()},
          {"own", own()}};
}

void Supervisor::drain_commands(std::int64_t now) {
  using Verdict = dds::CommandArbiter::Verdict;
  command_reader_.drain(commands_);
  const std::uint64_t floor = monitor_.min_epoch_followed(now);
  for (const auto& r : commands_) {
    if (!r.valid_data || r.source == node_->source()) continue;  // our own publications are known
    dds::CommandSample c;
    std::string why;
    if (!dds::from_msg(r.msg, r.source, c, why)) {
      ++commands_refused_;
      throttled_.warn("command", "command epoch " + std::to_string(r.msg.epoch()) + " rejected: " + why);
      continue;
    }
    const Verdict v = arbiter_.offer(c, floor);
    if (v == Verdict::Adopted) {
      learnt(now);
    } else if (v == Verdict::Refused) {
      ++commands_refused_;
      const std::string who = dds::describe_issuer(c.issuer_name, c.id.issuer);
      const std::string line =
          "command " + dds::CommandArbiter::refusal(c, arbiter_.reference(floor)) + " (the agents refuse it too)";
      // Each new epoch refused is reported; a publisher repeating one is throttled.
      const bool fresh = c.id.epoch != last_refused_epoch_;
      last_refused_epoch_ = c.id.epoch;
      if (fresh) util::log_warn(line);
      if (fresh || throttled_.warn("command jump", line))
        out_.event("rejected", {{"what", "command"}, {"epoch", c.id.epoch}, {"issuer", dds::to_string(c.id.issuer)},
                                {"publisher", who}, {"why", line}});
    }
  }
  if (arbiter_.has_refused() && arbiter_.recheck(floor)) learnt(now);
}

void Supervisor::learnt(std::int64_t now) {
  const dds::CommandSample& c = arbiter_.current();
  current_ = c.command;
  epoch_start_ns_ = now;
  clock_synced_ = false;
  monitor_.set_command(current_, c.id, now);
  record_command(now);
  const bool replaced_own = own_epoch_ != 0 && superseded_ != own_epoch_;
  if (replaced_own) superseded_ = own_epoch_;
  const std::string who = publisher();
  std::ostream& out = out_.human();
  if (replaced_own)
    out << "epoch " << own_epoch_ << " of this supervisor was superseded by ";
  else
    out << "command in force: ";
  out << "epoch " << c.id.epoch << " of " << who << " (another participant): " << describe_command(current_)
      << "; the metrics measure against it" << std::endl;
  util::log_warn((replaced_own ? "superseded: the agents follow epoch " : "command in force: epoch ") +
                 std::to_string(c.id.epoch) + " of " + who);
  nlohmann::json j = in_force_json();
  j["superseded"] = replaced_own ? nlohmann::json(own_epoch_) : nlohmann::json();
  j["shape"] = std::string(core::to_string(current_.shape.kind));
  j["law"] = std::string(core::to_string(current_.law));
  j["tracking"] = current_.tracking.enabled;
  j["hold"] = current_.hold;
  out_.event("in_force", j);
  // A wait on the command just replaced would measure a command nobody follows any more: it ends.
  if (pending_ && !pending_on_.none() &&
      (std::holds_alternative<WaitConverged>(*pending_) || std::holds_alternative<WaitTime>(*pending_))) {
    out << "wait " << wait_name(*pending_) << ": ended, epoch " << pending_on_.epoch << " was superseded by epoch "
        << c.id.epoch << " of " << who << std::endl;
    out_.event("wait", {{"wait", wait_name(*pending_)},
                        {"ok", false},
                        {"superseded", true},
                        {"epoch", c.id.epoch},
                        {"publisher", who},
                        {"model_time", metrics_time(now)},
                        {"alive", monitor_.alive_count(now)}});
    exit_status_ = kExitWaitTimedOut;
    pending_.reset();
  }
}

bool Supervisor::foreign_command_in_force(std::int64_t now) const {
  if (own_epoch_ != 0) return false;  // this supervisor commands already: `start` is its own choice
  // The agents' states may show it before its sample arrives: it is in force all the same.
  return arbiter_.has_command() || monitor_.min_epoch_followed(now) != 0;
}

void Supervisor::recover_from_stall() {
  for (const dds::SourceId& refused : node_->take_refused())
    out_.event("refused", {{"participant", dds::to_string(refused)}, {"by", dds::to_string(node_->source())}});
  const auto stall_s = node_->recover_if_stalled(1.0 / cfg_.supervisor.target_rate_hz);
  if (!stall_s) return;
  // The new command writer starts empty: offer this supervisor's command in force (same id) to later
  // joiners again (the agents re-offer it too).
  if (own() && !command_writer_.write(dds::to_msg(current_, arbiter_.id(), own_name_)))
    util::log_warn("command write failed");
  out_.event("recovered", {{"stall_s", *stall_s}});
}

void Supervisor::drain(std::int64_t now) {
  drain_commands(now);
  state_input_.drain(states_);
  for (const auto& r : states_) {
    if (r.kind == dds::StateItem::Kind::Gone) {
      // Disposed, or its writer left (its dispose, best effort, may be lost) while it was still heard:
      // a clean exit, logged once. A writer leaving after the agent fell silent (a lease expiring after
      // a kill) changes nothing: that agent is shown dead already.
      // A duplicate's writer leaving (a second process with the id exiting) is not the agent leaving.
      const auto it = monitor_.agents().find(r.id);
      if (it != monitor_.agents().end() && monitor_.alive(it->second, now) &&
          (!r.source.known() || !it->second.source.known() || r.source == it->second.source)) {
        monitor_.on_departed(r.id);
        util::log_info("agent " + std::to_string(r.id) + " left");
      }
      continue;
    }
    if (r.kind == dds::StateItem::Kind::Rejected) {
      ++rejected_;
      throttled_.warn(r.why.substr(0, r.why.find(':')), "agent state rejected: " + r.why);  // per refused field
      continue;
    }
    const dds::StateSample& s = r.state;
    if (!owned(s.id, r.source, now)) {
      ++rejected_;
      continue;
    }
    monitor_.on_state(s.id, s.x, s.prev_x, s.command, s.model_time, now, r.source);
  }
  status_reader_.drain(statuses_);
  for (const auto& r : statuses_) {
    dds::StatusSample s;
    std::string why;
    if (r.valid_data && dds::from_msg(r.msg, s, why) && owned(s.id, r.source, now))
      monitor_.on_status(s.id, s.neighbours_heard, s.samples_rejected);
  }
}

bool Supervisor::owned(std::int32_t id, const dds::SourceId& source, std::int64_t now) {
  const SwarmMonitor::Claim c = monitor_.claim(id, source, now);
  if (c == SwarmMonitor::Claim::NewDuplicate) {
    const std::string owner = dds::to_string(monitor_.agents().at(id).source), other = dds::to_string(source);
    util::log_warn("agent id " + std::to_string(id) + " is published by two participants: " + owner +
                   " (in use) and " + other + " (a second process started with this id? it is ignored)");
    out_.event("duplicate", {{"id", id}, {"source", owner}, {"other", other}});
  }
  return c == SwarmMonitor::Claim::Owner;
}

void Supervisor::report_membership(std::int64_t now) {
  if (!out_.json()) return;
  std::set<std::int32_t> alive;
  for (const auto& [id, a] : monitor_.agents())
    if (monitor_.alive(a, now)) alive.insert(id);
  for (const auto id : alive)
    if (!alive_ids_.count(id)) out_.event("agent", {{"id", id}, {"change", "joined"}});
  for (const auto id : alive_ids_)  // "left": disposed its instance (a clean exit); "lost": fell silent
    if (!alive.count(id))
      out_.event("agent", {{"id", id}, {"change", monitor_.agents().at(id).departed ? "left" : "lost"}});
  alive_ids_.swap(alive);
}

void Supervisor::publish_target(std::int64_t now) {
  // Another participant's command: its publisher publishes the target (or the agents follow its path).
  if (!own() || !current_.tracking.enabled || current_.hold) return;
  const double t = model_time(now);
  const core::Vec2 c = core::centre_at(current_.tracking.path, t);
  target_writer_.write(dds::to_msg(dds::TargetSample{arbiter_.id(), t, c, core::centre_velocity(current_.tracking.path, t), now}));
  recorder_.write_centre(wall_s(now), t, epoch(), c.x(), c.y());
}

void Supervisor::publish_command(const core::CompiledCommand& cmd, std::int64_t now) {
  // After every epoch seen: on the command topic (the arbiter's), and in the agents' states unless
  // that is an absurd jump (the agents refuse one such command too).
  const std::uint64_t floor = monitor_.min_epoch_followed(now);
  std::uint64_t after = epoch();
  if (!dds::CommandArbiter::absurd(monitor_.max_epoch_seen(), arbiter_.reference(floor)))
    after = std::max(after, monitor_.max_epoch_seen());
  const dds::CommandSample sample{cmd, dds::CommandId{after + 1, own_issuer_}, own_name_};
  if (arbiter_.offer(sample, floor) != dds::CommandArbiter::Verdict::Adopted) {  // cannot happen: it is greater
    util::log_error("command epoch " + std::to_string(after + 1) + " not adopted");
    return;
  }
  own_epoch_ = sample.id.epoch;
  current_ = cmd;
  epoch_start_ns_ = now;
  clock_synced_ = true;
  monitor_.set_command(cmd, sample.id, now);
  record_command(now);
  if (!command_writer_.write(dds::to_msg(cmd, sample.id, own_name_))) util::log_warn("command write failed");
  out_.human() << "epoch " << own_epoch_ << ": " << describe_command(cmd) << std::endl;
  nlohmann::json j = in_force_json();
  j["shape"] = std::string(core::to_string(cmd.shape.kind));
  j["law"] = std::string(core::to_string(cmd.law));
  j["tracking"] = cmd.tracking.enabled;
  j["hold"] = cmd.hold;
  out_.event("epoch", j);
}

void Supervisor::metrics_tick(std::int64_t now) {
  if (!clock_synced_) {
    // A learnt command: its model clock is where the agents following it are.
    if (const auto at = monitor_.min_following_model_time(now)) {
      const double ticks = *at / current_.dt;  // agent ticks since the command was adopted
      epoch_start_ns_ = now - static_cast<std::int64_t>(std::llround(ticks / cfg_.agent.rate_hz * 1e9));
      clock_synced_ = true;
    }
  }
  const double t = metrics_time(now);
  // Held, no model time passes: nothing is fed to the convergence detector (it would pile up samples
  // at one instant).
  const SwarmMonitor::Sample s = current_.hold ? monitor_.measure(t, now) : monitor_.update(t, now);
  if (epoch() != 0) metrics_writer_.write(dds::to_msg(s.metrics, epoch(), t, now, s.converged));
  const double wall = wall_s(now);
  if (recorder_.is_open()) {
    try {
      recorder_.write_metrics({wall, t, epoch(), s.alive, s.metrics, s.converged});
      const auto step = static_cast<std::int64_t>(std::llround(t / current_.dt));
      for (const auto& [id, x] : monitor_.alive_positions(now, t))
        recorder_.write_positions(wall, t, step, monitor_.agents().at(id).command.epoch, id, x.x(), x.y());
      recorder_.flush_if_due(record::Recorder::Clock::now());
    } catch (const std::exception& e) {
      throttled_.error("record", std::string("recording: ") + e.what());
    }
  }
  if (progress_.due(s, epoch(), now)) util::log_info(progress_line(s, current_));
}

std::optional<bool> Supervisor::wait_outcome(const Action& a, std::int64_t now) {
  std::ostream& out = out_.human();
  const bool timed_out = now >= pending_deadline_ns_;
  if (const auto* w = std::get_if<WaitConverged>(&a)) {
    if (epoch() != 0 && monitor_.converged()) {
      out << "converged at t=" << fmt(model_time(now), "%.0f") << " ("
          << fmt(static_cast<double>(now - epoch_start_ns_) * 1e-9, "%.1f") << " s after epoch " << epoch()
          << (own() ? std::string() : " of " + publisher()) << ")" << std::endl;
      return true;
    }
    if (!timed_out) return std::nullopt;
    out << "wait converged: timed out after " << w->timeout_s << " s" << std::endl;
    util::log_warn("wait converged timed out after " + fmt(w->timeout_s, "%g") + " s");
    exit_status_ = kExitWaitTimedOut;
    return false;
  }
  if (const auto* w = std::get_if<WaitAgents>(&a)) {
    // N agents alive, and each hears the others (its status says so): a command sent before discovery
    // completes would be followed by agents that do not yet know all their neighbours.
    const int n = monitor_.alive_count(now);
    if (n >= w->count && monitor_.all_hear(w->count - 1, now)) {
      out << "agents: " << n << " alive, each hearing " << w->count - 1 << " or more" << std::endl;
      return true;
    }
    if (!timed_out) return std::nullopt;
    out << "wait agents: timed out after " << w->timeout_s << " s with " << n << " of " << w->count << " agents"
        << std::endl;
    util::log_warn("wait agents timed out with " + std::to_string(n) + " of " + std::to_string(w->count));
    exit_status_ = kExitWaitTimedOut;
    return false;
  }
  if (const auto* w = std::get_if<WaitTime>(&a)) {
    // Done when every agent on the current command has done T of model time by its own count (a
    // loaded agent skips ticks, a lockstep agent waits for the others: wall time is not enough).
    const auto t = monitor_.min_following_model_time(now);
    if (t && monitor_.following_count(now) == monitor_.alive_count(now) && *t >= w->model_time - 1e-9) return true;
    if (!timed_out) return std::nullopt;
    out << "wait time: timed out after " << w->timeout_s << " s" << std::endl;
    exit_status_ = kExitWaitTimedOut;
    return false;
  }
  return timed_out ? std::optional<bool>(true) : std::nullopt;  // Sleep
}

void Supervisor::start_recording(const std::string& dir, std::int64_t now) {
  recorder_.open(dir);  // closes the current recording only once the new one is open
  record_command(now);  // a recording begins with the command its rows are measured against
  out_.event("record", {{"dir", dir}, {"open", true}});
}

void Supervisor::record_command(std::int64_t now) {
  if (!arbiter_.has_command() || !recorder_.is_open()) return;
  try {
    recorder_.write_command(wall_s(now), model_time(now), epoch(), dds::to_string(arbiter_.id().issuer),
                            arbiter_.current().issuer_name, current_);
  } catch (const std::exception& e) {
    throttled_.error("record", std::string("recording: ") + e.what());
  }
}

void Supervisor::execute(const Action& a, std::int64_t now) {
  const auto block = [&](double seconds) {
    pending_ = a;
    pending_on_ = arbiter_.id();
    // Capped at 10^9 s (32 years), so that any accepted number of seconds stays inside int64 ns.
    pending_deadline_ns_ = now + static_cast<std::int64_t>(std::min(seconds, 1e9) * 1e9);
  };
  std::ostream& out = out_.human();
  std::visit(
      [&](const auto& act) {
        using T = std::decay_t<decltype(act)>;
        if constexpr (std::is_same_v<T, SetCommand>) {
          publish_command(act.command, now);
        } else if constexpr (std::is_same_v<T, StartScenario>) {
          if (!act.replace && !opt_.replace_on_start && foreign_command_in_force(now)) {
            // The operator's last command outlives a supervisor restart: it is not replaced unasked.
            out << "start: epoch " << (epoch() != 0 ? epoch() : monitor_.max_epoch_seen()) << " of "
                << (arbiter_.has_command() ? publisher() : std::string("another participant"))
                << " is in force; kept ('start replace' publishes the --config scenario)" << std::endl;
            nlohmann::json j = in_force_json();
            j["kept"] = true;
            out_.event("start_kept", j);
          } else {
            core::CompiledCommand c = cfg_.command;
            c.hold = c.hold || current_.hold;  // only `resume` releases a hold
            publish_command(c, now);
          }
        } else if constexpr (std::is_same_v<T, Hold>) {
          // The tracked path restarts where the agents are (a no-op when already held: model time
          // stands still then), so that `resume` continues from here.
          core::CompiledCommand c = current_;
          if (c.tracking.enabled) c.tracking.path = core::advanced(c.tracking.path, metrics_time(now));
          c.hold = true;
          publish_command(c, now);
        } else if constexpr (std::is_same_v<T, Resume>) {
          if (!current_.hold) {
            out << "resume: nothing is held" << std::endl;
          } else {
            core::CompiledCommand c = current_;
            c.hold = false;
            publish_command(c, now);
          }
        } else if constexpr (std::is_same_v<T, TrackStop>) {
          core::CompiledCommand c = current_;
          if (c.tracking.enabled) c.shape.centre = core::centre_at(c.tracking.path, model_time(now));
          c.tracking.enabled = false;
          publish_command(c, now);
        } else if constexpr (std::is_same_v<T, Status>) {
          const double t = model_time(now);
          const auto rows = agent_rows(monitor_, now, t);
          out << status_table(rows) << std::flush;
          nlohmann::json j = status_json(rows, epoch(), t);
          j.update(in_force_json());
          out_.event("status", j);
        } else if constexpr (std::is_same_v<T, ShowMetrics>) {
          // A query: the detector sees only the metrics ticks.
          const SwarmMonitor::Sample sample = monitor_.measure(metrics_time(now), now);
          nlohmann::json j = metrics_answer(sample, epoch());
          j.update(in_force_json());
          // With --json the human copy stays the JSON object (scripts filter it like the event).
          if (act.json || out_.json()) out << j.dump() << std::endl;
          else out << metrics_table(sample, epoch()) << std::flush;
          out_.event("metrics", j);
        } else if constexpr (std::is_same_v<T, Show>) {
          const ShowInfo info = show_info(now);
          out << show_text(info) << std::flush;
          nlohmann::json j = in_force_json();
          j["command"] = app::command_json(info.command);
          j["superseded"] = info.superseded != 0 ? nlohmann::json(info.superseded) : nlohmann::json();
          j["following"] = info.following;
          j["alive"] = info.alive;
          out_.event("show", j);
        } else if constexpr (std::is_same_v<T, Progress>) {
          if (act.mode == Progress::Mode::Off) progress_.off();
          else if (act.mode == Progress::Mode::Every) progress_.every(act.every_s);
          else progress_.on_change();
        } else if constexpr (std::is_same_v<T, WaitConverged> || std::is_same_v<T, WaitAgents> ||
                             std::is_same_v<T, WaitTime>) {
          block(act.timeout_s);
        } else if constexpr (std::is_same_v<T, Sleep>) {
          block(act.seconds);
        } else if constexpr (std::is_same_v<T, RecordStart>) {
          try {
            start_recording(act.dir, now);
            out << "recording into " << act.dir << std::endl;
          } catch (const std::exception& e) {
            std::cerr << "record start: " << e.what() << std::endl;
          }
        } else if constexpr (std::is_same_v<T, RecordStop>) {
          if (recorder_.is_open()) {
            out << "recording stopped: " << recorder_.dir().string() << std::endl;
            out_.event("record", {{"dir", recorder_.dir().string()}, {"open", false}});
          } else {
            out << "record stop: nothing is being recorded" << std::endl;
          }
          recorder_.close();
        } else if constexpr (std::is_same_v<T, Help>) {
          out << help_text(act.topic) << std::flush;
        } else if constexpr (std::is_same_v<T, Quit>) {
          quit_ = true;
        }
      },
      a);
}

void Supervisor::interrupt(std::int64_t now) {
  std::ostream& out = out_.human();
  if (pending_ || (script_ && !script_->eof())) {
    if (pending_) {
      out << (std::holds_alternative<Sleep>(*pending_) ? std::string("sleep") : std::string("wait ") + wait_name(*pending_))
          << ": cancelled (Ctrl-C)" << std::endl;
      out_.event("wait", {{"wait", wait_name(*pending_)},
                          {"ok", false},
                          {"cancelled", true},
                          {"model_time", metrics_time(now)},
                          {"alive", monitor_.alive_count(now)}});
      pending_.reset();
    }
    if (script_ && !script_->eof()) {
      out << "script " << script_->path() << " abandoned after line " << script_->line_number() << std::endl;
      script_.reset();
    }
    armed_quit_ns_ = -1;
    return;
  }
  if (armed_quit_ns_ >= 0 && now - armed_quit_ns_ <= 1'000'000'000LL) {
    quit_ = true;
    exit_status_ = kExitInterrupted;
    return;
  }
  armed_quit_ns_ = now;
  out << "(Ctrl-C again within 1 s, Ctrl-D or 'quit' to leave)" << std::endl;
}

ShowInfo Supervisor::show_info(std::int64_t now) const {
  ShowInfo info;
  info.command = current_;
  info.epoch = epoch();
  info.own = own();
  info.publisher = publisher();
  info.superseded = own() ? 0 : superseded_;  // once it commands again, its old loss is history
  info.published_s_ago = static_cast<double>(now - epoch_start_ns_) * 1e-9;
  info.agents_epoch = monitor_.max_epoch_seen();
  info.alive = monitor_.alive_count(now);
  info.following = monitor_.following_count(now);
  return info;
}

void Supervisor::run_input(std::int64_t now) {
  if (console_) {
    for (int n = console_->take_interrupts(); n > 0 && !quit_; --n) interrupt(now);
    // Ctrl-D at the terminal: the operator leaves (a recording in progress is closed).
    if (console_->interactive() && console_->eof()) quit_ = true;
  }
  run_lines(now);
  if (console_) {
    std::cout.flush();
    std::cerr.flush();
    console_->set_busy(pending_.has_value() || (script_ && !script_->eof()));
  }
}

void Supervisor::run_lines(std::int64_t now) {
  while (!quit_) {
    if (pending_) {
      const std::optional<bool> ok = wait_outcome(*pending_, now);
      if (!ok) return;
      out_.event("wait", {{"wait", wait_name(*pending_)},
                          {"ok", *ok},
                          {"model_time", metrics_time(now)},
                          {"alive", monitor_.alive_count(now)}});
      pending_.reset();
    }
    LineSource* src = nullptr;
    if (script_ && !script_->eof()) src = script_.get();
    else if (console_) src = console_.get();
    if (!src) return;
    const std::optional<std::string> line = src->poll();
    if (!line) return;
    const ParseResult r = parse_command(*line, current_);
    if (!r.ok()) {
      std::cerr << util::bounded_line(with_location(*src, r.error)) << std::endl;  // it may quote a long line
      continue;
    }
    execute(r.action, now);
  }
}

Summary Supervisor::summary(std::int64_t now) const {
  Summary s;
  s.name = cfg_.name;
  s.command = current_;
  s.epoch = epoch();
  s.commands_refused = commands_refused_;
  s.sample = monitor_.measure(metrics_time(now), now);
  s.agents_seen = monitor_.agents().size();
  const auto& cv = cfg_.supervisor.converge;
  s.settle_time = monitor_.settle_time(cv);
  s.final_positions = monitor_.alive_positions(now);
  for (const auto& [id, x] : s.final_positions) s.final_model_times.push_back(monitor_.agents().at(id).model_time);
  s.samples_rejected = rejected_;
  if (recorder_.is_open()) s.recording = recorder_.dir().string();
  s.exit_status = exit_status_;
  return s;
}

bool Supervisor::load_script() {
  try {
    ScriptSource check(opt_.script);
    bool bad = false;
    core::CompiledCommand c = cfg_.command;
    while (auto line = check.poll()) {
      const ParseResult r = parse_command(*line, c);
      if (!r.ok()) {
        std::cerr << util::bounded_line(with_location(check, r.error)) << std::endl;
        bad = true;
      } else if (const auto* set = std::get_if<SetCommand>(&r.action)) {
        c = set->command;
      }
    }
    if (bad) return false;
    script_ = std::make_unique<ScriptSource>(opt_.script);
    return true;
  } catch (const std::exception& e) {
    std::cerr << "shapeform_supervisor: --script: " << e.what() << std::endl;
    return false;
  }
}

void Supervisor::open_dds() {
  node_ = std::make_unique<dds::Node>(dds::with_identity(cfg_.transport, "supervisor"), "shapeform_supervisor");
  command_writer_ = node_->writer<msg::ShapeCommand>(dds::TopicId::Command);
  target_writer_ = node_->writer<msg::TrackingTarget>(dds::TopicId::Target);
  metrics_writer_ = node_->writer<msg::SwarmMetrics>(dds::TopicId::Metrics);
  state_input_ = dds::StateInput(*node_);
  status_reader_ = node_->reader<msg::AgentStatus>(dds::TopicId::Status);
  command_reader_ = node_->reader<msg::ShapeCommand>(dds::TopicId::Command);
  char host[256] = {};
  if (gethostname(host, sizeof host - 1) != 0) host[0] = '\0';
  own_name_ = node_->name() + " on " + host + " pid " + std::to_string(getpid());
  own_issuer_ = node_->source();
}

int Supervisor::run() {
  util::log_init("supervisor");
  util::install_stop_signals();
  // Validate the whole script before touching the swarm: a bad line is exit status 2, nothing sent.
  if (!opt_.script.empty() && !load_script()) return kExitBadInput;
  util::log_info(std::string("transport: ") + dds::describe(cfg_.transport));
  out_.event("start", {{"config", app::config_json(cfg_)}});
  try {
    open_dds();
  } catch (const std::exception& e) {
    util::log_error(e.what());
    return kExitRuntime;
  }
  if (!opt_.record_dir.empty()) {
    try {
      start_recording(opt_.record_dir, util::steady_ns());
    } catch (const std::exception& e) {
      std::cerr << "shapeform_supervisor: --record: " << e.what() << std::endl;
      return kExitBadInput;
    }
  }
  ConsoleInput::Options console_options;
  console_options.history_file = default_history_file();
  console_options.complete = [](std::string_view before_cursor) {
    const Completion c = complete(before_cursor);
    return ConsoleInput::Completion{c.start, c.candidates};
  };
  console_ = std::make_unique<ConsoleInput>(std::move(console_options));

  util::RateLoop loop(cfg_.supervisor.target_rate_hz);
  const auto metrics_every = std::max<std::uint64_t>(
      1, static_cast<std::uint64_t>(std::llround(cfg_.supervisor.target_rate_hz / cfg_.supervisor.metrics_rate_hz)));
  for (std::uint64_t ticks = 0; !quit_ && loop.wait_next(util::stop_flag()); ++ticks) {
    tick(util::steady_ns(), ticks % metrics_every == 0);
    const bool input_done = (!script_ || script_->eof()) && !pending_ && console_->eof();
    if (input_done && !recorder_.is_open()) break;
  }
  console_.reset();  // the terminal back as it was: the summary is printed straight to it
  const std::int64_t now = util::steady_ns();
  drain(now);
  const Summary s = summary(now);
  if (opt_.json) {
    nlohmann::json j = summary_json(s);
    j.update(in_force_json());  // who published the command the summary measured against
    std::cout << j.dump() << std::endl;
  }
  else std::cout << summary_text(s) << std::flush;
  recorder_.close();
  return exit_status_;
}

}  // namespace

int run_supervisor(const config::Config& cfg, const SupervisorOptions& opt) {
  try {
    Supervisor s(cfg, opt);
    return s.run();
  } catch (const dds::SecurityError& e) {
    util::log_error(e.what());
    return kExitBadInput;  // a key file or keystore that cannot work
  } catch (const std::exception& e) {
    util::log_error(e.what());
    return kExitRuntime;
  }
}

}  // namespace shapeform::supervisor
