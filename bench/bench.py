#!/usr/bin/env python3
"""shapeform benchmark driver (run it through scripts/bench.sh).

Starts real processes on loopback, reads the figures the processes publish about themselves
(AgentStatus through shapeform_bench_probe, SwarmMetrics for convergence, the supervisor's JSON
summary) plus kernel counters (/proc), takes the median over runs, stores the results in
OUT/figures/bench_results.json and renders OUT/BENCHMARKS.md from that file. OUT is runs/<UTC time>-bench
unless given (--out; --write-docs: the committed docs/). Rows not run keep the results they have in the
committed docs/figures/bench_results.json.

Every run gets its own DDS domain (--domain-base upwards) and stops only the processes it started
(scripts/lib/shapeform_procs.py).
"""
from __future__ import annotations

import argparse
import dataclasses
import datetime as dt
import json
import signal
import sys
import time
from pathlib import Path

sys.dont_write_bytecode = True  # no __pycache__ beside the sources
sys.path.insert(0, str(Path(__file__).resolve().parent))
# The driver's parts, each importing only those before it: what to run, measuring, running, the report.
from bench_plan import (ROOT, SCENARIO_SETS, PlanError, lever_rows, main_rows, rerun_command, runs_of,  # noqa: E402
                        scale_rows, select_rows, timeouts_of, window_of)
from bench_measure import aggregate, git_commit, log, machine_info  # noqa: E402
from bench_run import Ctx, run_rows, sim_rows, wait_quiet  # noqa: E402
from bench_report import render, report_plan  # noqa: E402


def parse_args(argv=None) -> argparse.Namespace:
    """The command line, with OUT's defaults filled in (results, report, runs folder)."""
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter,
                                 usage="bench/bench.py [--quick] [--runs K] [--levers] [--only ROW]... [--row SPEC]... "
                                       "[--list] [--out DIR | --write-docs] [options]")
    ap.add_argument("--quick", action="store_true", help="1 run per row and short windows")
    ap.add_argument("--runs", type=int, help="runs per row (default 3; 1 with --quick)")
    ap.add_argument("--window", type=float, help="measurement window, s (default: max(30, 1100 ticks); 12 with --quick)")
    ap.add_argument("--only", action="append", default=[],
                    help="row id or prefix to run (repeatable); `sim`: the simulator rows; `leverK`: lever K's rows; "
                         "`scale`: the scale ladder (2000, 4000, 5000, 10000 agents and their baselines)")
    ap.add_argument("--row", action="append", default=[],
                    help="ad-hoc row KIND:N:RATE[:PRESET[:STAGGER_S[:GROUP[:FLAG]...]]], FLAG view (the browser view "
                         "beside), internal or ros2 (the agents drive robots: bench_plan.vehicle_sets) (stored, shown "
                         "under experiments)")
    ap.add_argument("--levers", action="store_true", help="also run the lever rows")
    ap.add_argument("--lever-runs", type=int, default=1, help="runs per lever row that is not a main row (default 1)")
    ap.add_argument("--no-main", action="store_true", help="skip the main rows")
    ap.add_argument("--no-scale", action="store_true", help="skip the scale ladder (2000 to 10000 agents)")
    ap.add_argument("--no-sim", action="store_true", help="skip the simulator rows")
    ap.add_argument("--build", default=str(ROOT / "build"), help="build directory (default build/)")
    ap.add_argument("--out", help="output folder (default runs/<UTC time>-bench)")
    ap.add_argument("--write-docs", action="store_true",
                    help="write into the committed docs/ (docs/BENCHMARKS.md, docs/figures/bench_results.json)")
    ap.add_argument("--runs-dir", help="where process logs and CSVs go (default OUT/runs; runs/bench with --write-docs)")
    ap.add_argument("--results", help="results file (default OUT/figures/bench_results.json)")
    ap.add_argument("--report", help="report file (default OUT/BENCHMARKS.md)")
    ap.add_argument("--domain-base", type=int, default=200, help="first DDS domain id (30 are used in turn)")
    ap.add_argument("--quiet-busy", type=float, default=15.0,
                    help="before each run wait until the host is at most this %% busy (default 15)")
    ap.add_argument("--quiet-wait", type=float, default=600.0, help="longest wait for a quiet host, s")
    ap.add_argument("--max-other-load", type=float, default=25.0,
                    help="repeat a run when other jobs used more than this %% of one core during its window (default 25)")
    ap.add_argument("--retries", type=int, default=2, help="how often a disturbed run is repeated (default 2)")
    ap.add_argument("--scenario", default="config/scenarios/arc_circle.yaml",
                    help="agents' and supervisor's config (default: the circle with the arc law, which converges at "
                         "every N; the paper law's circle cannot meet the convergence test's gap CV at N >= 50)")
    ap.add_argument("--render-only", action="store_true", help="only re-render the report from the results file")
    ap.add_argument("--list", action="store_true", help="list the row ids and exit")
    args = ap.parse_args(argv)
    docs = ROOT / "docs"
    out = docs if args.write_docs else Path(args.out or ROOT / "runs" / (
        time.strftime("%Y%m%dT%H%M%SZ", time.gmtime()) + "-bench")).resolve()
    args.results = args.results or str(out / "figures" / "bench_results.json")
    args.report = args.report or str(out / "BENCHMARKS.md")
    args.runs_dir = args.runs_dir or str(ROOT / "runs" / "bench" if out == docs else out / "runs")
    return args


def list_rows() -> int:
    for r in main_rows():
        print("main  ", r.id)
    for r in scale_rows():
        print("scale ", r.id)
    for r in lever_rows():
        print("lever ", r.id)
    print("sim    sim (every simulator row)")
    return 0


def load_store(results_path: Path) -> dict:
    """The results file, else the committed one: rows not run keep their stored results."""
    committed = ROOT / "docs" / "figures" / "bench_results.json"
    seed = results_path if results_path.exists() else committed
    store = json.loads(seed.read_text()) if seed.exists() else {}
    results_path.parent.mkdir(parents=True, exist_ok=True)
    store.setdefault("rows", {})
    store.setdefault("sim", {})
    return store


def save(store: dict, results_path: Path) -> None:
    results_path.write_text(json.dumps(store, indent=1, default=str))


def render_only(store: dict, results_path: Path, report: Path) -> int:
    """The stored runs, aggregated by the current code, and the report from them."""
    for e in store["rows"].values():
        e["agg"] = aggregate(e["runs"])
    save(store, results_path)
    render(store, report, report_plan(store))
    return 0


def make_ctx(args, bindir: Path) -> Ctx:
    return Ctx(bin=bindir, runs_dir=Path(args.runs_dir), window_s=0, disc_timeout_s=60 if not args.quick else 40,
               conv_timeout_s=60 if not args.quick else 40, scenario=(ROOT / args.scenario).resolve(),
               scenario_sets=SCENARIO_SETS, status_rate_hz=2.0, domain_base=args.domain_base,
               quiet_busy=args.quiet_busy / 100, quiet_wait_s=args.quiet_wait, max_other_pct=args.max_other_load,
               retries=args.retries)


def main(argv=None) -> int:
    args = parse_args(argv)

    # Ctrl-C or SIGTERM: unwind so that run_once stops the processes it started (ours only).
    def interrupted(signum, frame):
        raise KeyboardInterrupt(f"signal {signum}")
    signal.signal(signal.SIGINT, interrupted)
    signal.signal(signal.SIGTERM, interrupted)

    if args.list:
        return list_rows()
    results_path, report = Path(args.results), Path(args.report)
    store = load_store(results_path)
    if args.render_only:
        return render_only(store, results_path, report)

    bindir = Path(args.build).resolve() / "bin"
    ctx = make_ctx(args, bindir)
    try:
        selected, run_sim = select_rows(args, store["rows"])
    except PlanError as e:
        print(f"bench: {e}", file=sys.stderr)
        return 2
    needed = ["shapeform_agent", "shapeform_supervisor", "shapeform_bench_baseline", "shapeform_bench_probe"]
    needed += ["shapeform_vehicle"] if any(r.vehicle == "ros2" for r in selected) else []
    for exe in needed:
        if not (bindir / exe).exists():
            print(f"bench: {bindir / exe} missing: run ./scripts/build.sh first", file=sys.stderr)
            return 2

    store["machine"] = machine_info()
    store["commit"] = git_commit()
    store["date"] = dt.datetime.now().isoformat(timespec="seconds")
    store.pop("quick", None)  # per row since rows of several invocations share the file
    runs = args.runs or (1 if args.quick else 3)
    for row in selected:
        n_runs = runs_of(row, args, runs)
        ctx.window_s = window_of(row, args)
        ctx.disc_timeout_s, ctx.conv_timeout_s = timeouts_of(row, args.quick)
        run_rows(ctx, [row], n_runs, store["rows"])
        store["rows"][row.id]["row"]["section"] = row.section
        store["rows"][row.id]["command"] = rerun_command(row, args, n_runs)
        store["rows"][row.id]["quick"] = bool(args.quick)
        results_path.parent.mkdir(parents=True, exist_ok=True)
        save(store, results_path)
        render(store, report, report_plan(store))  # partial results stay readable
    if run_sim:
        # Each call waits (up to two minutes) for a quiet host, as the agent rows do.
        sim_ctx = dataclasses.replace(ctx, quiet_wait_s=min(ctx.quiet_wait_s, 120.0))
        store["sim"] = sim_rows(bindir, args.quick, before=lambda: wait_quiet(sim_ctx))
        store["sim"]["commit"] = git_commit()
        store["sim"]["quick"] = bool(args.quick)
        save(store, results_path)
    render(store, report, report_plan(store))
    log(f"wrote {args.report} and {results_path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
