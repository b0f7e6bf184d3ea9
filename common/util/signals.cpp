#include "util/signals.hpp"

#include <cerrno>
#include <csignal>
#include <string>
#include <system_error>

namespace shapeform::util {

namespace {

// Lock-free atomics are the only shared state a signal handler may touch portably.
std::atomic<bool> g_stop{false};
std::atomic<int> g_signal{0};
static_assert(std::atomic<bool>::is_always_lock_free, "stop flag must be lock-free");
static_assert(std::atomic<int>::is_always_lock_free, "signal number must be lock-free");

void on_stop_signal(int sig) {
  g_signal.store(sig);
  g_stop.store(true);
}

void install(int sig) {
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESETHAND;
  if (sigaction(sig, &sa, nullptr) != 0) {
    throw std::system_error(errno, std::generic_category(),
                            "sigaction failed for signal " + std::to_string(sig));
  }
}

}  // namespace

void install_stop_signals() {
  install(SIGINT);
  install(SIGTERM);
}

const std::atomic<bool>& stop_flag() { return g_stop; }

void request_stop() { g_stop.store(true); }

int stop_signal() { return g_signal.load(); }

void reset_stop() {
  g_signal.store(0);
  g_stop.store(false);
}

}  // namespace shapeform::util
