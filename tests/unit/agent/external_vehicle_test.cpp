// Unit tests of AgentLogic driving a robot outside the process (vehicle.interface ros2): how it judges
// the robot's poses, and the velocity command each step computes for it.
#include <catch2/catch.hpp>
#include <cmath>
#include <string>

#include "agent_logic.hpp"
#include "core/vehicle.hpp"

using namespace shapeform;
using agent::AgentLogic;
using Catch::Matchers::Contains;
using core::Vec2;

namespace {
constexpr std::int64_t kMs = 1'000'000;
constexpr double kPi = 3.14159265358979323846;

core::CompiledCommand circle(double dt = 1.0, bool hold = false) {
  core::Command c;
  c.shape.kind = core::ShapeKind::Circle;
  c.shape.r0 = 4;
  c.dt = dt;
  c.hold = hold;
  return core::compile(c);
}

bool adopt(AgentLogic& a, const core::CompiledCommand& cmd, std::uint64_t epoch) {
  return a.on_command(dds::CommandSample{cmd, dds::CommandId{epoch}, ""}) ==
         dds::CommandArbiter::Verdict::Adopted;
}

core::VehicleParams integrator(double max_speed) {
  core::VehicleParams p;
  p.max_speed = max_speed;
  p.seconds_per_model_time = 0.05;
  return p;
}

core::VehicleParams unicycle() {
  core::VehicleParams p;
  p.model = core::VehicleModel::Unicycle;
  p.max_speed = 1.0;
  p.max_yaw_rate = 2.0;
  p.offset = 0.2;
  p.seconds_per_model_time = 0.05;
  return p;
}

AgentLogic::ExternalVehicle ext(double period_s = 0.05) {
  AgentLogic::ExternalVehicle e;
  e.frame = "map";
  e.pose_timeout_ns = 500 * kMs;
  e.pose_jump_m = 0.5;
  e.period_s = period_s;
  return e;
}

bool zero(const core::VehicleCommand& c) {
  return c.twist.vx == 0.0 && c.twist.vy == 0.0 && c.twist.wz == 0.0 && c.world == Vec2::Zero();
}

using Verdict = AgentLogic::PoseVerdict;
}  // namespace

TEST_CASE("external vehicle: a pose in another frame is refused, naming both frames",
          "[agent][vehicle][ros2]") {
  AgentLogic a(3, Vec2(0, 0), 60 * kMs);
  a.set_external_vehicle(integrator(1.0), ext());
  CHECK(a.external());
  CHECK_FALSE(a.has_pose());
  std::string why;
  CHECK(a.on_pose(Vec2(1, 2), 0.0, "odom", 10 * kMs, why) == Verdict::WrongFrame);
  CHECK_THAT(why, Contains("'odom'"));
  CHECK_THAT(why, Contains("'map'"));
  CHECK_THAT(why, Contains("vehicle.frame"));
  CHECK(a.poses_refused() == 1);
  CHECK_FALSE(a.has_pose());
  CHECK(a.pose_received_ns() == -1);
  CHECK(a.position() == Vec2(0, 0));  // not used
  // Case matters: a frame is a name.
  CHECK(a.on_pose(Vec2(1, 2), 0.0, "Map", 20 * kMs, why) == Verdict::WrongFrame);
  CHECK(a.poses_refused() == 2);
  // Refused before on_pose (an invalid message): counted with the others.
  a.count_refused_pose();
  CHECK(a.poses_refused() == 3);
  why.clear();
  CHECK(a.on_pose(Vec2(1, 2), 0.0, "map", 30 * kMs, why) == Verdict::Accepted);
  CHECK(a.poses_refused() == 3);
}

TEST_CASE("external vehicle: the first pose is accepted anywhere; the agent is at its controlled point",
          "[agent][vehicle][ros2]") {
  SECTION("integrator: the pose itself") {
    AgentLogic a(0, Vec2(0, 0), 60 * kMs);
    a.set_external_vehicle(integrator(1.0), ext());
    std::string why;
    CHECK(a.on_pose(Vec2(900, -700), 1.0, "map", 5 * kMs, why) == Verdict::Accepted);  // far from the start
    CHECK(a.position() == Vec2(900, -700));
    CHECK(a.vehicle().heading == 1.0);
    CHECK(a.has_pose());
    CHECK(a.pose_received_ns() == 5 * kMs);
  }
  SECTION("unicycle: offset ahead of the axle along the yaw") {
    AgentLogic a(0, Vec2(0, 0), 60 * kMs);
    const core::VehicleParams p = unicycle();
    a.set_external_vehicle(p, ext());
    std::string why;
    CHECK(a.on_pose(Vec2(2, 3), kPi / 2, "map", 0, why) == Verdict::Accepted);
    CHECK(a.position().x() == Approx(2.0).margin(1e-15));
    CHECK(a.position().y() == Approx(3.2).margin(1e-15));
    CHECK(a.position() == core::controlled_point(p, Vec2(2, 3), kPi / 2));
    CHECK(a.vehicle().x == a.position());
    CHECK(a.vehicle().heading == kPi / 2);
  }
}

TEST_CASE("external vehicle: a pose beyond max_speed x elapsed + pose_jump_m is refused and not used",
          "[agent][vehicle][ros2]") {
  AgentLogic a(0, Vec2(0, 0), 60 * kMs);
  a.set_external_vehicle(integrator(2.0), ext());  // 2 m/s, 0.5 m of slack
  std::string why;
  REQUIRE(a.on_pose(Vec2(10, 0), 0.0, "map", 1000 * kMs, why) == Verdict::Accepted);
  // 0.25 s later it may be 2 x 0.25 + 0.5 = 1 m away.
  CHECK(a.on_pose(Vec2(11.01, 0), 0.0, "map", 1250 * kMs, why) == Verdict::Jump);
  CHECK_THAT(why, Contains("pose jumped 1.01 m in 0.25 s"));
  CHECK_THAT(why, Contains("vehicle.pose_jump_m = 1 m"));
  CHECK(a.poses_refused() == 1);
  CHECK(a.position() == Vec2(10, 0));         // not used
  CHECK(a.pose_received_ns() == 1000 * kMs);  // nor its time: the next pose is judged from the last accepted
  CHECK(a.on_pose(Vec2(10, 0.99), 0.0, "map", 1250 * kMs, why) == Verdict::Accepted);
  CHECK(a.position() == Vec2(10, 0.99));
  CHECK(a.poses_refused() == 1);
  // No time elapsed, or a clock that went back: the slack alone.
  CHECK(a.on_pose(Vec2(10, 1.5), 0.0, "map", 1250 * kMs, why) == Verdict::Jump);  // 0.51 m
  CHECK(a.on_pose(Vec2(10, 1.5), 0.0, "map", 1000 * kMs, why) == Verdict::Jump);
  CHECK_THAT(why, Contains("in -0.25 s"));
  CHECK(a.on_pose(Vec2(10, 1.48), 0.0, "map", 1000 * kMs, why) == Verdict::Accepted);  // 0.49 m
  CHECK(a.poses_refused() == 3);
  // Long silence: the reach grows with the time since the last accepted pose.
  CHECK(a.on_pose(Vec2(30, 1.48), 0.0, "map", 11'000 * kMs, why) == Verdict::Accepted);  // 20 m in 10 s
  CHECK(a.position() == Vec2(30, 1.48));
}

TEST_CASE("external vehicle: a unicycle's jump is judged at its controlled point", "[agent][vehicle][ros2]") {
  AgentLogic a(0, Vec2(0, 0), 60 * kMs);
  core::VehicleParams p = unicycle();
  p.offset = 0.4;
  a.set_external_vehicle(p, ext());
  std::string why;
  REQUIRE(a.on_pose(Vec2(0, 0), 0.0, "map", 0, why) == Verdict::Accepted);
  // Turning on the spot by a half turn moves the point 0.8 m: more than the 0.5 m slack at once.
  CHECK(a.on_pose(Vec2(0, 0), kPi, "map", 0, why) == Verdict::Jump);
  CHECK(a.vehicle().heading == 0.0);
  // A quarter turn moves it 0.4 sqrt(2) = 0.57 m: accepted 0.1 s later (reach 1 x 0.1 + 0.5).
  CHECK(a.on_pose(Vec2(0, 0), kPi / 2, "map", 100 * kMs, why) == Verdict::Accepted);
  CHECK(a.position().x() == Approx(0.0).margin(1e-15));
  CHECK(a.position().y() == Approx(0.4));
}

TEST_CASE("external vehicle: pose_fresh until pose_timeout after the newest accepted pose",
          "[agent][vehicle][ros2]") {
  AgentLogic a(0, Vec2(0, 0), 60 * kMs);
  a.set_external_vehicle(integrator(1.0), ext());
  CHECK_FALSE(a.pose_fresh(0));
  std::string why;
  REQUIRE(a.on_pose(Vec2(1, 1), 0.0, "map", 2000 * kMs, why) == Verdict::Accepted);
  CHECK(a.pose_fresh(2000 * kMs));
  CHECK(a.pose_fresh(2500 * kMs));  // exactly the timeout: still fresh
  CHECK_FALSE(a.pose_fresh(2500 * kMs + 1));
  // A refused pose does not refresh it.
  CHECK(a.on_pose(Vec2(1, 1), 0.0, "odom", 2400 * kMs, why) == Verdict::WrongFrame);
  CHECK_FALSE(a.pose_fresh(2600 * kMs));
  REQUIRE(a.on_pose(Vec2(1, 1.1), 0.0, "map", 2600 * kMs, why) == Verdict::Accepted);
  CHECK(a.pose_fresh(3100 * kMs));
  CHECK_FALSE(a.pose_fresh(3100 * kMs + 1));
}

TEST_CASE("external vehicle: an integrator is commanded (law_x - x) / h, shortened to max_speed",
          "[agent][vehicle][ros2]") {
  const core::CompiledCommand cmd = circle(0.5);
  const Vec2 at(6, 1);
  const double h = cmd.dt * 0.05;  // integration.dt x seconds_per_model_time
  const Vec2 law_x = core::agent_step(cmd, 0, at, {}, 0.0).x;
  const Vec2 wanted = (law_x - at) / h;
  REQUIRE(wanted.norm() > 1.0);  // so a limit below it binds

  SECTION("within max_speed: the law's step in one law step's time") {
    AgentLogic a(0, Vec2(0, 0), 60 * kMs);
    a.set_external_vehicle(integrator(10 * wanted.norm()), ext());
    std::string why;
    REQUIRE(a.on_pose(at, 0.3, "map", 0, why) == Verdict::Accepted);
    REQUIRE(adopt(a, cmd, 1));
    CHECK(a.step());
    const core::VehicleCommand& c = a.vehicle_command();
    CHECK(c.world.x() == Approx(wanted.x()).epsilon(1e-12));
    CHECK(c.world.y() == Approx(wanted.y()).epsilon(1e-12));
    CHECK_FALSE(c.saturated);
    CHECK(a.commands_saturated() == 0);
    // The twist is the same velocity in the body frame (heading 0.3), no yaw.
    const Vec2 back(std::cos(0.3) * c.twist.vx - std::sin(0.3) * c.twist.vy,
                    std::sin(0.3) * c.twist.vx + std::cos(0.3) * c.twist.vy);
    CHECK(back.x() == Approx(wanted.x()).epsilon(1e-12));
    CHECK(back.y() == Approx(wanted.y()).epsilon(1e-12));
    CHECK(c.twist.wz == 0.0);
    // Nothing moves until the robot says so: the agent stays at the pose.
    CHECK(a.position() == at);
    // What it publishes as its velocity: shape units per model time.
    CHECK(a.velocity().x() == Approx(wanted.x() * 0.05).epsilon(1e-12));
    CHECK(a.velocity().y() == Approx(wanted.y() * 0.05).epsilon(1e-12));
  }
  SECTION("beyond max_speed: max_speed along the law's direction, counted") {
    AgentLogic a(0, Vec2(0, 0), 60 * kMs);
    a.set_external_vehicle(integrator(0.5), ext());
    std::string why;
    REQUIRE(a.on_pose(at, 0.0, "map", 0, why) == Verdict::Accepted);
    REQUIRE(adopt(a, cmd, 1));
    CHECK(a.step());
    const core::VehicleCommand& c = a.vehicle_command();
    CHECK(c.saturated);
    CHECK(c.world.norm() == Approx(0.5).epsilon(1e-12));
    CHECK(c.world.normalized().dot(wanted.normalized()) == Approx(1.0).epsilon(1e-12));
    CHECK(a.commands_saturated() == 1);
    CHECK(a.step());
    CHECK(a.commands_saturated() == 2);
  }
}

TEST_CASE("external vehicle: a unicycle's twist is core::vehicle_command's for its pose",
          "[agent][vehicle][ros2]") {
  const core::CompiledCommand cmd = circle();
  const core::VehicleParams p = unicycle();
  for (const auto& [base, yaw] :
       {std::pair<Vec2, double>{Vec2(6, 1), 0.0}, {Vec2(-3, 5), 2.0}, {Vec2(1, -7), -2.5}}) {
    AgentLogic a(0, Vec2(0, 0), 60 * kMs);
    a.set_external_vehicle(p, ext(0.05));
    std::string why;
    REQUIRE(a.on_pose(base, yaw, "map", 0, why) == Verdict::Accepted);
    REQUIRE(adopt(a, cmd, 1));
    REQUIRE(a.step());
    const Vec2 point = core::controlled_point(p, base, yaw);
    const Vec2 law_x = core::agent_step(cmd, 0, point, {}, 0.0).x;
    const core::VehicleCommand want =
        core::vehicle_command(p, core::vehicle_start(point, yaw), law_x, cmd.dt, 0.05);
    const core::VehicleCommand& got = a.vehicle_command();
    INFO("base " << base.transpose() << " yaw " << yaw);
    CHECK(got.twist.vx == want.twist.vx);
    CHECK(got.twist.vy == 0.0);
    CHECK(got.twist.wz == want.twist.wz);
    CHECK(got.world == want.world);
    CHECK(got.saturated == want.saturated);
    CHECK((got.twist.vx != 0.0 || got.twist.wz != 0.0));  // it is told to move
    CHECK(std::abs(got.twist.vx) <= p.max_speed);
    CHECK(std::abs(got.twist.wz) <= p.max_yaw_rate);
  }
}

TEST_CASE("external vehicle: a double integrator's command changes by at most max_accel x period per tick",
          "[agent][vehicle][ros2]") {
  core::VehicleParams p = integrator(1.0);
  p.model = core::VehicleModel::DoubleIntegrator;
  p.max_accel = 0.4;
  AgentLogic a(0, Vec2(0, 0), 60 * kMs);
  a.set_external_vehicle(p, ext(0.05));  // 0.02 m/s per tick
  std::string why;
  REQUIRE(a.on_pose(Vec2(6, 1), 0.0, "map", 0, why) == Verdict::Accepted);
  REQUIRE(adopt(a, circle(), 1));
  Vec2 last = Vec2::Zero();
  for (int k = 1; k <= 5; ++k) {
    REQUIRE(a.step());
    const Vec2 now = a.vehicle_command().world;
    INFO("tick " << k);
    // The last command is the velocity it ramps from (the agent feeds it back).
    CHECK((now - last).norm() == Approx(0.02).epsilon(1e-9));
    CHECK(now.norm() == Approx(0.02 * k).epsilon(1e-9));
    CHECK(a.vehicle_command().saturated);
    last = now;
  }
}

TEST_CASE("external vehicle: zero command before any command, while held, after stop_vehicle",
          "[agent][vehicle][ros2]") {
  AgentLogic a(0, Vec2(0, 0), 60 * kMs);
  a.set_external_vehicle(integrator(1.0), ext());
  std::string why;
  REQUIRE(a.on_pose(Vec2(6, 1), 0.0, "map", 0, why) == Verdict::Accepted);
  CHECK(zero(a.vehicle_command()));
  CHECK_FALSE(a.step());  // no command yet
  CHECK(zero(a.vehicle_command()));
  CHECK(a.model_time() == 0.0);

  REQUIRE(adopt(a, circle(), 1));
  REQUIRE(a.step());
  CHECK_FALSE(zero(a.vehicle_command()));
  CHECK(a.velocity() != Vec2::Zero());

  // Held: zero at once, model time stands still.
  const double t = a.model_time();
  REQUIRE(adopt(a, circle(1.0, true), 2));
  CHECK_FALSE(a.step());
  CHECK(zero(a.vehicle_command()));
  CHECK(a.velocity() == Vec2::Zero());
  CHECK(a.model_time() == 0.0);  // a new command restarts model time, and a held one does not advance it
  CHECK_FALSE(a.step());
  CHECK(a.model_time() == 0.0);
  CHECK(t > 0.0);

  // Released: moving again; then the pose is lost: stop_vehicle.
  REQUIRE(adopt(a, circle(), 3));
  REQUIRE(a.step());
  REQUIRE_FALSE(zero(a.vehicle_command()));
  a.stop_vehicle();
  CHECK(zero(a.vehicle_command()));
  CHECK(a.velocity() == Vec2::Zero());
  CHECK(a.vehicle().velocity == Vec2::Zero());
  CHECK(a.model_time() == 1.0);  // stopping does not step
}

TEST_CASE("external vehicle: model time advances by dt per step, the law stepping from each new pose",
          "[agent][vehicle][ros2]") {
  const core::CompiledCommand cmd = circle(0.25);
  AgentLogic a(0, Vec2(0, 0), 60 * kMs);
  const core::VehicleParams p = integrator(1e4);  // no limit binds: the robot can do as told
  a.set_external_vehicle(p, ext());
  std::string why;
  Vec2 at(6, 1);
  REQUIRE(a.on_pose(at, 0.0, "map", 0, why) == Verdict::Accepted);
  REQUIRE(adopt(a, cmd, 1));
  for (int k = 1; k <= 8; ++k) {
    const double t = a.model_time();
    REQUIRE(a.step());
    CHECK(a.model_time() == Approx(k * 0.25).margin(1e-15));
    // The command is toward the law's step from where the pose put the agent, at the agent's model time.
    const Vec2 law_x = core::agent_step(cmd, 0, at, {}, t).x;
    const Vec2 want = (law_x - at) / (cmd.dt * p.seconds_per_model_time);
    CHECK((a.vehicle_command().world - want).norm() <= 1e-12 * want.norm());
    // The robot moved as told (exactly, this once): the next pose.
    at += a.vehicle_command().world * (cmd.dt * p.seconds_per_model_time);
    REQUIRE(a.on_pose(at, 0.0, "map", k * 20 * kMs, why) == Verdict::Accepted);
    CHECK(a.previous_position() != a.position());
  }
}

TEST_CASE("fence: a robot found beyond it is a breach, counted once, and takes the breach action",
          "[agent][fence]") {
  core::Command c;
  c.shape.kind = core::ShapeKind::Circle;
  c.shape.r0 = 2;
  c.fence = {Vec2(-3, -3), Vec2(3, -3), Vec2(3, 3), Vec2(-3, 3)};
  c.fence_margin = 0.2;
  for (const auto action : {core::BreachAction::Return, core::BreachAction::Stop, core::BreachAction::Hold}) {
    CAPTURE(static_cast<int>(action));
    c.breach_action = action;
    AgentLogic a(0, Vec2(0, 2), 60 * kMs);
    AgentLogic::ExternalVehicle e = ext();
    e.pose_jump_m = 10.0;  // the push outside is accepted as a pose
    a.set_external_vehicle(integrator(1.0), e);
    std::string why;
    REQUIRE(a.on_pose(Vec2(0, 2), 0.0, "map", 0, why) == AgentLogic::PoseVerdict::Accepted);
    REQUIRE(adopt(a, core::compile(c), 1));
    a.step();
    CHECK_FALSE(a.beyond_fence());
    CHECK(a.take_breach() == 0.0);
    // Pushed 0.5 beyond the fence.
    REQUIRE(a.on_pose(Vec2(3.5, 0), 0.0, "map", 50 * kMs, why) == AgentLogic::PoseVerdict::Accepted);
    a.step();
    CHECK(a.beyond_fence());
    CHECK(a.take_breach() == Approx(0.5));
    CHECK(a.take_breach() == 0.0);  // reported once
    CHECK(a.safety().fence_breaches == 1);
    if (action == core::BreachAction::Return) {
      CHECK(a.fence_state() == agent::FenceState::Returning);
      CHECK(a.vehicle_command().world.x() < 0.0);  // driven back in
    } else {
      CHECK(a.fence_state() == agent::FenceState::Stopped);
      CHECK(zero(a.vehicle_command()));
    }
    // Still outside next step: the same excursion, not a new breach.
    REQUIRE(a.on_pose(Vec2(3.5, 0), 0.0, "map", 100 * kMs, why) == AgentLogic::PoseVerdict::Accepted);
    a.step();
    CHECK(a.safety().fence_breaches == 1);
    // The next command (the operator's resume, a new shape): back inside first.
    REQUIRE(adopt(a, core::compile(c), 2));
    CHECK(a.fence_state() == agent::FenceState::Returning);
    a.step();
    CHECK(a.vehicle_command().world.x() < 0.0);
  }
}
