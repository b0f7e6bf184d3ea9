// DDS wiring of the supervisor: one fixed-rate loop that drains agent states, publishes the tracking
// target, computes/publishes/records metrics, and runs console and script commands between ticks.
#include "supervisor_node.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <sstream>

#include <nlohmann/json.hpp>

#include "console_input.hpp"
#include "console_parser.hpp"
#include "dds/convert.hpp"
#include "dds/node.hpp"
#include "dds/participant.hpp"
#include "recorder.hpp"
#include "shapeform/msg/AgentState.h"
#include "shapeform/msg/AgentStatus.h"
#include "shapeform/msg/ShapeCommand.h"
#include "shapeform/msg/SwarmMetrics.h"
#include "shapeform/msg/TrackingTarget.h"
#include "sim/simulation.hpp"
#include "swarm_monitor.hpp"
#include "util/log.hpp"
#include "util/proc_stats.hpp"
#include "util/rate_loop.hpp"
#include "util/signals.hpp"

namespace shapeform::supervisor {

namespace {

std::string fmt_opt(const std::optional<double>& v, const char* f = "%.4f") {
  if (!v) return "-";
  char b[32];
  std::snprintf(b, sizeof b, f, *v);
  return b;
}

std::string describe_command(const core::CompiledCommand& c) {
  std::ostringstream o;
  const auto& s = c.shape;
  o << core::to_string(s.kind);
  switch (s.kind) {
    case core::ShapeKind::Line: o << " m=" << s.m << " c=" << s.c; break;
    case core::ShapeKind::Circle: o << " r=" << s.r0; break;
    case core::ShapeKind::Ellipse: o << " a=" << s.a << " b=" << s.b; break;
    case core::ShapeKind::Square: o << " a=" << s.a; break;
    case core::ShapeKind::Polar: o << " r=\"" << s.r_expr << '"'; break;
    case core::ShapeKind::Parametric:
      o << " x=\"" << s.x_expr << "\" y=\"" << s.y_expr << '"' << (s.closed ? " closed" : " open");
      break;
    case core::ShapeKind::Implicit: o << " f=\"" << s.f_expr << '"'; break;
    case core::ShapeKind::Polygon: o << " with " << s.vertices.size() << (s.closed ? " vertices, closed" : " vertices, open"); break;
  }
  if (s.rotation != 0.0) o << " rotated " << s.rotation * 180.0 / 3.14159265358979323846 << " deg";
  if (s.scale != 1.0) o << " scaled " << s.scale;
  if (c.tracking.enabled)
    o << ", tracking on a " << core::to_string(c.tracking.path.kind) << " path"
      << (c.tracking.feedforward ? " with feed-forward" : "");
  else if (c.curve().closed())
    o << " centre (" << s.centre.x() << ", " << s.centre.y() << ")";
  if (c.law == core::Law::Arc) {
    o << "; law arc k_normal=" << c.arc.k_normal << " k_tangent=" << c.arc.k_tangent;
    if (s.kind == core::ShapeKind::Line) o << " spacing=" << c.arc.spacing;
  }
  o << "; k1=" << c.gains.k1 << " k2=" << c.gains.k2 << " sigma=" << c.gains.sigma << " beta=" << c.gains.beta
    << " r=" << c.gains.r << ", " << core::to_string(c.integrator) << " dt=" << c.dt;
  if (c.max_speed > 0) o << ", max_speed=" << c.max_speed;
  return o.str();
}

/// The running supervisor. One thread of control; Fast DDS threads only fill reader mailboxes.
class Supervisor {
 public:
  Supervisor(const config::Config& cfg, const SupervisorOptions& opt)
      : cfg_(cfg),
        opt_(opt),
        out_(opt.json ? std::cerr : std::cout),
        // Agents publish once per period: never call one dead before it missed 3 periods.
        monitor_(static_cast<std::int64_t>(std::max(cfg.supervisor.agent_timeout_s, 3.0 / cfg.agent.rate_hz) * 1e9),
                 cfg.supervisor.converge, cfg.agent.lockstep),
        recorder_(cfg.supervisor.flush_s),
        current_(cfg.command) {}

  int run();

 private:
  double model_time(std::int64_t now) const {
    if (epoch_ == 0) return 0.0;
    return static_cast<double>(now - epoch_start_ns_) * 1e-9 * cfg_.agent.rate_hz * current_.dt;
  }
  /// The model time the metrics are taken at: the supervisor's clock, or, in lockstep, where the agents
  /// are (the slowest agent on the command: the others are at most one step ahead).
  double metrics_time(std::int64_t now) const {
    if (cfg_.agent.lockstep)
      if (const auto t = monitor_.min_following_model_time(now)) return *t;
    return model_time(now);
  }
  void drain(std::int64_t now);
  void publish_target(std::int64_t now);
  void metrics_tick(std::int64_t now);
  void publish_command(const core::CompiledCommand& cmd, std::int64_t now);
  /// Runs input lines until one blocks (wait, sleep) or none is available.
  void run_input(std::int64_t now);
  /// Executes one parsed action; returns false when it blocks.
  void execute(const Action& a, std::int64_t now);
  bool pending_done(std::int64_t now);
  void print_summary(std::int64_t now);
  void print_metrics_line(const SwarmMonitor::Sample& s);

  const config::Config& cfg_;
  SupervisorOptions opt_;
  std::ostream& out_;
  SwarmMonitor monitor_;
  Recorder recorder_;
  core::CompiledCommand current_;  ///< the command in force (or the config's, before any)
  std::uint32_t epoch_ = 0;
  std::int64_t epoch_start_ns_ = 0;
  std::int64_t start_ns_ = util::steady_ns();

  std::unique_ptr<dds::Node> node_;
  dds::Writer<msg::ShapeCommand> command_writer_;
  dds::Writer<msg::TrackingTarget> target_writer_;
  dds::Writer<msg::SwarmMetrics> metrics_writer_;
  dds::Reader<msg::AgentState> state_reader_;
  dds::Reader<msg::AgentStatus> status_reader_;
  std::vector<dds::Received<msg::AgentState>> states_;
  std::vector<dds::Received<msg::AgentStatus>> statuses_;
  std::uint64_t rejected_ = 0;
  util::ThrottledLog throttled_{5.0};

  std::unique_ptr<ScriptSource> script_;
  std::unique_ptr<ConsoleInput> console_;
  std::optional<Action> pending_;
  std::int64_t pending_deadline_ns_ = 0;
  bool quit_ = false;
  int exit_status_ = kExitOk;
  std::int64_t last_progress_ns_ = 0;
  std::uint64_t metrics_ticks_ = 0;
};

void Supervisor::drain(std::int64_t now) {
  state_reader_.drain(states_);
  for (const auto& s : states_) {
    if (!s.valid_data) {
      // Disposed, or its writer left (its dispose, best effort, may be lost) while it was still heard:
      // a clean exit, logged once. A writer leaving after the agent fell silent (a lease expiring after
      // a kill) changes nothing: that agent is shown dead already.
      const auto it = monitor_.agents().find(s.key_id);
      if (s.instance != dds::InstanceState::Alive && it != monitor_.agents().end() && monitor_.alive(it->second, now)) {
        monitor_.on_departed(s.key_id);
        util::log_info("agent " + std::to_string(s.key_id) + " left");
      }
      continue;
    }
    std::string why;
    if (!dds::valid_state(s.msg, why)) {
      ++rejected_;
      throttled_.warn("state", "agent state rejected: " + why);
      continue;
    }
    monitor_.on_state(s.msg.id(), core::Vec2(s.msg.x(), s.msg.y()), core::Vec2(s.msg.prev_x(), s.msg.prev_y()),
                      s.msg.epoch(), s.msg.model_time(), now);
  }
  status_reader_.drain(statuses_);
  for (const auto& s : statuses_)
    if (s.valid_data && s.msg.id() >= 0)
      monitor_.on_status(s.msg.id(), s.msg.neighbours_heard(), s.msg.samples_rejected());
}

void Supervisor::publish_target(std::int64_t now) {
  if (epoch_ == 0 || !current_.tracking.enabled) return;
  const double t = model_time(now);
  const core::Vec2 c = core::centre_at(current_.tracking.path, t);
  const core::Vec2 v = core::centre_velocity(current_.tracking.path, t);
  msg::TrackingTarget m;
  m.epoch(epoch_);
  m.model_time(t);
  m.cx(c.x());
  m.cy(c.y());
  m.vx(v.x());
  m.vy(v.y());
  m.stamp_ns(now);
  target_writer_.write(m);
}

void Supervisor::publish_command(const core::CompiledCommand& cmd, std::int64_t now) {
  // A restarted supervisor continues after the newest epoch the agents follow.
  epoch_ = std::max(epoch_, monitor_.max_epoch_seen()) + 1;
  current_ = cmd;
  epoch_start_ns_ = now;
  monitor_.set_command(cmd, epoch_, now);
  if (!command_writer_.write(dds::to_msg(cmd, epoch_))) util::log_warn("command write failed");
  out_ << "epoch " << epoch_ << ": " << describe_command(cmd) << std::endl;
}

void Supervisor::print_metrics_line(const SwarmMonitor::Sample& s) {
  const core::Metrics& m = s.metrics;
  std::ostringstream o;
  o << "t=" << fmt_opt(s.model_time, "%.0f") << " agents=" << s.alive << " following=" << s.following
    << " shape_error=" << fmt_opt(m.shape_error_mean) << " max=" << fmt_opt(m.shape_error_max)
    << " gap_cv=" << fmt_opt(m.gap_cv) << " min_sep=" << fmt_opt(m.min_separation)
    << " clusters=" << (m.clusters ? std::to_string(*m.clusters) : "-");
  if (m.centroid_error) o << " centroid_error=" << fmt_opt(m.centroid_error) << " ring_error=" << fmt_opt(m.ring_error);
  if (current_.law == core::Law::Arc || !m.shape_error_mean || m.curve_error_mean != m.shape_error_mean)
    o << " curve_error=" << fmt_opt(m.curve_error_mean, "%.2e") << " arc_gap_cv=" << fmt_opt(m.arc_gap_cv, "%.2e");
  o << (s.converged ? " converged" : "");
  util::log_info(o.str());
}

void Supervisor::metrics_tick(std::int64_t now) {
  const double t = metrics_time(now);
  const SwarmMonitor::Sample s = monitor_.update(t, now);
  if (epoch_ != 0) metrics_writer_.write(dds::to_msg(s.metrics, epoch_, t, now, s.converged));
  const double wall = static_cast<double>(now - start_ns_) * 1e-9;
  if (recorder_.is_open()) {
    try {
      recorder_.write_metrics({wall, t, epoch_, s.alive, s.metrics, s.converged});
      const auto step = static_cast<std::int64_t>(std::llround(t / current_.dt));
      for (const auto& [id, x] : monitor_.alive_positions(now, t)) recorder_.write_positions(wall, t, step, id, x.x(), x.y());
      recorder_.flush_if_due(Recorder::Clock::now());
    } catch (const std::exception& e) {
      throttled_.error("record", std::string("recording: ") + e.what());
    }
  }
  if (now - last_progress_ns_ >= 1'000'000'000LL) {
    last_progress_ns_ = now;
    print_metrics_line(s);
  }
}

bool Supervisor::pending_done(std::int64_t now) {
  if (!pending_) return true;
  const bool timed_out = now >= pending_deadline_ns_;
  if (const auto* w = std::get_if<WaitConverged>(&*pending_)) {
    if (epoch_ != 0 && monitor_.converged()) {
      out_ << "converged at t=" << fmt_opt(model_time(now), "%.0f") << " ("
           << fmt_opt(static_cast<double>(now - epoch_start_ns_) * 1e-9, "%.1f") << " s after epoch " << epoch_ << ")"
           << std::endl;
      return true;
    }
    if (timed_out) {
      out_ << "wait converged: timed out after " << w->timeout_s << " s" << std::endl;
      util::log_warn("wait converged timed out after " + fmt_opt(w->timeout_s, "%g") + " s");
      exit_status_ = kExitWaitTimedOut;
      return true;
    }
    return false;
  }
  if (const auto* w = std::get_if<WaitAgents>(&*pending_)) {
    // N agents alive, and each hears the others (its status says so): a command sent before discovery
    // completes would be followed by agents that do not yet know all their neighbours.
    const int n = monitor_.alive_count(now);
    if (n >= w->count && monitor_.all_hear(w->count - 1, now)) {
      out_ << "agents: " << n << " alive, each hearing " << w->count - 1 << " or more" << std::endl;
      return true;
    }
    if (timed_out) {
      out_ << "wait agents: timed out after " << w->timeout_s << " s with " << n << " of " << w->count << " agents"
           << std::endl;
      util::log_warn("wait agents timed out with " + std::to_string(n) + " of " + std::to_string(w->count));
      exit_status_ = kExitWaitTimedOut;
      return true;
    }
    return false;
  }
  if (const auto* w = std::get_if<WaitTime>(&*pending_)) {
    // Done when every agent on the current command has done T of model time by its own count (a
    // loaded agent skips ticks, a lockstep agent waits for the others: wall time is not enough).
    const auto t = monitor_.min_following_model_time(now);
    if (t && monitor_.following_count(now) == monitor_.alive_count(now) && *t >= w->model_time - 1e-9) return true;
    if (timed_out) {
      out_ << "wait time: timed out after " << w->timeout_s << " s" << std::endl;
      exit_status_ = kExitWaitTimedOut;
      return true;
    }
    return false;
  }
  return timed_out;  // Sleep
}

void Supervisor::execute(const Action& a, std::int64_t now) {
  const auto block = [&](double seconds) {
    pending_ = a;
    // Capped at 10^9 s (32 years), so that any accepted number of seconds stays inside int64 ns.
    pending_deadline_ns_ = now + static_cast<std::int64_t>(std::min(seconds, 1e9) * 1e9);
  };
  std::visit(
      [&](const auto& act) {
        using T = std::decay_t<decltype(act)>;
        if constexpr (std::is_same_v<T, SetCommand>) {
          publish_command(act.command, now);
        } else if constexpr (std::is_same_v<T, StartScenario>) {
          publish_command(cfg_.command, now);
        } else if constexpr (std::is_same_v<T, TrackStop>) {
          core::CompiledCommand c = current_;
          if (c.tracking.enabled) c.shape.centre = core::centre_at(c.tracking.path, model_time(now));
          c.tracking.enabled = false;
          publish_command(c, now);
        } else if constexpr (std::is_same_v<T, Status>) {
          out_ << monitor_.status_table(now, model_time(now)) << std::flush;
        } else if constexpr (std::is_same_v<T, ShowMetrics>) {
          const auto s = monitor_.measure(metrics_time(now), now);  // a query: the detector sees only the metrics ticks
          nlohmann::json j = sim::metrics_json(s.metrics);
          j["epoch"] = epoch_;
          j["model_time"] = s.model_time;
          j["converged"] = s.converged;
          out_ << j.dump() << std::endl;
        } else if constexpr (std::is_same_v<T, WaitConverged>) {
          block(act.timeout_s);
        } else if constexpr (std::is_same_v<T, WaitAgents>) {
          block(act.timeout_s);
        } else if constexpr (std::is_same_v<T, WaitTime>) {
          block(act.timeout_s);
        } else if constexpr (std::is_same_v<T, Sleep>) {
          block(act.seconds);
        } else if constexpr (std::is_same_v<T, RecordStart>) {
          try {
            recorder_.open(act.dir);  // closes the current recording only once the new one is open
            out_ << "recording into " << act.dir << std::endl;
          } catch (const std::exception& e) {
            std::cerr << "record start: " << e.what() << std::endl;
          }
        } else if constexpr (std::is_same_v<T, RecordStop>) {
          if (recorder_.is_open()) out_ << "recording stopped: " << recorder_.dir().string() << std::endl;
          recorder_.close();
        } else if constexpr (std::is_same_v<T, Help>) {
          out_ << help_text(act.topic) << std::flush;
        } else if constexpr (std::is_same_v<T, Quit>) {
          quit_ = true;
        }
      },
      a);
}

void Supervisor::run_input(std::int64_t now) {
  while (!quit_) {
    if (pending_) {
      if (!pending_done(now)) return;
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
      std::cerr << with_location(*src, r.error) << std::endl;
      continue;
    }
    execute(r.action, now);
  }
}

void Supervisor::print_summary(std::int64_t now) {
  const double t = metrics_time(now);
  const SwarmMonitor::Sample s = monitor_.measure(t, now);
  nlohmann::json j = sim::metrics_json(s.metrics);
  j["name"] = cfg_.name;
  j["shape"] = std::string(core::to_string(current_.shape.kind));
  j["law"] = std::string(core::to_string(current_.law));
  j["tracking"] = current_.tracking.enabled;
  j["epoch"] = epoch_;
  j["model_time"] = t;
  j["dt"] = current_.dt;
  j["steps"] = static_cast<long>(std::llround(t / current_.dt));
  j["agents_seen"] = monitor_.agents().size();
  j["converged"] = s.converged;
  const auto& cv = cfg_.supervisor.converge;
  const auto settle = monitor_.settle_time({cv.band_abs, cv.band_rel, cv.gap_cv_max});
  j["settle_step"] = settle ? nlohmann::json(std::llround(*settle / current_.dt)) : nlohmann::json(nullptr);
  if (!current_.tracking.enabled) {
    j.erase("centroid_error");
    j.erase("ring_error");
  }
  auto& ids = j["final_ids"] = nlohmann::json::array();
  auto& fp = j["final_positions"] = nlohmann::json::array();
  auto& ft = j["final_model_times"] = nlohmann::json::array();  // each agent's own model time
  for (const auto& [id, x] : monitor_.alive_positions(now)) {
    ids.push_back(id);
    fp.push_back({x.x(), x.y()});
    ft.push_back(monitor_.agents().at(id).model_time);
  }
  j["samples_rejected"] = rejected_;
  j["recording"] = recorder_.is_open() ? nlohmann::json(recorder_.dir().string()) : nlohmann::json(nullptr);
  j["exit_status"] = exit_status_;
  if (opt_.json) {
    std::cout << j.dump() << std::endl;
    return;
  }
  std::cout << "summary: epoch " << epoch_ << ", " << s.alive << " agents, t=" << fmt_opt(t, "%.0f")
            << (s.converged ? ", converged" : ", not converged") << "\n  shape_error_mean="
            << fmt_opt(s.metrics.shape_error_mean) << " shape_error_max=" << fmt_opt(s.metrics.shape_error_max)
            << " gap_cv=" << fmt_opt(s.metrics.gap_cv) << " min_separation=" << fmt_opt(s.metrics.min_separation)
            << " clusters=" << (s.metrics.clusters ? std::to_string(*s.metrics.clusters) : "-")
            << " settle_step=" << (settle ? std::to_string(std::llround(*settle / current_.dt)) : "-");
  std::cout << " curve_error_mean=" << fmt_opt(s.metrics.curve_error_mean, "%.3g")
            << " arc_gap_cv=" << fmt_opt(s.metrics.arc_gap_cv, "%.3g");
  if (s.metrics.centroid_error)
    std::cout << " centroid_error=" << fmt_opt(s.metrics.centroid_error) << " ring_error=" << fmt_opt(s.metrics.ring_error);
  std::cout << std::endl;
  if (recorder_.is_open()) std::cout << "  recording: " << recorder_.dir().string() << std::endl;
}

int Supervisor::run() {
  util::log_init("supervisor");
  util::install_stop_signals();
  // Validate the whole script before touching the swarm: a bad line is exit status 2, nothing sent.
  if (!opt_.script.empty()) {
    try {
      ScriptSource check(opt_.script);
      bool bad = false;
      core::CompiledCommand c = cfg_.command;
      while (auto line = check.poll()) {
        const ParseResult r = parse_command(*line, c);
        if (!r.ok()) {
          std::cerr << with_location(check, r.error) << std::endl;
          bad = true;
        } else if (const auto* set = std::get_if<SetCommand>(&r.action)) {
          c = set->command;
        }
      }
      if (bad) return kExitBadInput;
      script_ = std::make_unique<ScriptSource>(opt_.script);
    } catch (const std::exception& e) {
      std::cerr << "shapeform_supervisor: --script: " << e.what() << std::endl;
      return kExitBadInput;
    }
  }
  util::log_info(std::string("transport: ") + dds::describe(cfg_.transport));
  try {
    node_ = std::make_unique<dds::Node>(cfg_.transport, "shapeform_supervisor");
    command_writer_ = node_->writer<msg::ShapeCommand>(dds::TopicId::Command);
    target_writer_ = node_->writer<msg::TrackingTarget>(dds::TopicId::Target);
    metrics_writer_ = node_->writer<msg::SwarmMetrics>(dds::TopicId::Metrics);
    state_reader_ = node_->reader<msg::AgentState>(dds::TopicId::State);
    status_reader_ = node_->reader<msg::AgentStatus>(dds::TopicId::Status);
  } catch (const std::exception& e) {
    util::log_error(e.what());
    return kExitRuntime;
  }
  if (!opt_.record_dir.empty()) {
    try {
      recorder_.open(opt_.record_dir);
    } catch (const std::exception& e) {
      std::cerr << "shapeform_supervisor: --record: " << e.what() << std::endl;
      return kExitBadInput;
    }
  }
  console_ = std::make_unique<ConsoleInput>();

  util::RateLoop loop(cfg_.supervisor.target_rate_hz);
  const auto metrics_every = std::max<std::uint64_t>(
      1, static_cast<std::uint64_t>(std::llround(cfg_.supervisor.target_rate_hz / cfg_.supervisor.metrics_rate_hz)));
  std::uint64_t tick = 0;
  while (!quit_ && loop.wait_next(util::stop_flag())) {
    const std::int64_t now = util::steady_ns();
    drain(now);
    publish_target(now);
    if (tick++ % metrics_every == 0) metrics_tick(now);
    run_input(now);
    const bool input_done = (!script_ || script_->eof()) && !pending_ && console_->eof();
    if (input_done && !recorder_.is_open()) break;
  }
  const std::int64_t now = util::steady_ns();
  drain(now);
  print_summary(now);
  recorder_.close();
  console_.reset();
  return exit_status_;
}

}  // namespace

int run_supervisor(const config::Config& cfg, const SupervisorOptions& opt) {
  try {
    Supervisor s(cfg, opt);
    return s.run();
  } catch (const std::exception& e) {
    util::log_error(e.what());
    return kExitRuntime;
  }
}

}  // namespace shapeform::supervisor
