// shapeform_supervisor: publishes shape commands and tracking targets, takes console commands,
// computes, publishes and records the swarm's convergence metrics.
#include <CLI/CLI.hpp>
#include <iostream>

#include "supervisor_node.hpp"

int main(int argc, char** argv) {
  using namespace shapeform;
  CLI::App app{"shapeform_supervisor: commands the swarm and records its convergence. Type 'help' at the console."};
  std::string config_path;
  std::vector<std::string> sets;
  int domain = -1;
  supervisor::SupervisorOptions opt;
  app.add_option("--config", config_path, "YAML config; its command is what `start` publishes");
  app.add_option("--domain", domain, "DDS domain id 0..232 (overrides transport.domain)");
  app.add_option("--script", opt.script, "run the console commands of this file first");
  app.add_option("--record", opt.record_dir, "record metrics.csv and positions.csv into this folder");
  app.add_flag("--json", opt.json, "print the exit summary as one JSON object on stdout");
  app.add_option("--set", sets, "override any config key: dotted.key=value (repeatable)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::cerr << "shapeform_supervisor: " << e.what() << '\n';
    return supervisor::kExitBadInput;
  }
  if (app.count("--domain")) sets.push_back("transport.domain=" + std::to_string(domain));
  config::Config cfg;
  try {
    cfg = config::load(config_path, sets);
  } catch (const config::ConfigError& e) {
    for (const auto& p : e.problems()) std::cerr << "shapeform_supervisor: " << p << '\n';
    return supervisor::kExitBadInput;
  }
  return supervisor::run_supervisor(cfg, opt);
}
