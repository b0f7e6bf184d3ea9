#include "console_input.hpp"

#include <fcntl.h>
#include <histedit.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <csignal>

#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <system_error>
#include <utility>

#include "util/log.hpp"

namespace shapeform::supervisor {
namespace {

constexpr int kPollTimeoutMs = 100;  ///< how long a stop request may wait for the reader thread
constexpr int kHistoryMax = 1000;
constexpr auto kPartialFlush = std::chrono::milliseconds(100);  ///< output without newline waits so long

/// The one live ConsoleInput: libedit's callbacks are C functions without a context we control.
std::atomic<ConsoleInput*> g_console{nullptr};
/// Ctrl-C presses not yet seen by the reader thread, and the pipe that wakes it (signal handler).
std::atomic<int> g_sigint_count{0};
std::atomic<int> g_wake_fd{-1};
struct sigaction g_old_sigint {};
std::string g_prompt;  ///< what libedit draws as the prompt (reader thread)

void strip_cr(std::string& line) {
  if (!line.empty() && line.back() == '\r') line.pop_back();
}

void on_sigint(int) {
  g_sigint_count.fetch_add(1);
  const int fd = g_wake_fd.load();
  if (fd >= 0) {
    const char c = 'i';
    const ssize_t r = ::write(fd, &c, 1);  // async-signal-safe; a full pipe is fine (already awake)
    (void)r;
  }
}

char* prompt_fn(EditLine*) { return const_cast<char*>(g_prompt.c_str()); }

unsigned char tab_fn(EditLine*, int) {
  ConsoleInput* c = g_console.load();
  return c != nullptr ? c->on_tab() : static_cast<unsigned char>(CC_ERROR);
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

void set_cloexec(int fd) { ::fcntl(fd, F_SETFD, FD_CLOEXEC); }

void set_nonblocking(int fd) { ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) | O_NONBLOCK); }

EditLine* editline(void* p) { return static_cast<EditLine*>(p); }
History* history_of(void* p) { return static_cast<History*>(p); }

}  // namespace

std::string with_location(const LineSource& source, std::string_view message) {
  std::string loc = source.location();
  if (loc.empty()) return std::string(message);
  loc += ": ";
  loc += message;
  return loc;
}

std::string default_history_file() {
  if (const char* state = std::getenv("XDG_STATE_HOME"); state != nullptr && *state != '\0')
    return std::string(state) + "/shapeform_history";
  if (const char* home = std::getenv("HOME"); home != nullptr && *home != '\0')
    return std::string(home) + "/.shapeform_history";
  return {};
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
    if (interactive_) capture_output();
    thread_ = std::thread([this] { run(); });
  } catch (...) {
    if (interactive_) restore_output();
    g_console.store(nullptr);
    throw;
  }
}

ConsoleInput::~ConsoleInput() {
  if (interactive_) {
    std::fflush(stdout);
    restore_output();  // the pipe's last write ends close: the reader prints the rest, then sees its end
  }
  stop_.store(true);
  if (wake_pipe_[1] >= 0) {
    const char c = 's';
    const ssize_t r = ::write(wake_pipe_[1], &c, 1);
    (void)r;
  }
  if (thread_.joinable()) thread_.join();
  if (interactive_) {
    g_wake_fd.store(-1);
    for (int fd : {out_pipe_[0], wake_pipe_[0], wake_pipe_[1]})
      if (fd >= 0) ::close(fd);
    if (term_fd_ >= 0) ::close(term_fd_);
  }
  g_console.store(nullptr);
}

void ConsoleInput::capture_output() {
  // The terminal stays reachable through term_fd_; stdout (and stderr, when it is the same terminal)
  // now feed a pipe that the reader thread prints above the prompt.
  term_fd_ = ::dup(STDOUT_FILENO);
  if (term_fd_ < 0 || ::pipe(out_pipe_) != 0 || ::pipe(wake_pipe_) != 0)
    throw std::runtime_error("console: cannot set up the terminal output pipe");
  for (int fd : {term_fd_, out_pipe_[0], out_pipe_[1], wake_pipe_[0], wake_pipe_[1]}) set_cloexec(fd);
  set_nonblocking(out_pipe_[0]);
  set_nonblocking(wake_pipe_[0]);
  set_nonblocking(wake_pipe_[1]);
  std::fflush(stdout);
  std::fflush(stderr);
  ::dup2(out_pipe_[1], STDOUT_FILENO);
  if (::isatty(STDERR_FILENO) == 1) {
    saved_err_ = ::dup(STDERR_FILENO);
    set_cloexec(saved_err_);
    ::dup2(out_pipe_[1], STDERR_FILENO);
  }
  ::close(out_pipe_[1]);
  out_pipe_[1] = -1;
  std::setvbuf(stdout, nullptr, _IOLBF, BUFSIZ);  // a pipe now: keep stdout line-buffered
  // Ctrl-C becomes a key of the console (see take_interrupts), no longer a stop request.
  g_sigint_count.store(0);
  g_wake_fd.store(wake_pipe_[1]);
  struct sigaction sa {};
  sa.sa_handler = on_sigint;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;
  ::sigaction(SIGINT, &sa, &g_old_sigint);
}

void ConsoleInput::restore_output() {
  ::sigaction(SIGINT, &g_old_sigint, nullptr);
  if (term_fd_ >= 0) ::dup2(term_fd_, STDOUT_FILENO);
  if (saved_err_ >= 0) {
    ::dup2(saved_err_, STDERR_FILENO);
    ::close(saved_err_);
    saved_err_ = -1;
  }
}

std::optional<std::string> ConsoleInput::poll() {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (lines_.empty()) return std::nullopt;
  std::string line = std::move(lines_.front());
  lines_.pop_front();
  busy_ = true;  // the loop runs it; set_busy(false) brings the prompt back after its answer
  return line;
}

bool ConsoleInput::eof() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return ended_ && lines_.empty();
}

void ConsoleInput::set_busy(bool busy) {
  if (!interactive_) return;
  std::fflush(stdout);  // the answer goes into the pipe before the prompt comes back
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (busy_ == busy) return;
    busy_ = busy;
  }
  const char c = 'b';
  const ssize_t r = ::write(wake_pipe_[1], &c, 1);
  (void)r;
}

int ConsoleInput::take_interrupts() {
  const std::lock_guard<std::mutex> lock(mutex_);
  const int n = interrupts_for_loop_;
  interrupts_for_loop_ = 0;
  if (n > 0) busy_ = true;  // the prompt returns once the loop has answered
  return n;
}

void ConsoleInput::push_lines(std::vector<std::string> lines) {
  for (std::string& line : lines) strip_cr(line);
  const std::lock_guard<std::mutex> lock(mutex_);
  for (std::string& line : lines) lines_.push_back(std::move(line));
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
    // The lines of one read go to the loop together: lines written at once ("shape ...\nwait converged")
    // run one after the other as a script's would, with no DDS event between them.
    std::vector<std::string> lines;
    std::size_t start = 0;
    for (std::size_t nl = partial.find('\n'); nl != std::string::npos;
         nl = partial.find('\n', start)) {
      lines.push_back(partial.substr(start, nl - start));
      start = nl + 1;
    }
    partial.erase(0, start);
    push_lines(std::move(lines));
  }
  if (!partial.empty()) push_lines({std::move(partial)});  // last line without a newline
}

void ConsoleInput::write_term(std::string_view text) {
  std::fflush(static_cast<FILE*>(term_file_));  // libedit's own output first
  util::write_all(term_fd_, text);
}

void ConsoleInput::erase_edit_area() {
  // Back to the column 0 of the prompt's row, then clear to the end of the screen. The prompt and
  // the line are ASCII in practice: one column per byte.
  const LineInfo* li = el_line(editline(el_));
  const std::size_t cursor = g_prompt.size() + static_cast<std::size_t>(li->cursor - li->buffer);
  winsize ws{};
  const std::size_t cols = ::ioctl(term_fd_, TIOCGWINSZ, &ws) == 0 && ws.ws_col > 0 ? ws.ws_col : 80;
  std::string seq = "\r";
  if (const std::size_t rows = cursor / cols; rows > 0) seq += "\x1b[" + std::to_string(rows) + "A";
  seq += "\x1b[J";
  write_term(seq);
}

void ConsoleInput::show_prompt(bool show) {
  EditLine* el = editline(el_);
  if (show) {
    if (!at_line_start_) write_term("\n");
    g_prompt = options_.prompt;
    el_resize(el);
    el_set(el, EL_REFRESH);  // draws the prompt and the line from column 0
  } else {
    erase_edit_area();  // the line itself is kept for when the prompt returns
    g_prompt.clear();
    at_line_start_ = true;
  }
  prompt_shown_ = show;
}

void ConsoleInput::print_above(std::string_view text) {
  if (text.empty()) return;
  if (!prompt_shown_) {
    write_term(text);
    at_line_start_ = text.back() == '\n';
    return;
  }
  erase_edit_area();
  write_term(text);
  if (text.back() != '\n') write_term("\n");
  el_resize(editline(el_));
  el_set(editline(el_), EL_REFRESH);
}

unsigned char ConsoleInput::on_tab() {
  EditLine* el = editline(el_);
  const LineInfo* li = el_line(el);
  const std::string before(li->buffer, static_cast<std::size_t>(li->cursor - li->buffer));
  if (!options_.complete) return CC_ERROR;
  const Completion c = options_.complete(before);
  if (c.candidates.empty() || c.start > before.size()) return CC_ERROR;
  const std::string word = before.substr(c.start);
  std::string common = c.candidates.front();
  for (const std::string& cand : c.candidates) {
    std::size_t n = 0;
    while (n < common.size() && n < cand.size() && common[n] == cand[n]) ++n;
    common.resize(n);
  }
  if (common.size() < word.size() || common.compare(0, word.size(), word) != 0) return CC_ERROR;
  std::string insert = common.substr(word.size());
  if (c.candidates.size() == 1 && common.back() != '=') insert += ' ';  // a whole word: on to the next
  if (!insert.empty()) {
    el_insertstr(el, insert.c_str());
    return CC_REFRESH;
  }
  std::string list;  // several candidates and nothing to add: list them above the line
  for (const std::string& cand : c.candidates) list += (list.empty() ? "" : "  ") + cand;
  print_above(list + "\n");
  return CC_NORM;
}

void ConsoleInput::run_editline() {
  // All libedit calls happen on this thread. libedit reads one key per el_gets() (unbuffered mode),
  // only when poll() says a key is there, so the thread never blocks in libedit and can print the
  // process's output (from out_pipe_) above the line at any time.
  if (!open_editline()) {
    run_plain();
    return;
  }
  while (true) {
    drain_output();
    if (stop_.load() && !out_open_) break;
    take_sigints();
    if (!wait_for_input()) break;
  }
  close_editline();
}

bool ConsoleInput::open_editline() {
  FILE* term = ::fdopen(::dup(term_fd_), "w");
  if (term == nullptr) return false;
  term_file_ = term;
  EditLine* el = el_init("shapeform", stdin, term, term);
  History* hist = history_init();
  if (el == nullptr || hist == nullptr) {
    if (el != nullptr) el_end(el);
    if (hist != nullptr) history_end(hist);
    std::fclose(term);
    term_file_ = nullptr;
    return false;
  }
  el_ = el;
  hist_ = hist;
  HistEvent ev;
  history(hist, &ev, H_SETSIZE, kHistoryMax);
  history(hist, &ev, H_SETUNIQUE, 1);
  if (!options_.history_file.empty()) history(hist, &ev, H_LOAD, options_.history_file.c_str());
  g_prompt.clear();
  el_set(el, EL_SIGNAL, 0);  // our SIGINT handler stays; libedit installs none
  el_set(el, EL_EDITOR, "emacs");
  el_set(el, EL_PROMPT, prompt_fn);
  el_set(el, EL_HIST, history, hist);
  el_set(el, EL_ADDFN, "shapeform-complete", "complete a command, shape or parameter name", tab_fn);
  el_set(el, EL_BIND, "^I", "shapeform-complete", static_cast<const char*>(nullptr));
  el_source(el, nullptr);        // ~/.editrc, as every libedit program
  el_set(el, EL_UNBUFFERED, 1);  // raw terminal, one key per el_gets(); the prompt is still empty
  out_open_ = true;
  return true;
}

void ConsoleInput::close_editline() {
  EditLine* el = editline(el_);
  History* hist = history_of(hist_);
  if (prompt_shown_) erase_edit_area();
  el_set(el, EL_PREP_TERM, 0);  // cooked again
  el_end(el);
  el_ = nullptr;
  if (!options_.history_file.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(std::filesystem::path(options_.history_file).parent_path(), ec);
    HistEvent ev;
    history(hist, &ev, H_SAVE, options_.history_file.c_str());
  }
  history_end(hist);
  hist_ = nullptr;
  std::fclose(static_cast<FILE*>(term_file_));
  term_file_ = nullptr;
}

void ConsoleInput::new_line() {
  el_reset(editline(el_));
  el_set(editline(el_), EL_PREP_TERM, 1);
  prompt_shown_ = false;
  g_prompt.clear();
  at_line_start_ = true;
}

void ConsoleInput::drain_output() {
  char buf[4096];
  std::string got;
  for (;;) {
    const ssize_t n = ::read(out_pipe_[0], buf, sizeof buf);
    if (n > 0) {
      got.append(buf, static_cast<std::size_t>(n));
      continue;
    }
    if (n == 0) out_open_ = false;  // every writer closed: the destructor restored stdout
    if (n < 0 && errno == EINTR) continue;
    break;
  }
  if (!got.empty()) {
    if (partial_.empty()) partial_since_ = std::chrono::steady_clock::now();
    partial_ += got;
  }
  // Whole lines at once; a line without its newline waits a little for the rest.
  const std::size_t nl = partial_.rfind('\n');
  const bool flush_all =
      !out_open_ || !prompt_shown_ || std::chrono::steady_clock::now() - partial_since_ >= kPartialFlush;
  const std::size_t n = flush_all ? partial_.size() : (nl == std::string::npos ? 0 : nl + 1);
  if (n > 0) {
    print_above(std::string_view(partial_).substr(0, n));
    partial_.erase(0, n);
    partial_since_ = std::chrono::steady_clock::now();
  }
}

void ConsoleInput::take_sigints() {
  for (int n = g_sigint_count.exchange(0); n > 0; --n) {
    const LineInfo* li = el_line(editline(el_));
    if (prompt_shown_ && li->lastchar != li->buffer) {  // a line being typed: clear it, go on
      write_term(std::string(li->cursor, li->lastchar) + "^C\n");
      new_line();
      continue;
    }
    write_term(prompt_shown_ || at_line_start_ ? "^C\n" : "\n^C\n");
    new_line();
    const std::lock_guard<std::mutex> lock(mutex_);
    ++interrupts_for_loop_;
  }
}

bool ConsoleInput::wait_for_input() {
  bool want = false;
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    want = !busy_ && lines_.empty() && interrupts_for_loop_ == 0 && !ended_ && !stop_.load();
  }
  if (want != prompt_shown_) show_prompt(want);

  pollfd fds[3] = {
      {out_open_ ? out_pipe_[0] : -1, POLLIN, 0}, {wake_pipe_[0], POLLIN, 0}, {STDIN_FILENO, POLLIN, 0}};
  const nfds_t nfds = prompt_shown_ ? 3 : 2;
  const int timeout = partial_.empty() ? kPollTimeoutMs : 20;
  if (::poll(fds, nfds, timeout) < 0 && errno != EINTR) return false;
  if ((fds[1].revents & POLLIN) != 0) {
    char wake[64];
    while (::read(wake_pipe_[0], wake, sizeof wake) > 0) {
    }
  }
  if (prompt_shown_ && (fds[2].revents & (POLLIN | POLLHUP | POLLERR)) != 0) read_key(fds[2].revents);
  return true;
}

void ConsoleInput::read_key(short revents) {
  int pending = 0;
  if ((revents & POLLIN) == 0 || ::ioctl(STDIN_FILENO, FIONREAD, &pending) != 0 || pending == 0) {
    write_term("\n");  // the terminal hung up: end of input
    new_line();
    set_ended();
    return;
  }
  int count = 0;
  const char* buf = el_gets(editline(el_), &count);
  if (buf == nullptr || count <= 0) return;  // an empty line after this key
  if (count == 1 && buf[0] == '\x04') {      // Ctrl-D on an empty line
    write_term("\n");
    new_line();
    set_ended();
    return;
  }
  if (buf[count - 1] != '\n') return;  // still editing
  std::string text(buf, static_cast<std::size_t>(count - 1));
  bool blank = true;
  for (const char ch : text) blank = blank && (ch == ' ' || ch == '\t');
  HistEvent ev;
  if (!blank) history(history_of(hist_), &ev, H_ENTER, text.c_str());
  new_line();  // libedit has moved to the next row already
  push_lines({std::move(text)});
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
