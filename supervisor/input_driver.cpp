#include "input_driver.hpp"

#include <exception>
#include <ostream>
#include <utility>

#include "console_parser.hpp"
#include "util/log.hpp"
#include "util/text.hpp"

namespace shapeform::supervisor {

InputDriver::InputDriver(Output& out, const SwarmMonitor& monitor, const CommandAuthority& authority)
    : out_(out), monitor_(monitor), authority_(authority) {}

bool InputDriver::load_script(const std::string& path, const core::CompiledCommand& initial) {
  try {
    ScriptSource check(path);
    bool bad = false;
    core::CompiledCommand c = initial;
    while (auto line = check.poll()) {
      const ParseResult r = parse_command(*line, c);
      if (!r.ok()) {
        out_.errors() << util::bounded_line(with_location(check, r.error)) << std::endl;
        bad = true;
      } else if (const auto* set = std::get_if<SetCommand>(&r.action)) {
        c = set->command;
      }
    }
    if (bad) return false;
    script_ = std::make_unique<ScriptSource>(path);
    return true;
  } catch (const std::exception& e) {
    out_.errors() << "shapeform_supervisor: --script: " << e.what() << std::endl;
    return false;
  }
}

void InputDriver::run_lines(std::int64_t now_ns) {
  while (!quit_) {
    if (pending_ && !wait_over(now_ns)) return;
    LineSource* src = script_running() ? script_.get() : console_;
    if (src == nullptr) return;
    const std::optional<std::string> line = src->poll();
    if (!line) return;
    const ParseResult r = parse_command(*line, authority_.current());
    if (!r.ok()) {
      out_.errors() << util::bounded_line(with_location(*src, r.error))
                    << std::endl;  // it may quote a long line
      continue;
    }
    if (dispatch_) dispatch_(r.action, now_ns);
  }
}

bool InputDriver::wait_over(std::int64_t now_ns) {
  const std::optional<WaitEnd> end = pending_->outcome(monitor_, authority_, now_ns);
  if (!end) return false;
  if (!end->text.empty()) out_.human() << end->text << std::endl;
  if (!end->warning.empty()) util::log_warn(end->warning);
  if (!end->ok) exit_status_ = kExitWaitTimedOut;
  end_wait(end->ok, nlohmann::json::object(), now_ns);
  return true;
}

void InputDriver::end_wait(bool ok, nlohmann::json extra, std::int64_t now_ns) {
  nlohmann::json j = {{"wait", pending_->name()},
                      {"ok", ok},
                      {"model_time", authority_.metrics_time(now_ns)},
                      {"alive", monitor_.alive_count(now_ns)}};
  j.update(extra);
  out_.event("wait", j);
  pending_.reset();
}

void InputDriver::interrupt(std::int64_t now_ns) {
  if (busy()) {
    if (pending_) {
      out_.human() << pending_->label() << ": cancelled (Ctrl-C)" << std::endl;
      end_wait(false, {{"cancelled", true}}, now_ns);
    }
    if (script_running()) {
      out_.human() << "script " << script_->path() << " abandoned after line " << script_->line_number()
                   << std::endl;
      script_.reset();
    }
    armed_quit_ns_ = -1;
    return;
  }
  if (armed_quit_ns_ >= 0 && now_ns - armed_quit_ns_ <= 1'000'000'000LL) {
    quit_ = true;
    exit_status_ = kExitInterrupted;
    return;
  }
  armed_quit_ns_ = now_ns;
  out_.human() << "(Ctrl-C again within 1 s, Ctrl-D or 'quit' to leave)" << std::endl;
}

void InputDriver::command_replaced(std::int64_t now_ns) {
  if (!pending_ || pending_->on().none() || !pending_->on_command()) return;
  const std::uint64_t epoch = authority_.epoch();
  const std::string who = authority_.publisher();
  out_.human() << "wait " << pending_->name() << ": ended, epoch " << pending_->on().epoch
               << " was superseded by epoch " << epoch << " of " << who << std::endl;
  exit_status_ = kExitWaitTimedOut;
  end_wait(false, {{"superseded", true}, {"epoch", epoch}, {"publisher", who}}, now_ns);
}

}  // namespace shapeform::supervisor
