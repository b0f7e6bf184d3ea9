#include "server.hpp"

#include <stdexcept>
#include <httplib.h>

#include "assets.hpp"

namespace shapeform::view {

WebServer::WebServer(FrameBus& bus, ControlHandler control) : bus_(bus), server_(std::make_unique<httplib::Server>()) {
  for (std::size_t i = 0; i < kAssetCount; ++i) {
    const Asset& a = kAssets[i];
    server_->Get(std::string(a.path), [&a](const httplib::Request&, httplib::Response& res) {
      res.set_header("Cache-Control", "no-store");
      res.set_content(a.body.data(), a.body.size(), std::string(a.content_type));
    });
  }
  server_->Get("/frame", [this](const httplib::Request&, httplib::Response& res) {
    res.set_header("Cache-Control", "no-store");
    res.set_content(bus_.latest(), "application/json");
  });
  server_->Get("/events", [this](const httplib::Request&, httplib::Response& res) {
    res.set_header("Cache-Control", "no-store");
    auto seen = std::make_shared<std::uint64_t>(0);
    res.set_chunked_content_provider("text/event-stream", [this, seen](std::size_t, httplib::DataSink& sink) {
      // One frame per call; a closed browser makes write() fail, which ends the stream.
      while (!bus_.closed()) {
        if (const auto frames = bus_.wait_newer(*seen, 0.5)) {
          std::string events;
          for (const std::string& f : *frames) events += "data: " + f + "\n\n";
          return sink.write(events.data(), events.size());
        }
        if (!sink.is_writable()) return false;
      }
      sink.done();
      return true;
    });
  });
  if (control) {
    server_->Post("/control", [control](const httplib::Request& req, httplib::Response& res) {
      double value = 0.0;
      if (req.has_param("value")) {
        try {
          value = std::stod(req.get_param_value("value"));
        } catch (const std::exception&) {
          res.status = 400;
          res.set_content("value: not a number", "text/plain");
          return;
        }
      }
      const std::string why = control(req.get_param_value("action"), value);
      res.status = why.empty() ? 200 : 400;
      res.set_content(why.empty() ? "ok" : why, "text/plain");
    });
  }
}

WebServer::~WebServer() { stop(); }

int WebServer::start(const std::string& addr, int port) {
  const int bound = port == 0 ? server_->bind_to_any_port(addr) : (server_->bind_to_port(addr, port) ? port : -1);
  if (bound <= 0) throw std::runtime_error("cannot listen on " + addr + ":" + std::to_string(port) + " (address in use or not on this host)");
  thread_ = std::thread([this] { server_->listen_after_bind(); });
  return bound;
}

void WebServer::stop() {
  bus_.close();
  if (server_) server_->stop();
  if (thread_.joinable()) thread_.join();
}

}  // namespace shapeform::view
