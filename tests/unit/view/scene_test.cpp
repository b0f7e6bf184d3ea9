#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <map>
#include <optional>

#include "scene.hpp"
#include "shapes/shapes.hpp"

using namespace shapeform;
using Catch::Matchers::WithinAbs;

namespace {

core::CompiledCommand circle(double r0, core::Vec2 centre = core::Vec2::Zero()) {
  core::Command c;
  c.shape.kind = core::ShapeKind::Circle;
  c.shape.r0 = r0;
  c.shape.centre = centre;
  return shapes::compile(c);
}

/// Agent row k of a frame as an object of its columns.
nlohmann::json agent(const nlohmann::json& f, std::size_t k) {
  nlohmann::json out = nlohmann::json::object();
  const auto& row = f["agents"].at(k);
  for (std::size_t c = 0; c < f["agent_columns"].size(); ++c)
    out[f["agent_columns"][c].get<std::string>()] = row.at(c);
  return out;
}

/// core::outline's points (the page's and Foxglove's outline).
std::vector<core::Vec2> outline_of(const core::CompiledCommand& cmd, double t, int n, double half = 100.0) {
  bool closed = false;
  return core::outline(cmd, t, closed, n, half);
}

}  // namespace

TEST_CASE("outline: a circle's points lie on it, evenly spread, closed without repeating the start") {
  const auto pts = outline_of(circle(3.0, {1.0, -2.0}), 0.0, 60);
  REQUIRE(pts.size() == 60);
  for (const auto& p : pts) CHECK_THAT((p - core::Vec2(1.0, -2.0)).norm(), WithinAbs(3.0, 1e-9));
  const double gap = (pts[1] - pts[0]).norm();
  for (std::size_t i = 1; i < pts.size(); ++i) CHECK_THAT((pts[i] - pts[i - 1]).norm(), WithinAbs(gap, 1e-6));
  CHECK_THAT((pts.front() - pts.back()).norm(), WithinAbs(gap, 1e-6));
}

TEST_CASE("outline: the line is drawn over its half length both ways, on x2 = m x1 + c") {
  core::Command c;
  c.shape.kind = core::ShapeKind::Line;
  c.shape.m = 0.5;
  c.shape.c = 2.0;
  const auto pts = outline_of(shapes::compile(c), 0.0, 10, 50.0);
  REQUIRE(pts.size() == 11);
  for (const auto& p : pts) CHECK_THAT(p.y(), WithinAbs(0.5 * p.x() + 2.0, 1e-9));
  CHECK_THAT((pts.back() - pts.front()).norm(), WithinAbs(100.0, 1e-9));
}

TEST_CASE("outline: a tracked shape is drawn about the centre of the model time given") {
  core::Command c = circle(2.0);
  c.tracking.enabled = true;
  c.tracking.path.kind = core::CentrePath::Kind::Line;
  c.tracking.path.point = {0.0, 0.0};
  c.tracking.path.velocity = {0.1, 0.0};
  const auto pts = outline_of(shapes::compile(c), 50.0, 40);
  for (const auto& p : pts) CHECK_THAT((p - core::Vec2(5.0, 0.0)).norm(), WithinAbs(2.0, 1e-9));
}

TEST_CASE("Series: bounded, thinned by half when full, the first point and the newest kept") {
  view::Series s(8, 1);
  for (int i = 0; i < 100; ++i) {
    s.push({static_cast<double>(i)});
    REQUIRE(s.size() <= 8);
  }
  CHECK(s.points().front()[0] == 0.0);
  CHECK(s.points().back()[0] == 99.0);
  for (std::size_t i = 1; i < s.size(); ++i) CHECK(s.points()[i][0] > s.points()[i - 1][0]);
  CHECK_THROWS(s.push({1.0, 2.0}));
}

TEST_CASE("Scene: agents are alive, stale, then dead as they fall silent; disposed is dead at once") {
  view::SceneParams p;
  p.stale_s = 0.3;
  p.dead_s = 1.0;
  view::Scene scene(p);
  scene.on_state(3, {1.0, 2.0}, 10.0, 1, 100.0);
  scene.on_state(4, {0.0, 0.0}, 10.0, 2, 100.0);
  const auto& a = scene.agents().at(3);
  CHECK(std::string(scene.state(a, 100.2)) == "alive");
  CHECK(std::string(scene.state(a, 100.5)) == "stale");
  CHECK(std::string(scene.state(a, 101.5)) == "dead");
  CHECK(scene.min_epoch_followed(100.1) == 1);
  scene.on_departed(3);
  CHECK(std::string(scene.state(scene.agents().at(3), 100.0)) == "dead");
  CHECK(scene.min_epoch_followed(100.1) == 2);
  scene.on_state(3, {1.0, 2.0}, 11.0, 1, 100.2);  // back: alive again
  CHECK(std::string(scene.state(scene.agents().at(3), 100.3)) == "alive");
}

TEST_CASE("Scene::snapshot: exact agent positions, the outline, the table fields and the charts") {
  view::Scene scene;
  scene.on_command(circle(4.0), 7);
  scene.on_state(0, {0.123456789012345, -4.0}, 12.5, 7, 1.0);
  scene.on_status(0, 5, 250.0);
  scene.on_status(9, 5, 250.0);  // never seen: not drawn
  core::Metrics m;
  m.shape_error_mean = 0.5;
  m.gap_cv = 0.1;
  scene.on_metrics(12.0, 7, 1, m, false);
  const auto f = scene.snapshot(1.05);
  CHECK(f["full"] == true);
  REQUIRE(f["agents"].size() == 1);
  CHECK(agent(f, 0)["id"] == 0);
  CHECK(agent(f, 0)["x1"].get<double>() == 0.1235);  // rounded to 1e-4
  CHECK(agent(f, 0)["x2"].get<double>() == -4.0);
  CHECK(agent(f, 0)["state"] == "alive");
  CHECK(agent(f, 0)["heard"] == 5);
  CHECK(agent(f, 0)["lateness_us"] == 250.0);
  CHECK(agent(f, 0)["model_time"] == 12.5);  // exact: the key of a recorded row
  CHECK(agent(f, 0)["epoch"] == 7);
  CHECK(f["model_time"] == 12.0);
  CHECK(f["epoch"] == 7);
  CHECK(f["outline"]["closed"] == true);
  CHECK(f["outline"]["points"].size() == 240);
  CHECK(f["chart"]["points"].size() == 1);
  CHECK(f["chart"]["points"][0][1] == 0.5);
  CHECK(f["chart"]["points"][0][2] == 0.1);
  CHECK(f["metrics"]["agents_alive"] == 1);
  CHECK(f["metrics"]["shape_error_mean"] == 0.5);
  CHECK(f["metrics"]["extent"].is_null());
  CHECK(f["centre"].is_null());
}

TEST_CASE("Scene::snapshot: a vehicle's heading while its pose is fresh, null before and after") {
  view::SceneParams p;
  p.dead_s = 1.0;
  view::Scene scene(p);
  scene.on_heading(2, 1.0, 100.0);  // a pose before the agent's state: nothing to draw it at
  scene.on_state(2, {1.0, 2.0}, 1.0, 1, 100.0);
  CHECK(agent(scene.snapshot(100.0), 0)["heading"].is_null());
  scene.on_heading(2, -2.5, 100.1);
  CHECK(agent(scene.snapshot(100.2), 0)["heading"] == -2.5);
  scene.on_heading(2, std::nan(""), 100.3);  // not a heading: the last one kept
  CHECK(agent(scene.snapshot(100.4), 0)["heading"] == -2.5);
  scene.on_state(2, {1.0, 2.0}, 2.0, 1, 101.2);  // the agent still heard, its vehicle's pose no longer
  CHECK(agent(scene.snapshot(101.2), 0)["heading"].is_null());
}

TEST_CASE("Scene: a new epoch or a model time going back starts the charts anew; one point per model time") {
  view::Scene scene;
  core::Metrics m;
  m.shape_error_mean = 1.0;
  scene.on_metrics(1.0, 1, 3, m, false);
  scene.on_metrics(1.0, 1, 3, m, false);
  scene.on_metrics(2.0, 1, 3, m, false);
  CHECK(scene.snapshot(0.0)["chart"]["points"].size() == 2);
  scene.on_metrics(0.5, 2, 3, m, false);
  CHECK(scene.snapshot(0.0)["chart"]["points"].size() == 1);
  scene.on_metrics(0.2, 2, 3, m, false);
  CHECK(scene.snapshot(0.0)["chart"]["points"].size() == 1);
}

TEST_CASE("Scene: trails keep the last trail_s seconds, one point per trail_step_s") {
  view::SceneParams p;
  p.trail_s = 2.0;
  p.trail_step_s = 0.2;
  view::Scene scene(p);
  for (int k = 0; k <= 100; ++k) scene.on_state(1, {0.01 * k, 0.0}, k, 1, 0.05 * k);  // 5 s at 20 Hz
  const auto f = scene.snapshot(5.0);
  const auto& pts = f["trails"];  // id, t, x1, x2 per point
  REQUIRE(pts.size() % 4 == 0);
  CHECK(pts.size() / 4 >= 9);
  CHECK(pts.size() / 4 <= 11);
  CHECK(pts[0] == 1);
  CHECK(pts[1].get<double>() >= 3.0);  // none older than trail_s
  CHECK(pts[pts.size() - 2].get<double>() >= 0.95);
}

TEST_CASE("Scene: the centre and its path; a command without tracking hides the centre") {
  view::Scene scene;
  scene.on_centre({1.0, 1.0});
  scene.on_centre({1.0, 1.0});
  scene.on_centre({2.0, 1.0});
  auto f = scene.snapshot(0.0);
  CHECK(f["centre"] == nlohmann::json::array({2.0, 1.0}));
  CHECK(f["centre_path"]["replace"] == true);
  CHECK(f["centre_path"]["points"].size() == 2);
  scene.on_command(circle(1.0), 2);
  CHECK(scene.snapshot(0.0)["centre"].is_null());
}

TEST_CASE("Scene::snapshot: the command's keep-out zones with their geometry and its separation; none without") {
  view::Scene scene;
  CHECK(scene.snapshot(0.0)["keep_out"] == nlohmann::json::array());
  CHECK(scene.snapshot(0.0)["min_separation"] == 0.0);
  core::Command c = circle(4.0);
  c.min_separation = 0.25;
  core::KeepOutZone disc;
  disc.kind = core::KeepOutZone::Kind::Circle;
  disc.centre = {5.0, -0.5};
  disc.radius = 1.25;
  core::KeepOutZone triangle;
  triangle.kind = core::KeepOutZone::Kind::Polygon;
  triangle.vertices = {{-3.5, 3.8}, {-1.5, 3.8}, {-2.5, 5.2}};
  c.keep_out = {disc, triangle};
  scene.on_command(shapes::compile(c), 3);
  const auto f = scene.snapshot(0.0);
  CHECK(f["min_separation"] == 0.25);
  REQUIRE(f["keep_out"].size() == 2);
  CHECK(f["keep_out"][0] == nlohmann::json({{"circle", {5.0, -0.5, 1.25}}}));
  CHECK(f["keep_out"][1] == nlohmann::json({{"polygon", {{-3.5, 3.8}, {-1.5, 3.8}, {-2.5, 5.2}}}}));
  CHECK(f["fence"].is_null());  // no fence set: the workspace box, not drawn
  c.fence = {{-6.0, -6.0}, {6.0, -6.0}, {6.0, 2.0}, {-6.0, 2.0}};
  c.fence_margin = 0.5;
  c.breach_action = core::BreachAction::Return;
  scene.on_command(shapes::compile(c), 4);
  const auto g = scene.snapshot(0.0);
  CHECK(g["fence"] == nlohmann::json({{"polygon", {{-6.0, -6.0}, {6.0, -6.0}, {6.0, 2.0}, {-6.0, 2.0}}},
                                      {"margin", 0.5},
                                      {"action", "return"}}));
  scene.on_command(circle(4.0), 5);  // a command without zones clears them
  CHECK(scene.snapshot(0.0)["keep_out"].empty());
  CHECK(scene.snapshot(0.0)["fence"].is_null());
  CHECK(scene.snapshot(0.0)["min_separation"] == 0.0);
}

TEST_CASE("Scene::snapshot: the run's safety figures, null until defined; the separation charted at the end") {
  view::Scene scene;
  auto f = scene.snapshot(0.0);
  REQUIRE(f["safety"].size() == 8);
  for (const auto& [name, value] : f["safety"].items()) CHECK(value.is_null());
  const nlohmann::json columns = {"model_time",   "shape_error_mean", "gap_cv",
                                  "agents_alive", "min_separation",   "min_separation_run"};
  CHECK(f["chart"]["columns"] == columns);

  core::Metrics m;
  m.shape_error_mean = 0.5;
  m.min_separation = 0.4;
  m.min_separation_run = 0.3;
  m.min_separation_run_time = 7.5;
  m.filter_interventions = 12;
  m.deadlock_sidesteps = 1;
  m.promises_broken = 0;
  m.agents_blocked = 2;
  m.fence_breaches = 0;  // agents_beyond_fence left undefined
  scene.on_metrics(10.0, 1, 5, m, false);
  m.min_separation = 0.35;
  scene.on_metrics(11.0, 1, 5, m, false);
  f = scene.snapshot(0.0);
  const auto& s = f["safety"];
  CHECK(s["min_separation_run"] == 0.3);
  CHECK(s["min_separation_run_time"] == 7.5);
  CHECK(s["filter_interventions"] == 12);
  CHECK(s["deadlock_sidesteps"] == 1);
  CHECK(s["promises_broken"] == 0);
  CHECK(s["agents_blocked"] == 2);
  CHECK(s["fence_breaches"] == 0);
  CHECK(s["agents_beyond_fence"].is_null());
  CHECK(f["metrics"]["agents_blocked"] == 2);
  const auto& pts = f["chart"]["points"];
  REQUIRE(pts.size() == 2);
  for (const auto& p : pts) REQUIRE(p.size() == columns.size());
  CHECK(pts[0] == nlohmann::json({10.0, 0.5, nullptr, 5.0, 0.4, 0.3}));
  CHECK(pts[1][4] == 0.35);
  CHECK(pts[1][5] == 0.3);
}

namespace {

/// What a page keeps, applying frames as view.js does: a full frame replaces everything; a delta
/// replaces the agents' rows it carries, appends trail points (dropping those older than
/// now_s - trail_s), appends or replaces the series, and takes the command's parts it carries.
struct Page {
  std::uint64_t seq = 0;
  std::map<std::int64_t, nlohmann::json> agents;
  std::vector<nlohmann::json> trail;  // [id, t, x1, x2]
  nlohmann::json centre_path = nlohmann::json::array(), chart = nlohmann::json::array();
  nlohmann::json outline, keep_out, fence, min_separation, centre;

  void apply(const nlohmann::json& f) {
    if (f["full"].get<bool>())
      *this = Page{};
    else
      REQUIRE(f["seq"].get<std::uint64_t>() == seq + 1);  // no gap
    seq = f["seq"];
    for (const auto& row : f["agents"]) agents[row[0].get<std::int64_t>()] = row;
    const auto& t = f["trails"];
    for (std::size_t k = 0; k < t.size(); k += 4) trail.push_back({t[k], t[k + 1], t[k + 2], t[k + 3]});
    const double oldest = f["now_s"].get<double>() - f["trail_s"].get<double>();
    trail.erase(std::remove_if(trail.begin(), trail.end(),
                               [&](const nlohmann::json& p) { return p[1].get<double>() < oldest; }),
                trail.end());
    for (auto [key, kept] : {std::pair{"centre_path", &centre_path}, std::pair{"chart", &chart}}) {
      if (f[key]["replace"].get<bool>()) *kept = nlohmann::json::array();
      for (const auto& p : f[key]["points"]) kept->push_back(p);
    }
    for (auto [key, kept] : {std::pair{"outline", &outline}, std::pair{"keep_out", &keep_out},
                             std::pair{"fence", &fence}, std::pair{"min_separation", &min_separation}}) {
      if (f.contains(key)) *kept = f[key];
    }
    centre = f["centre"];
  }

  /// The snapshot's content in the page's terms.
  static Page of(const nlohmann::json& snapshot) {
    Page p;
    p.apply(snapshot);
    return p;
  }
  void require_same(const Page& o) const {
    CHECK(seq == o.seq);
    CHECK(agents == o.agents);
    std::vector<nlohmann::json> a = trail, b = o.trail;
    std::sort(a.begin(), a.end());
    std::sort(b.begin(), b.end());
    CHECK(a == b);
    CHECK(centre_path == o.centre_path);
    CHECK(chart == o.chart);
    CHECK(outline == o.outline);
    CHECK(keep_out == o.keep_out);
    CHECK(fence == o.fence);
    CHECK(min_separation == o.min_separation);
    CHECK(centre == o.centre);
  }
};

}  // namespace

TEST_CASE("Scene::delta: a page applying every delta holds what a snapshot of the same moment says") {
  view::SceneParams p;
  p.trail_s = 1.0;
  p.chart_capacity = 8;  // thinned often: the charts are sent again whole
  p.centre_path_capacity = 8;
  view::Scene scene(p);
  Page page;
  std::optional<Page> late;
  core::Command tracked = circle(3.0);
  tracked.tracking.enabled = true;
  tracked.tracking.path.kind = core::CentrePath::Kind::Line;
  tracked.tracking.path.velocity = {0.1, 0.0};
  core::Metrics m;
  m.shape_error_mean = 0.5;
  std::size_t sizes = 0, fulls = 0;
  for (int k = 0; k < 300; ++k) {
    const double now = 0.05 * k;
    if (k == 20) scene.on_command(shapes::compile(tracked), 1);  // the outline moves from now on
    if (k == 150) {
      core::Command c = circle(2.0);
      c.min_separation = 0.3;
      scene.on_command(shapes::compile(c), 2);  // a new command: zones, separation change
    }
    for (int id = 0; id < 5; ++id) {
      if (id == 3 && k > 100) continue;     // falls silent: stale, then dead, still sent as it changes state
      if (id == 4 && k % 3 != 0) continue;  // moves every third tick only
      scene.on_state(id, {std::sin(0.01 * k + id), std::cos(0.02 * k) + id}, 0.1 * k, k < 150 ? 1 : 2, now);
      if (k % 7 == 0) scene.on_status(id, 3, 100.0 + k);
    }
    if (k % 2 == 0) {
      scene.on_centre({0.005 * k, 0.0});
      scene.on_metrics(0.1 * k, k < 150 ? 1 : 2, 4, m, false);
    }
    if (k == 200) scene.clear();  // a replay's seek back: the next delta is full
    const auto d = scene.delta(now);
    sizes += d.dump().size();
    fulls += d["full"].get<bool>();
    page.apply(d);
    if (late) late->apply(d);
    if (k == 50) late = Page::of(scene.snapshot(now));  // a stream that joins: the snapshot, then the deltas
    if (k % 10 == 0 || k == 201) {
      const Page now_page = Page::of(scene.snapshot(now));
      page.require_same(now_page);
      if (late) late->require_same(now_page);
    }
  }
  CHECK(fulls == 2);  // the first delta and the one after clear()
  CHECK(scene.seq() == 300);
}

TEST_CASE("Scene::delta: only what changed: agents that moved, trail points added, the command once") {
  view::SceneParams p;
  p.trail_step_s = 0.0;  // a trail point per state
  view::Scene scene(p);
  scene.on_command(circle(4.0), 1);
  scene.on_state(0, {1.0, 2.0}, 1.0, 1, 0.0);
  scene.on_state(1, {3.0, 4.0}, 1.0, 1, 0.0);
  const auto first = scene.delta(0.0);
  CHECK(first["full"] == true);
  CHECK(first["seq"] == 1);
  CHECK(first["agents"].size() == 2);
  CHECK(first["outline"]["points"].size() == 240);
  scene.on_state(1, {3.00001, 4.0}, 1.1, 1, 0.05);  // a new model time: sent
  scene.on_state(0, {1.00001, 2.0}, 1.0, 1, 0.05);  // moved less than the rounding, same model time: not sent
  const auto d = scene.delta(0.05);
  CHECK(d["full"] == false);
  CHECK(d["seq"] == 2);
  REQUIRE(d["agents"].size() == 1);
  CHECK(d["agents"][0][0] == 1);
  CHECK(d["trails"] == nlohmann::json::array({0, 0.05, 1.0, 2.0, 1, 0.05, 3.0, 4.0}));
  CHECK_FALSE(d.contains("outline"));  // not tracked: the same outline, not sent again
  CHECK_FALSE(d.contains("keep_out"));
  CHECK_FALSE(d.contains("fence"));
  CHECK_FALSE(d.contains("min_separation"));
  CHECK(d["chart"]["replace"] == false);
  CHECK(d["chart"]["points"].empty());
  const auto s = scene.snapshot(0.05);  // numbered as the latest delta, full, does not move the deltas on
  CHECK(s["seq"] == 2);
  CHECK(s["full"] == true);
  CHECK(s["agents"].size() == 2);
  const auto e = scene.delta(0.4);  // agents fall stale: their state changed, so they are sent
  CHECK(e["seq"] == 3);
  REQUIRE(e["agents"].size() == 2);
  CHECK(e["agents"][0][3] == "stale");
  CHECK(e["trails"].empty());
}

TEST_CASE("Scene::delta: at 1000 agents a delta of moved agents stays compact") {
  view::Scene scene;
  for (int id = 0; id < 1000; ++id) scene.on_state(id, {0.123456789 * id, -0.987654321 * id}, 12.5, 1, 0.0);
  scene.delta(0.0);
  for (int id = 0; id < 1000; ++id)
    scene.on_state(id, {0.123456789 * id + 0.01, -0.987654321 * id}, 12.6, 1, 0.1);
  const std::size_t bytes = scene.delta(0.1).dump().size();
  CHECK(bytes < 60 * 1000);  // under 60 bytes an agent (positions to 1e-4, no key names per agent)
}
