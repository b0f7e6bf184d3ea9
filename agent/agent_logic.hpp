#pragma once
/// The agent's behaviour without DDS or clocks: a latest-per-agent neighbour table (shared by the
/// agents one process hosts), the command and tracking target in force, and one core::agent_step per
/// tick (one core::agent_steps for the hosted agents together when they can share it), whose step the
/// agent's vehicle then drives (core::drive).
/// agent_node.cpp only wires DDS to it.
#include <algorithm>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/compiled_command.hpp"
#include "core/law.hpp"
#include "core/safety.hpp"
#include "core/vehicle.hpp"
#include "protocol/command_arbiter.hpp"
#include "protocol/samples.hpp"
#include "util/id_map.hpp"

namespace shapeform::agent {

/// Largest agent id (ids are 0..kMaxAgentId, unique in the swarm; received samples are held to it).
inline constexpr int kMaxAgentId = dds::kMaxAgentId;

/// The latest tracking target heard: the centre C and its velocity at the supervisor's model time.
using TargetSample = dds::TargetSample;

/// One agent's counters. The first four are counted once per received sample by the process's
/// NeighbourTable; an agent's figure is the process's count less what concerns the agent itself,
/// which is what a table of its own (every sample but its own) would have counted.
struct AgentCounters {
  std::uint64_t samples_received = 0;  ///< neighbour states accepted
  std::uint64_t samples_lost = 0;      ///< gaps in neighbours' sequence numbers
  std::uint64_t stale_dropped = 0;     ///< neighbours dropped for silence
  std::uint64_t departed = 0;          ///< neighbours dropped because they left (disposed)
  std::uint64_t samples_rejected = 0;  ///< states, commands or targets refused by validation
  std::uint64_t steps_clamped = 0;     ///< steps the law would have taken out of the workspace (or not finite)
};

/// What the safety filter (core::safety_filter, docs/SAFETY.md) did for one agent since the command it
/// follows was adopted; all zero while the command does not filter (core::filters).
struct SafetyFigures {
  std::uint64_t interventions = 0;  ///< steps whose position the filter moved
  std::uint64_t sidesteps = 0;      ///< deadlock sidesteps begun
  std::uint64_t broken = 0;         ///< (step, neighbour) pairs found closer than safety.min_separation
  /// The smallest distance from this agent, after a step, to a neighbour as last heard (-1: none yet),
  /// and the model time of that step. Measured whether or not the command filters.
  double min_gap = -1.0;
  double min_gap_time = 0.0;
  bool blocked = false;          ///< held or sidestepping on the last step (not where the law sends it)
  std::int64_t blocked_by = -1;  ///< what held it: a neighbour id (>= 0), keep-out zone k as -2 - k, -1 none
  std::uint64_t fence_breaches = 0;  ///< excursions beyond the fence (core::beyond_fence > 0) begun
};

/// Where the agent stands against the fence (safety.fence, core/fence.hpp).
enum class FenceState {
  Inside,     ///< inside the fence (or on it)
  Returning,  ///< heading back to core::fence_return_point (breach_action return, or a new command)
  Stopped     ///< breach_action stop or hold: standing still until the next command
};

/// The latest states heard by one process, shared by the agents it hosts: one entry per agent id
/// (hosted agents included: their own samples come back to the process, and co-hosted agents hear
/// each other there), each updated once per received sample. Each hosted agent reads it without its
/// own entry. Entries are kept in ascending id order, so a step needs no sort.
class NeighbourTable {
 public:
  struct Snapshot {
    core::Vec2 x;
    dds::CommandId command;
    double model_time;  ///< the sender's model time after its step (step tag = model_time / dt)
    std::optional<double> arc;
  };
  struct Entry {
    int hosted;  ///< index of the hosted agent with this id, -1 for an agent hosted elsewhere
    std::int64_t last_seen_ns;
    std::uint64_t seq;
    Snapshot cur, prev;  ///< the newest state and the one before (lockstep needs step k after k+1)
  };

  /// hosted: the ids of the process's agents; timeout_ns: an agent unheard for longer is dropped;
  /// idle_timeout_ns: the same before the hosted agents' first command (0: timeout_ns).
  NeighbourTable(std::vector<std::int32_t> hosted, std::int64_t timeout_ns, std::int64_t idle_timeout_ns = 0);

  /// A valid state received at now_ns (see AgentLogic::on_state); dt: the step of the command the
  /// receivers follow (the sender's previous state is tagged model_time - dt). A negative id (never
  /// valid) is ignored.
  void on_state(std::int32_t id, const core::Vec2& x, std::uint64_t seq, std::int64_t now_ns, dds::CommandId command,
                std::optional<double> arc, double model_time, std::optional<core::Vec2> prev_x,
                std::optional<double> prev_arc, double dt);
  /// Agent id left (its instance was disposed or lost its writer): dropped now.
  void on_gone(std::int32_t id);
  /// Drops the agents unheard since now_ns - timeout (the idle timeout while not `commanded`; once per
  /// now_ns: the hosted agents each call it).
  void drop_stale(std::int64_t now_ns, bool commanded = true);

  /// Every agent heard, ascending ids: pairs of id and entry.
  const util::IdMap<Entry>& entries() const { return entries_; }
  /// Agents heard by hosted agent `id` (every entry but its own).
  int heard_by(std::int32_t id) const;
  /// The table's counters as hosted agent `id` counts them (samples_rejected, steps_clamped: 0).
  AgentCounters counters_for(std::int32_t id) const;
  /// The index of hosted agent id, -1 if it is not hosted here.
  int hosted_index(std::int32_t id) const;

 private:
  struct Counts {
    std::uint64_t received = 0, lost = 0, stale = 0, departed = 0;
  };
  std::vector<std::int32_t> hosted_;
  /// index_of_[id]: the index of hosted agent id, -1 for the others (sized to the largest hosted id):
  /// hosted_index() is asked once per received sample.
  std::vector<int> index_of_;
  std::int64_t timeout_ns_;
  std::int64_t idle_timeout_ns_;
  std::int64_t dropped_at_ns_ = -1;  ///< the last drop_stale's now_ns
  /// Found by id in one look-up per received sample.
  util::IdMap<Entry> entries_;
  Counts total_;            ///< the process's counts, every agent's samples
  std::vector<Counts> own_; ///< per hosted agent: the part that is its own samples
};

class AgentLogic {
 public:
  /// timeout_ns: a neighbour unheard for longer is dropped (neighbour_timeout periods); before this
  /// agent's first command idle_timeout_ns instead (the same periods of agent.idle_rate_hz: its
  /// neighbours publish slowly until they are commanded too; 0: timeout_ns).
  /// lockstep: see step(); max_wait_ticks bounds how long a lockstep agent waits for a neighbour that
  /// is alive but does not advance (e.g. it refused the command), after which it steps without it.
  /// The agent has a table of its own.
  AgentLogic(std::int32_t id, core::Vec2 start, std::int64_t timeout_ns, bool lockstep = false,
             int max_wait_ticks = 50, std::int64_t idle_timeout_ns = 0);
  /// An agent of a process that shares `table` (which hosts `id`) between its agents.
  AgentLogic(std::int32_t id, core::Vec2 start, std::shared_ptr<NeighbourTable> table, bool lockstep = false,
             int max_wait_ticks = 50);

  /// A received command, judged by dds::CommandArbiter (commands ordered by epoch then issuer; an
  /// absurd epoch jump refused and counted); before its first command this agent judges jumps from the
  /// lowest epoch its neighbours follow. When adopted, model time restarts.
  dds::CommandArbiter::Verdict on_command(const dds::CommandSample& c);
  /// Re-judges the commands refused as absurd jumps against the neighbours heard now (an agent that
  /// joined a swarm whose epoch is far above 0 adopts its command once it hears it); true if it adopted.
  bool recheck_commands();
  /// Keeps the newest target of the followed command, received at now_ns.
  void on_target(const TargetSample& t, std::int64_t now_ns);
  /// A valid neighbour state received at now_ns, into the table (a shared table takes each sample
  /// once: call it on one of its agents, or on the table). Own samples are kept apart: this agent
  /// never hears itself. command and arc: the command
  /// the neighbour follows and its arc length along that command's shape (used by the arc law only
  /// when the command is the one this agent follows).
  /// model_time: the neighbour's model time after its last step (its step tag, for lockstep).
  /// prev_x / prev_arc: the sender's state one step earlier (carried in every sample so that a lost
  /// sample does not break lockstep).
  void on_state(std::int32_t id, const core::Vec2& x, std::uint64_t seq, std::int64_t now_ns,
                dds::CommandId command = {}, std::optional<double> arc = std::nullopt, double model_time = 0.0,
                std::optional<core::Vec2> prev_x = std::nullopt, std::optional<double> prev_arc = std::nullopt);
  /// The neighbour left (its instance was disposed or lost its writer): drop it now.
  void on_gone(std::int32_t id) { table_->on_gone(id); }
  void count_rejected() { ++rejected_; }

  /// Drops neighbours unheard since now_ns - timeout, and a tracking target unheard for
  /// kTargetTimeout_ns; now_ns is also the tick's time for the next step (how old the neighbours'
  /// states are, for the safety filter) (the supervisor is gone): the centre then follows the command's own path on the
  /// agent's model clock instead of flying off along the last target's velocity.
  void drop_stale(std::int64_t now_ns);
  static constexpr std::int64_t kTargetTimeout_ns = 1'000'000'000;
  /// Whether a tracking target from the supervisor is in use (false: none yet, lost, or lockstep).
  bool following_target() const { return cmd_.tracking.enabled && target_ && !lockstep_; }
  /// One control step: the law for the command and target in force, integrated over cmd.dt, and the
  /// vehicle driven by that step. Before the first command, and while the command is held
  /// (Command::hold), the agent keeps its position with velocity 0 (its vehicle stopped) and its model
  /// time does not advance; returns false.
  /// Lockstep (agent.sync: lockstep): step k -> k+1 is taken only once every neighbour has published
  /// its state of step k for the same command, and uses exactly those states; the tracked centre is
  /// then the command's path at the agent's own model time. This is the simulator's synchronous
  /// update, so processes and simulator compute the same numbers. Returns whether it stepped.
  /// Tracking a moving centre with feed-forward, a neighbour's state of another frame (free running:
  /// one that already stepped in this period, or one not heard since its last step) is seen where it
  /// would be in this agent's: moved with the centre by dC/dt per step. Following the supervisor's
  /// target, by the targets that arrived since the state was taken (centre_frame_steps); on the
  /// command's own path, by the steps between model times, at most kMaxCentreFrameSteps (see
  /// centre_frame()). In lockstep every state used is of the agent's own step, so nothing moves.
  bool step();
  /// Neighbour states more steps than this from the agent's own are taken as heard, not moved with the
  /// centre: the difference is then not the age of a state (free running, a state is at most one step
  /// old) but clocks that started apart (a late joiner counts its model time from its own adoption).
  static constexpr long kMaxCentreFrameSteps = 1;
  /// Following the supervisor's target: by how many steps of the centre's motion a neighbour state
  /// received at state_ns is behind this agent's step, which uses the target received at target_ns
  /// moved on by target_age_steps of its own steps (0 while a target comes every period). The state
  /// came out of the neighbour's step against the newest target then, feed-forward included, so it is
  /// one step ahead of that target's centre: -1 when it was taken after this agent's target arrived
  /// (both stepped against the same one), and one more per target period before (period_ns; the
  /// supervisor's loop runs at the agents' rate by default), plus this agent's own steps since. Pure.
  static double centre_frame_steps(std::int64_t state_ns, std::int64_t target_ns, double target_age_steps,
                                   std::int64_t period_ns) {
    const std::int64_t arrivals = state_ns < target_ns ? (target_ns - state_ns) / period_ns + 1 : 0;
    return target_age_steps + static_cast<double>(arrivals) - 1.0;
  }

  /// Whether this agent's step may be taken together with `first`'s in one core::agent_steps: both
  /// free running, on the same command (core::shares_steps) at the same model time with the same
  /// tracking target, so both see one shape.
  bool shares_step_with(const AgentLogic& first) const;
  /// Steps agents that all share_step_with(*agents.front()) together: one sorted arc list and offset
  /// for all (the heard agents not hosted here plus the hosted ones at their positions now), then each
  /// agent's own step, as step() would book it. agents: the process's hosted agents, one table.
  static void step_shared(const std::vector<AgentLogic*>& agents);

  /// How long the safety filter keeps a neighbour that fell silent (lost samples past the neighbour
  /// timeout, a stalled or killed process, a robot without poses) as an obstacle at its last position,
  /// its margin growing with the silence: the law forgets it at once, the filter not.
  static constexpr std::int64_t kSilentMemory_ns = 1'000'000'000;
  /// A neighbour state whose model time is up to this many steps behind the agent's own is taken to be
  /// that old (the transport may take longer than a period); further behind, its clock started apart.
  static constexpr double kMaxLagSteps = 40.0;
  /// The loop period, s: the safety filter takes a neighbour state received a seconds ago as
  /// a / period_s + 1 of its steps old (the steps it may have taken since, and one more while this agent
  /// steps), or as many steps as its model time is behind this agent's when that is more (up to
  /// kMaxLagSteps), each at most the command's and the vehicle's speed bound (core::safety_params).
  void set_period(double period_s) { period_s_ = period_s; }
  const SafetyFigures& safety() const { return safety_; }
  /// Whether the agent is beyond the fence now (at its last step or check), and what it does about it.
  bool beyond_fence() const { return beyond_; }
  FenceState fence_state() const { return fence_; }
  /// The breach the last step found (the agent just went beyond the fence), cleared by reading it:
  /// how far beyond, shape units (0: none).
  double take_breach() { return std::exchange(breach_depth_, 0.0); }

  /// The vehicle this agent drives (the robot's own: agent config), from its start position with this
  /// heading (rad). Call before the first step; without it the agent moves as the law steps it.
  void set_vehicle(const core::VehicleParams& p, double heading);
  const core::VehicleState& vehicle() const { return vehicle_state_; }

  /// A robot outside the process (vehicle.interface ros2): how the agent judges its poses.
  struct ExternalVehicle {
    std::string frame = "map";                   ///< the swarm's frame: a pose in another is refused
    std::int64_t pose_timeout_ns = 500'000'000;  ///< an older pose stops the vehicle (pose_fresh)
    double pose_jump_m = 0.5;  ///< a pose may be max_speed x elapsed + this from the last accepted one
    double period_s = 0.02;    ///< the agent's loop period: how long a command is held
  };
  /// Drives a robot it does not simulate: its position and heading come from on_pose (the agent has
  /// none before the first), and step() computes the velocity command for it (vehicle_command())
  /// instead of moving anything. Call before the first step.
  void set_external_vehicle(const core::VehicleParams& p, ExternalVehicle ext);
  bool external() const { return external_.has_value(); }
  enum class PoseVerdict {
    Accepted,
    WrongFrame,  ///< not in the swarm's frame
    Jump         ///< further from the last accepted pose than the vehicle could move
  };
  /// A valid pose (the robot's base and yaw, in `frame`) received at now_ns. Accepted: the agent is
  /// where it says (its controlled point, core::controlled_point). Refused: `why` says why, the pose is
  /// counted (poses_refused) and not used.
  PoseVerdict on_pose(const core::Vec2& base, double yaw, const std::string& frame, std::int64_t now_ns,
                      std::string& why);
  bool has_pose() const { return pose_ns_ >= 0; }
  /// Whether the newest accepted pose is at most pose_timeout old.
  bool pose_fresh(std::int64_t now_ns) const { return has_pose() && now_ns - pose_ns_ <= external_->pose_timeout_ns; }
  /// When the newest accepted pose was received (-1: none).
  std::int64_t pose_received_ns() const { return pose_ns_; }
  /// The command for the external vehicle now: the last step's, zero before any command, while held,
  /// and after stop_vehicle().
  const core::VehicleCommand& vehicle_command() const { return command_; }
  /// The pose is lost (or the agent stops): command zero, no step (model time moves on by skip()).
  void stop_vehicle();
  /// `periods` of the command's clock passed without a step of this agent: its loop skipped them (a
  /// busy host, a stall), or its robot had no fresh pose. Free running, its model time (and its
  /// tracked target's age) moves on by as many steps, its position not, so that its model time stays
  /// the periods since it adopted the command, as its neighbours' and the supervisor's are: a state
  /// whose model time is behind an agent's own is taken as that much older by the safety filter, so a
  /// neighbour whose clock had stood still would look old for the rest of the command and hold agents
  /// near it (so an agent stopped by the fence counts its periods too). In lockstep (steps are counted,
  /// not timed), before any command and while held, model time stands still, as in step().
  void skip(std::uint64_t periods);
  std::uint64_t poses_refused() const { return poses_refused_; }
  /// A pose refused before on_pose (its message was invalid): counted with the others.
  void count_refused_pose() { ++poses_refused_; }
  /// Commands a limit cut (the vehicle cannot follow the law).
  std::uint64_t commands_saturated() const { return saturated_; }

  std::int32_t id() const { return id_; }
  const core::Vec2& position() const { return x_; }
  const core::Vec2& velocity() const { return v_; }
  /// The command followed (epoch 0: none yet), and that command's sample (only when has_command()).
  dds::CommandId command_id() const { return arbiter_.id(); }
  const dds::CommandSample& command_sample() const { return arbiter_.current(); }
  double model_time() const { return t_; }
  bool has_command() const { return arbiter_.has_command(); }
  const core::CompiledCommand& command() const { return cmd_; }
  int neighbours() const { return table_->heard_by(id_); }
  AgentCounters counters() const;
  std::uint64_t steps_clamped() const { return clamped_; }
  /// The tracked centre this agent uses now (extrapolated from the last target), if tracking.
  std::optional<core::Vec2> tracked_centre() const;
  /// This agent's arc length along the shape in force (published so the others need not project it);
  /// nullopt before the first command.
  std::optional<double> arc() const;
  /// Position and arc length before the last step (equal to the current ones before any step).
  const core::Vec2& previous_position() const { return x_prev_; }
  const std::optional<double>& previous_arc() const { return arc_prev_; }

 private:
  using Snapshot = NeighbourTable::Snapshot;
  long step_of(double model_time) const { return std::lround(model_time / cmd_.dt); }
  /// The command actually integrated now: tracking follows the latest target from its last position.
  core::CompiledCommand effective_command() const;
  /// How a step at time t of the integrated command `local` sees neighbour states of other steps.
  struct CentreFrame {
    bool moving = false;  ///< feed-forward tracking of a moving centre: states of other steps move with it
    core::Vec2 velocity = core::Vec2::Zero();  ///< dC/dt at the step's time, the feed-forward it adds
    /// Following the supervisor's target: every agent steps against the centre of the newest target
    /// (moved on by its own steps since, when one is late), so the frames are the supervisor's ticks
    /// and a state is moved by the targets that arrived since it was taken (centre_frame_steps), not by
    /// the steps between model times.
    bool by_target = false;
  };
  static CentreFrame centre_frame(const core::CompiledCommand& local, double t);
  /// Neighbour state s (received at seen_ns) as this agent's step sees it, when f.moving and s is of
  /// the followed command: following the target (f.by_target), moved by centre_frame_steps steps of
  /// the centre; otherwise moved into this agent's model time when at most kMaxCentreFrameSteps steps
  /// (but not 0) from its step.
  core::Vec2 seen_now(const CentreFrame& f, const Snapshot& s, std::int64_t seen_ns,
                      const dds::CommandId& followed) const;
  /// Drives the vehicle by the law's step r and books the result (position, velocity, model time,
  /// counters).
  /// gap: book the smallest gap now (book_gap); step_shared books all its agents' at once instead.
  void take_step(const core::StepResult& r, bool gap = true);
  /// The law's step r through the safety filter (the neighbours as last heard, each with its age), or r
  /// itself when the command does not filter; books the filter's figures. f is set when it filtered.
  core::StepResult filtered(const core::StepResult& r, std::optional<core::SafetyOutcome>& f);
  /// Books the smallest distance from the new position to a neighbour as last heard.
  void book_gap();
  /// Books `gap` (the smallest distance to a neighbour as last heard; ignored when negative: none) as
  /// book_gap would.
  void book_gap(double gap);
  /// book_gap() of every agent of one table, found on a grid (the same figures, bit for bit).
  static void book_gaps(const std::vector<AgentLogic*>& agents);
  /// Checks the position against the fence before a step: a new excursion is a breach (counted, and
  /// breach_action taken); back inside, the excursion ends.
  void check_fence();
  /// A step of the return inside: toward core::fence_return_point, at most the speed limit's step.
  core::StepResult return_step() const;
  /// Back inside: at least fence_margin inside the fence (or as deep as the fence allows).
  bool returned() const;
  std::int32_t id_;
  core::Vec2 x_;  ///< the vehicle's controlled point (vehicle_state_.x)
  core::Vec2 v_ = core::Vec2::Zero();
  core::VehicleParams vehicle_;
  core::VehicleState vehicle_state_;
  core::Vec2 x_prev_;
  std::optional<double> arc_prev_;
  bool lockstep_;
  int max_wait_ticks_;
  int waited_ = 0;
  /// Makes the arbiter's command the one integrated.
  void adopt();
  /// The lowest non-zero epoch the neighbours follow (0: none), the floor of a fresh agent's judgement.
  std::uint64_t peer_floor() const;
  dds::CommandArbiter arbiter_;
  core::CompiledCommand cmd_;  ///< the arbiter's command (the default one before any)
  double t_ = 0.0;  ///< model time since the command was adopted
  std::optional<TargetSample> target_;
  double target_age_ = 0.0;  ///< model time since the target was received (one dt per step)
  std::int64_t target_seen_ns_ = 0;
  std::shared_ptr<NeighbourTable> table_;
  std::vector<core::Neighbour> nbrs_;  ///< reused every step
  std::uint64_t rejected_ = 0;         ///< AgentCounters::samples_rejected
  std::uint64_t clamped_ = 0;          ///< AgentCounters::steps_clamped
  std::optional<ExternalVehicle> external_;
  std::int64_t pose_ns_ = -1;           ///< when the newest accepted pose was received
  core::VehicleCommand command_;        ///< the external vehicle's command now
  std::uint64_t poses_refused_ = 0;
  std::uint64_t saturated_ = 0;
  double period_s_ = 0.05;
  std::int64_t now_ns_ = 0;                    ///< the tick's time (drop_stale)
  core::SafetyParams safety_params_;           ///< of the command in force and the vehicle
  std::vector<core::ConvexZone> zones_;        ///< the command's keep-out zones in convex pieces
  core::SafetyState safety_state_;
  std::vector<core::SafetyNeighbour> snbrs_;   ///< reused every step
  /// The neighbours the filter knew at its last step, id-sorted, kept while silent (dropped from the
  /// table for silence, or gone) for kSilentMemory_ns: still obstacles, their margins growing.
  struct Known {
    std::int32_t id;
    core::Vec2 x;
    std::int64_t seen_ns;
  };
  std::vector<Known> known_, known_next_;
  SafetyFigures safety_;
  bool beyond_ = false;
  FenceState fence_ = FenceState::Inside;
  double breach_depth_ = 0.0;
};

/// Whether this process may publish its agent ids when another participant publishes one of them (two
/// processes started with one --id). A process listens for a grace period before its first
/// publication: hearing one of its ids from another participant then, it is the newcomer and yields
/// (exits, never having published, so the incumbent is never displaced). Two processes that both got
/// past the grace (they started together, or one was unheard throughout the other's grace) resolve by
/// the participants' GUID prefixes, which both see alike: the higher one yields, the lower one keeps
/// the id. Pure: the caller passes every foreign sample of a hosted id and the clock.
class IdentityGuard {
 public:
  /// own: this process's identity (dds::Node::source, kept across participant rebuilds); grace_end_ns:
  /// the steady time its grace period ends.
  IdentityGuard(const dds::SourceId& own, std::int64_t grace_end_ns) : own_(own), grace_end_ns_(grace_end_ns) {}

  enum class Action {
    None,   ///< nothing new: this (id, participant) pair was handled already, or we are yielding
    Keep,   ///< a duplicate that must yield to us: report it, keep running
    Yield,  ///< we must give the id up: report it, stop without disposing, exit 2
  };
  /// A sample of hosted agent `id` from participant `other`. Samples from ourselves or from an unknown
  /// participant are not duplicates (None).
  Action on_sample(std::int32_t id, const dds::SourceId& other);
  /// Whether the grace period is over and we did not yield: the agents may step and publish.
  bool may_publish(std::int64_t now_ns) const { return !yielding_ && (published_ || now_ns >= grace_end_ns_); }
  void published() { published_ = true; }
  bool yielding() const { return yielding_; }
  const dds::SourceId& own() const { return own_; }
  bool ours(const dds::SourceId& s) const { return s == own_; }

 private:
  dds::SourceId own_;
  std::int64_t grace_end_ns_;
  bool published_ = false;
  bool yielding_ = false;
  std::vector<std::pair<std::int32_t, dds::SourceId>> reported_;
};

/// Agent i's start for a seeded swarm of n: the i-th position of core::uniform_start(max(n, i+1), seed),
/// so a swarm of processes starts exactly where the simulator with the same seed starts.
core::Vec2 seeded_start(std::int32_t id, int n, std::uint64_t seed, double half_width);

}  // namespace shapeform::agent
