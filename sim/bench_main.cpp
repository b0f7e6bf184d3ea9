// shapeform_bench_sim: Euler steps per second of the paper's law, batched kernel against the scalar
// reference (every agent through agent_step, each pair computed twice), or with --peak the core's peak
// multiply-add rate. Prints one JSON object.
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>

#include "core/swarm.hpp"
#include "app/app.hpp"

namespace {
double rss_mb() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  return -1;
}
}  // namespace

int main(int argc, char** argv) {
  using namespace shapeform;
  app::App app("shapeform_bench_sim", "shapeform_bench_sim: simulator throughput (paper law, Euler dt = 1, circle r0 = 4)");
  int agents = 1000;
  long steps = 100;
  std::string impl = "fast";
  std::string simd = std::string(core::to_string(core::simd_best()));
  int threads = 1;
  bool peak = false;
  double beta = core::Gains{}.beta;
  app.cli().add_option("--agents", agents, "swarm size")->check(CLI::Range(1, 1000000));
  app.cli().add_option("--steps", steps, "steps to time")->check(CLI::Range(1L, 100000000L));
  app.cli().add_option("--impl", impl, "fast (batched, vectorised) | reference (scalar, per agent)")
      ->check(CLI::IsMember({"fast", "reference"}));
  std::vector<std::string> isas;
  for (const core::Simd s : core::simd_available()) isas.emplace_back(core::to_string(s));
  app.cli().add_option("--simd", simd, "instruction set of the fast kernel (default: the widest this CPU runs)")
      ->check(CLI::IsMember(isas));
  app.cli().add_option("--threads", threads, "threads of the fast kernel's pair pass")->check(CLI::Range(1, 64));
  app.cli().add_option("--beta", beta, "the law's decay exponent (default: the paper's)")->check(CLI::Range(0.0, 10.0));
  app.cli().add_flag("--peak", peak, "measure instead the multiply-adds per second one thread sustains with --simd");
  if (const auto rc = app.parse(argc, argv)) return *rc;
  core::BatchOptions batch;
  for (const core::Simd s : core::simd_available())
    if (core::to_string(s) == simd) batch.simd = s;
  batch.threads = threads;
  nlohmann::json j;
  if (peak) {
    j["simd"] = simd;
    j["lanes"] = core::simd_lanes(batch.simd);
    j["fma_per_s"] = core::fma_peak(batch.simd, 0.5);
    std::cout << j.dump() << std::endl;
    return 0;
  }
  core::CompiledCommand cmd;  // the paper's circle
  cmd.gains.beta = beta;
  core::Swarm swarm(cmd, core::uniform_start(agents, 1, 5.0));
  swarm.set_kernel(impl == "fast" ? core::Kernel::Batch : core::Kernel::Agent);
  swarm.set_batch(batch);
  swarm.step();  // warm-up (allocations)
  const auto t0 = std::chrono::steady_clock::now();
  for (long k = 0; k < steps; ++k) swarm.step();
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  j["agents"] = agents;
  j["steps"] = steps;
  j["impl"] = impl;
  j["simd"] = impl == "fast" ? nlohmann::json(simd) : nlohmann::json(nullptr);
  j["threads"] = impl == "fast" ? threads : 1;
  j["beta"] = beta;
  j["seconds"] = secs;
  j["steps_per_s"] = static_cast<double>(steps) / secs;
  // Per pair {i, j}: the fast kernel computes each once, the reference twice (once per agent).
  j["ns_per_pair"] = secs / static_cast<double>(steps) / (0.5 * agents * (agents - 1.0)) * 1e9;
  j["rss_mb"] = rss_mb();
  std::cout << j.dump() << std::endl;
  return 0;
}
