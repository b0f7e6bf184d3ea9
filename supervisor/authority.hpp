#pragma once
/// The command authority: which command is in force, as this supervisor knows it, and publishing its
/// own. The command in force is chosen by dds::CommandArbiter, the rule every agent applies; a command
/// this supervisor publishes takes the epoch after every one seen (on the topic and in the agents'
/// states); another participant's command that wins the order is learnt from the command topic. The
/// authority keeps the model clock of the epoch in force, writes each command to commands.csv and
/// reports each change (text, JSON events). No DDS: what it publishes goes to a Send function.
#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>

#include "core/compiled_command.hpp"
#include "output.hpp"
#include "protocol/command_arbiter.hpp"
#include "protocol/samples.hpp"
#include "record/recorder.hpp"
#include "swarm_monitor.hpp"

namespace shapeform::supervisor {

class CommandAuthority {
 public:
  /// Writes a command on the command topic; false when the write failed.
  using Send = std::function<bool(const dds::CommandSample&)>;

  /// `initial`: the command before any is in force (the --config one). The model clock runs at
  /// agent_rate_hz steps of the command's dt; `lockstep`: the metrics are taken where the agents are.
  /// A recording's wall_s counts from start_ns.
  CommandAuthority(const core::CompiledCommand& initial, double agent_rate_hz, bool lockstep,
                   std::int64_t start_ns, SwarmMonitor& monitor, record::Recorder& recorder, Output& out);

  /// The steady-clock time (ns) of wall_s 0 of its recordings: when the supervisor started.
  std::int64_t start_ns() const { return start_ns_; }

  /// How this supervisor names itself in its commands, its issuer (its first participant's GUID
  /// prefix, kept when a stall recreates the participant, so that its commands stay its own and keep
  /// their order) and where its commands go.
  void set_identity(std::string name, dds::SourceId issuer, Send send);

  // ----- The command in force
  /// The arbiter's command (the initial one before any).
  const core::CompiledCommand& current() const { return current_; }
  bool has_command() const { return arbiter_.has_command(); }
  dds::CommandId id() const { return arbiter_.id(); }
  /// Its epoch (0: none known).
  std::uint64_t epoch() const { return arbiter_.id().epoch; }
  /// Whether it is this supervisor's own publication.
  bool own() const { return arbiter_.has_command() && arbiter_.id().issuer == own_issuer_; }
  /// Who published it, in words ("" when none).
  std::string publisher() const;
  /// The epoch this supervisor published last once another participant's command replaced it (0: never).
  std::uint64_t superseded() const { return superseded_; }
  std::uint64_t commands_refused() const { return commands_refused_; }
  /// Wall seconds since it was published (own) or learnt.
  double since_epoch_s(std::int64_t now_ns) const {
    return static_cast<double>(now_ns - epoch_start_ns_) * 1e-9;
  }
  /// Model time of the epoch in force by the supervisor's clock; it stands still while held.
  double model_time(std::int64_t now_ns) const;
  /// The model time the metrics are taken at: the supervisor's clock, or, in lockstep, where the agents
  /// are (the slowest agent on the command: the others are at most one step ahead).
  double metrics_time(std::int64_t now_ns) const;
  /// `start`: whether a command is in force that this supervisor did not publish (it then keeps it).
  bool foreign_in_force(std::int64_t now_ns) const;
  /// {"epoch", "issuer", "publisher", "own"} of the command in force, for the JSON events.
  nlohmann::json in_force_json() const;

  // ----- Changes
  /// Publishes cmd as this supervisor's command, after every epoch seen (unless that is an absurd jump).
  void publish(const core::CompiledCommand& cmd, std::int64_t now_ns);
  /// After a participant rebuild: offers this supervisor's command in force (same id) again.
  void republish();
  /// A valid command heard on the topic from another participant. True when it is in force from now
  /// (learnt); an absurd epoch jump is refused, counted and reported. `peer_floor`: the lowest epoch the
  /// agents follow (SwarmMonitor::min_epoch_followed).
  bool hear(const dds::CommandSample& c, std::uint64_t peer_floor, std::int64_t now_ns);
  /// A command refused as invalid (dds::from_msg): counted and reported.
  void refuse_invalid(std::uint64_t epoch, const std::string& why);
  /// Re-judges the commands refused so far against the agents' epochs now; true when one was learnt.
  bool recheck(std::uint64_t peer_floor, std::int64_t now_ns);
  /// Whether a refused command waits for recheck() (without one, recheck() does nothing).
  bool has_refused() const { return arbiter_.has_refused(); }
  /// A learnt command's model clock is where the agents following it are: taken once they report it.
  void sync_clock(std::int64_t now_ns);
  /// commands.csv: the command in force (when one is) from now.
  void record_command(std::int64_t now_ns);

 private:
  /// The arbiter adopted another participant's command: measure against it, record and report it.
  void learnt(std::int64_t now_ns);
  void report_published(const core::CompiledCommand& cmd);

  double agent_rate_hz_;
  bool lockstep_;
  std::int64_t start_ns_;
  SwarmMonitor& monitor_;
  record::Recorder& recorder_;
  Output& out_;
  dds::CommandArbiter arbiter_;
  core::CompiledCommand current_;
  std::int64_t epoch_start_ns_ = 0;  ///< when the command in force was published (own) or learnt
  bool clock_synced_ = true;  ///< false: a learnt command whose model clock is still to take from the agents
  std::uint64_t own_epoch_ = 0;   ///< the epoch this supervisor published last (0: none yet)
  std::uint64_t superseded_ = 0;  ///< own_epoch_ once another participant's command replaced it
  std::uint64_t commands_refused_ = 0;
  std::uint64_t last_refused_epoch_ = 0;
  std::string own_name_;
  dds::SourceId own_issuer_;
  Send send_;
};

}  // namespace shapeform::supervisor
