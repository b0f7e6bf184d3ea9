#include "util/text.hpp"

#include <sstream>

namespace shapeform::util {

namespace {

/// Appends s with its control characters escaped.
void append_escaped(std::string& out, std::string_view s) {
  static constexpr char kHex[] = "0123456789abcdef";
  for (const char ch : s) {
    const auto u = static_cast<unsigned char>(ch);
    if (ch == '\n') {
      out += "\\n";
    } else if (ch == '\r') {
      out += "\\r";
    } else if (ch == '\t') {
      out += "\\t";
    } else if (u < 0x20 || u == 0x7f) {
      out += "\\x";
      out += kHex[u >> 4];
      out += kHex[u & 0xf];
    } else {
      out += ch;
    }
  }
}

}  // namespace

std::string trim(std::string_view s) {
  constexpr std::string_view kBlanks = " \t\r\n\v\f";
  const auto first = s.find_first_not_of(kBlanks);
  if (first == std::string_view::npos) return {};
  const auto last = s.find_last_not_of(kBlanks);
  return std::string(s.substr(first, last - first + 1));
}

std::string format_g10(double v) {
  std::ostringstream os;
  os.precision(10);
  os << v;
  return os.str();
}

std::string excerpt(std::string_view s, std::size_t max) {
  std::string out;
  if (s.size() <= max) {
    out.reserve(s.size());
    append_escaped(out, s);
    return out;
  }
  // The beginning says what the input was, the end often where (a line number, a closing quote).
  const std::size_t tail = max / 4;
  const std::size_t head = max > tail + 30 ? max - tail - 30 : 1;
  append_escaped(out, s.substr(0, head));
  out += " [... " + std::to_string(s.size() - head - tail) + " characters ...] ";
  append_escaped(out, s.substr(s.size() - tail));
  return out;
}

std::string bounded_line(std::string_view line, std::size_t max) {
  return line.size() <= max ? std::string(line) : excerpt(line, max);
}

}  // namespace shapeform::util
