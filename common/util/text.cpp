#include "util/text.hpp"

#include <sstream>
#include <stdexcept>

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

std::string regenerate_blocks(std::string_view text, std::string_view begin, std::string_view end,
                              const std::function<std::string(const std::string& section)>& generate) {
  std::string out;
  std::size_t pos = 0;
  for (;;) {
    const std::size_t at = text.find(begin, pos);
    if (at == std::string_view::npos) break;
    const std::size_t line_end = text.find('\n', at);
    if (line_end == std::string_view::npos) throw std::invalid_argument("no line after the marker " + std::string(begin));
    std::string section = trim(text.substr(at + begin.size(), line_end - at - begin.size()));
    if (section.size() >= 3 && section.compare(section.size() - 3, 3, "-->") == 0)
      section = trim(section.substr(0, section.size() - 3));
    if (section.empty()) throw std::invalid_argument("no section name after the marker " + std::string(begin));
    const std::size_t close = text.find(end, line_end);
    if (close == std::string_view::npos)
      throw std::invalid_argument("no " + std::string(end) + " after the block of " + section);
    out += text.substr(pos, line_end + 1 - pos);
    out += generate(section);
    pos = text.rfind('\n', close) + 1;  // the end marker's whole line stays
  }
  out += text.substr(pos);
  return out;
}

}  // namespace shapeform::util
