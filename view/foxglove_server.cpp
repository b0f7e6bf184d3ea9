#include "foxglove_server.hpp"

#include <chrono>
#include <map>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <websocketpp/config/asio_no_tls.hpp>
#include <websocketpp/server.hpp>

#include "util/log.hpp"

namespace shapeform::view {

using WsServer = websocketpp::server<websocketpp::config::asio>;
using Hdl = websocketpp::connection_hdl;

struct FoxgloveServer::Impl {
  struct Client {
    foxglove::Subscriptions subs;
    std::uint64_t dropped = 0;
    std::string name;
  };

  std::vector<foxglove::AdvertisedChannel> channels;
  std::size_t max_buffered;
  WsServer ws;
  std::thread thread;
  bool running = false;
  // Touched on the server's thread only.
  std::map<Hdl, Client, std::owner_less<Hdl>> clients;
  // Read by the caller's thread.
  std::unique_ptr<std::atomic<int>[]> subscribers;  ///< per channel index: subscriptions over all clients
  std::atomic<std::uint64_t> n_clients{0}, connections{0}, sent{0}, dropped{0}, bytes{0};
  std::string session_id;

  void recount() {
    for (std::size_t i = 0; i < channels.size(); ++i) {
      int n = 0;
      for (const auto& [h, c] : clients) n += static_cast<int>(c.subs.count(channels[i].id));
      subscribers[i].store(n);
    }
  }

  void send_text(Hdl h, const std::string& text) {
    websocketpp::lib::error_code ec;
    ws.send(h, text, websocketpp::frame::opcode::text, ec);
  }

  void on_message(Hdl h, WsServer::message_ptr m) {
    auto it = clients.find(h);
    if (it == clients.end()) return;
    if (m->get_opcode() != websocketpp::frame::opcode::text) {
      send_text(h, foxglove::status_json(foxglove::StatusLevel::Error,
                                         "shapeform_view is read-only: binary client messages (publish, "
                                         "service calls) are not accepted"));
      return;
    }
    const foxglove::ClientOp op = foxglove::parse_client_op(m->get_payload());
    std::vector<std::string> problems;
    switch (op.kind) {
      case foxglove::ClientOp::Kind::Subscribe:
        problems = it->second.subs.subscribe(op.subscribe, channels);
        break;
      case foxglove::ClientOp::Kind::Unsubscribe:
        problems = it->second.subs.unsubscribe(op.unsubscribe);
        break;
      case foxglove::ClientOp::Kind::Unsupported:
        problems.push_back(
            "op \"" + op.op.substr(0, 40) +
            "\" is not supported: shapeform_view is read-only (subscribe and unsubscribe only)");
        break;
      case foxglove::ClientOp::Kind::Invalid:
        problems.push_back("bad message: " + op.error);
        break;
    }
    for (const auto& p : problems) send_text(h, foxglove::status_json(foxglove::StatusLevel::Error, p));
    recount();
  }

  void deliver(std::size_t index, std::uint64_t stamp_ns, const std::string& payload) {
    const std::uint32_t channel = channels[index].id;
    for (auto& [h, c] : clients) {
      const auto ids = c.subs.of_channel(channel);
      if (ids.empty()) continue;
      websocketpp::lib::error_code ec;
      auto con = ws.get_con_from_hdl(h, ec);
      if (ec || !con || con->get_state() != websocketpp::session::state::open) continue;
      for (const std::uint32_t id : ids) {
        if (con->get_buffered_amount() > max_buffered) {
          ++c.dropped;
          ++dropped;
          continue;
        }
        const std::string frame = foxglove::message_data(id, stamp_ns, payload);
        ws.send(h, frame, websocketpp::frame::opcode::binary, ec);
        if (!ec) {
          ++sent;
          bytes += frame.size();
        }
      }
    }
  }
};

FoxgloveServer::FoxgloveServer(std::vector<viz::Channel> channels, std::size_t max_buffered_bytes)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.max_buffered = max_buffered_bytes;
  for (std::size_t i = 0; i < channels.size(); ++i)
    m.channels.push_back({static_cast<std::uint32_t>(i + 1), std::move(channels[i])});
  m.subscribers = std::make_unique<std::atomic<int>[]>(m.channels.size());
  for (std::size_t i = 0; i < m.channels.size(); ++i) m.subscribers[i].store(0);
  m.session_id = std::to_string(std::chrono::system_clock::now().time_since_epoch().count());
}

FoxgloveServer::~FoxgloveServer() { stop(); }

int FoxgloveServer::start(const std::string& bind, int port) {
  Impl& m = *impl_;
  m.ws.clear_access_channels(websocketpp::log::alevel::all);
  m.ws.clear_error_channels(websocketpp::log::elevel::all);
  m.ws.init_asio();
  m.ws.set_reuse_addr(true);
  m.ws.set_validate_handler([&m](Hdl h) {
    auto con = m.ws.get_con_from_hdl(h);
    const auto chosen = foxglove::choose_subprotocol(con->get_requested_subprotocols());
    if (!chosen) {
      con->set_status(websocketpp::http::status_code::bad_request);
      con->set_body(
          "shapeform_view: a Foxglove client must ask for the WebSocket subprotocol foxglove.sdk.v1 or "
          "foxglove.websocket.v1\n");
      return false;
    }
    con->select_subprotocol(*chosen);
    return true;
  });
  m.ws.set_open_handler([&m](Hdl h) {
    auto con = m.ws.get_con_from_hdl(h);
    Impl::Client c;
    c.name = con->get_remote_endpoint();
    m.clients.emplace(h, std::move(c));
    ++m.connections;
    m.n_clients = m.clients.size();
    m.send_text(h, foxglove::server_info_json("shapeform_view", m.session_id));
    m.send_text(h, foxglove::advertise_json(m.channels));
    util::log_info("foxglove: client " + con->get_remote_endpoint() + " connected (" +
                   con->get_subprotocol() + ")");
  });
  const auto gone = [&m](Hdl h) {
    const auto it = m.clients.find(h);
    if (it == m.clients.end()) return;
    util::log_info("foxglove: client " + it->second.name + " left (" + std::to_string(it->second.dropped) +
                   " messages dropped for it)");
    m.clients.erase(it);
    m.n_clients = m.clients.size();
    m.recount();
  };
  m.ws.set_close_handler(gone);
  m.ws.set_fail_handler(gone);
  m.ws.set_message_handler([&m](Hdl h, WsServer::message_ptr msg) { m.on_message(h, std::move(msg)); });
  websocketpp::lib::error_code ec;
  const auto address = asio::ip::make_address(bind, ec);
  if (!ec) m.ws.listen(asio::ip::tcp::endpoint(address, static_cast<unsigned short>(port)), ec);
  if (!ec) m.ws.start_accept(ec);
  if (ec)
    throw std::runtime_error("foxglove: cannot listen on " + bind + ":" + std::to_string(port) + ": " +
                             ec.message());
  const int bound = m.ws.get_local_endpoint(ec).port();
  if (ec) throw std::runtime_error("foxglove: no local port on " + bind + ": " + ec.message());
  m.running = true;
  m.thread = std::thread([&m] {
    try {
      m.ws.run();
    } catch (const std::exception& e) {
      util::log_error(std::string("foxglove: server stopped: ") + e.what());
    }
  });
  return bound;
}

void FoxgloveServer::stop() {
  Impl& m = *impl_;
  if (!m.running) return;
  m.running = false;
  asio::post(m.ws.get_io_service(), [&m] {
    websocketpp::lib::error_code ec;
    m.ws.stop_listening(ec);
    for (auto& [h, c] : m.clients)
      m.ws.close(h, websocketpp::close::status::going_away, "shapeform_view stopping", ec);
  });
  // Closing handshakes get a second; a client that does not answer is cut.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(1);
  while (m.n_clients.load() > 0 && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  m.ws.stop();
  if (m.thread.joinable()) m.thread.join();
}

bool FoxgloveServer::subscribed(std::size_t index) const { return impl_->subscribers[index].load() > 0; }

void FoxgloveServer::publish(std::size_t index, std::uint64_t stamp_ns, std::string payload) {
  Impl& m = *impl_;
  if (!m.running || index >= m.channels.size()) return;
  asio::post(m.ws.get_io_service(),
             [&m, index, stamp_ns, p = std::make_shared<std::string>(std::move(payload))] {
               m.deliver(index, stamp_ns, *p);
             });
}

FoxgloveServer::Stats FoxgloveServer::stats() const {
  const Impl& m = *impl_;
  return {m.n_clients.load(), m.connections.load(), m.sent.load(), m.dropped.load(), m.bytes.load()};
}

}  // namespace shapeform::view
