#pragma once
/// A vehicle's ROS 2 topics, the one place they are read and written: the agent's side
/// (VehicleController: the robot's pose in, velocity commands out) and the robot driver's
/// (VehicleDriver: commands in, poses out, as shapeform_vehicle plays a driver). Names are ROS 2's
/// (rt/<namespace>/<topic>), types from idl/ros2, QoS from the topic table (commands reliable and
/// volatile, as rclcpp's default, which a best-effort reader also matches; poses read best effort, which
/// matches reliable and best-effort drivers alike). Every sample goes through dds/convert_ros2.
#include <cstdint>
#include <string>
#include <vector>

#include "dds/convert_ros2.hpp"
#include "dds/node.hpp"

namespace shapeform::dds {

/// Which topics and types one vehicle uses (config: vehicle.namespace, cmd_topic, cmd_type, pose_topic,
/// pose_type).
struct VehicleTopics {
  std::string ns = "robot_0";          ///< the vehicle's namespace, resolved ({id} replaced)
  std::string cmd_topic = "cmd_vel";   ///< relative to the namespace; "/x" is absolute
  bool cmd_stamped = false;            ///< geometry_msgs/TwistStamped instead of Twist
  std::string pose_topic = "odom";
  bool pose_stamped = false;           ///< geometry_msgs/PoseStamped instead of nav_msgs/Odometry
  std::string cmd_name() const { return vehicle_topic_name(ns, cmd_topic); }
  std::string pose_name() const { return vehicle_topic_name(ns, pose_topic); }
};

/// One received sample of a vehicle's topic, converted (valid) or refused (`why` names the field).
template <class Sample>
struct VehicleItem {
  bool valid = false;
  Sample sample;
  std::int64_t receive_stamp_ns = 0;
  std::string why;
};
using PoseItem = VehicleItem<PoseSample>;
using CommandItem = VehicleItem<VelocitySample>;

/// The agent's side of one vehicle: reads its pose, writes its commands.
class VehicleController {
 public:
  VehicleController() = default;
  VehicleController(Node& node, const VehicleTopics& t);
  /// Every pose received since the last call (out cleared first), oldest first.
  void drain(std::vector<PoseItem>& out);
  /// Publishes the command (TwistStamped: with its stamp and frame). False when DDS refuses it.
  bool command(const VelocitySample& v);
  /// Waits up to `seconds` until the robot's driver acknowledged every command written (false on timeout).
  bool wait_acknowledged(double seconds);
  /// Writers of the pose topic matched now (the robot's driver, when it is there).
  int pose_writers() const;
  const VehicleTopics& topics() const { return topics_; }

 private:
  VehicleTopics topics_;
  Reader<ros2::Odometry> odom_;
  Reader<ros2::PoseStamped> pose_;
  Writer<ros2::Twist> twist_;
  Writer<ros2::TwistStamped> twist_stamped_;
  std::vector<Received<ros2::Odometry>> odom_buf_;
  std::vector<Received<ros2::PoseStamped>> pose_buf_;
};

/// The driver's side of one vehicle: reads its commands, writes its pose.
class VehicleDriver {
 public:
  VehicleDriver() = default;
  VehicleDriver(Node& node, const VehicleTopics& t);
  /// Every command received since the last call (out cleared first), oldest first.
  void drain(std::vector<CommandItem>& out);
  /// Publishes the pose (Odometry or PoseStamped). False when DDS refuses it.
  bool publish(const PoseSample& p);
  /// Writers of the command topic matched now (the agent, when it is there).
  int command_writers() const;
  const VehicleTopics& topics() const { return topics_; }

 private:
  VehicleTopics topics_;
  Reader<ros2::Twist> twist_;
  Reader<ros2::TwistStamped> twist_stamped_;
  Writer<ros2::Odometry> odom_;
  Writer<ros2::PoseStamped> pose_;
  std::vector<Received<ros2::Twist>> twist_buf_;
  std::vector<Received<ros2::TwistStamped>> twist_stamped_buf_;
};

}  // namespace shapeform::dds
