#include "dds/library_log.hpp"

#include <algorithm>
#include <cstdlib>
#include <memory>
#include <mutex>
#include <string>

#include <fastdds/dds/log/Log.hpp>

#include "util/log.hpp"

namespace shapeform::dds {
namespace {

namespace fdds = eprosima::fastdds::dds;

std::mutex refusals_mutex;
std::vector<SourceId> refusals;  ///< guarded by refusals_mutex

/// Parses "xx.xx. ... .xx" (12 hex bytes) at the start of text.
std::optional<SourceId> parse_prefix(std::string_view text) {
  SourceId s;
  std::size_t pos = 0;
  for (std::size_t i = 0; i < s.prefix.size(); ++i) {
    if (pos + 2 > text.size()) return std::nullopt;
    const std::string byte(text.substr(pos, 2));
    char* end = nullptr;
    const unsigned long v = std::strtoul(byte.c_str(), &end, 16);
    if (end != byte.c_str() + 2) return std::nullopt;
    s.prefix[i] = static_cast<std::uint8_t>(v);
    pos += 2;
    if (i + 1 < s.prefix.size()) {
      if (pos >= text.size() || text[pos] != '.') return std::nullopt;
      ++pos;
    }
  }
  return s;
}

class Consumer final : public fdds::LogConsumer {
 public:
  void Consume(const fdds::Log::Entry& entry) override {
    if (const auto refused = permission_refusal(entry.message)) {
      std::lock_guard<std::mutex> lock(refusals_mutex);
      if (std::find(refusals.begin(), refusals.end(), *refused) == refusals.end()) refusals.push_back(*refused);
    }
    const std::string category = entry.context.category != nullptr ? entry.context.category : "?";
    const util::LogLevel level = entry.kind == fdds::Log::Kind::Error ? util::LogLevel::Error : util::LogLevel::Warn;
    // A rogue participant retries its handshake every 0.5 s: the same message once per 5 s is enough.
    throttled_.log(level, category + entry.message.substr(0, 60), "fastdds " + category + ": " + entry.message);
  }

 private:
  util::ThrottledLog throttled_{5.0};
};

}  // namespace

std::optional<SourceId> permission_refusal(std::string_view message) {
  for (const std::string_view marker : {std::string_view("Error validating remote permissions for "),
                                        std::string_view("Error checking remote participant")}) {
    const auto at = message.find(marker);
    if (at == std::string_view::npos) continue;
    std::string_view rest = message.substr(at + marker.size());
    while (!rest.empty() && rest.front() == ' ') rest.remove_prefix(1);
    return parse_prefix(rest);
  }
  return std::nullopt;
}

std::vector<SourceId> take_permission_refusals() {
  std::lock_guard<std::mutex> lock(refusals_mutex);
  std::vector<SourceId> out;
  out.swap(refusals);
  return out;
}

void route_library_log() {
  static std::once_flag once;
  std::call_once(once, [] {
    fdds::Log::ClearConsumers();
    fdds::Log::RegisterConsumer(std::make_unique<Consumer>());
    fdds::Log::SetVerbosity(fdds::Log::Kind::Error);  // its default: warnings stay off
  });
}

}  // namespace shapeform::dds
