#pragma once
/// Line sources for the supervisor's command loop: the console (stdin, line-edited with libedit
/// when it is a terminal) and script files. The loop polls one of them each tick; neither blocks.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <fstream>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

namespace shapeform::supervisor {

/// Something that yields command lines without blocking.
class LineSource {
 public:
  virtual ~LineSource() = default;
  /// The next complete line (no trailing newline or CR), or nullopt when none is ready yet.
  virtual std::optional<std::string> poll() = 0;
  /// True once the input has ended and every line has been returned by poll().
  virtual bool eof() const = 0;
  /// Where the line last returned by poll() came from ("script.txt:3"); empty for the console.
  virtual std::string location() const { return {}; }
};

/// "LOCATION: message" when the source has a location, else the message unchanged.
std::string with_location(const LineSource& source, std::string_view message);

/// The default history file: $XDG_STATE_HOME/shapeform_history when XDG_STATE_HOME is set, else
/// ~/.shapeform_history ($HOME); empty when neither variable is set.
std::string default_history_file();

/// Reads stdin on its own thread into a queue.
///
/// When stdin and stdout are terminals (interactive) it edits lines with libedit: prompt, Emacs
/// keys, history (kept in a file between runs), Tab completion. Everything the process writes to
/// stdout (and stderr, when it is the same terminal) is then passed through a pipe to this thread,
/// which prints it above the line being typed and redraws that line, so no output ever breaks it.
/// Ctrl-C is a key, not a stop request: it clears a line being typed; on an empty line, or while the
/// loop is busy (a wait, a script), it is counted for the loop (take_interrupts()), which cancels the
/// wait or, on a second press within a second, ends. While the loop is busy the prompt is hidden and
/// keys wait in the terminal. Ctrl-D on an empty line ends the input.
///
/// Otherwise it reads raw lines (pipes, files, /dev/null) and SIGINT keeps its meaning (stop).
/// The terminal and the output descriptors are restored when the object is destroyed. At most one
/// ConsoleInput may exist at a time.
class ConsoleInput : public LineSource {
 public:
  struct Completion {
    std::size_t start = 0;                ///< where the completed word starts in the line
    std::vector<std::string> candidates;  ///< whole replacements of that word
  };
  struct Options {
    std::string prompt = "shapeform> ";
    std::string history_file;  ///< loaded at start, saved at the end; empty: no file
    bool plain = false;        ///< never use libedit, even on a terminal
    /// Tab completion: the candidates for the word that ends the text before the cursor.
    std::function<Completion(std::string_view)> complete;
  };

  /// Starts the reader thread. Throws std::logic_error if another ConsoleInput exists.
  ConsoleInput();
  explicit ConsoleInput(Options options);
  /// Prints what is still in the output pipe, restores stdout/stderr and the terminal, stops the
  /// reader thread, saves history.
  ~ConsoleInput() override;
  ConsoleInput(const ConsoleInput&) = delete;
  ConsoleInput& operator=(const ConsoleInput&) = delete;

  std::optional<std::string> poll() override;
  bool eof() const override;
  /// True when libedit drives a terminal.
  bool interactive() const { return interactive_; }

  /// Interactive: whether the loop is running something (the prompt is hidden meanwhile). The loop
  /// calls it after it has written its answer, so the answer comes before the next prompt.
  void set_busy(bool busy);
  /// Interactive: the Ctrl-C presses the loop must handle since the last call (none otherwise).
  int take_interrupts();

  /// Called on the reader thread; public only for the C callbacks.
  /// Queues lines for the loop at once (it never sees some of them without the others).
  void push_lines(std::vector<std::string> lines);
  void set_ended();
  unsigned char on_tab();

 private:
  bool ended() const;  ///< input ended (lines may still be queued)
  void run();
  void run_plain();
  void run_editline();
  /// libedit on the terminal, history loaded; false when it cannot be set up.
  bool open_editline();
  /// The terminal cooked again, history saved, libedit gone.
  void close_editline();
  /// An empty line buffer, terminal still raw, nothing drawn.
  void new_line();
  /// What the process wrote (out_pipe_), printed above the line: whole lines at once, a line without
  /// its newline after kPartialFlush.
  void drain_output();
  /// Ctrl-C presses: clear a line being typed, or count for the loop.
  void take_sigints();
  /// Shows or hides the prompt, waits for output, a wake-up or a key, reads the key; false when
  /// polling failed.
  bool wait_for_input();
  /// One key into libedit (`revents`: stdin's poll events); a finished line is queued.
  void read_key(short revents);
  void capture_output();
  void restore_output();
  /// Reader thread: prints `text` above the prompt (or plainly while it is hidden).
  void print_above(std::string_view text);
  void erase_edit_area();
  void show_prompt(bool show);
  void write_term(std::string_view text);

  Options options_;
  bool interactive_ = false;
  std::atomic<bool> stop_{false};
  mutable std::mutex mutex_;
  std::deque<std::string> lines_;
  bool ended_ = false;
  bool busy_ = false;
  int interrupts_for_loop_ = 0;
  std::thread thread_;

  // Interactive only.
  int term_fd_ = -1;          ///< the terminal (a dup of the original stdout)
  int saved_err_ = -1;        ///< the original stderr, when it was captured
  int out_pipe_[2] = {-1, -1};  ///< stdout (and stderr) -> reader thread
  int wake_pipe_[2] = {-1, -1};  ///< anything -> reader thread: look at the flags again
  void* term_file_ = nullptr;  ///< FILE* on a dup of term_fd_, libedit's output
  void* el_ = nullptr;        ///< EditLine*
  void* hist_ = nullptr;      ///< History*
  bool prompt_shown_ = false;  ///< the prompt and the line being edited are on the screen
  bool at_line_start_ = true;  ///< the terminal's cursor is at a line start (prompt hidden)
  bool out_open_ = true;       ///< the output pipe still has writers
  std::string partial_;        ///< output without its newline yet
  std::chrono::steady_clock::time_point partial_since_{};  ///< when partial_ began
};

/// Lines of a script file, one per poll() (a script never waits for input). Comments and blank
/// lines are returned too; the parser treats them as no-ops, so line numbers stay right.
class ScriptSource : public LineSource {
 public:
  /// Throws std::runtime_error naming the path when it cannot be opened.
  explicit ScriptSource(const std::filesystem::path& path);

  std::optional<std::string> poll() override;
  bool eof() const override { return !next_.has_value(); }
  /// "PATH:N" for the line last returned (N counts from 1; 0 before the first poll()).
  std::string location() const override;
  int line_number() const { return line_number_; }
  const std::string& path() const { return path_; }

 private:
  void read_ahead();

  std::string path_;
  std::ifstream in_;
  std::optional<std::string> next_;
  int line_number_ = 0;
};

}  // namespace shapeform::supervisor
