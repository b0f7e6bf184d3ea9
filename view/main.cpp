// shapeform_view: the swarm in a web browser, live from the DDS domain or replayed from a recording.
#include <algorithm>
#include <iostream>
#include <limits>
#include <map>
#include <mutex>
#include <optional>

#include "app/app.hpp"
#include "app/json.hpp"
#include "dds/wire.hpp"
#include "foxglove_scene.hpp"
#include "foxglove_server.hpp"
#include "live.hpp"
#include "replay.hpp"
#include "server.hpp"
#include "util/clock.hpp"
#include "util/ipv4.hpp"
#include "util/log.hpp"
#include "util/rate_loop.hpp"
#include "util/signals.hpp"

namespace shapeform {
namespace {

double now_s() { return static_cast<double>(util::steady_ns()) * 1e-9; }

/// The Foxglove server's channels: the scene's (viz::scene_channels), then, live, each topic the feed
/// reads as its CDR bytes with its omgidl schema (dds::topic_schema).
std::vector<viz::Channel> foxglove_channels(bool live) {
  std::vector<viz::Channel> out = viz::scene_channels();
  if (!live) return out;
  for (const dds::TopicId t : view::LiveFeed::topics()) {
    const dds::TopicSchema& s = dds::topic_schema(t);
    out.push_back({dds::topic_name(t), s.name, std::string(s.encoding), s.text, std::string(s.message_encoding)});
  }
  return out;
}

/// The live feed's raw samples to the Foxglove server: serialized only for a channel someone subscribed to.
class FoxgloveSink : public view::SampleSink {
 public:
  explicit FoxgloveSink(view::FoxgloveServer& server) : server_(server) {
    const auto topics = view::LiveFeed::topics();
    for (std::size_t i = 0; i < topics.size(); ++i) index_[topics[i]] = viz::scene_channels().size() + i;
  }
  bool wants(dds::TopicId topic) const override {
    const auto it = index_.find(topic);
    return it != index_.end() && server_.subscribed(it->second);
  }
  void on_sample(dds::TopicId topic, std::vector<std::uint8_t> cdr) override {
    server_.publish(index_.at(topic), static_cast<std::uint64_t>(util::system_ns()), std::string(cdr.begin(), cdr.end()));
  }

 private:
  view::FoxgloveServer& server_;
  std::map<dds::TopicId, std::size_t> index_;
};

/// How agents are drawn, from the config: stale after the agents' own neighbour timeout (at least
/// 0.3 s, so a recording's 10 Hz rows do not flicker), dead after the supervisor's agent timeout.
view::SceneParams scene_params(const config::Config& cfg) {
  view::SceneParams p;
  p.stale_s = std::max(0.3, 1e-9 * static_cast<double>(cfg.agent.neighbour_timeout_ns()));
  p.dead_s = std::max(p.stale_s, cfg.supervisor.agent_timeout_s);
  return p;
}

int run(int argc, char** argv) {
  app::App app("shapeform_view",
               "shapeform_view: the swarm in a web browser. Live (default): joins the DDS domain read-only (the "
               "transport profile of the config; it writes no topic) and serves a page with the agents, the "
               "commanded shape, the tracked centre, trails, charts and an agent table, streamed as Server-Sent "
               "Events. --replay RUN_DIR plays a recording in the same page (play, pause, speed, seek; no DDS). "
               "Prints the page's URL on stdout (with --json: a start event with \"url\").\n\n"
               "--foxglove-port P also serves the swarm to Foxglove or Lichtblick (Open connection > Foxglove "
               "WebSocket > ws://127.0.0.1:P; docs/FOXGLOVE.md): a read-only Foxglove WebSocket server "
               "(subprotocols foxglove.sdk.v1 and foxglove.websocket.v1, several clients at once) with the channel "
               "shapeform/scene (foxglove.SceneUpdate, json: agents coloured by state, headings, outline, zones, "
               "fence, centre; frame \"shapeform\", shape units as metres) and shapeform/agent_poses "
               "(foxglove.PosesInFrame) at --fps, and, live, every topic the viewer reads (shapeform/state, "
               "state_batch, command, target, metrics, status, status_batch) as cdr with its omgidl schema, forwarded as samples "
               "arrive to the clients subscribed to it. A client too far behind misses messages (counted in the "
               "stop event). With --foxglove-port and no --port, no page is served. --bind applies to both.");
  app.add_config_options();
  std::string bind = "127.0.0.1";
  int port = 8080;
  double fps = 15.0;
  int foxglove_port = -1;
  std::string replay_dir;
  bool json = false;
  app.cli().add_option("--bind", bind, "IPv4 address to serve on (default 127.0.0.1: this host only; 0.0.0.0: every interface)");
  auto* port_opt = app.cli().add_option("--port", port, "TCP port of the page (default 8080; 0: a free port, printed); with --foxglove-port the page is served only when --port is given")->check(CLI::Range(0, 65535));
  app.cli().add_option("--foxglove-port", foxglove_port, "also serve a Foxglove WebSocket server on this TCP port (0: a free port, printed as \"foxglove_port\" and \"foxglove_url\")")->check(CLI::Range(0, 65535));
  app.cli().add_option("--fps", fps, "frames per second streamed to the page (default 15)")->check(CLI::Range(1.0, 60.0));
  app.cli().add_option("--replay", replay_dir, "play a recording instead of the live swarm: RUN_DIR (a launcher run folder or a record folder of CSV files) or a run.mcap file");
  app.cli().add_flag("--json", json, "machine output on stdout: JSON event lines (start with \"url\" and/or \"foxglove_url\", stop with the Foxglove server's counts)");
  if (const auto rc = app.parse(argc, argv)) return *rc;
  if (!util::is_ipv4(bind)) return app.usage_error("--bind: expected an IPv4 address such as 127.0.0.1, got '" + bind.substr(0, 60) + "'");
  const auto cfg = app.load_config();
  if (!cfg) return app::kExitUsage;
  std::optional<view::Recording> recording;
  if (!replay_dir.empty()) {
    try {
      recording = record::load_recording(replay_dir);
    } catch (const record::RecordingError& e) {
      return app.usage_error(std::string("--replay: ") + e.what());
    }
  }
  const bool foxglove = foxglove_port >= 0;
  const bool page = !foxglove || port_opt->count() > 0;
  util::log_init("view");
  util::install_stop_signals();
  return app.run([&] {
    view::SceneParams params = scene_params(*cfg);
    // Without the page nothing draws trails: keep one point per agent (the page's frame prunes them).
    if (!page) params.trail_step_s = std::numeric_limits<double>::infinity();
    view::Scene scene(params);
    view::FrameBus bus;
    std::mutex clock_mutex;
    std::optional<view::ReplayClock> clock;
    std::optional<view::ReplayFeeder> feeder;
    std::unique_ptr<view::LiveFeed> live;
    view::ControlHandler control;
    if (recording) {
      clock.emplace(recording->start_s, recording->end_s, now_s());
      feeder.emplace(*recording, scene_params(*cfg).dead_s + view::SceneParams{}.trail_s);
      control = [&](const std::string& action, double value) {
        std::lock_guard<std::mutex> lock(clock_mutex);
        return view::apply_control(*clock, action, value, now_s());
      };
    } else {
      live = std::make_unique<view::LiveFeed>(*cfg);
    }
    view::WebServer server(bus, control);
    std::string url;
    int bound = -1;
    if (page) {
      bound = server.start(bind, port);
      url = "http://" + bind + ":" + std::to_string(bound) + "/";
    }
    std::optional<view::FoxgloveServer> fox;
    std::optional<FoxgloveSink> sink;
    std::string fox_url;
    int fox_bound = -1;
    if (foxglove) {
      fox.emplace(foxglove_channels(!recording));
      fox_bound = fox->start(bind, foxglove_port);
      fox_url = "ws://" + bind + ":" + std::to_string(fox_bound);
      if (live) {
        sink.emplace(*fox);
        live->set_sink(&*sink);
      }
    }
    if (json) {
      nlohmann::json start = {{"event", "start"}, {"mode", recording ? "replay" : "live"}, {"bind", bind}};
      if (page) {
        start["url"] = url;
        start["port"] = bound;
      }
      if (foxglove) {
        start["foxglove_url"] = fox_url;
        start["foxglove_port"] = fox_bound;
      }
      if (recording) start["recording"] = recording->dir.string();
      else start["config"] = app::config_json(*cfg);
      std::cout << start.dump() << std::endl;
    } else {
      if (page) std::cout << url << std::endl;
      if (foxglove) std::cout << fox_url << std::endl;
    }
    const std::string where = (page ? url : "") + (page && foxglove ? " and " : "") + fox_url;
    util::log_info(recording ? "replaying " + recording->dir.string() + " at " + where
                             : "viewing domain " + std::to_string(cfg->transport.domain) + " at " + where);
    util::RateLoop loop(fps);
    const double t0 = now_s();
    while (loop.wait_next(util::stop_flag())) {
      const double real = now_s();
      // One delta per tick, and a snapshot of the same moment when a stream asked for one.
      std::optional<std::string> snapshot;
      const bool want = bus.snapshot_wanted();
      nlohmann::json frame;
      if (recording) {
        std::lock_guard<std::mutex> lock(clock_mutex);
        const double pos = clock->position(real);
        feeder->advance(scene, pos);
        const nlohmann::json replay = view::clock_json(*clock, real);
        frame = scene.delta(pos);
        frame["mode"] = "replay";
        frame["replay"] = replay;
        if (want) {
          nlohmann::json full = scene.snapshot(pos);
          full["mode"] = "replay";
          full["replay"] = replay;
          snapshot = full.dump();
        }
      } else {
        live->drain(scene, real - t0, loop.period_s());
        if (page) {
          frame = scene.delta(real - t0);
          frame["mode"] = "live";
          if (want) {
            nlohmann::json full = scene.snapshot(real - t0);
            full["mode"] = "live";
            snapshot = full.dump();
          }
        }
      }
      if (page) bus.publish(frame.dump(), std::move(snapshot));
      if (fox && (fox->subscribed(viz::kSceneChannel) || fox->subscribed(viz::kPosesChannel))) {
        double shown = real - t0;
        if (recording) {
          std::lock_guard<std::mutex> lock(clock_mutex);
          shown = clock->position(real);
        }
        const viz::SceneSnapshot snap = view::foxglove_snapshot(scene, shown);
        const auto stamp = static_cast<std::uint64_t>(util::system_ns());
        if (fox->subscribed(viz::kSceneChannel)) fox->publish(viz::kSceneChannel, stamp, viz::scene_update_json(snap, stamp));
        if (fox->subscribed(viz::kPosesChannel)) fox->publish(viz::kPosesChannel, stamp, viz::poses_json(snap, stamp));
      }
    }
    if (live) live->set_sink(nullptr);
    if (page) server.stop();
    nlohmann::json stop = {{"event", "stop"}};
    if (fox) {
      fox->stop();
      const auto st = fox->stats();
      stop["foxglove"] = {{"connections", st.connections}, {"messages_sent", st.messages_sent},
                          {"messages_dropped", st.messages_dropped}, {"bytes_sent", st.bytes_sent}};
    }
    if (json) std::cout << stop.dump() << std::endl;
    return 0;
  });
}

}  // namespace
}  // namespace shapeform

int main(int argc, char** argv) { return shapeform::run(argc, argv); }
