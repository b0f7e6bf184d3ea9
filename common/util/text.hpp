#pragma once
/// Small text helpers shared by the config loader, the console, the conversions and the simulator.
#include <cstddef>
#include <functional>
#include <string>
#include <string_view>

namespace shapeform::util {

/// s without leading and trailing whitespace (space, \t, \r, \n, \v, \f).
std::string trim(std::string_view s);

/// v with 10 significant digits, as an ostream writes it ("0.1", "1e+300", "nan"): for messages and CSV.
std::string format_g10(double v);

/// How much of one piece of untrusted input (a console token, a YAML value or key, a flag, a string
/// received over DDS) an error line quotes, in characters.
inline constexpr std::size_t kQuoteMax = 200;
/// How long any one error or log line may get, in characters (a line quotes its input with
/// excerpt(), and the whole line is bounded again with excerpt(line, kLineMax) where it is printed).
inline constexpr std::size_t kLineMax = 400;

/// Untrusted text as an error line may show it: control characters escaped (\n, \r, \t, \xNN) so one
/// problem stays one line, and when longer than max characters, its beginning and its end around
/// " [... N characters ...] " (the result is then about max characters long). The one helper every
/// place that quotes input uses, so that a 1 MB line is never echoed.
std::string excerpt(std::string_view s, std::size_t max = kQuoteMax);

/// A message line as it is when at most max characters long, else excerpt(line, max): the last guard
/// where a line that may quote input is printed.
std::string bounded_line(std::string_view line, std::size_t max = kLineMax);

/// A file with generated blocks (a doc's tables, a script's rules), each regenerated in place: every line
/// holding `begin` followed by a section name (the rest of the line, a trailing "-->" dropped) opens a
/// block that ends at the next line holding `end`. Returns text with each block's lines in between
/// replaced by generate(section); the marker lines and everything outside the blocks stay as they are.
/// Throws std::invalid_argument when a block has no end or no section name; whatever generate throws.
std::string regenerate_blocks(std::string_view text, std::string_view begin, std::string_view end,
                              const std::function<std::string(const std::string& section)>& generate);

}  // namespace shapeform::util
