// shapeform_topics: every topic seen on a domain, with its writers and readers and their QoS.
#include <iostream>

#include "app/app.hpp"
#include "dds/discovery.hpp"
#include "traffic_json.hpp"
#include "util/signals.hpp"

namespace shapeform {
namespace {

int run(int argc, char** argv) {
  app::App app("shapeform_topics",
               "shapeform_topics: lists every topic seen on a DDS domain with its type, its writers and readers "
               "(participant, host, pid) and their QoS, after listening --wait seconds. Joins the domain with the "
               "transport profile of the config (default: loopback).");
  app.add_config_options();
  double wait_s = 2.0;
  bool json = false;
  app.cli().add_option("--wait", wait_s, "listening period, seconds (default 2)")->check(CLI::Range(0.0, 3600.0));
  app.cli().add_flag("--json", json, "one JSON object per topic on stdout ({\"event\": \"topic\", ...})");
  if (const auto rc = app.parse(argc, argv)) return *rc;
  const auto cfg = app.load_config();
  if (!cfg) return app::kExitUsage;
  util::install_stop_signals();
  return app.run([&] {
    const auto topics = dds::discover_topics(dds::with_identity(cfg->transport, "viewer"), "shapeform_topics", wait_s, &util::stop_flag());
    if (json) {
      for (const auto& t : topics) std::cout << tools::topic_json(t).dump() << '\n';
    } else {
      std::cout << tools::topics_table(topics);
    }
    std::cout << std::flush;
    return 0;
  });
}

}  // namespace
}  // namespace shapeform

int main(int argc, char** argv) { return shapeform::run(argc, argv); }
