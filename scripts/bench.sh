#!/usr/bin/env bash
# Benchmarks shapeform on this host and writes BENCHMARKS.md, figures/bench_results.json and
# figures/bench_scaling.png into an output folder (default runs/<UTC time>-bench; with --write-docs the
# committed docs/BENCHMARKS.md and docs/figures/bench_*):
#  - agents (one process each, or grouped) against a bare Fast DDS pub/sub baseline with the same payload,
#    transport and rate, N = 10, 25, 50, 100 (20 Hz; 50 Hz for N <= 25);
#  - how far one host goes: 2000, 4000, 5000 and 10000 agents in 10 shapeform_agent_group processes, each beside
#    its bare grouped baseline (run alone: --only scale; skip with --no-scale); a large row waits longer
#    for discovery and convergence (bench_plan.timeouts_of);
#  - the transport levers, measured one at a time (--levers);
#  - agents driving robots over ROS 2 (one shapeform_vehicle for the N robots) beside agents integrating
#    the same robot themselves, N = 12 and 50: control latency p50/p99 and CPU per agent (--only lever16);
#  - simulator throughput (build/bin/shapeform_bench_sim), N = 100, 1000, 10000, against the core's peak
#    multiply-add rate (run alone: --only sim).
# Rows not run keep their committed results (docs/figures/bench_results.json), so a partial run renders
# a whole report. Run ./scripts/build.sh first. All DDS traffic stays on loopback (domains 200..229 by
# default). The kernel's socket limits (net.core.rmem_max) are read and reported, never changed.
#
# Usage: scripts/bench.sh [--quick] [--runs K] [--levers] [--only ROW_ID]... [--row SPEC]... [--list]
#                         [--out DIR | --write-docs] [--help]
#   --quick       1 run per row, 12 s windows (minutes instead of about an hour; lateness then includes start-up)
#   --levers      also run the lever rows (socket buffers, multicast, announcement period, stagger, grouping,
#                 robots over ROS 2, ...)
#   --only ROW    run only this row (or id prefix; `sim`: the simulator rows; `leverK`: lever K's rows, e.g.
#                 lever16: agents driving robots over ROS 2 beside the internal model; `scale`: the scale
#                 ladder), keep the stored
#                 others, re-render the report
#   --list        list the row ids
#   --out DIR     the output folder
#   --write-docs  rewrite the committed docs/BENCHMARKS.md and docs/figures/bench_*
# Every other option is bench/bench.py's (bench/bench.py --help). Environment: BUILD_DIR (default build).
set -euo pipefail
cd "$(dirname "$0")/.."
build="${BUILD_DIR:-build}"
case " $* " in
  *" -h "*|*" --help "*) sed -n '2,/^set -euo/{/^set -euo/d;s/^# \{0,1\}//;p}' "$0"; exit 0 ;;
esac
for a in "$@"; do
  case "$a" in --list|--render-only) exec /usr/bin/python3 bench/bench.py --build "$build" "$@" ;; esac
done
if [ ! -x "$build/bin/shapeform_agent" ] || [ ! -x "$build/bin/shapeform_bench_probe" ]; then
  echo "bench.sh: $build/bin has no shapeform_agent/shapeform_bench_probe: run ./scripts/build.sh first" >&2
  exit 2
fi
out="" args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --out) [ $# -ge 2 ] || { echo "bench.sh: --out: missing value" >&2; exit 2; }; out=$2; shift 2 ;;
    --write-docs) out=docs; shift ;;
    *) args+=("$1"); shift ;;
  esac
done
[ -n "$out" ] || out="runs/$(date -u +%Y%m%dT%H%M%SZ)-bench"
/usr/bin/python3 bench/bench.py --build "$build" --out "$out" "${args[@]+"${args[@]}"}"
/usr/bin/python3 scripts/plot_bench.py "$out/figures/bench_results.json" --out "$out/figures/bench_scaling.png"
