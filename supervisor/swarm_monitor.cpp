#include "swarm_monitor.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace shapeform::supervisor {

SwarmMonitor::SwarmMonitor(std::int64_t agent_timeout_ns, core::ConvergenceDetector::Params converge, bool lockstep,
                           std::int64_t idle_timeout_ns)
    : agent_timeout_ns_(agent_timeout_ns),
      idle_timeout_ns_(std::max(agent_timeout_ns, idle_timeout_ns)),
      detector_(converge),
      lockstep_(lockstep) {}

SwarmMonitor::Claim SwarmMonitor::claim(std::int32_t id, const dds::SourceId& source, std::int64_t now_ns) {
  const auto it = agents_.find(id);
  if (it == agents_.end() || !alive(it->second, now_ns)) return Claim::Owner;
  AgentView& a = it->second;
  if (!source.known() || !a.source.known() || source == a.source) return Claim::Owner;
  if (std::find(a.duplicates.begin(), a.duplicates.end(), source) != a.duplicates.end()) return Claim::Duplicate;
  a.duplicates.push_back(source);
  return Claim::NewDuplicate;
}

void SwarmMonitor::on_state(std::int32_t id, const core::Vec2& x, const core::Vec2& prev_x, dds::CommandId command,
                            double model_time, std::int64_t now_ns, const dds::SourceId& source,
                            const core::Vec2& v) {
  AgentView& a = agents_[id];
  if (source.known()) a.source = source;
  a.x = x;
  a.prev_x = prev_x;
  a.v = v;
  a.command = command;
  a.model_time = model_time;
  a.last_seen_ns = now_ns;
  a.departed = false;
  if (command.epoch > max_epoch_seen_) max_epoch_seen_ = command.epoch;
}

void SwarmMonitor::on_status(const dds::StatusSample& s) {
  const auto it = agents_.find(s.id);
  if (it == agents_.end()) return;  // status before any state: wait for a state
  it->second.neighbours_heard = s.neighbours_heard;
  it->second.samples_rejected = s.samples_rejected;
  it->second.status = s;
}

void SwarmMonitor::run_figures(core::Metrics& m, std::int64_t now_ns) const {
  if (id_.none()) return;
  std::optional<std::pair<double, double>> low = sampled_min_;
  int interventions = 0, sidesteps = 0, broken = 0, blocked = 0, breaches = 0, beyond = 0;
  bool reported = false;
  for (const auto& [id, a] : agents_) {
    const dds::StatusSample& st = a.status;
    if (st.epoch != id_.epoch) continue;  // figures of another command (or no status yet)
    reported = true;
    if (st.min_gap >= 0.0 && (!low || st.min_gap < low->first)) low = std::make_pair(st.min_gap, st.min_gap_time);
    interventions += static_cast<int>(st.filter_interventions);
    sidesteps += static_cast<int>(st.deadlock_sidesteps);
    broken += static_cast<int>(st.promises_broken);
    breaches += static_cast<int>(st.fence_breaches);
    if (alive(a, now_ns)) {
      blocked += st.blocked ? 1 : 0;
      beyond += st.beyond_fence ? 1 : 0;
    }
  }
  if (low) {
    m.min_separation_run = low->first;
    m.min_separation_run_time = low->second;
  }
  if (!reported) return;
  m.filter_interventions = interventions;
  m.deadlock_sidesteps = sidesteps;
  m.promises_broken = broken;
  m.agents_blocked = blocked;
  m.fence_breaches = breaches;
  m.agents_beyond_fence = beyond;
}

void SwarmMonitor::on_departed(std::int32_t id) {
  const auto it = agents_.find(id);
  if (it != agents_.end()) it->second.departed = true;
}

void SwarmMonitor::set_command(const core::CompiledCommand& cmd, dds::CommandId id, std::int64_t) {
  command_ = cmd;
  id_ = id;
  detector_.set_command(cmd);  // judged against this command's shape from now on
  last_.reset();
  sampled_min_.reset();
  hist_t_.clear();
  hist_err_.clear();
  hist_gap_.clear();
}

bool SwarmMonitor::alive(const AgentView& a, std::int64_t now_ns) const {
  return !a.departed && now_ns - a.last_seen_ns <= (a.command.none() ? idle_timeout_ns_ : agent_timeout_ns_);
}

int SwarmMonitor::alive_count(std::int64_t now_ns) const {
  int n = 0;
  for (const auto& [id, a] : agents_) n += alive(a, now_ns) ? 1 : 0;
  return n;
}

int SwarmMonitor::following_count(std::int64_t now_ns) const {
  int n = 0;
  for (const auto& [id, a] : agents_) n += (alive(a, now_ns) && a.command == id_ && !id_.none()) ? 1 : 0;
  return n;
}

std::uint64_t SwarmMonitor::min_epoch_followed(std::int64_t now_ns) const {
  std::uint64_t floor = 0;
  for (const auto& [id, a] : agents_)
    if (alive(a, now_ns) && !a.command.none() && (floor == 0 || a.command.epoch < floor)) floor = a.command.epoch;
  return floor;
}

bool SwarmMonitor::all_hear(int count, std::int64_t now_ns) const {
  for (const auto& [id, a] : agents_)
    if (alive(a, now_ns) && (!a.neighbours_heard || *a.neighbours_heard < count)) return false;
  return true;
}

std::optional<double> SwarmMonitor::min_following_model_time(std::int64_t now_ns) const {
  std::optional<double> t;
  for (const auto& [id, a] : agents_)
    if (alive(a, now_ns) && !id_.none() && a.command == id_) t = t ? std::min(*t, a.model_time) : a.model_time;
  return t;
}

std::vector<std::pair<std::int32_t, core::Vec2>> SwarmMonitor::alive_positions(std::int64_t now_ns,
                                                                               std::optional<double> at) const {
  std::vector<std::pair<std::int32_t, core::Vec2>> out;
  for (const auto& [id, a] : agents_) {
    if (!alive(a, now_ns)) continue;
    // In lockstep an agent is at most one step past the slowest one: its previous state is at `at`.
    const bool ahead = lockstep_ && at && a.command == id_ && a.model_time > *at;
    out.emplace_back(id, ahead ? a.prev_x : a.x);
  }
  return out;
}

SwarmMonitor::Sample SwarmMonitor::measure(double model_time, std::int64_t now_ns) const {
  Sample s;
  s.model_time = model_time;
  s.alive = alive_count(now_ns);
  s.following = following_count(now_ns);
  if (command_) {
    std::vector<core::Vec2> x;
    x.reserve(agents_.size());
    for (const auto& [id, p] : alive_positions(now_ns, model_time)) x.push_back(p);
    s.metrics = core::compute_metrics(*command_, x, model_time);
    s.spread = core::spread(x);
    run_figures(s.metrics, now_ns);
  } else {
    s.metrics.agents = s.alive;
  }
  s.converged = detector_.converged();
  s.why = detector_.why();
  return s;
}

SwarmMonitor::Sample SwarmMonitor::update(double model_time, std::int64_t now_ns) {
  Sample s = measure(model_time, now_ns);
  if (command_) {
    const std::optional<double>& low = s.metrics.min_separation;
    if (low && s.following == s.alive && (!sampled_min_ || *low < sampled_min_->first)) {
      sampled_min_ = std::make_pair(*low, model_time);
      if (!s.metrics.min_separation_run || *low < *s.metrics.min_separation_run) {
        s.metrics.min_separation_run = *low;
        s.metrics.min_separation_run_time = model_time;
      }
    }
    if (s.alive > 0 && s.following == s.alive && s.metrics.agents_blocked.value_or(0) > 0) {
      detector_.blocked();  // the safety filter holds agents from their slots: never converged now
      hist_t_.push_back(model_time);
      hist_err_.push_back(s.metrics.shape_error_mean.value_or(0.0));
      hist_gap_.push_back(core::uniformity(*command_, s.metrics));
    } else if (s.alive > 0 && s.following == s.alive) {
      const auto uniform = core::uniformity(*command_, s.metrics);
      detector_.add(model_time, s.metrics.shape_error_mean, uniform, s.spread);
      hist_t_.push_back(model_time);
      hist_err_.push_back(s.metrics.shape_error_mean.value_or(0.0));
      hist_gap_.push_back(uniform);
    } else {
      detector_.reset();  // agents still switching to the new command (or following another one)
    }
    s.converged = detector_.converged();
    s.why = detector_.why();
  }
  last_ = s;
  return s;
}

std::optional<double> SwarmMonitor::settle_time(const core::SettleParams& p) const {
  const auto k = core::settle_index(hist_err_, hist_gap_, p);
  if (!k) return std::nullopt;
  return hist_t_[static_cast<std::size_t>(*k)];
}

}  // namespace shapeform::supervisor
