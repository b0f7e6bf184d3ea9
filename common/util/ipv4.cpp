#include "util/ipv4.hpp"

namespace shapeform::util {

bool parse_ipv4(std::string_view text, std::array<std::uint8_t, 4>& octets) {
  std::size_t pos = 0;
  for (std::size_t i = 0; i < 4; ++i) {
    if (i > 0) {
      if (pos >= text.size() || text[pos] != '.') return false;
      ++pos;
    }
    const std::size_t start = pos;
    unsigned value = 0;
    while (pos < text.size() && text[pos] >= '0' && text[pos] <= '9' && pos - start < 3) {
      value = value * 10 + static_cast<unsigned>(text[pos] - '0');
      ++pos;
    }
    if (pos == start || value > 255) return false;
    if (pos - start > 1 && text[start] == '0') return false;  // no leading zeros (octal ambiguity)
    octets[i] = static_cast<std::uint8_t>(value);
  }
  return pos == text.size();
}

bool is_ipv4(std::string_view text) {
  std::array<std::uint8_t, 4> ignored{};
  return parse_ipv4(text, ignored);
}

}  // namespace shapeform::util
