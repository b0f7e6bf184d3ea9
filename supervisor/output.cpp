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
  now_.clear();
  for (const auto& [id, a] : monitor.agents())  // ascending ids
    if (monitor.alive(a, now_ns)) now_.push_back(id);
  const auto gone = [&](std::int32_t id) {
    out.event("agent", {{"id", id}, {"change", monitor.agents().at(id).departed ? "left" : "lost"}});
  };
  // One merge of the two ascending lists: joined are in now_ only, left or lost in alive_ only.
  auto was = alive_.begin();
  for (const auto id : now_) {
    for (; was != alive_.end() && *was < id; ++was) gone(*was);
    if (was != alive_.end() && *was == id) ++was;
    else out.event("agent", {{"id", id}, {"change", "joined"}});
  }
  for (; was != alive_.end(); ++was) gone(*was);
  alive_.swap(now_);
}

}  // namespace shapeform::supervisor
