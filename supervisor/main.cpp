// shapeform_supervisor: publishes shape commands and tracking targets, takes console commands,
// computes, publishes and records the swarm's convergence metrics.
#include "supervisor_node.hpp"
#include "app/app.hpp"

int main(int argc, char** argv) {
  using namespace shapeform;
  app::App app("shapeform_supervisor",
                "shapeform_supervisor: commands the swarm and records its convergence. Type 'help' at the console.");
  supervisor::SupervisorOptions opt;
  app.add_config_options("YAML config; its command is what `start` publishes");
  app.cli().add_option("--script", opt.script, "run the console commands of this file first");
  app.cli()
      .add_option("--record", opt.record_dir, "record the run into this folder (metrics, positions, commands, tracked centre as CSV files, and run.mcap with those, every DDS sample read or written and the swarm drawn for Foxglove: docs/RECORDING.md)")
      ->check(app::writable_dir());
  app.cli().add_flag("--json", opt.json,
                     "machine output: stdout carries only JSON lines, one event each (epoch, wait, status, metrics, "
                     "agent, record, and the exit summary); human text goes to stderr");
  std::string on_start = "keep";
  app.cli()
      .add_option("--command-on-start", on_start,
                   "what `start` does when a command is in force that this supervisor did not publish (one "
                   "published before it started): keep it (default) or replace it with the --config scenario")
      ->check(CLI::IsMember({"keep", "replace"}));
  if (const auto rc = app.parse(argc, argv)) return *rc;
  opt.replace_on_start = on_start == "replace";
  const auto cfg = app.load_config();
  if (!cfg) return supervisor::kExitBadInput;
  return supervisor::run_supervisor(*cfg, opt);
}
