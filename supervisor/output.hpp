#pragma once
/// Where the supervisor's output goes. Without --json: human text on stdout. With --json: the same text
/// on stderr, and on stdout only JSON lines, one event each. Errors about input go to stderr; logs
/// (util/log.hpp) go to stderr, repeated ones throttled.
#include <cstdint>
#include <functional>
#include <iosfwd>
#include <nlohmann/json.hpp>
#include <vector>

#include "swarm_monitor.hpp"
#include "util/log.hpp"

namespace shapeform::supervisor {

class Output {
 public:
  /// The standard streams.
  explicit Output(bool json);
  /// Given streams (tests): human text, JSON events, errors.
  Output(bool json, std::ostream& human, std::ostream& events, std::ostream& errors);

  bool json() const { return json_; }
  /// Who else takes every event (the recorder's shapeform/events channel), with or without --json.
  void set_event_sink(std::function<void(const nlohmann::json&)> sink) { sink_ = std::move(sink); }
  /// Whether events go anywhere (--json, or a sink): callers skip building them otherwise.
  bool wants_events() const { return json_ || static_cast<bool>(sink_); }
  std::ostream& human() { return *human_; }
  std::ostream& errors() { return *errors_; }
  /// With --json, `j` with "event": name as one line on the events stream; and to the sink.
  void event(const char* name, nlohmann::json j);
  /// Warnings and errors that may repeat in the loop: at most one per key every 5 s.
  util::ThrottledLog& throttled() { return throttled_; }

 private:
  bool json_;
  std::ostream* human_;
  std::ostream* events_;
  std::ostream* errors_;
  util::ThrottledLog throttled_{5.0};
  std::function<void(const nlohmann::json&)> sink_;
};

/// --json: an "agent" event for every agent that became alive ("joined") or stopped being alive
/// ("left": it disposed its instance, a clean exit; "lost": it fell silent).
class MembershipReport {
 public:
  void update(const SwarmMonitor& monitor, std::int64_t now_ns, Output& out);

 private:
  std::vector<std::int32_t> alive_;  ///< the agents reported alive, ascending
  std::vector<std::int32_t> now_;    ///< this tick's, ascending (kept: no allocation per tick)
};

}  // namespace shapeform::supervisor
