#pragma once
/// Line sources for the supervisor's command loop: the console (stdin, line-edited with libedit
/// when it is a terminal) and script files. The loop polls one of them each tick; neither blocks.
#include <atomic>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <thread>

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

/// Reads stdin on its own thread into a queue. When stdin and stdout are terminals it uses
/// libedit's readline-compatible callback interface (prompt, line editing, history); otherwise
/// it reads raw lines (pipes, files, /dev/null). libedit is set up with rl_catch_signals = 0, so
/// the application's SIGINT/SIGTERM handlers stay in force; the terminal is restored when the
/// object is destroyed. At most one ConsoleInput may exist at a time.
class ConsoleInput : public LineSource {
 public:
  struct Options {
    std::string prompt = "shapeform> ";
    std::string history_file;  ///< loaded at start, saved at the end; empty: no file
    bool plain = false;        ///< never use libedit, even on a terminal
  };

  /// Starts the reader thread. Throws std::logic_error if another ConsoleInput exists.
  ConsoleInput();
  explicit ConsoleInput(Options options);
  /// Stops the reader thread (within about 0.1 s), restores the terminal, saves history.
  ~ConsoleInput() override;
  ConsoleInput(const ConsoleInput&) = delete;
  ConsoleInput& operator=(const ConsoleInput&) = delete;

  std::optional<std::string> poll() override;
  bool eof() const override;
  /// True when libedit drives a terminal.
  bool interactive() const { return interactive_; }

  /// Called on the reader thread; public only for the C callback.
  void push_line(std::string line);
  void set_ended();

 private:
  bool ended() const;  ///< input ended (lines may still be queued)
  bool queue_empty() const;
  void run();
  void run_plain();
  void run_editline();

  Options options_;
  bool interactive_ = false;
  std::atomic<bool> stop_{false};
  mutable std::mutex mutex_;
  std::deque<std::string> lines_;
  bool ended_ = false;
  std::atomic<std::uint64_t> lines_pushed_{0};
  std::thread thread_;
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
