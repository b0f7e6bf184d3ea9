// shapeform_view: the swarm in a web browser, live from the DDS domain or replayed from a recording.
#include <algorithm>
#include <iostream>
#include <mutex>
#include <optional>

#include "app/app.hpp"
#include "app/json.hpp"
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

/// How agents are drawn, from the config: stale after the agents' own neighbour timeout (at least
/// 0.3 s, so a recording's 10 Hz rows do not flicker), dead after the supervisor's agent timeout.
view::SceneParams scene_params(const config::Config& cfg) {
  view::SceneParams p;
  p.stale_s = std::max(0.3, cfg.agent.neighbour_timeout_periods / cfg.agent.rate_hz);
  p.dead_s = std::max(p.stale_s, cfg.supervisor.agent_timeout_s);
  return p;
}

int run(int argc, char** argv) {
  app::App app("shapeform_view",
               "shapeform_view: the swarm in a web browser. Live (default): joins the DDS domain read-only (the "
               "transport profile of the config; it writes no topic) and serves a page with the agents, the "
               "commanded shape, the tracked centre, trails, charts and an agent table, streamed as Server-Sent "
               "Events. --replay RUN_DIR plays a recording in the same page (play, pause, speed, seek; no DDS). "
               "Prints the page's URL on stdout (with --json: a start event with \"url\").");
  app.add_config_options();
  std::string bind = "127.0.0.1";
  int port = 8080;
  double fps = 15.0;
  std::string replay_dir;
  bool json = false;
  app.cli().add_option("--bind", bind, "IPv4 address to serve on (default 127.0.0.1: this host only; 0.0.0.0: every interface)");
  app.cli().add_option("--port", port, "TCP port (default 8080; 0: a free port, printed)")->check(CLI::Range(0, 65535));
  app.cli().add_option("--fps", fps, "frames per second streamed to the page (default 15)")->check(CLI::Range(1.0, 60.0));
  app.cli().add_option("--replay", replay_dir, "play the recording of RUN_DIR (a launcher run folder or a record folder) instead of the live swarm");
  app.cli().add_flag("--json", json, "machine output on stdout: JSON event lines (start with \"url\", stop)");
  if (const auto rc = app.parse(argc, argv)) return *rc;
  if (!util::is_ipv4(bind)) return app.usage_error("--bind: expected an IPv4 address such as 127.0.0.1, got '" + bind.substr(0, 60) + "'");
  const auto cfg = app.load_config();
  if (!cfg) return app::kExitUsage;
  std::optional<view::Recording> recording;
  if (!replay_dir.empty()) {
    try {
      recording = view::load_recording(replay_dir);
    } catch (const view::RecordingError& e) {
      return app.usage_error(std::string("--replay: ") + e.what());
    }
  }
  util::log_init("view");
  util::install_stop_signals();
  return app.run([&] {
    view::Scene scene(scene_params(*cfg));
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
    const int bound = server.start(bind, port);
    const std::string url = "http://" + bind + ":" + std::to_string(bound) + "/";
    if (json) {
      nlohmann::json start = {{"event", "start"}, {"mode", recording ? "replay" : "live"}, {"url", url}, {"port", bound},
                              {"bind", bind}};
      if (recording) start["recording"] = recording->dir.string();
      else start["config"] = app::config_json(*cfg);
      std::cout << start.dump() << std::endl;
    } else {
      std::cout << url << std::endl;
    }
    util::log_info(recording ? "replaying " + recording->dir.string() + " at " + url
                             : "viewing domain " + std::to_string(cfg->transport.domain) + " at " + url);
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
        frame = scene.delta(real - t0);
        frame["mode"] = "live";
        if (want) {
          nlohmann::json full = scene.snapshot(real - t0);
          full["mode"] = "live";
          snapshot = full.dump();
        }
      }
      bus.publish(frame.dump(), std::move(snapshot));
    }
    server.stop();
    if (json) std::cout << nlohmann::json{{"event", "stop"}}.dump() << std::endl;
    return 0;
  });
}

}  // namespace
}  // namespace shapeform

int main(int argc, char** argv) { return shapeform::run(argc, argv); }
