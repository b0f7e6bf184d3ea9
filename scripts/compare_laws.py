#!/usr/bin/python3
"""Compares the paper's law and the arc law on the same starts; writes LAW_COMPARISON.md and
figures/law_comparison.png into an output folder (default runs/<UTC time>-laws; --write-docs: the
committed docs/). Simulator runs for every shape and N = 2, 3, 12, 50, 200; agent-process runs (through
scripts/launch_swarm.sh) for a few shapes unless --no-distributed.

  scripts/compare_laws.py [--build build] [--quick] [--no-distributed] [--out DIR | --write-docs]
"""
import argparse
import datetime
import json
import math
import os
import sys
import time

sys.dont_write_bytecode = True  # no __pycache__ in scripts/
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "lib"))
import shapeform_procs as procs  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SHAPES = [  # name, scenario file, overrides giving the shape
    ("circle", "circle", []),
    ("ellipse", "ellipse", []),
    ("square", "square", []),
    ("line", "line", []),
    ("polar star", "polar_star", []),
    ("polygon", "polygon", []),
    ("implicit", "implicit", []),
    ("parametric, closed", "polygon", ["--set", "shape.kind=parametric", "--set", "shape.x_expr=4*cos(2*_pi*s)",
                                       "--set", "shape.y_expr=2*sin(2*_pi*s)+sin(6*_pi*s)", "--set", "shape.closed=true"]),
    ("parametric, open", "polygon", ["--set", "shape.kind=parametric", "--set", "shape.x_expr=8*s-4",
                                     "--set", "shape.y_expr=2*sin(2*_pi*s)", "--set", "shape.closed=false"]),
    ("polygon, open", "polygon", ["--set", "shape.closed=false"]),
]
SIZES = [2, 3, 12, 50, 200]


def sim(build, scenario, law, n, steps, seed, extra=()):
    cmd = [os.path.join(build, "bin", "shapeform_sim"), "--config", os.path.join(ROOT, "config", "scenarios", scenario + ".yaml"),
           "--agents", str(n), "--seed", str(seed), "--steps", str(steps), "--set", "dynamics.law=" + law,
           "--outline", "400", *extra]
    return json.loads(procs.run(cmd).stdout)


def launch(build, scenario, law, n, steps, seed, domain, rate, runs):
    cmd = [os.path.join(ROOT, "scripts", "launch_swarm.sh"), "-n", str(n), "--scenario", scenario, "--seed", str(seed),
           "--steps", str(steps), "--json", "--domain", str(domain), "--build", build, "--timeout", "300",
           "--rate", str(rate),
           "--set", "dynamics.law=" + law, "--runs", runs]
    p = procs.run(cmd, check=False)
    summary = procs.summary(p.stdout)
    if summary is None:
        raise RuntimeError(f"launch {scenario} {law} n={n} failed (exit {p.returncode}): {p.stderr[-2000:]}")
    return summary


def process_rate(n):
    """Agent loop rate for n processes: 50 Hz, or 20 Hz from 50 agents (all-to-all at 50 Hz would fill
    the 2-core host, docs/BENCHMARKS.md)."""
    return 50 if n < 50 else 20


def size_of(result, name):
    # The shape's size: radius-like. Read from the scenario via the sim's positions is not possible, so
    # use the known sizes of the scenario files.
    return {"circle": 4.0, "ellipse": 4.0, "square": 5.0, "line": 1.0, "polar star": 5.0, "polygon": 5.0,
            "implicit": 4.0, "parametric, closed": 4.0, "parametric, open": 4.0, "polygon, open": 5.0}[name]


def dash(v):
    return "–" if v is None else str(v)


def fmt(v, spec=".2e"):
    return "–" if v is None else format(v, spec)


def verdicts(r, name, law):
    size = size_of(r, name)
    ok_err = r["curve_error_mean"] is not None and r["curve_error_mean"] <= 1e-3 * size
    uni = r["arc_gap_cv"]
    ok_uni = uni is not None and uni <= 0.01
    ok_still = r["max_step"] <= 1e-4 * size
    return ok_err, ok_uni, ok_still


def parse_args():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                 usage="scripts/compare_laws.py [--build build] [--quick] [--no-distributed] "
                                       "[--out DIR | --write-docs]")
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--quick", action="store_true", help="fewer sizes and steps")
    ap.add_argument("--no-distributed", action="store_true", help="simulator only")
    ap.add_argument("--out", help="output folder (default runs/<UTC time>-laws)")
    ap.add_argument("--write-docs", action="store_true", help="write into the committed docs/ instead")
    return ap.parse_args()


def run_shapes(build, sizes, steps, seed):
    """Every shape at every size with both laws in the simulator: the rows [(shape, N, law, summary)] and
    the final formations to draw {(shape, N, law): (positions, outline)}."""
    rows = []
    finals = {}
    for name, scen, extra in SHAPES:
        for n in sizes:
            for law in ("paper", "arc"):
                print(f"compare_laws: sim {name:10s} N={n:3d} {law}", file=sys.stderr, flush=True)
                r = sim(build, scen, law, n, steps, seed, extra)
                rows.append((name, n, law, r))
                if n == 12 or (n == 50 and name in ("circle", "square")):
                    finals[(name, n, law)] = (r["final_positions"], r["outline"])
    return rows, finals


def run_tracking(build, seed):
    """Tracking with feed-forward on both paths: [(scenario, law, summary)]."""
    track_rows = []
    for scen in ("track_line_ff", "track_circle_ff"):
        for law in ("paper", "arc"):
            r = sim(build, scen, law, 10, 200, seed)
            track_rows.append((scen, law, r))
    return track_rows


def run_distributed(build, seed, runs):
    """A few shapes on agent processes (through the launcher, their logs in `runs`) and in the simulator:
    [(shape, N, law, processes' summary, simulator's summary)]."""
    dist_rows = []
    domain = 160
    for name, scen, n in (("circle", "circle", 12), ("polar star", "polar_star", 12), ("square", "square", 25),
                          ("circle", "circle", 50)):
        for law in ("paper", "arc"):
            print(f"compare_laws: agents {name} N={n} {law}", file=sys.stderr, flush=True)
            d = launch(build, scen, law, n, 300, seed, domain, process_rate(n), runs)
            domain += 1
            s = sim(build, scen, law, n, 300, seed)
            dist_rows.append((name, n, law, d, s))
    return dist_rows


def report(quick, steps, seed, rows, track_rows, dist_rows):
    """The lines of LAW_COMPARISON.md."""
    out = []
    out.append("# The paper's law against the arc law\n")
    out.append(f"Generated by `scripts/compare_laws.py{' --quick' if quick else ''}` on "
               f"{datetime.datetime.utcnow():%Y-%m-%d %H:%M} UTC. Same starts for both laws (seed {seed}, uniform "
               f"in [-5,5]^2), Euler dt = 1, {steps} iterations; the arc law with its defaults "
               "(k_normal 0.5, k_tangent 1, spacing 1). The law is explained in [LAW.md](LAW.md).\n")
    out.append("The arc law's acceptance criteria: curve error (distance to the true closest point) mean <= 1e-3 "
               "of the shape's size; arc-length gap CV <= 0.01 (closed curves; on the line a row of fixed "
               "length); largest per-step displacement at the end <= 1e-4 of the size; settling no slower "
               "than the paper's law.\n")
    out.append("| shape | N | law | curve error mean | arc gap CV | gap CV (Euclidean) | max step | min separation | extent | settle step | criteria |")
    out.append("|---|---|---|---|---|---|---|---|---|---|---|")
    for name, n, law, r in rows:
        e, u, st = verdicts(r, name, law)
        crit = "met" if (e and u and st) else "not met (" + ", ".join(
            w for w, ok in (("error", e), ("spacing", u), ("still", st)) if not ok) + ")"
        out.append(f"| {name} | {n} | {law} | {fmt(r['curve_error_mean'])} | {fmt(r['arc_gap_cv'])} | "
                   f"{fmt(r['gap_cv'], '.3f')} | {fmt(r['max_step'])} | {fmt(r['min_separation'], '.3f')} | "
                   f"{fmt(r['extent'], '.2f')} | {dash(r['settle_step'])} | {crit} |")
    out.append("\n## Tracking with feed-forward (10 agents, r0 = 2, step 200)\n")
    out.append("| path | law | centroid error | ring error | gap CV |")
    out.append("|---|---|---|---|---|")
    for scen, law, r in track_rows:
        out.append(f"| {scen.replace('track_', '').replace('_ff', '')} | {law} | {fmt(r['centroid_error'], '.4f')} | "
                   f"{fmt(r['ring_error'], '.4f')} | {fmt(r['gap_cv'], '.3f')} |")
    if dist_rows:
        out.append("\n## On agent processes (loopback, free running at 50 Hz, 20 Hz for 50 agents; 300 iterations) "
                   "against the simulator, same starts\n")
        out.append("| shape | N | law | agents: curve error | sim: curve error | agents: arc gap CV | sim: arc gap CV | agents: settle | sim: settle |")
        out.append("|---|---|---|---|---|---|---|---|---|")
        for name, n, law, d, s in dist_rows:
            out.append(f"| {name} | {n} | {law} | {fmt(d.get('curve_error_mean'))} | {fmt(s['curve_error_mean'])} | "
                       f"{fmt(d.get('arc_gap_cv'))} | {fmt(s['arc_gap_cv'])} | {dash(d.get('settle_step'))} | "
                       f"{dash(s['settle_step'])} |")
    out.append("\n![final formations of both laws](figures/law_comparison.png)\n")
    return out


def plot(finals, path):
    """The final formations of both laws from the same starts, the commanded shape dashed."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    keys = [("circle", 12), ("ellipse", 12), ("square", 12), ("polar star", 12), ("polygon", 12), ("implicit", 12),
            ("circle", 50), ("square", 50)]
    keys = [k for k in keys if (k[0], k[1], "paper") in finals]
    fig, axes = plt.subplots(2, len(keys), figsize=(2.6 * len(keys), 5.6))
    for c, (name, n) in enumerate(keys):
        for r, law in enumerate(("paper", "arc")):
            ax = axes[r][c]
            pts, outline = finals[(name, n, law)]
            ax.plot([p[0] for p in outline], [p[1] for p in outline], "--", color="0.55", lw=1)
            ax.plot([p[0] for p in pts], [p[1] for p in pts], "o", ms=3 if n > 20 else 5,
                    color="tab:red" if law == "paper" else "tab:blue")
            # The same frame for both laws: the shape and every agent of either run.
            both = finals[(name, n, "paper")][0] + finals[(name, n, "arc")][0] + outline
            xs, ys = [p[0] for p in both], [p[1] for p in both]
            m = 0.08 * max(max(xs) - min(xs), max(ys) - min(ys))
            ax.set_xlim(min(xs) - m, max(xs) + m)
            ax.set_ylim(min(ys) - m, max(ys) + m)
            ax.set_aspect("equal")
            ax.set_title(f"{name}, N={n}\n{law} law", fontsize=8)
            ax.tick_params(labelsize=6)
    fig.suptitle("Final formations from the same starts: the paper's law (top) and the arc law (bottom); "
                 "the commanded shape dashed")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main():
    args = parse_args()
    build = os.path.abspath(args.build)
    out_dir = (os.path.join(ROOT, "docs") if args.write_docs else
               os.path.abspath(args.out or os.path.join(ROOT, "runs", time.strftime("%Y%m%dT%H%M%SZ", time.gmtime())
                                                        + "-laws")))
    os.makedirs(os.path.join(out_dir, "figures"), exist_ok=True)
    sizes = [2, 3, 12, 50] if args.quick else SIZES
    steps = 300 if args.quick else 1000
    seed = 1
    rows, finals = run_shapes(build, sizes, steps, seed)
    track_rows = run_tracking(build, seed)
    dist_rows = []
    if not args.no_distributed:
        runs = os.path.join(out_dir, "swarm-runs") if not args.write_docs else os.path.join(build, "compare-runs")
        dist_rows = run_distributed(build, seed, runs)
    with open(os.path.join(out_dir, "LAW_COMPARISON.md"), "w") as f:
        f.write("\n".join(report(args.quick, steps, seed, rows, track_rows, dist_rows)) + "\n")
    plot(finals, os.path.join(out_dir, "figures", "law_comparison.png"))
    print(f"compare_laws: wrote {out_dir}/LAW_COMPARISON.md and {out_dir}/figures/law_comparison.png", file=sys.stderr)


if __name__ == "__main__":
    main()
