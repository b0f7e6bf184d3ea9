// shapeform_rogue_publisher: a test tool that publishes hand-made samples built from the project's own
// types on one topic, to check how the swarm treats a participant that is not one of its processes
// (absurd ids or model times, epochs from nowhere) or a robot's pose that is not the robot's (a jump, a
// position that is not a number, another frame). Any field of the message a test needs is settable:
//   shapeform_rogue_publisher --domain 138 --topic state --field id=2147483647 --field model_time=1e300
//                             --count 50 --rate 50 --wait-readers 1
//   shapeform_rogue_publisher --domain 138 --topic odom --robot 3 --field x=nan --wait-readers 1
// Each sample starts from a plausible one (state: agent 0 at the origin; command: the config's
// command, epoch 1; target: centre 0, epoch 1; odom: nav_msgs/Odometry on robot K's pose topic,
// rt/<vehicle.namespace>/<vehicle.pose_topic> with {id} = K, at the origin, yaw 0, in vehicle.frame) and
// the --field values are applied in order.
// Prints one JSON line per event on stdout: {"event":"matched","readers":N},
// {"event":"sent","count":N,"source":"<its GUID prefix>"}. With --stay it then keeps its writer until
// SIGINT/SIGTERM (a transient-local command lives as long as its writer). With DDS Security (the
// security.* keys, an identity always given) it reports each participant it refused, as the swarm's
// processes do: {"event":"refused","participant":"<GUID prefix>","by":"<its own>"}. A command leaves its
// issuer field empty, so receivers take the writer's GUID prefix ("source") as the issuer.
#include <chrono>
#include <cmath>
#include <cstdint>
#include <functional>
#include <iostream>
#include <map>
#include <stdexcept>
#include <string>
#include <thread>
#include <type_traits>
#include <vector>

#include "app/app.hpp"
#include "dds/convert.hpp"
#include "dds/convert_ros2.hpp"
#include "dds/node.hpp"
#include "util/clock.hpp"
#include "util/signals.hpp"

namespace shapeform {
namespace {

/// The field's own type from its setter's argument: integers via stoll/stoull, reals via stod.
template <class T>
T parse_as(const std::string& text) {
  std::size_t used = 0;
  T v{};
  if constexpr (std::is_floating_point_v<T>) {
    v = static_cast<T>(std::stod(text, &used));
  } else if constexpr (std::is_signed_v<T>) {
    v = static_cast<T>(std::stoll(text, &used));
  } else {
    v = static_cast<T>(std::stoull(text, &used));
  }
  if (used != text.size()) throw std::invalid_argument("not a number: '" + text + "'");
  return v;
}

template <class Msg>
using Setters = std::map<std::string, std::function<void(Msg&, const std::string&)>>;

/// A setter for the numeric field that `get` reads and `set` writes.
#define ROGUE_NUMBER(Msg, name) \
  {#name, [](Msg& m, const std::string& v) { m.name(parse_as<std::decay_t<decltype(m.name())>>(v)); }}
#define ROGUE_TEXT(Msg, name) {#name, [](Msg& m, const std::string& v) { m.name(v); }}

const Setters<msg::AgentState> kStateFields = {
    ROGUE_NUMBER(msg::AgentState, id),     ROGUE_NUMBER(msg::AgentState, seq),    ROGUE_NUMBER(msg::AgentState, epoch),
    ROGUE_NUMBER(msg::AgentState, model_time), ROGUE_NUMBER(msg::AgentState, x),  ROGUE_NUMBER(msg::AgentState, y),
    ROGUE_NUMBER(msg::AgentState, vx),     ROGUE_NUMBER(msg::AgentState, vy),     ROGUE_NUMBER(msg::AgentState, prev_x),
    ROGUE_NUMBER(msg::AgentState, prev_y), ROGUE_NUMBER(msg::AgentState, stamp_ns)};

const Setters<msg::ShapeCommand> kCommandFields = {
    ROGUE_NUMBER(msg::ShapeCommand, epoch), ROGUE_NUMBER(msg::ShapeCommand, k1),   ROGUE_NUMBER(msg::ShapeCommand, k2),
    ROGUE_NUMBER(msg::ShapeCommand, cx),    ROGUE_NUMBER(msg::ShapeCommand, cy),   ROGUE_NUMBER(msg::ShapeCommand, r0),
    ROGUE_NUMBER(msg::ShapeCommand, scale), ROGUE_NUMBER(msg::ShapeCommand, dt),   ROGUE_NUMBER(msg::ShapeCommand, max_speed),
    ROGUE_NUMBER(msg::ShapeCommand, sigma), ROGUE_TEXT(msg::ShapeCommand, shape_kind), ROGUE_TEXT(msg::ShapeCommand, f_expr),
    ROGUE_TEXT(msg::ShapeCommand, law)};

const Setters<msg::TrackingTarget> kTargetFields = {
    ROGUE_NUMBER(msg::TrackingTarget, epoch), ROGUE_NUMBER(msg::TrackingTarget, model_time),
    ROGUE_NUMBER(msg::TrackingTarget, cx),    ROGUE_NUMBER(msg::TrackingTarget, cy),
    ROGUE_NUMBER(msg::TrackingTarget, vx),    ROGUE_NUMBER(msg::TrackingTarget, vy)};

/// A robot's pose: its position, its yaw (the orientation about z) and its frame.
const Setters<dds::ros2::Odometry> kOdomFields = {
    {"x",
     [](dds::ros2::Odometry& m, const std::string& v) { m.pose().pose().position().x(parse_as<double>(v)); }},
    {"y",
     [](dds::ros2::Odometry& m, const std::string& v) { m.pose().pose().position().y(parse_as<double>(v)); }},
    {"yaw",
     [](dds::ros2::Odometry& m, const std::string& v) {
       const double yaw = parse_as<double>(v);
       m.pose().pose().orientation().z(std::sin(yaw / 2));
       m.pose().pose().orientation().w(std::cos(yaw / 2));
     }},
    {"frame_id", [](dds::ros2::Odometry& m, const std::string& v) { m.header().frame_id(v); }}};

#undef ROGUE_NUMBER
#undef ROGUE_TEXT

struct Options {
  std::vector<std::string> fields;
  int count = 1;
  double rate_hz = 10.0;
  int wait_readers = 0;
  double wait_s = 10.0;
  bool stay = false;
};

/// Prints the participants DDS Security refused since the last call.
void report_refused(dds::Node& node) {
  for (const dds::SourceId& r : node.take_refused())
    std::cout << R"({"event":"refused","participant":")" << dds::to_string(r) << R"(","by":")"
              << dds::to_string(node.source()) << "\"}" << std::endl;
}

/// topic_name: the DDS topic's name for a vehicle's topic, else empty (the topic table's).
template <class Msg>
int publish(dds::Node& node, dds::TopicId topic, Msg m, const Setters<Msg>& setters, const Options& opt,
            const std::string& topic_name = {}) {
  for (const std::string& f : opt.fields) {
    const auto eq = f.find('=');
    const auto it = eq == std::string::npos ? setters.end() : setters.find(f.substr(0, eq));
    if (it == setters.end()) {
      std::string known;
      for (const auto& [name, set] : setters) known += (known.empty() ? "" : ", ") + name;
      throw std::invalid_argument("--field " + f + ": expected name=value with a name among " + known);
    }
    it->second(m, f.substr(eq + 1));
  }
  dds::Writer<Msg> writer = node.writer<Msg>(topic, topic_name);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(opt.wait_s);
  while (writer.matched() < opt.wait_readers && !util::stop_flag()) {
    if (std::chrono::steady_clock::now() > deadline)
      throw std::runtime_error("fewer than " + std::to_string(opt.wait_readers) + " readers matched");
    report_refused(node);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::cout << R"({"event":"matched","readers":)" << writer.matched() << "}" << std::endl;
  const auto period = std::chrono::duration<double>(1.0 / opt.rate_hz);
  int sent = 0;
  for (auto next = std::chrono::steady_clock::now(); sent < opt.count && !util::stop_flag(); ++sent) {
    if (!writer.write(m)) throw std::runtime_error("write failed");
    report_refused(node);
    next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(period);
    std::this_thread::sleep_until(next);
  }
  std::cout << R"({"event":"sent","count":)" << sent << R"(,"source":")" << dds::to_string(node.source()) << "\"}"
            << std::endl;
  while (opt.stay && !util::stop_flag()) {
    report_refused(node);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return 0;
}

int run(int argc, char** argv) {
  app::App app("shapeform_rogue_publisher",
               "shapeform_rogue_publisher: publishes hand-made samples on one topic (a test tool).");
  std::string topic;
  Options opt;
  int robot = 0;
  app.cli()
      .add_option("--topic", topic, "state | command | target | odom (a robot's pose)")
      ->required()
      ->check(CLI::IsMember({"state", "command", "target", "odom"}));
  app.cli()
      .add_option("--robot", robot, "odom: the robot whose pose topic it is (default 0)")
      ->check(CLI::Range(0, dds::kMaxAgentId));
  app.cli().add_option("--field", opt.fields, "name=value: a field of the message (repeatable)");
  app.cli().add_option("--count", opt.count, "samples to publish (default 1)")->check(CLI::Range(1, 1000000));
  app.cli().add_option("--rate", opt.rate_hz, "samples per second (default 10)")->check(CLI::Range(0.001, 1000.0));
  app.cli()
      .add_option("--wait-readers", opt.wait_readers, "first wait until this many readers match (default 0)")
      ->check(CLI::Range(0, 1000));
  app.cli().add_option("--wait-s", opt.wait_s, "how long to wait for them (default 10)")->check(CLI::Range(0.1, 600.0));
  app.cli().add_flag("--stay", opt.stay, "keep the writer after publishing, until SIGINT/SIGTERM");
  app.add_config_options();
  if (const auto rc = app.parse(argc, argv)) return *rc;
  const auto cfg = app.load_config();
  if (!cfg) return app::kExitUsage;
  util::install_stop_signals();
  return app.run([&] {
    dds::Node node(cfg->transport, "shapeform_rogue_publisher");
    if (topic == "state") {
      dds::StateSample s;
      s.seq = 1;
      return publish(node, dds::TopicId::State, dds::to_msg(s), kStateFields, opt);
    }
    if (topic == "command") return publish(node, dds::TopicId::Command, dds::to_msg(cfg->command, 1), kCommandFields, opt);
    if (topic == "odom") {
      const config::VehicleLink& link = cfg->vehicle_link;
      dds::PoseSample p;
      p.stamp_ns = util::system_ns();
      p.frame_id = link.frame;
      p.child_frame_id = link.namespace_of(robot) + "/" + cfg->vehicle_sim.child_frame;
      dds::ros2::Odometry m;
      dds::to_msg(p, m);
      return publish(node, dds::TopicId::Odom, m, kOdomFields, opt,
                     dds::vehicle_topic_name(link.namespace_of(robot),
                                             config::VehicleLink::with_id(link.pose_topic, robot)));
    }
    return publish(node, dds::TopicId::Target, dds::to_msg(dds::TargetSample{1, 0.0, {}, {}, 0}), kTargetFields, opt);
  });
}

}  // namespace
}  // namespace shapeform

int main(int argc, char** argv) { return shapeform::run(argc, argv); }
