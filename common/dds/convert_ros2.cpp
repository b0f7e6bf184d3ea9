#include "dds/convert_ros2.hpp"

#include <cmath>
#include <optional>


namespace shapeform::dds {
namespace {

/// Appends "field: must be finite, got v" to why when v is not finite; returns whether it was.
bool finite(double v, const char* field, std::string& why) {
  if (std::isfinite(v)) return true;
  why += (why.empty() ? "" : "; ") + std::string(field) + ": must be finite, got " + std::to_string(v);
  return false;
}

bool position_ok(double v, const char* field, std::string& why) {
  if (!finite(v, field, why)) return false;
  if (std::abs(v) <= kStateLimit) return true;
  why += (why.empty() ? "" : "; ") + std::string(field) + ": must be within +-" + std::to_string(kStateLimit) +
         " m, got " + std::to_string(v);
  return false;
}

bool frame_ok(const std::string& frame, const char* field, std::string& why) {
  if (frame.size() <= kFrameIdMax) return true;
  why += (why.empty() ? "" : "; ") + std::string(field) + ": longer than " + std::to_string(kFrameIdMax) +
         " characters (" + std::to_string(frame.size()) + ")";
  return false;
}

bool stamp_ok(const builtin_interfaces::msg::dds_::Time_& t, const char* field, std::string& why) {
  if (t.nanosec() < 1'000'000'000u) return true;
  why += (why.empty() ? "" : "; ") + std::string(field) + ".nanosec: must be below 1e9, got " +
         std::to_string(t.nanosec());
  return false;
}

geometry_msgs::msg::dds_::Twist_ twist_msg(double vx, double vy, double wz) {
  geometry_msgs::msg::dds_::Twist_ t;  // generated types start at 0
  t.linear().x(vx);
  t.linear().y(vy);
  t.angular().z(wz);
  return t;
}

geometry_msgs::msg::dds_::Pose_ pose_msg(const PoseSample& s) {
  geometry_msgs::msg::dds_::Pose_ p;
  p.position().x(s.x.x());
  p.position().y(s.x.y());
  p.orientation().z(std::sin(0.5 * s.yaw));
  p.orientation().w(std::cos(0.5 * s.yaw));
  return p;
}

/// The parts of a pose message both types share, checked; `prefix` names the message ("odom").
bool read_pose(const geometry_msgs::msg::dds_::Pose_& p, const std_msgs::msg::dds_::Header_& h,
               const std::string& prefix, PoseSample& out, std::string& why) {
  const std::string pos = prefix + ".pose.position.", ori = prefix + ".pose.orientation";
  bool ok = position_ok(p.position().x(), (pos + "x").c_str(), why);
  ok = position_ok(p.position().y(), (pos + "y").c_str(), why) && ok;
  const auto& q = p.orientation();
  const std::optional<double> yaw = yaw_of(q.x(), q.y(), q.z(), q.w());
  if (!yaw) {
    why += (why.empty() ? "" : "; ") + ori + ": not a rotation (x " + std::to_string(q.x()) + ", y " +
           std::to_string(q.y()) + ", z " + std::to_string(q.z()) + ", w " + std::to_string(q.w()) + ")";
    ok = false;
  }
  ok = stamp_ok(h.stamp(), (prefix + ".header.stamp").c_str(), why) && ok;
  ok = frame_ok(h.frame_id(), (prefix + ".header.frame_id").c_str(), why) && ok;
  if (!ok) return false;
  out.x = {p.position().x(), p.position().y()};
  out.yaw = *yaw;
  out.frame_id = h.frame_id();
  out.stamp_ns = stamp_ns(h.stamp().sec(), h.stamp().nanosec());
  return true;
}

bool read_twist(const geometry_msgs::msg::dds_::Twist_& t, const std::string& prefix, double& vx, double& vy,
                double& wz, std::string& why) {
  bool ok = finite(t.linear().x(), (prefix + ".linear.x").c_str(), why);
  ok = finite(t.linear().y(), (prefix + ".linear.y").c_str(), why) && ok;
  ok = finite(t.angular().z(), (prefix + ".angular.z").c_str(), why) && ok;
  if (!ok) return false;
  vx = t.linear().x();
  vy = t.linear().y();
  wz = t.angular().z();
  return true;
}

}  // namespace

builtin_interfaces::msg::dds_::Time_ stamp_msg(std::int64_t ns) {
  builtin_interfaces::msg::dds_::Time_ t;
  std::int64_t sec = ns / 1'000'000'000, rem = ns % 1'000'000'000;
  if (rem < 0) {
    rem += 1'000'000'000;
    --sec;
  }
  t.sec(static_cast<std::int32_t>(sec));
  t.nanosec(static_cast<std::uint32_t>(rem));
  return t;
}

std_msgs::msg::dds_::Header_ header_msg(std::int64_t ns, const std::string& frame) {
  std_msgs::msg::dds_::Header_ h;
  h.stamp(stamp_msg(ns));
  h.frame_id(frame);
  return h;
}


std::int64_t stamp_ns(std::int32_t sec, std::uint32_t nanosec) {
  return static_cast<std::int64_t>(sec) * 1'000'000'000 + static_cast<std::int64_t>(nanosec);
}

std::optional<double> yaw_of(double x, double y, double z, double w) {
  const double n = std::sqrt(x * x + y * y + z * z + w * w);
  if (!std::isfinite(n) || n < 1e-6) return std::nullopt;
  x /= n;
  y /= n;
  z /= n;
  w /= n;
  return std::atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z));
}

void to_msg(const VelocitySample& s, ros2::Twist& out) { out = twist_msg(s.vx, s.vy, s.wz); }

void to_msg(const VelocitySample& s, ros2::TwistStamped& out) {
  out.header(header_msg(s.stamp_ns, s.frame_id));
  out.twist(twist_msg(s.vx, s.vy, s.wz));
}

bool from_msg(const ros2::Twist& m, VelocitySample& out, std::string& why) {
  VelocitySample s;
  if (!read_twist(m, "cmd_vel", s.vx, s.vy, s.wz, why)) return false;
  out = s;
  return true;
}

bool from_msg(const ros2::TwistStamped& m, VelocitySample& out, std::string& why) {
  VelocitySample s;
  bool ok = read_twist(m.twist(), "cmd_vel.twist", s.vx, s.vy, s.wz, why);
  ok = stamp_ok(m.header().stamp(), "cmd_vel.header.stamp", why) && ok;
  ok = frame_ok(m.header().frame_id(), "cmd_vel.header.frame_id", why) && ok;
  if (!ok) return false;
  s.stamp_ns = stamp_ns(m.header().stamp().sec(), m.header().stamp().nanosec());
  s.frame_id = m.header().frame_id();
  out = s;
  return true;
}

void to_msg(const PoseSample& s, ros2::Odometry& out) {
  out.header(header_msg(s.stamp_ns, s.frame_id));
  out.child_frame_id(s.child_frame_id);
  out.pose().pose(pose_msg(s));
  out.twist().twist(s.has_twist ? twist_msg(s.vx, s.vy, s.wz) : twist_msg(0, 0, 0));
}

void to_msg(const PoseSample& s, ros2::PoseStamped& out) {
  out.header(header_msg(s.stamp_ns, s.frame_id));
  out.pose(pose_msg(s));
}

bool from_msg(const ros2::Odometry& m, PoseSample& out, std::string& why) {
  PoseSample s;
  bool ok = read_pose(m.pose().pose(), m.header(), "odom", s, why);
  ok = read_twist(m.twist().twist(), "odom.twist.twist", s.vx, s.vy, s.wz, why) && ok;
  ok = frame_ok(m.child_frame_id(), "odom.child_frame_id", why) && ok;
  if (!ok) return false;
  s.has_twist = true;
  s.child_frame_id = m.child_frame_id();
  out = s;
  return true;
}

bool from_msg(const ros2::PoseStamped& m, PoseSample& out, std::string& why) {
  PoseSample s;
  if (!read_pose(m.pose(), m.header(), "pose", s, why)) return false;
  out = s;
  return true;
}

}  // namespace shapeform::dds
