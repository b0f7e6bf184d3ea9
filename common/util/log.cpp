#include "util/log.hpp"

#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "util/text.hpp"

namespace shapeform::util {

namespace {

// Built on first use and never destroyed, so threads may log during static destruction.
struct LogState {
  std::mutex mutex;  // guards prefix and serialises writes to fd 2
  std::string prefix = "[shapeform] ";
};

LogState& state() {
  static LogState* s = new LogState;
  return *s;
}

std::string_view level_tag(LogLevel level) {
  switch (level) {
    case LogLevel::Info:
      return "";
    case LogLevel::Warn:
      return "WARN ";
    case LogLevel::Error:
      return "ERROR ";
  }
  return "";
}

/// A log line longer than this is shortened with excerpt(): whatever input a message quotes, a line
/// stays readable (and a test harness's read of it bounded).
constexpr std::size_t kLogLineMax = 4 * kLineMax;

std::string format_with_prefix(const std::string& prefix, LogLevel level, std::string_view msg) {
  if (!msg.empty() && msg.back() == '\n') msg.remove_suffix(1);
  std::string shortened;
  if (msg.size() > kLogLineMax) {
    shortened = excerpt(msg, kLogLineMax);
    msg = shortened;
  }
  const std::string_view tag = level_tag(level);
  std::string line;
  line.reserve(prefix.size() + tag.size() + msg.size() + 1);
  line.append(prefix).append(tag).append(msg).push_back('\n');
  return line;
}

}  // namespace

void log_init(std::string role, int id) {
  std::string prefix = "[" + std::move(role);
  if (id >= 0) prefix += " " + std::to_string(id);
  prefix += "] ";
  LogState& st = state();
  const std::lock_guard<std::mutex> lock(st.mutex);
  st.prefix = std::move(prefix);
}

std::string format_log_line(LogLevel level, std::string_view msg) {
  LogState& st = state();
  const std::lock_guard<std::mutex> lock(st.mutex);
  return format_with_prefix(st.prefix, level, msg);
}

void log(LogLevel level, std::string_view msg) {
  LogState& st = state();
  const std::lock_guard<std::mutex> lock(st.mutex);
  write_all(STDERR_FILENO, format_with_prefix(st.prefix, level, msg));  // one write(2) per line
}

void log_info(std::string_view msg) { log(LogLevel::Info, msg); }
void log_warn(std::string_view msg) { log(LogLevel::Warn, msg); }
void log_error(std::string_view msg) { log(LogLevel::Error, msg); }

ThrottledLog::ThrottledLog(double interval_s, NowFn now) : now_(std::move(now)) {
  if (!std::isfinite(interval_s) || interval_s < 0.0) {
    throw std::invalid_argument("ThrottledLog: interval_s must be finite and >= 0, got " +
                                std::to_string(interval_s));
  }
  interval_ = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(interval_s));
  if (!now_) now_ = [] { return std::chrono::steady_clock::now(); };
}

bool ThrottledLog::allow(std::string_view key, std::uint64_t* suppressed_since_last) {
  const auto now = now_();
  const std::lock_guard<std::mutex> lock(mutex_);
  auto it = entries_.find(key);
  if (it == entries_.end()) {
    entries_.emplace(std::string(key), Entry{now, 0, 0});
    if (suppressed_since_last != nullptr) *suppressed_since_last = 0;
    return true;
  }
  Entry& e = it->second;
  if (now - e.last_emit < interval_) {
    ++e.pending;
    ++e.total;
    ++total_;
    return false;
  }
  if (suppressed_since_last != nullptr) *suppressed_since_last = e.pending;
  e.last_emit = now;
  e.pending = 0;
  return true;
}

bool ThrottledLog::log(LogLevel level, std::string_view key, std::string_view msg) {
  std::uint64_t n = 0;
  if (!allow(key, &n)) return false;
  if (n == 0) {
    util::log(level, msg);
  } else {
    std::string line(msg);
    if (!line.empty() && line.back() == '\n') line.pop_back();
    line += " (" + std::to_string(n) + " similar suppressed)";
    util::log(level, line);
  }
  return true;
}

std::uint64_t ThrottledLog::suppressed(std::string_view key) const {
  const std::lock_guard<std::mutex> lock(mutex_);
  const auto it = entries_.find(key);
  return it == entries_.end() ? 0 : it->second.total;
}

std::uint64_t ThrottledLog::suppressed_total() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return total_;
}

void write_all(int fd, std::string_view text) {
  const char* p = text.data();
  std::size_t left = text.size();
  while (left > 0) {
    const ssize_t n = ::write(fd, p, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      return;
    }
    p += n;
    left -= static_cast<std::size_t>(n);
  }
}

}  // namespace shapeform::util
