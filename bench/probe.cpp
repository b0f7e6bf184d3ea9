// shapeform_bench_probe: a passive listener for benchmarks. Subscribes to AgentStatus (agents and
// baseline processes) and SwarmMetrics (the supervisor) and appends every sample to CSV files with
// its receive time on the host's steady clock (CLOCK_MONOTONIC, the clock of every *_stamp_ns):
//   DIR/status.csv   recv_ns,id,stamp_ns,ticks,overruns,lateness_max_us,lateness_p99_us,
//                    neighbours_heard,stale_dropped,samples_rejected,samples_received,samples_lost,
//                    age_p50_us,age_p99_us,cpu_percent,rss_mb,epoch
//   DIR/metrics.csv  recv_ns,epoch,model_time,agents_alive,shape_error_mean,gap_cv,converged
// Prints "ready <steady ns>" on stdout once its readers exist; runs until SIGINT/SIGTERM.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "config/config.hpp"
#include "dds/node.hpp"
#include "shapeform/msg/AgentStatus.h"
#include "shapeform/msg/SwarmMetrics.h"
#include "util/log.hpp"
#include "util/proc_stats.hpp"
#include "util/rate_loop.hpp"
#include "util/signals.hpp"

namespace {

namespace dds = shapeform::dds;
namespace msg = shapeform::msg;
namespace util = shapeform::util;
namespace config = shapeform::config;

int run(const config::Config& cfg, const std::filesystem::path& dir) {
  util::log_init("probe");
  util::install_stop_signals();
  std::FILE* status_csv = std::fopen((dir / "status.csv").c_str(), "w");
  std::FILE* metrics_csv = std::fopen((dir / "metrics.csv").c_str(), "w");
  if (!status_csv || !metrics_csv) {
    util::log_error("cannot write into " + dir.string());
    return 2;
  }
  std::fprintf(status_csv,
               "recv_ns,id,stamp_ns,ticks,overruns,lateness_max_us,lateness_p99_us,neighbours_heard,"
               "stale_dropped,samples_rejected,samples_received,samples_lost,age_p50_us,age_p99_us,"
               "cpu_percent,rss_mb,epoch\n");
  std::fprintf(metrics_csv, "recv_ns,epoch,model_time,agents_alive,shape_error_mean,gap_cv,converged\n");
  int status = 0;
  try {
    dds::Node node(cfg.transport, "shapeform_bench_probe");
    auto status_reader = node.reader<msg::AgentStatus>(dds::TopicId::Status);
    auto metrics_reader = node.reader<msg::SwarmMetrics>(dds::TopicId::Metrics);
    std::cout << "ready " << util::steady_ns() << std::endl;
    std::vector<dds::Received<msg::AgentStatus>> statuses;
    std::vector<dds::Received<msg::SwarmMetrics>> metrics;
    util::RateLoop loop(10.0);
    auto drain = [&] {
      status_reader.drain(statuses);
      for (const auto& r : statuses) {
        if (!r.valid_data) continue;
        const auto& s = r.msg;
        std::fprintf(status_csv, "%lld,%d,%lld,%llu,%llu,%.1f,%.1f,%d,%llu,%llu,%llu,%llu,%.1f,%.1f,%.2f,%.2f,%u\n",
                     static_cast<long long>(r.receive_stamp_ns), s.id(), static_cast<long long>(s.stamp_ns()),
                     static_cast<unsigned long long>(s.ticks()), static_cast<unsigned long long>(s.overruns()),
                     s.lateness_max_us(), s.lateness_p99_us(), s.neighbours_heard(),
                     static_cast<unsigned long long>(s.stale_dropped()),
                     static_cast<unsigned long long>(s.samples_rejected()),
                     static_cast<unsigned long long>(s.samples_received()),
                     static_cast<unsigned long long>(s.samples_lost()), s.age_p50_us(), s.age_p99_us(),
                     s.cpu_percent(), s.rss_mb(), s.epoch());
      }
      metrics_reader.drain(metrics);
      for (const auto& r : metrics) {
        if (!r.valid_data) continue;
        const auto& m = r.msg;
        std::fprintf(metrics_csv, "%lld,%u,%.3f,%d,%.6f,%.6f,%d\n", static_cast<long long>(r.receive_stamp_ns),
                     m.epoch(), m.model_time(), m.agents_alive(), m.shape_error_mean(), m.gap_cv(),
                     m.converged() ? 1 : 0);
      }
      std::fflush(status_csv);
      std::fflush(metrics_csv);
    };
    while (loop.wait_next(util::stop_flag())) drain();
    drain();
  } catch (const std::exception& e) {
    util::log_error(e.what());
    status = 1;
  }
  std::fclose(status_csv);
  std::fclose(metrics_csv);
  return status;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"shapeform_bench_probe: records AgentStatus and SwarmMetrics samples as CSV for benchmarks."};
  int domain = -1;
  std::string config_path, out;
  std::vector<std::string> sets;
  app.add_option("--out", out, "directory for status.csv and metrics.csv (created)")->required();
  app.add_option("--config", config_path, "YAML config (transport.*)");
  app.add_option("--domain", domain, "DDS domain id 0..232 (overrides transport.domain)");
  app.add_option("--set", sets, "override any config key: dotted.key=value (repeatable)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::cerr << "shapeform_bench_probe: " << e.what() << '\n';
    return 2;
  }
  if (app.count("--domain")) sets.push_back("transport.domain=" + std::to_string(domain));
  config::Config cfg;
  try {
    cfg = config::load(config_path, sets);
  } catch (const config::ConfigError& e) {
    for (const auto& p : e.problems()) std::cerr << "shapeform_bench_probe: " << p << '\n';
    return 2;
  }
  std::error_code ec;
  std::filesystem::create_directories(out, ec);
  if (ec) {
    std::cerr << "shapeform_bench_probe: --out: cannot create " << out << ": " << ec.message() << '\n';
    return 2;
  }
  return run(cfg, out);
}
