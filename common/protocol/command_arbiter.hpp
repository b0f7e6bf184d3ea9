#pragma once
/// Which command a receiver follows: one rule, applied identically by every agent and by the
/// supervisor, so that a swarm never splits between two commands. No Fast DDS, no clock.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "protocol/samples.hpp"

namespace shapeform::dds {

/// Largest step above the epoch a receiver judges from that it accepts (see CommandArbiter). Our
/// supervisors step by one per command, so a legitimate step is tiny: even a script commanding 100
/// times a second for 2 hours, unheard by one agent all along, stays under it. A step beyond it comes
/// from a broken or hostile participant (an epoch of 2^32 - 1 or 2^64 - 1): refused, it can neither
/// take the swarm over nor leave no room above it. And since each accepted step is at most 10^6, it
/// takes more than 10^13 accepted commands to approach 2^64: the counter never wraps.
inline constexpr std::uint64_t kMaxEpochJump = 1'000'000;

class CommandArbiter {
 public:
  enum class Verdict {
    Older,    ///< below the command followed: ignored
    Same,     ///< the command followed (a re-offered copy): nothing to do
    Adopted,  ///< now followed
    Refused   ///< above, but an absurd jump: not followed, kept aside (recheck), to be counted
  };

  /// A received command. It is adopted when it is greater than the command followed (or the first
  /// one) and its epoch is at most kMaxEpochJump above the reference: the epoch followed, or, before
  /// any, `peer_floor`, the lowest non-zero epoch that this receiver's peers report following (0 when
  /// it hears none). A fresh receiver so judges by the swarm's epoch, not by 0, and ends on the
  /// command the others follow.
  Verdict offer(const CommandSample& c, std::uint64_t peer_floor = 0);
  /// Re-judges the commands refused so far against the reference now (a fresh receiver that has since
  /// heard its peers): adopts the greatest acceptable one and returns true, or returns false.
  bool recheck(std::uint64_t peer_floor);

  bool has_command() const { return current_.has_value(); }
  /// The command followed; only when has_command().
  const CommandSample& current() const { return *current_; }
  /// Its id; epoch 0 before any.
  CommandId id() const { return current_ ? current_->id : CommandId{}; }
  /// The epoch jumps are judged from (see offer).
  std::uint64_t reference(std::uint64_t peer_floor) const { return current_ ? current_->id.epoch : peer_floor; }
  /// Whether `epoch` lies more than kMaxEpochJump above `reference`.
  static bool absurd(std::uint64_t epoch, std::uint64_t reference) {
    return epoch > reference && epoch - reference > kMaxEpochJump;
  }
  /// Why c is refused, judged from `reference`: "epoch E of NAME [GUID] is more than 1000000 above
  /// epoch R: refused" (the one wording of agents and supervisor).
  static std::string refusal(const CommandSample& c, std::uint64_t reference);
  /// Whether a refused command waits for recheck().
  bool has_refused() const { return !refused_.empty(); }
  /// Refused commands kept for recheck(), the greatest ones.
  static constexpr std::size_t kRefusedKept = 8;

 private:
  std::optional<CommandSample> current_;
  std::vector<CommandSample> refused_;  ///< descending id, distinct, at most kRefusedKept
};

}  // namespace shapeform::dds
