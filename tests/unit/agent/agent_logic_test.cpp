#include <catch2/catch.hpp>

#include "agent_logic.hpp"
#include "config/config.hpp"
#include "core/swarm.hpp"

#include <map>
#include <memory>
#include <numeric>
#include <random>

using namespace shapeform;
using agent::AgentCounters;
using agent::AgentLogic;
using core::Vec2;

namespace {
constexpr std::int64_t kMs = 1'000'000;
core::CompiledCommand circle() {
  core::Command c;
  c.shape.kind = core::ShapeKind::Circle;
  c.shape.r0 = 4;
  return core::compile(c);
}
/// Offers `cmd` as epoch `epoch` of an unknown issuer; true when adopted.
bool adopt(AgentLogic& a, const core::CompiledCommand& cmd, std::uint64_t epoch, dds::SourceId issuer = {}) {
  return a.on_command(dds::CommandSample{cmd, dds::CommandId{epoch, issuer}, ""}) ==
         dds::CommandArbiter::Verdict::Adopted;
}
}  // namespace

TEST_CASE("before the first command the agent holds its position", "[agent]") {
  AgentLogic a(0, Vec2(1, 2), 60 * kMs);
  a.on_state(1, Vec2(0, 0), 1, 0);
  for (int k = 0; k < 5; ++k) a.step();
  CHECK(a.position() == Vec2(1, 2));
  CHECK(a.velocity() == Vec2::Zero());
  CHECK(a.command_id().none());
}

TEST_CASE("commands: newer epochs only; model time restarts", "[agent]") {
  AgentLogic a(0, Vec2(1, 2), 60 * kMs);
  CHECK(adopt(a, circle(), 3));
  a.step();
  a.step();
  CHECK(a.model_time() == 2.0);
  core::CompiledCommand sq = circle();
  sq.shape.kind = core::ShapeKind::Square;
  sq = core::compile(sq);
  CHECK_FALSE(adopt(a, sq, 3));  // same epoch: ignored
  CHECK_FALSE(adopt(a, sq, 2));  // older: ignored
  CHECK(a.command().shape.kind == core::ShapeKind::Circle);
  CHECK(adopt(a, sq, 4));
  CHECK(a.model_time() == 0.0);
  CHECK(a.command().shape.kind == core::ShapeKind::Square);
}

TEST_CASE("a tick of the agent is exactly the simulator's step", "[agent]") {
  // Three agents, each with the others' exact positions: AgentLogic must reproduce core::Swarm.
  const auto start = core::uniform_start(3, 9);
  core::Swarm swarm(circle(), start);
  std::vector<AgentLogic> agents;
  for (int i = 0; i < 3; ++i) agents.emplace_back(i, start[i], 60 * kMs);
  for (auto& a : agents) adopt(a, circle(), 1);
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

TEST_CASE("an agent driving a vehicle is exactly the simulator's agent driving it", "[agent][vehicle]") {
  // Every model, the arc law (arc lengths exchanged as processes do) and the paper's: AgentLogic and
  // core::Swarm call the same core::drive on the same law step.
  for (auto model : {core::VehicleModel::DoubleIntegrator, core::VehicleModel::Unicycle}) {
    for (auto law : {core::Law::Paper, core::Law::Arc}) {
      core::CompiledCommand cmd = circle();
      cmd.law = law;
      core::VehicleParams v;
      v.model = model;
      v.max_speed = 0.3;
      v.max_yaw_rate = 0.8;
      v.max_accel = 0.2;
      v.heading_spread = 3.0;
      const auto start = core::uniform_start(4, 9);
      const auto headings = core::start_headings(v, 4, 9);
      core::Swarm swarm(cmd, start);
      swarm.set_vehicle(v, headings);
      std::vector<AgentLogic> agents;
      for (int i = 0; i < 4; ++i) {
        agents.emplace_back(i, start[i], 60 * kMs);
        agents.back().set_vehicle(v, core::start_heading(v, i, 9));
        adopt(agents.back(), cmd, 1);
      }
      for (std::uint64_t seq = 1; seq <= 60; ++seq) {
        for (auto& a : agents)
          for (const auto& b : agents) a.on_state(b.id(), b.position(), seq, 0, b.command_id(), b.arc());
        for (auto& a : agents) a.step();
        swarm.step();
      }
      INFO(core::to_string(model) << " " << core::to_string(law));
      for (int i = 0; i < 4; ++i) {
        CHECK(agents[i].position() == swarm.positions()[i]);
        CHECK(agents[i].vehicle().heading == swarm.vehicles()[i].heading);
        CHECK(agents[i].vehicle().x == agents[i].position());
      }
    }
  }
}

TEST_CASE("a held agent's vehicle stops; with the default vehicle it moves as the law", "[agent][vehicle]") {
  AgentLogic a(0, Vec2(6, 0), 60 * kMs);
  core::VehicleParams v;
  v.model = core::VehicleModel::DoubleIntegrator;
  v.max_accel = 0.1;
  a.set_vehicle(v, 0.0);
  REQUIRE(adopt(a, circle(), 1));
  for (int k = 0; k < 5; ++k) a.step();
  CHECK(a.vehicle().velocity.norm() > 0.0);
  core::CompiledCommand held = circle();
  held.hold = true;
  REQUIRE(adopt(a, held, 2));
  const Vec2 at = a.position();
  CHECK_FALSE(a.step());
  CHECK(a.vehicle().velocity == Vec2::Zero());
  CHECK(a.position() == at);
  // No vehicle set: the integrator, whose step is the law's, bit for bit.
  AgentLogic plain(0, Vec2(6, 0), 60 * kMs);
  REQUIRE(adopt(plain, circle(), 1));
  plain.step();
  CHECK(plain.position() == core::agent_step(circle(), 0, Vec2(6, 0), {}, 0.0).x);
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

TEST_CASE("before its first command a neighbour is dropped after the idle timeout, then the loop's", "[agent]") {
  // agent.idle_rate_hz: until commanded, neighbours publish slowly, so silence is judged on that scale.
  AgentLogic a(0, Vec2(0, 0), 60 * kMs, false, 50, 1500 * kMs);
  a.on_state(1, Vec2(1, 0), 1, 0);
  a.drop_stale(1000 * kMs);  // 1 s without a sample: within 1.5 s while uncommanded
  CHECK(a.neighbours() == 1);
  a.drop_stale(1501 * kMs);
  CHECK(a.neighbours() == 0);
  a.on_state(1, Vec2(1, 0), 2, 2000 * kMs);
  REQUIRE(adopt(a, circle(), 1));
  a.drop_stale(2061 * kMs);  // commanded: 61 ms is past the loop's 60 ms
  CHECK(a.neighbours() == 0);
  CHECK(a.counters().stale_dropped == 2);
}

TEST_CASE("a shared table: each sample once, each hosted agent's counters as a table of its own", "[agent]") {
  auto table = std::make_shared<agent::NeighbourTable>(std::vector<std::int32_t>{3, 4}, 60 * kMs);
  AgentLogic a(3, Vec2(0, 0), table), b(4, Vec2(1, 0), table);
  AgentLogic alone(3, Vec2(0, 0), 60 * kMs);  // agent 3 with a table of its own, hearing the same
  const auto hear = [&](std::int32_t id, std::uint64_t seq, std::int64_t t) {
    table->on_state(id, Vec2(id, 0), seq, t, {}, std::nullopt, 0.0, std::nullopt, std::nullopt, 1.0);
    alone.on_state(id, Vec2(id, 0), seq, t);
  };
  hear(3, 1, 0);  // agent 3's own sample, back from the wire
  hear(4, 1, 0);  // its co-hosted neighbour
  hear(9, 1, 0);
  hear(9, 4, 10 * kMs);  // 2 lost
  hear(3, 3, 10 * kMs);  // agent 3 lost one of its own: not its loss
  CHECK(table->entries().size() == 3);
  CHECK(a.neighbours() == 2);  // 4 and 9
  CHECK(b.neighbours() == 2);  // 3 and 9
  CHECK(a.counters().samples_received == 3);  // 4 once, 9 twice
  CHECK(a.counters().samples_lost == 2);
  CHECK(b.counters().samples_received == 4);  // 3 twice, 9 twice
  CHECK(b.counters().samples_lost == 3);
  table->on_gone(4);
  alone.on_gone(4);
  hear(9, 5, 50 * kMs);
  a.drop_stale(71 * kMs);  // 3 heard at 10 ms: dropped once, whichever agent asks
  b.drop_stale(71 * kMs);
  CHECK(b.counters().stale_dropped == 1);
  CHECK(a.counters().stale_dropped == 0);  // its own entry is no neighbour of its own
  CHECK(a.counters().departed == 1);
  CHECK(b.counters().departed == 0);
  for (const auto& k : {&AgentCounters::samples_received, &AgentCounters::samples_lost, &AgentCounters::stale_dropped,
                        &AgentCounters::departed}) {
    alone.drop_stale(71 * kMs);
    CHECK(a.counters().*k == alone.counters().*k);
  }
  CHECK(a.neighbours() == alone.neighbours());
}

TEST_CASE("hosted agents stepped together take each one's own step (the arc law, bit for bit)", "[agent]") {
  core::CompiledCommand c = circle();
  c.law = core::Law::Arc;
  const auto start = core::uniform_start(8, 3);
  // Agents 0..4 hosted in one process; 5..7 heard from elsewhere with their arc lengths.
  auto table = std::make_shared<agent::NeighbourTable>(std::vector<std::int32_t>{0, 1, 2, 3, 4}, 60 * kMs);
  std::vector<std::unique_ptr<AgentLogic>> shared, own;
  for (std::int32_t i = 0; i < 5; ++i) {
    shared.push_back(std::make_unique<AgentLogic>(i, start[static_cast<std::size_t>(i)], table));
    own.push_back(std::make_unique<AgentLogic>(i, start[static_cast<std::size_t>(i)], 60 * kMs));
  }
  for (auto* set : {&shared, &own})
    for (auto& l : *set) REQUIRE(adopt(*l, c, 1));
  std::vector<AgentLogic*> group;
  for (auto& l : shared) {
    CHECK(l->shares_step_with(*shared.front()));
    group.push_back(l.get());
  }
  CHECK_FALSE(own[1]->shares_step_with(*own[0]));  // tables of their own
  const dds::CommandId cmd = shared.front()->command_id();
  for (std::uint64_t seq = 1; seq <= 20; ++seq) {
    for (std::int32_t j = 5; j < 8; ++j) {
      const Vec2 x = start[static_cast<std::size_t>(j)] * (1.0 - 0.02 * static_cast<double>(seq));
      const double arc = core::closest_point(c.shape, c.curve(), x).s + 0.01 * j;
      table->on_state(j, x, seq, 0, cmd, arc, 0.0, std::nullopt, std::nullopt, 1.0);
      for (auto& l : own) l->on_state(j, x, seq, 0, cmd, arc);
    }
    // Each alone hears the other hosted agents where they are, without an arc length (projected),
    // as a shared step sees them.
    for (auto& l : own)
      for (auto& m : own) l->on_state(m->id(), m->position(), seq, 0);
    // The process hears its own agents too (the law leaves them out; the gap counts them as heard).
    for (auto& m : shared) table->on_state(m->id(), m->position(), seq, 0, {}, std::nullopt, 0.0, std::nullopt, std::nullopt, 1.0);
    AgentLogic::step_shared(group);
    for (auto& l : own) l->step();
    for (std::size_t k = 0; k < 5; ++k) {
      CHECK(shared[k]->position().x() == own[k]->position().x());
      CHECK(shared[k]->position().y() == own[k]->position().y());
      CHECK(shared[k]->velocity() == own[k]->velocity());
      CHECK(shared[k]->model_time() == own[k]->model_time());
      CHECK(shared[k]->previous_arc() == own[k]->previous_arc());
      // The gaps booked in one pass for the group are each agent's own, bit for bit.
      REQUIRE(own[k]->safety().min_gap > 0.0);
      CHECK(shared[k]->safety().min_gap == own[k]->safety().min_gap);
      CHECK(shared[k]->safety().min_gap_time == own[k]->safety().min_gap_time);
    }
  }
  // The group does not share once its agents follow different model times.
  shared[2]->step();
  CHECK_FALSE(shared[2]->shares_step_with(*shared.front()));
}

TEST_CASE("tracking follows the latest target, extrapolated over model time", "[agent][tracking]") {
  core::CompiledCommand c = circle();
  c.shape.r0 = 2;
  c = core::compile(c);
  c.tracking.enabled = true;
  c.tracking.path.kind = core::CentrePath::Kind::Line;
  c.tracking.path.point = Vec2(-10, -10);
  c.tracking.path.velocity = Vec2(0.1, 0.1);
  AgentLogic a(0, Vec2(0, 0), 60 * kMs);
  adopt(a, c, 1);
  // Without a target yet: the command's own path at the agent's model time.
  CHECK((*a.tracked_centre() - Vec2(-10, -10)).norm() < 1e-12);
  a.on_target({2, 0.0, Vec2(50, 50), Vec2(0, 0)}, 0);  // another epoch: ignored
  CHECK((*a.tracked_centre() - Vec2(-10, -10)).norm() < 1e-12);
  a.on_target({1, 30.0, Vec2(-7, -7), Vec2(0.1, 0.1)}, 0);
  CHECK(a.following_target());
  CHECK((*a.tracked_centre() - Vec2(-7, -7)).norm() < 1e-12);
  a.step();
  a.step();
  CHECK((*a.tracked_centre() - Vec2(-6.8, -6.8)).norm() < 1e-12);
  a.on_target({1, 20.0, Vec2(-8, -8), Vec2(0.1, 0.1)}, 0);  // older than the one held: ignored
  CHECK((*a.tracked_centre() - Vec2(-6.8, -6.8)).norm() < 1e-12);
  // The supervisor goes quiet: still the target within the timeout, then the command's own path at
  // the agent's model time (2 steps: (-10, -10) + 2 (0.1, 0.1)), not the last target flown on for ever.
  a.drop_stale(AgentLogic::kTargetTimeout_ns);
  CHECK(a.following_target());
  a.drop_stale(AgentLogic::kTargetTimeout_ns + 1);
  CHECK_FALSE(a.following_target());
  CHECK((*a.tracked_centre() - Vec2(-9.8, -9.8)).norm() < 1e-12);
  // A target heard again is followed again.
  a.on_target({1, 40.0, Vec2(-6, -6), Vec2(0.1, 0.1)}, 2 * AgentLogic::kTargetTimeout_ns);
  CHECK((*a.tracked_centre() - Vec2(-6, -6)).norm() < 1e-12);
}

TEST_CASE("seeded starts match the simulator's uniform start", "[agent]") {
  const auto s = core::uniform_start(12, 7, 5.0);
  for (int i = 0; i < 12; ++i) CHECK(agent::seeded_start(i, 12, 7, 5.0) == s[i]);
  // An agent beyond the configured size still gets a deterministic start.
  CHECK(agent::seeded_start(15, 12, 7, 5.0) == core::uniform_start(16, 7, 5.0)[15]);
}

TEST_CASE("arc law: agents exchanging their arc lengths reproduce the simulator", "[agent][arc]") {
  core::Command ellipse;
  ellipse.law = core::Law::Arc;
  ellipse.shape.kind = core::ShapeKind::Ellipse;
  const core::CompiledCommand cmd = core::compile(ellipse);
  const auto start = core::uniform_start(5, 4);
  core::Swarm swarm(cmd, start);
  std::vector<AgentLogic> agents;
  for (int i = 0; i < 5; ++i) agents.emplace_back(i, start[i], 60 * kMs);
  for (auto& a : agents) adopt(a, cmd, 1);
  std::uint64_t seq = 0;
  for (int k = 0; k < 40; ++k) {
    ++seq;
    for (auto& a : agents)
      for (const auto& b : agents) a.on_state(b.id(), b.position(), seq, 0, b.command_id(), b.arc());
    for (auto& a : agents) a.step();
    swarm.step();
  }
  for (int i = 0; i < 5; ++i) CHECK((agents[i].position() - swarm.positions()[i]).norm() < 1e-12);
  // A neighbour's arc length from another epoch is not used (it would belong to another shape).
  AgentLogic a(0, Vec2(4, 0), 60 * kMs);
  adopt(a, cmd, 2);
  a.on_state(1, Vec2(-4, 0), 1, 0, 1, 123.0);  // epoch 1: arc ignored, position projected instead
  AgentLogic b(0, Vec2(4, 0), 60 * kMs);
  adopt(b, cmd, 2);
  b.on_state(1, Vec2(-4, 0), 1, 0);
  a.step();
  b.step();
  CHECK(a.position() == b.position());
}

namespace {
/// Agents ticking once per period in a random order, each publishing after every tick (stepped or
/// held), so that an agent sees some neighbours already at step k+1 and others still at k, as
/// processes do; a fraction `loss` of deliveries is lost. Agents stop stepping at `steps`.
std::vector<Vec2> run_shuffled(const core::CompiledCommand& cmd, const std::vector<Vec2>& start, bool lockstep, long steps,
                               double loss = 0.0) {
  std::vector<AgentLogic> agents;
  for (int i = 0; i < static_cast<int>(start.size()); ++i) agents.emplace_back(i, start[i], 60 * kMs, lockstep);
  std::mt19937 rng(11);
  std::bernoulli_distribution lost(loss);
  std::vector<std::uint64_t> seq(start.size(), 0);
  const auto publish = [&](int i) {
    ++seq[i];
    for (auto& b : agents)
      if (!lost(rng))  // a best-effort sample may not arrive
        b.on_state(i, agents[i].position(), seq[i], 0, agents[i].command_id(), agents[i].arc(), agents[i].model_time(),
                   agents[i].previous_position(), agents[i].previous_arc());
  };
  // As processes do: agents publish while they hold, before the first command, so they know each other
  // (the supervisor's `wait agents N` precedes `start`); a lockstep barrier waits only for known agents.
  for (int round = 0; round < 20; ++round)
    for (int i = 0; i < static_cast<int>(agents.size()); ++i) publish(i);
  for (auto& a : agents) adopt(a, cmd, 1);
  for (int i = 0; i < static_cast<int>(agents.size()); ++i) publish(i);
  std::vector<int> order(agents.size());
  std::iota(order.begin(), order.end(), 0);
  for (int period = 0; period < 100 * steps; ++period) {
    bool done = true;
    for (const auto& a : agents) done = done && a.model_time() >= static_cast<double>(steps);
    if (done) break;
    std::shuffle(order.begin(), order.end(), rng);
    for (int i : order) {
      if (agents[i].model_time() < static_cast<double>(steps)) agents[i].step();
      publish(i);
    }
  }
  std::vector<Vec2> out;
  for (const auto& a : agents) out.push_back(a.position());
  return out;
}
}  // namespace

TEST_CASE("lockstep agents in any tick order reproduce the simulator exactly", "[agent][lockstep]") {
  for (auto law : {core::Law::Paper, core::Law::Arc}) {
    core::Command square;
    square.law = law;
    square.shape.kind = core::ShapeKind::Square;
    square.shape.a = 5;
    const core::CompiledCommand cmd = core::compile(square);
    const auto start = core::uniform_start(8, 3);
    core::Swarm swarm(cmd, start);
    for (int k = 0; k < 60; ++k) swarm.step();
    const auto lock = run_shuffled(cmd, start, true, 60);
    for (int i = 0; i < 8; ++i) CHECK((lock[i] - swarm.positions()[i]).norm() < 1e-12);
    // Lost samples only delay a lockstep swarm: each sample also carries the sender's previous step.
    const auto lossy = run_shuffled(cmd, start, true, 60, 0.3);
    for (int i = 0; i < 8; ++i) CHECK((lossy[i] - swarm.positions()[i]).norm() < 1e-12);
    // Free running under the same schedule is a different (asynchronous) iteration.
    if (law == core::Law::Paper) {
      const auto free = run_shuffled(cmd, start, false, 60);
      double diff = 0;
      for (int i = 0; i < 8; ++i) diff = std::max(diff, (free[i] - swarm.positions()[i]).norm());
      CHECK(diff > 1e-6);
    }
  }
}

TEST_CASE("lockstep: wait for a lagging neighbour, a late joiner starts at the swarm's step", "[agent][lockstep]") {
  const core::CompiledCommand cmd;
  AgentLogic a(0, Vec2(1, 0), 60 * kMs, true, 3);
  adopt(a, cmd, 1);
  a.on_state(1, Vec2(-1, 0), 1, 0, 1, std::nullopt, 0.0);
  CHECK(a.step());  // neighbour at step 0: step 0 -> 1
  CHECK_FALSE(a.step());  // the neighbour has not published step 1 yet: hold
  CHECK(a.model_time() == 1.0);
  a.on_state(1, Vec2(-1, 0), 2, 0, 1, std::nullopt, 1.0);
  CHECK(a.step());
  CHECK(a.model_time() == 2.0);
  // A neighbour that never advances is waited for at most max_wait_ticks (3) ticks.
  int held = 0;
  while (!a.step()) ++held;
  CHECK(held == 3);
  // A late joiner adopts the step of the swarm it joins.
  AgentLogic late(5, Vec2(0, 3), 60 * kMs, true);
  late.on_state(0, a.position(), 9, 0, 1, std::nullopt, a.model_time());
  adopt(late, cmd, 1);
  CHECK(late.model_time() == a.model_time());
}

TEST_CASE("a held command: the agent keeps its position, model time stands still; resume moves on", "[agent][hold]") {
  for (const bool lockstep : {false, true}) {
    INFO("lockstep " << lockstep);
    core::CompiledCommand c = circle();
    c.tracking.enabled = true;
    c.tracking.path.kind = core::CentrePath::Kind::Line;
    c.tracking.path.velocity = Vec2(0.1, 0);
    AgentLogic a(0, Vec2(9, 9), 60 * kMs, lockstep);
    a.on_state(1, Vec2(-9, 9), 1, 0, 1, std::nullopt, 0.0);
    REQUIRE(adopt(a, c, 1));
    REQUIRE(a.step());
    const Vec2 moved = a.position();
    CHECK(moved != Vec2(9, 9));
    // The same command held, as the supervisor's `hold` publishes it (a new epoch).
    core::CompiledCommand held = c;
    held.hold = true;
    REQUIRE(adopt(a, held, 2));
    a.on_state(1, Vec2(-9, 9), 2, 0, 2, std::nullopt, 0.0);
    for (int k = 0; k < 20; ++k) CHECK_FALSE(a.step());
    CHECK(a.position() == moved);  // exactly: not even rounding
    CHECK(a.velocity() == Vec2::Zero());
    CHECK(a.previous_position() == moved);
    CHECK(a.model_time() == 0.0);
    CHECK((*a.tracked_centre() - Vec2(0, 0)).norm() == 0.0);  // the tracked centre does not move on
    // A late target of the held epoch changes nothing either.
    a.on_target({2, 5.0, Vec2(3, 3), Vec2(1, 1)}, 0);
    CHECK_FALSE(a.step());
    CHECK(a.position() == moved);
    // resume: the same command with hold off, a new epoch: the agent moves again.
    REQUIRE(adopt(a, c, 3));
    a.on_state(1, Vec2(-9, 9), 3, 0, 3, std::nullopt, 0.0);
    CHECK(a.step());
    CHECK(a.position() != moved);
    CHECK(a.model_time() == c.dt);
  }
}

namespace {
dds::SourceId issuer(std::uint8_t first) {
  dds::SourceId s;
  s.prefix[0] = first;
  s.prefix[11] = 7;
  return s;
}
core::CompiledCommand square() {
  core::Command c;
  c.shape.kind = core::ShapeKind::Square;
  c.shape.a = 5;
  return core::compile(c);
}
}  // namespace

TEST_CASE("commands: one epoch from two issuers, every agent ends on the greater issuer", "[agent][order]") {
  // Two commanders publish epoch 5 at once; agents receive the two in either order.
  AgentLogic a(0, Vec2(1, 2), 60 * kMs), b(1, Vec2(3, 4), 60 * kMs);
  const dds::CommandSample low{circle(), dds::CommandId{5, issuer(1)}, "low"};
  const dds::CommandSample high{square(), dds::CommandId{5, issuer(2)}, "high"};
  using V = dds::CommandArbiter::Verdict;
  CHECK(a.on_command(low) == V::Adopted);
  CHECK(a.on_command(high) == V::Adopted);
  CHECK(b.on_command(high) == V::Adopted);
  CHECK(b.on_command(low) == V::Older);
  for (const AgentLogic* x : {&a, &b}) {
    CHECK(x->command_id() == high.id);
    CHECK(x->command().shape.kind == core::ShapeKind::Square);
    CHECK(x->command_sample().issuer_name == "high");
  }
  // The re-offered copy of the command followed changes nothing; a later epoch of the loser wins.
  CHECK(a.on_command(high) == V::Same);
  const dds::CommandSample next{circle(), dds::CommandId{6, issuer(1)}, "low"};
  CHECK(a.on_command(next) == V::Adopted);
  CHECK(b.on_command(next) == V::Adopted);
  CHECK((a.command_id() == b.command_id() && a.command_id().epoch == 6));
  CHECK(a.counters().samples_rejected == 0);
}

TEST_CASE("commands: the order is (epoch, issuer bytewise)", "[agent][order]") {
  CHECK(dds::CommandId{5, issuer(9)} < dds::CommandId{6, issuer(1)});
  CHECK(dds::CommandId{5, issuer(1)} < dds::CommandId{5, issuer(2)});
  dds::SourceId last_byte = issuer(1);
  last_byte.prefix[11] = 8;
  CHECK(dds::CommandId{5, issuer(1)} < dds::CommandId{5, last_byte});
  CHECK_FALSE(dds::CommandId{5, issuer(1)} < dds::CommandId{5, issuer(1)});
  CHECK(dds::CommandId{1ULL << 32, {}} > dds::CommandId{(1ULL << 32) - 1, issuer(0xff)});  // 64-bit: no wrap
}

TEST_CASE("commands: an absurd epoch jump is refused and counted, later commands are obeyed", "[agent][order]") {
  AgentLogic a(0, Vec2(1, 2), 60 * kMs);
  REQUIRE(adopt(a, circle(), 5));
  using V = dds::CommandArbiter::Verdict;
  for (const std::uint64_t rogue : {std::uint64_t{(1ULL << 32) - 1}, std::uint64_t{~0ULL}, 5 + dds::kMaxEpochJump + 1}) {
    INFO(rogue);
    CHECK(a.on_command(dds::CommandSample{square(), dds::CommandId{rogue, issuer(3)}, "rogue"}) == V::Refused);
    CHECK(a.command_id().epoch == 5);
    CHECK(a.command().shape.kind == core::ShapeKind::Circle);
  }
  CHECK(a.counters().samples_rejected == 3);
  CHECK_FALSE(a.recheck_commands());  // the neighbours change nothing for an agent that follows a command
  CHECK(adopt(a, square(), 6));        // the supervisor's next command
  CHECK(a.command().shape.kind == core::ShapeKind::Square);
  CHECK(adopt(a, circle(), 6 + dds::kMaxEpochJump));  // the largest step accepted
  CHECK(a.command_id().epoch == 6 + dds::kMaxEpochJump);
}

TEST_CASE("commands: a fresh agent judges jumps from the epoch its neighbours follow", "[agent][order]") {
  using V = dds::CommandArbiter::Verdict;
  const std::uint64_t swarm = 3 * dds::kMaxEpochJump;  // an epoch far above 0, reached step by step
  const dds::CommandSample in_force{circle(), dds::CommandId{swarm, issuer(1)}, "supervisor"};
  const dds::CommandSample rogue{square(), dds::CommandId{~0ULL, issuer(9)}, "rogue"};
  SECTION("no neighbour heard yet: judged from 0, refused, then adopted once they are heard") {
    AgentLogic a(0, Vec2(1, 2), 60 * kMs);
    CHECK(a.on_command(rogue) == V::Refused);
    CHECK(a.on_command(in_force) == V::Refused);
    CHECK_FALSE(a.has_command());
    CHECK_FALSE(a.recheck_commands());
    a.on_state(1, Vec2(0, 0), 1, 0, in_force.id);
    a.on_state(2, Vec2(0, 1), 1, 0, in_force.id);
    CHECK(a.recheck_commands());
    CHECK(a.command_id() == in_force.id);  // the swarm's command, not the rogue's
    CHECK_FALSE(a.recheck_commands());
  }
  SECTION("neighbours heard first: the swarm's command at once, the rogue's refused") {
    AgentLogic a(0, Vec2(1, 2), 60 * kMs);
    a.on_state(1, Vec2(0, 0), 1, 0, in_force.id);
    CHECK(a.on_command(rogue) == V::Refused);
    CHECK(a.on_command(in_force) == V::Adopted);
    CHECK(a.command_id() == in_force.id);
  }
  SECTION("a fresh swarm: the first epochs are small and adopted at once") {
    AgentLogic a(0, Vec2(1, 2), 60 * kMs);
    CHECK(adopt(a, circle(), 1));
  }
}

TEST_CASE("tracking targets of another command with the same epoch are ignored", "[agent][order]") {
  AgentLogic a(0, Vec2(1, 2), 60 * kMs);
  core::Command c = circle();
  c.tracking.enabled = true;
  REQUIRE(adopt(a, core::compile(c), 5, issuer(2)));
  a.on_target(dds::TargetSample{dds::CommandId{5, issuer(1)}, 0.0, Vec2(9, 9), Vec2::Zero(), 0}, 0);
  CHECK_FALSE(a.following_target());
  a.on_target(dds::TargetSample{dds::CommandId{5, issuer(2)}, 0.0, Vec2(9, 9), Vec2::Zero(), 0}, 0);
  CHECK(a.following_target());
}

/// A participant whose GUID prefix ends in b (so participant(1) < participant(2)).
static dds::SourceId participant(std::uint8_t b) { return dds::SourceId{{1, 15, 0, 0, 0, 0, 0, 0, 0, 0, 0, b}}; }

TEST_CASE("identity: a newcomer that hears its id during the grace period yields without publishing",
          "[agent][identity]") {
  agent::IdentityGuard g(participant(1), 1000);
  CHECK_FALSE(g.may_publish(999));  // listening
  CHECK(g.on_sample(3, participant(1)) == agent::IdentityGuard::Action::None);  // our own sample
  CHECK(g.on_sample(3, dds::SourceId{}) == agent::IdentityGuard::Action::None);  // unknown: cannot tell
  // Even from a higher GUID prefix: whoever published first keeps the id.
  CHECK(g.on_sample(3, participant(9)) == agent::IdentityGuard::Action::Yield);
  CHECK(g.yielding());
  CHECK_FALSE(g.may_publish(2000));  // never publishes
  CHECK(g.on_sample(3, participant(9)) == agent::IdentityGuard::Action::None);
}

TEST_CASE("identity: after the grace period the higher GUID prefix yields, the lower keeps the id",
          "[agent][identity]") {
  agent::IdentityGuard low(participant(2), 1000), high(participant(5), 1000);
  CHECK(low.may_publish(1000));
  CHECK(high.may_publish(1000));
  low.published();
  high.published();
  // Each sees the other: both decide alike, exactly one yields.
  CHECK(low.on_sample(7, participant(5)) == agent::IdentityGuard::Action::Keep);
  CHECK(high.on_sample(7, participant(2)) == agent::IdentityGuard::Action::Yield);
  CHECK_FALSE(low.yielding());
  CHECK(low.may_publish(5000));
  CHECK(high.yielding());
  CHECK(low.on_sample(7, participant(5)) == agent::IdentityGuard::Action::None);  // reported once
  CHECK(low.on_sample(8, participant(5)) == agent::IdentityGuard::Action::Keep);  // another hosted id
}

namespace {
/// The paper's tracking experiment: a ring of radius 2 around a centre moving on the line path
/// C(t) = (-10, -10) + t (0.1, 0.1), with feed-forward.
core::CompiledCommand tracking_ff(core::CentrePath::Kind path = core::CentrePath::Kind::Line) {
  core::CompiledCommand c = circle();
  c.shape.r0 = 2;
  c = core::compile(c);
  c.tracking.enabled = true;
  c.tracking.feedforward = true;
  c.tracking.path.kind = path;
  c.tracking.path.point = Vec2(-10, -10);
  c.tracking.path.velocity = Vec2(0.1, 0.1);
  return c;
}
struct Heard {
  Vec2 before, after;  ///< agent 0's position before and after the step that heard agent 1
  double t;            ///< agent 0's model time at that step
};
/// Agent 0 (free running) takes `alone` steps of cmd without neighbours, then one hearing agent 1 at
/// x1, model time t1, on the command followed (or on `other`, when given).
Heard step_hearing(const core::CompiledCommand& cmd, int alone, const Vec2& x1, double t1,
                   std::optional<dds::CommandId> other = std::nullopt) {
  AgentLogic a(0, Vec2(-9, -10), 60 * kMs);
  REQUIRE(adopt(a, cmd, 1));
  for (int k = 0; k < alone; ++k) a.step();
  const Vec2 before = a.position();
  const double t = a.model_time();
  a.on_state(1, x1, 1, 0, other.value_or(a.command_id()), std::nullopt, t1);
  a.step();
  return {before, a.position(), t};
}
/// Where the law's step from h.before goes when agent 1 is seen at `seen`.
Vec2 law_step(const core::CompiledCommand& cmd, const Heard& h, const Vec2& seen) {
  return core::agent_step(cmd, 0, h.before, {core::Neighbour{1, seen}}, h.t).x;
}
}  // namespace

TEST_CASE(
    "free running, tracking with feed-forward: a neighbour of another step is seen at the agent's model time",
    "[agent][tracking]") {
  const core::CompiledCommand c = tracking_ff();
  const Vec2 x1(-11, -9.5), v = c.tracking.path.velocity;
  SECTION("a neighbour one step ahead is moved back by the centre's motion over a step") {
    const Heard h = step_hearing(c, 0, x1, 1.0);
    CHECK(h.after == law_step(c, h, x1 + (-1.0 * c.dt) * v));
    CHECK(h.after != law_step(c, h, x1));
  }
  SECTION("a neighbour one step behind is moved on") {
    const Heard h = step_hearing(c, 3, x1, 2.0);
    CHECK(h.after == law_step(c, h, x1 + (1.0 * c.dt) * v));
  }
  SECTION("on the circle path, with dC/dt at the agent's own model time") {
    const core::CompiledCommand cc = tracking_ff(core::CentrePath::Kind::Circle);
    const Heard h = step_hearing(cc, 3, x1, 4.0);
    CHECK(h.after == law_step(cc, h, x1 + (-1.0 * cc.dt) * core::centre_velocity(cc.tracking.path, 3.0)));
  }
  SECTION("following the supervisor's target: moved with the target's velocity") {
    AgentLogic a(0, Vec2(-9, -10), 60 * kMs);
    REQUIRE(adopt(a, c, 1));
    const Vec2 centre(-8, -8), vt(0.2, 0.0);
    a.on_target({1, 20.0, centre, vt}, 0);
    a.on_state(1, x1, 1, 0, a.command_id(), std::nullopt, 1.0);
    a.step();
    core::CompiledCommand local = c;
    local.tracking.path.point = centre;
    local.tracking.path.velocity = vt;
    CHECK(a.position() == law_step(local, {Vec2(-9, -10), Vec2::Zero(), 0.0}, x1 - vt));
  }
  SECTION(
      "taken as heard: the same step, farther than a step, another command, no feed-forward, a fixed "
      "centre") {
    const Heard same = step_hearing(c, 2, x1, 2.0);
    CHECK(same.after == law_step(c, same, x1));
    const Heard far = step_hearing(c, 0, x1, 2.0);  // a clock that started apart, not a stale state
    CHECK(far.after == law_step(c, far, x1));
    const Heard other = step_hearing(c, 0, x1, 1.0, dds::CommandId{7, {}});
    CHECK(other.after == law_step(c, other, x1));
    core::CompiledCommand no_ff = c;
    no_ff.tracking.feedforward = false;
    const Heard plain = step_hearing(no_ff, 0, x1, 1.0);
    CHECK(plain.after == law_step(no_ff, plain, x1));
    core::CompiledCommand fixed = c;
    fixed.tracking.path.kind = core::CentrePath::Kind::Fixed;
    const Heard still = step_hearing(fixed, 0, x1, 1.0);
    CHECK(still.after == law_step(fixed, still, x1));
  }
}

TEST_CASE("tracking with feed-forward: neighbours of the agent's own step are taken bit for bit",
          "[agent][tracking]") {
  for (const auto path : {core::CentrePath::Kind::Line, core::CentrePath::Kind::Circle}) {
    const core::CompiledCommand c = tracking_ff(path);
    std::vector<Vec2> start = core::uniform_start(6, 5);
    for (auto& x : start) x += Vec2(-10, -10);
    // Lockstep in any tick order is the simulator's update, bit for bit.
    core::Swarm swarm(c, start);
    for (int k = 0; k < 40; ++k) swarm.step();
    const auto lock = run_shuffled(c, start, true, 40);
    // Free running, every agent hearing the others' states of its own step: the simulator too.
    std::vector<AgentLogic> agents;
    for (int i = 0; i < 6; ++i) agents.emplace_back(i, start[i], 60 * kMs);
    for (auto& a : agents) REQUIRE(adopt(a, c, 1));
    for (std::uint64_t seq = 1; seq <= 40; ++seq) {
      for (auto& a : agents)
        for (const auto& b : agents)
          a.on_state(b.id(), b.position(), seq, 0, b.command_id(), std::nullopt, b.model_time());
      for (auto& a : agents) a.step();
    }
    for (int i = 0; i < 6; ++i) {
      CHECK(lock[i] == swarm.positions()[i]);
      CHECK(agents[i].position() == swarm.positions()[i]);
    }
  }
}

TEST_CASE("free running on the line path with feed-forward is the fixed-centre swarm in the centre's frame",
          "[agent][tracking]") {
  // The same tick orders, around a centre moving at constant velocity and around it held at C(0):
  // seen in the centre's frame the two are one problem, once every neighbour is seen at the agent's
  // own model time (without that, a neighbour that already stepped is 0.14 ahead of its place).
  const core::CompiledCommand moving = tracking_ff();
  core::CompiledCommand fixed = moving;
  fixed.tracking.path.kind = core::CentrePath::Kind::Fixed;
  std::vector<Vec2> start = core::uniform_start(8, 3);
  for (auto& x : start) x += Vec2(-10, -10);
  const long steps = 60;
  const auto ff = run_shuffled(moving, start, false, steps);
  const auto fx = run_shuffled(fixed, start, false, steps);
  const Vec2 moved = core::centre_at(moving.tracking.path, static_cast<double>(steps)) - Vec2(-10, -10);
  for (int i = 0; i < 8; ++i) CHECK((ff[i] - moved - fx[i]).norm() < 1e-9);
}

TEST_CASE("following the target: a state's place in the centre's frame is set by the targets since it",
          "[agent][tracking]") {
  // Taken by a neighbour's step against the newest target then, feed-forward included: one step ahead
  // of that target's centre. Times in ms, targets every 20 ms, the one in use received at 0.
  CHECK(AgentLogic::centre_frame_steps(10, 0, 0.0, 20) == -1.0);  // after it: the same target, a step on
  CHECK(AgentLogic::centre_frame_steps(0, 0, 0.0, 20) == -1.0);
  CHECK(AgentLogic::centre_frame_steps(-5, 0, 0.0, 20) == 0.0);   // against the one before, as this agent
  CHECK(AgentLogic::centre_frame_steps(-25, 0, 0.0, 20) == 1.0);  // a sample lost since
  CHECK(AgentLogic::centre_frame_steps(-45, 0, 0.0, 20) == 2.0);
  CHECK(AgentLogic::centre_frame_steps(10, 0, 1.0, 20) == 0.0);   // a late target: this agent stepped on
  const core::CompiledCommand c = tracking_ff();
  const Vec2 x0(-9, -10), x1(-11, -9.5), centre(-8, -8), vt(0.2, 0.0);
  core::CompiledCommand local = c;
  local.tracking.path.point = centre;
  local.tracking.path.velocity = vt;
  for (const auto& [heard_ms, steps] : std::vector<std::pair<std::int64_t, double>>{
           {10, -1.0}, {-5, 0.0}, {-25, 1.0}, {-45, 2.0}}) {
    AgentLogic a(0, x0, 100 * kMs);
    a.set_period(0.02);
    REQUIRE(adopt(a, c, 1));
    a.on_target({1, 20.0, centre, vt}, 100 * kMs);
    // The model time says nothing here (a clock that started apart): the targets since do.
    a.on_state(1, x1, 1, 100 * kMs + heard_ms * kMs, a.command_id(), std::nullopt, 7.0);
    a.drop_stale(115 * kMs);
    CHECK((*a.tracked_centre() - centre).norm() < 1e-12);
    a.step();
    const Vec2 seen = x1 + (steps * c.dt) * vt;
    const core::StepResult expect = core::agent_step(local, 0, x0, {core::Neighbour{1, seen}}, 0.0);
    INFO("heard at " << heard_ms << " ms");
    CHECK((a.position() - expect.x).norm() < 1e-12);
  }
}

TEST_CASE(
    "free running after the target, in any tick phases, is the fixed-centre swarm in the centre's frame",
    "[agent][tracking]") {
  // Processes as they run: each agent ticks at its own phase of the period, the supervisor publishes the
  // target at its own, every state is heard when it is published. Around a centre moving at constant
  // velocity with feed-forward, and around it held still, from the same start and phases: seen in the
  // frames of the supervisor's ticks, one problem (each agent steps against the newest target, each
  // neighbour moved by the targets since its state). Moving neighbours by the steps between model times
  // instead, the two differ by up to a step of the centre's motion.
  constexpr std::int64_t kPeriod = 20 * kMs;
  const int n = 8;
  const std::vector<double> phase = {0.91, 0.13, 0.55, 0.07, 0.72, 0.38, 0.64, 0.29};
  const double sup_phase = 0.46;
  const long periods = 60;
  for (const auto law : {core::Law::Paper, core::Law::Arc}) {
    core::CompiledCommand moving = tracking_ff();
    moving.law = law;
    core::CompiledCommand fixed = moving;
    fixed.tracking.path.velocity = Vec2::Zero();
    const Vec2 c0 = moving.tracking.path.point, v = moving.tracking.path.velocity;
    std::vector<Vec2> start = core::uniform_start(n, 3);
    for (auto& x : start) x += c0;
    // The supervisor tick whose target agent i stepped against last in `period` (in periods).
    const auto target_of = [&](int i, long period) {
      return static_cast<double>(phase[i] > sup_phase ? period : period - 1) + sup_phase;
    };
    // Agents step from period 1 on, and are heard from their first step: agent i's start is its place
    // against the first target it steps against; the moving run starts there in the centre's frame.
    const auto run = [&](const core::CompiledCommand& cmd) {
      const Vec2 vc = cmd.tracking.path.velocity;
      std::vector<AgentLogic> agents;
      for (int i = 0; i < n; ++i) {
        agents.emplace_back(i, start[i] + (target_of(i, 1) * cmd.dt) * vc, 3 * kPeriod);
        agents.back().set_period(1e-9 * static_cast<double>(kPeriod));
      }
      std::vector<std::uint64_t> seq(n, 0);
      const auto publish = [&](int i, std::int64_t now) {
        ++seq[i];
        for (auto& b : agents)
          b.on_state(i, agents[i].position(), seq[i], now, agents[i].command_id(), agents[i].arc(),
                     agents[i].model_time());
      };
      for (auto& a : agents) REQUIRE(adopt(a, cmd, 1));
      // Events of one period in time order: the supervisor's target and each agent's tick.
      std::vector<std::pair<double, int>> events{{sup_phase, -1}};
      for (int i = 0; i < n; ++i) events.push_back({phase[i], i});
      std::sort(events.begin(), events.end());
      for (long p = 0; p < periods; ++p)
        for (const auto& [ph, who] : events) {
          const std::int64_t now = std::llround((static_cast<double>(p) + ph) * static_cast<double>(kPeriod));
          const double t = (static_cast<double>(p) + ph) * cmd.dt;  // the supervisor's model time
          if (who < 0) {
            const Vec2 centre = cmd.tracking.path.point + t * cmd.tracking.path.velocity;
            for (auto& a : agents) a.on_target({1, t, centre, cmd.tracking.path.velocity}, now);
            continue;
          }
          if (p == 0) continue;  // the first target comes at the supervisor's phase of period 0
          agents[who].drop_stale(now);
          agents[who].step();
          publish(who, now);
        }
      std::vector<Vec2> out;
      for (const auto& a : agents) out.push_back(a.position());
      return out;
    };
    const auto ff = run(moving);
    const auto fx = run(fixed);
    for (int i = 0; i < n; ++i) {
      // Agent i's last step, in period periods - 1: its state is of the centre one step after its target.
      const Vec2 moved = (target_of(i, periods - 1) + 1.0) * moving.dt * v;
      INFO("law " << static_cast<int>(law) << ", agent " << i);
      CHECK((ff[i] - moved - fx[i]).norm() < 1e-9);
      CHECK((fx[i] - start[i] - (1.0 + phase[i]) * moving.dt * fixed.tracking.path.velocity).norm() > 0.1);
    }
  }
}

namespace {
/// The line x1 = 0 (every agent on the x1 axis has its closest point at the origin), the arc law, with
/// a speed limit and the safety filter at separation d.
core::CompiledCommand line_90(double d) {
  core::Command c;
  c.law = core::Law::Arc;
  c.shape.kind = core::ShapeKind::Line;
  c.shape.m = 0;
  c.shape.c = 0;
  c.shape.rotation = M_PI / 2;
  c.max_speed = 0.1;
  c.min_separation = d;
  c.arc.k_normal = 0.5;  // config/scenarios/arc_circle.yaml's
  c.arc.k_tangent = 1.0;
  c.arc.spacing = 1.0;
  return core::compile(c);
}

/// One agent's loop skips `periods` periods from period `from` on (a busy host, a stall); at its next
/// tick it is told of them (AgentLogic::skip) as its process's loop does, unless `told` is false.
struct Stall {
  int agent = -1;
  int from = 0;
  int periods = 0;
  bool told = true;
};

/// Free-running agents with a clock: period P = 20 ms, each agent ticking at its own phase, its state
/// delivered to the others `latency` later (a fraction `loss` lost). Returns the smallest distance of
/// two agents' true positions after any step, and the agents. With a vehicle, each agent drives one and
/// its states carry its previous position, as agent processes' do.
double free_running(const core::CompiledCommand& cmd, const std::vector<Vec2>& start, int periods,
                    std::vector<AgentLogic>& agents, std::int64_t latency = 3 * kMs, double loss = 0.0,
                    const core::VehicleParams* vehicle = nullptr, const Stall& stall = {}) {
  constexpr std::int64_t P = 20 * kMs;
  agents.clear();
  for (int i = 0; i < static_cast<int>(start.size()); ++i) {
    agents.emplace_back(i, start[i], 60 * kMs);
    agents.back().set_period(1e-9 * static_cast<double>(P));
    if (vehicle) agents.back().set_vehicle(*vehicle, 0.0);
  }
  std::mt19937 rng(5);
  std::uniform_int_distribution<std::int64_t> phase(0, P - 1);
  std::bernoulli_distribution lost(loss);
  std::vector<std::int64_t> offset;
  for (std::size_t i = 0; i < agents.size(); ++i) offset.push_back(phase(rng));
  struct Delivery {
    std::int64_t at;
    int from;
    Vec2 x;
    std::uint64_t seq;
    double t;
    std::optional<double> arc;
    std::optional<Vec2> prev;
  };
  std::vector<Delivery> inflight;
  std::vector<std::uint64_t> seq(agents.size(), 0);
  double low = std::numeric_limits<double>::infinity();
  // As processes do: every agent heard before the command (the supervisor waits for them).
  for (std::size_t i = 0; i < agents.size(); ++i)
    for (std::size_t j = 0; j < agents.size(); ++j)
      if (i != j) agents[j].on_state(static_cast<int>(i), agents[i].position(), ++seq[i], 0);
  for (auto& a : agents) adopt(a, cmd, 1);
  // Ticks in time order; deliveries due before a tick are taken first.
  std::vector<std::pair<std::int64_t, int>> ticks;
  for (int k = 0; k < periods; ++k)
    for (std::size_t i = 0; i < agents.size(); ++i)
      if (static_cast<int>(i) != stall.agent || k < stall.from || k >= stall.from + stall.periods)
        ticks.emplace_back(k * P + offset[i], static_cast<int>(i));
  std::sort(ticks.begin(), ticks.end());
  for (const auto& [now, i] : ticks) {
    for (auto it = inflight.begin(); it != inflight.end();) {
      if (it->at > now) {
        ++it;
        continue;
      }
      for (std::size_t j = 0; j < agents.size(); ++j)
        if (static_cast<int>(j) != it->from)
          agents[j].on_state(it->from, it->x, it->seq, it->at, agents[it->from].command_id(), it->arc, it->t, it->prev);
      it = inflight.erase(it);
    }
    AgentLogic& a = agents[static_cast<std::size_t>(i)];
    if (i == stall.agent && stall.told && now / P == stall.from + stall.periods)
      a.skip(static_cast<std::uint64_t>(stall.periods));
    a.drop_stale(now);
    const Vec2 before = a.position();
    a.step();
    for (std::size_t j = 0; j < agents.size(); ++j)
      if (static_cast<int>(j) != i) low = std::min(low, (agents[j].position() - a.position()).norm());
    if (!lost(rng))
      inflight.push_back({now + latency, i, a.position(), ++seq[i], a.model_time(), a.arc(),
                          vehicle ? std::optional<Vec2>(before) : std::nullopt});
  }
  return low;
}

std::vector<Vec2> on_x_axis(int n, double gap) {
  std::vector<Vec2> x;
  for (int i = 0; i < n; ++i) x.emplace_back(gap * (i - (n - 1) / 2.0), 0.0);
  return x;
}
}  // namespace

TEST_CASE("safety filter: free-running agents with late and lost states never come closer than d", "[agent][safety]") {
  const double d = 0.25;
  const auto start = on_x_axis(12, 0.5);
  std::vector<AgentLogic> agents;
  // Without the filter the crossing comes closer (so the start does force it).
  CHECK(free_running(line_90(0.0), start, 400, agents) < d);
  for (const std::int64_t latency : {1 * kMs, 15 * kMs, 35 * kMs, 150 * kMs})
    for (const double loss : {0.0, 0.3, 0.7}) {
      CAPTURE(latency, loss);
      CHECK(free_running(line_90(d), start, 400, agents, latency, loss) >= d - 1e-9);
      std::uint64_t interventions = 0, broken = 0;
      double min_gap = 1e9;
      for (const auto& a : agents) {
        interventions += a.safety().interventions;
        broken += a.safety().broken;
        REQUIRE(a.safety().min_gap >= 0.0);
        min_gap = std::min(min_gap, a.safety().min_gap);
      }
      CHECK(interventions > 0);
      CHECK(broken == 0);
      CHECK(min_gap >= d - 1e-9);  // what each agent saw of its neighbours, as last heard
    }
}

TEST_CASE("safety filter: an agent whose loop skipped periods keeps its clock, and nobody is held by it",
          "[agent][safety]") {
  // The middle agent's loop skips 25 periods (0.5 s) on the way. Were its model time to stand still
  // meanwhile, it would be 25 steps behind the others' for the rest of the command, its states taken as
  // 25 steps old (margins of 2.5 against a slot spacing of 1): agents near it are held for ever.
  const double d = 0.25;
  const auto start = on_x_axis(12, 0.5);
  std::vector<AgentLogic> agents;
  const auto on_line = [&] {
    std::vector<double> along;
    for (const auto& a : agents) {
      if (std::abs(a.position().x()) > 1e-3) return false;
      along.push_back(a.position().y());
    }
    std::sort(along.begin(), along.end());
    for (std::size_t k = 1; k < along.size(); ++k)
      if (std::abs(along[k] - along[k - 1] - 1.0) > 1e-3) return false;  // arc.spacing
    return true;
  };
  const auto held = [&] {
    int n = 0;
    for (const auto& a : agents) n += a.safety().blocked ? 1 : 0;
    return n;
  };
  for (const bool told : {false, true}) {
    CAPTURE(told);
    CHECK(free_running(line_90(d), start, 1500, agents, 3 * kMs, 0.0, nullptr, Stall{5, 10, 25, told}) >= d - 1e-9);
    const double stalled = agents[5].model_time(), other = agents[4].model_time();
    if (told) {
      CHECK(stalled == other);  // the same clock (each of their 1500 periods)
      CHECK(on_line());
      CHECK(held() == 0);
    } else {
      CHECK(other - stalled == 25.0);  // the stall's periods behind for good
      CHECK_FALSE(on_line());
      CHECK(held() > 0);
    }
  }
}

TEST_CASE("safety filter: free-running double integrators with late and lost states never come closer than d",
          "[agent][safety][braking]") {
  // Point masses that cannot stop within a step (0.05 per step, 0.01 per step^2):
  // each keeps its braking segment apart from its neighbours' as it last heard them.
  const double d = 0.25;
  const auto start = on_x_axis(12, 0.5);
  core::VehicleParams vp;
  vp.model = core::VehicleModel::DoubleIntegrator;
  vp.max_speed = 0.05;
  vp.max_accel = 0.01;
  std::vector<AgentLogic> agents;
  CHECK(free_running(line_90(0.0), start, 600, agents, 3 * kMs, 0.0, &vp) < d);
  for (const std::int64_t latency : {1 * kMs, 35 * kMs, 150 * kMs})
    for (const double loss : {0.0, 0.3, 0.7}) {
      CAPTURE(latency, loss);
      CHECK(free_running(line_90(d), start, 1000, agents, latency, loss, &vp) >= d - 1e-9);
      std::uint64_t interventions = 0, broken = 0;
      for (const auto& a : agents) {
        interventions += a.safety().interventions;
        broken += a.safety().broken;
      }
      CHECK(interventions > 0);
      CHECK(broken == 0);
      // With states up to a couple of periods late they still form the line (every agent on x1 = 0).
      // States 7.5 periods late: a neighbour's segment may have moved far (margins of 2 vmax + a h / 2 per
      // period of age at full speed), but the margins count from each neighbour's own speed
      // (braking_reach), so agents near slow ones still get room: they come most of the way (from
      // 1.5 off the line on average; with full-speed margins every agent braked where it started). One
      // not on the line is held, reported, or still on its way.
      double off_line = 0.0, mean_off = 0.0;
      for (const auto& a : agents) {
        const double off = std::abs(a.position().x());
        off_line = std::max(off_line, off);
        mean_off += off / static_cast<double>(agents.size());
        if (off > 0.05) CHECK((a.safety().blocked || a.velocity().norm() > 1e-6));
      }
      if (latency <= 35 * kMs && loss <= 0.3) CHECK(off_line < 0.05);
      if (latency > 35 * kMs) CHECK(mean_off < 0.5);
    }
  // (safety_test.cpp shows that cells of positions alone let such vehicles' momentum carry them closer.)
}

TEST_CASE("safety filter: lockstep agents reproduce the simulator's filtered swarm exactly", "[agent][safety][lockstep]") {
  const core::CompiledCommand cmd = line_90(0.25);
  const auto start = on_x_axis(8, 0.5);
  core::Swarm swarm(cmd, start);
  for (int k = 0; k < 60; ++k) swarm.step();
  REQUIRE(swarm.safety_counts().interventions > 0);
  const auto lock = run_shuffled(cmd, start, true, 60);
  for (int i = 0; i < 8; ++i) CHECK((lock[i] - swarm.positions()[i]).norm() < 1e-12);
}

TEST_CASE("fence: a command whose fence leaves the agent outside is a breach; the next command brings it back",
          "[agent][fence]") {
  core::Command c;
  c.shape.kind = core::ShapeKind::Circle;
  c.shape.r0 = 2;
  c.max_speed = 0.5;
  c.fence = {Vec2(-3, -3), Vec2(3, -3), Vec2(3, 3), Vec2(-3, 3)};
  c.fence_margin = 0.2;
  for (const auto action : {core::BreachAction::Return, core::BreachAction::Stop, core::BreachAction::Hold}) {
    CAPTURE(static_cast<int>(action));
    c.breach_action = action;
    AgentLogic a(0, Vec2(5, 0), 60 * kMs);
    REQUIRE(adopt(a, core::compile(c), 1));
    CHECK(a.beyond_fence());
    CHECK(a.safety().fence_breaches == 1);
    CHECK(a.take_breach() == Approx(2.0));
    if (action != core::BreachAction::Return) {
      // Stopped until the next command, which brings it back (not a new breach: the same excursion).
      CHECK(a.fence_state() == agent::FenceState::Stopped);
      for (int k = 0; k < 5; ++k) CHECK_FALSE(a.step());
      CHECK(a.position() == Vec2(5, 0));
      CHECK(a.model_time() == 5.0);  // still, its clock going on with the others'
      REQUIRE(adopt(a, core::compile(c), 2));
      CHECK(a.safety().fence_breaches == 0);
    }
    CHECK(a.fence_state() == agent::FenceState::Returning);
    Vec2 last = a.position();
    int steps = 0;
    for (; steps < 20 && a.fence_state() != agent::FenceState::Inside; ++steps) {
      a.step();
      CHECK((a.position() - last).norm() <= 0.5 + 1e-12);  // at the speed limit
      CHECK(a.position().x() < last.x());                  // straight back
      last = a.position();
    }
    CHECK(a.fence_state() == agent::FenceState::Inside);
    CHECK(steps == 5);  // 5 - 2.8 = 2.2 at 0.5 per step
    CHECK(a.position().x() == Approx(2.8));
    CHECK_FALSE(a.beyond_fence());
    // Then the law, on the circle (inside the fence, which the filter keeps it in).
    for (int k = 0; k < 100; ++k) a.step();
    CHECK(std::abs(a.position().norm() - 2.0) < 0.01);
  }
}

TEST_CASE("the neighbour table knows its hosted agents by id", "[agent]") {
  const agent::NeighbourTable table({7, 3, 12}, 60 * kMs);
  CHECK(table.hosted_index(7) == 0);
  CHECK(table.hosted_index(3) == 1);
  CHECK(table.hosted_index(12) == 2);
  for (const std::int32_t other : {-1, 0, 4, 11, 13, 9999}) CHECK(table.hosted_index(other) == -1);
}

TEST_CASE("the neighbour table's index follows arrivals, departures and drops (random property)", "[agent]") {
  // A reference model: id -> (x, last seen, seq). The table must hold exactly its entries, ascending.
  std::mt19937 rng(11);
  agent::NeighbourTable table({2, 5}, 30 * kMs);
  std::map<std::int32_t, std::tuple<double, std::int64_t, std::uint64_t>> model;
  std::uint64_t seq = 0;
  for (std::int64_t now = 0; now < 3000 * kMs; now += kMs) {
    const int op = std::uniform_int_distribution<int>(0, 9)(rng);
    const auto id = std::uniform_int_distribution<std::int32_t>(0, 60)(rng);
    if (op < 7) {
      ++seq;
      const double x = static_cast<double>(seq);
      table.on_state(id, Vec2(x, 0), seq, now, {}, std::nullopt, 0.0, std::nullopt, std::nullopt, 1.0);
      model[id] = {x, now, seq};
    } else if (op < 9) {
      table.on_gone(id);
      model.erase(id);
    } else {
      table.drop_stale(now);
      for (auto it = model.begin(); it != model.end();)
        it = now - std::get<1>(it->second) > 30 * kMs ? model.erase(it) : std::next(it);
    }
    REQUIRE(table.entries().size() == model.size());
    auto m = model.begin();
    for (const auto& [key, e] : table.entries()) {
      REQUIRE(key == m->first);
      REQUIRE(e.cur.x.x() == std::get<0>(m->second));
      REQUIRE(e.hosted == (key == 2 ? 0 : key == 5 ? 1 : -1));
      ++m;
    }
  }
  table.on_state(-1, Vec2(0, 0), ++seq, 0, {}, std::nullopt, 0.0, std::nullopt, std::nullopt, 1.0);  // ignored
  CHECK(table.entries().size() == model.size());
}

namespace {
/// 12 free-running arc-law agents on three hosts of four (ids 0-3, 4-7, 8-11), as scripts/reliability.sh
/// places them, every host losing a fraction p of the datagrams it sends and of those it receives: a
/// state from one host to another is lost for each receiver on its own with probability 1 - (1 - p)^2,
/// within a host never. Period 20 ms (50 Hz), each agent at its own phase, deliveries `latency` late;
/// the agents keep a silent neighbour timeout_ns. worst_moved: the largest distance of any agent from
/// its start at any tick.
std::vector<AgentLogic> lossy_lan(const core::CompiledCommand& cmd, const std::vector<Vec2>& start, int periods,
                                  double p, std::int64_t timeout_ns, double& worst_moved,
                                  std::int64_t latency = 3 * kMs) {
  constexpr std::int64_t P = 20 * kMs;
  const int n = static_cast<int>(start.size());
  std::vector<AgentLogic> agents;
  for (int i = 0; i < n; ++i) {
    agents.emplace_back(i, start[i], timeout_ns);
    agents.back().set_period(1e-9 * static_cast<double>(P));
  }
  std::mt19937 rng(29);
  std::uniform_int_distribution<std::int64_t> phase(0, P - 1);
  std::bernoulli_distribution lost(1.0 - (1.0 - p) * (1.0 - p));
  std::vector<std::int64_t> offset;
  for (int i = 0; i < n; ++i) offset.push_back(phase(rng));
  struct Delivery {
    std::int64_t at;
    int from, to;
    Vec2 x;
    std::uint64_t seq;
    double t;
    std::optional<double> arc;
  };
  std::vector<Delivery> inflight;
  std::vector<std::uint64_t> seq(static_cast<std::size_t>(n), 0);
  for (int i = 0; i < n; ++i)  // every agent heard before the command (the supervisor waits for them)
    for (int j = 0; j < n; ++j)
      if (i != j) agents[static_cast<std::size_t>(j)].on_state(i, start[static_cast<std::size_t>(i)], ++seq[static_cast<std::size_t>(i)], 0);
  for (auto& a : agents) adopt(a, cmd, 1);
  std::vector<std::pair<std::int64_t, int>> ticks;
  for (int k = 1; k <= periods; ++k)
    for (int i = 0; i < n; ++i) ticks.emplace_back(k * P + offset[static_cast<std::size_t>(i)], i);
  std::sort(ticks.begin(), ticks.end());
  worst_moved = 0.0;
  for (const auto& [now, i] : ticks) {
    for (auto it = inflight.begin(); it != inflight.end();) {
      if (it->at > now) {
        ++it;
        continue;
      }
      auto& to = agents[static_cast<std::size_t>(it->to)];
      to.on_state(it->from, it->x, it->seq, it->at, agents[static_cast<std::size_t>(it->from)].command_id(), it->arc, it->t);
      it = inflight.erase(it);
    }
    AgentLogic& a = agents[static_cast<std::size_t>(i)];
    a.drop_stale(now);
    a.step();
    worst_moved = std::max(worst_moved, (a.position() - start[static_cast<std::size_t>(i)]).norm());
    const std::uint64_t s = ++seq[static_cast<std::size_t>(i)];
    for (int j = 0; j < n; ++j)
      if (j != i && (j / 4 == i / 4 || !lost(rng)))
        inflight.push_back({now + latency, i, j, a.position(), s, a.model_time(), a.arc()});
  }
  return agents;
}

core::CompiledCommand arc_circle() {
  core::Command c;
  c.law = core::Law::Arc;
  c.shape.kind = core::ShapeKind::Circle;
  c.shape.r0 = 4;
  c.arc.k_normal = 0.5;  // config/scenarios/arc_circle.yaml's
  c.arc.k_tangent = 1.0;
  return core::compile(c);
}
}  // namespace

TEST_CASE("loss on every host changes neither who is in the swarm nor the arc law's slots", "[agent][loss]") {
  // 40 % loss on every host: 64 % of the exchanges between hosts lost. The swarm already stands on its
  // slots (12 evenly spaced on the circle), which every agent computes alike from the same states; a
  // neighbour dropped for silence changes the count and the ranks (slots L/11 apart) in one agent's view,
  // which then leaves its slot. With the default timeout no live neighbour is dropped, and the agents
  // stand still (the states they keep are their neighbours' states now).
  const std::int64_t timeout = config::AgentConfig{}.neighbour_timeout_ns();
  CHECK(config::AgentConfig{}.rate_hz == 50.0);  // the 20 ms period of lossy_lan
  std::vector<Vec2> slots;
  for (int i = 0; i < 12; ++i) slots.emplace_back(4 * std::cos(0.3 + i * M_PI / 6), 4 * std::sin(0.3 + i * M_PI / 6));
  // Late as well as lost: 45 ms is more than two periods, so every state used is that old.
  for (const auto& [p, latency] : {std::pair{0.2, 3 * kMs}, std::pair{0.4, 3 * kMs}, std::pair{0.4, 45 * kMs}}) {
    CAPTURE(p, latency);
    double moved = 0.0;
    const auto agents = lossy_lan(arc_circle(), slots, 1500, p, timeout, moved, latency);  // 30 s
    for (const auto& a : agents) {
      CHECK(a.counters().stale_dropped == 0);
      CHECK(a.neighbours() == 11);
      CHECK(a.counters().samples_received > 0);
    }
    CHECK(moved < 1e-9);
  }
  // The former 3 periods (60 ms): neighbours dropped and re-admitted all the time, and agents leave their
  // slots by up to a third of the gap between slots (2.1).
  double moved = 0.0;
  const auto agents = lossy_lan(arc_circle(), slots, 1500, 0.2, 60 * kMs, moved);
  std::uint64_t dropped = 0;
  for (const auto& a : agents) dropped += a.counters().stale_dropped;
  CHECK(dropped > 100);
  CHECK(moved > 0.1);
}

TEST_CASE("at 40 % loss on every host the arc law forms its exact, evenly spaced circle", "[agent][loss]") {
  // From the seeded start of config/scenarios/arc_circle.yaml's swarm, with states up to several periods
  // old (each neighbour's newest state is 1 / 0.36 = 2.8 periods old on average across hosts): the same
  // circle as without loss, on the curve and evenly spaced, in the same order.
  const std::int64_t timeout = config::AgentConfig{}.neighbour_timeout_ns();
  const auto start = core::uniform_start(12, 1);
  double moved = 0.0;
  const auto agents = lossy_lan(arc_circle(), start, 1500, 0.4, timeout, moved);
  std::vector<std::pair<double, int>> by_angle;
  for (const auto& a : agents) {
    CHECK(a.counters().stale_dropped == 0);
    CHECK(std::abs(a.position().norm() - 4.0) < 1e-6);
    by_angle.emplace_back(std::atan2(a.position().y(), a.position().x()), a.id());
  }
  std::sort(by_angle.begin(), by_angle.end());
  for (std::size_t k = 0; k < by_angle.size(); ++k) {
    const double next = k + 1 < by_angle.size() ? by_angle[k + 1].first : by_angle[0].first + 2 * M_PI;
    CHECK(std::abs(next - by_angle[k].first - M_PI / 6) < 1e-6);
  }
}
