#include "live.hpp"

#include <cmath>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "dds/convert.hpp"
#include "dds/convert_ros2.hpp"
#include "dds/node.hpp"
#include "dds/state_input.hpp"
#include "dds/status_input.hpp"
#include "dds/wire.hpp"
#include "protocol/command_arbiter.hpp"
#include "util/log.hpp"

namespace shapeform::view {
namespace {

/// Mailbox bound of a vehicle's pose reader: a second of a 50 Hz driver; drained at the view's rate.
constexpr std::size_t kPoseMailbox = 64;

/// The pose topic of one agent's vehicle (vehicle.interface ros2), read only: the view takes the
/// heading from it and never writes the vehicle's command topic (dds::VehicleController would).
struct PoseFeed {
  dds::Reader<dds::ros2::Odometry> odom;
  dds::Reader<dds::ros2::PoseStamped> pose;
  std::vector<dds::Received<dds::ros2::Odometry>> odom_buf;
  std::vector<dds::Received<dds::ros2::PoseStamped>> pose_buf;

  PoseFeed(dds::Node& node, const config::VehicleLink& link, std::int32_t id) {
    const std::string name = dds::vehicle_topic_name(link.namespace_of(id), link.pose_topic);
    if (link.pose_type == config::VehicleLink::PoseType::PoseStamped)
      pose = node.reader<dds::ros2::PoseStamped>(dds::TopicId::Pose, kPoseMailbox, name);
    else
      odom = node.reader<dds::ros2::Odometry>(dds::TopicId::Odom, kPoseMailbox, name);
  }

  /// The yaw of the newest valid pose in `frame` since the last call, if any.
  std::optional<double> newest_yaw(const std::string& frame) {
    std::optional<double> yaw;
    odom.drain(odom_buf);
    pose.drain(pose_buf);
    take(odom_buf, frame, yaw);
    take(pose_buf, frame, yaw);
    return yaw;
  }

 private:
  template <class Msg>
  static void take(const std::vector<dds::Received<Msg>>& in, const std::string& frame,
                   std::optional<double>& yaw) {
    std::string why;
    for (const auto& r : in) {
      dds::PoseSample p;
      if (r.valid_data && dds::from_msg(r.msg, p, why) && p.frame_id == frame) yaw = p.yaw;
    }
  }
};

/// The valid samples of buf to sink, serialized only when it wants the topic.
template <class Msg>
void forward(SampleSink* sink, const std::vector<dds::Received<Msg>>& buf) {
  constexpr dds::TopicId topic = dds::MsgTraits<Msg>::topic;
  if (sink == nullptr || buf.empty() || !sink->wants(topic)) return;
  for (const auto& r : buf) {
    if (r.valid_data) sink->on_sample(topic, dds::to_cdr(r.msg));
  }
}

}  // namespace

struct LiveFeed::Impl {
  explicit Impl(const config::Config& cfg)
      : link(cfg.vehicle_link),
        node(dds::with_identity(cfg.transport, "viewer"), "shapeform_view"),
        states(node),
        statuses(node),
        commands(node.reader<msg::ShapeCommand>(dds::TopicId::Command)),
        targets(node.reader<msg::TrackingTarget>(dds::TopicId::Target)),
        metrics(node.reader<msg::SwarmMetrics>(dds::TopicId::Metrics)) {}

  const config::VehicleLink link;
  dds::Node node;  // readers only: the viewer never writes a topic
  // Each reader with the buffer its samples are drained into.
  dds::StateInput states;  // shapeform/state and shapeform/state_batch
  std::vector<dds::StateItem> state_buf;
  dds::StatusInput statuses;  // shapeform/status and shapeform/status_batch
  std::vector<dds::StatusItem> status_buf;
  dds::Reader<msg::ShapeCommand> commands;
  std::vector<dds::Received<msg::ShapeCommand>> command_buf;
  dds::Reader<msg::TrackingTarget> targets;
  std::vector<dds::Received<msg::TrackingTarget>> target_buf;
  dds::Reader<msg::SwarmMetrics> metrics;
  std::vector<dds::Received<msg::SwarmMetrics>> metrics_buf;
  dds::CommandArbiter arbiter;
  std::map<std::int32_t, PoseFeed> poses;  ///< vehicle.interface ros2: one per agent id heard
  SampleSink* sink = nullptr;
};

LiveFeed::LiveFeed(const config::Config& cfg) : impl_(std::make_unique<Impl>(cfg)) {}
LiveFeed::~LiveFeed() = default;

void LiveFeed::set_sink(SampleSink* sink) { impl_->sink = sink; }

std::vector<dds::TopicId> LiveFeed::topics() {
  return {dds::TopicId::State, dds::TopicId::StateBatch, dds::TopicId::Command,
          dds::TopicId::Target, dds::TopicId::Metrics, dds::TopicId::Status, dds::TopicId::StatusBatch};
}

void LiveFeed::drain(Scene& scene, double now_s, double period_s) {
  Impl& m = *impl_;
  m.node.recover(period_s);
  std::string why;
  m.states.drain(m.state_buf);
  forward(m.sink, m.states.last_states());
  forward(m.sink, m.states.last_batches());
  for (const auto& r : m.state_buf) {
    if (r.kind == dds::StateItem::Kind::Gone) {
      if (r.instance == dds::InstanceState::Disposed) scene.on_departed(r.id);
    } else if (r.kind == dds::StateItem::Kind::State) {
      scene.on_state(r.state.id, r.state.x, r.state.model_time, r.state.command.epoch, now_s);
    }
  }
  if (m.link.ros2()) {
    // Each agent heard drives a vehicle: its heading from the vehicle's pose topic.
    for (const auto& [id, a] : scene.agents()) {
      if (m.poses.find(id) == m.poses.end()) m.poses.try_emplace(id, m.node, m.link, id);
    }
    for (auto& [id, feed] : m.poses) {
      if (const auto yaw = feed.newest_yaw(m.link.frame)) scene.on_heading(id, *yaw, now_s);
    }
  }
  m.statuses.drain(m.status_buf);
  forward(m.sink, m.statuses.last_statuses());
  forward(m.sink, m.statuses.last_batches());
  for (const auto& r : m.status_buf) {
    if (r.valid) scene.on_status(r.status.id, r.status.neighbours_heard, r.status.lateness_p99_us);
  }
  // The command in force is chosen by the swarm's one rule (dds::CommandArbiter), as agents and
  // supervisor choose it.
  const std::uint64_t floor = scene.min_epoch_followed(now_s);
  bool adopted = false;
  m.commands.drain(m.command_buf);
  forward(m.sink, m.command_buf);
  for (const auto& r : m.command_buf) {
    dds::CommandSample c;
    if (r.valid_data && dds::from_msg(r.msg, r.source, c, why)) {
      adopted = m.arbiter.offer(c, floor) == dds::CommandArbiter::Verdict::Adopted || adopted;
    }
  }
  if (m.arbiter.has_refused() && m.arbiter.recheck(floor)) adopted = true;
  if (adopted) scene.on_command(m.arbiter.current().command, m.arbiter.current().id.epoch);
  m.targets.drain(m.target_buf);
  forward(m.sink, m.target_buf);
  for (const auto& r : m.target_buf) {
    dds::TargetSample t;
    if (r.valid_data && dds::from_msg(r.msg, t, why) && t.command.epoch == m.arbiter.id().epoch) scene.on_centre(t.centre);
  }
  m.metrics.drain(m.metrics_buf);
  forward(m.sink, m.metrics_buf);
  for (const auto& r : m.metrics_buf) {
    if (!r.valid_data || !std::isfinite(r.msg.model_time())) continue;
    scene.on_metrics(r.msg.model_time(), r.msg.epoch(), r.msg.agents_alive(), dds::from_msg(r.msg), r.msg.converged());
  }
}

}  // namespace shapeform::view
