#include <catch2/catch.hpp>

#include "agent_logic.hpp"
#include "core/swarm.hpp"

using namespace shapeform;
using agent::AgentLogic;
using core::Vec2;

namespace {
constexpr std::int64_t kMs = 1'000'000;
core::Command circle() {
  core::Command c;
  c.shape.kind = core::ShapeKind::Circle;
  c.shape.r0 = 4;
  return c;
}
}  // namespace

TEST_CASE("before the first command the agent holds its position", "[agent]") {
  AgentLogic a(0, Vec2(1, 2), 60 * kMs);
  a.on_state(1, Vec2(0, 0), 1, 0);
  for (int k = 0; k < 5; ++k) a.step();
  CHECK(a.position() == Vec2(1, 2));
  CHECK(a.velocity() == Vec2::Zero());
  CHECK(a.epoch() == 0);
}

TEST_CASE("commands: newer epochs only; model time restarts", "[agent]") {
  AgentLogic a(0, Vec2(1, 2), 60 * kMs);
  CHECK(a.on_command(circle(), 3));
  a.step();
  a.step();
  CHECK(a.model_time() == 2.0);
  core::Command sq = circle();
  sq.shape.kind = core::ShapeKind::Square;
  CHECK_FALSE(a.on_command(sq, 3));  // same epoch: ignored
  CHECK_FALSE(a.on_command(sq, 2));  // older: ignored
  CHECK(a.command().shape.kind == core::ShapeKind::Circle);
  CHECK(a.on_command(sq, 4));
  CHECK(a.model_time() == 0.0);
  CHECK(a.command().shape.kind == core::ShapeKind::Square);
}

TEST_CASE("a tick of the agent is exactly the simulator's step", "[agent]") {
  // Three agents, each with the others' exact positions: AgentLogic must reproduce core::Swarm.
  const auto start = core::uniform_start(3, 9);
  core::Swarm swarm(circle(), start);
  std::vector<AgentLogic> agents;
  for (int i = 0; i < 3; ++i) agents.emplace_back(i, start[i], 60 * kMs);
  for (auto& a : agents) a.on_command(circle(), 1);
  std::uint64_t seq = 0;
  for (int k = 0; k < 50; ++k) {
    ++seq;
    for (auto& a : agents)
      for (const auto& b : agents) a.on_state(b.id(), b.position(), seq, 0);
    for (auto& a : agents) a.step();
    swarm.step();
  }
  for (int i = 0; i < 3; ++i) CHECK(agents[i].position() == swarm.positions()[i]);
}

TEST_CASE("neighbour table: latest per agent, losses counted, stale and departed dropped", "[agent]") {
  AgentLogic a(0, Vec2(0, 0), 60 * kMs);
  a.on_state(0, Vec2(9, 9), 1, 0);  // own sample: ignored
  CHECK(a.neighbours() == 0);
  a.on_state(1, Vec2(1, 0), 1, 0);
  a.on_state(1, Vec2(2, 0), 4, 10 * kMs);  // seq 2 and 3 lost
  a.on_state(1, Vec2(5, 5), 3, 11 * kMs);  // late, older: ignored
  a.on_state(2, Vec2(0, 1), 1, 10 * kMs);
  CHECK(a.neighbours() == 2);
  CHECK(a.counters().samples_lost == 2);
  CHECK(a.counters().samples_received == 3);
  a.drop_stale(65 * kMs);  // both last heard at 10 ms: 55 ms ago, within 60
  CHECK(a.neighbours() == 2);
  a.on_state(2, Vec2(0, 1), 2, 50 * kMs);
  a.drop_stale(71 * kMs);  // agent 1 unheard for 61 ms
  CHECK(a.neighbours() == 1);
  CHECK(a.counters().stale_dropped == 1);
  a.on_gone(2);
  CHECK(a.neighbours() == 0);
  CHECK(a.counters().departed == 1);
}

TEST_CASE("tracking follows the latest target, extrapolated over model time", "[agent][tracking]") {
  core::Command c = circle();
  c.shape.r0 = 2;
  c.tracking.enabled = true;
  c.tracking.path.kind = core::CentrePath::Kind::Line;
  c.tracking.path.point = Vec2(-10, -10);
  c.tracking.path.velocity = Vec2(0.1, 0.1);
  AgentLogic a(0, Vec2(0, 0), 60 * kMs);
  a.on_command(c, 1);
  // Without a target yet: the command's own path at the agent's model time.
  CHECK((*a.tracked_centre() - Vec2(-10, -10)).norm() < 1e-12);
  a.on_target({2, 0.0, Vec2(50, 50), Vec2(0, 0)});  // another epoch: ignored
  CHECK((*a.tracked_centre() - Vec2(-10, -10)).norm() < 1e-12);
  a.on_target({1, 30.0, Vec2(-7, -7), Vec2(0.1, 0.1)});
  CHECK((*a.tracked_centre() - Vec2(-7, -7)).norm() < 1e-12);
  a.step();
  a.step();
  CHECK((*a.tracked_centre() - Vec2(-6.8, -6.8)).norm() < 1e-12);
  a.on_target({1, 20.0, Vec2(-8, -8), Vec2(0.1, 0.1)});  // older than the one held: ignored
  CHECK((*a.tracked_centre() - Vec2(-6.8, -6.8)).norm() < 1e-12);
}

TEST_CASE("seeded starts match the simulator's uniform start", "[agent]") {
  const auto s = core::uniform_start(12, 7, 5.0);
  for (int i = 0; i < 12; ++i) CHECK(agent::seeded_start(i, 12, 7, 5.0) == s[i]);
  // An agent beyond the configured size still gets a deterministic start.
  CHECK(agent::seeded_start(15, 12, 7, 5.0) == core::uniform_start(16, 7, 5.0)[15]);
}

TEST_CASE("arc law: agents exchanging their arc lengths reproduce the simulator", "[agent][arc]") {
  core::Command cmd;
  cmd.law = core::Law::Arc;
  cmd.shape.kind = core::ShapeKind::Ellipse;
  const auto start = core::uniform_start(5, 4);
  core::Swarm swarm(cmd, start);
  std::vector<AgentLogic> agents;
  for (int i = 0; i < 5; ++i) agents.emplace_back(i, start[i], 60 * kMs);
  for (auto& a : agents) a.on_command(cmd, 1);
  std::uint64_t seq = 0;
  for (int k = 0; k < 40; ++k) {
    ++seq;
    for (auto& a : agents)
      for (const auto& b : agents) a.on_state(b.id(), b.position(), seq, 0, b.epoch(), b.arc());
    for (auto& a : agents) a.step();
    swarm.step();
  }
  for (int i = 0; i < 5; ++i) CHECK((agents[i].position() - swarm.positions()[i]).norm() < 1e-12);
  // A neighbour's arc length from another epoch is not used (it would belong to another shape).
  AgentLogic a(0, Vec2(4, 0), 60 * kMs);
  a.on_command(cmd, 2);
  a.on_state(1, Vec2(-4, 0), 1, 0, 1, 123.0);  // epoch 1: arc ignored, position projected instead
  AgentLogic b(0, Vec2(4, 0), 60 * kMs);
  b.on_command(cmd, 2);
  b.on_state(1, Vec2(-4, 0), 1, 0);
  a.step();
  b.step();
  CHECK(a.position() == b.position());
}
