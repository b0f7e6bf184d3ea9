#pragma once
/// The preamble every program shares: CLI11 parsing with the project's exit codes, and the config
/// file with its --set overrides (and --domain) loaded through the one loader.
///   app::App app("shapeform_x", "what it does");
///   app.add_config_options();
///   app.cli().add_option(...);                      // the program's own flags
///   if (const auto rc = app.parse(argc, argv)) return *rc;
///   const auto cfg = app.load_config();
///   if (!cfg) return app::kExitUsage;
#include <CLI/CLI.hpp>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "config/config.hpp"

namespace shapeform::app {

/// Exit status of a bad command line or config.
inline constexpr int kExitUsage = 2;

/// Why `dir` cannot be the folder a program writes into, or "" when it can: it is created if missing
/// (as the program would create it) and a probe file is created and removed in it, so a read-only file
/// system, a missing permission or a path under a regular file is found before anything starts, even
/// for root.
std::string writable_dir_problem(const std::string& dir);

/// Why `file` cannot be written, or "": its folder must be writable (writable_dir_problem) and the
/// path, if it exists, a regular file.
std::string writable_file_problem(const std::string& file);

/// An id list as `--ids` takes it ("0-49", "3", "0-9,20-29") -> ids in the order given. False with
/// `error` naming the bad part: not a number or range, outside 0..max_id, an id listed twice, more
/// than max_count ids, or none.
bool parse_id_list(const std::string& text, int max_id, std::size_t max_count, std::vector<std::int32_t>& ids,
                   std::string& error);

/// CLI11 checks for flags that name an output folder or file (`--record DIR`, `--csv FILE`): a bad
/// path is a parse error, exit 2, before the program loads its config or creates a DDS participant.
CLI::Validator writable_dir();
CLI::Validator writable_file();

/// "prog VERSION": the project version and, when built from git, `git describe --always --dirty`
/// ("shapeform_agent 0.1.0 (git 0b3727a-dirty)"). What --version prints.
std::string version_line(const std::string& prog);

class App {
 public:
  App(std::string prog, const std::string& description);

  CLI::App& cli() { return cli_; }
  const std::string& prog() const { return prog_; }

  /// --config PATH (`config_help` describes it), --set key=value (repeatable) and, when
  /// `with_domain`, --domain N (an override of transport.domain).
  void add_config_options(const std::string& config_help = "YAML config (default: built-in defaults)",
                          bool with_domain = true);

  /// Parses argv. nullopt: go on. Otherwise the exit status to return at once: 0 after --help or
  /// --version (printed), 2 after a parse error (printed on stderr as "prog: message").
  std::optional<int> parse(int argc, char** argv);

  /// Loads the config: the --config file with the --set overrides, then --domain, then `extra`
  /// (program flags that override keys, e.g. "swarm.seed=3"). Problems go to stderr, one per line,
  /// as "prog: problem"; nullopt then (exit status kExitUsage).
  std::optional<config::Config> load_config(const std::vector<std::string>& extra = {}) const;

  /// Runs the program's body: its exit status, or 1 (a runtime failure) after printing
  /// "prog: what" on stderr when it throws.
  int run(const std::function<int()>& body) const;

  /// Prints "prog: message" on stderr and returns kExitUsage.
  int usage_error(const std::string& message) const;

  /// Whether the flag (an option of this program) was given on the command line.
  bool given(const std::string& flag) const { return cli_.count(flag) > 0; }

 private:
  std::string prog_;
  CLI::App cli_;
  std::string config_path_;
  std::vector<std::string> sets_;
  int domain_ = -1;
  CLI::Option* domain_option_ = nullptr;  ///< --domain, when the program takes it
};

}  // namespace shapeform::app
