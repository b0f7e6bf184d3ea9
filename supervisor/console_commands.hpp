#pragma once
/// The console's commands, declared once: one entry per command word with its forms (second words),
/// their parameters (each bound to its command-table key and unit), their help text and the function
/// that turns the arguments into an Action. The parser, `help`, Tab completion and the checks of the
/// tests are all derived from this table (console_parser.cpp); the Executor runs the Actions.
#include <cstddef>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "actions.hpp"
#include "console_args.hpp"
#include "core/compiled_command.hpp"

namespace shapeform::supervisor {

/// Turns a form's checked arguments into its Action; `current` is the command in force (a command
/// that changes it returns a copy with the change applied). Reports problems with fail().
using ParseFn = std::function<Action(const Args& args, const core::CompiledCommand& current)>;

/// One way of calling a command: `shape circle`, `wait agents`, or the command alone (`gains`).
struct FormSpec {
  std::string sub;  ///< the second word ("circle"); empty when the command has none
  /// The positional part of each syntax line, one per line of its help page ("N", "euler|rk4",
  /// "[json]"; {""} when it takes none); its key=value parameters follow the last. Lower-case words
  /// are literal values (Tab offers them), upper-case ones placeholders.
  std::vector<std::string> usages = {""};
  std::vector<ParamSpec> params;  ///< its own key=value parameters (the command's shared ones follow)
  /// The overview's description. Empty: the form shares the previous form's overview line.
  std::string summary;
  ParseFn parse;

  /// How many positional values it takes at most (the most words in one usage).
  std::size_t max_positionals() const;
  /// The literal values of its usages ("json"; "on", "off", "every"), for Tab completion.
  std::vector<std::string> values() const;
};

/// One command word, its forms and its help page.
struct CommandSpec {
  std::string word;                  ///< "shape"
  std::vector<std::string> aliases;  ///< other words for the same command ("exit")
  /// Commands with second words: what the second word names ("shape", "path"), and the text of the
  /// error when it is missing ("a shape (line, circle, ...)").
  std::string noun;
  std::string expected;
  std::vector<ParamSpec> shared;  ///< key=value parameters every form takes (shape: rot, scale)
  std::string shared_summary;     ///< the overview's description of those
  std::vector<FormSpec> forms;
  std::string details;           ///< `help WORD` after the syntax lines (indented lines)
  bool offers_commands = false;  ///< Tab offers the command words as its value (help)
  /// The form the command word alone is (`safety` is `safety show`); empty: a command with second
  /// words needs one.
  std::string bare;

  bool has_sub() const { return !forms.empty() && !forms.front().sub.empty(); }
  /// The form of second word `sub` (the only form when the command has no second word); null if none.
  const FormSpec* form(std::string_view sub) const;
  /// The words a form is typed with ("shape circle", "gains").
  std::string words(const FormSpec& f) const;
  /// The form's own parameters, then the shared ones: every key it takes.
  std::vector<ParamSpec> params(const FormSpec& f) const;
};

/// Every console command, in help order.
const std::vector<CommandSpec>& command_specs();

/// The command typed as `word` (its word or an alias), or null.
const CommandSpec* find_command(std::string_view word);

}  // namespace shapeform::supervisor
