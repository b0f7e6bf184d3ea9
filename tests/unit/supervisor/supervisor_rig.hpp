#pragma once
/// The supervisor's parts without DDS, wired as the node wires them: what they print is kept in
/// strings, the commands the authority sends in `sent`.
#include <cmath>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "authority.hpp"
#include "executor.hpp"
#include "input_driver.hpp"
#include "monitor_fixtures.hpp"
#include "output.hpp"
#include "presentation.hpp"
#include "record/recorder.hpp"
#include "swarm_monitor.hpp"

namespace shapeform::test {

/// A participant's identity whose bytes all equal b (b > 0: known).
inline dds::SourceId source(std::uint8_t b) {
  dds::SourceId s;
  s.prefix.fill(b);
  return s;
}

struct Rig {
  static constexpr double kAgentRateHz = 10.0;

  std::ostringstream human, events, errors;
  supervisor::Output out{true, human, events, errors};
  supervisor::SwarmMonitor monitor;
  record::Recorder recorder;
  supervisor::ProgressFilter progress;
  supervisor::CommandAuthority authority;
  supervisor::InputDriver input{out, monitor, authority};
  supervisor::Executor executor;
  std::vector<dds::CommandSample> sent;  ///< what the authority wrote on the command topic

  explicit Rig(const core::CompiledCommand& scenario = circle(), bool replace_on_start = false,
               core::ConvergenceDetector::Params converge = {})
      : monitor(kS, converge),
        authority(scenario, kAgentRateHz, false, 0, monitor, recorder, out),
        executor(scenario, replace_on_start,
                 supervisor::ExecutorParts{authority, monitor, recorder, input, progress, out}) {
    authority.set_identity("test supervisor", source(0x10), [this](const dds::CommandSample& s) {
      sent.push_back(s);
      return true;
    });
    input.set_dispatch([this](const supervisor::Action& a, std::int64_t now) { executor(a, now); });
  }

  /// Agents 0..n-1 evenly on a ring of `radius`, following `id` at `model_time`, heard at now.
  void follow(int n, double radius, dds::CommandId id, double model_time, std::int64_t now) {
    for (int i = 0; i < n; ++i) {
      const double a = 2 * M_PI * i / n;
      const core::Vec2 x = radius * core::Vec2(std::cos(a), std::sin(a));
      monitor.on_state(i, x, x, id, model_time, now);
    }
  }

  /// The JSON events printed since the last call.
  std::vector<nlohmann::json> take_events() {
    std::vector<nlohmann::json> out_events;
    std::istringstream lines(events.str());
    for (std::string line; std::getline(lines, line);) out_events.push_back(nlohmann::json::parse(line));
    events.str("");
    return out_events;
  }
  /// The human text printed since the last call.
  std::string take_human() {
    std::string s = human.str();
    human.str("");
    return s;
  }
};

/// A command sample of another participant: `cmd` as epoch `epoch` of issuer `issuer`.
inline dds::CommandSample rival(const core::CompiledCommand& cmd, std::uint64_t epoch,
                                std::uint8_t issuer = 0x20, std::string name = "rival") {
  return dds::CommandSample{cmd, dds::CommandId{epoch, source(issuer)}, std::move(name)};
}

}  // namespace shapeform::test
