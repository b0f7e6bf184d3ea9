#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "monitor_fixtures.hpp"
#include "output.hpp"
#include "swarm_monitor.hpp"

using namespace shapeform;
using core::Vec2;
using supervisor::SwarmMonitor;

using test::circle;
using test::kS;
using test::ring;

TEST_CASE("an agent that follows no command yet is alive for the idle timeout, a commanded one for the agent timeout",
          "[supervisor]") {
  SwarmMonitor m(kS, {}, false, 15 * kS);  // agent.idle_rate_hz = 0.2: a state every 5 s until commanded
  m.on_state(0, Vec2(4, 0), Vec2(4, 0), 0, 0, 0);   // no command yet
  m.on_state(1, Vec2(-4, 0), Vec2(-4, 0), 1, 0, 0);  // epoch 1
  CHECK(m.alive(m.agents().at(0), 5 * kS));
  CHECK_FALSE(m.alive(m.agents().at(1), 5 * kS));
  CHECK(m.alive_count(15 * kS) == 1);
  CHECK(m.alive_count(15 * kS + 1) == 0);
  SwarmMonitor plain(kS, {});  // no idle timeout: the agent timeout for all
  plain.on_state(0, Vec2(4, 0), Vec2(4, 0), 0, 0, 0);
  CHECK_FALSE(plain.alive(plain.agents().at(0), 2 * kS));
}

TEST_CASE("alive, dead and departed agents", "[supervisor]") {
  SwarmMonitor m(kS, {});
  ring(m, 4, 4.0, 0, 0);
  CHECK(m.alive_count(kS / 2) == 4);
  m.on_departed(2);
  CHECK(m.alive_count(kS / 2) == 3);
  m.on_state(0, Vec2(4, 0), Vec2(4, 0), 0, 0, kS);
  CHECK(m.alive_count(kS + kS / 2) == 1);  // the others unheard for 1.5 s
  CHECK(m.agents().at(2).departed);
  CHECK_FALSE(m.agents().at(1).departed);  // silent, not departed (the status table's DEAD)
  CHECK_FALSE(m.alive(m.agents().at(1), kS + kS / 2));
}

TEST_CASE("metrics with the core functions; converged only when every agent follows the epoch", "[supervisor]") {
  core::ConvergenceDetector::Params p;
  p.hold = 10;
  SwarmMonitor m(kS, p);
  ring(m, 12, 4.0, 0, 0);
  auto s = m.update(0, 0);
  CHECK_FALSE(s.metrics.shape_error_mean);  // no command yet
  m.set_command(circle(), 1, 0);
  for (int k = 0; k <= 20; ++k) {
    ring(m, 12, 3.9, 0, k * 1000);  // still on epoch 0
    s = m.update(k, k * 1000);
    CHECK_FALSE(s.converged);
  }
  CHECK(*s.metrics.shape_error_mean == Approx(0.1));
  for (int k = 21; k <= 40; ++k) {
    ring(m, 12, 3.9, 1, k * 1000);
    s = m.update(k, k * 1000);
  }
  CHECK(s.following == 12);
  CHECK(s.converged);
  REQUIRE(m.settle_time({}));
  CHECK(*m.settle_time({}) == 21.0);
}

TEST_CASE("measure reports the metrics now without feeding the convergence detector", "[supervisor]") {
  core::ConvergenceDetector::Params p;
  p.hold = 10;
  SwarmMonitor m(kS, p);
  m.set_command(circle(), 1, 0);
  for (int k = 0; k <= 20; ++k) {
    ring(m, 12, 3.9, 1, k * 1000);
    m.update(k, k * 1000);
  }
  REQUIRE(m.converged());
  // The swarm has just moved off the plateau: the summary shows where it is, and still reports the
  // verdict of the samples the detector saw; update() would have reset it.
  ring(m, 12, 3.0, 1, 21 * 1000);
  const auto s = m.measure(21, 21 * 1000);
  CHECK(*s.metrics.shape_error_mean == Approx(1.0));
  CHECK(s.converged);
  CHECK(m.converged());
  CHECK(m.last()->model_time == 20.0);
  CHECK_FALSE(m.update(21, 21 * 1000).converged);
}

TEST_CASE("a restarted supervisor learns the newest epoch followed", "[supervisor]") {
  SwarmMonitor m(kS, {});
  ring(m, 3, 4.0, 7, 0);
  CHECK(m.max_epoch_seen() == 7);
}

namespace {

SwarmMonitor monitor_with_two_agents(bool lockstep) {
  SwarmMonitor m(kS, core::ConvergenceDetector::Params{}, lockstep);
  m.set_command(core::CompiledCommand{}, 1, 0);
  // Agent 0 has done step 3; agent 1 already step 4 (its step-3 position is prev).
  m.on_state(0, Vec2(1, 0), Vec2(0.5, 0), 1, 3.0, 0);
  m.on_state(1, Vec2(-1, 2), Vec2(-1, 1), 1, 4.0, 0);
  return m;
}

}  // namespace

TEST_CASE("swarm monitor: in lockstep a sample at step t takes every agent at step t", "[supervisor][monitor]") {
  const SwarmMonitor m = monitor_with_two_agents(true);
  REQUIRE(m.min_following_model_time(0) == Approx(3.0));
  const auto at3 = m.alive_positions(0, 3.0);
  REQUIRE(at3.size() == 2);
  CHECK(at3[0].second == Vec2(1, 0));   // at step 3: its current state
  CHECK(at3[1].second == Vec2(-1, 1));  // one step ahead: its previous state
  const auto latest = m.alive_positions(0);
  CHECK(latest[1].second == Vec2(-1, 2));
  // The metrics of the aligned sample are those of the step-3 positions.
  const auto s = m.measure(3.0, 0);
  REQUIRE(s.metrics.agents == 2);
  CHECK(s.metrics.extent.value() == Approx((Vec2(1, 0) - Vec2(-1, 1)).norm()));
}

TEST_CASE("swarm monitor: free-running agents are sampled at their latest state", "[supervisor][monitor]") {
  const SwarmMonitor m = monitor_with_two_agents(false);
  const auto at3 = m.alive_positions(0, 3.0);
  CHECK(at3[1].second == Vec2(-1, 2));
  CHECK(m.measure(3.0, 0).metrics.extent.value() == Approx((Vec2(1, 0) - Vec2(-1, 2)).norm()));
}

TEST_CASE("following means the same command: epoch and issuer; the lowest epoch followed", "[supervisor][order]") {
  SwarmMonitor m(kS, {});
  dds::SourceId mine, theirs;
  mine.prefix[0] = 1;
  theirs.prefix[0] = 2;
  m.set_command(circle(), dds::CommandId{5, mine}, 0);
  CHECK(m.min_epoch_followed(0) == 0);  // nobody heard
  m.on_state(0, Vec2(4, 0), Vec2(4, 0), dds::CommandId{5, mine}, 0, 0);
  m.on_state(1, Vec2(0, 4), Vec2(0, 4), dds::CommandId{5, theirs}, 0, 0);  // the same epoch, another issuer
  m.on_state(2, Vec2(-4, 0), Vec2(-4, 0), dds::CommandId{}, 0, 0);          // no command yet
  CHECK(m.following_count(0) == 1);
  CHECK(m.min_epoch_followed(0) == 5);
  m.on_state(2, Vec2(-4, 0), Vec2(-4, 0), dds::CommandId{(1ULL << 40), theirs}, 0, 0);
  CHECK(m.min_epoch_followed(0) == 5);
  CHECK(m.max_epoch_seen() == (1ULL << 40));  // 64-bit
}

static dds::SourceId source(std::uint8_t b) { return dds::SourceId{{1, 15, 0, 0, 0, 0, 0, 0, 0, 0, 0, b}}; }

TEST_CASE("swarm monitor: a second participant publishing an id in use is a duplicate, reported once",
          "[supervisor][monitor][identity]") {
  SwarmMonitor m(kS, {});
  const auto a = source(1), b = source(2);
  CHECK(m.claim(3, a, 0) == SwarmMonitor::Claim::Owner);  // unknown id: whoever comes first
  m.on_state(3, Vec2(1, 2), Vec2(1, 2), dds::CommandId{}, 0.0, 0, a);
  CHECK(m.agents().at(3).source == a);
  CHECK(m.claim(3, a, 10) == SwarmMonitor::Claim::Owner);
  CHECK(m.claim(3, b, 20) == SwarmMonitor::Claim::NewDuplicate);
  CHECK(m.claim(3, b, 30) == SwarmMonitor::Claim::Duplicate);  // reported once
  CHECK(m.claim(3, source(3), 30) == SwarmMonitor::Claim::NewDuplicate);
  CHECK(m.claim(3, dds::SourceId{}, 30) == SwarmMonitor::Claim::Owner);  // unknown source: cannot tell
  CHECK(m.claim(4, b, 30) == SwarmMonitor::Claim::Owner);                // another id: b owns it
  // The incumbent keeps the id while alive; once it fell silent (or left), the id is free again.
  CHECK(m.claim(3, b, kS) == SwarmMonitor::Claim::Duplicate);
  CHECK(m.claim(3, b, kS + 1) == SwarmMonitor::Claim::Owner);
  m.on_state(3, Vec2(0, 0), Vec2(0, 0), dds::CommandId{}, 0.0, kS + 1, b);
  CHECK(m.agents().at(3).source == b);
  m.on_departed(3);
  CHECK(m.claim(3, a, kS + 2) == SwarmMonitor::Claim::Owner);
}

TEST_CASE("membership events: joined, left and lost, each once, whatever the order of ids",
          "[supervisor][membership]") {
  SwarmMonitor m(kS, {});
  std::ostringstream human, events, errors;
  supervisor::Output out(true, human, events, errors);
  supervisor::MembershipReport report;
  const auto take = [&] {
    std::vector<std::string> lines;
    std::istringstream in(events.str());
    for (std::string line; std::getline(in, line);) {
      const auto j = nlohmann::json::parse(line);
      lines.push_back(std::to_string(j.at("id").get<int>()) + " " + j.at("change").get<std::string>());
    }
    events.str("");
    std::sort(lines.begin(), lines.end());
    return lines;
  };
  for (const int id : {5, 1, 9, 3}) m.on_state(id, Vec2(id, 0), Vec2(id, 0), 0, 0, 0);
  report.update(m, 0, out);
  CHECK(take() == std::vector<std::string>{"1 joined", "3 joined", "5 joined", "9 joined"});
  report.update(m, kS / 2, out);
  CHECK(take().empty());  // nothing changed: nothing said again
  m.on_departed(3);
  for (const int id : {0, 1, 7, 9}) m.on_state(id, Vec2(id, 0), Vec2(id, 0), 0, 0, kS);
  report.update(m, kS + kS / 2, out);  // 5 unheard for 1.5 s: lost; 3 disposed: left; 0 and 7 new
  CHECK(take() == std::vector<std::string>{"0 joined", "3 left", "5 lost", "7 joined"});
  report.update(m, 5 * kS, out);  // everyone silent
  CHECK(take() == std::vector<std::string>{"0 lost", "1 lost", "7 lost", "9 lost"});
}
