// Waits: each condition, and the outcome at the deadline.
#include "waits.hpp"

#include <catch2/catch.hpp>

#include "supervisor_rig.hpp"

using namespace shapeform;
using namespace shapeform::test;
using supervisor::Wait;

namespace {

/// A rig whose convergence detector decides after 10 units of model time.
Rig quick_rig() {
  core::ConvergenceDetector::Params p;
  p.hold = 10;
  return Rig(circle(), false, p);
}

}  // namespace

TEST_CASE("wait converged: ends when the epoch in force converged, else times out at its deadline",
          "[supervisor][waits]") {
  Rig r = quick_rig();
  r.authority.publish(circle(), 0);
  const Wait w(supervisor::WaitConverged{2.0}, 0, r.authority.id());
  r.follow(12, 3.0, r.authority.id(), 0.0, 0);  // off the circle of radius 4: not converged
  r.monitor.update(0.0, 0);
  CHECK_FALSE(w.outcome(r.monitor, r.authority, 2 * kS - 1));  // holds input until the deadline
  const auto late = w.outcome(r.monitor, r.authority, 2 * kS);
  REQUIRE(late);
  CHECK_FALSE(late->ok);
  CHECK(late->text == "wait converged: timed out after 2 s");
  CHECK(late->warning == "wait converged timed out after 2 s");
  for (int k = 0; k <= 20; ++k) {  // on the circle for 20 units of model time
    r.follow(12, 4.0, r.authority.id(), k, k * 1000);
    r.monitor.update(k, k * 1000);
  }
  REQUIRE(r.monitor.converged());
  const auto done = w.outcome(r.monitor, r.authority, kS);
  REQUIRE(done);
  CHECK(done->ok);
  CHECK(done->text == "converged at t=10 (1.0 s after epoch 1)");
}

TEST_CASE("wait converged: nothing in force is never converged", "[supervisor][waits]") {
  Rig r;
  const Wait w(supervisor::WaitConverged{60.0}, 0, {});
  CHECK_FALSE(w.outcome(r.monitor, r.authority, kS));
  CHECK_FALSE(w.outcome(r.monitor, r.authority, 60 * kS)->ok);
}

TEST_CASE("wait agents: N alive, each hearing N - 1 others", "[supervisor][waits]") {
  Rig r;
  const Wait w(supervisor::WaitAgents{3, 5.0}, 0, {});
  r.follow(3, 4.0, {}, 0.0, 0);
  CHECK_FALSE(w.outcome(r.monitor, r.authority, 0));  // no status yet: hearing unknown
  for (int id = 0; id < 3; ++id) r.monitor.on_status(status(id, 1));
  CHECK_FALSE(w.outcome(r.monitor, r.authority, 0));  // each hears only one other
  const auto late = w.outcome(r.monitor, r.authority, 5 * kS);
  REQUIRE(late);
  CHECK_FALSE(late->ok);
  CHECK(late->text == "wait agents: timed out after 5 s with 0 of 3 agents");  // unheard for 5 s: dead
  for (int id = 0; id < 3; ++id) r.monitor.on_status(status(id, 2));
  const auto done = w.outcome(r.monitor, r.authority, 0);
  REQUIRE(done);
  CHECK(done->ok);
  CHECK(done->text == "agents: 3 alive, each hearing 2 or more");
}

TEST_CASE("wait time: every alive agent follows the command and has done T", "[supervisor][waits]") {
  Rig r;
  r.authority.publish(circle(), 0);
  const Wait w(supervisor::WaitTime{5.0, 30.0}, 0, r.authority.id());
  r.follow(2, 4.0, r.authority.id(), 4.5, 0);
  r.monitor.on_state(2, core::Vec2(4, 0), core::Vec2(4, 0), dds::CommandId{}, 0.0, 0);  // not on it yet
  CHECK_FALSE(w.outcome(r.monitor, r.authority, 0));
  r.follow(3, 4.0, r.authority.id(), 4.5, 0);
  CHECK_FALSE(w.outcome(r.monitor, r.authority, 0));  // the slowest agent is at 4.5
  r.follow(3, 4.0, r.authority.id(), 5.0, 0);
  const auto done = w.outcome(r.monitor, r.authority, 0);
  REQUIRE(done);
  CHECK(done->ok);
  CHECK(done->text.empty());
  const Wait never(supervisor::WaitTime{100.0, 30.0}, 0, r.authority.id());
  CHECK(never.outcome(r.monitor, r.authority, 30 * kS)->text == "wait time: timed out after 30 s");
}

TEST_CASE("sleep: ends well at its deadline", "[supervisor][waits]") {
  Rig r;
  const Wait w(supervisor::Sleep{1.5}, kS, {});
  CHECK(w.deadline_ns() == kS + kS * 3 / 2);
  CHECK_FALSE(w.outcome(r.monitor, r.authority, kS + kS));
  const auto done = w.outcome(r.monitor, r.authority, kS + kS * 3 / 2);
  REQUIRE(done);
  CHECK(done->ok);
  CHECK(done->text.empty());
}

TEST_CASE("waits: names, and which ones end with the command in force", "[supervisor][waits]") {
  const Wait converged(supervisor::WaitConverged{}, 0, 4), agents(supervisor::WaitAgents{}, 0, 4),
      time(supervisor::WaitTime{}, 0, 4), sleep(supervisor::Sleep{1e300}, 0, 4);
  CHECK(std::string(converged.name()) == "converged");
  CHECK(agents.label() == "wait agents");
  CHECK(sleep.label() == "sleep");
  CHECK(converged.on_command());
  CHECK(time.on_command());
  CHECK_FALSE(agents.on_command());
  CHECK_FALSE(sleep.on_command());
  CHECK(converged.on().epoch == 4);
  CHECK(sleep.deadline_ns() == static_cast<std::int64_t>(1e18));  // capped at 10^9 s
  CHECK(converged.deadline_ns() == 60 * kS);                      // the default timeouts
  CHECK(agents.deadline_ns() == 30 * kS);
}
