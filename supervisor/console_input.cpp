#include "console_input.hpp"

#include <editline/readline.h>
#include <poll.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <utility>

namespace shapeform::supervisor {
namespace {

constexpr int kPollTimeoutMs = 100;  ///< how long a stop request may wait for the reader thread
constexpr int kPromptPollMs = 10;    ///< how often to look whether the main loop took a line
constexpr int kPromptDelayMs = 50;   ///< time the main loop gets to answer before the next prompt
constexpr int kHistoryMax = 1000;

/// The one live ConsoleInput: libedit's callback interface has global state and a C callback.
std::atomic<ConsoleInput*> g_console{nullptr};

void strip_cr(std::string& line) {
  if (!line.empty() && line.back() == '\r') line.pop_back();
}

/// libedit line handler (reader thread). line is malloc'ed and ours; nullptr means end of input.
void on_editline_line(char* line) {
  ConsoleInput* console = g_console.load();
  if (line == nullptr) {
    if (console != nullptr) console->set_ended();
    return;
  }
  std::string text(line);
  std::free(line);
  static std::string last;  // reader thread only: skip blank lines and immediate repeats
  bool blank = true;
  for (const char ch : text) blank = blank && (ch == ' ' || ch == '\t');
  if (!blank && text != last) {
    add_history(text.c_str());
    last = text;
  }
  if (console != nullptr) console->push_line(std::move(text));
}

enum class Wait { Ready, Timeout, Ended };

/// Waits up to the poll timeout for fd to be readable (or at end / in error: Ended).
Wait wait_readable(int fd) {
  pollfd p{fd, POLLIN, 0};
  const int r = ::poll(&p, 1, kPollTimeoutMs);
  if (r < 0) return errno == EINTR ? Wait::Timeout : Wait::Ended;
  if (r == 0) return Wait::Timeout;
  if ((p.revents & POLLIN) != 0) return Wait::Ready;  // data, or end of file (read() gives 0)
  return Wait::Ended;                                 // POLLHUP, POLLERR, POLLNVAL without data
}

}  // namespace

std::string with_location(const LineSource& source, std::string_view message) {
  std::string loc = source.location();
  if (loc.empty()) return std::string(message);
  loc += ": ";
  loc += message;
  return loc;
}

// ---------------------------------------------------------------------------------------------
// ConsoleInput

ConsoleInput::ConsoleInput() : ConsoleInput(Options{}) {}

ConsoleInput::ConsoleInput(Options options) : options_(std::move(options)) {
  ConsoleInput* expected = nullptr;
  if (!g_console.compare_exchange_strong(expected, this)) {
    throw std::logic_error("ConsoleInput: only one console input may exist at a time");
  }
  interactive_ = !options_.plain && ::isatty(STDIN_FILENO) == 1 && ::isatty(STDOUT_FILENO) == 1;
  try {
    thread_ = std::thread([this] { run(); });
  } catch (...) {
    g_console.store(nullptr);
    throw;
  }
}

ConsoleInput::~ConsoleInput() {
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
  g_console.store(nullptr);
}

std::optional<std::string> ConsoleInput::poll() {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (lines_.empty()) return std::nullopt;
  std::string line = std::move(lines_.front());
  lines_.pop_front();
  return line;
}

bool ConsoleInput::eof() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return ended_ && lines_.empty();
}

void ConsoleInput::push_line(std::string line) {
  strip_cr(line);
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    lines_.push_back(std::move(line));
  }
  ++lines_pushed_;
}

bool ConsoleInput::queue_empty() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return lines_.empty();
}

bool ConsoleInput::ended() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return ended_;
}

void ConsoleInput::set_ended() {
  const std::lock_guard<std::mutex> lock(mutex_);
  ended_ = true;
}

void ConsoleInput::run() {
  if (interactive_) {
    run_editline();
  } else {
    run_plain();
  }
  set_ended();
}

void ConsoleInput::run_plain() {
  // poll() + read() rather than std::getline: a blocked getline could not be stopped.
  std::string partial;
  char buf[4096];
  while (!stop_.load()) {
    const Wait w = wait_readable(STDIN_FILENO);
    if (w == Wait::Timeout) continue;
    if (w == Wait::Ended) break;
    const ssize_t n = ::read(STDIN_FILENO, buf, sizeof buf);
    if (n < 0) {
      if (errno == EINTR || errno == EAGAIN) continue;
      break;
    }
    if (n == 0) break;  // end of input
    partial.append(buf, static_cast<std::size_t>(n));
    std::size_t start = 0;
    for (std::size_t nl = partial.find('\n'); nl != std::string::npos;
         nl = partial.find('\n', start)) {
      push_line(partial.substr(start, nl - start));
      start = nl + 1;
    }
    partial.erase(0, start);
  }
  if (!partial.empty()) push_line(std::move(partial));  // last line without a newline
}

void ConsoleInput::run_editline() {
  // All libedit calls happen on this thread. In callback mode libedit reads one character per
  // rl_callback_read_char(), so the thread checks stop_ between characters and never blocks in
  // libedit. libedit leaves callback (raw) mode when it hands over a line; left so, its next call
  // would block for a whole line. So the handler is installed again for every line, once the
  // main loop has taken the line and had a moment to print its answer before the new prompt.
  rl_catch_signals = 0;  // keep the application's signal handlers (must precede rl_initialize)
  rl_readline_name = "shapeform";
  rl_instream = stdin;
  rl_outstream = stdout;
  rl_initialize();
  stifle_history(kHistoryMax);
  if (!options_.history_file.empty()) read_history(options_.history_file.c_str());
  bool installed = false;
  bool prompt_shown = false;  // a prompt without a newline after it is on the screen
  while (!stop_.load() && !ended()) {
    if (!installed) {
      if (!queue_empty()) {  // the main loop has not taken the last line yet
        std::this_thread::sleep_for(std::chrono::milliseconds(kPromptPollMs));
        continue;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(kPromptDelayMs));
      std::fflush(stdout);
      rl_callback_handler_install(options_.prompt.c_str(), on_editline_line);  // raw mode, prompt
      installed = prompt_shown = true;
    }
    const Wait w = wait_readable(STDIN_FILENO);
    if (w == Wait::Timeout) continue;
    if (w == Wait::Ended) break;
    const std::uint64_t before = lines_pushed_.load();
    rl_callback_read_char();
    // After a line or end of input libedit is out of callback mode (terminal cooked).
    if (lines_pushed_.load() != before) installed = prompt_shown = false;  // Enter gave a newline
    if (ended()) installed = false;
  }
  if (installed) rl_callback_handler_remove();  // back to cooked mode
  if (prompt_shown) {
    std::fputs("\n", stdout);  // leave the cursor off the prompt line
    std::fflush(stdout);
  }
  if (!options_.history_file.empty()) write_history(options_.history_file.c_str());
}

// ---------------------------------------------------------------------------------------------
// ScriptSource

ScriptSource::ScriptSource(const std::filesystem::path& path) : path_(path.string()), in_(path) {
  if (!in_) throw std::runtime_error("cannot open script " + path_);
  read_ahead();
  if (next_ && next_->rfind("\xEF\xBB\xBF", 0) == 0) next_->erase(0, 3);  // UTF-8 BOM
}

std::optional<std::string> ScriptSource::poll() {
  if (!next_) return std::nullopt;
  std::optional<std::string> line = std::move(next_);
  ++line_number_;
  read_ahead();
  return line;
}

std::string ScriptSource::location() const { return path_ + ":" + std::to_string(line_number_); }

void ScriptSource::read_ahead() {
  next_.reset();
  std::string line;
  if (std::getline(in_, line)) {
    strip_cr(line);
    next_ = std::move(line);
  } else if (in_.bad()) {
    throw std::runtime_error("error reading script " + path_);
  }
}

}  // namespace shapeform::supervisor
