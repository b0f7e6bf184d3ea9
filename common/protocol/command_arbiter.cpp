#include "protocol/command_arbiter.hpp"

#include <algorithm>

namespace shapeform::dds {

CommandArbiter::Verdict CommandArbiter::offer(const CommandSample& c, std::uint64_t peer_floor) {
  if (c.id.none()) return Verdict::Older;  // from_msg refuses epoch 0; nothing is below "none"
  const CommandId now = id();
  if (current_ && c.id == now) return Verdict::Same;
  if (current_ && c.id < now) return Verdict::Older;
  if (absurd(c.id.epoch, reference(peer_floor))) {
    const auto at = std::find_if(refused_.begin(), refused_.end(), [&](const CommandSample& r) { return !(c.id < r.id); });
    if (at == refused_.end() || at->id != c.id) refused_.insert(at, c);
    if (refused_.size() > kRefusedKept) refused_.pop_back();
    return Verdict::Refused;
  }
  current_ = c;
  // What lies at or below the new command can never be adopted any more.
  refused_.erase(std::remove_if(refused_.begin(), refused_.end(), [&](const CommandSample& r) { return !(c.id < r.id); }),
                 refused_.end());
  return Verdict::Adopted;
}

bool CommandArbiter::recheck(std::uint64_t peer_floor) {
  const std::uint64_t ref = reference(peer_floor);
  for (auto it = refused_.begin(); it != refused_.end(); ++it) {  // greatest first
    if (absurd(it->id.epoch, ref)) continue;
    const CommandSample c = *it;
    return offer(c, peer_floor) == Verdict::Adopted;
  }
  return false;
}

std::string CommandArbiter::refusal(const CommandSample& c, std::uint64_t reference) {
  return "epoch " + std::to_string(c.id.epoch) + " of " + describe_issuer(c.issuer_name, c.id.issuer) +
         " is more than " + std::to_string(kMaxEpochJump) + " above epoch " + std::to_string(reference) + ": refused";
}

}  // namespace shapeform::dds
