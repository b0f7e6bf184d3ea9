#include <catch2/catch.hpp>
#include <cmath>
#include <set>

#include "core/metric_table.hpp"
#include "monitor_fixtures.hpp"
#include "presentation.hpp"
#include "app/json.hpp"

using namespace shapeform;
using core::Vec2;
using supervisor::SwarmMonitor;

using test::circle;
using test::kS;

namespace {

/// Agent 0 on the circle following epoch 1 (with a status), agent 1 off it on epoch 1, agent 2 on an
/// old epoch, agent 3 left, agent 4 silent for 2 s (dead); the command is epoch 1.
SwarmMonitor swarm(std::int64_t now) {
  SwarmMonitor m(kS, {});
  m.set_command(circle(), 1, 0);
  m.on_state(0, Vec2(4, 0), Vec2(4, 0), 1, 10.0, now);
  m.on_status(test::status(0, 3));
  m.on_state(1, Vec2(0, 5), Vec2(0, 5), 1, 10.0, now - kS / 2);
  m.on_state(2, Vec2(-4, 0), Vec2(-4, 0), 0, 0.0, now);
  m.on_state(3, Vec2(0, -4), Vec2(0, -4), 1, 10.0, now);
  m.on_departed(3);
  m.on_state(4, Vec2(1, 1), Vec2(1, 1), 1, 10.0, now - 2 * kS);
  return m;
}
}  // namespace

TEST_CASE("status JSON and table carry the same facts for every agent", "[supervisor][presentation]") {
  const std::int64_t now = 10 * kS;
  const SwarmMonitor m = swarm(now);
  const auto rows = supervisor::agent_rows(m, now, 10.0);
  const nlohmann::json j = supervisor::status_json(rows, 1, 10.0);
  CHECK(j["event"] == "status");
  CHECK(j["epoch"] == 1);
  CHECK(j["model_time"] == 10.0);
  const auto& a = j["agents"];
  REQUIRE(a.size() == 5);
  for (std::size_t i = 0; i < a.size(); ++i) {
    CHECK(a[i]["id"] == static_cast<int>(i));  // ascending id
    const std::set<std::string> keys = {"id",    "alive",       "state",
                                            "last_seen_s", "x", "y", "epoch", "shape_error", "neighbours_heard",
                                            "safety"};
    std::set<std::string> got;
    for (const auto& [k, v] : a[i].items()) got.insert(k);
    CHECK(got == keys);
  }
  CHECK(a[0]["alive"] == true);
  CHECK(a[0]["x"] == 4.0);
  CHECK(a[0]["y"] == 0.0);
  CHECK(a[0]["shape_error"].get<double>() == Approx(0.0).margin(1e-12));
  CHECK(a[0]["neighbours_heard"] == 3);
  CHECK(a[0]["last_seen_s"] == 0.0);
  CHECK(a[1]["shape_error"].get<double>() == Approx(1.0));  // |(0, 5)| - 4
  CHECK(a[1]["last_seen_s"] == 0.5);
  CHECK(a[1]["neighbours_heard"].is_null());  // no status yet
  CHECK(a[2]["epoch"] == 0);
  CHECK(a[2]["shape_error"].is_null());  // not on the current command
  CHECK(a[0]["state"] == "alive");
  CHECK(a[3]["alive"] == false);
  CHECK(a[3]["state"] == "left");  // disposed its instance
  CHECK(a[4]["alive"] == false);
  CHECK(a[4]["state"] == "dead");  // silent
  CHECK(a[4]["last_seen_s"] == 2.0);
  CHECK(a[0]["safety"] == "");  // the filter does not hold it

  const std::string table = supervisor::status_table(rows);
  CHECK(table.find("     0 yes         0.00s     4.0000     0.0000      1      0.0000      3  \n") != std::string::npos);
  CHECK(table.find("     1 yes         0.50s     0.0000     5.0000      1      1.0000      -  \n") != std::string::npos);
  CHECK(table.find("     3 left") != std::string::npos);
  CHECK(table.find("     4 DEAD") != std::string::npos);
  CHECK(supervisor::status_table({}).find("(no agent heard yet)") != std::string::npos);
  CHECK(supervisor::status_json({}, 0, 0.0)["agents"].empty());
}

TEST_CASE("metrics JSON has every metric of the table; undefined is null, counts are integers",
          "[supervisor][presentation]") {
  core::Metrics m;
  m.agents = 7;
  m.gap_cv = 0.25;
  m.clusters = 2;
  const nlohmann::json j = app::metrics_json(m);
  CHECK(j.size() == std::size(core::kMetricTable) + 1);
  CHECK(j["agents"] == 7);
  for (const core::MetricInfo& info : core::kMetricTable) {
    INFO(info.name);
    REQUIRE(j.contains(std::string(info.name)));
    CHECK(j[std::string(info.name)].is_null() == !info.get(m).has_value());
  }
  CHECK(j["gap_cv"] == 0.25);
  CHECK(j["clusters"].is_number_integer());
  CHECK(j.dump().find("\"clusters\":2,") != std::string::npos);

  SwarmMonitor::Sample s;
  s.model_time = 12.5;
  s.metrics = m;
  s.converged = true;
  const nlohmann::json answer = supervisor::metrics_answer(s, 3);
  CHECK(answer["epoch"] == 3);
  CHECK(answer["model_time"] == 12.5);
  CHECK(answer["converged"] == true);
  CHECK(answer["gap_cv"] == 0.25);
}

TEST_CASE("summary JSON keeps every key, tracking errors only when tracking", "[supervisor][presentation]") {
  supervisor::Summary s;
  s.name = "circle";
  s.command = circle();
  s.command.dt = 0.5;
  s.epoch = 2;
  s.sample.model_time = 50.0;
  s.sample.metrics.agents = 2;
  s.sample.metrics.shape_error_mean = 0.01;
  s.sample.converged = true;
  s.sample.alive = 2;
  s.agents_seen = 3;
  s.settle_time = 20.0;
  s.final_positions = {{0, Vec2(4, 0)}, {5, Vec2(-4, 0)}};
  s.final_model_times = {50.0, 49.5};
  s.samples_rejected = 4;
  s.exit_status = 3;

  nlohmann::json j = supervisor::summary_json(s);
  std::set<std::string> keys;
  for (const auto& [k, v] : j.items()) keys.insert(k);
  std::set<std::string> want = {"event", "agents", "name", "shape", "law", "tracking", "epoch", "model_time", "dt",
                                "steps", "agents_seen", "converged", "verdict", "settle_step", "final_ids",
                                "final_positions", "final_model_times", "samples_rejected", "commands_refused",
                                "recording", "exit_status"};
  for (const core::MetricInfo& info : core::kMetricTable)
    if (info.name != "centroid_error" && info.name != "ring_error") want.insert(std::string(info.name));
  CHECK(keys == want);
  CHECK(j["event"] == "summary");
  CHECK(j["shape"] == "circle");
  CHECK(j["law"] == "paper");
  CHECK(j["steps"] == 100);
  CHECK(j["settle_step"] == 40);
  CHECK(j["final_ids"] == nlohmann::json({0, 5}));
  CHECK(j["final_positions"] == nlohmann::json({{4.0, 0.0}, {-4.0, 0.0}}));
  CHECK(j["final_model_times"] == nlohmann::json({50.0, 49.5}));
  CHECK(j["recording"].is_null());
  CHECK(j["exit_status"] == 3);
  CHECK(j["shape_error_mean"] == 0.01);
  CHECK(j["gap_cv"].is_null());

  s.command.tracking.enabled = true;
  s.recording = "/tmp/rec";
  s.settle_time.reset();
  j = supervisor::summary_json(s);
  CHECK(j.contains("centroid_error"));
  CHECK(j.contains("ring_error"));
  CHECK(j["recording"] == "/tmp/rec");
  CHECK(j["settle_step"].is_null());

  const std::string text = supervisor::summary_text(s);
  CHECK(text.rfind("summary: epoch 2, 2 agents, t=50, converged\n  shape_error_mean=0.0100 ", 0) == 0);
  CHECK(text.find(" settle_step=- ") != std::string::npos);
  CHECK(text.find("\n  recording: /tmp/rec\n") != std::string::npos);
}

TEST_CASE("a command is described on one line", "[supervisor][presentation]") {
  CHECK(supervisor::describe_command(circle()) ==
        "circle r=4 centre (0, 0); k1=0.1 k2=2 sigma=3.5 beta=1.2 r=0.1, euler dt=1, max_speed=10");
  core::CompiledCommand unlimited = circle();
  unlimited.max_speed = 0.0;  // no speed limit: not mentioned
  CHECK(supervisor::describe_command(unlimited) ==
        "circle r=4 centre (0, 0); k1=0.1 k2=2 sigma=3.5 beta=1.2 r=0.1, euler dt=1");
}

namespace {
SwarmMonitor::Sample sample(int alive, double shape_error, bool converged = false) {
  SwarmMonitor::Sample s;
  s.model_time = 12.0;
  s.alive = alive;
  s.following = alive;
  s.converged = converged;
  s.metrics.agents = alive;
  s.metrics.shape_error_mean = shape_error;
  s.metrics.clusters = 1;
  return s;
}
}  // namespace

TEST_CASE("metrics table: every metric, 4 significant digits, units", "[supervisor][presentation]") {
  SwarmMonitor::Sample s = sample(8, 0.0123456789, true);
  s.metrics.gap_cv = 12345.678;
  const std::string t = supervisor::metrics_table(s, 3);
  INFO(t);
  CHECK(t.rfind("epoch 3, model time t=12, 8 agents alive, 8 following, converged\n", 0) == 0);
  for (const char* row : {"\n  shape_error_mean      0.01235  shape units\n", "\n  gap_cv              1.235e+04\n",
                          "\n  clusters                    1  count\n", "\n  min_separation              -  shape units\n"})
    CHECK(t.find(row) != std::string::npos);
  for (const core::MetricInfo& info : core::kMetricTable) CHECK(t.find("  " + std::string(info.name) + " ") != std::string::npos);
  CHECK(t.find("0.0123456") == std::string::npos);  // no long numbers
}

TEST_CASE("progress: printed on change only, every S, or never", "[supervisor][presentation]") {
  using supervisor::ProgressFilter;
  ProgressFilter f;
  std::int64_t now = 100 * kS;
  CHECK(f.due(sample(8, 1.0), 1, now));               // the first line
  CHECK_FALSE(f.due(sample(8, 1.0), 1, now += 2 * kS));  // nothing changed
  CHECK_FALSE(f.due(sample(8, 0.95), 1, now += kS));     // 5%: below the tolerance
  CHECK(f.due(sample(8, 0.85), 1, now += kS));           // 15% of the last printed value
  CHECK_FALSE(f.due(sample(7, 0.85), 1, now + kS / 2));  // changed, but within a second of the last line
  CHECK(f.due(sample(7, 0.85), 1, now += kS));           // agents count
  CHECK(f.due(sample(7, 0.85), 2, now += kS));           // epoch
  CHECK(f.due(sample(7, 0.85, true), 2, now += kS));     // converged
  CHECK(f.due(sample(7, 0.0), 2, now += kS));            // 0.85 -> 0
  CHECK_FALSE(f.due(sample(7, 0.0009), 2, now += kS));   // below the absolute floor
  SwarmMonitor::Sample two = sample(7, 0.0009);
  two.metrics.clusters = 2;
  CHECK(f.due(two, 2, now += kS));  // a count changes
  f.off();
  CHECK_FALSE(f.due(sample(1, 5.0), 9, now += 10 * kS));
  f.every(0.2);
  CHECK(f.due(sample(1, 5.0), 9, now += kS));
  CHECK_FALSE(f.due(sample(1, 5.0), 9, now + kS / 10));
  CHECK(f.due(sample(1, 5.0), 9, now += kS / 5));  // unchanged, but 0.2 s passed
  f.on_change();
  CHECK_FALSE(f.due(sample(1, 5.0), 9, now += 5 * kS));
}

TEST_CASE("show: the command in force and who published it", "[supervisor][presentation]") {
  supervisor::ShowInfo info;
  info.command = test::circle();
  info.command.gains.k1 = 0.5;
  info.command.max_speed = 0.0;
  info.epoch = 4;
  info.published_s_ago = 12.34;
  info.agents_epoch = 4;
  info.alive = 8;
  info.following = 7;
  std::string t = supervisor::show_text(info);
  INFO(t);
  CHECK(t.rfind("epoch 4, published by this supervisor 12.3 s ago; 7 of 8 agents follow it\n", 0) == 0);
  for (const char* row : {"  shape       circle r=4 centre (0, 0) rot=0 deg scale=1\n", "  tracking    off\n",
                          "  law         paper\n", "  gains       k1=0.5 k2=", "  integrator  euler dt=1\n",
                          "  max_speed   off\n"})
    CHECK(t.find(row) != std::string::npos);
  CHECK(t.find("another participant") == std::string::npos);
  CHECK(t.find("superseded") == std::string::npos);
  // Another participant's command, which replaced this supervisor's epoch 4: shown with its publisher.
  info.epoch = 6;
  info.own = false;
  info.publisher = "shapeform_supervisor on box pid 42 [01.02.03.04.05.06.07.08.09.0a.0b.0c]";
  info.superseded = 4;
  info.published_s_ago = 0.5;
  info.agents_epoch = 6;
  t = supervisor::show_text(info);
  CHECK(t.rfind("epoch 6, published by shapeform_supervisor on box pid 42 [01.02.03.04.05.06.07.08.09.0a.0b.0c] "
                "(another participant), learnt 0.5 s ago; 7 of 8 agents follow it\n"
                "this supervisor's epoch 4 was superseded by it\n",
                0) == 0);
  CHECK(t.find("  shape       circle r=4") != std::string::npos);
  info.agents_epoch = 7;  // an agent is ahead of the command topic
  CHECK(supervisor::show_text(info).find("some agents follow epoch 7") != std::string::npos);
  info.epoch = 0;  // nothing in force
  info.agents_epoch = 6;
  t = supervisor::show_text(info);
  CHECK(t.rfind("no command in force yet", 0) == 0);
  CHECK(t.find("the agents follow epoch 6, published by another participant") != std::string::npos);
}

TEST_CASE(
    "safety_lines: separation, the zones numbered from 1, the fence, its margin and breach action; in show "
    "too",
    "[supervisor][presentation][safety]") {
  core::Command c;
  CHECK(supervisor::safety_lines(c) ==
        "  separation  off\n"
        "  keep_out    none\n"
        "  fence       box [-1000, 1000]^2 (safety.workspace)\n"
        "  margin      0\n"
        "  breach      hold\n");
  c.min_separation = 0.25;
  core::KeepOutZone circle;
  circle.centre = core::Vec2(5, 0);
  circle.radius = 1.5;
  core::KeepOutZone triangle;
  triangle.kind = core::KeepOutZone::Kind::Polygon;
  triangle.vertices = {core::Vec2(0, 0), core::Vec2(1, 0), core::Vec2(0, 1)};
  c.keep_out = {circle, triangle};
  c.fence = {core::Vec2(-8, -8), core::Vec2(8, -8), core::Vec2(0, 9.5)};
  c.fence_margin = 0.5;
  c.breach_action = core::BreachAction::Return;
  const std::string lines = supervisor::safety_lines(c);
  CHECK(lines ==
        "  separation  0.25\n"
        "  keep_out    2 zones\n"
        "    1  circle centre (5, 0) r=1.5\n"
        "    2  polygon (0, 0; 1, 0; 0, 1)\n"
        "  fence       polygon (-8, -8; 8, -8; 0, 9.5)\n"
        "  margin      0.5\n"
        "  breach      return\n");
  supervisor::ShowInfo info;
  info.command = c;
  CHECK(supervisor::show_text(info).find(lines) != std::string::npos);
}

TEST_CASE("status: what the safety filter does to each agent, from its status of the current command",
          "[supervisor][presentation]") {
  const std::int64_t now = 10 * kS;
  SwarmMonitor m(kS, {});
  m.set_command(circle(), 1, 0);
  for (int i = 0; i < 5; ++i) m.on_state(i, Vec2(i, 0), Vec2(i, 0), 1, 10.0, now);
  auto st = test::status(0, 4);
  st.blocked = true;
  st.blocked_by = 3;
  m.on_status(st);
  st.id = 1;
  st.blocked_by = -2;  // the first zone
  m.on_status(st);
  st.id = 2;
  st.blocked_by = -1;
  m.on_status(st);
  st.id = 3;
  st.blocked = false;
  st.beyond_fence = true;
  m.on_status(st);
  st.id = 4;
  st.beyond_fence = true;
  st.epoch = 0;  // of another command: not shown
  m.on_status(st);
  const auto rows = supervisor::agent_rows(m, now, 10.0);
  CHECK(rows[0].safety == "held by 3");
  CHECK(rows[1].safety == "held by zone 1");
  CHECK(rows[2].safety == "held by the fence");
  CHECK(rows[3].safety == "beyond the fence");
  CHECK(rows[4].safety == "");
  CHECK(supervisor::status_table(rows).find("held by zone 1") != std::string::npos);
  core::Metrics metrics;
  m.run_figures(metrics, now);
  CHECK(metrics.agents_blocked == 3);
  CHECK(metrics.agents_beyond_fence == 1);
}
