#include "agent_logic.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "core/fence.hpp"
#include "core/law.hpp"
#include "core/metrics.hpp"
#include "core/swarm.hpp"

namespace shapeform::agent {

NeighbourTable::NeighbourTable(std::vector<std::int32_t> hosted, std::int64_t timeout_ns,
                               std::int64_t idle_timeout_ns)
    : hosted_(std::move(hosted)),
      timeout_ns_(timeout_ns),
      idle_timeout_ns_(idle_timeout_ns > 0 ? idle_timeout_ns : timeout_ns),
      own_(hosted_.size()) {
  for (std::size_t k = 0; k < hosted_.size(); ++k) {
    const std::int32_t id = hosted_[k];
    if (id < 0) continue;  // never received: a valid sample's id is >= 0
    const auto slot = static_cast<std::size_t>(id);
    if (slot >= index_of_.size()) index_of_.resize(slot + 1, -1);
    if (index_of_[slot] < 0) index_of_[slot] = static_cast<int>(k);  // the first, as a search would find
  }
}

int NeighbourTable::hosted_index(std::int32_t id) const {
  const auto slot = static_cast<std::size_t>(id);
  return id >= 0 && slot < index_of_.size() ? index_of_[slot] : -1;
}

void NeighbourTable::on_state(std::int32_t id, const core::Vec2& x, std::uint64_t seq, std::int64_t now_ns,
                              dds::CommandId command, std::optional<double> arc, double model_time,
                              std::optional<core::Vec2> prev_x, std::optional<double> prev_arc, double dt) {
  const Snapshot snap{x, command, model_time, arc};
  // The sender's previous step comes with the sample: a lost sample never leaves a hole in lockstep.
  const std::optional<Snapshot> before =
      prev_x ? std::optional<Snapshot>(Snapshot{*prev_x, command, model_time - dt, prev_arc}) : std::nullopt;
  if (id < 0) return;  // never a valid sample's (dds::valid_state): nothing to index it by
  const auto found = entries_.find(id);
  Entry* it = found == entries_.end() ? nullptr : &found->second;
  std::uint64_t lost = 0;
  if (it == nullptr) {
    it = &entries_.insert_or_assign(id, Entry{hosted_index(id), now_ns, seq, snap, before.value_or(snap)});
  } else {
    Entry& e = *it;
    if (seq <= e.seq) return;  // duplicate or reordered: keep the newest
    lost = seq - e.seq - 1;
    if (before) e.prev = *before;
    else if (snap.command != e.cur.command || snap.model_time != e.cur.model_time) e.prev = e.cur;
    e.cur = snap;
    e.seq = seq;
    e.last_seen_ns = now_ns;
  }
  ++total_.received;
  total_.lost += lost;
  if (it->hosted >= 0) {
    ++own_[static_cast<std::size_t>(it->hosted)].received;
    own_[static_cast<std::size_t>(it->hosted)].lost += lost;
  }
}

void NeighbourTable::on_gone(std::int32_t id) {
  const auto e = entries_.find(id);
  if (e == entries_.end()) return;
  ++total_.departed;
  if (e->second.hosted >= 0) ++own_[static_cast<std::size_t>(e->second.hosted)].departed;
  entries_.erase(id);
}

void NeighbourTable::drop_stale(std::int64_t now_ns, bool commanded) {
  if (now_ns == dropped_at_ns_) return;
  dropped_at_ns_ = now_ns;
  const std::int64_t timeout = commanded ? timeout_ns_ : idle_timeout_ns_;
  entries_.erase_if([&](const auto& p) {
    const Entry& e = p.second;
    if (now_ns - e.last_seen_ns <= timeout) return false;
    ++total_.stale;
    if (e.hosted >= 0) ++own_[static_cast<std::size_t>(e.hosted)].stale;
    return true;
  });
}

int NeighbourTable::heard_by(std::int32_t id) const {
  return static_cast<int>(entries_.size()) - (entries_.contains(id) ? 1 : 0);
}

AgentCounters NeighbourTable::counters_for(std::int32_t id) const {
  const int k = hosted_index(id);
  const Counts own = k >= 0 ? own_[static_cast<std::size_t>(k)] : Counts{};
  AgentCounters c;
  c.samples_received = total_.received - own.received;
  c.samples_lost = total_.lost - own.lost;
  c.stale_dropped = total_.stale - own.stale;
  c.departed = total_.departed - own.departed;
  return c;
}

AgentLogic::AgentLogic(std::int32_t id, core::Vec2 start, std::int64_t timeout_ns, bool lockstep,
                       int max_wait_ticks, std::int64_t idle_timeout_ns)
    : AgentLogic(id, start,
                 std::make_shared<NeighbourTable>(std::vector<std::int32_t>{id}, timeout_ns, idle_timeout_ns), lockstep,
                 max_wait_ticks) {}

AgentLogic::AgentLogic(std::int32_t id, core::Vec2 start, std::shared_ptr<NeighbourTable> table, bool lockstep,
                       int max_wait_ticks)
    : id_(id),
      x_(start),
      vehicle_state_(core::vehicle_start(start, 0.0)),
      x_prev_(start),
      lockstep_(lockstep),
      max_wait_ticks_(max_wait_ticks),
      table_(std::move(table)) {}

void AgentLogic::set_vehicle(const core::VehicleParams& p, double heading) {
  vehicle_ = p;
  safety_params_ = core::safety_params(cmd_, vehicle_);
  vehicle_state_ = core::vehicle_start(x_, heading);
}

void AgentLogic::set_external_vehicle(const core::VehicleParams& p, ExternalVehicle ext) {
  vehicle_ = p;
  safety_params_ = core::safety_params(cmd_, vehicle_);
  external_ = std::move(ext);
}

AgentLogic::PoseVerdict AgentLogic::on_pose(const core::Vec2& base, double yaw, const std::string& frame,
                                            std::int64_t now_ns, std::string& why) {
  if (frame != external_->frame) {
    ++poses_refused_;
    why = "pose in frame '" + frame + "', not the swarm's '" + external_->frame +
          "' (vehicle.frame): localise every robot in one frame";
    return PoseVerdict::WrongFrame;
  }
  const core::Vec2 point = core::controlled_point(vehicle_, base, yaw);
  if (has_pose()) {
    const double elapsed_s = static_cast<double>(now_ns - pose_ns_) * 1e-9;
    const double reach = vehicle_.max_speed * std::max(elapsed_s, 0.0) + external_->pose_jump_m;
    const double moved = (point - vehicle_state_.x).norm();
    if (moved > reach) {
      ++poses_refused_;
      char text[200];
      std::snprintf(text, sizeof text,
                    "pose jumped %.3g m in %.3g s, more than the vehicle can move (max_speed x elapsed + "
                    "vehicle.pose_jump_m = %.3g m)",
                    moved, elapsed_s, reach);
      why = text;
      return PoseVerdict::Jump;
    }
  }
  vehicle_state_.x = point;
  vehicle_state_.heading = yaw;
  x_ = point;
  pose_ns_ = now_ns;
  return PoseVerdict::Accepted;
}

void AgentLogic::stop_vehicle() {
  command_ = {};
  vehicle_state_.velocity = core::Vec2::Zero();
  v_ = core::Vec2::Zero();
}

void AgentLogic::skip(std::uint64_t periods) {
  if (periods == 0 || lockstep_ || !has_command() || cmd_.hold) return;
  const double by = static_cast<double>(periods) * cmd_.dt;
  t_ += by;
  target_age_ += by;
}

AgentCounters AgentLogic::counters() const {
  AgentCounters c = table_->counters_for(id_);
  c.samples_rejected = rejected_;
  c.steps_clamped = clamped_;
  return c;
}

dds::CommandArbiter::Verdict AgentLogic::on_command(const dds::CommandSample& c) {
  const auto v = arbiter_.offer(c, peer_floor());
  if (v == dds::CommandArbiter::Verdict::Refused) ++rejected_;
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
  for (const auto& [id, e] : table_->entries())
    if (id != id_ && !e.cur.command.none() && (floor == 0 || e.cur.command.epoch < floor)) floor = e.cur.command.epoch;
  return floor;
}

void AgentLogic::adopt() {
  const dds::CommandId command = arbiter_.id();
  cmd_ = arbiter_.current().command;
  t_ = 0.0;
  waited_ = 0;
  x_prev_ = x_;
  arc_prev_.reset();
  safety_params_ = core::safety_params(cmd_, vehicle_);
  zones_ = core::convex_pieces(cmd_.keep_out);
  safety_state_ = {};
  safety_ = {};
  // Any new command releases a fence stop. An agent the new command's fence leaves outside breaches it
  // (its action taken); one already outside (the excursion goes on: the operator's resume or a new
  // shape after a breach) returns inside first.
  fence_ = FenceState::Inside;
  if (beyond_ && core::beyond_fence(cmd_, x_) > 0.0) fence_ = FenceState::Returning;
  else beyond_ = false;
  check_fence();
  if (lockstep_) {
    // A late joiner starts at the step the swarm is at, so nobody waits for its past.
    long k0 = 0;
    for (const auto& [id, e] : table_->entries())
      if (id != id_ && e.cur.command == command) k0 = std::max(k0, step_of(e.cur.model_time));
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
  table_->on_state(id, x, seq, now_ns, command, arc, model_time, prev_x, prev_arc, cmd_.dt);
}

void AgentLogic::drop_stale(std::int64_t now_ns) {
  now_ns_ = now_ns;
  table_->drop_stale(now_ns, has_command());
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
  // The command is copied only to follow a target (asked twice a tick per agent).
  const core::ShapeSpec s = following_target() ? core::shape_at(effective_command(), 0.0) : core::shape_at(cmd_, t_);
  return core::closest_point(s, cmd_.curve(), x_).s;
}

bool AgentLogic::step() {
  if (has_command()) check_fence();
  if (!has_command() || cmd_.hold) {
    // Before any command, and while held: stay put, and model time (with the tracked centre and
    // the lockstep step count) stands still.
    v_ = core::Vec2::Zero();
    core::stop(vehicle_state_);
    command_ = {};
    return false;
  }
  if (fence_ == FenceState::Stopped) {
    // Stopped by a breach (stop, or hold until the supervisor holds everyone): still, its clock going
    // on with the others' (skip()).
    v_ = core::Vec2::Zero();
    core::stop(vehicle_state_);
    command_ = {};
    skip(1);
    return false;
  }
  if (fence_ == FenceState::Returning) {
    take_step(return_step());
    if (returned()) fence_ = FenceState::Inside;
    return true;
  }
  const bool arc_law = cmd_.law == core::Law::Arc;
  const dds::CommandId followed = arbiter_.id();
  const long k = step_of(t_);
  const bool follow_target = following_target();
  const core::CompiledCommand local = follow_target ? effective_command() : cmd_;
  const double t_local = follow_target ? 0.0 : t_;
  CentreFrame frame = centre_frame(local, t_local);
  frame.by_target = follow_target;
  nbrs_.clear();
  bool ready = true;
  for (const auto& [id, e] : table_->entries()) {
    if (id == id_) continue;  // never itself
    // Lockstep: the neighbour's state of step k (the newest, or the one before if it is already
    // ahead); free running: the newest.
    const Snapshot* use = &e.cur;
    if (lockstep_) {
      const long cur = step_of(e.cur.model_time);
      if (e.cur.command != followed || cur < k) ready = false;
      else if (cur > k && e.prev.command == followed && step_of(e.prev.model_time) == k) use = &e.prev;
    }
    core::Neighbour n{id, seen_now(frame, *use, e.last_seen_ns, followed)};
    if (arc_law && use->command == followed && use->arc) n.s = *use->arc;
    nbrs_.push_back(n);
  }
  if (lockstep_ && !ready) {
    // Hold until every neighbour has published step k; past the bound, go on without the laggard
    // (free running) until it catches up.
    if (++waited_ <= max_wait_ticks_) {
      v_ = core::Vec2::Zero();
      command_ = {};
      return false;
    }
  } else {
    waited_ = 0;
  }
  // The table keeps ids ascending: a deterministic neighbour order, whatever the arrival order.
  take_step(core::agent_step(local, id_, x_, nbrs_, t_local));
  return true;
}

AgentLogic::CentreFrame AgentLogic::centre_frame(const core::CompiledCommand& local, double t) {
  const core::CentrePath& p = local.tracking.path;
  CentreFrame f;
  if (!local.tracking.enabled || !local.tracking.feedforward || p.kind == core::CentrePath::Kind::Fixed)
    return f;
  f.velocity = core::centre_velocity(p, t);
  f.moving = f.velocity != core::Vec2::Zero();
  return f;
}

core::Vec2 AgentLogic::seen_now(const CentreFrame& f, const Snapshot& s, std::int64_t seen_ns,
                                const dds::CommandId& followed) const {
  if (!f.moving || s.command != followed) return s.x;
  if (f.by_target) {
    // Every agent steps against the newest target's centre: the supervisor's ticks are the frames (the
    // supervisor measures at them too), and a state's frame is set by the targets since it was taken.
    const auto period_ns = std::max<std::int64_t>(std::llround(period_s_ * 1e9), 1);
    const double steps = centre_frame_steps(seen_ns, target_seen_ns_, target_age_ / cmd_.dt, period_ns);
    return s.x + (steps * cmd_.dt) * f.velocity;
  }
  // With feed-forward every agent's step carries the centre's motion dC/dt dt, so a state `behind`
  // steps older than this agent's is that much of the centre's motion behind (ahead when negative):
  // the static problem in the centre's frame needs it where it would be now.
  const long behind = step_of(t_) - step_of(s.model_time);
  if (behind == 0 || std::labs(behind) > kMaxCentreFrameSteps) return s.x;
  return s.x + (static_cast<double>(behind) * cmd_.dt) * f.velocity;
}

core::StepResult AgentLogic::filtered(const core::StepResult& r, std::optional<core::SafetyOutcome>& f) {
  if (!core::filters(cmd_)) return r;
  const dds::CommandId followed = arbiter_.id();
  const long k = step_of(t_);
  // A neighbour may have moved max_step per step since its state: lockstep states of this very step are
  // exact (age 0, the simulator's synchronous update); any other is as old as the time since it was
  // received, in periods, plus the step the neighbour may take while this agent steps.
  double max_speed = safety_params_.max_step / cmd_.dt;
  // Double integrators keep braking segments apart (core/safety.hpp). A neighbour's velocity is known
  // as the mean of its last step ((x - prev x) / dt), within max_accel h / 2 of its true one, so its
  // speed is at most that much above the mean's and its segment is blurred by that much times
  // braking_lipschitz at that speed; over its age the segment's ends move at most braking_reach from
  // that speed (at most 2 vmax + max_accel h / 2 per step from full speed, far less from a slow one: agents
  // held near each other are slow, and a bound of full speed would leave them no room). One whose
  // velocity is not known is a disc of the longest braking distance, its ends moving at full speed.
  const bool braking = safety_params_.braking;
  const double h = cmd_.dt * vehicle_.seconds_per_model_time;
  const double accel = vehicle_.max_accel;
  const double vmax = vehicle_.max_speed > 0.0 ? vehicle_.max_speed : std::numeric_limits<double>::infinity();
  const double unsure = accel > 0.0 ? std::min(0.5 * accel * h, vmax) : vmax;  // |true - mean velocity|
  double unknown = 0.0;
  if (braking) {
    max_speed = core::braking_reach(vmax, 1.0, vmax, accel, h) / cmd_.dt;  // per step from full speed
    unknown = core::braking_distance(vmax, accel, h);
  }
  const auto age = [&](std::int64_t seen_ns) {
    return (static_cast<double>(std::max<std::int64_t>(now_ns_ - seen_ns, 0)) * 1e-9 / period_s_ + 1.0) * cmd_.dt;
  };
  // A state that spent long on the way (a transport slower than a period: an overloaded host) is older
  // than its reception says. Agents on one command step once per tick from about the same moment, so
  // how far the state's model time is behind this agent's own counts its steps since, with no common
  // clock; a gap past kMaxLagSteps is clocks that started apart (a late joiner), not age.
  const auto lag = [&](const Snapshot& snap) {
    if (snap.command != followed) return 0.0;
    const double behind = (t_ - snap.model_time) / cmd_.dt + 1.0;
    return behind <= kMaxLagSteps ? behind * cmd_.dt : 0.0;
  };
  // A neighbour known at the last step but no longer in the table: kept while its silence is short.
  const auto silent = [&](const Known& g) {
    if (now_ns_ - g.seen_ns > kSilentMemory_ns) return;
    snbrs_.push_back({g.id, g.x, age(g.seen_ns), max_speed, core::Vec2::Zero(), unknown});
    known_next_.push_back(g);
  };
  snbrs_.clear();
  known_next_.clear();
  auto g = known_.begin();
  for (const auto& [id, e] : table_->entries()) {
    for (; g != known_.end() && g->id < id; ++g) silent(*g);
    if (g != known_.end() && g->id == id) ++g;
    if (id == id_) continue;
    const Snapshot* use = &e.cur;
    if (lockstep_ && e.cur.command == followed && step_of(e.cur.model_time) > k && e.prev.command == followed)
      use = &e.prev;
    const bool exact = lockstep_ && use->command == followed && step_of(use->model_time) == k;
    core::SafetyNeighbour& j =
        snbrs_.emplace_back(core::SafetyNeighbour{id, use->x, exact ? 0.0 : std::max(age(e.last_seen_ns), lag(*use)), max_speed});
    if (braking) {
      const bool step_before = use == &e.cur && e.prev.command == use->command &&
                               std::abs(use->model_time - cmd_.dt - e.prev.model_time) <= 1e-9 * (1.0 + std::abs(use->model_time));
      j.brake = core::Vec2::Zero();
      j.blur = unknown;
      if (step_before) {
        const core::Vec2 mean = (use->x - e.prev.x) / h;
        const double speed = std::min(vmax, mean.norm() + unsure);
        j.brake = core::braking_displacement(mean, accel, h);
        j.blur = core::braking_lipschitz(speed, accel, h) * unsure;
        // The margin is max_speed * age: the mean speed of the segment's ends over the age.
        if (j.age_s > 0.0) j.max_speed = core::braking_reach(speed, j.age_s / cmd_.dt, vmax, accel, h) / j.age_s;
      }
    }
    known_next_.push_back({id, e.cur.x, e.last_seen_ns});
  }
  for (; g != known_.end(); ++g) silent(*g);
  known_.swap(known_next_);
  f = core::safety_filter(safety_params_, safety_state_, id_, x_, r.x, snbrs_, zones_,
                          braking ? core::braking_displacement(vehicle_state_.velocity, accel, h) : core::Vec2::Zero());
  safety_.interventions += f->intervened ? 1 : 0;
  safety_.sidesteps += f->sidestep_started ? 1 : 0;
  safety_.broken += static_cast<std::uint64_t>(f->broken);
  safety_.blocked = f->held || f->sidestep;
  safety_.blocked_by = !safety_.blocked          ? -1
                       : f->blocking_id >= 0     ? f->blocking_id
                       : f->blocking_zone >= 0   ? -2 - f->blocking_zone
                                                 : -1;
  return {f->x, (f->x - x_) / cmd_.dt, r.clamped};
}

void AgentLogic::check_fence() {
  const double out = core::beyond_fence(cmd_, x_);
  if (out > 0.0 && !beyond_) {
    ++safety_.fence_breaches;
    breach_depth_ = out;
    if (fence_ == FenceState::Inside)
      fence_ = cmd_.breach_action == core::BreachAction::Return ? FenceState::Returning : FenceState::Stopped;
  }
  beyond_ = out > 0.0;
  // Returned: at least fence_margin inside again (or as deep as the fence allows).
  if (fence_ == FenceState::Returning && returned()) fence_ = FenceState::Inside;
}

bool AgentLogic::returned() const { return (core::fence_return_point(cmd_, x_) - x_).norm() <= 1e-9; }

core::StepResult AgentLogic::return_step() const {
  const core::Vec2 to = core::fence_return_point(cmd_, x_);
  core::Vec2 step = to - x_;
  const double longest = safety_params_.max_step;
  if (longest > 0.0 && step.norm() > longest) step *= longest / step.norm();
  return {x_ + step, step / cmd_.dt, false};
}

void AgentLogic::book_gap() {
  double gap = -1.0;
  for (const auto& [id, e] : table_->entries())
    if (id != id_) {
      const double g = (e.cur.x - x_).norm();
      if (gap < 0.0 || g < gap) gap = g;
    }
  book_gap(gap);
}

void AgentLogic::book_gap(double gap) {
  if (gap >= 0.0 && (safety_.min_gap < 0.0 || gap < safety_.min_gap)) {
    safety_.min_gap = gap;
    safety_.min_gap_time = t_;
  }
}

void AgentLogic::book_gaps(const std::vector<AgentLogic*>& agents) {
  // Every agent against every state heard, on a grid (core::nearest_squared): the smallest squared
  // distance, bit for bit that of comparing every pair, and its square root the smallest norm (the square
  // root is monotone).
  thread_local std::vector<core::Vec2> heard, hosted;
  thread_local std::vector<std::int32_t> heard_ids, hosted_ids;
  heard.clear(), heard_ids.clear(), hosted.clear(), hosted_ids.clear();
  for (const auto& [id, e] : agents.front()->table_->entries()) {
    heard.push_back(e.cur.x);
    heard_ids.push_back(id);
  }
  for (const AgentLogic* a : agents) {
    hosted.push_back(a->x_);
    hosted_ids.push_back(a->id_);
  }
  const std::vector<double> best = core::nearest_squared(heard, heard_ids, hosted, hosted_ids);
  for (std::size_t k = 0; k < agents.size(); ++k) {
    AgentLogic& a = *agents[k];
    // Any entry but its own: a gap (infinite only if every distance overflows, as the norms would).
    const bool any = a.table_->heard_by(a.id_) > 0;
    a.book_gap(any ? std::sqrt(best[k]) : -1.0);
  }
}

void AgentLogic::take_step(const core::StepResult& law, bool gap) {
  std::optional<core::SafetyOutcome> f;
  const core::StepResult safe = filtered(law, f);
  if (external_) {
    // A robot outside: command it toward the (filtered) law's new position; it moves by itself, and the
    // next pose says where it got to.
    command_ = core::vehicle_command(vehicle_, vehicle_state_, safe.x, cmd_.dt, external_->period_s);
    if (command_.saturated) ++saturated_;
    if (law.clamped) ++clamped_;
    vehicle_state_.velocity = command_.world;
    arc_prev_ = cmd_.law == core::Law::Arc ? arc() : std::nullopt;
    x_prev_ = x_;
    v_ = command_.world * vehicle_.seconds_per_model_time;  // shape units per model time, as published
    t_ += cmd_.dt;
    target_age_ += cmd_.dt;
    return;
  }
  // The integrator without a speed limit returns the law's step bit for bit.
  bool outside = false;
  const core::StepResult r = f ? core::drive_safely(vehicle_, vehicle_state_, law, *f, cmd_.dt, cmd_.workspace, outside)
                               : core::drive(vehicle_, vehicle_state_, law, cmd_.dt, cmd_.workspace);
  if (r.clamped) ++clamped_;
  arc_prev_ = cmd_.law == core::Law::Arc ? arc() : std::nullopt;
  x_prev_ = x_;
  x_ = r.x;
  v_ = r.v;
  t_ += cmd_.dt;
  target_age_ += cmd_.dt;
  if (gap) book_gap();
}

bool AgentLogic::shares_step_with(const AgentLogic& first) const {
  // Filtered steps, and an agent dealing with a fence breach, are each taken on their own.
  if (!has_command() || lockstep_ || first.lockstep_ || !core::shares_steps(cmd_) || table_ != first.table_ ||
      core::filters(cmd_) || fence_ != FenceState::Inside)
    return false;
  if (command_id() != first.command_id() || t_ != first.t_ || following_target() != first.following_target())
    return false;
  if (!following_target()) return true;
  const TargetSample& a = *target_;
  const TargetSample& b = *first.target_;
  return a.command == b.command && a.model_time == b.model_time && a.centre == b.centre && a.velocity == b.velocity &&
         target_age_ == first.target_age_;
}

void AgentLogic::step_shared(const std::vector<AgentLogic*>& agents) {
  const AgentLogic& first = *agents.front();
  const dds::CommandId followed = first.command_id();
  thread_local std::vector<core::Neighbour> hosted, others;
  thread_local std::vector<core::StepResult> steps;
  hosted.clear();
  others.clear();
  for (const AgentLogic* a : agents) hosted.push_back({a->id_, a->x_});
  const bool follow_target = first.following_target();
  const core::CompiledCommand local = follow_target ? first.effective_command() : first.cmd_;
  const double t_local = follow_target ? 0.0 : first.t_;
  CentreFrame frame = centre_frame(local, t_local);
  frame.by_target = follow_target;
  // The agents hosted here are taken as they are now (hosted), the others as last heard (moved into
  // the hosted agents' model time as step() moves them).
  for (const auto& [id, e] : first.table_->entries()) {
    if (e.hosted >= 0) continue;
    core::Neighbour n{id, first.seen_now(frame, e.cur, e.last_seen_ns, followed)};
    if (e.cur.command == followed && e.cur.arc) n.s = *e.cur.arc;
    others.push_back(n);
  }
  core::agent_steps(local, hosted, others, t_local, steps);
  // A breach found now is dealt with from the next tick on (shares_step_with is false then).
  for (AgentLogic* a : agents) a->check_fence();
  for (std::size_t k = 0; k < agents.size(); ++k) agents[k]->take_step(steps[k], false);
  book_gaps(agents);
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
