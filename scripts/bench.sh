#!/usr/bin/env bash
# Benchmarks shapeform on this host and regenerates docs/BENCHMARKS.md and docs/figures/bench_*.png:
#  - agents (one process each, or grouped) against a bare Fast DDS pub/sub baseline with the same payload,
#    transport and rate, N = 10, 25, 50, 100 (20 Hz; 50 Hz for N <= 25);
#  - the transport levers, measured one at a time (--levers);
#  - simulator throughput (build/bin/shapeform_bench_sim), N = 100, 1000, 10000.
# Run ./scripts/build.sh first. All DDS traffic stays on loopback (domains 200..229 by default).
# The kernel's socket limits (net.core.rmem_max) are read and reported, never changed.
#
# Usage: scripts/bench.sh [--quick] [--runs K] [--levers] [--only ROW_ID]... [--row SPEC]... [--list] [--help]
#   --quick       1 run per row, 12 s windows (minutes instead of about an hour; lateness then includes start-up)
#   --levers      also run the lever rows (socket buffers, multicast, announcement period, stagger, grouping)
#   --only ROW    run only this row (or id prefix), keep the stored others, re-render the report
#   --list        list the row ids
# Environment: BUILD_DIR (default build).
set -euo pipefail
cd "$(dirname "$0")/.."
build="${BUILD_DIR:-build}"
for a in "$@"; do
  case "$a" in -h|--help|--list|--render-only) exec /usr/bin/python3 bench/bench.py --build "$build" "$@" ;; esac
done
if [ ! -x "$build/bin/shapeform_agent" ] || [ ! -x "$build/bin/shapeform_bench_probe" ]; then
  echo "bench.sh: $build/bin has no shapeform_agent/shapeform_bench_probe: run ./scripts/build.sh first" >&2
  exit 2
fi
/usr/bin/python3 bench/bench.py --build "$build" "$@"
/usr/bin/python3 scripts/plot_bench.py docs/figures/bench_results.json docs/figures/bench_scaling.png
