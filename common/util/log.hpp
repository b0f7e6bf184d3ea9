#pragma once
/// Line logging to stderr with the process role and id: "[agent 3] WARN stale neighbour 5".
/// Each line is written with a single write(2) on fd 2 under a mutex, so lines from threads never
/// interleave and reach a test harness immediately (no stdio buffering). stdout stays for results.
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <string_view>

namespace shapeform::util {

enum class LogLevel { Info, Warn, Error };

/// Sets the line prefix: "[role id] ", or "[role] " when id < 0. Until called: "[shapeform] ".
void log_init(std::string role, int id = -1);

/// Writes all of text to fd, looping only on a partial write or EINTR. Errors are dropped: this is
/// how logs and the console reach a terminal, and there is nowhere left to report a failing one.
void write_all(int fd, std::string_view text);

/// The full line for msg at level, with prefix, level tag (none for Info, "WARN ", "ERROR ") and
/// one trailing newline (a trailing newline already in msg is not doubled). A msg longer than
/// 4 * kLineMax characters (util/text.hpp) is shortened with excerpt().
std::string format_log_line(LogLevel level, std::string_view msg);

void log(LogLevel level, std::string_view msg);
void log_info(std::string_view msg);
void log_warn(std::string_view msg);
void log_error(std::string_view msg);

/// Rate limit for messages inside loops: each key may pass at most once per interval; the others
/// are counted. Thread-safe. After the first use of a key, no allocation (the key table is a
/// std::map with transparent lookup).
class ThrottledLog {
 public:
  using NowFn = std::function<std::chrono::steady_clock::time_point()>;

  /// interval_s: minimum seconds between two messages with the same key (>= 0).
  /// now: time source, steady_clock by default (tests inject a fake one).
  explicit ThrottledLog(double interval_s, NowFn now = {});

  /// True if a message for key may be emitted now (and starts a new interval); false if it is
  /// suppressed (and counted). When true and suppressed_since_last is given, it receives the
  /// number of messages for key suppressed since the previous emitted one.
  bool allow(std::string_view key, std::uint64_t* suppressed_since_last = nullptr);

  /// log(level, msg) if allow(key); appends " (N similar suppressed)" when N > 0. Returns allow().
  bool log(LogLevel level, std::string_view key, std::string_view msg);
  bool warn(std::string_view key, std::string_view msg) { return log(LogLevel::Warn, key, msg); }
  bool error(std::string_view key, std::string_view msg) { return log(LogLevel::Error, key, msg); }

  /// Messages suppressed for key since construction (0 for an unknown key).
  std::uint64_t suppressed(std::string_view key) const;
  /// Messages suppressed for all keys since construction.
  std::uint64_t suppressed_total() const;

 private:
  struct Entry {
    std::chrono::steady_clock::time_point last_emit;
    std::uint64_t pending = 0;  ///< suppressed since last_emit
    std::uint64_t total = 0;    ///< suppressed since construction
  };

  std::chrono::steady_clock::duration interval_;
  NowFn now_;
  mutable std::mutex mutex_;
  std::map<std::string, Entry, std::less<>> entries_;
  std::uint64_t total_ = 0;
};

}  // namespace shapeform::util
