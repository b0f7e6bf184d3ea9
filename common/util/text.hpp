#pragma once
/// Small text helpers shared by the config loader and the console.
#include <string>
#include <string_view>

namespace shapeform::util {

/// s without leading and trailing whitespace (space, \t, \r, \n, \v, \f).
std::string trim(std::string_view s);

}  // namespace shapeform::util
