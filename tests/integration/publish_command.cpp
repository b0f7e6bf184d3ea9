// shapeform_test_publish_command: a commander built from the project's own types, for the
// integration tests of command arbitration (tests/integration/test_authority.py). It publishes the
// --config command on "shapeform/command" with any epoch the test asks for, 2^32 - 1 and 2^64 - 1
// included, as a participant that is neither a supervisor nor an agent, and leaves the issuer field
// empty (receivers take the writer's GUID prefix). It stays (the sample is transient-local: it lives
// as long as its writer) until SIGINT/SIGTERM.
// Output: one JSON line {"event": "published", "epoch": E, "source": "<GUID prefix>"} once written.
#include <chrono>
#include <cstdint>
#include <iostream>
#include <thread>

#include <nlohmann/json.hpp>

#include "app/app.hpp"
#include "dds/convert.hpp"
#include "dds/node.hpp"
#include "util/clock.hpp"
#include "util/signals.hpp"

int main(int argc, char** argv) {
  namespace dds = shapeform::dds;
  namespace util = shapeform::util;
  namespace msg = shapeform::msg;
  shapeform::app::App app("shapeform_test_publish_command", "publishes one command with a chosen epoch (a test's rogue commander)");
  app.add_config_options("YAML config; its command is published");
  std::uint64_t epoch = 1;
  int readers = 1;
  std::string name = "shapeform_test_publish_command";
  app.cli().add_option("--epoch", epoch, "the epoch to publish (1 .. 2^64 - 1)")->required();
  app.cli().add_option("--readers", readers, "wait until this many readers (agents, supervisors) are matched");
  app.cli().add_option("--issuer-name", name, "the issuer_name field");
  if (const auto rc = app.parse(argc, argv)) return *rc;
  const auto cfg = app.load_config();
  if (!cfg) return shapeform::app::kExitUsage;
  return app.run([&] {
    util::install_stop_signals();
    dds::Node node(cfg->transport, "shapeform_test_publish_command");
    auto writer = node.writer<msg::ShapeCommand>(dds::TopicId::Command);
    const std::int64_t deadline = util::steady_ns() + 20'000'000'000LL;
    while (writer.matched() < readers && util::steady_ns() < deadline && !util::stop_flag())
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    if (!writer.write(dds::to_msg(cfg->command, dds::CommandId{epoch}, name))) throw std::runtime_error("write failed");
    const nlohmann::json line = {
        {"event", "published"}, {"epoch", epoch}, {"source", dds::to_string(node.source())}, {"readers", writer.matched()}};
    std::cout << line.dump() << std::endl;
    while (!util::stop_flag()) std::this_thread::sleep_for(std::chrono::milliseconds(20));
    return 0;
  });
}
