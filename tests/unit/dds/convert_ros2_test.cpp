// Unit tests of common/dds/convert_ros2: the vehicle interface's ROS 2 messages (Twist, TwistStamped,
// Odometry, PoseStamped) <-> VelocitySample / PoseSample, and what a received message is refused for.
#include "dds/convert_ros2.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <string>

namespace shapeform {
namespace {

using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kPi = 3.14159265358979323846;

/// The quaternion of a rotation by yaw about z.
struct Quat {
  double x, y, z, w;
};
Quat about_z(double yaw) { return {0.0, 0.0, std::sin(0.5 * yaw), std::cos(0.5 * yaw)}; }

dds::PoseSample a_pose() {
  dds::PoseSample s;
  s.x = core::Vec2(1.5, -2.25);
  s.yaw = 2.0;
  s.frame_id = "map";
  s.stamp_ns = 1'234'567'890'123;
  s.has_twist = true;
  s.vx = 0.5;
  s.vy = -0.125;
  s.wz = 0.75;
  s.child_frame_id = "robot_3/base_link";
  return s;
}

/// from_msg's verdict on m: the reason ("" when accepted); a refused message leaves `out` as it was.
template <class Msg, class Out = dds::PoseSample>
std::string refusal(const Msg& m) {
  Out out;
  out.frame_id = "untouched";
  std::string why;
  const bool ok = dds::from_msg(m, out, why);
  CHECK(ok == why.empty());
  if (!ok) CHECK(out.frame_id == "untouched");
  return why;
}

std::string twist_refusal(const dds::ros2::TwistStamped& m) {
  return refusal<dds::ros2::TwistStamped, dds::VelocitySample>(m);
}

}  // namespace

TEST_CASE("yaw_of: the heading of a rotation about z, whatever the quaternion's norm or sign",
          "[dds][ros2]") {
  for (const double yaw : {0.0, 0.3, -0.3, 1.0, kPi / 2, -kPi / 2, 2.5, -2.5, 3.1, -3.1}) {
    INFO("yaw " << yaw);
    const Quat q = about_z(yaw);
    const auto got = dds::yaw_of(q.x, q.y, q.z, q.w);
    REQUIRE(got);
    CHECK(*got == Approx(yaw).margin(1e-12));
    // Not normalised (a driver's rounding, or a sloppy one): the same heading.
    for (const double scale : {3.7, 1e-3, 1e3}) {
      const auto scaled = dds::yaw_of(scale * q.x, scale * q.y, scale * q.z, scale * q.w);
      REQUIRE(scaled);
      CHECK(*scaled == Approx(yaw).margin(1e-12));
    }
    // -q is the same rotation.
    const auto negated = dds::yaw_of(-q.x, -q.y, -q.z, -q.w);
    REQUIRE(negated);
    CHECK(*negated == Approx(yaw).margin(1e-12));
  }
  // A half turn is +-pi, in range either way.
  const Quat half = about_z(kPi);
  const auto pi = dds::yaw_of(half.x, half.y, half.z, half.w);
  REQUIRE(pi);
  CHECK(std::abs(*pi) == Approx(kPi).margin(1e-12));
  // A tilt (roll about x) alone has no yaw; a tilted robot keeps its heading.
  CHECK(*dds::yaw_of(std::sin(0.2), 0.0, 0.0, std::cos(0.2)) == Approx(0.0).margin(1e-12));
  {
    // yaw 1.2 then roll 0.3 (q = q_yaw * q_roll): heading 1.2.
    const double cy = std::cos(0.6), sy = std::sin(0.6), cr = std::cos(0.15), sr = std::sin(0.15);
    CHECK(*dds::yaw_of(cy * sr, sy * sr, sy * cr, cy * cr) == Approx(1.2).margin(1e-12));
  }
  // Not a rotation: nullopt.
  CHECK_FALSE(dds::yaw_of(0, 0, 0, 0));
  CHECK_FALSE(dds::yaw_of(0, 0, 5e-7, 5e-7));  // norm 7e-7 < 1e-6
  CHECK(dds::yaw_of(0, 0, 0, 2e-6));           // a tiny but real rotation is one
  CHECK_FALSE(dds::yaw_of(kNaN, 0, 0, 1));
  CHECK_FALSE(dds::yaw_of(0, 0, 0, kNaN));
  CHECK_FALSE(dds::yaw_of(0, 0, kInf, 1));
  CHECK_FALSE(dds::yaw_of(1e200, 1e200, 1e200, 1e200));  // the norm overflows
}

TEST_CASE("stamps: ns <-> builtin_interfaces/Time, negative times included", "[dds][ros2]") {
  CHECK(dds::stamp_ns(0, 0) == 0);
  CHECK(dds::stamp_ns(3, 5) == 3'000'000'005);
  CHECK(dds::stamp_ns(-2, 500'000'000) == -1'500'000'000);
  CHECK(dds::stamp_ns(-2147483647 - 1, 0) == -2147483648LL * 1'000'000'000);
  dds::VelocitySample v;
  for (const std::int64_t ns : {std::int64_t{0}, std::int64_t{1}, std::int64_t{-1}, std::int64_t{999'999'999},
                                std::int64_t{-1'000'000'000}, std::int64_t{-1'500'000'000},
                                std::int64_t{1'700'000'000'123'456'789}}) {
    INFO("stamp " << ns);
    v.stamp_ns = ns;
    dds::ros2::TwistStamped m;
    dds::to_msg(v, m);
    CHECK(m.header().stamp().nanosec() < 1'000'000'000u);  // sec carries the sign, nanosec is never negative
    CHECK(dds::stamp_ns(m.header().stamp().sec(), m.header().stamp().nanosec()) == ns);
  }
  v.stamp_ns = -1'500'000'000;
  dds::ros2::TwistStamped m;
  dds::to_msg(v, m);
  CHECK((m.header().stamp().sec() == -2 && m.header().stamp().nanosec() == 500'000'000u));
}

TEST_CASE("Twist: the planar command both ways; a non-finite component is refused by name", "[dds][ros2]") {
  dds::VelocitySample s;
  s.vx = 0.5;
  s.vy = -0.25;
  s.wz = 1.125;
  s.stamp_ns = 77;  // Twist has no header: neither travels
  s.frame_id = "base";
  dds::ros2::Twist m;
  dds::to_msg(s, m);
  CHECK((m.linear().x() == 0.5 && m.linear().y() == -0.25 && m.angular().z() == 1.125));
  CHECK((m.linear().z() == 0.0 && m.angular().x() == 0.0 && m.angular().y() == 0.0));
  dds::VelocitySample back;
  std::string why;
  REQUIRE(dds::from_msg(m, back, why));
  CHECK(why.empty());
  CHECK((back.vx == s.vx && back.vy == s.vy && back.wz == s.wz));
  CHECK((back.stamp_ns == 0 && back.frame_id.empty()));

  // What is out of the plane is ignored, not refused.
  m.linear().z(3.0);
  m.angular().x(-1.0);
  REQUIRE(dds::from_msg(m, back, why));
  CHECK((back.vx == 0.5 && back.vy == -0.25 && back.wz == 1.125));

  const auto refused = [&](auto mutate) {
    dds::ros2::Twist w;
    dds::to_msg(s, w);
    mutate(w);
    dds::VelocitySample out;
    out.vx = 42;
    std::string error;
    CHECK_FALSE(dds::from_msg(w, out, error));
    CHECK(out.vx == 42);  // untouched
    return error;
  };
  CHECK(refused([](dds::ros2::Twist& w) { w.linear().x(kNaN); }) ==
        "cmd_vel.linear.x: must be finite, got nan");
  CHECK(refused([](dds::ros2::Twist& w) { w.linear().y(-kInf); }) ==
        "cmd_vel.linear.y: must be finite, got -inf");
  CHECK(refused([](dds::ros2::Twist& w) { w.angular().z(kInf); }) ==
        "cmd_vel.angular.z: must be finite, got inf");
  CHECK(refused([](dds::ros2::Twist& w) {
          w.linear().x(kNaN);
          w.angular().z(kNaN);
        }) == "cmd_vel.linear.x: must be finite, got nan; cmd_vel.angular.z: must be finite, got nan");
}

TEST_CASE("TwistStamped: command, stamp and frame both ways; bad stamps and frames refused by name",
          "[dds][ros2]") {
  dds::VelocitySample s;
  s.vx = -0.75;
  s.vy = 0.0;
  s.wz = -2.5;
  s.stamp_ns = -1'250'000'001;
  s.frame_id = "robot_7/base_link";
  dds::ros2::TwistStamped m;
  dds::to_msg(s, m);
  CHECK((m.twist().linear().x() == -0.75 && m.twist().angular().z() == -2.5));
  CHECK(m.header().frame_id() == "robot_7/base_link");
  dds::VelocitySample back;
  std::string why;
  REQUIRE(dds::from_msg(m, back, why));
  CHECK((back.vx == s.vx && back.vy == s.vy && back.wz == s.wz));
  CHECK((back.stamp_ns == s.stamp_ns && back.frame_id == s.frame_id));

  const auto with = [&](auto mutate) {
    dds::ros2::TwistStamped w = m;
    mutate(w);
    return twist_refusal(w);
  };
  CHECK(with([](dds::ros2::TwistStamped& w) { w.header().stamp().nanosec(999'999'999u); }).empty());
  CHECK(with([](dds::ros2::TwistStamped& w) { w.header().stamp().nanosec(1'000'000'000u); }) ==
        "cmd_vel.header.stamp.nanosec: must be below 1e9, got 1000000000");
  CHECK(with([](dds::ros2::TwistStamped& w) { w.header().stamp().nanosec(4'294'967'295u); }) ==
        "cmd_vel.header.stamp.nanosec: must be below 1e9, got 4294967295");
  CHECK(with([](dds::ros2::TwistStamped& w) {
          w.header().frame_id(std::string(dds::kFrameIdMax, 'f'));
        }).empty());
  CHECK(with([](dds::ros2::TwistStamped& w) {
          w.header().frame_id(std::string(dds::kFrameIdMax + 1, 'f'));
        }) == "cmd_vel.header.frame_id: longer than 256 characters (257)");
  CHECK(with([](dds::ros2::TwistStamped& w) { w.twist().linear().y(kNaN); }) ==
        "cmd_vel.twist.linear.y: must be finite, got nan");
  // Every bad field, each named.
  CHECK(with([](dds::ros2::TwistStamped& w) {
          w.twist().angular().z(kInf);
          w.header().stamp().nanosec(2'000'000'000u);
        }) ==
        "cmd_vel.twist.angular.z: must be finite, got inf; "
        "cmd_vel.header.stamp.nanosec: must be below 1e9, got 2000000000");
}

TEST_CASE("Odometry: the planar pose and its twist both ways", "[dds][ros2]") {
  const dds::PoseSample s = a_pose();
  dds::ros2::Odometry m;
  dds::to_msg(s, m);
  CHECK((m.header().frame_id() == "map" && m.child_frame_id() == "robot_3/base_link"));
  CHECK(dds::stamp_ns(m.header().stamp().sec(), m.header().stamp().nanosec()) == s.stamp_ns);
  const auto& p = m.pose().pose();
  CHECK((p.position().x() == 1.5 && p.position().y() == -2.25 && p.position().z() == 0.0));
  CHECK((p.orientation().x() == 0.0 && p.orientation().y() == 0.0));
  CHECK(p.orientation().z() == Approx(std::sin(1.0)));
  CHECK(p.orientation().w() == Approx(std::cos(1.0)));
  for (const double c : m.pose().covariance()) CHECK(c == 0.0);
  const auto& t = m.twist().twist();
  CHECK((t.linear().x() == 0.5 && t.linear().y() == -0.125 && t.angular().z() == 0.75));
  CHECK((t.linear().z() == 0.0 && t.angular().x() == 0.0 && t.angular().y() == 0.0));

  dds::PoseSample back;
  std::string why;
  REQUIRE(dds::from_msg(m, back, why));
  CHECK(back.x == s.x);
  CHECK(back.yaw == Approx(s.yaw).margin(1e-14));
  CHECK((back.frame_id == s.frame_id && back.stamp_ns == s.stamp_ns &&
         back.child_frame_id == s.child_frame_id));
  CHECK((back.has_twist && back.vx == s.vx && back.vy == s.vy && back.wz == s.wz));

  // Without a twist: it travels as zero (Odometry always carries one) and comes back as a twist of zero.
  dds::PoseSample still = s;
  still.has_twist = false;
  dds::to_msg(still, m);
  CHECK((m.twist().twist().linear().x() == 0.0 && m.twist().twist().linear().y() == 0.0 &&
         m.twist().twist().angular().z() == 0.0));
  REQUIRE(dds::from_msg(m, back, why));
  CHECK((back.has_twist && back.vx == 0.0 && back.vy == 0.0 && back.wz == 0.0));

  // Headings all round the circle, and a negative stamp.
  for (const double yaw : {-3.0, -1.0, 0.0, 1.5, 3.0}) {
    dds::PoseSample turned = s;
    turned.yaw = yaw;
    turned.stamp_ns = -7;
    dds::to_msg(turned, m);
    REQUIRE(dds::from_msg(m, back, why));
    CHECK(back.yaw == Approx(yaw).margin(1e-14));
    CHECK(back.stamp_ns == -7);
  }
}

TEST_CASE("Odometry: absurd, non-finite or malformed fields refused, each named, the output untouched",
          "[dds][ros2]") {
  dds::ros2::Odometry good;
  dds::to_msg(a_pose(), good);
  const auto with = [&](auto mutate) {
    dds::ros2::Odometry w = good;
    mutate(w);
    return refusal(w);
  };
  using M = dds::ros2::Odometry;
  CHECK(with([](M&) {}).empty());
  // Positions: within +-kStateLimit, finite.
  CHECK(with([](M& w) { w.pose().pose().position().x(dds::kStateLimit); }).empty());
  CHECK(with([](M& w) { w.pose().pose().position().y(-dds::kStateLimit); }).empty());
  const std::string beyond = with([](M& w) { w.pose().pose().position().x(2 * dds::kStateLimit); });
  CHECK_THAT(beyond, StartsWith("odom.pose.position.x: must be within +-"));
  CHECK_THAT(beyond, Contains("got 2000000"));
  const std::string below = with([](M& w) { w.pose().pose().position().y(-1.5e6); });
  CHECK_THAT(below, StartsWith("odom.pose.position.y: must be within +-"));
  CHECK_THAT(below, Contains("got -1500000"));
  CHECK(with([](M& w) { w.pose().pose().position().x(kNaN); }) ==
        "odom.pose.position.x: must be finite, got nan");
  CHECK(with([](M& w) { w.pose().pose().position().y(-kInf); }) ==
        "odom.pose.position.y: must be finite, got -inf");
  // z is not used: whatever it holds.
  CHECK(with([](M& w) { w.pose().pose().position().z(kNaN); }).empty());
  // Orientation: a rotation.
  const std::string zero = with([](M& w) {
    w.pose().pose().orientation().w(0.0);
    w.pose().pose().orientation().z(0.0);
  });
  CHECK_THAT(zero, StartsWith("odom.pose.orientation: not a rotation (x 0"));
  CHECK_THAT(with([](M& w) { w.pose().pose().orientation().z(kNaN); }),
             StartsWith("odom.pose.orientation: not a rotation"));
  // Stamp and frames.
  CHECK(with([](M& w) { w.header().stamp().nanosec(1'000'000'000u); }) ==
        "odom.header.stamp.nanosec: must be below 1e9, got 1000000000");
  CHECK(with([](M& w) { w.header().frame_id(std::string(300, 'm')); }) ==
        "odom.header.frame_id: longer than 256 characters (300)");
  CHECK(with([](M& w) { w.child_frame_id(std::string(257, 'c')); }) ==
        "odom.child_frame_id: longer than 256 characters (257)");
  // The twist.
  CHECK(with([](M& w) { w.twist().twist().linear().x(kNaN); }) ==
        "odom.twist.twist.linear.x: must be finite, got nan");
  CHECK(with([](M& w) { w.twist().twist().angular().z(-kInf); }) ==
        "odom.twist.twist.angular.z: must be finite, got -inf");
  // Every bad field at once, each named, in the message's order.
  const std::string all = with([](M& w) {
    w.pose().pose().position().x(kNaN);
    w.pose().pose().position().y(5e6);
    w.pose().pose().orientation().w(0.0);
    w.pose().pose().orientation().z(0.0);
    w.header().stamp().nanosec(1'000'000'001u);
    w.twist().twist().linear().y(kInf);
  });
  CHECK_THAT(
      all, StartsWith("odom.pose.position.x: must be finite, got nan; odom.pose.position.y: must be within"));
  CHECK_THAT(all, Contains("; odom.pose.orientation: not a rotation"));
  CHECK_THAT(all, Contains("; odom.header.stamp.nanosec: must be below 1e9, got 1000000001"));
  CHECK_THAT(all, Contains("; odom.twist.twist.linear.y: must be finite, got inf"));
}

TEST_CASE("PoseStamped: the planar pose both ways; refusals name the pose's fields", "[dds][ros2]") {
  dds::PoseSample s = a_pose();
  dds::ros2::PoseStamped m;
  dds::to_msg(s, m);
  CHECK(
      (m.header().frame_id() == "map" && m.pose().position().x() == 1.5 && m.pose().position().y() == -2.25));
  dds::PoseSample back;
  back.has_twist = true;  // PoseStamped has none: a fresh sample says so
  std::string why;
  REQUIRE(dds::from_msg(m, back, why));
  CHECK(back.x == s.x);
  CHECK(back.yaw == Approx(2.0).margin(1e-14));
  CHECK((back.frame_id == "map" && back.stamp_ns == s.stamp_ns));
  CHECK((!back.has_twist && back.vx == 0.0 && back.child_frame_id.empty()));

  s.stamp_ns = -2'000'000'000;
  s.x = core::Vec2(-dds::kStateLimit, dds::kStateLimit);
  dds::to_msg(s, m);
  REQUIRE(dds::from_msg(m, back, why));
  CHECK((back.stamp_ns == -2'000'000'000 && back.x == s.x));

  const auto with = [&](auto mutate) {
    dds::ros2::PoseStamped w = m;
    mutate(w);
    return refusal(w);
  };
  using M = dds::ros2::PoseStamped;
  CHECK_THAT(with([](M& w) { w.pose().position().x(-1.000001e6); }),
             StartsWith("pose.pose.position.x: must be within"));
  CHECK(with([](M& w) { w.pose().position().y(kNaN); }) == "pose.pose.position.y: must be finite, got nan");
  CHECK_THAT(with([](M& w) {
               w.pose().orientation().w(0.0);
               w.pose().orientation().z(0.0);
             }),
             StartsWith("pose.pose.orientation: not a rotation"));
  CHECK(with([](M& w) { w.header().stamp().nanosec(1'000'000'000u); }) ==
        "pose.header.stamp.nanosec: must be below 1e9, got 1000000000");
  CHECK(with([](M& w) { w.header().frame_id(std::string(dds::kFrameIdMax + 1, 'x')); }) ==
        "pose.header.frame_id: longer than 256 characters (257)");
}

}  // namespace shapeform
