#include "output.hpp"

#include <iostream>
#include <utility>

namespace shapeform::supervisor {

Output::Output(bool json) : Output(json, json ? std::cerr : std::cout, std::cout, std::cerr) {}

Output::Output(bool json, std::ostream& human, std::ostream& events, std::ostream& errors)
    : json_(json), human_(&human), events_(&events), errors_(&errors) {}

void Output::event(const char* name, nlohmann::json j) {
  if (!wants_events()) return;
  j["event"] = name;
  if (sink_) sink_(j);
  if (json_) *events_ << j.dump() << std::endl;
}

void MembershipReport::update(const SwarmMonitor& monitor, std::int64_t now_ns, Output& out) {
  if (!out.wants_events()) return;
  std::set<std::int32_t> alive;
  for (const auto& [id, a] : monitor.agents())
    if (monitor.alive(a, now_ns)) alive.insert(id);
  for (const auto id : alive)
    if (!alive_.count(id)) out.event("agent", {{"id", id}, {"change", "joined"}});
  for (const auto id : alive_)
    if (!alive.count(id))
      out.event("agent", {{"id", id}, {"change", monitor.agents().at(id).departed ? "left" : "lost"}});
  alive_.swap(alive);
}

}  // namespace shapeform::supervisor
