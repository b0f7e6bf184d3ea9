#pragma once
/// shapeform_view's Foxglove WebSocket server (foxglove/ws-protocol; websocketpp on standalone asio, on
/// its own thread): read-only, it advertises a fixed list of channels to every client, sends each
/// message only to the clients subscribed to its channel, and never stalls the caller: a client whose
/// socket has more than `max_buffered_bytes` queued misses messages (counted) until it catches up.
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "foxglove_protocol.hpp"

namespace shapeform::view {

class FoxgloveServer {
 public:
  /// channels[i] gets id i + 1. max_buffered_bytes: a client with more queued is skipped.
  explicit FoxgloveServer(std::vector<viz::Channel> channels, std::size_t max_buffered_bytes = 8u << 20);
  ~FoxgloveServer();
  FoxgloveServer(const FoxgloveServer&) = delete;
  FoxgloveServer& operator=(const FoxgloveServer&) = delete;

  /// Listens on bind:port (port 0: a free one) and serves on a thread of its own. Returns the port.
  /// Throws std::runtime_error naming the address when it cannot listen.
  int start(const std::string& bind, int port);
  /// Closes every connection (going away) and ends the thread. Idempotent.
  void stop();

  /// Whether any client is subscribed to channel `index` (an index of the constructor's list): the
  /// caller serializes a message only when someone will receive it.
  bool subscribed(std::size_t index) const;
  /// Sends payload on channel `index`, stamped stamp_ns (ns since the Unix epoch), to each subscription
  /// of it. Thread-safe, never blocks on a client: the sending happens on the server's thread.
  void publish(std::size_t index, std::uint64_t stamp_ns, std::string payload);

  struct Stats {
    std::uint64_t clients = 0;           ///< connected now
    std::uint64_t connections = 0;       ///< accepted since start
    std::uint64_t messages_sent = 0;     ///< message data frames handed to sockets
    std::uint64_t messages_dropped = 0;  ///< not sent to a client that was too far behind
    std::uint64_t bytes_sent = 0;
  };
  Stats stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace shapeform::view
