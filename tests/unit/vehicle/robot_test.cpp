// Unit tests of vehicle/robot: one simulated robot as its driver behaves (start pose, commands, the
// watchdog, the pose it publishes), without DDS or clocks.
#include "robot.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <vector>

using namespace shapeform;
using core::Vec2;
using vehicle::Robot;

namespace {
constexpr std::int64_t kMs = 1'000'000;
constexpr double kPi = 3.14159265358979323846;

core::VehicleParams unicycle() {
  core::VehicleParams p;
  p.model = core::VehicleModel::Unicycle;
  p.max_speed = 1.0;
  p.max_yaw_rate = 2.0;
  p.offset = 0.2;
  return p;
}

core::VehicleParams integrator() {
  core::VehicleParams p;
  p.max_speed = 1.0;
  return p;
}

core::BodyParams no_lag() {
  core::BodyParams b;
  b.response_s = 0.0;
  return b;
}

dds::VelocitySample twist(double vx, double vy, double wz) {
  dds::VelocitySample v;
  v.vx = vx;
  v.vy = vy;
  v.wz = wz;
  return v;
}
}  // namespace

TEST_CASE("robot: starts with its controlled point where it was told, at the heading it was told",
          "[vehicle]") {
  SECTION("unicycle: the base offset behind the point") {
    const core::VehicleParams p = unicycle();
    const Robot r(p, no_lag(), Vec2(3, -1), kPi / 2, 500 * kMs, 0.0, 1);
    CHECK(r.point().x() == Approx(3.0).margin(1e-15));
    CHECK(r.point().y() == Approx(-1.0).margin(1e-15));
    CHECK(r.body().base.x() == Approx(3.0).margin(1e-15));
    CHECK(r.body().base.y() == Approx(-1.2).margin(1e-15));
    CHECK(r.body().heading == kPi / 2);
    CHECK((r.body().actual.vx == 0.0 && r.body().actual.vy == 0.0 && r.body().actual.wz == 0.0));
    CHECK(r.commands() == 0);
    CHECK(r.watchdog_stops() == 0);
  }
  SECTION("a heading beyond pi is wrapped") {
    const Robot r(unicycle(), no_lag(), Vec2(0, 0), 1.5 * kPi, 500 * kMs, 0.0, 1);
    CHECK(r.body().heading == Approx(-kPi / 2).margin(1e-15));
    CHECK(r.point().y() == Approx(0.0).margin(1e-15));
    CHECK(r.body().base.y() == Approx(0.2).margin(1e-15));
  }
  SECTION("integrator: the base is the point") {
    const Robot r(integrator(), no_lag(), Vec2(-4, 2.5), 0.7, 500 * kMs, 0.0, 1);
    CHECK(r.body().base == Vec2(-4, 2.5));
    CHECK(r.point() == Vec2(-4, 2.5));
    CHECK(r.body().heading == 0.7);
  }
}

TEST_CASE("robot: without noise the pose is its base and heading exactly, with its velocity", "[vehicle]") {
  const core::VehicleParams p = unicycle();
  Robot r(p, no_lag(), Vec2(1, 1), 0.3, 500 * kMs, 0.0, 7);
  r.on_command(twist(0.5, 0.0, 0.25), 0);
  for (int k = 1; k <= 10; ++k) r.step(k * 20 * kMs, 0.02);
  const dds::PoseSample pose = r.pose();
  CHECK(pose.x == r.body().base);
  CHECK(pose.yaw == r.body().heading);
  CHECK(pose.has_twist);
  CHECK((pose.vx == 0.5 && pose.vy == 0.0 && pose.wz == 0.25));
  CHECK(r.pose().x == pose.x);  // every time
  // The heading turned by w x t exactly.
  CHECK(pose.yaw == Approx(0.3 + 0.25 * 0.2).margin(1e-12));
}

TEST_CASE("robot: noise on the published position only, seeded", "[vehicle]") {
  const core::VehicleParams p = integrator();
  Robot a(p, no_lag(), Vec2(2, 3), 0.0, 500 * kMs, 0.05, 11);
  Robot b(p, no_lag(), Vec2(2, 3), 0.0, 500 * kMs, 0.05, 11);
  Robot c(p, no_lag(), Vec2(2, 3), 0.0, 500 * kMs, 0.05, 12);
  Vec2 sum = Vec2::Zero();
  double sq = 0.0;
  bool differs = false;
  const int n = 4000;
  for (int k = 0; k < n; ++k) {
    const dds::PoseSample pa = a.pose(), pb = b.pose(), pc = c.pose();
    CHECK(pa.x == pb.x);  // the same seed, the same draws
    differs = differs || pa.x != pc.x;
    CHECK(pa.x != Vec2(2, 3));
    CHECK(pa.yaw == 0.0);
    sum += pa.x - Vec2(2, 3);
    sq += (pa.x - Vec2(2, 3)).squaredNorm();
  }
  CHECK(differs);
  CHECK(a.body().base == Vec2(2, 3));  // the body itself is not noisy
  // Mean about 0 (standard error 0.05 / sqrt(4000) = 0.0008), standard deviation per axis about 0.05.
  CHECK(std::abs(sum.x() / n) < 0.004);
  CHECK(std::abs(sum.y() / n) < 0.004);
  CHECK(std::sqrt(sq / (2 * n)) == Approx(0.05).epsilon(0.05));
}

TEST_CASE("robot: the watchdog: no command stopped, a fresh one moves, a stale one stops it once",
          "[vehicle]") {
  const core::VehicleParams p = integrator();
  const std::int64_t timeout = 500 * kMs;
  Robot r(p, no_lag(), Vec2(0, 0), 0.0, timeout, 0.0, 1);

  // No command yet: stopped, not counted as a watchdog stop.
  CHECK(r.stopped_by_watchdog(0));
  CHECK_FALSE(r.step(10 * kMs, 0.1));
  CHECK(r.body().base == Vec2(0, 0));
  CHECK(r.watchdog_stops() == 0);

  // A fresh command: it moves (0.5 m/s along x for 0.1 s).
  r.on_command(twist(0.5, 0.0, 0.0), 100 * kMs);
  CHECK(r.commands() == 1);
  CHECK_FALSE(r.stopped_by_watchdog(100 * kMs));
  CHECK_FALSE(r.step(200 * kMs, 0.1));
  CHECK(r.body().base.x() == Approx(0.05).margin(1e-15));
  CHECK(r.body().base.y() == 0.0);
  // Still fresh at exactly the timeout.
  CHECK_FALSE(r.stopped_by_watchdog(100 * kMs + timeout));
  CHECK_FALSE(r.step(100 * kMs + timeout, 0.1));
  CHECK(r.body().base.x() == Approx(0.10).margin(1e-15));

  // Older than the timeout: step() says so once, and the robot holds still.
  CHECK(r.stopped_by_watchdog(100 * kMs + timeout + 1));
  CHECK(r.step(100 * kMs + timeout + 1, 0.1));
  CHECK(r.watchdog_stops() == 1);
  const Vec2 held = r.body().base;
  CHECK(held.x() == Approx(0.10).margin(1e-15));
  CHECK((r.body().actual.vx == 0.0 && r.body().actual.vy == 0.0 && r.body().actual.wz == 0.0));
  for (int k = 1; k <= 5; ++k) CHECK_FALSE(r.step(100 * kMs + timeout + k * 100 * kMs, 0.1));
  CHECK(r.body().base == held);
  CHECK(r.watchdog_stops() == 1);
  CHECK(r.pose().vx == 0.0);

  // Commands again: moves; stale again: a second stop.
  r.on_command(twist(0.0, -1.0, 0.0), 2000 * kMs);
  CHECK_FALSE(r.step(2000 * kMs, 0.1));
  CHECK(r.body().base.y() == Approx(held.y() - 0.1).margin(1e-15));
  CHECK(r.step(2000 * kMs + timeout + 1, 0.1));
  CHECK(r.watchdog_stops() == 2);
  CHECK(r.commands() == 2);
}

TEST_CASE("robot: the newest command wins; limits and the lag are the body's", "[vehicle]") {
  const core::VehicleParams p = unicycle();
  core::BodyParams lag;
  lag.response_s = 0.1;
  Robot r(p, lag, Vec2(0, 0), 0.0, 500 * kMs, 0.0, 1);
  r.on_command(twist(0.2, 0.0, 0.0), 0);
  r.on_command(twist(3.0, 0.7, 5.0), 10 * kMs);  // beyond max_speed and max_yaw_rate, and sideways
  CHECK(r.commands() == 2);
  // The lag: after one step of h, 1 - exp(-h / 0.1) of the way to the command, then the limits.
  CHECK_FALSE(r.step(20 * kMs, 0.02));
  const double k = 1.0 - std::exp(-0.2);
  CHECK(r.body().actual.vx == Approx(3.0 * k));
  CHECK(r.body().actual.vy == 0.0);  // a unicycle cannot move sideways
  CHECK(r.body().actual.wz == Approx(5.0 * k));
  for (int i = 2; i <= 50; ++i) r.step(i * 10 * kMs, 0.02);
  CHECK(r.body().actual.vx == 1.0);  // held to max_speed
  CHECK(r.body().actual.wz == 2.0);  // and max_yaw_rate
  // Stopped by the watchdog, it slows with the same lag rather than at once.
  REQUIRE(r.step(510 * kMs + 1, 0.02));
  const double after = r.body().actual.vx;
  CHECK(after == Approx(1.0 * std::exp(-0.2)));
  r.step(530 * kMs, 0.02);
  CHECK(r.body().actual.vx < after);
}
