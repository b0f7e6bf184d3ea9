// shapeform_bench_mcap: what the MCAP recording of a swarm's states costs with each chunk compression
// (docs/BENCHMARKS.md, "MCAP recording: compression"). Writes N agents' states at R Hz for S seconds
// (each an XCDR1 struct of id, model_time, step, epoch, x1, x2: 44 bytes with its header, as they come
// off the wire), one message per state and again as batches of 50 states, with none, lz4 and zstd; prints
// file bytes per agent-second and the writer's CPU time per message. The states are generated before the
// clock starts: only McapWriter is measured.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <iostream>
#include <vector>

#include "app/app.hpp"
#include "record/mcap.hpp"

namespace shapeform {
namespace {

namespace fs = std::filesystem;

const char* kIdl = R"(module shapeform { module msg {
  struct AgentState { int32 id; double model_time; uint32 step; uint32 epoch; double x1; double x2; };
  struct AgentStateBatch { sequence<AgentState> states; };
}; };
)";

struct Cdr {
  std::vector<std::uint8_t>& b;
  std::size_t origin;
  void align(std::size_t n) {
    while ((b.size() - origin) % n != 0) b.push_back(0);
  }
  template <class T>
  void put(T v) {
    align(sizeof(T));
    const auto* p = reinterpret_cast<const std::uint8_t*>(&v);
    b.insert(b.end(), p, p + sizeof(T));
  }
};

/// Every message of the run, encoded: `offsets[i]..offsets[i+1]` is message i.
struct Stream {
  std::vector<std::uint8_t> bytes;
  std::vector<std::size_t> offsets{0};
  std::vector<std::uint64_t> times;
};

/// The agents spread on a circle of radius 20 m, each drifting towards its slot with a little noise.
void state(int id, int n, int tick, double rate_hz, std::uint32_t& seed, double& x1, double& x2) {
  const double t = tick / rate_hz;
  const double a = 2.0 * M_PI * id / n + 0.01 * t;
  const double r = 20.0 + 5.0 * std::exp(-0.1 * t);
  seed = seed * 1664525u + 1013904223u;
  const double noise = (double(seed >> 8) / double(1u << 24) - 0.5) * 0.02;
  x1 = r * std::cos(a) + noise;
  x2 = r * std::sin(a) - noise;
}

Stream make_stream(int agents, double rate_hz, double seconds, int batch) {
  Stream s;
  const int ticks = int(std::lround(rate_hz * seconds));
  std::vector<std::uint32_t> seeds(static_cast<std::size_t>(agents));
  for (int i = 0; i < agents; ++i) seeds[std::size_t(i)] = std::uint32_t(i) * 2654435761u;
  for (int k = 0; k < ticks; ++k) {
    const std::uint64_t t_ns = std::uint64_t(k) * std::uint64_t(1e9 / rate_hz) + 1'700'000'000'000'000'000ull;
    for (int first = 0; first < agents; first += batch) {
      const int count = std::min(batch, agents - first);
      s.bytes.insert(s.bytes.end(), {0x00, 0x01, 0x00, 0x00});
      Cdr c{s.bytes, s.bytes.size()};
      if (batch > 1) c.put(std::uint32_t(count));
      for (int i = first; i < first + count; ++i) {
        double x1, x2;
        state(i, agents, k, rate_hz, seeds[std::size_t(i)], x1, x2);
        c.put(std::int32_t(i));
        c.put(k / rate_hz);
        c.put(std::uint32_t(k));
        c.put(std::uint32_t(3));
        c.put(x1);
        c.put(x2);
      }
      s.offsets.push_back(s.bytes.size());
      s.times.push_back(t_ns + std::uint64_t(first) * 1000);  // received spread over the tick
    }
  }
  return s;
}

int run(int argc, char** argv) {
  app::App app(
      "shapeform_bench_mcap",
      "shapeform_bench_mcap: the MCAP recording of N agents' states at R Hz for S seconds, one message "
      "per state and in batches of 50, with each chunk compression (none, lz4, zstd): file bytes per "
      "agent-second and the writer's CPU time per message (docs/BENCHMARKS.md).");
  int agents = 1000;
  double rate_hz = 20.0, seconds = 30.0;
  std::size_t chunk_bytes = 1 << 20;
  std::string dir = fs::temp_directory_path().string();
  app.cli().add_option("--agents", agents, "agents (default 1000)")->check(CLI::Range(1, 100000));
  app.cli()
      .add_option("--rate", rate_hz, "states per agent per second (default 20)")
      ->check(CLI::Range(0.1, 1000.0));
  app.cli().add_option("--seconds", seconds, "recorded seconds (default 30)")->check(CLI::Range(0.1, 3600.0));
  app.cli()
      .add_option("--chunk-bytes", chunk_bytes, "chunk size before compression, bytes (default 1 MiB)")
      ->check(CLI::Range(std::size_t(1024), std::size_t(1) << 30));
  app.cli()
      .add_option("--dir", dir, "where the files are written (and removed), default the temp dir")
      ->check(app::writable_dir());
  if (const auto rc = app.parse(argc, argv)) return *rc;
  return app.run([&] {
    std::printf("%d agents, %.0f Hz, %.0f s, chunks of %zu bytes\n", agents, rate_hz, seconds, chunk_bytes);
    std::printf(
        "| messages | compression | file MB | bytes per agent-second | writer CPU ns per message | per state "
        "|\n");
    std::printf("|---|---|---:|---:|---:|---:|\n");
    for (const int batch : {1, 50}) {
      const Stream s = make_stream(agents, rate_hz, seconds, batch);
      const std::size_t n = s.times.size();
      const double states = double(agents) * double(std::lround(rate_hz * seconds));
      for (const auto c :
           {record::McapCompression::None, record::McapCompression::Lz4, record::McapCompression::Zstd}) {
        const fs::path file =
            fs::path(dir) / ("shapeform_bench_mcap_" + std::string(record::to_string(c)) + ".mcap");
        record::McapOptions o;
        o.compression = c;
        o.chunk_bytes = chunk_bytes;
        record::McapWriter w(o);
        w.open(file);
        const auto schema = w.add_schema(
            batch > 1 ? "shapeform::msg::AgentStateBatch" : "shapeform::msg::AgentState", "omgidl", kIdl);
        const auto ch =
            w.add_channel(schema, batch > 1 ? "/shapeform/states_batch" : "/shapeform/states", "cdr");
        const std::clock_t c0 = std::clock();
        for (std::size_t i = 0; i < n; ++i)
          w.write(ch, s.times[i], s.times[i], s.bytes.data() + s.offsets[i], s.offsets[i + 1] - s.offsets[i]);
        w.close();
        const double cpu_s = double(std::clock() - c0) / CLOCKS_PER_SEC;
        if (w.write_errors() != 0) throw std::runtime_error("write errors in " + file.string());
        const auto bytes = fs::file_size(file);
        fs::remove(file);
        std::printf("| %s | %s | %.2f | %.1f | %.0f | %.0f |\n",
                    batch > 1 ? "batches of 50" : "one per state", record::to_string(c), double(bytes) / 1e6,
                    double(bytes) / (double(agents) * seconds), cpu_s * 1e9 / double(n),
                    cpu_s * 1e9 / states);
        std::fflush(stdout);
      }
    }
    return 0;
  });
}

}  // namespace
}  // namespace shapeform

int main(int argc, char** argv) { return shapeform::run(argc, argv); }
