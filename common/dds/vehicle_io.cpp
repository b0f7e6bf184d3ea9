#include "dds/vehicle_io.hpp"

namespace shapeform::dds {
namespace {

/// Mailbox bound of a vehicle's readers: a few seconds of a fast driver; nobody lets them fill.
constexpr std::size_t kVehicleMailbox = 256;

/// Converts every valid sample of `in` into `out` (appended).
template <class Msg, class Sample>
void convert(const std::vector<Received<Msg>>& in, std::vector<VehicleItem<Sample>>& out) {
  for (const auto& r : in) {
    if (!r.valid_data) continue;  // an unkeyed topic: only its writer leaving, nothing to hand out
    VehicleItem<Sample> item;
    item.receive_stamp_ns = r.receive_stamp_ns;
    item.valid = from_msg(r.msg, item.sample, item.why);
    out.push_back(std::move(item));
  }
}

}  // namespace

VehicleController::VehicleController(Node& node, const VehicleTopics& t) : topics_(t) {
  if (t.pose_stamped) pose_ = node.reader<ros2::PoseStamped>(TopicId::Pose, kVehicleMailbox, t.pose_name());
  else odom_ = node.reader<ros2::Odometry>(TopicId::Odom, kVehicleMailbox, t.pose_name());
  if (t.cmd_stamped) twist_stamped_ = node.writer<ros2::TwistStamped>(TopicId::CmdVelStamped, t.cmd_name());
  else twist_ = node.writer<ros2::Twist>(TopicId::CmdVel, t.cmd_name());
}

void VehicleController::drain(std::vector<PoseItem>& out) {
  out.clear();
  odom_.drain(odom_buf_);
  convert(odom_buf_, out);
  pose_.drain(pose_buf_);
  convert(pose_buf_, out);
}

bool VehicleController::command(const VelocitySample& v) {
  if (topics_.cmd_stamped) {
    ros2::TwistStamped m;
    to_msg(v, m);
    return twist_stamped_.write(m);
  }
  ros2::Twist m;
  to_msg(v, m);
  return twist_.write(m);
}

bool VehicleController::wait_acknowledged(double seconds) {
  return topics_.cmd_stamped ? twist_stamped_.wait_acknowledged(seconds) : twist_.wait_acknowledged(seconds);
}

int VehicleController::pose_writers() const { return topics_.pose_stamped ? pose_.matched() : odom_.matched(); }

VehicleDriver::VehicleDriver(Node& node, const VehicleTopics& t) : topics_(t) {
  if (t.cmd_stamped)
    twist_stamped_ = node.reader<ros2::TwistStamped>(TopicId::CmdVelStamped, kVehicleMailbox, t.cmd_name());
  else twist_ = node.reader<ros2::Twist>(TopicId::CmdVel, kVehicleMailbox, t.cmd_name());
  if (t.pose_stamped) pose_ = node.writer<ros2::PoseStamped>(TopicId::Pose, t.pose_name());
  else odom_ = node.writer<ros2::Odometry>(TopicId::Odom, t.pose_name());
}

void VehicleDriver::drain(std::vector<CommandItem>& out) {
  out.clear();
  twist_.drain(twist_buf_);
  convert(twist_buf_, out);
  twist_stamped_.drain(twist_stamped_buf_);
  convert(twist_stamped_buf_, out);
}

bool VehicleDriver::publish(const PoseSample& p) {
  if (topics_.pose_stamped) {
    ros2::PoseStamped m;
    to_msg(p, m);
    return pose_.write(m);
  }
  ros2::Odometry m;
  to_msg(p, m);
  return odom_.write(m);
}

int VehicleDriver::command_writers() const {
  return topics_.cmd_stamped ? twist_stamped_.matched() : twist_.matched();
}

}  // namespace shapeform::dds
