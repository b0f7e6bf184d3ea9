#include "foxglove_protocol.hpp"

#include <algorithm>
#include <nlohmann/json.hpp>

namespace shapeform::view::foxglove {

using nlohmann::json;

std::optional<std::string> choose_subprotocol(const std::vector<std::string>& requested) {
  for (const std::string& r : requested) {
    for (const std::string_view s : kSubprotocols) {
      if (r == s) return r;
    }
  }
  return std::nullopt;
}

std::string server_info_json(std::string_view name, std::string_view session_id) {
  return json{{"op", "serverInfo"},
              {"name", name},
              {"capabilities", json::array()},
              {"supportedEncodings", json::array()},
              {"metadata", json::object()},
              {"sessionId", session_id}}
      .dump();
}

std::string advertise_json(const std::vector<AdvertisedChannel>& channels) {
  json list = json::array();
  for (const auto& a : channels) {
    list.push_back({{"id", a.id},
                    {"topic", a.channel.topic},
                    {"encoding", a.channel.message_encoding},
                    {"schemaName", a.channel.schema_name},
                    {"schema", a.channel.schema},
                    {"schemaEncoding", a.channel.schema_encoding}});
  }
  return json{{"op", "advertise"}, {"channels", std::move(list)}}.dump();
}

std::string status_json(StatusLevel level, std::string_view message) {
  return json{{"op", "status"}, {"level", static_cast<int>(level)}, {"message", message}}.dump();
}

std::string message_data(std::uint32_t subscription_id, std::uint64_t stamp_ns, std::string_view payload) {
  std::string out;
  out.reserve(kMessageDataHeader + payload.size());
  out.push_back(static_cast<char>(0x01));
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>((subscription_id >> (8 * i)) & 0xFFu));
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<char>((stamp_ns >> (8 * i)) & 0xFFu));
  out.append(payload);
  return out;
}

namespace {

bool as_u32(const json& v, std::uint32_t& out) {
  if (!v.is_number_unsigned() && !(v.is_number_integer() && v.get<std::int64_t>() >= 0)) return false;
  const auto x = v.get<std::uint64_t>();
  if (x > 0xFFFFFFFFu) return false;
  out = static_cast<std::uint32_t>(x);
  return true;
}

}  // namespace

ClientOp parse_client_op(std::string_view text) {
  ClientOp r;
  const json j = json::parse(text, nullptr, false);
  if (j.is_discarded() || !j.is_object()) {
    r.error = "not a JSON object";
    return r;
  }
  if (!j.contains("op") || !j["op"].is_string()) {
    r.error = "no \"op\" string";
    return r;
  }
  r.op = j["op"].get<std::string>();
  if (r.op == "subscribe") {
    if (!j.contains("subscriptions") || !j["subscriptions"].is_array()) {
      r.error = "subscribe: \"subscriptions\" must be an array of {\"id\", \"channelId\"}";
      return r;
    }
    for (const auto& s : j["subscriptions"]) {
      std::uint32_t id = 0, channel = 0;
      if (!s.is_object() || !s.contains("id") || !s.contains("channelId") || !as_u32(s["id"], id) ||
          !as_u32(s["channelId"], channel)) {
        r.error = "subscribe: each subscription must be {\"id\": uint32, \"channelId\": uint32}, got " +
                  s.dump().substr(0, 80);
        return r;
      }
      r.subscribe.emplace_back(id, channel);
    }
    r.kind = ClientOp::Kind::Subscribe;
  } else if (r.op == "unsubscribe") {
    if (!j.contains("subscriptionIds") || !j["subscriptionIds"].is_array()) {
      r.error = "unsubscribe: \"subscriptionIds\" must be an array of uint32";
      return r;
    }
    for (const auto& s : j["subscriptionIds"]) {
      std::uint32_t id = 0;
      if (!as_u32(s, id)) {
        r.error = "unsubscribe: subscription ids must be uint32, got " + s.dump().substr(0, 40);
        return r;
      }
      r.unsubscribe.push_back(id);
    }
    r.kind = ClientOp::Kind::Unsubscribe;
  } else {
    r.kind = ClientOp::Kind::Unsupported;
  }
  return r;
}

std::vector<std::string> Subscriptions::subscribe(
    const std::vector<std::pair<std::uint32_t, std::uint32_t>>& subs,
    const std::vector<AdvertisedChannel>& channels) {
  std::vector<std::string> problems;
  for (const auto& [id, channel] : subs) {
    const bool known =
        std::any_of(channels.begin(), channels.end(), [&](const auto& a) { return a.id == channel; });
    if (!known) {
      problems.push_back("subscription " + std::to_string(id) + ": channel " + std::to_string(channel) +
                         " is not advertised");
    } else if (by_id_.count(id) != 0) {
      problems.push_back("subscription " + std::to_string(id) + ": the id is already in use (channel " +
                         std::to_string(by_id_[id]) + "); unsubscribe it first");
    } else {
      by_id_[id] = channel;
    }
  }
  return problems;
}

std::vector<std::string> Subscriptions::unsubscribe(const std::vector<std::uint32_t>& ids) {
  std::vector<std::string> problems;
  for (const std::uint32_t id : ids) {
    if (by_id_.erase(id) == 0) problems.push_back("unsubscribe: no subscription " + std::to_string(id));
  }
  return problems;
}

std::vector<std::uint32_t> Subscriptions::of_channel(std::uint32_t channel_id) const {
  std::vector<std::uint32_t> out;
  for (const auto& [id, ch] : by_id_) {
    if (ch == channel_id) out.push_back(id);
  }
  return out;
}

std::size_t Subscriptions::count(std::uint32_t channel_id) const {
  return static_cast<std::size_t>(
      std::count_if(by_id_.begin(), by_id_.end(), [&](const auto& e) { return e.second == channel_id; }));
}

}  // namespace shapeform::view::foxglove
