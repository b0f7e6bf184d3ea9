#pragma once
/// Runs the console's actions: one function per Action (a new Action that has none does not compile).
/// No DDS: commands go out through the CommandAuthority, waits to the InputDriver.
#include <cstdint>
#include <string>

#include "actions.hpp"
#include "authority.hpp"
#include "core/compiled_command.hpp"
#include "input_driver.hpp"
#include "output.hpp"
#include "presentation.hpp"
#include "record/recorder.hpp"
#include "swarm_monitor.hpp"

namespace shapeform::supervisor {

/// What the executor acts on: the parts of the supervisor it reads and changes.
struct ExecutorParts {
  CommandAuthority& authority;
  SwarmMonitor& monitor;
  record::Recorder& recorder;
  InputDriver& input;
  ProgressFilter& progress;
  Output& out;
};

class Executor {
 public:
  /// `scenario`: what `start` publishes (the --config command); `replace_on_start`: `start` replaces
  /// a command in force that this supervisor did not publish (--command-on-start replace).
  Executor(const core::CompiledCommand& scenario, bool replace_on_start, ExecutorParts parts);

  /// Runs `a` at now_ns.
  void operator()(const Action& a, std::int64_t now_ns);
  /// Starts recording into dir (closing the recording in progress once the new one is open); throws
  /// when the folder cannot be written.
  void start_recording(const std::string& dir, std::int64_t now_ns);

 private:
  void execute(const NoOp&, std::int64_t) {}
  void execute(const SetCommand& a, std::int64_t now_ns);
  void execute(const StartScenario& a, std::int64_t now_ns);
  void execute(const Hold& a, std::int64_t now_ns);
  void execute(const Resume& a, std::int64_t now_ns);
  void execute(const TrackStop& a, std::int64_t now_ns);
  void execute(const Status& a, std::int64_t now_ns);
  void execute(const ShowMetrics& a, std::int64_t now_ns);
  void execute(const Show& a, std::int64_t now_ns);
  void execute(const ShowSafety& a, std::int64_t now_ns);
  void execute(const Progress& a, std::int64_t now_ns);
  void execute(const WaitConverged& a, std::int64_t now_ns);
  void execute(const WaitAgents& a, std::int64_t now_ns);
  void execute(const WaitTime& a, std::int64_t now_ns);
  void execute(const Sleep& a, std::int64_t now_ns);
  void execute(const RecordStart& a, std::int64_t now_ns);
  void execute(const RecordStop& a, std::int64_t now_ns);
  void execute(const Help& a, std::int64_t now_ns);
  void execute(const Quit& a, std::int64_t now_ns);

  /// The `show` answer.
  ShowInfo show_info(std::int64_t now_ns) const;

  core::CompiledCommand scenario_;
  bool replace_on_start_;
  ExecutorParts p_;
};

}  // namespace shapeform::supervisor
