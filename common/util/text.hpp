#pragma once
/// Small text helpers shared by the config loader, the console, the conversions and the simulator.
#include <string>
#include <string_view>

namespace shapeform::util {

/// s without leading and trailing whitespace (space, \t, \r, \n, \v, \f).
std::string trim(std::string_view s);

/// v with 10 significant digits, as an ostream writes it ("0.1", "1e+300", "nan"): for messages and CSV.
std::string format_g10(double v);

}  // namespace shapeform::util
