#include "console_input.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <cstdlib>
#include <optional>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "console_parser.hpp"

using namespace shapeform;
using namespace shapeform::supervisor;
namespace fs = std::filesystem;

namespace {

fs::path temp_file(const std::string& name, const std::string& content) {
  const fs::path p = fs::temp_directory_path() /
                     ("shapeform_console_test_" + std::to_string(::getpid()) + "_" + name);
  std::ofstream(p, std::ios::binary) << content;
  return p;
}

/// Replaces stdin (fd 0) with the read end of a pipe for the object's lifetime.
class StdinPipe {
 public:
  StdinPipe() {
    int fds[2];
    REQUIRE(::pipe(fds) == 0);
    saved_ = ::dup(STDIN_FILENO);
    REQUIRE(saved_ >= 0);
    REQUIRE(::dup2(fds[0], STDIN_FILENO) == STDIN_FILENO);
    ::close(fds[0]);
    write_fd_ = fds[1];
  }
  ~StdinPipe() {
    close_writer();
    ::dup2(saved_, STDIN_FILENO);
    ::close(saved_);
  }
  void write(const std::string& s) const {
    REQUIRE(::write(write_fd_, s.data(), s.size()) == static_cast<ssize_t>(s.size()));
  }
  void close_writer() {
    if (write_fd_ >= 0) ::close(write_fd_);
    write_fd_ = -1;
  }

 private:
  int saved_ = -1;
  int write_fd_ = -1;
};

/// Polls until n lines arrived or 5 s passed.
std::vector<std::string> collect(LineSource& src, std::size_t n) {
  std::vector<std::string> lines;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (lines.size() < n && std::chrono::steady_clock::now() < deadline) {
    if (auto line = src.poll()) {
      lines.push_back(*line);
    } else {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }
  return lines;
}

bool wait_eof(const LineSource& src) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (!src.eof() && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return src.eof();
}

}  // namespace

TEST_CASE("script source: lines with numbers, CR stripped, eof", "[supervisor][input]") {
  const fs::path p =
      temp_file("script.txt", "\xEF\xBB\xBFshape circle r=2\r\n\n# c\nshape circle\n");
  ScriptSource src(p);
  CHECK(src.line_number() == 0);
  CHECK_FALSE(src.eof());
  CHECK(src.poll() == std::optional<std::string>("shape circle r=2"));
  CHECK(src.location() == p.string() + ":1");
  CHECK(src.poll() == std::optional<std::string>(""));
  CHECK(src.poll() == std::optional<std::string>("# c"));
  CHECK_FALSE(src.eof());
  const auto line = src.poll();
  REQUIRE(line);
  CHECK(src.eof());  // the last line has been returned
  CHECK(src.line_number() == 4);
  const ParseResult r = parse_command(*line, core::CompiledCommand{});
  CHECK(with_location(src, r.error) == p.string() + ":4: shape circle: missing parameter r");
  CHECK_FALSE(src.poll());
  CHECK(src.eof());
  fs::remove(p);
}

TEST_CASE("script source: last line without newline; empty file", "[supervisor][input]") {
  const fs::path p = temp_file("nonl.txt", "status\nquit");
  ScriptSource src(p);
  CHECK(src.poll() == std::optional<std::string>("status"));
  CHECK(src.poll() == std::optional<std::string>("quit"));
  CHECK(src.eof());
  fs::remove(p);

  const fs::path e = temp_file("empty.txt", "");
  ScriptSource empty(e);
  CHECK(empty.eof());
  CHECK_FALSE(empty.poll());
  fs::remove(e);
}

TEST_CASE("script source: a missing file throws naming it", "[supervisor][input]") {
  CHECK_THROWS_WITH(ScriptSource("/nonexistent/dir/script.txt"),
                    "cannot open script /nonexistent/dir/script.txt");
}

TEST_CASE("console input: plain lines from a pipe, then eof", "[supervisor][input]") {
  StdinPipe pipe;
  ConsoleInput::Options opt;
  opt.plain = true;
  ConsoleInput console(opt);
  CHECK_FALSE(console.interactive());
  CHECK(console.location().empty());
  CHECK(with_location(console, "oops") == "oops");
  CHECK_FALSE(console.poll());
  CHECK_FALSE(console.eof());

  pipe.write("status\r\nshape circle");
  pipe.write(" r=2\n\n");
  CHECK(collect(console, 3) == std::vector<std::string>{"status", "shape circle r=2", ""});
  CHECK_FALSE(console.eof());

  pipe.write("quit");  // no newline: delivered at end of input
  pipe.close_writer();
  CHECK(collect(console, 1) == std::vector<std::string>{"quit"});
  CHECK(wait_eof(console));
  CHECK_FALSE(console.poll());
}

TEST_CASE("console input: lines stay queued until polled at eof", "[supervisor][input]") {
  StdinPipe pipe;
  ConsoleInput::Options opt;
  opt.plain = true;
  ConsoleInput console(opt);
  pipe.write("a\nb\n");
  pipe.close_writer();
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  CHECK_FALSE(console.eof());  // two lines still queued
  CHECK(collect(console, 2) == std::vector<std::string>{"a", "b"});
  CHECK(console.eof());
}

TEST_CASE("console input: destruction does not wait for input; one at a time",
          "[supervisor][input]") {
  StdinPipe pipe;  // never written: the reader thread must still stop
  ConsoleInput::Options opt;
  opt.plain = true;
  const auto t0 = std::chrono::steady_clock::now();
  {
    ConsoleInput console(opt);
    CHECK_THROWS_AS(ConsoleInput(opt), std::logic_error);
  }
  CHECK(std::chrono::steady_clock::now() - t0 < std::chrono::seconds(5));
  ConsoleInput again(opt);  // the slot is free again
  CHECK_FALSE(again.eof());
}

TEST_CASE("the history file: XDG_STATE_HOME, else HOME", "[supervisor][console]") {
  const char* old_state = std::getenv("XDG_STATE_HOME");
  const char* old_home = std::getenv("HOME");
  const std::string saved_state = old_state ? old_state : "";
  const std::string saved_home = old_home ? old_home : "";
  ::setenv("XDG_STATE_HOME", "/tmp/state", 1);
  ::setenv("HOME", "/home/op", 1);
  CHECK(default_history_file() == "/tmp/state/shapeform_history");
  ::unsetenv("XDG_STATE_HOME");
  CHECK(default_history_file() == "/home/op/.shapeform_history");
  ::unsetenv("HOME");
  CHECK(default_history_file().empty());
  if (old_state) ::setenv("XDG_STATE_HOME", saved_state.c_str(), 1);
  if (old_home) ::setenv("HOME", saved_home.c_str(), 1);
}

TEST_CASE("without a terminal Ctrl-C and busy are not the console's", "[supervisor][console]") {
  StdinPipe in;
  ConsoleInput console(ConsoleInput::Options{"> ", "", false, {}});
  CHECK_FALSE(console.interactive());
  console.set_busy(true);  // no effect, no prompt to hide
  CHECK(console.take_interrupts() == 0);
  in.write("status\n");
  in.close_writer();
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  std::optional<std::string> line;
  while (!line && std::chrono::steady_clock::now() < deadline) {
    line = console.poll();
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  CHECK(line == std::optional<std::string>("status"));
}
