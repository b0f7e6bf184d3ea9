#include "authority.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <ostream>
#include <utility>

#include "core/enum_names.hpp"
#include "presentation.hpp"
#include "util/log.hpp"

namespace shapeform::supervisor {

namespace {

/// The fields of a command that the "epoch" and "in_force" events carry.
void add_command(nlohmann::json& j, const core::Command& cmd) {
  j["shape"] = std::string(core::to_string(cmd.shape.kind));
  j["law"] = std::string(core::to_string(cmd.law));
  j["tracking"] = cmd.tracking.enabled;
  j["hold"] = cmd.hold;
}

}  // namespace

CommandAuthority::CommandAuthority(const core::CompiledCommand& initial, double agent_rate_hz, bool lockstep,
                                   std::int64_t start_ns, SwarmMonitor& monitor, record::Recorder& recorder,
                                   Output& out)
    : agent_rate_hz_(agent_rate_hz),
      lockstep_(lockstep),
      start_ns_(start_ns),
      monitor_(monitor),
      recorder_(recorder),
      out_(out),
      current_(initial) {}

void CommandAuthority::set_identity(std::string name, dds::SourceId issuer, Send send) {
  own_name_ = std::move(name);
  own_issuer_ = issuer;
  send_ = std::move(send);
}

std::string CommandAuthority::publisher() const {
  if (!arbiter_.has_command()) return "";
  if (own()) return own_name_;
  return dds::describe_issuer(arbiter_.current().issuer_name, arbiter_.id().issuer);
}

double CommandAuthority::model_time(std::int64_t now_ns) const {
  if (epoch() == 0 || current_.hold) return 0.0;
  return static_cast<double>(now_ns - epoch_start_ns_) * 1e-9 * agent_rate_hz_ * current_.dt;
}

double CommandAuthority::metrics_time(std::int64_t now_ns) const {
  if (lockstep_)
    if (const auto t = monitor_.min_following_model_time(now_ns)) return *t;
  return model_time(now_ns);
}

bool CommandAuthority::foreign_in_force(std::int64_t now_ns) const {
  if (own_epoch_ != 0) return false;  // this supervisor commands already: `start` is its own choice
  // The agents' states may show it before its sample arrives: it is in force all the same.
  return arbiter_.has_command() || monitor_.min_epoch_followed(now_ns) != 0;
}

nlohmann::json CommandAuthority::in_force_json() const {
  const bool known = arbiter_.has_command();
  return {{"epoch", epoch()},
          {"issuer", known ? nlohmann::json(dds::to_string(arbiter_.id().issuer)) : nlohmann::json()},
          {"publisher", known ? nlohmann::json(publisher()) : nlohmann::json()},
          {"own", own()}};
}

void CommandAuthority::publish(const core::CompiledCommand& cmd, std::int64_t now_ns) {
  // After every epoch seen: on the command topic (the arbiter's), and in the agents' states unless
  // that is an absurd jump (the agents refuse one such command too).
  const std::uint64_t floor = monitor_.min_epoch_followed(now_ns);
  std::uint64_t after = epoch();
  if (!dds::CommandArbiter::absurd(monitor_.max_epoch_seen(), arbiter_.reference(floor)))
    after = std::max(after, monitor_.max_epoch_seen());
  const dds::CommandSample sample{cmd, dds::CommandId{after + 1, own_issuer_}, own_name_};
  if (arbiter_.offer(sample, floor) !=
      dds::CommandArbiter::Verdict::Adopted) {  // cannot happen: it is greater
    util::log_error("command epoch " + std::to_string(after + 1) + " not adopted");
    return;
  }
  own_epoch_ = sample.id.epoch;
  current_ = cmd;
  epoch_start_ns_ = now_ns;
  clock_synced_ = true;
  monitor_.set_command(cmd, sample.id, now_ns);
  record_command(now_ns);
  if (send_ && !send_(sample)) util::log_warn("command write failed");
  report_published(cmd);
}

void CommandAuthority::report_published(const core::CompiledCommand& cmd) {
  out_.human() << "epoch " << own_epoch_ << ": " << describe_command(cmd) << std::endl;
  nlohmann::json j = in_force_json();
  add_command(j, cmd);
  out_.event("epoch", j);
}

void CommandAuthority::republish() {
  if (own() && send_ && !send_(dds::CommandSample{current_, arbiter_.id(), own_name_}))
    util::log_warn("command write failed");
}

bool CommandAuthority::hear(const dds::CommandSample& c, std::uint64_t peer_floor, std::int64_t now_ns) {
  const dds::CommandArbiter::Verdict v = arbiter_.offer(c, peer_floor);
  if (v == dds::CommandArbiter::Verdict::Adopted) {
    learnt(now_ns);
    return true;
  }
  if (v != dds::CommandArbiter::Verdict::Refused) return false;
  ++commands_refused_;
  const std::string who = dds::describe_issuer(c.issuer_name, c.id.issuer);
  const std::string line = "command " + dds::CommandArbiter::refusal(c, arbiter_.reference(peer_floor)) +
                           " (the agents refuse it too)";
  // Each new epoch refused is reported; a publisher repeating one is throttled.
  const bool fresh = c.id.epoch != last_refused_epoch_;
  last_refused_epoch_ = c.id.epoch;
  if (fresh) util::log_warn(line);
  if (fresh || out_.throttled().warn("command jump", line))
    out_.event("rejected", {{"what", "command"},
                            {"epoch", c.id.epoch},
                            {"issuer", dds::to_string(c.id.issuer)},
                            {"publisher", who},
                            {"why", line}});
  return false;
}

void CommandAuthority::refuse_invalid(std::uint64_t epoch, const std::string& why) {
  ++commands_refused_;
  out_.throttled().warn("command", "command epoch " + std::to_string(epoch) + " rejected: " + why);
}

bool CommandAuthority::recheck(std::uint64_t peer_floor, std::int64_t now_ns) {
  if (!arbiter_.has_refused() || !arbiter_.recheck(peer_floor)) return false;
  learnt(now_ns);
  return true;
}

void CommandAuthority::learnt(std::int64_t now_ns) {
  const dds::CommandSample& c = arbiter_.current();
  current_ = c.command;
  epoch_start_ns_ = now_ns;
  clock_synced_ = false;
  monitor_.set_command(current_, c.id, now_ns);
  record_command(now_ns);
  const bool replaced_own = own_epoch_ != 0 && superseded_ != own_epoch_;
  if (replaced_own) superseded_ = own_epoch_;
  const std::string who = publisher();
  std::ostream& out = out_.human();
  if (replaced_own)
    out << "epoch " << own_epoch_ << " of this supervisor was superseded by ";
  else
    out << "command in force: ";
  out << "epoch " << c.id.epoch << " of " << who << " (another participant): " << describe_command(current_)
      << "; the metrics measure against it" << std::endl;
  util::log_warn((replaced_own ? "superseded: the agents follow epoch " : "command in force: epoch ") +
                 std::to_string(c.id.epoch) + " of " + who);
  nlohmann::json j = in_force_json();
  j["superseded"] = replaced_own ? nlohmann::json(own_epoch_) : nlohmann::json();
  add_command(j, current_);
  out_.event("in_force", j);
}

void CommandAuthority::sync_clock(std::int64_t now_ns) {
  if (clock_synced_) return;
  if (const auto at = monitor_.min_following_model_time(now_ns)) {
    const double ticks = *at / current_.dt;  // agent ticks since the command was adopted
    epoch_start_ns_ = now_ns - static_cast<std::int64_t>(std::llround(ticks / agent_rate_hz_ * 1e9));
    clock_synced_ = true;
  }
}

void CommandAuthority::record_command(std::int64_t now_ns) {
  if (!arbiter_.has_command() || !recorder_.is_open()) return;
  try {
    recorder_.write_command(static_cast<double>(now_ns - start_ns_) * 1e-9, model_time(now_ns), epoch(),
                            dds::to_string(arbiter_.id().issuer), arbiter_.current().issuer_name, current_);
  } catch (const std::exception& e) {
    out_.throttled().error("record", std::string("recording: ") + e.what());
  }
}

}  // namespace shapeform::supervisor
