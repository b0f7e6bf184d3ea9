#pragma once
/// Process stop request: SIGINT/SIGTERM (or request_stop()) set one global atomic flag that
/// RateLoop::wait_next polls. The handler does nothing else, so it is async-signal-safe.
#include <atomic>

namespace shapeform::util {

/// Installs SIGINT and SIGTERM handlers that set stop_flag() and remember the signal number.
/// No SA_RESTART, so a blocking system call in the receiving thread returns EINTR. Each handler is
/// one-shot (SA_RESETHAND): a second Ctrl-C or SIGTERM gets the default action and ends a process
/// whose shutdown hangs. Calling it again re-arms both handlers. Throws std::system_error on
/// failure.
void install_stop_signals();

/// The global stop flag: false until a stop signal arrives or request_stop() is called.
const std::atomic<bool>& stop_flag();

/// Sets the stop flag from code (tests, a console "quit" command, a fatal error in another thread).
void request_stop();

/// Signal number that set the flag (SIGINT, SIGTERM), or 0 if none did (not stopped, or
/// request_stop).
int stop_signal();

/// Clears the flag and the recorded signal. For tests that share one process.
void reset_stop();

}  // namespace shapeform::util
