// DDS wiring of the agent: drain inputs into AgentLogic, step, publish, report. No maths here.
// One process hosts one agent (shapeform_agent) or several (shapeform_agent_group); the loop is the same.
#include "agent_node.hpp"

#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <iostream>
#include <memory>
#include <mutex>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "agent_logic.hpp"
#include "app/json.hpp"
#include "core/enum_names.hpp"
#include "core/params.hpp"
#include "core/safety.hpp"
#include "dds/convert.hpp"
#include "dds/node.hpp"
#include "dds/state_input.hpp"
#include "dds/vehicle_io.hpp"
#include "dds/participant.hpp"
#include "util/log.hpp"
#include "util/phase_clock.hpp"
#include "util/proc_stats.hpp"
#include "util/rate_loop.hpp"
#include "util/signals.hpp"
#include "util/stats.hpp"

namespace shapeform::agent {

namespace {

/// Data ages kept per status period (the rest of a period's samples are not booked).
constexpr std::size_t kAgeCapacity = 4096;

std::uint64_t ticks_per(double rate_hz, double every_hz) {
  return std::max<std::uint64_t>(1, static_cast<std::uint64_t>(std::llround(rate_hz / every_hz)));
}

/// One JSON object per line on stdout (--json), flushed so a reader sees it at once.
void emit(const nlohmann::json& j) { std::cout << j.dump() << std::endl; }

/// Checks and compiles received commands (dds::from_msg: validation, envelope, shapes::compile) on
/// a thread of its own, so that no command, however costly its curve, stalls the control loop: the
/// loop submits what it drained and takes what is ready, in the order submitted.
class CommandCompiler {
 public:
  struct Result {
    std::uint64_t epoch = 0;
    bool ok = false;
    dds::CommandSample sample;  ///< when ok
    std::string error;          ///< when not ok
  };
  CommandCompiler() : worker_([this] { work(); }) {}
  ~CommandCompiler() {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    wake_.notify_one();
    worker_.join();
  }
  CommandCompiler(const CommandCompiler&) = delete;
  CommandCompiler& operator=(const CommandCompiler&) = delete;

  /// m as received from the participant `source` (its issuer when the command names none).
  void submit(const msg::ShapeCommand& m, const dds::SourceId& source) {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      todo_.emplace_back(m, source);
    }
    wake_.notify_one();
  }
  /// Moves the results ready so far into `out` (cleared first). Never waits for a compilation.
  void take(std::vector<Result>& out) {
    out.clear();
    const std::lock_guard<std::mutex> lock(mutex_);
    out.swap(done_);
  }

 private:
  void work() {
    std::unique_lock<std::mutex> lock(mutex_);
    while (true) {
      wake_.wait(lock, [this] { return stop_ || !todo_.empty(); });
      if (stop_) return;
      const auto [m, source] = std::move(todo_.front());
      todo_.pop_front();
      lock.unlock();
      Result r;
      r.epoch = m.epoch();
      r.ok = dds::from_msg(m, source, r.sample, r.error);
      lock.lock();
      done_.push_back(std::move(r));
    }
  }

  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::pair<msg::ShapeCommand, dds::SourceId>> todo_;
  std::vector<Result> done_;
  bool stop_ = false;
  std::thread worker_;  ///< last: starts once the rest is built
};

/// The agents of one process around their pure AgentLogic: each tick drains the inputs, steps,
/// publishes and reports. One thread of control; Fast DDS threads only fill reader mailboxes.
class AgentNode {
 public:
  AgentNode(const std::vector<std::int32_t>& ids, const std::vector<core::Vec2>& starts, const config::Config& cfg,
            const AgentOptions& opt);
  /// Runs until SIGINT/SIGTERM, then disposes the hosted instances; returns the exit status (0, or
  /// 2 when another participant holds one of the ids). Throws on a DDS set-up failure.
  int run();

 private:
  void tick() {
    recover_participant();
    const std::int64_t now = util::steady_ns();
    phases_.start_at(util::thread_cpu_ns());
    drain_commands();
    drain_targets();
    phases_.lap_at(kCommands, util::thread_cpu_ns());
    drain_states();
    phases_.lap_at(kStates, util::thread_cpu_ns());
    if (identity_.yielding()) return farewell(now);
    if (!identity_.may_publish(now)) return;  // the grace period: listening whether an id is in use
    drain_poses();
    step(now);
    command_robots();
    phases_.lap_at(kLaw, util::thread_cpu_ns());
    // Slow until commanded (agent.idle_rate_hz): a large swarm's discovery runs on a nearly idle host.
    if (logics_.front()->has_command() || ticks_ % idle_every_ == 0) publish();
    phases_.lap_at(kPublish, util::thread_cpu_ns());
    report();
    phases_.lap_at(kReport, util::thread_cpu_ns());
  }
  /// The loop's phases, in this thread's CPU time per tick (a few clock reads per tick, none per
  /// sample; CPU, not wall time, so that a busy host's preemptions are not booked to a phase), logged
  /// at exit with the process's CPU split between this thread and the others (Fast DDS's receive and
  /// event threads): scripts/profile_group.py reads that line.
  enum Phase : std::size_t { kCommands, kStates, kLaw, kPublish, kReport, kPhases };
  util::PhaseClock<kPhases> phases_{{"commands", "states", "law", "publish", "report"}};
  /// The loop thread's and the process's CPU time when the loop began, ns.
  std::int64_t loop_cpu0_ns_ = 0, process_cpu0_ns_ = 0, wall0_ns_ = 0;
  /// Logs the phases (tick times) and the CPU split since run() began.
  void log_profile();
  /// After a stall longer than the peers' lease, or a split from a peer, the participant is recreated
  /// (dds::Node::recover); participants DDS Security refused are reported ("refused" events).
  void recover_participant();
  void drain_commands();
  /// Re-offers the command followed on command_relay_, if there is one.
  void relay_command();
  void drain_targets();
  void drain_states();
  void step(std::int64_t now);
  /// vehicle.interface ros2: the robots' poses into their agents (refused ones counted and said).
  void drain_poses();
  /// vehicle.interface ros2: each robot's command of this tick (zero without a fresh pose), and the
  /// control latency of the commands that used a new pose.
  void command_robots();
  /// A hosted agent's robot changed health (pose lost, back, first pose): say so.
  void vehicle_health(std::size_t k, dds::VehicleHealth health, const std::string& why);
  void publish();
  void report();
  /// The process-wide figures of the status period ending now (loop timing, data ages, CPU, memory).
  void take_period_figures();
  /// Statuses of the hosted agents k with k % every == phase, with the period's figures (with batch_,
  /// in AgentStatusBatch samples); with --json also their "status" events.
  void publish_status(bool json, std::uint64_t phase = 0, std::uint64_t every = 1);
  /// Says that agent l went `out` beyond the fence, and what it does (safety.breach_action).
  void report_breach(const AgentLogic& l, double out);
  /// Another participant publishes hosted agent `id`: report it; yield (stop, exit 2) if we must.
  void on_duplicate(std::int32_t id, const dds::SourceId& other, std::int64_t now);
  /// While yielding: our statuses (so a supervisor sees the duplicate too) once a reader matches,
  /// then stop. No state is published and nothing is disposed: the id stays the incumbent's.
  void farewell(std::int64_t now);
  /// A refused sample: counted by every hosted agent, logged (throttled per first refused field, e.g.
  /// "state.id" or "state_batch.states[3].x", unless `always`).
  void reject(const char* what, const std::string& log_line, const std::string& why, bool always = false);
  /// Asked once per received sample: the table's index, not a search.
  bool hosted(std::int32_t id) const { return table_->hosted_index(id) >= 0; }

  const std::vector<std::int32_t> ids_;
  const config::Config& cfg_;
  const AgentOptions opt_;
  const bool group_;
  /// One AgentStateBatch per tick and one AgentStatusBatch per status period for all hosted agents (a
  /// group with agent.batch_state), else one AgentState and one AgentStatus per hosted agent.
  const bool batch_;
  /// The states heard, shared by the hosted agents (each sample taken in once).
  std::shared_ptr<NeighbourTable> table_;
  std::vector<std::unique_ptr<AgentLogic>> logics_;
  std::vector<AgentLogic*> sharing_;  ///< reused by step(): the agents stepped together
  /// vehicle.interface ros2: each hosted agent's robot (same order as logics_), else empty.
  struct Robot {
    dds::VehicleController io;
    dds::VehicleHealth health = dds::VehicleHealth::NoPose;
    std::int64_t pose_used_ns = -1;   ///< the pose the last command was computed from
    std::vector<double> latency_us;   ///< control latencies of this status period
    std::uint64_t saturated_reported = 0;
  };
  std::vector<Robot> robots_;
  std::vector<dds::PoseItem> poses_;  ///< reused by drain_poses()

  dds::Node node_;
  dds::Writer<msg::AgentState> state_writer_;         ///< unless batch_
  dds::Writer<msg::AgentStateBatch> batch_writer_;    ///< when batch_
  std::vector<dds::StateSample> batch_states_;        ///< reused by publish()
  msg::AgentStateBatch batch_msg_;                     ///< reused by publish()
  dds::Writer<msg::AgentStatus> status_writer_;            ///< unless batch_
  dds::Writer<msg::AgentStatusBatch> status_batch_writer_;  ///< when batch_
  std::vector<dds::StatusSample> batch_statuses_;           ///< reused by publish_status()
  msg::AgentStatusBatch status_batch_msg_;                  ///< reused by publish_status()
  dds::StateInput state_input_;
  dds::Reader<msg::ShapeCommand> command_reader_;
  /// Re-offers the command this process follows (transient-local, KEEP_LAST 1): it outlives its
  /// publisher, for a supervisor started later and for agents that join while nobody commands. None
  /// with DDS Security: only the supervisor may publish commands there (docs/SECURITY.md).
  dds::Writer<msg::ShapeCommand> command_relay_;
  dds::CommandId relayed_;  ///< what command_relay_ offers now
  std::uint64_t last_refused_epoch_ = 0;  ///< the last epoch refused as an absurd jump
  dds::Reader<msg::TrackingTarget> target_reader_;
  std::vector<dds::Received<msg::ShapeCommand>> commands_;
  CommandCompiler compiler_;
  std::vector<CommandCompiler::Result> compiled_;
  std::vector<dds::Received<msg::TrackingTarget>> targets_;

  util::RateLoop loop_;
  util::ThrottledLog throttled_{5.0};
  util::CpuMeter cpu_;
  std::vector<double> ages_us_;  ///< data ages of this status period
  dds::StatusSample period_;     ///< the last status period's process-wide figures
  bool period_taken_ = false;    ///< period_ holds a whole period's
  std::vector<std::uint64_t> clamped_before_;  ///< reused by step()
  const std::uint64_t log_every_;     ///< ticks between "hearing" lines (~1 s)
  const std::uint64_t status_every_;  ///< ticks per status period
  const std::uint64_t idle_every_;    ///< ticks per state publication before the first command
  std::uint64_t seq_ = 0, ticks_ = 0;
  std::uint64_t overruns_seen_ = 0;  ///< the loop's skipped periods already given to the agents (step())
  int heard_logged_ = -1;
  IdentityGuard identity_;
  std::int64_t farewell_end_ns_ = 0;  ///< yielding: stop at the latest then
  int farewell_sent_ = 0;             ///< yielding: status rounds written to a matched reader
  bool done_ = false;                 ///< yielding: the loop ends
};

std::string node_name(const std::vector<std::int32_t>& ids) {
  return (ids.size() > 1 ? "shapeform_agent_group_" : "shapeform_agent_") + std::to_string(ids.front());
}

/// The participant's profile: the config's, with the identity agent_K (K the first hosted id) when the
/// config names none.
dds::TransportConfig agent_transport(const config::Config& cfg, const std::vector<std::int32_t>& ids) {
  return dds::with_identity(cfg.transport, "agent_" + std::to_string(ids.front()));
}

AgentNode::AgentNode(const std::vector<std::int32_t>& ids, const std::vector<core::Vec2>& starts,
                     const config::Config& cfg, const AgentOptions& opt)
    : ids_(ids),
      cfg_(cfg),
      opt_(opt),
      group_(ids.size() > 1),
      batch_(group_ && cfg.agent.batch_state),
      table_(std::make_shared<NeighbourTable>(
          ids, cfg.agent.neighbour_timeout_ns(), cfg.agent.idle_neighbour_timeout_ns())),
      node_(agent_transport(cfg, ids), node_name(ids)),
      state_writer_(batch_ ? dds::Writer<msg::AgentState>() : node_.writer<msg::AgentState>(dds::TopicId::State)),
      batch_writer_(batch_ ? node_.writer<msg::AgentStateBatch>(dds::TopicId::StateBatch)
                           : dds::Writer<msg::AgentStateBatch>()),
      status_writer_(batch_ ? dds::Writer<msg::AgentStatus>() : node_.writer<msg::AgentStatus>(dds::TopicId::Status)),
      status_batch_writer_(batch_ ? node_.writer<msg::AgentStatusBatch>(dds::TopicId::StatusBatch)
                                  : dds::Writer<msg::AgentStatusBatch>()),
      state_input_(node_),
      command_reader_(node_.reader<msg::ShapeCommand>(dds::TopicId::Command)),
      command_relay_(cfg.transport.security.enabled ? dds::Writer<msg::ShapeCommand>()
                                                    : node_.writer<msg::ShapeCommand>(dds::TopicId::Command)),
      target_reader_(node_.reader<msg::TrackingTarget>(dds::TopicId::Target)),
      loop_(cfg.agent.rate_hz),
      log_every_(ticks_per(cfg.agent.rate_hz, 1.0)),
      status_every_(ticks_per(cfg.agent.rate_hz, cfg.agent.status_rate_hz)),
      idle_every_(ticks_per(cfg.agent.rate_hz, cfg.agent.idle_state_rate_hz())),
      identity_(node_.source(), util::steady_ns() + static_cast<std::int64_t>(cfg.agent.identity_grace_s * 1e9)) {
  const int max_wait_ticks = static_cast<int>(std::lround(5.0 * cfg.agent.rate_hz));
  const config::VehicleLink& link = cfg.vehicle_link;
  for (std::size_t k = 0; k < ids.size(); ++k) {
    logics_.push_back(std::make_unique<AgentLogic>(ids[k], starts[k], table_, cfg.agent.lockstep, max_wait_ticks));
    AgentLogic& l = *logics_.back();
    l.set_period(1.0 / cfg.agent.rate_hz);
    if (!link.ros2()) {
      l.set_vehicle(cfg.vehicle, core::start_heading(cfg.vehicle, ids[k], cfg.swarm.seed));
      continue;
    }
    l.set_external_vehicle(cfg.vehicle, {link.frame, static_cast<std::int64_t>(link.pose_timeout_s * 1e9),
                                         link.pose_jump_m, 1.0 / cfg.agent.rate_hz});
    dds::VehicleTopics t;
    t.ns = link.namespace_of(ids[k]);
    t.cmd_topic = config::VehicleLink::with_id(link.cmd_topic, ids[k]);
    t.cmd_stamped = link.cmd_type == config::VehicleLink::CmdType::TwistStamped;
    t.pose_topic = config::VehicleLink::with_id(link.pose_topic, ids[k]);
    t.pose_stamped = link.pose_type == config::VehicleLink::PoseType::PoseStamped;
    robots_.emplace_back();
    robots_.back().io = dds::VehicleController(node_, t);
    robots_.back().latency_us.reserve(kAgeCapacity);
    util::log_info("agent " + std::to_string(ids[k]) + " drives the robot " + t.ns + ": pose from " + t.pose_name() +
                   ", commands on " + t.cmd_name());
  }
  if (link.ros2()) {
    // One law step should last one tick: the robot then covers each step before the next one.
    const double step_s = cfg.command.dt * cfg.vehicle.seconds_per_model_time, period_s = 1.0 / cfg.agent.rate_hz;
    if (std::abs(step_s - period_s) > 0.01 * period_s)
      util::log_warn("a law step lasts " + core::params::format_number(step_s) +
                     " s (integration.dt x vehicle.seconds_per_model_time) but a tick " +
                     core::params::format_number(period_s) + " s (1 / agent.rate_hz): the robot covers " +
                     core::params::format_number(period_s / step_s) +
                     " of each step per tick; set vehicle.seconds_per_model_time = " +
                     core::params::format_number(period_s / cfg.command.dt));
  }
  ages_us_.reserve(kAgeCapacity);
}

int AgentNode::run() {
  // As its peers' logs name it, and where it listens (the port: the participant slot it holds).
  util::log_info("participant " + dds::to_string(node_.source()) + " on " + node_.listening());
  loop_cpu0_ns_ = util::thread_cpu_ns();
  process_cpu0_ns_ = util::process_cpu_ns();
  wall0_ns_ = util::steady_ns();
  while (!done_ && loop_.wait_next(util::stop_flag())) tick();
  log_profile();
  if (identity_.yielding()) {
    if (opt_.json) emit({{"event", "stop"}, {"ticks", ticks_}, {"signal", util::stop_signal()}, {"refused", true}});
    return 2;  // a bad command line: the id is in use
  }
  // Leave cleanly: robots are told to stop (a real one would otherwise drive on until its driver's own
  // timeout), and our instances disposed so the others drop us at once (the entities go with node_).
  for (const auto& l : logics_)
    if (l->external()) l->stop_vehicle();
  command_robots();
  // The stop is the command that must arrive: a lost datagram is resent only while its writer lives,
  // and the writers go with node_ below. Each robot's driver gets the rest of 0.5 s in all to ack it.
  const std::int64_t ack_deadline = util::steady_ns() + 500'000'000;
  for (auto& r : robots_)
    r.io.wait_acknowledged(std::max<double>(0.0, static_cast<double>(ack_deadline - util::steady_ns()) * 1e-9));
  if (batch_) {
    // Its instances, one per part of agent.batch_max_states (each disposes every id it carried).
    for (const auto& [begin, end] : dds::batch_ranges(ids_.size(), static_cast<std::size_t>(cfg_.agent.batch_max_states))) {
      (void)end;
      msg::AgentStateBatch gone;
      gone.first_id(ids_[begin]);
      batch_writer_.dispose(gone);
    }
  } else {
    for (const auto id : ids_) {
      msg::AgentState gone;
      gone.id(id);
      state_writer_.dispose(gone);
    }
  }
  util::log_info("stopping after " + std::to_string(ticks_) + " ticks (signal " + std::to_string(util::stop_signal()) + ")");
  if (opt_.json) emit({{"event", "stop"}, {"ticks", ticks_}, {"signal", util::stop_signal()}});
  if (cfg_.agent.leave_by_lease) node_.exit_without_goodbye(0);
  return 0;
}

void AgentNode::log_profile() {
  const double wall_s = static_cast<double>(util::steady_ns() - wall0_ns_) * 1e-9;
  if (wall_s <= 0.0 || phases_.ticks() == 0) return;
  const double loop_pct = 1e-7 * static_cast<double>(util::thread_cpu_ns() - loop_cpu0_ns_) / wall_s;
  const double all_pct = 1e-7 * static_cast<double>(util::process_cpu_ns() - process_cpu0_ns_) / wall_s;
  char cpu[160];
  std::snprintf(cpu, sizeof cpu, "; cpu %.2f %% of a core: loop thread %.2f %%, other threads %.2f %%", all_pct,
                loop_pct, all_pct - loop_pct);
  util::log_info("profile: " + phases_.line() + cpu);
}

void AgentNode::on_duplicate(std::int32_t id, const dds::SourceId& other, std::int64_t now) {
  const IdentityGuard::Action action = identity_.on_sample(id, other);
  if (action == IdentityGuard::Action::None) return;
  const bool yield = action == IdentityGuard::Action::Yield;
  const std::string own = dds::to_string(identity_.own()), theirs = dds::to_string(other);
  if (yield) {
    util::log_error("id " + std::to_string(id) + " is already in use by participant " + theirs + " (this one is " +
                    own + "): refusing to run; give every agent its own id");
    farewell_end_ns_ = now + 1'000'000'000;
  } else {
    util::log_warn("id " + std::to_string(id) + " is also published by participant " + theirs + " (this one is " +
                   own + ", the lower GUID prefix, keeps it): that process must exit");
  }
  if (opt_.json)
    emit({{"event", "duplicate"}, {"id", id}, {"source", own}, {"other", theirs}, {"action", yield ? "exit" : "keep"}});
}

void AgentNode::farewell(std::int64_t now) {
  if ((batch_ ? status_batch_writer_.matched() : status_writer_.matched()) > 0) {
    take_period_figures();
    publish_status(false);
    ++farewell_sent_;
  }
  // A few rounds (a reliable topic: the first may race the reader's matching of this writer).
  done_ = farewell_sent_ >= 3 || now >= farewell_end_ns_;
}

void AgentNode::reject(const char* what, const std::string& log_line, const std::string& why, bool always) {
  for (auto& l : logics_) l->count_rejected();
  bool shown = true;
  if (always) util::log_warn(log_line);
  else shown = throttled_.warn(why.substr(0, why.find(':')), log_line);  // throttled per refused field
  if (opt_.json && shown) emit({{"event", "rejected"}, {"what", what}, {"why", why}});
}

void AgentNode::recover_participant() {
  for (const dds::SourceId& refused : node_.take_refused()) {
    if (opt_.json)
      emit({{"event", "refused"}, {"participant", dds::to_string(refused)}, {"by", dds::to_string(node_.source())}});
  }
  const auto recovered = node_.recover(1.0 / cfg_.agent.rate_hz);
  if (!recovered) return;
  // The new re-offer writer starts empty: offer the command followed again.
  if (!relayed_.none()) relay_command();
  if (opt_.json) {
    nlohmann::json e = app::recovered_json(recovered->cause == dds::Node::Recovery::Cause::Split, recovered->seconds,
                                           dds::to_string(recovered->peer));
    e["event"] = "recovered";
    emit(e);
  }
}

void AgentNode::drain_commands() {
  using Verdict = dds::CommandArbiter::Verdict;
  // New commands go to the compiler; those it has finished are judged (compilation never runs here).
  command_reader_.drain(commands_);
  for (const auto& c : commands_)
    if (c.valid_data && c.source != node_.source()) compiler_.submit(c.msg, c.source);  // not our own re-offer
  compiler_.take(compiled_);
  for (const auto& c : compiled_) {
    if (!c.ok) {
      reject("command", "command epoch " + std::to_string(c.epoch) + " rejected: " + c.error, c.error, true);
      continue;
    }
    const dds::CommandSample& cmd = c.sample;
    bool refused = false;
    for (auto& l : logics_) refused = l->on_command(cmd) == Verdict::Refused || refused;  // each counts it
    if (refused) {
      const std::string why = dds::CommandArbiter::refusal(cmd, logics_.front()->command_id().epoch);
      // Each new epoch refused is reported; a publisher repeating one is throttled.
      const bool fresh = cmd.id.epoch != last_refused_epoch_;
      last_refused_epoch_ = cmd.id.epoch;
      if (fresh) util::log_warn("command " + why);
      if ((fresh || throttled_.warn("command jump", "command " + why)) && opt_.json)
        emit({{"event", "rejected"}, {"what", "command"}, {"why", why}, {"epoch", cmd.id.epoch}});
    }
  }
  for (auto& l : logics_) l->recheck_commands();
  const AgentLogic& first = *logics_.front();
  if (first.command_id() == relayed_) return;
  // A new command is followed: say so, and re-offer it as received (epoch, issuer and name kept).
  const dds::CommandSample& s = first.command_sample();
  relayed_ = s.id;
  const std::string shape(core::to_string(s.command.shape.kind));
  const std::string issuer = dds::describe_issuer(s.issuer_name, s.id.issuer);
  util::log_info("following command epoch " + std::to_string(s.id.epoch) + " of " + issuer + ": " + shape +
                 (s.command.tracking.enabled ? " (tracking)" : ""));
  // The filter's margins against stale neighbours are their speed bound times the states' ages.
  if (core::filters(s.command)) {
    const core::SafetyParams sp = core::safety_params(s.command, cfg_.vehicle);
    if (sp.max_step <= 0.0)
      util::log_warn("command epoch " + std::to_string(s.id.epoch) +
                     " filters steps with no speed bound (dynamics.max_speed = 0 and vehicle.max_speed = 0): the "
                     "safety filter cannot allow for the neighbours' motion since their states were sent; set "
                     "dynamics.max_speed (docs/SAFETY.md)");
    else if (s.command.min_separation > 0.0 && 4.0 * sp.max_step > s.command.min_separation)
      util::log_warn("command epoch " + std::to_string(s.id.epoch) + ": a step may be " +
                     core::params::format_number(sp.max_step) + " long (dynamics.max_speed x integration.dt) against "
                     "safety.min_separation = " + core::params::format_number(s.command.min_separation) +
                     ": agents keep about d + 4 steps from one another and may stand still near each other; "
                     "lower dynamics.max_speed to at most " +
                     core::params::format_number(s.command.min_separation / (4.0 * s.command.dt)) +
                     " (docs/SAFETY.md)");
  }
  if (opt_.json)
    emit({{"event", "command"}, {"epoch", s.id.epoch}, {"issuer", dds::to_string(s.id.issuer)},
          {"publisher", issuer}, {"shape", shape}, {"tracking", s.command.tracking.enabled}});
  relay_command();
}

void AgentNode::relay_command() {
  if (!command_relay_.valid()) return;  // secured: no relay writer
  const dds::CommandSample& s = logics_.front()->command_sample();
  if (!command_relay_.write(dds::to_msg(s.command, s.id, s.issuer_name))) util::log_warn("command re-offer failed");
}

void AgentNode::drain_targets() {
  target_reader_.drain(targets_);
  for (const auto& t : targets_) {
    if (!t.valid_data) continue;
    dds::TargetSample target;
    std::string why;
    if (!dds::from_msg(t.msg, target, why)) {
      reject("target", "tracking target rejected: " + why, why);
      continue;
    }
    for (auto& l : logics_) l->on_target(target, t.receive_stamp_ns);
  }
}

void AgentNode::drain_states() {
  const double dt = logics_.front()->command().dt;  // the hosted agents follow one command
  // Each state from the message into the table: no list of the swarm's states in between.
  state_input_.drain([this, dt](const dds::StateItem& r) {
    if (r.kind == dds::StateItem::Kind::Gone) return table_->on_gone(r.id);
    if (r.kind == dds::StateItem::Kind::Rejected) return reject("state", "state sample rejected: " + r.why, r.why);
    const dds::StateSample& s = r.state;
    const bool ours = hosted(s.id);
    if (ours && !identity_.ours(r.source)) return on_duplicate(s.id, r.source, r.receive_stamp_ns);  // from another participant
    // Once into the shared table; each hosted agent leaves its own entry out.
    table_->on_state(s.id, s.x, s.seq, r.receive_stamp_ns, s.command, s.arc, s.model_time, s.prev_x, s.prev_arc, dt);
    // Data age of samples from agents hosted elsewhere (a process's own samples are not a delivery).
    if (!ours && ages_us_.size() < ages_us_.capacity())
      ages_us_.push_back(static_cast<double>(r.receive_stamp_ns - s.stamp_ns) * 1e-3);
  });
}

void AgentNode::step(std::int64_t now) {
  // Periods the loop skipped since the last tick pass on the agents' clocks too (AgentLogic::skip).
  const std::uint64_t overruns = loop_.overruns();
  for (auto& l : logics_) l->skip(overruns - overruns_seen_);
  overruns_seen_ = overruns;
  sharing_.clear();
  for (std::size_t k = 0; k < logics_.size(); ++k) {
    AgentLogic& l = *logics_[k];
    const bool had_target = l.following_target();
    l.drop_stale(now);  // the shared table drops once per tick
    if (k == 0 && had_target && !l.following_target())
      util::log_warn("tracking target unheard for 1 s: the centre follows the command's path on this agent's clock");
    if (group_ && robots_.empty() && l.shares_step_with(*logics_.front())) sharing_.push_back(&l);
  }
  std::vector<std::uint64_t>& clamped = clamped_before_;
  clamped.clear();
  for (const auto& l : logics_) clamped.push_back(l->steps_clamped());
  // The arc law: one sorted list and offset for all hosted agents when they can share them (same
  // command, model time and target), else (and always for one agent, and for robots) each on its own.
  if (sharing_.size() == logics_.size()) {
    AgentLogic::step_shared(sharing_);
  } else {
    for (std::size_t k = 0; k < logics_.size(); ++k) {
      AgentLogic& l = *logics_[k];
      if (robots_.empty()) {
        l.step();
        continue;
      }
      // A robot is driven only from a fresh pose: without one it is told to stop, at once.
      if (l.pose_fresh(now)) {
        if (robots_[k].health != dds::VehicleHealth::Driving) vehicle_health(k, dds::VehicleHealth::Driving, "");
        l.step();
      } else {
        l.stop_vehicle();
        l.skip(1);  // no step this period: the clock moves on all the same
        if (l.has_pose() && robots_[k].health == dds::VehicleHealth::Driving)
          vehicle_health(k, dds::VehicleHealth::PoseLost,
                         "no pose from " + robots_[k].io.topics().pose_name() + " for " +
                             core::params::format_number(cfg_.vehicle_link.pose_timeout_s) +
                             " s (vehicle.pose_timeout_s): commanding zero velocity until poses return");
      }
    }
  }
  for (std::size_t k = 0; k < logics_.size(); ++k) {
    AgentLogic& l = *logics_[k];
    if (const double out = l.take_breach(); out > 0.0) report_breach(l, out);
    if (l.steps_clamped() != clamped[k])
      throttled_.warn("clamp", "agent " + std::to_string(l.id()) +
                                   ": the command's step would leave the workspace; kept at its edge (safety.workspace = " +
                                   core::params::format_number(l.command().workspace) + ")");
  }
}

void AgentNode::report_breach(const AgentLogic& l, double out) {
  const core::BreachAction action = l.command().breach_action;
  const char* what = action == core::BreachAction::Return ? "returning inside"
                     : action == core::BreachAction::Stop ? "stopped until the next command"
                                                          : "stopped; the supervisor holds the swarm (resume to go on)";
  util::log_warn("agent " + std::to_string(l.id()) + " is " + core::params::format_number(out) +
                 " beyond the fence at (" + core::params::format_number(l.position().x()) + ", " +
                 core::params::format_number(l.position().y()) + "): safety.breach_action " +
                 std::string(core::params::name_of(core::params::kBreachActionNames, action)) + ", " + what);
  if (opt_.json)
    emit({{"event", "fence_breach"}, {"id", l.id()}, {"beyond", out}, {"x", l.position().x()},
          {"y", l.position().y()}, {"action", core::params::name_of(core::params::kBreachActionNames, action)}});
}

void AgentNode::publish() {
  identity_.published();
  ++seq_;
  batch_states_.clear();
  // The samples' stamp, taken as they are written (as DDS's source timestamp is): their data age is the
  // time from the write to the reading, the transport's and the reader's share, as the baseline's is.
  const std::int64_t stamp_ns = util::steady_ns();
  for (const auto& l : logics_) {
    // A robot whose pose is not known (none yet, or lost) is not in the swarm: the others space without it.
    if (l->external() && !l->pose_fresh(stamp_ns)) continue;
    dds::StateSample s;
    s.id = l->id();
    s.seq = seq_;
    s.stamp_ns = stamp_ns;
    s.command = l->command_id();
    s.model_time = l->model_time();
    s.x = l->position();
    s.v = l->velocity();
    // The arc law's agents share their arc lengths so that nobody projects everyone else.
    if (l->command().law == core::Law::Arc) s.arc = l->arc();
    s.prev_x = l->previous_position();
    s.prev_arc = l->previous_arc();
    if (batch_) batch_states_.push_back(s);
    else state_writer_.write(dds::to_msg(s));
  }
  // One sample per part of at most agent.batch_max_states states (one datagram each by default), each
  // through the one message reused from tick to tick.
  if (batch_)
    for (const auto& [begin, end] :
         dds::batch_ranges(batch_states_.size(), static_cast<std::size_t>(cfg_.agent.batch_max_states))) {
      dds::to_msg(batch_states_, begin, end, batch_msg_);
      batch_writer_.write(batch_msg_);
    }
}

void AgentNode::drain_poses() {
  for (std::size_t k = 0; k < robots_.size(); ++k) {
    AgentLogic& l = *logics_[k];
    robots_[k].io.drain(poses_);
    for (const dds::PoseItem& p : poses_) {
      std::string why = p.why;
      // Refusals are throttled per agent and per reason (the first bad field, another frame, a jump): one
      // kind does not hide another, nor one robot's another's.
      std::string reason;
      if (!p.valid) {
        l.count_refused_pose();
        reason = why.substr(0, why.find(':'));
      } else {
        const AgentLogic::PoseVerdict verdict =
            l.on_pose(p.sample.x, p.sample.yaw, p.sample.frame_id, p.receive_stamp_ns, why);
        if (verdict == AgentLogic::PoseVerdict::Accepted) continue;
        reason = verdict == AgentLogic::PoseVerdict::WrongFrame ? "frame" : "jump";
      }
      const std::string line = "agent " + std::to_string(l.id()) + ": pose of " + robots_[k].io.topics().ns +
                               " refused: " + why;
      if (throttled_.warn("pose " + std::to_string(l.id()) + " " + reason, line) && opt_.json)
        emit({{"event", "pose_refused"}, {"id", l.id()}, {"why", why}});
    }
  }
}

void AgentNode::command_robots() {
  for (std::size_t k = 0; k < robots_.size(); ++k) {
    AgentLogic& l = *logics_[k];
    Robot& r = robots_[k];
    const core::Twist& c = l.vehicle_command().twist;
    dds::VelocitySample v;
    v.vx = c.vx;
    v.vy = c.vy;
    v.wz = c.wz;
    v.stamp_ns = util::system_ns();
    v.frame_id = r.io.topics().ns + "/" + cfg_.vehicle_sim.child_frame;
    r.io.command(v);
    // Pose received -> command published, once per pose that a step used.
    if (r.health == dds::VehicleHealth::Driving && l.pose_received_ns() != r.pose_used_ns) {
      r.pose_used_ns = l.pose_received_ns();
      if (r.latency_us.size() < r.latency_us.capacity())
        r.latency_us.push_back(static_cast<double>(util::steady_ns() - r.pose_used_ns) * 1e-3);
    }
  }
}

void AgentNode::vehicle_health(std::size_t k, dds::VehicleHealth health, const std::string& why) {
  Robot& r = robots_[k];
  const AgentLogic& l = *logics_[k];
  const dds::VehicleHealth was = r.health;
  r.health = health;
  const std::string who = "agent " + std::to_string(l.id()) + " (robot " + r.io.topics().ns + ")";
  if (health == dds::VehicleHealth::PoseLost) {
    util::log_warn(who + ": " + why + "; it leaves the swarm until then");
    if (!batch_) {  // the others drop it at once (a batch's agents are dropped by the neighbour timeout)
      msg::AgentState gone;
      gone.id(l.id());
      state_writer_.dispose(gone);
    }
  }
  else if (was == dds::VehicleHealth::PoseLost) util::log_info(who + ": poses are back, driving again");
  else util::log_info(who + ": first pose received, driving");
  if (opt_.json)
    emit({{"event", "vehicle"}, {"id", l.id()}, {"state", dds::to_string(health)}, {"was", dds::to_string(was)},
          {"why", why}});
}

void AgentNode::report() {
  int heard = logics_.front()->neighbours();
  for (const auto& l : logics_) heard = std::min(heard, l->neighbours());
  if (heard != heard_logged_ && ticks_ % log_every_ == 0) {
    heard_logged_ = heard;
    util::log_info(std::string(group_ ? "every hosted agent hears at least " : "hearing ") + std::to_string(heard) +
                   " neighbours");
  }
  // Each hosted agent's status once per status period. With agent.batch_state, all of them in one
  // AgentStatusBatch (a sample per part of kBatchStatusesPerDatagram, one datagram each) on the period's
  // first tick; otherwise one AgentStatus each, a group's agents spread over the period's ticks (agent k
  // on the ticks where ticks % status_every == k % status_every), never in one burst that a reader's
  // socket buffer would have to hold at once.
  const std::uint64_t phase = ++ticks_ % status_every_;
  if (phase == 0) take_period_figures();
  if (!period_taken_) return;
  if (batch_) {
    if (phase == 0) publish_status(true);
  } else {
    publish_status(true, phase, status_every_);
  }
}

void AgentNode::take_period_figures() {
  const double share = 1.0 / static_cast<double>(logics_.size());  // of the process figures, per agent
  period_ = dds::process_status(util::steady_ns(), loop_.stats(), ages_us_, cpu_.percent() * share,
                                util::rss_mb() * share);
  ages_us_.clear();
  period_taken_ = true;
}

void AgentNode::publish_status(bool json, std::uint64_t phase, std::uint64_t every) {
  if (phase >= logics_.size()) return;  // no hosted agent on this tick of the period
  dds::StatusSample st = period_;
  st.stamp_ns = util::steady_ns();  // the counters' time
  batch_statuses_.clear();
  for (std::size_t i = phase; i < logics_.size(); i += every) {
    const auto& l = logics_[i];
    const AgentCounters& k = l->counters();
    st.id = l->id();
    if (!robots_.empty()) {
      Robot& r = robots_[i];
      st.vehicle = r.health;
      st.poses_refused = l->poses_refused();
      st.commands_saturated = l->commands_saturated();
      st.control_latency_p50_us = util::percentile(r.latency_us, 50).value_or(-1);
      st.control_latency_p99_us = util::percentile(r.latency_us, 99).value_or(-1);
      r.latency_us.clear();
      if (st.commands_saturated != r.saturated_reported) {
        // Not hidden: a robot whose commands the limits cut does not move as the law asks.
        throttled_.warn("saturated", "agent " + std::to_string(st.id) + ": " +
                                         std::to_string(st.commands_saturated - r.saturated_reported) +
                                         " commands cut by the vehicle's limits in the last status period "
                                         "(vehicle.max_speed, max_yaw_rate, max_accel): the robot cannot follow "
                                         "the law there");
        if (opt_.json && json)
          emit({{"event", "saturated"}, {"id", st.id}, {"commands", st.commands_saturated - r.saturated_reported},
                {"total", st.commands_saturated}});
        r.saturated_reported = st.commands_saturated;
      }
    }
    st.neighbours_heard = l->neighbours();
    st.stale_dropped = k.stale_dropped;
    st.samples_rejected = k.samples_rejected;
    st.samples_received = k.samples_received;
    st.samples_lost = k.samples_lost;
    st.epoch = l->command_id().epoch;
    const SafetyFigures& f = l->safety();
    st.min_gap = f.min_gap;
    st.min_gap_time = f.min_gap_time;
    st.filter_interventions = f.interventions;
    st.deadlock_sidesteps = f.sidesteps;
    st.promises_broken = f.broken;
    st.blocked = f.blocked;
    st.blocked_by = static_cast<std::int32_t>(f.blocked_by);
    st.beyond_fence = l->beyond_fence();
    st.fence_breaches = f.fence_breaches;
    if (batch_) batch_statuses_.push_back(st);
    else status_writer_.write(dds::to_msg(st));
    if (opt_.json && json)
      emit({{"event", "status"}, {"id", st.id}, {"neighbours_heard", st.neighbours_heard}, {"epoch", st.epoch},
            {"model_time", l->model_time()}, {"x", l->position().x()}, {"y", l->position().y()},
            {"ticks", st.ticks}, {"samples_rejected", st.samples_rejected}, {"steps_clamped", k.steps_clamped},
            {"vehicle", dds::to_string(st.vehicle)}, {"heading", l->vehicle().heading},
            {"poses_refused", st.poses_refused}, {"commands_saturated", st.commands_saturated},
            {"control_latency_p50_us", st.control_latency_p50_us},
            {"control_latency_p99_us", st.control_latency_p99_us}, {"age_p99_us", st.age_p99_us}, {"min_gap", st.min_gap},
            {"filter_interventions", st.filter_interventions}, {"deadlock_sidesteps", st.deadlock_sidesteps},
            {"promises_broken", st.promises_broken}, {"blocked", st.blocked}, {"blocked_by", st.blocked_by},
            {"beyond_fence", st.beyond_fence}, {"fence_breaches", st.fence_breaches}});
  }
  if (batch_)
    for (const auto& [begin, end] : dds::batch_ranges(batch_statuses_.size(), dds::kBatchStatusesPerDatagram)) {
      dds::to_msg(batch_statuses_, begin, end, status_batch_msg_);
      status_batch_writer_.write(status_batch_msg_);
    }
}

}  // namespace

int run_agents(const std::vector<std::int32_t>& ids, const std::vector<core::Vec2>& starts, const config::Config& cfg,
               const AgentOptions& opt) {
  if (ids.size() > 1) {
    util::log_init("agent-group " + std::to_string(ids.front()) + ".." + std::to_string(ids.back()));
  } else {
    util::log_init("agent", ids.front());
  }
  util::install_stop_signals();
  {
    std::ostringstream s;
    if (ids.size() > 1) {
      s << ids.size() << " agents in one process, ";
    } else {
      s << "start (" << starts.front().x() << ", " << starts.front().y() << "), ";
    }
    s << cfg.agent.rate_hz << " Hz, " << dds::describe(agent_transport(cfg, ids)) << ", neighbour timeout "
      << cfg.agent.neighbour_timeout_periods << " periods";
    util::log_info(s.str());
  }
  if (opt.json) {
    nlohmann::json at = nlohmann::json::array();
    for (const core::Vec2& x : starts) at.push_back({x.x(), x.y()});
    emit({{"event", "start"}, {"ids", ids}, {"starts", std::move(at)}, {"config", app::config_json(cfg)}});
  }
  try {
    AgentNode node(ids, starts, cfg, opt);
    return node.run();
  } catch (const dds::SecurityError& e) {
    util::log_error(e.what());
    return 2;  // a key file or keystore that cannot work: a bad configuration
  } catch (const std::exception& e) {
    util::log_error(e.what());
    return 1;
  }
}

}  // namespace shapeform::agent
