// shapeform_echo: the samples of one topic as JSON lines, one per sample.
#include <chrono>
#include <iostream>
#include <thread>

#include "app/app.hpp"
#include "dds/node.hpp"
#include "traffic_json.hpp"
#include "util/clock.hpp"
#include "util/signals.hpp"

namespace shapeform {
namespace {

/// Prints every sample of topic `id` (type Msg) until `count` lines (0: no limit), SIGINT/SIGTERM,
/// or `timeout_s` seconds (0: none) without reaching count (exit status 1).
template <class Msg>
int echo(const config::Config& cfg, dds::TopicId id, const std::string& topic, long long count, double timeout_s) {
  dds::Node node(dds::with_identity(cfg.transport, "viewer"), "shapeform_echo");
  dds::Reader<Msg> reader =
      node.reader<Msg>(id, dds::kDefaultMailboxCapacity, dds::is_vehicle_topic(id) ? topic : std::string());
  std::vector<dds::Received<Msg>> got;
  long long printed = 0;
  const std::int64_t start = util::steady_ns();
  while (!util::stop_flag()) {
    reader.drain(got);
    for (const auto& r : got) {
      std::cout << tools::echo_line(topic.c_str(), r).dump() << std::endl;
      if (count > 0 && ++printed >= count) return 0;
    }
    if (timeout_s > 0 && static_cast<double>(util::steady_ns() - start) * 1e-9 >= timeout_s) {
      std::cerr << "shapeform_echo: " << printed << " of " << count << " samples of " << topic
                << " in " << timeout_s << " s" << std::endl;
      return 1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return 0;
}

/// The program: arguments, config, then echo() of the topic's message type.
int run(int argc, char** argv) {
  std::string topics;
  for (const dds::TopicId id : dds::kAllTopics) topics += (topics.empty() ? "" : ", ") + std::string(dds::topic_name(id));
  app::App app("shapeform_echo",
               "shapeform_echo: prints the samples of one topic as JSON lines, one per sample, every field "
               "(as the project's conversion reads it). Joins the domain with the transport profile of the config "
               "(default: loopback) and the topic's own QoS (the command topic gives the command in force at once).");
  app.add_config_options();
  std::string topic;
  long long count = 0;
  double timeout_s = 0.0;
  app.cli()
      .add_option("topic", topic,
                  "the topic: " + topics +
                      " (a vehicle's: its name, e.g. rt/robot_0/odom; rt/NS/cmd_vel reads geometry_msgs/Twist)")
      ->required();
  app.cli().add_option("--count", count, "exit 0 after K lines (default 0: until Ctrl-C)")->check(CLI::NonNegativeNumber);
  app.cli()
      .add_option("--timeout", timeout_s, "exit 1 after S seconds without --count lines (default 0: never)")
      ->check(CLI::NonNegativeNumber);
  if (const auto rc = app.parse(argc, argv)) return *rc;
  const auto id = dds::find_topic(topic);
  if (!id) return app.usage_error("unknown topic '" + topic + "' (expected one of " + topics + ")");
  const auto cfg = app.load_config();
  if (!cfg) return app::kExitUsage;
  util::install_stop_signals();
  return app.run([&] {
    return dds::visit_topic(*id, [&](auto type) {
      return echo<typename decltype(type)::type>(*cfg, *id, topic, count, timeout_s);
    });
  });
}

}  // namespace
}  // namespace shapeform

int main(int argc, char** argv) { return shapeform::run(argc, argv); }
