#include "agent_logic.hpp"

#include <algorithm>

#include "core/swarm.hpp"

namespace shapeform::agent {

AgentLogic::AgentLogic(std::int32_t id, core::Vec2 start, std::int64_t timeout_ns, bool lockstep,
                       int max_wait_ticks, std::int64_t idle_timeout_ns)
    : id_(id),
      x_(start),
      x_prev_(start),
      timeout_ns_(timeout_ns),
      idle_timeout_ns_(idle_timeout_ns > 0 ? idle_timeout_ns : timeout_ns),
      lockstep_(lockstep),
      max_wait_ticks_(max_wait_ticks) {}

dds::CommandArbiter::Verdict AgentLogic::on_command(const dds::CommandSample& c) {
  const auto v = arbiter_.offer(c, peer_floor());
  if (v == dds::CommandArbiter::Verdict::Refused) ++counters_.samples_rejected;
  if (v == dds::CommandArbiter::Verdict::Adopted) adopt();
  return v;
}

bool AgentLogic::recheck_commands() {
  if (!arbiter_.has_refused() || !arbiter_.recheck(peer_floor())) return false;
  adopt();
  return true;
}

std::uint64_t AgentLogic::peer_floor() const {
  std::uint64_t floor = 0;
  for (const auto& [id, e] : table_)
    if (!e.cur.command.none() && (floor == 0 || e.cur.command.epoch < floor)) floor = e.cur.command.epoch;
  return floor;
}

void AgentLogic::adopt() {
  const dds::CommandId command = arbiter_.id();
  cmd_ = arbiter_.current().command;
  t_ = 0.0;
  waited_ = 0;
  x_prev_ = x_;
  arc_prev_.reset();
  if (lockstep_) {
    // A late joiner starts at the step the swarm is at, so nobody waits for its past.
    long k0 = 0;
    for (const auto& [id, e] : table_)
      if (e.cur.command == command) k0 = std::max(k0, step_of(e.cur.model_time));
    t_ = static_cast<double>(k0) * cmd_.dt;
  }
  if (target_ && target_->command != command) target_.reset();
}

void AgentLogic::on_target(const TargetSample& t, std::int64_t now_ns) {
  if (t.command != arbiter_.id()) return;  // a target of another command (older, or not adopted yet)
  if (target_ && t.model_time < target_->model_time) return;  // out of order
  target_ = t;
  target_age_ = 0.0;
  target_seen_ns_ = now_ns;
}

void AgentLogic::on_state(std::int32_t id, const core::Vec2& x, std::uint64_t seq, std::int64_t now_ns,
                          dds::CommandId command, std::optional<double> arc, double model_time,
                          std::optional<core::Vec2> prev_x, std::optional<double> prev_arc) {
  if (id == id_) return;
  const Snapshot snap{x, command, model_time, arc};
  // The sender's previous step comes with the sample: a lost sample never leaves a hole in lockstep.
  const std::optional<Snapshot> before =
      prev_x ? std::optional<Snapshot>(Snapshot{*prev_x, command, model_time - cmd_.dt, prev_arc}) : std::nullopt;
  auto it = table_.find(id);
  if (it == table_.end()) {
    table_.emplace(id, Entry{now_ns, seq, snap, before.value_or(snap)});
  } else {
    Entry& e = it->second;
    if (seq <= e.seq) return;  // duplicate or reordered: keep the newest
    counters_.samples_lost += seq - e.seq - 1;
    if (before) e.prev = *before;
    else if (snap.command != e.cur.command || snap.model_time != e.cur.model_time) e.prev = e.cur;
    e.cur = snap;
    e.seq = seq;
    e.last_seen_ns = now_ns;
  }
  ++counters_.samples_received;
}

void AgentLogic::on_gone(std::int32_t id) {
  if (table_.erase(id) > 0) ++counters_.departed;
}

void AgentLogic::drop_stale(std::int64_t now_ns) {
  const std::int64_t timeout = has_command() ? timeout_ns_ : idle_timeout_ns_;
  for (auto it = table_.begin(); it != table_.end();) {
    if (now_ns - it->second.last_seen_ns > timeout) {
      it = table_.erase(it);
      ++counters_.stale_dropped;
    } else {
      ++it;
    }
  }
  if (target_ && now_ns - target_seen_ns_ > kTargetTimeout_ns) target_.reset();
}

std::optional<core::Vec2> AgentLogic::tracked_centre() const {
  if (!cmd_.tracking.enabled) return std::nullopt;
  if (following_target()) return target_->centre + target_age_ * target_->velocity;
  return core::centre_at(cmd_.tracking.path, t_);
}

core::CompiledCommand AgentLogic::effective_command() const {
  core::CompiledCommand local = cmd_;
  if (cmd_.tracking.enabled && target_) {
    // Follow the supervisor's target: the centre moves on from where it was last heard, linearly,
    // with its published velocity (which feed-forward then uses). Time runs from 0 at "now".
    local.tracking.path.kind = core::CentrePath::Kind::Line;
    local.tracking.path.point = target_->centre + target_age_ * target_->velocity;
    local.tracking.path.velocity = target_->velocity;
  }
  return local;
}

std::optional<double> AgentLogic::arc() const {
  if (!has_command()) return std::nullopt;
  const bool follow_target = following_target();
  const core::CompiledCommand local = follow_target ? effective_command() : cmd_;
  const double t = follow_target ? 0.0 : t_;
  const core::ShapeSpec s = core::shape_at(local, t);
  return core::closest_point(s, cmd_.curve(), x_).s;
}

bool AgentLogic::step() {
  if (!has_command() || cmd_.hold) {
    // Before any command, and while held: stay put, and model time (with the tracked centre and
    // the lockstep step count) stands still.
    v_ = core::Vec2::Zero();
    return false;
  }
  const bool arc_law = cmd_.law == core::Law::Arc;
  const dds::CommandId followed = arbiter_.id();
  const long k = step_of(t_);
  nbrs_.clear();
  bool ready = true;
  for (const auto& [id, e] : table_) {
    // Lockstep: the neighbour's state of step k (the newest, or the one before if it is already
    // ahead); free running: the newest.
    const Snapshot* use = &e.cur;
    if (lockstep_) {
      const long cur = step_of(e.cur.model_time);
      if (e.cur.command != followed || cur < k) ready = false;
      else if (cur > k && e.prev.command == followed && step_of(e.prev.model_time) == k) use = &e.prev;
    }
    core::Neighbour n{id, use->x};
    if (arc_law && use->command == followed && use->arc) n.s = *use->arc;
    nbrs_.push_back(n);
  }
  if (lockstep_ && !ready) {
    // Hold until every neighbour has published step k; past the bound, go on without the laggard
    // (free running) until it catches up.
    if (++waited_ <= max_wait_ticks_) {
      v_ = core::Vec2::Zero();
      return false;
    }
  } else {
    waited_ = 0;
  }
  // Deterministic neighbour order (ids ascending) so results never depend on hash order.
  std::sort(nbrs_.begin(), nbrs_.end(), [](const auto& a, const auto& b) { return a.id < b.id; });

  const bool follow_target = following_target();
  const core::StepResult r =
      core::agent_step(follow_target ? effective_command() : cmd_, id_, x_, nbrs_, follow_target ? 0.0 : t_);
  if (r.clamped) ++counters_.steps_clamped;
  arc_prev_ = arc_law ? arc() : std::nullopt;
  x_prev_ = x_;
  x_ = r.x;
  v_ = r.v;
  t_ += cmd_.dt;
  target_age_ += cmd_.dt;
  return true;
}

core::Vec2 seeded_start(std::int32_t id, int n, std::uint64_t seed, double half_width) {
  return core::uniform_start(std::max(n, id + 1), seed, half_width)[static_cast<std::size_t>(id)];
}

IdentityGuard::Action IdentityGuard::on_sample(std::int32_t id, const dds::SourceId& other) {
  if (yielding_ || !other.known() || ours(other)) return Action::None;
  const std::pair<std::int32_t, dds::SourceId> key{id, other};
  if (std::find(reported_.begin(), reported_.end(), key) != reported_.end()) return Action::None;
  reported_.push_back(key);
  // A newcomer yields; two publishers agree on the GUID prefix order: the higher one yields.
  yielding_ = !published_ || other < own();
  return yielding_ ? Action::Yield : Action::Keep;
}

}  // namespace shapeform::agent
