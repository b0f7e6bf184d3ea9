#include "agent_logic.hpp"

#include <algorithm>

#include "core/swarm.hpp"

namespace shapeform::agent {

AgentLogic::AgentLogic(std::int32_t id, core::Vec2 start, std::int64_t timeout_ns)
    : id_(id), x_(start), timeout_ns_(timeout_ns) {}

bool AgentLogic::on_command(const core::Command& cmd, std::uint32_t epoch) {
  if (epoch <= epoch_) return false;
  cmd_ = cmd;
  core::ensure_curve(cmd_.shape);  // analytic shapes; expression shapes arrive compiled
  epoch_ = epoch;
  t_ = 0.0;
  if (target_ && target_->epoch != epoch) target_.reset();
  return true;
}

void AgentLogic::on_target(const TargetSample& t) {
  if (t.epoch != epoch_) return;  // a target of another command (older, or not adopted yet)
  if (target_ && t.model_time < target_->model_time) return;  // out of order
  target_ = t;
  target_age_ = 0.0;
}

void AgentLogic::on_state(std::int32_t id, const core::Vec2& x, std::uint64_t seq, std::int64_t now_ns,
                          std::uint32_t epoch, std::optional<double> arc) {
  if (id == id_) return;
  auto it = table_.find(id);
  if (it == table_.end()) {
    table_.emplace(id, Entry{x, now_ns, seq, epoch, arc});
  } else {
    if (seq <= it->second.seq) return;  // duplicate or reordered: keep the newest
    counters_.samples_lost += seq - it->second.seq - 1;
    it->second = Entry{x, now_ns, seq, epoch, arc};
  }
  ++counters_.samples_received;
}

void AgentLogic::on_gone(std::int32_t id) {
  if (table_.erase(id) > 0) ++counters_.departed;
}

void AgentLogic::drop_stale(std::int64_t now_ns) {
  for (auto it = table_.begin(); it != table_.end();) {
    if (now_ns - it->second.last_seen_ns > timeout_ns_) {
      it = table_.erase(it);
      ++counters_.stale_dropped;
    } else {
      ++it;
    }
  }
}

std::optional<core::Vec2> AgentLogic::tracked_centre() const {
  if (!cmd_.tracking.enabled) return std::nullopt;
  if (target_) return target_->centre + target_age_ * target_->velocity;
  return core::centre_at(cmd_.tracking.path, t_);
}

core::Command AgentLogic::effective_command() const {
  core::Command local = cmd_;
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
  const core::Command local = effective_command();
  const double t = cmd_.tracking.enabled && target_ ? 0.0 : t_;
  const core::ShapeSpec s = core::shape_at(local, t);
  return core::closest_point(s, *core::curve_of(s), x_).s;
}

void AgentLogic::step() {
  if (!has_command()) {
    v_ = core::Vec2::Zero();
    return;
  }
  const bool arc_law = cmd_.law == core::Law::Arc;
  nbrs_.clear();
  for (const auto& [id, e] : table_) {
    core::Neighbour n{id, e.x};
    if (arc_law && e.epoch == epoch_ && e.arc) n.s = *e.arc;
    nbrs_.push_back(n);
  }
  // Deterministic neighbour order (ids ascending) so results never depend on hash order.
  std::sort(nbrs_.begin(), nbrs_.end(), [](const auto& a, const auto& b) { return a.id < b.id; });

  const bool follow_target = cmd_.tracking.enabled && target_;
  const core::StepResult r =
      core::agent_step(follow_target ? effective_command() : cmd_, id_, x_, nbrs_, follow_target ? 0.0 : t_);
  x_ = r.x;
  v_ = r.v;
  t_ += cmd_.dt;
  target_age_ += cmd_.dt;
}

core::Vec2 seeded_start(std::int32_t id, int n, std::uint64_t seed, double half_width) {
  return core::uniform_start(std::max(n, id + 1), seed, half_width)[static_cast<std::size_t>(id)];
}

}  // namespace shapeform::agent
