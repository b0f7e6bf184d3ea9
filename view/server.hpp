#pragma once
/// The viewer's HTTP side (cpp-httplib): the page and its script and style (embedded in the binary at
/// build time from view/web/), the frames as Server-Sent Events, the newest frame as JSON, and the
/// replay's controls. Every request is served on httplib's threads; the loop only publishes frames.
#include <functional>
#include <memory>
#include <string>
#include <thread>

#include "frame_bus.hpp"

namespace httplib {
class Server;
}

namespace shapeform::view {

/// A replay control request (action "play", "pause", "speed" or "seek", value its number): "" when
/// done, else why not (answered 400). Live, no controls exist (answered 404).
using ControlHandler = std::function<std::string(const std::string& action, double value)>;

class WebServer {
 public:
  /// GET / (the page), /view.js, /view.css, /events (text/event-stream: one "data: FRAME" event per
  /// frame: a snapshot, then deltas; FrameBus::wait_newer), /frame (a snapshot of the newest frame);
  /// POST /control?action=A&value=V when `control` is set.
  WebServer(FrameBus& bus, ControlHandler control);
  ~WebServer();  ///< stop()
  WebServer(const WebServer&) = delete;
  WebServer& operator=(const WebServer&) = delete;

  /// Binds addr:port (port 0: a free port) and serves on a thread of its own; returns the port.
  /// Throws std::runtime_error naming the address when it cannot bind.
  int start(const std::string& addr, int port);
  /// Ends the streams and the server; joins its thread.
  void stop();

 private:
  FrameBus& bus_;
  std::unique_ptr<httplib::Server> server_;
  std::thread thread_;
};

}  // namespace shapeform::view
