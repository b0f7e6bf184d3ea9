#pragma once
/// The supervisor's console language: one line in, one action (or one error line) out; its help and
/// Tab completion. All of it is derived from the command registry (console_commands.hpp).
/// Pure: no I/O, no clocks, no DDS. The main loop executes the actions.
///
/// Syntax: a command word (sometimes two: `shape circle`, `wait agents`), then positional values
/// and key=value parameters in any order. Tokens split on whitespace except inside double quotes;
/// quotes are stripped (`r="4 + 1"` gives key r, value `4 + 1`). A token starting with `#`
/// (outside quotes) starts a comment; blank and comment-only lines are no-ops.
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "actions.hpp"
#include "core/compiled_command.hpp"

namespace shapeform::supervisor {

/// Either an action (error empty) or an error (action is NoOp).
struct ParseResult {
  Action action;
  std::string error;  ///< one line naming the command and what is wrong, e.g.
                      ///< `shape circle: r must be > 0, got -2`; empty on success
  bool ok() const { return error.empty(); }
};

/// Parses one console or script line. `current` is the command in force; commands that change it
/// return a copy of it with the change applied. Never throws for bad input.
ParseResult parse_command(std::string_view line, const core::CompiledCommand& current);

/// Help text: with an empty `command`, one line per command with its syntax; with a command word
/// (`shape`, `track`, `gains`, ...), the details of that command. Unknown words give a line saying
/// so. Every returned text ends with a newline.
std::string help_text(std::string_view command = {});

/// True when `help_text(word)` has a details page for `word`.
bool has_help(std::string_view word);

/// The command words (`shape`, `wait`, `quit`, `exit`, ...), in help order.
std::vector<std::string> command_words();

/// Tab completion of the word that ends `before_cursor` (the line up to the cursor): command words,
/// second words (shape kinds, track paths, wait conditions, record start/stop), positional values
/// (law and integrator names, help topics, progress modes) and parameter names, offered as "key=".
struct Completion {
  std::size_t start = 0;                ///< where the word being completed starts in the line
  std::vector<std::string> candidates;  ///< whole replacements for the word, sorted
};
Completion complete(std::string_view before_cursor);

}  // namespace shapeform::supervisor
