#pragma once
/// The pure pieces of the Foxglove WebSocket protocol (foxglove/ws-protocol, docs/spec.md) as
/// shapeform_view serves it, read-only: the subprotocol chosen, the server's JSON messages (serverInfo,
/// advertise, status), the binary "message data" frame, the client's ops parsed, and one client's
/// subscriptions. No socket here (view/foxglove_server.cpp is the wiring).
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "viz/scene_update.hpp"

namespace shapeform::view::foxglove {

/// The subprotocols accepted, the current first: Foxglove's SDK clients ask for "foxglove.sdk.v1",
/// older ones (Lichtblick, @foxglove/ws-protocol) for "foxglove.websocket.v1".
inline constexpr std::string_view kSubprotocols[] = {"foxglove.sdk.v1", "foxglove.websocket.v1"};

/// The subprotocol to answer with: the first of `requested` (the client's order of preference) that is
/// one of kSubprotocols; nullopt when none is (the connection is refused).
std::optional<std::string> choose_subprotocol(const std::vector<std::string>& requested);

/// A channel as advertised: its id (>= 1, unique for the server's lifetime) and definition.
struct AdvertisedChannel {
  std::uint32_t id = 0;
  viz::Channel channel;
};

/// {"op":"serverInfo", "name", "capabilities": [] (read-only: no clientPublish, no parameters, no
/// services), "supportedEncodings": [], "metadata": {}, "sessionId"}.
std::string server_info_json(std::string_view name, std::string_view session_id);

/// {"op":"advertise","channels":[{"id","topic","encoding","schemaName","schema","schemaEncoding"}]}.
std::string advertise_json(const std::vector<AdvertisedChannel>& channels);

enum class StatusLevel { Info = 0, Warning = 1, Error = 2 };
/// {"op":"status","level","message"}.
std::string status_json(StatusLevel level, std::string_view message);

/// The binary "message data" frame: opcode 0x01, u32 LE subscription id, u64 LE timestamp (ns), payload.
std::string message_data(std::uint32_t subscription_id, std::uint64_t stamp_ns, std::string_view payload);
inline constexpr std::size_t kMessageDataHeader = 13;

/// A client's text message, parsed.
struct ClientOp {
  enum class Kind {
    Subscribe,    ///< `subscribe`: (subscription id, channel id) pairs
    Unsubscribe,  ///< `unsubscribe`: subscription ids
    Unsupported,  ///< a well-formed op this server does not serve (`op` names it)
    Invalid,      ///< not JSON, no "op", or fields of the wrong type (`error` says what)
  };
  Kind kind = Kind::Invalid;
  std::string op;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> subscribe;
  std::vector<std::uint32_t> unsubscribe;
  std::string error;
};
ClientOp parse_client_op(std::string_view text);

/// One client's subscriptions: subscription id -> channel id.
class Subscriptions {
 public:
  /// Adds each (subscription id, channel id) whose channel is in `channels` and whose id is not in use;
  /// returns a sentence for each refused one ("subscription 3: channel 99 is not advertised").
  std::vector<std::string> subscribe(const std::vector<std::pair<std::uint32_t, std::uint32_t>>& subs,
                                     const std::vector<AdvertisedChannel>& channels);
  /// Removes each id; returns a sentence for each unknown one.
  std::vector<std::string> unsubscribe(const std::vector<std::uint32_t>& ids);
  /// The subscription ids of channel `channel_id` (a client may subscribe to one channel twice).
  std::vector<std::uint32_t> of_channel(std::uint32_t channel_id) const;
  /// How many subscriptions name channel_id.
  std::size_t count(std::uint32_t channel_id) const;
  std::size_t size() const { return by_id_.size(); }

 private:
  std::map<std::uint32_t, std::uint32_t> by_id_;
};

}  // namespace shapeform::view::foxglove
