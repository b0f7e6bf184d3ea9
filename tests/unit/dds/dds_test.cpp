// Unit tests of common/dds: conversions, validation, the transport profiles' QoS, the topic table, and
// an in-process loopback pub/sub between two nodes (each test case on its own DDS domain).
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <set>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastrtps/utils/IPLocator.h>

#include "core/metric_table.hpp"
#include "core/command_table.hpp"
#include "core/params.hpp"
#include "dds/convert.hpp"
#include "force_transport.hpp"
#include "dds/discovery.hpp"
#include "dds/node.hpp"
#include "dds/node_entities.hpp"
#include "dds/locators.hpp"
#include "dds/participant_factory.hpp"
#include "dds/stall.hpp"
#include "dds/state_input.hpp"
#include "dds/status_input.hpp"
#include "dds/topic_qos.hpp"
#include "protocol/transport.hpp"
#include "shapeform/msg/all_pubsub_types.h"
#include "shapes/shapes.hpp"
#include "util/clock.hpp"
#include "util/ipv4.hpp"

// Everything lives in namespace shapeform: Fast DDS's Topic.hpp declares a global ::dds namespace, so
// `using namespace shapeform; dds::...` would be ambiguous.
namespace shapeform {
namespace fdds = eprosima::fastdds::dds;
namespace frtps = eprosima::fastrtps::rtps;
using core::Vec2;

namespace {
/// True when the command's curve is the one its shape compiles to (not a default or stale curve).
bool compiled_from_shape(const core::CompiledCommand& c) {
  const auto fresh = shapes::compile_curve(c.shape);
  return fresh->closed() == c.curve().closed() && fresh->length() == c.curve().length();
}


constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

/// A domain of its own for each pub/sub test case and each test process (ctest may run the cases as
/// parallel processes): 150 + 5 * (pid % 16) + offset, offset 0..4, always within 150..229.
int test_domain(int offset) { return 150 + 5 * static_cast<int>(::getpid() % 16) + offset; }

dds::TransportConfig loopback(int domain) {
  test::force_transport();
  dds::TransportConfig t;
  t.profile = "loopback";
  t.domain = domain;
  t.max_participants = 16;
  return t;
}

/// Polls pred until true or timeout_s passes; returns the last verdict.
template <class Pred>
bool wait_for(Pred pred, double timeout_s = 10.0) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (std::chrono::steady_clock::now() < end) {
    if (pred()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return pred();
}

core::Command sample_command() {
  core::Command c;
  c.shape.kind = core::ShapeKind::Ellipse;
  c.shape.m = -0.5;
  c.shape.c = 1.25;
  c.shape.r0 = 3.5;
  c.shape.a = 6.0;
  c.shape.b = 2.5;
  c.shape.centre = core::Vec2(1.0, -2.0);
  c.shape.rotation = 0.625;
  c.shape.scale = 1.5;
  // Valid for their kinds, so every kind of this command compiles.
  c.shape.r_expr = "4 + cos(5*phi)";
  c.shape.x_expr = "3*cos(2*pi*s)";
  c.shape.y_expr = "2*sin(2*pi*s) + 0.5*sin(4*pi*s)";
  c.shape.f_expr = "x^4 + y^4 - 81";
  c.shape.vertices = {core::Vec2(-4, -3), core::Vec2(4, -3), core::Vec2(4, 2), core::Vec2(0, 5),
                      core::Vec2(-4, 2)};
  c.shape.closed = false;
  c.law = core::Law::Arc;
  c.arc.k_normal = 0.75;
  c.arc.k_tangent = 0.5;
  c.arc.spacing = 1.25;
  c.tracking.enabled = true;
  c.tracking.path.kind = core::CentrePath::Kind::Circle;
  c.tracking.path.point = core::Vec2(0.5, 0.25);
  c.tracking.path.velocity = core::Vec2(0.01, -0.02);
  c.tracking.path.origin = core::Vec2(-1.0, 3.0);
  c.tracking.path.radius = 7.0;
  c.tracking.path.period = 150.0;
  c.tracking.path.phase = 0.75;
  c.tracking.feedforward = true;
  c.gains.k1 = 0.2;
  c.gains.k2 = 1.5;
  c.gains.sigma = 2.5;
  c.gains.beta = 1.1;
  c.gains.r = 0.05;
  c.integrator = core::Integrator::RK4;
  c.dt = 0.5;
  c.max_speed = 3.0;
  c.hold = true;  // not the default, so a field dropped on the way is seen
  return c;
}

/// Every field of the command table equal (a field the table gains is compared too).
void require_same(const core::Command& a, const core::Command& b) {
  for (const auto& p : core::params::command_table()) {
    INFO(p.key);
    CHECK(p.get(a) == p.get(b));
  }
}

/// from_msg of a valid command with one mutation; returns the error ("" when accepted).
template <class Mutate>
std::string reject(Mutate mutate) {
  msg::ShapeCommand m = dds::to_msg(sample_command(), 1);
  mutate(m);
  core::CompiledCommand out;
  out.dt = 123.0;  // sentinel: must stay untouched on failure
  std::string error;
  const bool ok = dds::from_msg(m, out, error);
  if (!ok) CHECK(out.dt == 123.0);
  return ok ? std::string() : error;
}

msg::AgentState good_state() {
  msg::AgentState s;
  s.id(3);
  s.seq(10);
  s.stamp_ns(123456789);
  s.epoch(2);
  s.model_time(42.0);
  s.x(1.5);
  s.y(-2.5);
  s.vx(0.1);
  s.vy(-0.2);
  s.has_arc(true);
  s.arc(7.25);
  return s;
}

std::string state_problem(const msg::AgentState& s) {
  std::string why;
  return dds::valid_state(s, why) ? std::string() : why;
}

std::shared_ptr<eprosima::fastdds::rtps::UDPv4TransportDescriptor> only_udp(const fdds::DomainParticipantQos& q) {
  REQUIRE(q.transport().user_transports.size() == 1);
  auto udp = std::dynamic_pointer_cast<eprosima::fastdds::rtps::UDPv4TransportDescriptor>(
      q.transport().user_transports.front());
  REQUIRE(udp != nullptr);
  return udp;
}

bool is_loopback_locator(const frtps::Locator_t& l) {
  return l.kind == LOCATOR_KIND_UDPv4 && frtps::IPLocator::toIPv4string(l) == "127.0.0.1";
}

}  // namespace

// ---------------------------------------------------------------------------------------------------
// Conversions and validation

TEST_CASE("ShapeCommand carries a 64-bit epoch, its issuer and the issuer's name", "[dds][convert][order]") {
  const dds::SourceId issuer{{1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12}};
  const dds::SourceId writer{{7, 7, 7, 7, 7, 7, 7, 7, 7, 7, 7, 7}};
  const std::uint64_t epoch = (1ULL << 32) + 5;  // beyond 32 bits
  msg::ShapeCommand m = dds::to_msg(sample_command(), dds::CommandId{epoch, issuer}, "shapeform_supervisor on h pid 1");
  CHECK(m.epoch() == epoch);
  dds::CommandSample c;
  std::string error;
  REQUIRE(dds::from_msg(m, writer, c, error));
  CHECK(c.id == dds::CommandId{epoch, issuer});  // a re-offered copy keeps the issuer, not its writer
  CHECK(c.issuer_name == "shapeform_supervisor on h pid 1");
  CHECK(dds::describe_issuer(c.issuer_name, c.id.issuer) ==
        "shapeform_supervisor on h pid 1 [01.02.03.04.05.06.07.08.09.0a.0b.0c]");
  // A writer that leaves the issuer empty issued the command itself; its name is cleaned and cut.
  m.issuer({});
  m.issuer_name("rogue\n" + std::string(500, 'x'));
  REQUIRE(dds::from_msg(m, writer, c, error));
  CHECK(c.id == dds::CommandId{epoch, writer});
  CHECK(c.issuer_name.size() == dds::kIssuerNameMax);
  CHECK(c.issuer_name.rfind("rogue?x", 0) == 0);
  CHECK(dds::describe_issuer("", writer) == "07.07.07.07.07.07.07.07.07.07.07.07");
  m.epoch(0);
  CHECK_FALSE(dds::from_msg(m, writer, c, error));
  CHECK(error == "command.epoch: must be >= 1, got 0");
}

TEST_CASE("ShapeCommand round trip keeps every field", "[dds][convert]") {
  const core::Command in = sample_command();
  const msg::ShapeCommand m = dds::to_msg(in, 7);
  CHECK(m.epoch() == 7u);
  CHECK(m.shape_kind() == "ellipse");
  CHECK(m.path_kind() == "circle");
  CHECK(m.integrator() == "rk4");
  CHECK(m.law() == "arc");
  CHECK(m.rotation() == 0.625);
  CHECK(m.scale() == 1.5);
  CHECK(m.r_expr() == "4 + cos(5*phi)");
  CHECK(m.vertices() == std::vector<double>{-4, -3, 4, -3, 4, 2, 0, 5, -4, 2});  // flattened
  CHECK_FALSE(m.closed());
  CHECK(m.k_normal() == 0.75);
  CHECK(m.k_tangent() == 0.5);
  CHECK(m.spacing() == 1.25);
  CHECK(m.hold());
  CHECK_FALSE(dds::to_msg(core::Command{}, 1).hold());
  CHECK(dds::to_msg(core::Command{}, 1).law() == "paper");

  core::CompiledCommand out;
  std::string error;
  REQUIRE(dds::from_msg(m, out, error));
  CHECK(error.empty());
  require_same(in, out);
  CHECK(compiled_from_shape(out));  // compiled on receipt

  SECTION("every kind and law survives, compiled to the same curve as the sender's") {
    for (auto kind : {core::ShapeKind::Line, core::ShapeKind::Circle, core::ShapeKind::Ellipse,
                      core::ShapeKind::Square, core::ShapeKind::Polar, core::ShapeKind::Parametric,
                      core::ShapeKind::Implicit, core::ShapeKind::Polygon}) {
      for (const bool closed : {true, false}) {
        for (auto law : {core::Law::Paper, core::Law::Arc}) {
          INFO(core::to_string(kind) << " closed " << closed << " law " << core::to_string(law));
          core::Command c = in;
          c.shape.kind = kind;
          c.shape.closed = closed;
          c.law = law;
          const msg::ShapeCommand w = dds::to_msg(c, 3);
          CHECK(w.shape_kind() == std::string(core::to_string(kind)));
          CHECK(w.law() == std::string(core::to_string(law)));
          core::CompiledCommand back;
          REQUIRE(dds::from_msg(w, back, error));
          require_same(c, back);
          REQUIRE(compiled_from_shape(back));
          const core::CompiledCommand local = shapes::compile(c);
          CHECK(back.curve().closed() == local.curve().closed());
          CHECK(back.curve().length() == local.curve().length());
          for (const core::Vec2& x : {core::Vec2(9, 1), core::Vec2(-2, 7), core::Vec2(0.5, -6)}) {
            const core::Vec2 got = core::target_point(back.shape, back.curve(), x);
            const core::Vec2 want = core::target_point(local.shape, local.curve(), x);
            CHECK(got == want);
          }
        }
      }
    }
  }

  SECTION("every shape, path and integrator name survives") {
    for (auto kind : {core::ShapeKind::Line, core::ShapeKind::Circle, core::ShapeKind::Ellipse,
                      core::ShapeKind::Square}) {
      for (auto path : {core::CentrePath::Kind::Fixed, core::CentrePath::Kind::Line,
                        core::CentrePath::Kind::Circle}) {
        for (auto integ : {core::Integrator::Euler, core::Integrator::RK4}) {
          core::Command c = in;
          c.shape.kind = kind;
          c.tracking.path.kind = path;
          c.integrator = integ;
          core::CompiledCommand back;
          REQUIRE(dds::from_msg(dds::to_msg(c, 1), back, error));
          CHECK(back.shape.kind == kind);
          CHECK(back.tracking.path.kind == path);
          CHECK(back.integrator == integ);
        }
      }
    }
  }
  SECTION("the default command is accepted") {
    core::CompiledCommand back;
    REQUIRE(dds::from_msg(dds::to_msg(core::Command{}, 1), back, error));
    require_same(core::Command{}, back);
    CHECK(compiled_from_shape(back));
  }
  SECTION("an empty vertex list and empty expressions travel as such") {
    core::Command c = in;
    c.shape.vertices.clear();
    c.shape.r_expr.clear();
    c.shape.kind = core::ShapeKind::Circle;
    core::CompiledCommand back;
    REQUIRE(dds::from_msg(dds::to_msg(c, 1), back, error));
    CHECK(back.shape.vertices.empty());
    CHECK(back.shape.r_expr.empty());
  }
}

TEST_CASE("ShapeCommand survives CDR serialization, large polygons and long expressions included",
          "[dds][convert]") {
  core::Command c = sample_command();
  c.shape.kind = core::ShapeKind::Polygon;
  c.shape.closed = true;
  c.shape.vertices.clear();
  constexpr int kVertices = 2000;  // 32 KB of vertices: beyond any default bound of sequences
  for (int k = 0; k < kVertices; ++k) {
    const double th = 2.0 * 3.14159265358979323846 * k / kVertices;
    c.shape.vertices.emplace_back(4.0 * std::cos(th), 3.0 * std::sin(th));
  }
  std::string long_expr = "4";
  while (long_expr.size() < 1000) long_expr += " + 0*cos(phi)";
  c.shape.r_expr = long_expr;
  const msg::ShapeCommand m = dds::to_msg(c, 9);

  msg::ShapeCommandPubSubType type;
  eprosima::fastrtps::rtps::SerializedPayload_t payload(type.getSerializedSizeProvider(
      const_cast<msg::ShapeCommand*>(&m))());
  REQUIRE(type.serialize(const_cast<msg::ShapeCommand*>(&m), &payload));
  msg::ShapeCommand read;
  REQUIRE(type.deserialize(&payload, &read));
  CHECK(read.vertices().size() == 2u * kVertices);
  CHECK(read.r_expr() == long_expr);
  core::CompiledCommand back;
  std::string error;
  REQUIRE(dds::from_msg(read, back, error));
  require_same(c, back);
  c.shape.kind = core::ShapeKind::Polar;
  REQUIRE(dds::from_msg(dds::to_msg(c, 10), back, error));
  // r(phi) = 4 (the long sum adds zeros), scaled by 1.5 about the centre (1, -2).
  CHECK((core::target_point(back.shape, back.curve(), core::Vec2(30, 0)) - core::Vec2(1, -2)).norm() ==
        Approx(6.0).epsilon(1e-9));
}

TEST_CASE("ShapeCommand rejections name the field", "[dds][convert]") {
  using M = msg::ShapeCommand;
  // Non-positive where > 0 is required.
  CHECK(reject([](M& m) { m.sigma(-1); }) == "command.sigma: must be > 0, got -1");
  CHECK(reject([](M& m) { m.r0(0); }) == "command.r0: must be > 0, got 0");
  CHECK(reject([](M& m) { m.a(-2); }) == "command.a: must be > 0, got -2");
  CHECK(reject([](M& m) { m.b(0); }) == "command.b: must be > 0, got 0");
  CHECK(reject([](M& m) { m.dt(0); }) == "command.dt: must be in (0, 10], got 0");
  // The command table's bound, the same as the config's and the console's.
  CHECK(reject([](M& m) { m.dt(50); }) == "command.dt: must be in (0, 10], got 50");
  CHECK(reject([](M& m) { m.dt(10); }).empty());
  CHECK(reject([](M& m) { m.path_period(-5); }) == "command.path_period: must be > 0, got -5");
  // Negative where >= 0 is required.
  CHECK(reject([](M& m) { m.beta(-0.5); }) == "command.beta: must be >= 0, got -0.5");
  CHECK(reject([](M& m) { m.r(-0.1); }) == "command.r: must be >= 0, got -0.1");
  CHECK(reject([](M& m) { m.k1(-1); }) == "command.k1: must be >= 0, got -1");
  CHECK(reject([](M& m) { m.k2(-1); }) == "command.k2: must be >= 0, got -1");
  CHECK(reject([](M& m) { m.max_speed(-3); }) == "command.max_speed: must be >= 0, got -3");
  CHECK(reject([](M& m) { m.path_radius(-1); }) == "command.path_radius: must be >= 0, got -1");
  // Non-finite anywhere.
  CHECK(reject([](M& m) { m.k1(kNaN); }) == "command.k1: must be finite, got nan");
  CHECK(reject([](M& m) { m.cx(kInf); }) == "command.cx: must be finite, got inf");
  CHECK(reject([](M& m) { m.m(-kInf); }) == "command.m: must be finite, got -inf");
  CHECK(reject([](M& m) { m.sigma(kNaN); }) == "command.sigma: must be finite, got nan");
  CHECK(reject([](M& m) { m.path_phase(kNaN); }) == "command.path_phase: must be finite, got nan");
  // Unknown names.
  CHECK(reject([](M& m) { m.shape_kind("triangle"); }).find("command.shape_kind: unknown shape \"triangle\"") == 0);
  CHECK(reject([](M& m) { m.path_kind("spiral"); }).find("command.path_kind: unknown path \"spiral\"") == 0);
  CHECK(reject([](M& m) { m.integrator("rk45"); }).find("command.integrator: unknown integrator \"rk45\"") == 0);
  CHECK(reject([](M& m) { m.law("boids"); }) == "command.law: unknown law \"boids\" (paper|arc)");
  CHECK(reject([](M& m) { m.law("Arc"); }) == "command.law: unknown law \"Arc\" (paper|arc)");
  CHECK(reject([](M& m) { m.law(""); }).find("command.law:") == 0);
  CHECK(reject([](M& m) { m.law("paper"); }).empty());
  // The shape's placement and the arc law's parameters.
  CHECK(reject([](M& m) { m.rotation(kNaN); }) == "command.rotation: must be finite, got nan");
  CHECK(reject([](M& m) { m.scale(0); }) == "command.scale: must be > 0, got 0");
  CHECK(reject([](M& m) { m.scale(-1); }) == "command.scale: must be > 0, got -1");
  CHECK(reject([](M& m) { m.scale(kInf); }) == "command.scale: must be finite, got inf");
  CHECK(reject([](M& m) { m.k_normal(0); }) == "command.k_normal: must be in (0, 10], got 0");
  CHECK(reject([](M& m) { m.k_normal(10.5); }) == "command.k_normal: must be in (0, 10], got 10.5");
  CHECK(reject([](M& m) { m.k_normal(10); }).empty());
  CHECK(reject([](M& m) { m.k_tangent(0); }) == "command.k_tangent: must be in (0, 1], got 0");
  CHECK(reject([](M& m) { m.k_tangent(1.5); }) == "command.k_tangent: must be in (0, 1], got 1.5");
  CHECK(reject([](M& m) { m.k_tangent(kNaN); }) == "command.k_tangent: must be finite, got nan");
  CHECK(reject([](M& m) { m.spacing(0); }) == "command.spacing: must be > 0, got 0");
  CHECK(reject([](M& m) { m.vertices({1, 2, 3}); }) ==
        "command.vertices: must hold x, y pairs (an even count), got 3 numbers");
  CHECK(reject([](M& m) { m.vertices({1, 2, kNaN, 4}); }) ==
        "command.vertices[2]: must be finite, got nan");
  CHECK(reject([](M& m) { m.shape_kind("Polar"); }).find("command.shape_kind: unknown shape \"Polar\"") == 0);
  CHECK(reject([](M& m) { m.shape_kind(""); }).find("command.shape_kind:") == 0);

  SECTION("several problems are all reported") {
    const std::string e = reject([](M& m) {
      m.sigma(-1);
      m.dt(kNaN);
    });
    CHECK(e.find("command.sigma: must be > 0, got -1") != std::string::npos);
    CHECK(e.find("command.dt: must be finite, got nan") != std::string::npos);
  }
}

TEST_CASE("a shape that does not compile is rejected whole", "[dds][convert]") {
  using M = msg::ShapeCommand;
  CHECK(reject([](M& m) {
          m.shape_kind("polar");
          m.r_expr("4+foo");
        }) == "command: polar: r(phi) = '4+foo': Unexpected token \"foo\" found at position 2.");
  const std::string unknown = reject([](M& m) {
    m.shape_kind("polar");
    m.r_expr("4 + cos(5*theta)");
  });
  CHECK(unknown.rfind("command: polar: r(phi) = '4 + cos(5*theta)': ", 0) == 0);
  CHECK(unknown.find("\"theta\"") != std::string::npos);
  CHECK(reject([](M& m) {
          m.shape_kind("polar");
          m.r_expr("");
        }) == "command: polar: r(phi): empty expression");
  CHECK(reject([](M& m) {
          m.shape_kind("polar");
          m.r_expr("1 + 2*cos(phi)");
        }).rfind("command: polar: r(phi) must be finite and > 0 for every phi", 0) == 0);
  CHECK(reject([](M& m) {
          m.shape_kind("parametric");
          m.y_expr("sin(2*pi*t)");
        }).rfind("command: parametric: y(s) = 'sin(2*pi*t)': ", 0) == 0);
  CHECK(reject([](M& m) {
          m.shape_kind("implicit");
          m.f_expr("x^2+y^2+1");
        }) == "command: implicit curve: f(x, y) = 0 has no real points in the box "
              "(f = 'x^2+y^2+1', box [-20, 20]^2 around the centre)");
  CHECK(reject([](M& m) {
          m.shape_kind("polygon");
          m.closed(true);
          m.vertices({0, 0, 1, 0});
        }) == "command: polygon: a closed polygon needs at least 3 vertices, got 2");
  CHECK(reject([](M& m) {
          m.shape_kind("polygon");
          m.vertices({0, 0, 1, 0, 1, 0, 0, 1});
        }) == "command: polygon: vertices 1 and 2 coincide (zero-length edge)");
  CHECK(reject([](M& m) {
          m.shape_kind("polygon");
          m.closed(true);
          m.vertices({0, 0, 1, 1, 2, 2});
        }) == "command: polygon: the vertices are collinear (zero area)");
  // An open polygon of two vertices is a segment: fine.
  CHECK(reject([](M& m) {
          m.shape_kind("polygon");
          m.closed(false);
          m.vertices({0, 0, 1, 0});
        }).empty());
  // Field problems come first: a malformed message is not compiled at all.
  CHECK(reject([](M& m) {
          m.shape_kind("polar");
          m.r_expr("4+foo");
          m.sigma(-1);
        }) == "command.sigma: must be > 0, got -1");
}

TEST_CASE("valid_state rejects non-finite and absurd samples", "[dds][convert]") {
  CHECK(state_problem(good_state()).empty());

  auto s = good_state();
  s.id(-1);
  CHECK(state_problem(s) == "state.id: must be in 0..9999, got -1");
  s = good_state();
  s.x(kNaN);
  CHECK(state_problem(s) == "state.x: must be finite, got nan");
  s = good_state();
  s.vy(kInf);
  CHECK(state_problem(s) == "state.vy: must be finite, got inf");
  s = good_state();
  s.arc(kNaN);
  CHECK(state_problem(s) == "state.arc: must be finite, got nan");
  s.has_arc(false);  // arc must stay finite even when unknown
  CHECK(state_problem(s) == "state.arc: must be finite, got nan");
  s = good_state();
  s.arc(-kInf);
  CHECK(state_problem(s) == "state.arc: must be finite, got -inf");
  s = good_state();
  s.has_arc(false);
  s.arc(0.0);
  CHECK(state_problem(s).empty());
  dds::StateSample got;
  std::string why;
  REQUIRE(dds::from_msg(s, got, why));
  CHECK_FALSE(got.arc.has_value());  // without has_arc the arc is unknown
  CHECK_FALSE(got.prev_arc.has_value());
  REQUIRE(dds::from_msg(good_state(), got, why));
  CHECK(got.arc == std::optional<double>(7.25));
  s = good_state();
  s.model_time(kNaN);
  CHECK(state_problem(s) == "state.model_time: must be finite, got nan");
  s = good_state();
  s.y(2e6);
  CHECK(state_problem(s) == "state.y: |y| must be <= 1000000, got 2000000");
  s = good_state();
  s.x(-1e6);  // the limit itself is accepted
  CHECK(state_problem(s).empty());
  s = good_state();
  s.vx(8e5);
  s.vy(8e5);  // each component fine, speed 1.13e6 is not
  CHECK(state_problem(s).find("state.v: speed must be <= 1000000") == 0);
  // Speeds near the limit are decided by the named checks (hypot), not the quick test before them.
  s = good_state();
  s.vx(6e5);
  s.vy(8e5);  // exactly 1e6
  CHECK(state_problem(s).empty());
  s.vy(8.000001e5);
  CHECK(state_problem(s).find("state.v: speed must be <= 1000000") == 0);
  s.vx(0.0);
  s.vy(-9.95e5);  // within the limit, past the quick test's 0.99
  CHECK(state_problem(s).empty());
  s = good_state();
  s.prev_y(-kInf);
  CHECK(state_problem(s) == "state.prev_y: must be finite, got -inf");
  s = good_state();
  s.model_time(-1.0);
  CHECK(state_problem(s).find("state.model_time: must be in [0, ") == 0);
}

TEST_CASE("a state batch converts element by element and is refused whole, naming the element", "[dds][convert]") {
  std::vector<dds::StateSample> in(3);
  for (int k = 0; k < 3; ++k) {
    in[static_cast<std::size_t>(k)].id = 40 + k;
    in[static_cast<std::size_t>(k)].seq = 9;
    in[static_cast<std::size_t>(k)].x = core::Vec2(k, -k);
    in[static_cast<std::size_t>(k)].arc = 0.5 * k;
  }
  msg::AgentStateBatch m = dds::to_msg(in);
  CHECK(m.first_id() == 40);
  REQUIRE(m.states().size() == 3);
  // Into a reused message that held a longer, other batch: the same message as a fresh one.
  std::vector<dds::StateSample> longer(5);
  for (int k = 0; k < 5; ++k) longer[static_cast<std::size_t>(k)].id = 7 + k;
  msg::AgentStateBatch reused = dds::to_msg(longer);
  dds::to_msg(in, 0, in.size(), reused);
  CHECK(reused == m);
  std::vector<dds::StateSample> out;
  std::string why;
  REQUIRE(dds::from_msg(m, out, why));
  REQUIRE(out.size() == 3);
  for (std::size_t k = 0; k < 3; ++k) {
    // Each element as the per-agent conversion reads it.
    dds::StateSample one;
    REQUIRE(dds::from_msg(dds::to_msg(in[k]), one, why));
    CHECK(out[k].id == one.id);
    CHECK(out[k].x == one.x);
    CHECK(out[k].arc == one.arc);
    CHECK(out[k].prev_arc == one.prev_arc);
  }
  const auto refused = [&](msg::AgentStateBatch b) {
    std::vector<dds::StateSample> untouched(1);
    std::string w;
    CHECK_FALSE(dds::from_msg(b, untouched, w));
    CHECK(untouched.size() == 1);
    return w;
  };
  // Distinct ids in another order (not how a group publishes, but a valid batch): taken in its order.
  msg::AgentStateBatch shuffled = m;
  std::swap(shuffled.states()[0], shuffled.states()[1]);
  shuffled.first_id(41);
  REQUIRE(dds::from_msg(shuffled, out, why));
  REQUIRE(out.size() == 3);
  CHECK(out[0].id == 41);
  CHECK(out[1].id == 40);
  CHECK(out[1].x == in[0].x);
  CHECK(out[2].id == 42);
  msg::AgentStateBatch bad = m;
  bad.states()[1].x(std::nan(""));
  bad.states()[2].vy(1e300);
  CHECK(refused(bad) == "state_batch.states[1].x: must be finite, got nan; state_batch.states[2].v: speed must be <= "
                        "1000000, got 1e+300");
  bad = m;
  bad.first_id(41);
  CHECK(refused(bad) == "state_batch.first_id: must be the id of states[0] (40), got 41");
  bad = m;
  bad.states()[2].id(40);
  CHECK(refused(bad) == "state_batch.states: id 40 appears twice");
  bad.states().clear();
  CHECK(refused(bad) == "state_batch.states: must hold 1 to 1000 states, got 0");
  bad.states().assign(dds::kMaxBatchStates + 1, m.states()[0]);
  CHECK(refused(bad) == "state_batch.states: must hold 1 to 1000 states, got 1001");
}

TEST_CASE("batch_ranges cuts a process's states into nearly equal parts of at most max_states", "[dds][convert]") {
  using Ranges = std::vector<std::pair<std::size_t, std::size_t>>;
  CHECK(dds::batch_ranges(1000, 500) == Ranges{{0, 500}, {500, 1000}});
  CHECK(dds::batch_ranges(1000, 400) == Ranges{{0, 334}, {334, 667}, {667, 1000}});
  CHECK(dds::batch_ranges(100, 500) == Ranges{{0, 100}});
  CHECK(dds::batch_ranges(1, 1) == Ranges{{0, 1}});
  CHECK(dds::batch_ranges(0, 500).empty());
  CHECK(dds::batch_ranges(3, 0) == Ranges{{0, 1}, {1, 2}, {2, 3}});  // 0 taken as 1
  // Properties over a grid: in order, covering 0..count, each part 1..max, lengths within 1, fewest parts.
  for (std::size_t count = 1; count <= 1000; count += 37) {
    for (std::size_t max : {1u, 7u, 100u, 333u, 500u, 1000u}) {
      const auto r = dds::batch_ranges(count, max);
      REQUIRE(r.size() == (count + max - 1) / max);
      std::size_t at = 0, shortest = count, longest = 0;
      for (const auto& [b, e] : r) {
        CHECK(b == at);
        CHECK(e > b);
        CHECK(e - b <= max);
        shortest = std::min(shortest, e - b);
        longest = std::max(longest, e - b);
        at = e;
      }
      CHECK(at == count);
      CHECK(longest - shortest <= 1);
    }
  }
}

TEST_CASE("a part of a process's states converts as the batch of that part alone", "[dds][convert]") {
  std::vector<dds::StateSample> in(5);
  for (std::size_t k = 0; k < in.size(); ++k) {
    in[k].id = static_cast<std::int32_t>(100 + k);
    in[k].x = core::Vec2(static_cast<double>(k), 1.0);
  }
  const msg::AgentStateBatch part = dds::to_msg(in, 2, 5);
  CHECK(part.first_id() == 102);
  REQUIRE(part.states().size() == 3);
  CHECK(part == dds::to_msg(std::vector<dds::StateSample>(in.begin() + 2, in.end())));
  std::vector<dds::StateSample> out;
  std::string why;
  REQUIRE(dds::from_msg(part, out, why));
  CHECK(out[0].id == 102);
  CHECK(out[2].x == core::Vec2(4.0, 1.0));
  CHECK(dds::to_msg(in) == dds::to_msg(in, 0, in.size()));
}

TEST_CASE("valid_state refuses ids outside 0..kMaxAgentId and absurd model times", "[dds][convert]") {
  auto s = good_state();
  s.id(dds::kMaxAgentId);  // the bounds themselves are accepted
  s.model_time(dds::kModelTimeLimit);
  CHECK(state_problem(s).empty());
  s.id(0);
  s.model_time(0.0);
  CHECK(state_problem(s).empty());
  s = good_state();
  s.id(2147483647);  // 2^31 - 1: the rogue id of the fault probes
  CHECK(state_problem(s) == "state.id: must be in 0..9999, got 2147483647");
  s.id(dds::kMaxAgentId + 1);
  CHECK(state_problem(s) == "state.id: must be in 0..9999, got 10000");
  s = good_state();
  s.model_time(1e300);
  CHECK(state_problem(s) == "state.model_time: must be in [0, 1000000000], got 1e+300");
  s.model_time(-1.0);
  CHECK(state_problem(s) == "state.model_time: must be in [0, 1000000000], got -1");
  dds::StatusSample st;
  std::string why;
  msg::AgentStatus m;
  m.id(2147483647);
  CHECK_FALSE(dds::from_msg(m, st, why));
  CHECK(why == "status.id: must be in 0..9999, got 2147483647");
}

TEST_CASE("a received string is quoted in a rejection at most about util::kQuoteMax characters long",
          "[dds][convert]") {
  const std::string error = reject([](msg::ShapeCommand& m) { m.shape_kind(std::string(1'000'000, 'z')); });
  CHECK(error.find("command.shape_kind: unknown shape \"zzz") == 0);
  CHECK(error.size() < 500);
  CHECK(error.find("characters ...]") != std::string::npos);
}

TEST_CASE("AgentState converts both ways; a refused sample leaves the output untouched", "[dds][convert]") {
  dds::StateSample s;
  s.id = 7;
  s.seq = 99;
  s.stamp_ns = 123;
  s.command = dds::CommandId{(1ULL << 40) + 3, dds::SourceId{{1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12}}};
  s.model_time = 12.5;
  s.x = Vec2(1.0, -2.0);
  s.v = Vec2(0.5, 0.25);
  s.arc = 4.0;
  s.prev_x = Vec2(0.75, -1.5);
  s.prev_arc = 3.5;
  const msg::AgentState m = dds::to_msg(s);
  CHECK((m.id() == 7 && m.seq() == 99u && m.stamp_ns() == 123 && m.epoch() == (1ULL << 40) + 3 && m.model_time() == 12.5));
  CHECK(m.issuer() == s.command.issuer.prefix);
  CHECK((m.x() == 1.0 && m.y() == -2.0 && m.vx() == 0.5 && m.vy() == 0.25));
  CHECK((m.has_arc() && m.arc() == 4.0 && m.prev_arc() == 3.5 && m.prev_x() == 0.75 && m.prev_y() == -1.5));
  dds::StateSample back;
  std::string why;
  REQUIRE(dds::from_msg(m, back, why));
  CHECK((back.id == s.id && back.seq == s.seq && back.stamp_ns == s.stamp_ns && back.command == s.command));
  CHECK((back.model_time == s.model_time && back.x == s.x && back.v == s.v && back.prev_x == s.prev_x));
  CHECK((back.arc == s.arc && back.prev_arc == s.prev_arc));

  s.prev_arc.reset();  // a first step: the previous arc is the current one
  CHECK(dds::to_msg(s).prev_arc() == 4.0);
  s.arc.reset();  // no arc shared: both travel as 0 and come back unknown
  const msg::AgentState none = dds::to_msg(s);
  CHECK((!none.has_arc() && none.arc() == 0.0 && none.prev_arc() == 0.0));
  REQUIRE(dds::from_msg(none, back, why));
  CHECK((!back.arc && !back.prev_arc));

  msg::AgentState bad = m;
  bad.x(kNaN);
  dds::StateSample untouched;
  CHECK_FALSE(dds::from_msg(bad, untouched, why));
  CHECK(why == "state.x: must be finite, got nan");
  CHECK(untouched.id == 0);
}

TEST_CASE("TrackingTarget converts both ways and refuses non-finite or absurd values", "[dds][convert]") {
  const dds::TargetSample t{dds::CommandId{4, dds::SourceId{{9}}}, 20.0, Vec2(1.0, 2.0), Vec2(-0.5, 0.125), 777};
  const msg::TrackingTarget m = dds::to_msg(t);
  CHECK((m.epoch() == 4u && m.model_time() == 20.0 && m.cx() == 1.0 && m.cy() == 2.0));
  CHECK((m.vx() == -0.5 && m.vy() == 0.125 && m.stamp_ns() == 777));
  dds::TargetSample back;
  std::string why;
  REQUIRE(dds::from_msg(m, back, why));
  CHECK((back.command == t.command && back.model_time == t.model_time && back.centre == t.centre &&
         back.velocity == t.velocity && back.stamp_ns == t.stamp_ns));

  const auto problem = [&](auto mutate) {
    msg::TrackingTarget w = m;
    mutate(w);
    dds::TargetSample out;
    std::string error;
    const bool ok = dds::from_msg(w, out, error);
    CHECK(ok == error.empty());
    if (!ok) CHECK(out.command.none());  // untouched
    return error;
  };
  CHECK(problem([](msg::TrackingTarget&) {}).empty());
  CHECK(problem([](msg::TrackingTarget& w) { w.cx(kNaN); }) == "target.cx: must be finite, got nan");
  CHECK(problem([](msg::TrackingTarget& w) { w.model_time(kInf); }) == "target.model_time: must be finite, got inf");
  CHECK(problem([](msg::TrackingTarget& w) { w.vy(-2e6); }) == "target.vy: |vy| must be <= 1000000, got -2000000");
  CHECK(problem([](msg::TrackingTarget& w) { w.cy(1e6); }).empty());  // the limit itself is accepted
  CHECK(problem([](msg::TrackingTarget& w) {
          w.cx(kNaN);
          w.vx(kNaN);
        }) == "target.cx: must be finite, got nan; target.vx: must be finite, got nan");
}

TEST_CASE("a status batch converts element by element and is refused whole, naming the element", "[dds][convert]") {
  std::vector<dds::StatusSample> in(4);
  for (std::size_t k = 0; k < in.size(); ++k) {
    in[k].id = 30 + static_cast<std::int32_t>(k);
    in[k].ticks = 100 + k;
    in[k].neighbours_heard = static_cast<int>(k);
    in[k].min_gap = 0.25 * static_cast<double>(k);
  }
  // A part [1, 4) into a reused message that held a longer, other batch: first_id is the part's first.
  msg::AgentStatusBatch m;
  std::vector<dds::StatusSample> longer(6);
  dds::to_msg(longer, 0, longer.size(), m);
  dds::to_msg(in, 1, in.size(), m);
  CHECK(m.first_id() == 31);
  REQUIRE(m.statuses().size() == 3);
  std::vector<dds::StatusSample> out;
  std::string why;
  REQUIRE(dds::from_msg(m, out, why));
  REQUIRE(out.size() == 3);
  for (std::size_t k = 0; k < 3; ++k) {
    // Each element as the per-agent conversion writes and reads it.
    CHECK(m.statuses()[k] == dds::to_msg(in[k + 1]));
    CHECK(out[k].id == in[k + 1].id);
    CHECK(out[k].ticks == in[k + 1].ticks);
    CHECK(out[k].neighbours_heard == in[k + 1].neighbours_heard);
    CHECK(out[k].min_gap == in[k + 1].min_gap);
  }
  const auto refused = [&](const msg::AgentStatusBatch& b) {
    std::vector<dds::StatusSample> untouched(1);
    std::string w;
    CHECK_FALSE(dds::from_msg(b, untouched, w));
    CHECK(untouched.size() == 1);
    return w;
  };
  msg::AgentStatusBatch bad = m;
  bad.statuses()[1].id(-4);
  bad.statuses()[2].vehicle(9);
  CHECK(refused(bad) == "status_batch.statuses[1].id: must be in 0..9999, got -4; "
                        "status_batch.statuses[2].vehicle: must be 0..3, got 9");
  bad = m;
  bad.first_id(30);
  CHECK(refused(bad) == "status_batch.first_id: must be the id of statuses[0] (31), got 30");
  bad = m;
  bad.statuses()[2].id(31);
  CHECK(refused(bad) == "status_batch.statuses: id 31 appears twice");
  bad.statuses().clear();
  CHECK(refused(bad) == "status_batch.statuses: must hold 1 to 1000 statuses, got 0");
  bad.statuses().assign(dds::kMaxBatchStates + 1, m.statuses()[0]);
  CHECK(refused(bad) == "status_batch.statuses: must hold 1 to 1000 statuses, got 1001");
}

TEST_CASE("AgentStatus converts both ways; a negative id is refused", "[dds][convert]") {
  dds::StatusSample s;
  s.id = 5;
  s.stamp_ns = 1;
  s.ticks = 2;
  s.overruns = 3;
  s.lateness_max_us = 4.5;
  s.lateness_p99_us = 5.5;
  s.neighbours_heard = 6;
  s.stale_dropped = 7;
  s.samples_rejected = 8;
  s.samples_received = 9;
  s.samples_lost = 10;
  s.age_p50_us = 11.5;
  s.age_p99_us = 12.5;
  s.cpu_percent = 13.5;
  s.rss_mb = 14.5;
  s.epoch = 15;
  const msg::AgentStatus m = dds::to_msg(s);
  CHECK((m.id() == 5 && m.stamp_ns() == 1 && m.ticks() == 2u && m.overruns() == 3u));
  CHECK((m.lateness_max_us() == 4.5 && m.lateness_p99_us() == 5.5 && m.neighbours_heard() == 6));
  CHECK((m.stale_dropped() == 7u && m.samples_rejected() == 8u && m.samples_received() == 9u && m.samples_lost() == 10u));
  CHECK((m.age_p50_us() == 11.5 && m.age_p99_us() == 12.5 && m.cpu_percent() == 13.5 && m.rss_mb() == 14.5));
  CHECK(m.epoch() == 15u);
  dds::StatusSample back;
  std::string why;
  REQUIRE(dds::from_msg(m, back, why));
  CHECK((back.id == 5 && back.stamp_ns == 1 && back.ticks == 2u && back.overruns == 3u));
  CHECK((back.lateness_max_us == 4.5 && back.lateness_p99_us == 5.5 && back.neighbours_heard == 6));
  CHECK((back.stale_dropped == 7u && back.samples_rejected == 8u && back.samples_received == 9u && back.samples_lost == 10u));
  CHECK((back.age_p50_us == 11.5 && back.age_p99_us == 12.5 && back.cpu_percent == 13.5 && back.rss_mb == 14.5));
  CHECK(back.epoch == 15u);

  msg::AgentStatus bad = m;
  bad.id(-2);
  dds::StatusSample untouched;
  CHECK_FALSE(dds::from_msg(bad, untouched, why));
  CHECK(why == "status.id: must be in 0..9999, got -2");
  CHECK(untouched.id == 0);
}

TEST_CASE("SwarmMetrics carries every metric of the table under its name", "[dds][convert]") {
  // Each metric a distinct value (k + 0.5, counts k + 1): a field crossed with another would come back wrong.
  core::Metrics m;
  for (std::size_t k = 0; k < std::size(core::kMetricTable); ++k) {
    const core::MetricInfo& info = core::kMetricTable[k];
    info.set(m, static_cast<double>(k) + (info.count ? 1.0 : 0.5));
  }
  const msg::SwarmMetrics w = dds::to_msg(m, 1, 0.0, 0, false);
  CHECK((w.shape_error_mean() == 0.5 && w.gap_cv() == 2.5 && w.clusters() == 6 && w.arc_gap_cv() == 11.5));
  const core::Metrics back = dds::from_msg(w);
  for (const core::MetricInfo& info : core::kMetricTable) {
    INFO(info.name);
    REQUIRE(info.get(m).has_value());  // the test sets every metric of the table
    CHECK(info.get(back) == info.get(m));
  }
}

TEST_CASE("SwarmMetrics carries undefined values as -1", "[dds][convert]") {
  core::Metrics m;
  m.agents = 12;
  m.shape_error_mean = 0.25;
  m.gap_cv = 0.0;
  m.clusters = 1;
  m.curve_error_mean = 0.001;
  m.arc_gap_cv = 0.0;
  const msg::SwarmMetrics w = dds::to_msg(m, 4, 100.0, 99, true);
  CHECK(w.curve_error_mean() == 0.001);
  CHECK(w.curve_error_max() == -1.0);
  CHECK(w.arc_gap_cv() == 0.0);
  CHECK(w.epoch() == 4u);
  CHECK(w.agents_alive() == 12);
  CHECK(w.shape_error_mean() == 0.25);
  CHECK(w.shape_error_max() == -1.0);
  CHECK(w.gap_cv() == 0.0);
  CHECK(w.ring_error() == -1.0);
  CHECK(w.clusters() == 1);
  CHECK(w.converged());

  const core::Metrics back = dds::from_msg(w);
  CHECK(back.agents == 12);
  CHECK(back.shape_error_mean == std::optional<double>(0.25));
  CHECK_FALSE(back.shape_error_max.has_value());
  CHECK(back.gap_cv == std::optional<double>(0.0));
  CHECK_FALSE(back.centroid_error.has_value());
  CHECK(back.clusters == std::optional<int>(1));
  CHECK(back.curve_error_mean == std::optional<double>(0.001));
  CHECK_FALSE(back.curve_error_max.has_value());
  CHECK(back.arc_gap_cv == std::optional<double>(0.0));

  core::Metrics none;
  const core::Metrics none_back = dds::from_msg(dds::to_msg(none, 1, 0.0, 0, false));
  CHECK_FALSE(none_back.clusters.has_value());
  CHECK_FALSE(none_back.curve_error_mean.has_value());
  CHECK_FALSE(none_back.curve_error_max.has_value());
  CHECK_FALSE(none_back.arc_gap_cv.has_value());
  core::Metrics all;
  all.curve_error_max = 2.5;
  all.arc_gap_cv = 0.125;
  const core::Metrics all_back = dds::from_msg(dds::to_msg(all, 1, 0.0, 0, false));
  CHECK(all_back.curve_error_max == std::optional<double>(2.5));
  CHECK(all_back.arc_gap_cv == std::optional<double>(0.125));
}

// ---------------------------------------------------------------------------------------------------
// Transport profiles

TEST_CASE("loopback profile has no builtin transports and only unicast UDPv4 on 127.0.0.1", "[dds][qos]") {
  dds::TransportConfig cfg;  // defaults: loopback
  REQUIRE(cfg.profile == "loopback");
  cfg.max_participants = 40;
  cfg.lease_s = 2.0;
  cfg.announce_s = 0.5;
  const fdds::DomainParticipantQos q = dds::participant_qos(cfg, "agent-3");

  CHECK_FALSE(q.transport().use_builtin_transports);
  auto udp = only_udp(q);
  CHECK(udp->interfaceWhiteList == std::vector<std::string>{"127.0.0.1"});
  CHECK(udp->maxInitialPeersRange == 40u);
  CHECK(udp->sendBufferSize == 0u);
  CHECK(udp->receiveBufferSize == 0u);

  const auto& b = q.wire_protocol().builtin;
  CHECK(b.mutation_tries == 39u);  // a participant may take any of the 40 slots the peers probe
  REQUIRE(b.initialPeersList.size() == 1);
  CHECK(is_loopback_locator(*b.initialPeersList.begin()));
  CHECK(b.initialPeersList.begin()->port == 0u);
  REQUIRE(b.metatrafficUnicastLocatorList.size() == 1);
  CHECK(is_loopback_locator(*b.metatrafficUnicastLocatorList.begin()));
  CHECK(b.metatrafficMulticastLocatorList.empty());
  REQUIRE(q.wire_protocol().default_unicast_locator_list.size() == 1);
  CHECK(is_loopback_locator(*q.wire_protocol().default_unicast_locator_list.begin()));
  CHECK(q.wire_protocol().default_multicast_locator_list.empty());

  CHECK(b.discovery_config.discoveryProtocol == frtps::DiscoveryProtocol_t::SIMPLE);
  CHECK(b.discovery_config.leaseDuration == eprosima::fastrtps::Duration_t(2.0));
  CHECK(b.discovery_config.leaseDuration_announcementperiod == eprosima::fastrtps::Duration_t(0.5));
  CHECK(std::string(q.name().c_str()) == "agent-3");

  SECTION("socket buffers") {
    cfg.socket_buffer_bytes = 4 << 20;
    auto u = only_udp(dds::participant_qos(cfg, "x"));
    CHECK(u->sendBufferSize == (4u << 20));
    CHECK(u->receiveBufferSize == (4u << 20));
  }
}

TEST_CASE("multicast_data: State readers listen on one group on lo, nothing else changes", "[dds][qos]") {
  dds::TransportConfig cfg;
  cfg.domain = 7;
  const fdds::DomainParticipantQos plain = dds::participant_qos(cfg, "agent-1");
  cfg.multicast_data = true;
  const fdds::DomainParticipantQos q = dds::participant_qos(cfg, "agent-1");
  // The participant is the plain loopback one: unicast discovery and default locators on 127.0.0.1.
  // (The QoS objects hold their transport descriptors by pointer: compare what they point to.)
  CHECK(q.wire_protocol() == plain.wire_protocol());
  CHECK(q.transport().use_builtin_transports == plain.transport().use_builtin_transports);
  REQUIRE(q.transport().user_transports.size() == plain.transport().user_transports.size());
  CHECK(*only_udp(q) == *only_udp(plain));
  CHECK(only_udp(q)->interfaceWhiteList == std::vector<std::string>{"127.0.0.1"});
  CHECK(q.wire_protocol().default_multicast_locator_list.empty());

  const frtps::Locator_t group = dds::data_multicast_locator(cfg);
  CHECK(group.kind == LOCATOR_KIND_UDPv4);
  CHECK(frtps::IPLocator::toIPv4string(group) == "239.255.0.1");
  CHECK(group.port == 7400u + 250u * 7u + 1u);  // the domain's user multicast port

  // Only the State reader gets the group, as its only locator; other readers keep the defaults.
  const fdds::DataReaderQos state = dds::reader_qos(dds::TopicId::State, cfg);
  REQUIRE(state.endpoint().multicast_locator_list.size() == 1);
  CHECK(*state.endpoint().multicast_locator_list.begin() == group);
  CHECK(state.endpoint().unicast_locator_list.empty());
  for (dds::TopicId id : {dds::TopicId::Command, dds::TopicId::Target, dds::TopicId::Metrics, dds::TopicId::Status}) {
    INFO(dds::topic_name(id));
    CHECK(dds::reader_qos(id, cfg).endpoint().multicast_locator_list.empty());
    CHECK(dds::reader_qos(id, cfg) == dds::reader_qos(id));
  }
  cfg.multicast_data = false;
  CHECK(dds::reader_qos(dds::TopicId::State, cfg) == dds::reader_qos(dds::TopicId::State));
  cfg.multicast_data = true;
  CHECK(dds::describe(cfg).find("multicast 239.255.0.1:9151") != std::string::npos);

  SECTION("off by default") { CHECK_FALSE(dds::TransportConfig{}.multicast_data); }
  SECTION("a discovery server on loopback may use it") {
    cfg.profile = "discovery-server";
    cfg.discovery_server = "127.0.0.1:11811";
    CHECK_NOTHROW(dds::participant_qos(cfg, "x"));
    CHECK(dds::data_multicast_locator(cfg) == group);
    cfg.discovery_server = "localhost:11811";
    CHECK_NOTHROW(dds::participant_qos(cfg, "x"));
  }
  SECTION("lan without peers may use it: the participant is the plain lan one") {
    cfg.profile = "lan";
    cfg.interfaces = {"10.0.0.2"};
    const fdds::DomainParticipantQos lan = dds::participant_qos(cfg, "agent-1");
    cfg.multicast_data = false;
    CHECK(lan.wire_protocol() == dds::participant_qos(cfg, "agent-1").wire_protocol());
    cfg.multicast_data = true;
    CHECK(dds::data_multicast_locator(cfg) == group);
    CHECK(dds::reader_qos(dds::TopicId::State, cfg).endpoint().multicast_locator_list.size() == 1);
  }
  SECTION("lan with peers, or a remote discovery server, refuse it") {
    auto refusal = [&](const dds::TransportConfig& c) {
      try {
        dds::participant_qos(c, "x");
      } catch (const std::runtime_error& e) {
        return std::string(e.what());
      }
      return std::string();
    };
    cfg.profile = "lan";
    cfg.peers = {"10.0.0.2"};
    CHECK(refusal(cfg).find("transport.multicast_data: cannot be used with transport.peers") == 0);
    CHECK_THROWS_AS(dds::data_multicast_locator(cfg), std::runtime_error);
    cfg.profile = "discovery-server";
    cfg.peers.clear();
    cfg.discovery_server = "10.0.0.5:11811";
    CHECK(refusal(cfg).find("transport.multicast_data: needs transport.profile loopback, lan without peers") == 0);
  }
}

TEST_CASE("static_edp: STATIC endpoint discovery from a description of the topic table", "[dds][qos]") {
  dds::TransportConfig cfg;
  cfg.domain = 7;
  const fdds::DomainParticipantQos plain = dds::participant_qos(cfg, "agent-1");
  CHECK(plain.wire_protocol().builtin.discovery_config.use_SIMPLE_EndpointDiscoveryProtocol);
  CHECK_FALSE(plain.wire_protocol().builtin.discovery_config.use_STATIC_EndpointDiscoveryProtocol);
  CHECK_FALSE(dds::TransportConfig{}.static_edp);  // off by default

  // One user id per topic and direction, all distinct and positive (Fast DDS refuses a description that
  // repeats one), carried by the QoS every endpoint is created with.
  std::set<int> ids;
  std::size_t fixed = 0;
  for (dds::TopicId id : dds::kAllTopics) {
    INFO(dds::topic_name(id));
    if (dds::is_vehicle_topic(id)) {
      // ROS 2's topics: announced by simple discovery (static_edp is refused with vehicle.interface ros2).
      CHECK(dds::writer_qos(id).endpoint().user_defined_id <= 0);
      CHECK(dds::reader_qos(id, cfg).endpoint().user_defined_id <= 0);
      continue;
    }
    ++fixed;
    CHECK(dds::writer_qos(id).endpoint().user_defined_id == dds::static_edp_user_id(id, true));
    CHECK(dds::reader_qos(id, cfg).endpoint().user_defined_id == dds::static_edp_user_id(id, false));
    ids.insert(dds::static_edp_user_id(id, true));
    ids.insert(dds::static_edp_user_id(id, false));
  }
  CHECK(ids.size() == 2 * fixed);
  CHECK(*ids.begin() > 0);

  cfg.static_edp = true;
  const fdds::DomainParticipantQos q = dds::participant_qos(cfg, "agent-1");
  const auto& disc = q.wire_protocol().builtin.discovery_config;
  CHECK_FALSE(disc.use_SIMPLE_EndpointDiscoveryProtocol);
  CHECK(disc.use_STATIC_EndpointDiscoveryProtocol);
  const std::string xml = dds::static_edp_description(cfg);
  CHECK(std::string(disc.static_edp_xml_config()) == "data://" + xml);
  CHECK(dds::describe(cfg).find("static endpoint discovery") != std::string::npos);
  // The State endpoints as the table says; readers have no locator of their own (the peer's defaults).
  const std::string state_writer = "<writer><userId>" + std::to_string(dds::static_edp_user_id(dds::TopicId::State, true)) +
                                   "</userId><topicName>shapeform/state</topicName><topicDataType>shapeform::msg::"
                                   "AgentState</topicDataType><topicKind>WITH_KEY</topicKind><reliabilityQos>"
                                   "BEST_EFFORT_RELIABILITY_QOS</reliabilityQos><durabilityQos>VOLATILE_DURABILITY_QOS"
                                   "</durabilityQos></writer>";
  CHECK(xml.find(state_writer) != std::string::npos);
  CHECK(xml.find("<topicName>shapeform/command</topicName><topicDataType>shapeform::msg::ShapeCommand"
                 "</topicDataType><topicKind>NO_KEY</topicKind><reliabilityQos>RELIABLE_RELIABILITY_QOS"
                 "</reliabilityQos><durabilityQos>TRANSIENT_LOCAL_DURABILITY_QOS</durabilityQos>") != std::string::npos);
  CHECK(xml.find("Locator") == std::string::npos);
  // No vehicle topic (their names are per vehicle); the ROS 2 mirror's fixed names are there.
  CHECK(xml.find("{ns}") == std::string::npos);
  CHECK(xml.find("cmd_vel") == std::string::npos);
  CHECK(xml.find("<topicName>rt/shapeform/agents</topicName>") != std::string::npos);
  for (dds::TopicId id : dds::kAllTopics) {
    if (dds::is_vehicle_topic(id)) continue;
    for (bool writer : {true, false}) {
      INFO(dds::topic_name(id) << (writer ? " writer" : " reader"));
      CHECK(xml.find("<userId>" + std::to_string(dds::static_edp_user_id(id, writer)) + "</userId><topicName>" +
                     dds::topic_name(id) + "<") != std::string::npos);
    }
  }
  // With multicast_data, peers learn the State readers' group from the description (they have no
  // endpoint discovery to learn it from).
  cfg.multicast_data = true;
  const std::string mc = dds::static_edp_description(cfg);
  // The two state topics' readers (State, StateBatch) carry the group; nothing else does.
  const std::string group = "<multicastLocator address=\"239.255.0.1\" port=\"9151\"/>";
  std::size_t groups = 0;
  for (std::size_t at = mc.find("multicastLocator"); at != std::string::npos; at = mc.find("multicastLocator", at + 1))
    ++groups;
  CHECK(groups == 2);
  for (const dds::TopicId id : {dds::TopicId::State, dds::TopicId::StateBatch}) {
    const auto reader_at = mc.find("<reader><userId>" + std::to_string(dds::static_edp_user_id(id, false)) + "<");
    REQUIRE(reader_at != std::string::npos);
    CHECK(mc.find(group + "</reader>", reader_at) == mc.find("</reader>", reader_at) - group.size());
  }
  CHECK(mc.find("unicastLocator") == std::string::npos);

  // Refused where Fast DDS would not use it, by key.
  auto refusal = [](const dds::TransportConfig& c) {
    for (const auto& p : dds::transport_problems(c)) return p.key + ": " + p.what;
    return std::string();
  };
  cfg.multicast_data = false;
  cfg.profile = "discovery-server";
  CHECK(refusal(cfg).find("transport.static_edp: cannot be used with transport.profile discovery-server") == 0);
  CHECK_THROWS_AS(dds::participant_qos(cfg, "x"), std::runtime_error);
  cfg.profile = "lan";
  CHECK(refusal(cfg).empty());
  cfg.profile = "loopback";
  cfg.security.enabled = true;
  cfg.security.keystore = "/tmp/keystore";
  CHECK(refusal(cfg).find("transport.static_edp: cannot be used with security.enabled") == 0);
}

/// The one locator of `list` as "a.b.c.d:port"; "" when the list does not hold exactly one.
std::string only_locator(const frtps::LocatorList_t& list) {
  if (list.size() != 1) return "";
  return frtps::IPLocator::toIPv4string(*list.begin()) + ":" + std::to_string(list.begin()->port);
}

TEST_CASE("lan profile: multicast discovery, or unicast peers and no multicast at all", "[dds][qos]") {
  dds::TransportConfig cfg;
  cfg.profile = "lan";
  cfg.domain = 4;
  // Locators with address 0.0.0.0 and port 0: Fast DDS fills in the slot's port and lists the address of
  // each whitelisted interface (so peers never learn an address of another interface).
  SECTION("no peers: multicast discovery on all interfaces") {
    const auto q = dds::participant_qos(cfg, "sup");
    CHECK_FALSE(q.transport().use_builtin_transports);
    CHECK(only_udp(q)->interfaceWhiteList.empty());
    const auto& b = q.wire_protocol().builtin;
    CHECK(b.initialPeersList.empty());  // Fast DDS then announces to the multicast locator
    CHECK(only_locator(b.metatrafficMulticastLocatorList) == "239.255.0.1:0");
    CHECK(only_locator(b.metatrafficUnicastLocatorList) == "0.0.0.0:0");
    CHECK(only_locator(q.wire_protocol().default_unicast_locator_list) == "0.0.0.0:0");
    CHECK(q.wire_protocol().default_multicast_locator_list.empty());
    CHECK(dds::describe(cfg).find("lan (UDPv4 on all interfaces, multicast discovery on 239.255.0.1:8400)") == 0);
  }
  SECTION("interfaces, no peers: the same on the listed interfaces") {
    cfg.interfaces = {"10.200.8.1"};
    const auto q = dds::participant_qos(cfg, "sup");
    CHECK(only_udp(q)->interfaceWhiteList == std::vector<std::string>{"10.200.8.1"});
    CHECK(only_locator(q.wire_protocol().builtin.metatrafficMulticastLocatorList) == "239.255.0.1:0");
    CHECK(dds::describe(cfg).find("lan (UDPv4 on 10.200.8.1, multicast discovery") == 0);
  }
  SECTION("interfaces and peers: unicast discovery over the participant slots, no multicast locator") {
    cfg.interfaces = {"192.168.1.10"};
    cfg.peers = {"192.168.1.10", "192.168.1.11"};
    cfg.max_participants = 30;
    const auto q = dds::participant_qos(cfg, "sup");
    auto udp = only_udp(q);
    CHECK(udp->interfaceWhiteList == std::vector<std::string>{"192.168.1.10"});
    CHECK(udp->maxInitialPeersRange == 30u);
    const auto& b = q.wire_protocol().builtin;
    CHECK(b.mutation_tries == 29u);
    const auto& peers = b.initialPeersList;
    REQUIRE(peers.size() == 2);
    auto it = peers.begin();
    CHECK(frtps::IPLocator::toIPv4string(*it) == "192.168.1.10");
    CHECK(it->port == 0u);
    ++it;
    CHECK(frtps::IPLocator::toIPv4string(*it) == "192.168.1.11");
    CHECK(it->port == 0u);
    // Both metatraffic lists empty would make Fast DDS add the default multicast group.
    CHECK(b.metatrafficMulticastLocatorList.empty());
    CHECK(only_locator(b.metatrafficUnicastLocatorList) == "0.0.0.0:0");
    CHECK(only_locator(q.wire_protocol().default_unicast_locator_list) == "0.0.0.0:0");
    CHECK(q.wire_protocol().default_multicast_locator_list.empty());
    CHECK(dds::describe(cfg).find("lan (UDPv4 on 192.168.1.10, unicast peers 192.168.1.10,192.168.1.11 ids 0..29, "
                                  "no multicast)") == 0);
  }
  SECTION("loopback addresses: the loopback interface, whitelisted and probed as 127.0.0.1") {
    // Fast DDS 2.9 whitelists only addresses assigned to an interface; lo carries 127.0.0.1 alone.
    cfg.interfaces = {"127.0.0.2"};
    cfg.peers = {"127.0.0.2", "127.0.0.3", "10.0.0.1"};
    const auto q = dds::participant_qos(cfg, "sup");
    CHECK(only_udp(q)->interfaceWhiteList == std::vector<std::string>{"127.0.0.1"});
    std::vector<std::string> peers;
    for (const auto& loc : q.wire_protocol().builtin.initialPeersList) {
      peers.push_back(frtps::IPLocator::toIPv4string(loc));
    }
    CHECK(peers == std::vector<std::string>{"127.0.0.1", "10.0.0.1"});
    CHECK(dds::describe(cfg).find("lan (UDPv4 on 127.0.0.2 (lo, as 127.0.0.1), unicast peers") == 0);
  }
}

TEST_CASE("discovery-server profile: client of server id 0", "[dds][qos]") {
  dds::TransportConfig cfg;
  cfg.profile = "discovery-server";
  cfg.discovery_server = "127.0.0.1:11811";
  auto q = dds::participant_qos(cfg, "agent-0");
  const auto& d = q.wire_protocol().builtin.discovery_config;
  CHECK(d.discoveryProtocol == frtps::DiscoveryProtocol_t::CLIENT);
  CHECK(d.discoveryServer_client_syncperiod == eprosima::fastrtps::Duration_t(0.1));
  REQUIRE(d.m_DiscoveryServers.size() == 1);
  const auto& server = d.m_DiscoveryServers.front();
  frtps::GuidPrefix_t expected;
  frtps::get_server_client_default_guidPrefix(0, expected);
  CHECK(server.guidPrefix == expected);
  REQUIRE(server.metatrafficUnicastLocatorList.size() == 1);
  CHECK(is_loopback_locator(*server.metatrafficUnicastLocatorList.begin()));
  CHECK(server.metatrafficUnicastLocatorList.begin()->port == 11811u);
  CHECK_FALSE(q.transport().use_builtin_transports);
  CHECK(only_udp(q)->interfaceWhiteList == std::vector<std::string>{"127.0.0.1"});

  cfg.discovery_server = "localhost:12000";
  q = dds::participant_qos(cfg, "agent-0");
  CHECK(q.wire_protocol().builtin.discovery_config.m_DiscoveryServers.front()
            .metatrafficUnicastLocatorList.begin()->port == 12000u);

  cfg.discovery_server = "10.0.0.5:11811";  // remote server: no loopback whitelist
  CHECK(only_udp(dds::participant_qos(cfg, "agent-0"))->interfaceWhiteList.empty());
}

TEST_CASE("bad transport configs are refused with the field named", "[dds][qos]") {
  auto problem = [](dds::TransportConfig cfg) {
    try {
      dds::participant_qos(cfg, "x");
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  dds::TransportConfig cfg;
  auto c = cfg;
  c.domain = 233;
  CHECK(problem(c) == "transport.domain: must be in 0..232, got 233");
  c = cfg;
  c.domain = -1;
  CHECK(problem(c).find("transport.domain:") == 0);
  c = cfg;
  c.profile = "wifi";
  CHECK(problem(c).find("transport.profile:") == 0);
  c = cfg;
  c.max_participants = 0;
  CHECK(problem(c).find("transport.max_participants:") == 0);
  c.max_participants = 231;  // the loader's limit too
  CHECK(problem(c).find("transport.max_participants:") == 0);
  c = cfg;
  c.lease_s = 0;
  CHECK(problem(c).find("transport.lease_s:") == 0);
  c = cfg;
  c.announce_s = c.lease_s;
  CHECK(problem(c).find("transport.announce_s:") == 0);
  c = cfg;
  c.socket_buffer_bytes = -1;
  CHECK(problem(c).find("transport.socket_buffer_bytes:") == 0);
  c = cfg;
  c.profile = "lan";
  c.peers = {"10.0.0.1", "host.example"};
  CHECK(problem(c) ==
        "transport.peers: must be a list of IPv4 addresses (\"host.example\" is not one), got [\"10.0.0.1\", "
        "\"host.example\"]");
  c = cfg;
  c.profile = "lan";
  c.interfaces = {"eth0"};
  CHECK(problem(c).find("transport.interfaces: must be a list of IPv4 addresses (\"eth0\" is not one)") == 0);
  for (const char* bad : {"127.0.0.1", "127.0.0.1:", ":11811", "127.0.0.1:0", "127.0.0.1:70000", "h:1"}) {
    c = cfg;
    c.profile = "discovery-server";
    c.discovery_server = bad;
    INFO(bad);
    CHECK(problem(c).find("transport.discovery_server:") == 0);
  }
  // create_participant refuses the same way, before touching DDS.
  c = cfg;
  c.domain = 500;
  CHECK_THROWS_AS(dds::create_participant(c, "x"), std::runtime_error);
}

TEST_CASE("the transport's one validator reports every problem by key", "[dds][qos]") {
  CHECK(dds::transport_problems(dds::TransportConfig{}).empty());
  dds::TransportConfig c;
  c.domain = 300;
  c.peers = {"10.0.0.1", "01.2.3.4"};  // leading zeros: refused (octal ambiguity)
  c.lease_s = 1;
  c.announce_s = 1;
  c.profile = "lan";
  c.multicast_data = true;
  std::vector<std::string> keys;
  for (const auto& p : dds::transport_problems(c)) keys.push_back(p.key + ": " + p.what + ", got " + p.got);
  CHECK(keys == std::vector<std::string>{
                    "transport.domain: must be in 0..232, got 300",
                    "transport.peers: must be a list of IPv4 addresses (\"01.2.3.4\" is not one), got [\"10.0.0.1\", "
                    "\"01.2.3.4\"]",
                    "transport.announce_s: must be < transport.lease_s (1), got 1",
                    "transport.multicast_data: cannot be used with transport.peers (lan with peers sends no "
                    "multicast at all; remove the peers for multicast discovery and data), got true"});
  std::string thrown;
  try {
    dds::validate(c);
  } catch (const std::runtime_error& e) {
    thrown = e.what();
  }
  CHECK(thrown == "transport.domain: must be in 0..232, got 300");  // the first problem
  std::array<std::uint8_t, 4> ip{};
  std::uint16_t port = 0;
  REQUIRE(dds::parse_host_port("localhost:11811", ip, port));
  CHECK(ip == std::array<std::uint8_t, 4>{127, 0, 0, 1});
  CHECK(port == 11811);
  for (const char* bad : {"localhost", ":1", "1.2.3.4:0", "1.2.3.4:65536", "1.2.3.4:+1", "host:1", "1.2.3.4:"}) {
    INFO(bad);
    CHECK_FALSE(dds::parse_host_port(bad, ip, port));
  }
}

TEST_CASE("parse_ipv4 is strict", "[dds][qos][util]") {
  std::array<std::uint8_t, 4> ip{};
  CHECK(util::parse_ipv4("127.0.0.1", ip));
  CHECK(ip == std::array<std::uint8_t, 4>{127, 0, 0, 1});
  CHECK(util::parse_ipv4("255.255.255.255", ip));
  for (const char* bad : {"", "1.2.3", "1.2.3.4.5", "256.1.1.1", "1.2.3.x", "01.2.3.4", " 1.2.3.4", "1..2.3"}) {
    INFO(bad);
    CHECK_FALSE(util::parse_ipv4(bad, ip));
  }
}

TEST_CASE("describe gives a one-line summary", "[dds][qos]") {
  dds::TransportConfig cfg;
  const std::string d = dds::describe(cfg);
  CHECK(d.find("loopback") == 0);
  CHECK(d.find("127.0.0.1") != std::string::npos);
  CHECK(d.find('\n') == std::string::npos);
  cfg.profile = "discovery-server";
  CHECK(dds::describe(cfg).find("127.0.0.1:11811") != std::string::npos);
  cfg.profile = "bogus";
  CHECK_NOTHROW(dds::describe(cfg));
}

// ---------------------------------------------------------------------------------------------------
// Topic table

TEST_CASE("topic table gives names and keys and QoS", "[dds][topics]") {
  CHECK(std::string(dds::topic_name(dds::TopicId::State)) == "shapeform/state");
  CHECK(std::string(dds::topic_name(dds::TopicId::StateBatch)) == "shapeform/state_batch");
  CHECK(std::string(dds::topic_name(dds::TopicId::Command)) == "shapeform/command");
  CHECK(std::string(dds::topic_name(dds::TopicId::Target)) == "shapeform/target");
  CHECK(std::string(dds::topic_name(dds::TopicId::Metrics)) == "shapeform/metrics");
  CHECK(std::string(dds::topic_name(dds::TopicId::Status)) == "shapeform/status");

  // The table's type names are the generated ones.
  CHECK(std::string(dds::type_name(dds::TopicId::State)) == msg::AgentStatePubSubType().getName());
  CHECK(std::string(dds::type_name(dds::TopicId::StateBatch)) == msg::AgentStateBatchPubSubType().getName());
  CHECK(msg::AgentStateBatchPubSubType().m_isGetKeyDefined);
  CHECK(std::string(dds::type_name(dds::TopicId::Command)) == msg::ShapeCommandPubSubType().getName());
  CHECK(std::string(dds::type_name(dds::TopicId::Target)) == msg::TrackingTargetPubSubType().getName());
  CHECK(std::string(dds::type_name(dds::TopicId::Metrics)) == msg::SwarmMetricsPubSubType().getName());
  CHECK(std::string(dds::type_name(dds::TopicId::Status)) == msg::AgentStatusPubSubType().getName());
  CHECK(msg::AgentStatePubSubType().m_isGetKeyDefined);
  CHECK(msg::AgentStatusPubSubType().m_isGetKeyDefined);
  CHECK_FALSE(msg::ShapeCommandPubSubType().m_isGetKeyDefined);

  for (dds::TopicId id : dds::kAllTopics) {
    INFO(dds::topic_name(id));
    const fdds::DataWriterQos w = dds::writer_qos(id);
    const fdds::DataReaderQos r = dds::reader_qos(id);
    CHECK(w.data_sharing().kind() == fdds::OFF);
    CHECK(r.data_sharing().kind() == fdds::OFF);
    CHECK(w.history().kind == fdds::KEEP_LAST_HISTORY_QOS);
    CHECK(w.history().depth == 1);
    CHECK(r.history().kind == fdds::KEEP_LAST_HISTORY_QOS);
    CHECK(r.history().depth == 1);
    CHECK(w.reliability().kind == r.reliability().kind);
    CHECK(w.durability().kind == r.durability().kind);
    CHECK(dds::is_keyed(id) ==
          (id == dds::TopicId::State || id == dds::TopicId::StateBatch || id == dds::TopicId::Status ||
           id == dds::TopicId::StatusBatch));
    if (dds::is_keyed(id)) {
      CHECK(r.resource_limits().max_instances == 0);
      CHECK(r.resource_limits().max_samples == 0);
      CHECK(r.resource_limits().max_samples_per_instance == 1);
      CHECK(w.resource_limits().max_instances == 0);
    }
  }
  using dds::TopicId;
  CHECK(dds::reader_qos(TopicId::State).reliability().kind == fdds::BEST_EFFORT_RELIABILITY_QOS);
  CHECK(dds::reader_qos(TopicId::Target).reliability().kind == fdds::BEST_EFFORT_RELIABILITY_QOS);
  CHECK(dds::reader_qos(TopicId::Command).reliability().kind == fdds::RELIABLE_RELIABILITY_QOS);
  CHECK(dds::reader_qos(TopicId::Command).durability().kind == fdds::TRANSIENT_LOCAL_DURABILITY_QOS);
  CHECK(dds::reader_qos(TopicId::Metrics).reliability().kind == fdds::RELIABLE_RELIABILITY_QOS);
  CHECK(dds::reader_qos(TopicId::Metrics).durability().kind == fdds::VOLATILE_DURABILITY_QOS);
  CHECK(dds::reader_qos(TopicId::Status).reliability().kind == fdds::RELIABLE_RELIABILITY_QOS);
  CHECK(dds::reader_qos(TopicId::State).durability().kind == fdds::VOLATILE_DURABILITY_QOS);
}

// ---------------------------------------------------------------------------------------------------
// In-process pub/sub over loopback UDP, two participants

TEST_CASE("loopback pub-sub delivers 12 keyed instances and a dispose", "[dds][node][pubsub]") {
  const auto cfg = loopback(test_domain(0));
  dds::Node pub(cfg, "test-pub");
  dds::Node sub(cfg, "test-sub");
  auto writer = pub.writer<msg::AgentState>(dds::TopicId::State);
  auto reader = sub.reader<msg::AgentState>(dds::TopicId::State);
  REQUIRE(wait_for([&] { return writer.matched() >= 1 && reader.matched() >= 1; }));
  REQUIRE(pub.source().known());
  REQUIRE(pub.source() != sub.source());

  constexpr int kAgents = 12;  // more than Fast DDS's default max_instances (10)
  std::set<std::int32_t> seen;
  std::vector<dds::Received<msg::AgentState>> batch;
  std::uint64_t seq = 0;
  bool write_ok = true;
  const bool all = wait_for([&] {
    ++seq;
    for (int id = 0; id < kAgents; ++id) {
      msg::AgentState s = good_state();
      s.id(id);
      s.seq(seq);
      s.x(id);
      s.stamp_ns(util::steady_ns());
      write_ok = writer.write(s) && write_ok;
    }
    reader.drain(batch);
    for (const auto& r : batch) {
      REQUIRE(r.valid_data);
      CHECK(r.instance == dds::InstanceState::Alive);
      CHECK(r.key_id == r.msg.id());
      CHECK(r.msg.x() == r.msg.id());
      CHECK(r.receive_stamp_ns >= r.msg.stamp_ns());
      CHECK(r.source == pub.source());  // the sender's participant, not the reader's
      std::string why;
      CHECK(dds::valid_state(r.msg, why));
      seen.insert(r.msg.id());
    }
    return static_cast<int>(seen.size()) == kAgents;
  });
  CHECK(write_ok);
  INFO("instances seen: " << seen.size());
  REQUIRE(all);
  CHECK(reader.overflowed() == 0u);

  // Dispose one instance; best effort, so repeat (write + dispose) until the reader reports it.
  msg::AgentState gone = good_state();
  gone.id(5);
  bool disposed = false;
  auto last_try = std::chrono::steady_clock::now() - std::chrono::seconds(1);
  REQUIRE(wait_for([&] {
    if (std::chrono::steady_clock::now() - last_try > std::chrono::milliseconds(500)) {
      last_try = std::chrono::steady_clock::now();
      writer.write(gone);
      CHECK(writer.dispose(gone));
    }
    reader.drain(batch);
    for (const auto& r : batch) {
      if (r.instance == dds::InstanceState::Disposed) {
        CHECK_FALSE(r.valid_data);
        CHECK(r.key_id == 5);
        CHECK(r.source == pub.source());
        disposed = true;
      }
    }
    return disposed;
  }));
}

TEST_CASE("StateInput hears single states and batches, and a disposed batch as each id it carried gone",
          "[dds][node][pubsub]") {
  const auto cfg = loopback(test_domain(0));
  dds::Node pub(cfg, "test-pub");
  dds::Node sub(cfg, "test-sub");
  auto single = pub.writer<msg::AgentState>(dds::TopicId::State);
  auto batch = pub.writer<msg::AgentStateBatch>(dds::TopicId::StateBatch);
  dds::StateInput input(sub);
  REQUIRE(wait_for([&] { return single.matched() >= 1 && batch.matched() >= 1; }));
  std::vector<dds::StateSample> group(3);
  for (int k = 0; k < 3; ++k) group[static_cast<std::size_t>(k)].id = 20 + k;
  dds::StateSample alone;
  alone.id = 7;
  std::set<std::int32_t> heard, heard_batched;
  std::vector<dds::StateItem> items;
  std::uint64_t seq = 0;
  REQUIRE(wait_for([&] {
    ++seq;
    alone.seq = seq;
    for (auto& g : group) g.seq = seq;
    single.write(dds::to_msg(alone));
    batch.write(dds::to_msg(group));
    input.drain(items);
    for (const auto& r : items) {
      REQUIRE(r.kind == dds::StateItem::Kind::State);
      CHECK(r.id == r.state.id);
      CHECK(r.source == pub.source());
      heard.insert(r.id);
      if (r.batched) heard_batched.insert(r.id);
    }
    return heard.size() == 4;
  }));
  CHECK(heard_batched == std::set<std::int32_t>{20, 21, 22});
  CHECK(input.batches() >= 1);
  // A refused batch is one Rejected item naming the element.
  msg::AgentStateBatch bad = dds::to_msg(group);
  bad.states()[1].x(std::nan(""));
  bool rejected = false;
  REQUIRE(wait_for([&] {
    batch.write(bad);
    input.drain(items);
    for (const auto& r : items)
      if (r.kind == dds::StateItem::Kind::Rejected) {
        CHECK(r.why == "state_batch.states[1].x: must be finite, got nan");
        rejected = true;
      }
    return rejected;
  }));
  // Disposing the batch instance: every id it last carried is gone (best effort, so repeat).
  std::set<std::int32_t> gone;
  REQUIRE(wait_for([&] {
    batch.write(dds::to_msg(group));
    msg::AgentStateBatch key;
    key.first_id(20);
    batch.dispose(key);
    input.drain(items);
    for (const auto& r : items) {
      if (r.kind != dds::StateItem::Kind::Gone) continue;
      CHECK(r.instance == dds::InstanceState::Disposed);
      CHECK(r.batched);
      gone.insert(r.id);
    }
    return gone.size() == 3;
  }));
  CHECK(gone == std::set<std::int32_t>{20, 21, 22});
}

TEST_CASE("StatusInput hears single statuses and batches, and names a refused batch's element", "[dds][node][pubsub]") {
  const auto cfg = loopback(test_domain(0));
  dds::Node pub(cfg, "test-pub");
  dds::Node sub(cfg, "test-sub");
  auto single = pub.writer<msg::AgentStatus>(dds::TopicId::Status);
  auto batch = pub.writer<msg::AgentStatusBatch>(dds::TopicId::StatusBatch);
  dds::StatusInput input(sub);
  REQUIRE(wait_for([&] { return single.matched() >= 1 && batch.matched() >= 1; }));
  std::vector<dds::StatusSample> group(3);
  for (std::size_t k = 0; k < group.size(); ++k) {
    group[k].id = 20 + static_cast<std::int32_t>(k);
    group[k].neighbours_heard = 5 + static_cast<int>(k);
  }
  dds::StatusSample alone;
  alone.id = 7;
  msg::AgentStatusBatch wire;
  dds::to_msg(group, 0, group.size(), wire);
  std::map<std::int32_t, int> heard;
  std::set<std::int32_t> heard_batched;
  std::vector<dds::StatusItem> items;
  single.write(dds::to_msg(alone));
  batch.write(wire);
  REQUIRE(wait_for([&] {
    input.drain(items);
    for (const auto& r : items) {
      REQUIRE(r.valid);
      CHECK(r.source == pub.source());
      heard[r.status.id] = r.status.neighbours_heard;
      if (r.batched) heard_batched.insert(r.status.id);
    }
    return heard.size() == 4;
  }));
  CHECK(heard == std::map<std::int32_t, int>{{7, 0}, {20, 5}, {21, 6}, {22, 7}});
  CHECK(heard_batched == std::set<std::int32_t>{20, 21, 22});
  CHECK(input.last_batches().size() <= 1);
  // A refused batch is one invalid item naming the element (reliable: written once).
  wire.statuses()[1].id(-1);
  batch.write(wire);
  bool rejected = false;
  REQUIRE(wait_for([&] {
    input.drain(items);
    for (const auto& r : items) {
      CHECK_FALSE(r.valid);
      CHECK(r.batched);
      CHECK(r.why == "status_batch.statuses[1].id: must be in 0..9999, got -1");
      rejected = true;
    }
    return rejected;
  }));
}

TEST_CASE("multicast_data pub-sub: keyed state and a reliable topic between three nodes", "[dds][node][pubsub]") {
  auto cfg = loopback(test_domain(4));
  cfg.multicast_data = true;
  dds::Node a(cfg, "test-mc-a");
  dds::Node b(cfg, "test-mc-b");
  dds::Node c(cfg, "test-mc-c");
  auto writer = a.writer<msg::AgentState>(dds::TopicId::State);
  auto reader_b = b.reader<msg::AgentState>(dds::TopicId::State);
  auto reader_c = c.reader<msg::AgentState>(dds::TopicId::State);
  auto status_writer = b.writer<msg::AgentStatus>(dds::TopicId::Status);
  auto status_reader = c.reader<msg::AgentStatus>(dds::TopicId::Status);
  REQUIRE(wait_for([&] {
    return writer.matched() >= 2 && reader_b.matched() >= 1 && reader_c.matched() >= 1 && status_reader.matched() >= 1;
  }));

  std::set<std::int32_t> seen_b, seen_c;
  bool status_seen = false;
  std::vector<dds::Received<msg::AgentState>> batch;
  std::vector<dds::Received<msg::AgentStatus>> statuses;
  std::uint64_t seq = 0;
  REQUIRE(wait_for([&] {
    ++seq;
    for (int id = 0; id < 3; ++id) {
      msg::AgentState s = good_state();
      s.id(id);
      s.seq(seq);
      s.stamp_ns(util::steady_ns());
      writer.write(s);
    }
    msg::AgentStatus st;
    st.id(9);
    status_writer.write(st);
    reader_b.drain(batch);
    for (const auto& r : batch) seen_b.insert(r.msg.id());
    reader_c.drain(batch);
    for (const auto& r : batch) seen_c.insert(r.msg.id());
    status_reader.drain(statuses);
    for (const auto& r : statuses) status_seen = status_seen || (r.valid_data && r.msg.id() == 9);
    return seen_b.size() == 3 && seen_c.size() == 3 && status_seen;
  }));

  // Readers leave one by one: the writer keeps sending to the group (it has no unicast locator to fall
  // back to, which in 2.9 would abort on an unregistered output locator), and the last reader still hears it.
  reader_b = dds::Reader<msg::AgentState>();
  REQUIRE(wait_for([&] { return writer.matched() == 1; }));
  seen_c.clear();
  REQUIRE(wait_for([&] {
    msg::AgentState s = good_state();
    s.id(4);
    s.seq(++seq);
    writer.write(s);
    reader_c.drain(batch);
    for (const auto& r : batch) seen_c.insert(r.msg.id());
    return seen_c.count(4) == 1;
  }));
}

/// Counts the participants a participant discovered (DISCOVERED_PARTICIPANT), on Fast DDS's thread.
struct DiscoveryCount final : fdds::DomainParticipantListener {
  std::atomic<int> discovered{0};
  void on_participant_discovery(fdds::DomainParticipant*, frtps::ParticipantDiscoveryInfo&& info) override {
    if (info.status == frtps::ParticipantDiscoveryInfo::DISCOVERED_PARTICIPANT) ++discovered;
  }
};

TEST_CASE("static_edp pub-sub: State and Command match without endpoint discovery; a simple-EDP peer never does",
          "[dds][node][pubsub]") {
  auto cfg = loopback(test_domain(2));
  cfg.static_edp = true;
  // Neither name is in the description (it names only "shapeform"): Fast DDS matches by user id.
  dds::Node agent(cfg, "test-sedp-agent");
  dds::Node sup(cfg, "test-sedp-supervisor");
  auto command_writer = sup.writer<msg::ShapeCommand>(dds::TopicId::Command);
  REQUIRE(command_writer.write(dds::to_msg(sample_command(), 3)));  // before the reader: transient local

  // A participant of the same domain with simple endpoint discovery, writing State and reading Command
  // (not the same topic twice: its own endpoints would match each other).
  auto simple_cfg = cfg;
  simple_cfg.static_edp = false;
  DiscoveryCount heard;
  fdds::DomainParticipant* simple = dds::create_participant(simple_cfg, "test-simple-edp", &heard);
  const auto topic = [&](dds::TopicId id, fdds::TopicDataType* type) {
    REQUIRE(fdds::TypeSupport(type).register_type(simple) == eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK);
    return simple->create_topic(dds::topic_name(id), dds::type_name(id), fdds::TopicQos());
  };
  fdds::DataWriter* simple_writer = simple->create_publisher(fdds::PublisherQos())->create_datawriter(
      topic(dds::TopicId::State, new msg::AgentStatePubSubType()), dds::writer_qos(dds::TopicId::State));
  fdds::DataReader* simple_reader = simple->create_subscriber(fdds::SubscriberQos())->create_datareader(
      topic(dds::TopicId::Command, new msg::ShapeCommandPubSubType()), dds::reader_qos(dds::TopicId::Command));
  REQUIRE(simple_writer != nullptr);
  REQUIRE(simple_reader != nullptr);

  auto state_writer = agent.writer<msg::AgentState>(dds::TopicId::State);
  auto state_reader = sup.reader<msg::AgentState>(dds::TopicId::State);
  auto command_reader = agent.reader<msg::ShapeCommand>(dds::TopicId::Command);
  std::vector<dds::Received<msg::AgentState>> states;
  std::vector<dds::Received<msg::ShapeCommand>> commands;
  msg::ShapeCommand command;
  bool state_seen = false, command_seen = false;
  std::uint64_t seq = 0;
  REQUIRE(wait_for([&] {
    msg::AgentState s = good_state();
    s.id(7);
    s.seq(++seq);
    s.stamp_ns(util::steady_ns());
    state_writer.write(s);
    simple_writer->write(&s);
    state_reader.drain(states);
    for (const auto& r : states) {
      CHECK(r.source == agent.source());  // never the simple-EDP participant's writer
      state_seen = state_seen || (r.valid_data && r.msg.id() == 7);
    }
    command_reader.drain(commands);
    for (const auto& r : commands) {
      if (r.valid_data && r.msg.epoch() == 3u) command = r.msg;
    }
    command_seen = command.epoch() == 3u;
    return state_seen && command_seen && heard.discovered >= 2;
  }));
  core::CompiledCommand out;
  std::string error;
  REQUIRE(dds::from_msg(command, out, error));
  require_same(sample_command(), out);
  // The simple-EDP participant discovered both (participant discovery is the same), but its endpoints and
  // theirs never match: a swarm must set transport.static_edp alike in every process.
  CHECK(state_writer.matched() == 1);
  CHECK(state_reader.matched() == 1);
  fdds::PublicationMatchedStatus pub_status;
  fdds::SubscriptionMatchedStatus sub_status;
  simple_writer->get_publication_matched_status(pub_status);
  simple_reader->get_subscription_matched_status(sub_status);
  CHECK(pub_status.total_count == 0);
  CHECK(sub_status.total_count == 0);
  dds::delete_participant(simple);
}

TEST_CASE("command is reliable and transient local so a late reader gets the newest", "[dds][node][pubsub]") {
  const auto cfg = loopback(test_domain(1));
  dds::Node sup(cfg, "test-supervisor");
  auto writer = sup.writer<msg::ShapeCommand>(dds::TopicId::Command);
  const core::Command cmd = sample_command();
  REQUIRE(writer.write(dds::to_msg(core::Command{}, 1)));
  REQUIRE(writer.write(dds::to_msg(cmd, 2)));  // KEEP_LAST 1: only this one is kept for late joiners

  dds::Node agent(cfg, "test-agent");
  auto reader = agent.reader<msg::ShapeCommand>(dds::TopicId::Command);
  std::vector<dds::Received<msg::ShapeCommand>> got;
  std::vector<dds::Received<msg::ShapeCommand>> batch;
  REQUIRE(wait_for([&] {
    reader.drain(batch);
    got.insert(got.end(), batch.begin(), batch.end());
    return !got.empty();
  }));
  REQUIRE(got.size() == 1);
  CHECK(got.front().valid_data);
  CHECK(got.front().key_id == -1);
  CHECK(got.front().msg.epoch() == 2u);
  core::CompiledCommand out;
  std::string error;
  REQUIRE(dds::from_msg(got.front().msg, out, error));
  require_same(cmd, out);
}

TEST_CASE("a large polygon command crosses the wire; a bad shape or step is refused on receipt", "[dds][node][pubsub]") {
  const auto cfg = loopback(test_domain(3));
  dds::Node sup(cfg, "test-supervisor");
  dds::Node agent(cfg, "test-agent");
  auto writer = sup.writer<msg::ShapeCommand>(dds::TopicId::Command);
  auto reader = agent.reader<msg::ShapeCommand>(dds::TopicId::Command);
  REQUIRE(wait_for([&] { return writer.matched() >= 1 && reader.matched() >= 1; }));

  core::Command big = sample_command();
  big.shape.kind = core::ShapeKind::Polygon;
  big.shape.closed = true;
  big.shape.vertices.clear();
  constexpr int kVertices = 5000;  // 80 KB: more than one UDP datagram, so it is fragmented
  for (int k = 0; k < kVertices; ++k) {
    const double th = 2.0 * 3.14159265358979323846 * k / kVertices;
    big.shape.vertices.emplace_back(5.0 * std::cos(th), 2.0 * std::sin(th));
  }
  msg::ShapeCommand bad = dds::to_msg(sample_command(), 2);
  bad.shape_kind("polar");
  bad.r_expr("4+foo");

  // What an agent does: apply what from_msg accepts, count what it refuses.
  core::CompiledCommand in_force;
  std::uint64_t epoch = 0;
  int refused = 0;
  std::string last_error;
  std::vector<dds::Received<msg::ShapeCommand>> batch;
  const auto receive = [&] {
    reader.drain(batch);
    for (const auto& r : batch) {
      core::CompiledCommand c;
      std::string error;
      if (dds::from_msg(r.msg, c, error)) {
        in_force = c;
        epoch = r.msg.epoch();
      } else {
        ++refused;
        last_error = error;
      }
    }
  };
  // KEEP_LAST 1: the second write could replace the first before delivery, so one at a time.
  REQUIRE(writer.write(dds::to_msg(big, 1)));
  REQUIRE(wait_for([&] { receive(); return epoch == 1; }, 20.0));
  REQUIRE(writer.write(bad));
  REQUIRE(wait_for([&] { receive(); return refused == 1; }, 20.0));
  CHECK(epoch == 1);
  CHECK(last_error == "command: polar: r(phi) = '4+foo': Unexpected token \"foo\" found at position 2.");
  require_same(big, in_force);  // the refused command changed nothing

  // A step the config and the console refuse is refused on the topic too (the command table's bound).
  msg::ShapeCommand too_long = dds::to_msg(sample_command(), 3);
  too_long.dt(50);
  too_long.k_tangent(2);
  REQUIRE(writer.write(too_long));
  REQUIRE(wait_for([&] { receive(); return refused == 2; }, 20.0));
  CHECK(epoch == 1);
  CHECK(last_error == "command.dt: must be in (0, 10], got 50; command.k_tangent: must be in (0, 1], got 2");
  require_same(big, in_force);
  REQUIRE(compiled_from_shape(in_force));
  CHECK(in_force.curve().closed());
}

TEST_CASE("node refuses a topic of another type and handles survive their node", "[dds][node]") {
  const auto cfg = loopback(test_domain(2));
  auto node = std::make_unique<dds::Node>(cfg, "test-node");
  CHECK(node->participant() != nullptr);
  CHECK(node->name() == "test-node");
  CHECK_THROWS_AS(node->writer<msg::AgentState>(dds::TopicId::Command), std::logic_error);
  CHECK_THROWS_AS(node->reader<msg::AgentStatus>(dds::TopicId::State), std::logic_error);

  // Several endpoints on one topic share the topic; an early handle destruction deletes its endpoint.
  auto w1 = node->writer<msg::AgentStatus>(dds::TopicId::Status);
  {
    auto w2 = node->writer<msg::AgentStatus>(dds::TopicId::Status);
    CHECK(w2.valid());
  }
  auto r = node->reader<msg::AgentStatus>(dds::TopicId::Status);
  auto moved = std::move(r);
  CHECK(moved.valid());
  CHECK_FALSE(r.valid());

  node.reset();  // deletes every entity; handles now do nothing
  CHECK_FALSE(w1.valid());
  CHECK_FALSE(w1.write(msg::AgentStatus{}));
  CHECK(w1.matched() == -1);
  std::vector<dds::Received<msg::AgentStatus>> batch;
  CHECK(moved.drain(batch) == 0u);
  CHECK(moved.matched() == -1);
}

TEST_CASE("a rebuilt node has a new participant, keeps its identity, and its handles carry on", "[dds][node]") {
  const auto cfg = loopback(test_domain(2));
  dds::Node a(cfg, "test-rebuilt"), b(cfg, "test-peer");
  // Both publish and read the state topic: a is rebuilt, b is its peer.
  using State = msg::AgentState;
  constexpr auto kState = dds::TopicId::State;
  auto a_writer = a.writer<State>(kState), b_writer = b.writer<State>(kState);
  auto a_reader = a.reader<State>(kState), b_reader = b.reader<State>(kState);
  std::vector<dds::Received<msg::AgentState>> batch;
  bool a_saw_b_leave = false;
  // Each publishes its agent until each has heard the other's from the other's current participant.
  const auto exchange = [&] {
    bool a_heard = false, b_heard = false;
    return wait_for([&] {
      for (auto [w, id] : {std::pair{&a_writer, 1}, std::pair{&b_writer, 2}}) {
        msg::AgentState s = good_state();
        s.id(id);
        s.stamp_ns(util::steady_ns());
        w->write(s);
      }
      a_reader.drain(batch);
      for (const auto& r : batch) {
        if (!r.valid_data && r.key_id == 2) a_saw_b_leave = true;
        if (r.valid_data && r.msg.id() == 2 && r.source == b.source()) a_heard = true;
      }
      b_reader.drain(batch);
      for (const auto& r : batch)
        if (r.valid_data && r.msg.id() == 1 && r.source == a.source()) b_heard = true;
      return a_heard && b_heard;
    });
  };
  REQUIRE(exchange());
  const dds::SourceId before = a.source();
  const auto guid_before = a.participant()->guid();
  a.rebuild();
  CHECK(a.participant()->guid() != guid_before);  // a new GUID: peers discover it afresh
  CHECK(a.source() == before);                    // the same process: its samples keep its identity
  CHECK(a_writer.valid());
  CHECK(a_reader.valid());
  REQUIRE(exchange());  // b attributes the new participant's samples to a.source()
  // The old reader left with its listener detached: the peer's agent was never handed out as gone.
  CHECK_FALSE(a_saw_b_leave);
}

TEST_CASE("participants made after many in one process still take slots the peers probe", "[dds][node]") {
  // Fast DDS numbers a process's participants for good (a rebuilt one takes the next number); its ports
  // used to follow that number, so after max_participants participants a process bound slots no
  // initial announcement probes, and two such participants never met.
  auto cfg = loopback(test_domain(1));
  cfg.max_participants = 4;
  for (int k = 0; k < cfg.max_participants + 1; ++k) dds::Node(cfg, "test-spent-" + std::to_string(k));
  dds::Node a(cfg, "test-late-a"), b(cfg, "test-late-b");
  auto a_writer = a.writer<msg::AgentState>(dds::TopicId::State);
  auto b_reader = b.reader<msg::AgentState>(dds::TopicId::State);
  std::vector<dds::Received<msg::AgentState>> batch;
  CHECK(wait_for([&] {
    msg::AgentState s = good_state();
    s.id(1);
    a_writer.write(s);
    b_reader.drain(batch);
    return std::any_of(batch.begin(), batch.end(), [](const auto& r) { return r.valid_data && r.msg.id() == 1; });
  }));
}

TEST_CASE("participants are made while other sockets open and close (their ports read from their own sockets)",
          "[dds][node]") {
  // The kernel lists /proc/net/udp a page at a time: a reading taken while sockets open and close can
  // miss sockets bound all along, and the factory, reading the new participant's ports there, refused
  // it as one that found no free slot (integration.echo_sigterm_busy on a loaded host).
  // A busy host's table: 300 sockets bound throughout, 2 x 50 opened and closed over and over, and a
  // third thread that opens and closes the ports of the domain's first two participant slots: a port
  // this process held when the factory looked and let go before the participant bound it is the
  // participant's all the same (the factory once refused such a participant as one with no free port).
  auto cfg = loopback(test_domain(2));
  const auto open_bound = [](std::vector<int>& fds, int n, std::uint32_t port) {
    for (int k = 0; k < n; ++k) {
      const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
      sockaddr_in a{};
      a.sin_family = AF_INET;
      a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
      a.sin_port = htons(static_cast<std::uint16_t>(port == 0 ? 0 : port + static_cast<std::uint32_t>(k)));
      if (fd >= 0 && ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0) fds.push_back(fd);
      else if (fd >= 0) ::close(fd);
    }
  };
  std::vector<int> held;
  open_bound(held, 300, 0);
  std::atomic<bool> stop{false};
  std::vector<std::thread> churn;
  for (int t = 0; t < 3; ++t)
    churn.emplace_back([&stop, &open_bound, t, port0 = dds::metatraffic_unicast_port0(cfg.domain)] {
      std::vector<int> fds;
      while (!stop.load()) {
        if (t < 2) open_bound(fds, 50, 0);
        else open_bound(fds, 4, port0);  // slots 0 and 1: their metatraffic and user ports
        for (const int fd : fds) ::close(fd);
        fds.clear();
      }
    });
  int made = 0;
  std::string error;
  for (int k = 0; k < 100 && error.empty(); ++k) {
    try {
      dds::Node node(cfg, "test-churn-" + std::to_string(k));
      ++made;
    } catch (const std::exception& e) {
      error = e.what();
    }
  }
  stop = true;
  for (auto& t : churn) t.join();
  for (const int fd : held) ::close(fd);
  CAPTURE(error);
  CHECK(made == 100);
}

TEST_CASE("the stall watch reports a loop late by more than the threshold", "[dds]") {
  CHECK(dds::stall_threshold_s(dds::TransportConfig{}) == Approx(1.5));  // lease 2 s - announce 0.5 s
  constexpr std::int64_t kMs = 1'000'000;
  dds::StallWatch w;
  CHECK_FALSE(w.check(1000 * kMs, 0.02, 1.5));         // the first call only starts the watch
  CHECK_FALSE(w.check(1020 * kMs, 0.02, 1.5));         // on time
  CHECK_FALSE(w.check(2500 * kMs, 0.02, 1.5));         // 1.46 s late
  const auto stall = w.check(4100 * kMs, 0.02, 1.5);  // 1.58 s late
  REQUIRE(stall);
  CHECK(*stall == Approx(1.58));
  CHECK_FALSE(w.check(4120 * kMs, 0.02, 1.5));  // measured from the last call, not from the first
  dds::StallWatch slow;                           // a 0.5 Hz loop is slow, not stalled
  CHECK_FALSE(slow.check(0, 2.0, 1.5));
  CHECK_FALSE(slow.check(2000 * kMs, 2.0, 1.5));
  CHECK(slow.check(5600 * kMs, 2.0, 1.5));
  CHECK(dds::boot_ns() > 0);
}

TEST_CASE("the split watch: a peer dropped for silence and heard again within the window is due", "[dds]") {
  constexpr std::int64_t kMs = 1'000'000;
  dds::TransportConfig cfg;  // lease 2 s, announce 0.5 s
  CHECK(dds::SplitWatch::window_for(cfg) == Approx(2.5));
  dds::SplitWatch w(dds::SplitWatch::window_for(cfg), 0.5);
  dds::SourceId a, b, c;
  a.prefix[0] = 1;
  b.prefix[0] = 2;
  c.prefix[0] = 3;
  CHECK_FALSE(w.discovered(a, 0));  // first discovery: nothing to do (no drop before it)
  CHECK_FALSE(w.due(10'000 * kMs));
  // a partition of about a lease: dropped at 2.0 s, heard again at 2.6 s: due after the grace
  w.dropped(a, 2000 * kMs);
  const auto back = w.discovered(a, 2600 * kMs);  // the time since its drop, for the log
  REQUIRE(back);
  CHECK(*back == Approx(0.6));
  CHECK_FALSE(w.due(3000 * kMs));  // within the grace: the peer may rebuild itself (it stalled)
  const auto due = w.due(3100 * kMs);
  REQUIRE(due);
  CHECK(due->peer == a);
  CHECK(due->unheard_s == Approx(0.6));
  w.clear();  // rebuilt: no history
  CHECK_FALSE(w.due(4000 * kMs));
  // a long partition: dropped at 10 s, heard again at 20 s: it dropped this one too, nothing due
  w.dropped(b, 10'000 * kMs);
  CHECK(w.discovered(b, 20'000 * kMs).value_or(0.0) == Approx(10.0));
  CHECK_FALSE(w.due(30'000 * kMs));
  // a late return is still reported after another peer's drop in between (for the log), and not due
  w.dropped(b, 31'000 * kMs);
  w.dropped(c, 36'000 * kMs);
  CHECK(w.discovered(b, 39'000 * kMs).value_or(0.0) == Approx(8.0));
  w.removed(c);
  CHECK_FALSE(w.due(39'000 * kMs + 10 * kMs * 1000));
  // a peer that stalled: heard again, then removed (its own rebuild says goodbye) within the grace
  w.dropped(c, 40'000 * kMs);
  w.discovered(c, 41'000 * kMs);
  w.removed(c);
  CHECK_FALSE(w.due(45'000 * kMs));
  // a peer that dropped this one too: its endpoints are announced again within the grace
  w.dropped(b, 46'000 * kMs);
  w.discovered(b, 46'500 * kMs);
  w.endpoint(b);
  CHECK_FALSE(w.due(48'000 * kMs));
  // a peer that left cleanly and another participant: no drop, nothing due
  w.discovered(a, 50'000 * kMs);
  w.removed(a);
  CHECK_FALSE(w.due(60'000 * kMs));
}

TEST_CASE("the split watch, secured: a returned peer that authenticates again is no split", "[dds]") {
  constexpr std::int64_t kMs = 1'000'000;
  constexpr auto kBound = static_cast<std::int64_t>(dds::SplitWatch::kAuthBoundS * 1e9);
  dds::TransportConfig cfg;  // lease 2 s, announce 0.5 s: window 2.5 s
  dds::SplitWatch w(dds::SplitWatch::window_for(cfg), 0.5, true);
  dds::SourceId a, b, c, d;
  a.prefix[0] = 1;
  b.prefix[0] = 2;
  c.prefix[0] = 3;
  d.prefix[0] = 4;
  // both sides dropped each other: the peer authenticates again 1.4 s after its return (longer than
  // the plain grace); its endpoints may come much later still
  w.dropped(a, 2000 * kMs);
  w.discovered(a, 2600 * kMs);
  CHECK_FALSE(w.due(3200 * kMs));  // past the plain grace: still authenticating
  w.authenticated(a);
  CHECK_FALSE(w.due(2600 * kMs + 2 * kBound));
  // an endpoint announced (it comes only after the handshake) tells the same
  w.dropped(b, 10'000 * kMs);
  w.discovered(b, 10'500 * kMs);
  w.endpoint(b);
  CHECK_FALSE(w.due(10'500 * kMs + 2 * kBound));
  // half-matched: the peer never authenticates again (it kept this process authenticated and discards
  // the new handshake): due kAuthBoundS after its return, its silence as before
  w.dropped(c, 30'000 * kMs);
  w.discovered(c, 30'700 * kMs);
  CHECK_FALSE(w.due(30'700 * kMs + kBound - kMs));
  const auto due = w.due(30'700 * kMs + kBound);
  REQUIRE(due);
  CHECK(due->peer == c);
  CHECK(due->unheard_s == Approx(0.7));
  w.clear();
  // a first authentication (no drop before) is no return
  w.discovered(d, 40'000 * kMs);
  w.authenticated(d);
  CHECK_FALSE(w.due(50'000 * kMs));

  // Plain, an authentication changes nothing: due 0.5 s after the return
  dds::SplitWatch plain(dds::SplitWatch::window_for(cfg), 0.5);
  plain.dropped(a, 2000 * kMs);
  plain.discovered(a, 2600 * kMs);
  plain.authenticated(a);
  CHECK_FALSE(plain.due(3000 * kMs));
  CHECK(plain.due(3100 * kMs));
}

TEST_CASE("a source id prints as Fast DDS prints a GUID prefix and orders bytewise", "[dds]") {
  dds::SourceId a, b;
  CHECK_FALSE(a.known());
  a.prefix = {0x01, 0x0f, 0xab, 0, 0, 0, 0, 0, 0, 0, 0, 0xff};
  b = a;
  b.prefix[11] = 0xfe;
  CHECK(a.known());
  CHECK(dds::to_string(a) == "01.0f.ab.00.00.00.00.00.00.00.00.ff");
  CHECK(b < a);
  CHECK(b != a);
}

TEST_CASE("topic table lookup by name", "[dds][topics]") {
  for (const dds::TopicId id : dds::kAllTopics)
    if (!dds::is_vehicle_topic(id)) CHECK(dds::find_topic(dds::topic_name(id)) == id);
  CHECK_FALSE(dds::find_topic("shapeform/nope"));
  CHECK_FALSE(dds::find_topic("shapeform/State"));
  CHECK_FALSE(dds::find_topic(""));
}

TEST_CASE("discovery lists the topics of other participants with name, host, pid and QoS", "[dds][discovery]") {
  const auto cfg = loopback(test_domain(0));
  // Named after this process, so that a test of another process on the same domain cannot confuse it.
  const std::string name = "test-discovered-" + std::to_string(::getpid());
  dds::Node node(cfg, name);
  auto writer = node.writer<msg::ShapeCommand>(dds::TopicId::Command);
  auto reader = node.reader<msg::AgentState>(dds::TopicId::State);
  char host[256] = {};
  REQUIRE(::gethostname(host, sizeof host - 1) == 0);

  std::vector<dds::TopicSeen> topics;
  const auto mine = [&](const std::vector<dds::EndpointSeen>& list) {
    std::vector<dds::EndpointSeen> out;
    for (const auto& e : list)
      if (e.participant == name) out.push_back(e);
    return out;
  };
  const auto find = [&](const char* topic) -> const dds::TopicSeen* {
    for (const auto& t : topics)
      if (t.name == topic) return &t;
    return nullptr;
  };
  // Discovery takes a moment: listen again until both endpoints are seen (each call listens 1 s).
  REQUIRE(wait_for([&] {
    topics = dds::discover_topics(cfg, "test-discovery", 1.0);
    return find("shapeform/command") && find("shapeform/state") && !mine(find("shapeform/command")->writers).empty() &&
           !mine(find("shapeform/state")->readers).empty();
  }, 20.0));
  for (std::size_t i = 1; i < topics.size(); ++i) CHECK(topics[i - 1].name < topics[i].name);
  const dds::TopicSeen& cmd = *find("shapeform/command");
  CHECK(cmd.types == std::vector<std::string>{"shapeform::msg::ShapeCommand"});
  CHECK(mine(cmd.readers).empty());
  const auto w = mine(cmd.writers);
  REQUIRE(w.size() == 1);
  CHECK(w[0].host == host);
  CHECK(w[0].pid == ::getpid());
  CHECK(w[0].reliability == "reliable");
  CHECK(w[0].durability == "transient_local");
  CHECK(w[0].type == "shapeform::msg::ShapeCommand");
  CHECK_FALSE(w[0].guid.empty());
  const auto r = mine(find("shapeform/state")->readers);
  REQUIRE(r.size() == 1);
  CHECK(r[0].reliability == "best_effort");
  CHECK(r[0].durability == "volatile");
  CHECK(r[0].type == "shapeform::msg::AgentState");
  // The listening participant itself has no endpoints, and a stop flag ends the wait at once.
  std::atomic<bool> stop{true};
  const auto t0 = std::chrono::steady_clock::now();
  dds::discover_topics(cfg, "test-discovery", 30.0, &stop);
  CHECK(std::chrono::steady_clock::now() - t0 < std::chrono::seconds(10));
}


TEST_CASE("a command outside its envelope is refused on the wire, naming the value", "[dds][convert][envelope]") {
  const auto paper = [](msg::ShapeCommand& m) {
    m.law("paper");
    m.tracking(false);
  };
  CHECK(reject(paper).empty());
  CHECK(reject([&](msg::ShapeCommand& m) { paper(m), m.k1(1e300); })
            .rfind("command.k1: dynamics.k1 = 1e+300: the step gain k1 dt sigma^(-2 beta) is ", 0) == 0);
  CHECK(reject([&](msg::ShapeCommand& m) { paper(m), m.k2(1e300); }).rfind("command.k2: dynamics.k2 = 1e+300", 0) == 0);
  CHECK(reject([&](msg::ShapeCommand& m) { paper(m), m.cx(1e300); })
            .rfind("command.cx: shape.centre = (1e+300, -2): the shape's centre gets 1e+300 units from the origin", 0) == 0);
  CHECK(reject([&](msg::ShapeCommand& m) {
          paper(m);
          m.shape_kind("implicit");
          m.f_expr("sin(x*50)*sin(y*50)-0.5");
        }).find("more than 16 separate pieces") != std::string::npos);
  // The workspace itself travels with the command, within its own range.
  CHECK(reject([&](msg::ShapeCommand& m) { paper(m), m.workspace(1e300); }).rfind("command.workspace: must be in (0, 1e+05]", 0) == 0);
  CHECK(reject([&](msg::ShapeCommand& m) { paper(m), m.workspace(5); }).rfind("command.scale: shape.scale = 1.5: the shape reaches 11.2", 0) == 0);
}

}  // namespace shapeform
