#pragma once
/// The console's words: a line split into tokens, the declaration of a key=value parameter, and the
/// arguments of one command read and checked against its declared parameters. The registry's parse
/// functions (console_commands.cpp) read their arguments through Args. Pure: no I/O, no clocks, no DDS.
#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/params.hpp"
#include "core/shape.hpp"

namespace shapeform::supervisor {

/// One whitespace-separated word of a line.
struct Token {
  std::string text;  ///< the whole token, quotes stripped
  bool is_pair = false;
  std::string key;    ///< pairs: left of the first unquoted '='
  std::string value;  ///< pairs: right of it, quotes stripped
};

bool is_space(char ch);

/// Splits on whitespace outside double quotes; an unquoted '#' at a token start ends the line.
/// Returns an error message (empty on success).
std::string tokenize(std::string_view line, std::vector<Token>& out);

/// A problem with a line: thrown by the parse functions, turned into ParseResult::error by parse_command.
struct ParseError {
  std::string message;
};
[[noreturn]] void fail(std::string message);

/// The range the command table declares for a config key of core::Command ("shape.r0"): the console's
/// values are bounded exactly as the config file and the command topic. Throws std::logic_error for a
/// key not in the table.
const core::params::Range& field_range(std::string_view key);

/// One key=value parameter of a console command, declared once: the parser checks and bounds it, help
/// writes its syntax, Tab completion offers it.
struct ParamSpec {
  enum class Need {
    Required,  ///< `key=VALUE`
    Optional,  ///< `[key=VALUE]`
    Joined     ///< optional, inside the previous parameter's brackets: `[cx=X cy=Y]`
  };
  std::string key;    ///< as typed: "r"
  std::string value;  ///< how the syntax writes its value: "R", "\"EXPR\"", "X,Y", "on|off"
  Need need = Need::Required;
  /// The command table's key the value sets ("shape.r0"): its range bounds the value and its unit is
  /// the parameter's. Empty for a parameter that is not a field of the command (a timeout).
  std::string field;
  core::params::Range range;  ///< the bounds when `field` is empty
  std::string unit;           ///< the unit when `field` is empty ("" when it has none)

  const core::params::Range& bounds() const;
  /// The unit of the value: the command table's for a field ("shape units", "degrees"), else `unit`.
  std::string unit_name() const;
};

/// Arguments of one command after its command word(s): positionals and key=value pairs.
class Args {
 public:
  /// Checks unknown and duplicate parameters and too many positionals, in token order. `name` is how
  /// the messages name the command ("shape circle"); `params` what it takes.
  Args(std::string name, const std::vector<Token>& tokens, std::size_t first, std::vector<ParamSpec> params,
       std::size_t max_positionals);

  const std::string& name() const { return name_; }
  bool has(const std::string& key) const { return pairs_.count(key) != 0; }
  bool empty() const { return pairs_.empty() && positionals_.empty(); }
  std::size_t positionals() const { return positionals_.size(); }
  const std::string& positional(std::size_t i) const { return positionals_.at(i); }
  /// The declared parameter names, in declaration order.
  std::vector<std::string> keys() const;

  /// A required parameter's text.
  const std::string& raw(const std::string& key) const;
  /// A required number parameter, within its declared bounds.
  double number(const std::string& key) const;
  /// An optional number parameter, within its declared bounds.
  double number_or(const std::string& key, double fallback) const;
  /// Parses `text` as a number named `label` (empty label: the value of the command itself).
  /// The message names the bound broken, as written ("r must be > 0, got -2"; "dt must be <= 10").
  double check_number(const std::string& label, const std::string& text,
                      const core::params::Range& bound) const;
  /// A required `x,y` parameter with finite components.
  core::Vec2 vec2(const std::string& key) const;
  /// An optional on|off parameter.
  bool on_off_or(const std::string& key, bool fallback) const;
  /// Optional centre cx, cy (default 0, 0).
  core::Vec2 centre() const;
  /// A required `x,y;x,y;...` parameter (blanks around numbers allowed; empty text: no points).
  std::vector<core::Vec2> points(const std::string& key) const;
  /// `text` (a positional value) as `x,y` with finite components; `label` names it in the messages
  /// ("safety keep_out add circle: centre must be x,y, got '1'").
  core::Vec2 check_vec2(const std::string& label, const std::string& text) const;
  /// `text` (a positional value) as `x,y;x,y;...`, as points() reads a parameter.
  std::vector<core::Vec2> check_points(const std::string& label, const std::string& text) const;
  /// Optional rotation rot (degrees, default 0) and scale (default 1) of every shape.
  void placement(core::ShapeSpec& s) const;

 private:
  const ParamSpec& declared(const std::string& key) const;

  std::string name_;
  std::vector<ParamSpec> params_;
  std::vector<std::string> positionals_;
  std::map<std::string, std::string> pairs_;
};

}  // namespace shapeform::supervisor
