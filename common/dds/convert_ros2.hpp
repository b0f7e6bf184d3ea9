#pragma once
/// Conversions between ROS 2's messages of the vehicle interface (idl/ros2: geometry_msgs/Twist,
/// TwistStamped, PoseStamped, nav_msgs/Odometry) and the plain structs of protocol/samples.hpp, one
/// to_msg / from_msg pair per message. What a robot sends is never trusted: a pose whose numbers are not
/// finite, whose position is absurd (beyond kStateLimit), whose orientation is not a rotation or whose
/// stamp or frame is malformed is refused with a reason naming the field ("odom.pose.position.x: must be
/// finite, got nan"). The frame itself (is it the swarm's?) is the caller's to judge.
#include <cstdint>
#include <optional>
#include <string>

#include "geometry_msgs/msg/PoseStamped.h"
#include "geometry_msgs/msg/Twist.h"
#include "geometry_msgs/msg/TwistStamped.h"
#include "nav_msgs/msg/Odometry.h"
#include "protocol/samples.hpp"

namespace shapeform::dds {

namespace ros2 {
using Twist = geometry_msgs::msg::dds_::Twist_;
using TwistStamped = geometry_msgs::msg::dds_::TwistStamped_;
using PoseStamped = geometry_msgs::msg::dds_::PoseStamped_;
using Odometry = nav_msgs::msg::dds_::Odometry_;
}  // namespace ros2

/// Yaw (rotation about z, rad in [-pi, pi]) of the quaternion (x, y, z, w), normalised first; nullopt
/// when it is not a rotation (a norm below 1e-6, or not finite).
std::optional<double> yaw_of(double x, double y, double z, double w);

/// The planar command as a Twist (linear x, y; angular z; the rest 0).
void to_msg(const VelocitySample& s, ros2::Twist& out);
/// The same with its header (s.stamp_ns, s.frame_id).
void to_msg(const VelocitySample& s, ros2::TwistStamped& out);
/// Twist -> VelocitySample when every component is finite (components out of the plane are ignored);
/// otherwise false, `out` untouched, `why` naming the field ("cmd_vel.linear.x: ...").
bool from_msg(const ros2::Twist& m, VelocitySample& out, std::string& why);
bool from_msg(const ros2::TwistStamped& m, VelocitySample& out, std::string& why);

/// A planar pose as Odometry (orientation about z by s.yaw; covariances 0; the twist when has_twist).
void to_msg(const PoseSample& s, ros2::Odometry& out);
void to_msg(const PoseSample& s, ros2::PoseStamped& out);
/// Odometry or PoseStamped -> PoseSample when valid (see the file's comment); otherwise false, `out`
/// untouched and `why` naming every bad field.
bool from_msg(const ros2::Odometry& m, PoseSample& out, std::string& why);
bool from_msg(const ros2::PoseStamped& m, PoseSample& out, std::string& why);

/// ns since the clock's epoch -> builtin_interfaces/Time (sec, nanosec in [0, 1e9), sec rounded down).
builtin_interfaces::msg::dds_::Time_ stamp_msg(std::int64_t ns);
/// std_msgs/Header of a stamp (ns) and a frame.
std_msgs::msg::dds_::Header_ header_msg(std::int64_t ns, const std::string& frame);

/// ns <-> builtin_interfaces/Time (sec, nanosec): ns since the clock's epoch.
std::int64_t stamp_ns(std::int32_t sec, std::uint32_t nanosec);

}  // namespace shapeform::dds
