#!/usr/bin/python3
"""Plots delivery ratio and p99 data age against N from a benchmark results file.

usage: scripts/plot_bench.py [RESULTS_JSON] [--out PNG | --write-docs]

RESULTS_JSON defaults to the committed docs/figures/bench_results.json; the figure goes to PNG (default
runs/<UTC time>-bench/figures/bench_scaling.png), or with --write-docs to the committed
docs/figures/bench_scaling.png. Called by scripts/bench.sh. Needs Debian's python3-matplotlib.
"""
import argparse
import json
import math
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def series(rows, kind, rate, preset, group=None):
    pts = []
    for e in rows.values():
        r, a = e["row"], e["agg"]
        if r["kind"] != kind or r["rate"] != rate or r["preset"] != preset or r.get("stagger_s", 0):
            continue
        if group is not None and r.get("group") != group:
            continue
        if r.get("section") not in ("main", None):
            continue
        pts.append((r["n"], a.get("delivery"), a.get("age_p99_ms"), a.get("age_p99_worst_ms")))
    return sorted(pts)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                 usage="scripts/plot_bench.py [RESULTS_JSON] [--out PNG | --write-docs]")
    ap.add_argument("results", nargs="?", default=str(ROOT / "docs" / "figures" / "bench_results.json"))
    ap.add_argument("--out", help="the figure to write (default runs/<UTC time>-bench/figures/bench_scaling.png)")
    ap.add_argument("--write-docs", action="store_true", help="rewrite the committed docs/figures/bench_scaling.png")
    a = ap.parse_args()
    if a.out:
        out = Path(a.out)
    elif a.write_docs:
        out = ROOT / "docs" / "figures" / "bench_scaling.png"
    else:
        out = ROOT / "runs" / (time.strftime("%Y%m%dT%H%M%SZ", time.gmtime()) + "-bench") / "figures" / "bench_scaling.png"
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    store = json.loads(Path(a.results).read_text())
    rows = store.get("rows", {})
    main_presets = sorted({e["row"]["preset"] for e in rows.values() if e["row"].get("section") == "main"})
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
    styles = {"baseline": ("o", "--"), "agents": ("s", "-"), "group": ("^", "-.")}
    plotted = False
    for preset in main_presets:
        for kind in ("baseline", "agents", "group"):
            for rate in (20.0, 50.0):
                pts = series(rows, kind, rate, preset)
                if not pts:
                    continue
                plotted = True
                n = [p[0] for p in pts]
                marker, ls = styles[kind]
                label = f"{'agents, grouped' if kind == 'group' else kind} {rate:g} Hz" + (
                    f" ({preset})" if len(main_presets) > 1 else "")
                ax1.plot(n, [100 * p[1] if p[1] is not None else math.nan for p in pts], marker=marker, ls=ls,
                         label=label)
                ax2.plot(n, [p[2] if p[2] is not None else math.nan for p in pts], marker=marker, ls=ls, label=label)
    if not plotted:
        print("plot_bench: no main rows to plot", file=sys.stderr)
        return 1
    ax1.set_xlabel("agents N (processes unless grouped)")
    ax1.set_ylabel("delivery ratio, %")
    ax1.axhline(99, color="grey", lw=0.8, ls=":")
    ax1.text(10, 99.05, "target 99 %", color="grey", fontsize=8)
    ax1.set_title("State samples delivered (all-to-all)")
    ax2.set_xlabel("agents N (processes unless grouped)")
    ax2.set_ylabel("data age p99, ms (log)")
    ax2.set_yscale("log")
    ax2.axhline(100, color="grey", lw=0.8, ls=":")
    ax2.text(10, 110, "target at N=100: 100 ms", color="grey", fontsize=8)
    ax2.axhline(5, color="grey", lw=0.8, ls=":")
    ax2.text(10, 5.5, "target at N=25: 5 ms", color="grey", fontsize=8)
    ax2.set_title("Receive time minus sender stamp, p99")
    for ax in (ax1, ax2):
        ax.set_xscale("log")
        ax.set_xticks([10, 25, 50, 100])
        ax.get_xaxis().set_major_formatter(matplotlib.ticker.ScalarFormatter())
        ax.grid(True, which="both", alpha=0.3)
    ax2.legend(fontsize=7, loc="lower right")
    m = store.get("machine", {})
    commits = sorted({e.get("commit", "?") for e in rows.values() if e["row"].get("section") == "main"})
    fig.suptitle(f"shapeform on {m.get('host_cpus', '?')} CPUs ({m.get('cpu', '?')}), commit {', '.join(commits)}",
                 fontsize=9)
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    print(f"plot_bench: wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
