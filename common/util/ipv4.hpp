#pragma once
/// The project's one IPv4 literal parser (config loader, transport validation, participant factory).
#include <array>
#include <cstdint>
#include <string_view>

namespace shapeform::util {

/// Strict dotted quad ("127.0.0.1"): four decimal parts 0..255, no leading zeros (which some
/// parsers read as octal), nothing else. False for anything else; `octets` is then unspecified.
bool parse_ipv4(std::string_view text, std::array<std::uint8_t, 4>& octets);

/// parse_ipv4 without the octets.
bool is_ipv4(std::string_view text);

}  // namespace shapeform::util
