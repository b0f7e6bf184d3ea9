// shapeform_bench_probe: a passive listener for benchmarks. Subscribes to AgentStatus and
// AgentStatusBatch (agents and baseline processes) and SwarmMetrics (the supervisor) and appends every
// status (a batch's one by one) and metrics sample to CSV files with its receive time on the host's
// steady clock (CLOCK_MONOTONIC, the clock of every *_stamp_ns):
//   DIR/status.csv   recv_ns,id,stamp_ns,ticks,overruns,lateness_max_us,lateness_p99_us,
//                    neighbours_heard,stale_dropped,samples_rejected,samples_received,samples_lost,
//                    age_p50_us,age_p99_us,cpu_percent,rss_mb,epoch,control_latency_p50_us,
//                    control_latency_p99_us
//   DIR/metrics.csv  recv_ns,epoch,model_time,agents_alive,shape_error_mean,gap_cv,converged
//                    (the metrics by their core::kMetricTable names; -1 = undefined)
// Prints "ready <steady ns>" on stdout once its readers exist; runs until SIGINT/SIGTERM.
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "core/metric_table.hpp"
#include "dds/convert.hpp"
#include "dds/node.hpp"
#include "dds/status_input.hpp"
#include "shapeform/msg/SwarmMetrics.h"
#include "app/app.hpp"
#include "util/log.hpp"
#include "util/proc_stats.hpp"
#include "util/rate_loop.hpp"
#include "util/signals.hpp"

namespace {

namespace dds = shapeform::dds;
namespace msg = shapeform::msg;
namespace util = shapeform::util;
namespace config = shapeform::config;
namespace core = shapeform::core;

/// The metrics of metrics.csv (core::kMetricTable names), after recv_ns,epoch,model_time,agents_alive.
constexpr const core::MetricInfo* kProbeMetrics[] = {&core::metric("shape_error_mean"), &core::metric("gap_cv")};

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
               "cpu_percent,rss_mb,epoch,control_latency_p50_us,control_latency_p99_us\n");
  std::fprintf(metrics_csv, "recv_ns,epoch,model_time,agents_alive");
  for (const auto* info : kProbeMetrics) std::fprintf(metrics_csv, ",%s", std::string(info->name).c_str());
  std::fprintf(metrics_csv, ",converged\n");
  int status = 0;
  try {
    dds::Node node(dds::with_identity(cfg.transport, "viewer"), "shapeform_bench_probe");
    dds::StatusInput status_input(node);
    auto metrics_reader = node.reader<msg::SwarmMetrics>(dds::TopicId::Metrics);
    std::cout << "ready " << util::steady_ns() << std::endl;
    std::vector<dds::StatusItem> statuses;
    std::vector<dds::Received<msg::SwarmMetrics>> metrics;
    util::RateLoop loop(10.0);
    auto drain = [&] {
      status_input.drain(statuses);
      for (const auto& r : statuses) {
        if (!r.valid) continue;
        const dds::StatusSample& s = r.status;
        std::fprintf(status_csv, "%lld,%d,%lld,%llu,%llu,%.1f,%.1f,%d,%llu,%llu,%llu,%llu,%.1f,%.1f,%.4f,%.4f,%llu,%.1f,%.1f\n",
                     static_cast<long long>(r.receive_stamp_ns), s.id, static_cast<long long>(s.stamp_ns),
                     static_cast<unsigned long long>(s.ticks), static_cast<unsigned long long>(s.overruns),
                     s.lateness_max_us, s.lateness_p99_us, s.neighbours_heard,
                     static_cast<unsigned long long>(s.stale_dropped), static_cast<unsigned long long>(s.samples_rejected),
                     static_cast<unsigned long long>(s.samples_received),
                     static_cast<unsigned long long>(s.samples_lost), s.age_p50_us, s.age_p99_us, s.cpu_percent,
                     s.rss_mb, static_cast<unsigned long long>(s.epoch), s.control_latency_p50_us,
                     s.control_latency_p99_us);
      }
      metrics_reader.drain(metrics);
      for (const auto& r : metrics) {
        if (!r.valid_data) continue;
        const auto& m = r.msg;
        const core::Metrics values = dds::from_msg(m);
        std::fprintf(metrics_csv, "%lld,%llu,%.3f,%d", static_cast<long long>(r.receive_stamp_ns),
                     static_cast<unsigned long long>(m.epoch()),
                     m.model_time(), m.agents_alive());
        for (const auto* info : kProbeMetrics) std::fprintf(metrics_csv, ",%.6f", info->get(values).value_or(-1.0));
        std::fprintf(metrics_csv, ",%d\n", m.converged() ? 1 : 0);
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
  shapeform::app::App app("shapeform_bench_probe",
                "shapeform_bench_probe: records AgentStatus and SwarmMetrics samples as CSV for benchmarks.");
  std::string out;
  app.cli().add_option("--out", out, "directory for status.csv and metrics.csv (created)")->required()->check(shapeform::app::writable_dir());
  app.add_config_options("YAML config (transport.*)");
  if (const auto rc = app.parse(argc, argv)) return *rc;
  const auto cfg = app.load_config();
  if (!cfg) return shapeform::app::kExitUsage;
  std::error_code ec;
  std::filesystem::create_directories(out, ec);
  if (ec) return app.usage_error("--out: cannot create " + out + ": " + ec.message());
  return run(*cfg, out);
}
