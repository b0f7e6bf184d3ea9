// DDS wiring of the supervisor: one fixed-rate loop that drains agent states and commands, publishes
// the tracking target, computes/publishes/records metrics, and runs console and script commands between
// ticks. The logic is in the parts it wires (authority, input driver, executor, monitor, output), each
// tested without DDS.
#include "supervisor_node.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <iostream>
#include <memory>
#include <optional>

#include "app/json.hpp"
#include "authority.hpp"
#include "console_input.hpp"
#include "console_parser.hpp"
#include "dds/convert.hpp"
#include "dds/node.hpp"
#include "dds/participant.hpp"
#include "dds/ros2_mirror.hpp"
#include "dds/state_input.hpp"
#include "dds/status_input.hpp"
#include "dds/wire.hpp"
#include "executor.hpp"
#include "input_driver.hpp"
#include "output.hpp"
#include "presentation.hpp"
#include "record/recorder.hpp"
#include "swarm_monitor.hpp"
#include "util/clock.hpp"
#include "util/log.hpp"
#include "util/rate_loop.hpp"
#include "util/signals.hpp"

namespace shapeform::supervisor {

namespace {

/// The running supervisor. One thread of control; Fast DDS threads only fill reader mailboxes.
class SupervisorNode {
 public:
  SupervisorNode(const config::Config& cfg, const SupervisorOptions& opt);
  int run();

 private:
  /// Script, DDS, recording and console; the exit status when one of them fails.
  std::optional<int> start();
  void open_dds();
  /// The summary of the run, printed when it ends.
  int finish();

  /// One period of the loop.
  void tick(std::int64_t now, bool metrics_due, bool mirror_due) {
    recover_participant();
    drain(now);
    membership_.update(monitor_, now, out_);
    publish_target(now);
    if (metrics_due) metrics_tick(now);
    if (mirror_due) mirror_tick(now);
    run_input(now);
  }
  /// After a stall longer than the peers' lease, or a split from a peer, the participant is recreated
  /// (dds::Node::recover); participants DDS Security refused are reported ("refused" events).
  void recover_participant();
  void drain(std::int64_t now) {
    drain_commands(now);
    drain_states(now);
    drain_statuses(now);
  }
  /// The command topic: another participant's command that wins the order is the one in force from now.
  void drain_commands(std::int64_t now);
  void drain_states(std::int64_t now);
  void drain_statuses(std::int64_t now);
  /// Agent s.id reports it is beyond the fence of the command in force: with breach_action hold, the
  /// swarm is held (as the console's hold), said and recorded as an event.
  void on_breach(const dds::StatusSample& s, std::int64_t now);
  /// Whether a sample of agent id from `source` is the agent's own (SwarmMonitor::claim); the first
  /// sample of another participant on an id in use is reported (log line, "duplicate" event).
  bool owned(std::int32_t id, const dds::SourceId& source, std::int64_t now);
  void publish_target(std::int64_t now);
  void metrics_tick(std::int64_t now);
  /// The ROS 2 mirror's publications (ros2.mirror).
  void mirror_tick(std::int64_t now);
  void record_metrics(const SwarmMonitor::Sample& s, std::int64_t now);
  /// Handles Ctrl-C, runs input lines, tells the console whether the loop is busy.
  void run_input(std::int64_t now);
  Summary summary(std::int64_t now) const;
  /// A channel of run.mcap for topic id: its name, its IDL as omgidl schema, CDR messages.
  std::uint16_t wire_channel(dds::TopicId id);
  /// msg as it travels, into run.mcap's channel (when recording).
  template <class Msg>
  void record_wire(std::uint16_t channel, std::int64_t now, const Msg& msg) {
    if (!recorder_.is_open()) return;
    dds::to_cdr(msg, wire_buffer_);
    recorder_.write_message(channel, wall_s(now), wire_buffer_);
  }
  /// Every sample of buf that carries data (valid or refused later), as it travelled.
  template <class Msg>
  void record_wire(std::uint16_t channel, std::int64_t now, const std::vector<dds::Received<Msg>>& buf) {
    if (!recorder_.is_open()) return;
    for (const auto& r : buf)
      if (r.valid_data) record_wire(channel, now, r.msg);
  }
  /// Seconds since the supervisor started: a recording's wall_s.
  double wall_s(std::int64_t now) const { return static_cast<double>(now - start_ns_) * 1e-9; }

  const config::Config& cfg_;
  SupervisorOptions opt_;
  std::int64_t start_ns_ = util::steady_ns();
  Output out_;
  SwarmMonitor monitor_;
  record::Recorder recorder_;
  std::vector<std::uint8_t> wire_buffer_;  ///< record_wire's, reused
  ProgressFilter progress_;
  CommandAuthority authority_;
  InputDriver input_;
  Executor executor_;
  MembershipReport membership_;
  std::uint64_t rejected_ = 0;

  std::unique_ptr<dds::Node> node_;
  dds::Writer<msg::ShapeCommand> command_writer_;
  dds::Writer<msg::TrackingTarget> target_writer_;
  dds::Writer<msg::SwarmMetrics> metrics_writer_;
  dds::StateInput state_input_;  ///< shapeform/state and shapeform/state_batch
  dds::StatusInput status_input_;  ///< shapeform/status and shapeform/status_batch
  dds::Reader<msg::ShapeCommand> command_reader_;
  std::vector<dds::Received<msg::ShapeCommand>> commands_;
  std::vector<dds::StatusItem> statuses_;
  std::vector<record::AgentRow> positions_;  ///< one recorded sample (reused)
  /// run.mcap's channel of each topic the supervisor reads or writes (every sample, as CDR).
  std::uint16_t state_ch_ = 0, batch_ch_ = 0, command_ch_ = 0, status_ch_ = 0, status_batch_ch_ = 0, metrics_ch_ = 0,
                target_ch_ = 0;
  std::unique_ptr<ConsoleInput> console_;
  // The ROS 2 mirror (ros2.mirror): writers created only when it is on.
  dds::Writer<dds::ros2::PoseArray> ros2_agents_writer_;
  dds::Writer<dds::ros2::MarkerArray> ros2_markers_writer_;
  dds::ros2::PoseArray ros2_agents_;                ///< reused between publications
  dds::ros2::MarkerArray ros2_markers_;
};

SupervisorNode::SupervisorNode(const config::Config& cfg, const SupervisorOptions& opt)
    : cfg_(cfg),
      opt_(opt),
      out_(opt.json),
      // Agents publish once per period: never call one dead before it missed 3 periods (of
      // agent.idle_rate_hz while it follows no command yet).
      monitor_(
          static_cast<std::int64_t>(std::max(cfg.supervisor.agent_timeout_s, 3.0 / cfg.agent.rate_hz) * 1e9),
          cfg.supervisor.converge, cfg.agent.lockstep,
          static_cast<std::int64_t>(3.0 / cfg.agent.idle_state_rate_hz() * 1e9)),
      recorder_(cfg.supervisor.flush_s),
      authority_(cfg.command, cfg.agent.rate_hz, cfg.agent.lockstep, start_ns_, monitor_, recorder_, out_),
      input_(out_, monitor_, authority_),
      executor_(cfg.command, opt.replace_on_start,
                ExecutorParts{authority_, monitor_, recorder_, input_, progress_, out_}) {
  input_.set_dispatch([this](const Action& a, std::int64_t now) { executor_(a, now); });
  state_ch_ = wire_channel(dds::TopicId::State);
  batch_ch_ = wire_channel(dds::TopicId::StateBatch);
  command_ch_ = wire_channel(dds::TopicId::Command);
  status_ch_ = wire_channel(dds::TopicId::Status);
  status_batch_ch_ = wire_channel(dds::TopicId::StatusBatch);
  metrics_ch_ = wire_channel(dds::TopicId::Metrics);
  target_ch_ = wire_channel(dds::TopicId::Target);
  out_.set_event_sink([this](const nlohmann::json& e) {
    if (recorder_.is_open()) recorder_.write_event(wall_s(util::steady_ns()), e.dump());
  });
}

std::uint16_t SupervisorNode::wire_channel(dds::TopicId id) {
  const dds::TopicSchema& s = dds::topic_schema(id);
  return recorder_.add_channel({dds::topic_name(id), s.name, std::string(s.encoding), std::string(s.text),
                                std::string(s.message_encoding)});
}

// ---------------------------------------------------------------------------------------------
// Set-up, loop, end

int SupervisorNode::run() {
  util::log_init("supervisor");
  util::install_stop_signals();
  if (const auto failed = start()) return *failed;
  util::RateLoop loop(cfg_.supervisor.target_rate_hz);
  const auto metrics_every =
      std::max<std::uint64_t>(1, static_cast<std::uint64_t>(std::llround(cfg_.supervisor.target_rate_hz /
                                                                         cfg_.supervisor.metrics_rate_hz)));
  const auto mirror_every = std::max<std::uint64_t>(
      1, static_cast<std::uint64_t>(std::llround(cfg_.supervisor.target_rate_hz / cfg_.ros2.rate_hz)));
  for (std::uint64_t ticks = 0; !input_.quitting() && loop.wait_next(util::stop_flag()); ++ticks) {
    tick(util::steady_ns(), ticks % metrics_every == 0, cfg_.ros2.mirror && ticks % mirror_every == 0);
    if (input_.done() && !recorder_.is_open()) break;
  }
  return finish();
}

std::optional<int> SupervisorNode::start() {
  // Validate the whole script before touching the swarm: a bad line is exit status 2, nothing sent.
  if (!opt_.script.empty() && !input_.load_script(opt_.script, cfg_.command)) return kExitBadInput;
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
      executor_.start_recording(opt_.record_dir, util::steady_ns());
    } catch (const std::exception& e) {
      out_.errors() << "shapeform_supervisor: --record: " << e.what() << std::endl;
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
  input_.set_console(console_.get());
  return std::nullopt;
}

void SupervisorNode::open_dds() {
  node_ =
      std::make_unique<dds::Node>(dds::with_identity(cfg_.transport, "supervisor"), "shapeform_supervisor");
  command_writer_ = node_->writer<msg::ShapeCommand>(dds::TopicId::Command);
  target_writer_ = node_->writer<msg::TrackingTarget>(dds::TopicId::Target);
  metrics_writer_ = node_->writer<msg::SwarmMetrics>(dds::TopicId::Metrics);
  state_input_ = dds::StateInput(*node_);
  status_input_ = dds::StatusInput(*node_);
  command_reader_ = node_->reader<msg::ShapeCommand>(dds::TopicId::Command);
  if (cfg_.ros2.mirror) {
    ros2_agents_writer_ = node_->writer<dds::ros2::PoseArray>(dds::TopicId::Ros2Agents);
    ros2_markers_writer_ = node_->writer<dds::ros2::MarkerArray>(dds::TopicId::Ros2Markers);
    util::log_info("ros2.mirror: publishing rt/shapeform/agents and rt/shapeform/markers in frame '" +
                   cfg_.vehicle_link.frame + "'");
  }
  char host[256] = {};
  if (gethostname(host, sizeof host - 1) != 0) host[0] = '\0';
  authority_.set_identity(node_->name() + " on " + host + " pid " + std::to_string(getpid()), node_->source(),
                          [this](const dds::CommandSample& s) {
                            return command_writer_.write(dds::to_msg(s.command, s.id, s.issuer_name));
                          });
}

int SupervisorNode::finish() {
  console_.reset();  // the terminal back as it was: the summary is printed straight to it
  input_.set_console(nullptr);
  const std::int64_t now = util::steady_ns();
  drain(now);
  const Summary s = summary(now);
  if (opt_.json) {
    nlohmann::json j = summary_json(s);
    j.update(authority_.in_force_json());  // who published the command the summary measured against
    std::cout << j.dump() << std::endl;
  } else {
    std::cout << summary_text(s) << std::flush;
  }
  recorder_.close();
  return input_.exit_status();
}

Summary SupervisorNode::summary(std::int64_t now) const {
  Summary s;
  s.name = cfg_.name;
  s.command = authority_.current();
  s.epoch = authority_.epoch();
  s.commands_refused = authority_.commands_refused();
  s.sample = monitor_.measure(authority_.metrics_time(now), now);
  s.agents_seen = monitor_.agents().size();
  s.settle_time = monitor_.settle_time(cfg_.supervisor.converge);
  s.final_positions = monitor_.alive_positions(now);
  for (const auto& [id, x] : s.final_positions)
    s.final_model_times.push_back(monitor_.agents().at(id).model_time);
  s.samples_rejected = rejected_;
  if (recorder_.is_open()) s.recording = recorder_.dir().string();
  s.exit_status = input_.exit_status();
  return s;
}

// ---------------------------------------------------------------------------------------------
// Inputs: the participant, commands, states, statuses, the console

void SupervisorNode::recover_participant() {
  for (const dds::SourceId& refused : node_->take_refused())
    out_.event("refused",
               {{"participant", dds::to_string(refused)}, {"by", dds::to_string(node_->source())}});
  const auto recovered = node_->recover(1.0 / cfg_.supervisor.target_rate_hz);
  if (!recovered) return;
  // The new command writer starts empty: offer this supervisor's command in force (same id) to later
  // joiners again (the agents re-offer it too).
  authority_.republish();
  out_.event("recovered", app::recovered_json(recovered->cause == dds::Node::Recovery::Cause::Split,
                                              recovered->seconds, dds::to_string(recovered->peer)));
}

void SupervisorNode::drain_commands(std::int64_t now) {
  command_reader_.drain(commands_);
  record_wire(command_ch_, now, commands_);  // its own too: what every agent heard
  // Nothing heard and nothing to recheck (most ticks): no pass over the agents for the floor.
  if (commands_.empty() && !authority_.has_refused()) return;
  const std::uint64_t floor = monitor_.min_epoch_followed(now);
  for (const auto& r : commands_) {
    if (!r.valid_data || r.source == node_->source()) continue;  // our own publications are known
    dds::CommandSample c;
    std::string why;
    if (!dds::from_msg(r.msg, r.source, c, why))
      authority_.refuse_invalid(r.msg.epoch(), why);
    else if (authority_.hear(c, floor, now))
      input_.command_replaced(now);
  }
  if (authority_.recheck(floor, now)) input_.command_replaced(now);
}

void SupervisorNode::drain_states(std::int64_t now) {
  state_input_.drain([this, now](const dds::StateItem& r) {
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
      return;
    }
    if (r.kind == dds::StateItem::Kind::Rejected) {
      ++rejected_;
      out_.throttled().warn(r.why.substr(0, r.why.find(':')), "agent state rejected: " + r.why);  // per field
      return;
    }
    const dds::StateSample& s = r.state;
    if (!owned(s.id, r.source, now)) {
      ++rejected_;
      return;
    }
    monitor_.on_state(s.id, s.x, s.prev_x, s.command, s.model_time, now, r.source, s.v);
  });
  record_wire(state_ch_, now, state_input_.last_states());  // every sample as it came, before validation
  record_wire(batch_ch_, now, state_input_.last_batches());
}

void SupervisorNode::drain_statuses(std::int64_t now) {
  status_input_.drain(statuses_);
  record_wire(status_ch_, now, status_input_.last_statuses());  // every sample as it came, before validation
  record_wire(status_batch_ch_, now, status_input_.last_batches());
  for (const auto& r : statuses_) {
    if (!r.valid) {
      out_.throttled().warn(r.why.substr(0, r.why.find(':')), "agent status rejected: " + r.why);  // per field
      continue;
    }
    const dds::StatusSample& s = r.status;
    if (!owned(s.id, r.source, now)) continue;
    monitor_.on_status(s);
    // A breach of the command in force (an excursion that began under it: one going on since an
    // earlier command is the agent returning inside, not a new breach).
    if (s.beyond_fence && s.fence_breaches > 0 && s.epoch == authority_.epoch()) on_breach(s, now);
  }
}

void SupervisorNode::on_breach(const dds::StatusSample& s, std::int64_t now) {
  const core::CompiledCommand& cmd = authority_.current();
  // Only the commander holds the swarm, once: the hold is a new epoch, which the agents' next statuses
  // follow.
  if (!authority_.own() || cmd.hold || cmd.breach_action != core::BreachAction::Hold) return;
  const auto it = monitor_.agents().find(s.id);
  const core::Vec2 x = it != monitor_.agents().end() ? it->second.x : core::Vec2::Zero();
  util::log_warn("agent " + std::to_string(s.id) + " is beyond the fence at (" + core::params::format_number(x.x()) +
                 ", " + core::params::format_number(x.y()) +
                 "): holding the swarm (safety.breach_action hold); 'resume' releases it and the agent returns inside");
  out_.event("fence_breach", {{"id", s.id}, {"x", x.x()}, {"y", x.y()}, {"action", "hold"}, {"epoch", s.epoch}});
  executor_(Hold{false}, now);
}

bool SupervisorNode::owned(std::int32_t id, const dds::SourceId& source, std::int64_t now) {
  const SwarmMonitor::Claim c = monitor_.claim(id, source, now);
  if (c == SwarmMonitor::Claim::NewDuplicate) {
    const std::string owner = dds::to_string(monitor_.agents().at(id).source), other = dds::to_string(source);
    util::log_warn("agent id " + std::to_string(id) + " is published by two participants: " + owner +
                   " (in use) and " + other + " (a second process started with this id? it is ignored)");
    out_.event("duplicate", {{"id", id}, {"source", owner}, {"other", other}});
  }
  return c == SwarmMonitor::Claim::Owner;
}

void SupervisorNode::run_input(std::int64_t now) {
  if (console_) {
    for (int n = console_->take_interrupts(); n > 0 && !input_.quitting(); --n) input_.interrupt(now);
    // Ctrl-D at the terminal: the operator leaves (a recording in progress is closed).
    if (console_->interactive() && console_->eof()) input_.quit();
  }
  input_.run_lines(now);
  if (console_) {
    std::cout.flush();
    std::cerr.flush();
    console_->set_busy(input_.busy());
  }
}

// ---------------------------------------------------------------------------------------------
// Outputs: target, metrics

void SupervisorNode::publish_target(std::int64_t now) {
  // Another participant's command: its publisher publishes the target (or the agents follow its path).
  const core::CompiledCommand& cmd = authority_.current();
  if (!authority_.own() || !cmd.tracking.enabled || cmd.hold) return;
  const double t = authority_.model_time(now);
  const core::Vec2 c = core::centre_at(cmd.tracking.path, t);
  const msg::TrackingTarget target =
      dds::to_msg(dds::TargetSample{authority_.id(), t, c, core::centre_velocity(cmd.tracking.path, t), now});
  target_writer_.write(target);
  record_wire(target_ch_, now, target);
  recorder_.write_centre(wall_s(now), t, authority_.epoch(), c.x(), c.y());
}

void SupervisorNode::metrics_tick(std::int64_t now) {
  authority_.sync_clock(now);  // a learnt command: its model clock is where the agents following it are
  const double t = authority_.metrics_time(now);
  // Held, no model time passes: nothing is fed to the convergence detector (it would pile up samples
  // at one instant).
  const SwarmMonitor::Sample s =
      authority_.current().hold ? monitor_.measure(t, now) : monitor_.update(t, now);
  const std::uint64_t epoch = authority_.epoch();
  if (epoch != 0) {
    const msg::SwarmMetrics m = dds::to_msg(s.metrics, epoch, t, now, s.converged);
    metrics_writer_.write(m);
    record_wire(metrics_ch_, now, m);
  }
  record_metrics(s, now);
  if (progress_.due(s, epoch, now)) util::log_info(progress_line(s, authority_.current()));
}

void SupervisorNode::mirror_tick(std::int64_t now) {
  std::vector<dds::MirrorAgent> agents;
  for (const auto& [id, x] : monitor_.alive_positions(now)) agents.push_back({id, x, monitor_.agents().at(id).v});
  const bool commanded = authority_.epoch() != 0;
  const dds::MirrorScene scene =
      dds::mirror_scene(std::move(agents), commanded ? &authority_.current() : nullptr,
                        authority_.model_time(now), util::system_ns(), cfg_.vehicle_link.frame,
                        cfg_.vehicle_link.ros2());
  dds::build_agents(scene, ros2_agents_);
  dds::build_markers(scene, ros2_markers_);
  ros2_agents_writer_.write(ros2_agents_);
  ros2_markers_writer_.write(ros2_markers_);
}

void SupervisorNode::record_metrics(const SwarmMonitor::Sample& s, std::int64_t now) {
  if (!recorder_.is_open()) return;
  const double wall = wall_s(now), t = s.model_time;
  try {
    recorder_.write_metrics({wall, t, authority_.epoch(), s.alive, s.metrics, s.converged});
    const auto step = static_cast<std::int64_t>(std::llround(t / authority_.current().dt));
    positions_.clear();
    for (const auto& [id, x] : monitor_.alive_positions(now, t)) {
      // Drawn with the direction it moves in (its state's velocity), as the ROS 2 mirror orients it.
      const AgentView& a = monitor_.agents().at(id);
      std::optional<double> heading;
      if (a.v.norm() > 1e-12) heading = std::atan2(a.v.y(), a.v.x());
      positions_.push_back({id, a.command.epoch, x.x(), x.y(), heading});
    }
    recorder_.write_positions(wall, t, step, positions_);
    recorder_.flush_if_due(record::Recorder::Clock::now());
  } catch (const std::exception& e) {
    out_.throttled().error("record", std::string("recording: ") + e.what());
  }
}

}  // namespace

int run_supervisor(const config::Config& cfg, const SupervisorOptions& opt) {
  try {
    SupervisorNode s(cfg, opt);
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
