#include "util/text.hpp"

#include <sstream>

namespace shapeform::util {

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

}  // namespace shapeform::util
