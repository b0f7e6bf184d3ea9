#include "util/rate_loop.hpp"

#include <atomic>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <thread>
#include <vector>

#include "util/signals.hpp"

using namespace std::chrono_literals;
using shapeform::util::LoopClock;
using shapeform::util::RateLoop;
using shapeform::util::SteadyTime;

namespace {

// Manual time: sleep_until jumps straight to the target (plus an optional oversleep), so tests are
// exact and take no real time. Shared via shared_ptr because LoopClock copies the callables.
struct FakeTime {
  SteadyTime t{std::chrono::seconds(1000)};
  std::chrono::nanoseconds oversleep{0};
  std::vector<SteadyTime> sleep_targets;
  std::vector<SteadyTime> sleep_starts;
  std::atomic<bool>* stop_after_sleep = nullptr;  // set this flag on the first sleep if not null
};

LoopClock fake_clock(const std::shared_ptr<FakeTime>& ft) {
  return LoopClock{[ft] { return ft->t; },
                   [ft](SteadyTime target) {
                     ft->sleep_starts.push_back(ft->t);
                     ft->sleep_targets.push_back(target);
                     if (target > ft->t) ft->t = target;
                     ft->t += ft->oversleep;
                     if (ft->stop_after_sleep != nullptr) ft->stop_after_sleep->store(true);
                   }};
}

/// A 100 Hz loop (period 10 ms) on fake time that starts at t0, and a stop flag that stays down.
struct FakeLoop100 {
  std::shared_ptr<FakeTime> ft = std::make_shared<FakeTime>();
  SteadyTime t0 = ft->t;
  RateLoop loop{100.0, fake_clock(ft)};
  std::atomic<bool> stop{false};
};

}  // namespace

TEST_CASE("RateLoop rejects invalid rates", "[util][rate_loop]") {
  CHECK_THROWS_AS(RateLoop(0.0), std::invalid_argument);
  CHECK_THROWS_AS(RateLoop(-5.0), std::invalid_argument);
  CHECK_THROWS_AS(RateLoop(std::nan("")), std::invalid_argument);
  CHECK_THROWS_AS(RateLoop(HUGE_VAL), std::invalid_argument);
  CHECK_THROWS_AS(RateLoop(10.0, LoopClock{}), std::invalid_argument);
}

TEST_CASE("RateLoop period is 1/rate", "[util][rate_loop]") {
  CHECK(RateLoop(100.0).period() == 10ms);
  CHECK(RateLoop(3.0).period() == std::chrono::nanoseconds(333'333'333));
  CHECK(RateLoop(50.0).period_s() == Approx(0.02));
  CHECK(RateLoop(50.0).rate_hz() == 50.0);
}

TEST_CASE("RateLoop ticks land exactly on the deadline grid", "[util][rate_loop]") {
  FakeLoop100 fake;
  auto& [ft, t0, loop, stop] = fake;

  for (int k = 1; k <= 50; ++k) {
    REQUIRE(loop.wait_next(stop));
    CHECK(ft->t == t0 + k * 10ms);
    CHECK(loop.next_deadline() == t0 + (k + 1) * 10ms);
    ft->t += 3ms;  // some work, well inside the period
  }
  const auto s = loop.stats();
  CHECK(s.ticks == 50);
  CHECK(s.overruns == 0);
  CHECK(s.lateness_max_us == 0.0);
  CHECK(s.lateness_p99_us == 0.0);
  CHECK(s.work_max_us == Approx(3000.0));
}

TEST_CASE("RateLoop grid is anchored at the first wait_next, not at construction",
          "[util][rate_loop]") {
  auto ft = std::make_shared<FakeTime>();
  RateLoop loop(10.0, fake_clock(ft));
  ft->t += 5s;  // long set-up between construction and the loop
  const SteadyTime first_call = ft->t;
  const std::atomic<bool> stop{false};
  REQUIRE(loop.wait_next(stop));
  CHECK(ft->t == first_call + 100ms);
  CHECK(loop.stats().overruns == 0);
  CHECK(loop.stats().lateness_max_us == 0.0);
}

TEST_CASE("RateLoop sleeps in slices of at most 50 ms", "[util][rate_loop]") {
  auto ft = std::make_shared<FakeTime>();
  const SteadyTime t0 = ft->t;
  RateLoop loop(2.0, fake_clock(ft));  // 500 ms period
  const std::atomic<bool> stop{false};
  REQUIRE(loop.wait_next(stop));
  CHECK(ft->t == t0 + 500ms);
  REQUIRE(ft->sleep_targets.size() == 10);
  for (std::size_t i = 0; i < ft->sleep_targets.size(); ++i) {
    CHECK(ft->sleep_targets[i] - ft->sleep_starts[i] <= RateLoop::kMaxSleepSlice);
  }
  CHECK(ft->sleep_targets.back() == t0 + 500ms);
}

TEST_CASE("RateLoop records lateness from oversleeping", "[util][rate_loop]") {
  auto ft = std::make_shared<FakeTime>();
  ft->oversleep = 250us;
  RateLoop loop(100.0, fake_clock(ft));
  const std::atomic<bool> stop{false};
  for (int k = 0; k < 20; ++k) REQUIRE(loop.wait_next(stop));
  const auto s = loop.stats();
  CHECK(s.ticks == 20);
  CHECK(s.overruns == 0);
  CHECK(s.lateness_max_us == Approx(250.0));
  CHECK(s.lateness_p99_us == Approx(250.0));
}

TEST_CASE("RateLoop skips and counts whole missed periods, staying on the grid",
          "[util][rate_loop]") {
  FakeLoop100 fake;
  auto& [ft, t0, loop, stop] = fake;
  const auto P = 10ms;

  REQUIRE(loop.wait_next(stop));  // tick at t0 + P
  REQUIRE(ft->t == t0 + P);

  // Stall: the next call arrives 3.5 periods after its deadline (t0 + 2P).
  ft->t = t0 + 2 * P + 3 * P + P / 2;
  const auto sleeps_before = ft->sleep_targets.size();
  REQUIRE(loop.wait_next(stop));
  CHECK(ft->sleep_targets.size() == sleeps_before);  // already late: returns without sleeping
  auto s = loop.stats();
  CHECK(s.ticks == 2);
  CHECK(s.overruns == 3);  // deadlines t0+3P, t0+4P, t0+5P skipped
  CHECK(s.lateness_max_us == Approx(35'000.0));
  CHECK(s.work_max_us == Approx(45'000.0));
  CHECK(loop.next_deadline() == t0 + 6 * P);  // original grid, no burst

  // The loop recovers: following ticks are on time and on the grid.
  REQUIRE(loop.wait_next(stop));
  CHECK(ft->t == t0 + 6 * P);
  REQUIRE(loop.wait_next(stop));
  CHECK(ft->t == t0 + 7 * P);
  s = loop.stats();
  CHECK(s.ticks == 4);
  CHECK(s.overruns == 3);
}

TEST_CASE("RateLoop: late by under a period is no overrun, exactly one period is one",
          "[util][rate_loop]") {
  FakeLoop100 fake;
  auto& [ft, t0, loop, stop] = fake;
  const auto P = 10ms;
  REQUIRE(loop.wait_next(stop));

  ft->t = t0 + 2 * P + 9ms;  // 0.9 P late
  REQUIRE(loop.wait_next(stop));
  CHECK(loop.stats().overruns == 0);
  CHECK(loop.next_deadline() == t0 + 3 * P);

  REQUIRE(loop.wait_next(stop));  // sleeps the remaining 0.1 P
  CHECK(ft->t == t0 + 3 * P);

  ft->t = t0 + 4 * P + P;  // exactly one period late
  REQUIRE(loop.wait_next(stop));
  CHECK(loop.stats().overruns == 1);
  CHECK(loop.next_deadline() == t0 + 6 * P);
}

TEST_CASE("RateLoop p99 covers the recent window, max covers everything", "[util][rate_loop]") {
  auto ft = std::make_shared<FakeTime>();
  RateLoop loop(100.0, fake_clock(ft));
  const std::atomic<bool> stop{false};

  ft->oversleep = 5ms;  // one bad tick...
  REQUIRE(loop.wait_next(stop));
  ft->oversleep = 100us;  // ...then a full window of good ones pushes it out
  for (std::size_t k = 0; k < RateLoop::kLatenessWindow; ++k) REQUIRE(loop.wait_next(stop));
  auto s = loop.stats();
  CHECK(s.lateness_max_us == Approx(5000.0));
  CHECK(s.lateness_p99_us == Approx(100.0));

  // 2 % of the window late by 2 ms: p99 sees them.
  ft->oversleep = 2ms;
  for (int k = 0; k < 21; ++k) REQUIRE(loop.wait_next(stop));
  ft->oversleep = 100us;
  s = loop.stats();
  CHECK(s.lateness_p99_us == Approx(2000.0));
  CHECK(s.overruns == 0);

  loop.reset_stats();
  s = loop.stats();
  CHECK(s.ticks == 0);
  CHECK(s.lateness_max_us == 0.0);
  CHECK(s.lateness_p99_us == 0.0);
  REQUIRE(loop.wait_next(stop));
  CHECK(loop.stats().lateness_max_us == Approx(100.0));
}

TEST_CASE("RateLoop stops before the deadline when the flag is set", "[util][rate_loop]") {
  SECTION("flag already set: no tick, no sleep") {
    auto ft = std::make_shared<FakeTime>();
    RateLoop loop(1.0, fake_clock(ft));
    const std::atomic<bool> stop{true};
    CHECK_FALSE(loop.wait_next(stop));
    CHECK(ft->sleep_targets.empty());
    CHECK(loop.stats().ticks == 0);
  }
  SECTION("flag set during the wait: noticed after one slice") {
    auto ft = std::make_shared<FakeTime>();
    std::atomic<bool> stop{false};
    ft->stop_after_sleep = &stop;
    RateLoop loop(1.0, fake_clock(ft));  // 1 s period
    CHECK_FALSE(loop.wait_next(stop));
    CHECK(ft->sleep_targets.size() == 1);
    CHECK(loop.stats().ticks == 0);
  }
}

TEST_CASE("RateLoop real time: request_stop ends a long wait promptly", "[util][rate_loop][rt]") {
  shapeform::util::reset_stop();
  RateLoop loop(0.05);  // 20 s period: only the stop flag can end this wait in time
  const auto start = std::chrono::steady_clock::now();
  std::thread stopper([] {
    std::this_thread::sleep_for(30ms);
    shapeform::util::request_stop();
  });
  const bool ticked = loop.wait_next(shapeform::util::stop_flag());
  stopper.join();
  const auto waited = std::chrono::steady_clock::now() - start;
  CHECK_FALSE(ticked);
  CHECK(waited < 10s);  // generous: the design bound is one 50 ms slice after the request
  shapeform::util::reset_stop();
}

TEST_CASE("RateLoop real time: ticks advance with sane stats", "[util][rate_loop][rt]") {
  RateLoop loop(500.0);
  const std::atomic<bool> stop{false};
  for (int k = 0; k < 25; ++k) REQUIRE(loop.wait_next(stop));
  const auto s = loop.stats();
  CHECK(s.ticks == 25);
  CHECK(std::isfinite(s.lateness_max_us));
  CHECK(s.lateness_max_us >= 0.0);
  CHECK(s.lateness_p99_us >= 0.0);
  CHECK(s.lateness_p99_us <= s.lateness_max_us);
  CHECK(s.work_max_us >= 0.0);
}
