#!/usr/bin/python3
"""Draws the paper's figures from what scripts/paper/run.py recorded (the supervisor's and the
simulator's CSV files) as paper_*.png. Debian's python3-matplotlib and numpy only.

  scripts/plot_paper.py --data DIR [--out DIR | --write-docs]

Default output: DATA/figures; --write-docs: the committed docs/figures.
"""
import argparse
import json
import math
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.dont_write_bytecode = True  # no __pycache__ in scripts/
sys.path.insert(0, str(Path(__file__).resolve().parent / "paper"))
import analyse as P  # noqa: E402
import experiments as E  # noqa: E402

DIST_C, SIM_C, ASYNC_C = "tab:blue", "tab:orange", "0.6"
SNAP_COLOURS = ["#1b9e77", "#d95f02", "#7570b3", "#e7298a", "#66a61e"]


def shape_curve(shape, centre=(0.0, 0.0), span=None):
    """Points of a target shape for drawing (dashed)."""
    k = shape["kind"]
    t = np.linspace(0, 2 * np.pi, 400)
    if k == "circle":
        return centre[0] + shape["r0"] * np.cos(t), centre[1] + shape["r0"] * np.sin(t)
    if k == "ellipse":
        return centre[0] + shape["a"] * np.cos(t), centre[1] + shape["b"] * np.sin(t)
    if k == "square":
        a = shape["a"]
        return np.array([a, -a, -a, a, a]) + centre[0], np.array([a, a, -a, -a, a]) + centre[1]
    lo, hi = span
    x = np.linspace(lo, hi, 2)
    return x, shape["m"] * x + shape["c"]


def trajectories(pos):
    """agent -> (steps, xs, ys) from step -> {agent: (x, y)}."""
    out = {}
    for k in sorted(pos):
        for i, (x, y) in pos[k].items():
            o = out.setdefault(i, ([], [], []))
            o[0].append(k)
            o[1].append(x)
            o[2].append(y)
    return out


def agent_colours(n):
    cm = plt.get_cmap("tab20" if n > 10 else "tab10")
    return [cm(i % cm.N) for i in range(n)]


def draw_formation(ax, pos, shape, K, title, centre=(0.0, 0.0), start=None):
    tr = trajectories({k: v for k, v in pos.items() if k <= K})
    cols = agent_colours(max(tr) + 1 if tr else 1)
    xs_all, ys_all = [], []
    for i, (_, xs, ys) in sorted(tr.items()):
        ax.plot(xs, ys, "-", lw=0.7, color=cols[i], alpha=0.7)
        xs_all += xs
        ys_all += ys
    fin = P.at_step(pos, K)
    if fin:
        for i, (x, y) in fin.items():
            ax.plot(x, y, "o", ms=6, color=cols[i], mec="k", mew=0.6, zorder=5)
    if start:
        ax.plot([p[0] for p in start], [p[1] for p in start], "x", ms=4, color="0.4", zorder=4)
    span = (min(xs_all + [-6]) - 1, max(xs_all + [6]) + 1)
    cx, cy = shape_curve(shape, centre, span)
    ax.plot(cx, cy, "k--", lw=1.0, zorder=3)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_title(title, fontsize=9)
    ax.tick_params(labelsize=7)
    ax.grid(alpha=0.3)


def read_start(path):
    return [tuple(map(float, line.split(","))) for line in open(path) if line.strip()]


def shape_runs(data):
    """(column, shape, loaded run) of each shape experiment that ran."""
    for j, s in enumerate(("line", "circle", "ellipse", "square")):
        r = load(data, f"shape_{s}")
        if r:
            yield j, s, r


def load(data, name):
    d = data / name
    if not (d / "dist" / "summary.json").exists():
        return None
    return {
        "dir": d,
        "start": read_start(d / "start.csv"),
        "sim_series": P.load_series(d / "sim", "sim"),
        "dist_series": P.load_series(d / "dist", "dist"),
        "sim_pos": P.load_positions(d / "sim", "sim"),
        "dist_pos": P.load_positions(d / "dist", "dist"),
        "async": json.loads((d / "async.json").read_text()) if (d / "async.json").exists() else None,
    }


def save(fig, out, name):
    fig.savefig(out / name, dpi=110)
    plt.close(fig)
    print(f"wrote {out / name}")


# ---------------------------------------------------------------------------------------------


def fig1(data, out, K):
    fig, axs = plt.subplots(2, 4, figsize=(15, 7.6))
    for j, s, r in shape_runs(data):
        for i, (kind, lab) in enumerate((("dist", "agent processes"), ("sim", "simulator"))):
            ser = r[f"{kind}_series"]
            m = P.at_step(ser, K)
            draw_formation(axs[i, j], r[f"{kind}_pos"], E.SHAPE[s], K,
                           f"{s}, {lab}, step {K}\nshape error {P.fmt(m['shape_error_mean'])}, gap CV "
                           f"{P.fmt(m['gap_cv'])}", start=r["start"])
    fig.suptitle("Fig. 1 analogue: 12 agents, final formation (dots), trajectories (lines), start (x), target "
                 "shape (dashed)", fontsize=11)
    fig.tight_layout()
    save(fig, out, "paper_fig1_formations.png")


def fig2(data, out, K, agent=0):
    fig, axs = plt.subplots(1, 3, figsize=(15, 4))
    for j, s in enumerate(("line", "circle", "square")):
        r = load(data, f"shape_{s}")
        if not r:
            continue
        ax = axs[j]
        for kind, c1, c2, lw, lab in (("sim", "lightsalmon", "lightskyblue", 2.2, "simulator"),
                                      ("dist", "tab:red", "tab:blue", 1.0, "processes")):
            tr = trajectories(r[f"{kind}_pos"]).get(agent)
            if not tr:
                continue
            ax.plot(tr[0], tr[1], "-", color=c1, lw=lw, label=f"x1 ({lab})")
            ax.plot(tr[0], tr[2], "-", color=c2, lw=lw, label=f"x2 ({lab})")
        ax.set_xlim(0, K)
        ax.set_title(f"{s}: agent {agent}", fontsize=10)
        ax.set_xlabel("iteration")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle("Fig. 2 analogue: one agent's position components against time, agent processes (dark) and "
                 "simulator (light) from the same start, in lockstep the same curves\n(the wiggle is Euler dt=1 "
                 "chatter; the resting ring slowly turns, in the simulator as in the processes)",
                 fontsize=11)
    fig.tight_layout()
    save(fig, out, "paper_fig2_agent_states.png")


def fig3(data, out, Kr):
    steps = sorted({200, Kr})
    cols = [(rr, k) for rr in ("r0", "r01") for k in steps]
    fig, axs = plt.subplots(2, len(cols), figsize=(3.8 * len(cols), 7.4))
    axs = np.atleast_2d(axs)
    for i, s in enumerate(("ellipse", "square")):
        for j, (rr, k) in enumerate(cols):
            r = load(data, f"rep_{s}_{rr}")
            ax = axs[i, j]
            if not r:
                continue
            cx, cy = shape_curve(E.SHAPE[s])
            ax.plot(cx, cy, "k--", lw=1.0)
            sp, dp = P.at_step(r["sim_pos"], k), P.at_step(r["dist_pos"], k)
            ax.plot([p[0] for p in dp.values()], [p[1] for p in dp.values()], "o", ms=7, color=DIST_C, alpha=0.8,
                    label="processes")
            ax.plot([p[0] for p in sp.values()], [p[1] for p in sp.values()], "o", ms=10, mfc="none", mec=SIM_C,
                    mew=1.4, label="simulator")
            md, ms_ = P.at_step(r["dist_series"], k), P.at_step(r["sim_series"], k)

            def g(v):
                return "undefined" if v is None else P.fmt(v)

            ax.set_title(f"{s}, r={'0' if rr == 'r0' else '0.1'}, step {k}\ngap CV {g(md['gap_cv'])} / "
                         f"{g(ms_['gap_cv'])}, clusters {P.fmt(md['clusters'])} / {P.fmt(ms_['clusters'])}",
                         fontsize=9)
            ax.set_aspect("equal", adjustable="datalim")
            ax.grid(alpha=0.3)
            ax.tick_params(labelsize=7)
            if i == 0 and j == 0:
                ax.legend(fontsize=7, loc="lower left")
    fig.suptitle("Fig. 3 analogue: without (r=0) and with (r=0.1) nearest-neighbour repulsion, 12 agents\n"
                 "(values: processes / simulator; clusters at link 0.05; without repulsion the agents pile up "
                 "in clumps, and by step 1000 all 12 sit on one point: gap CV undefined)", fontsize=11)
    fig.tight_layout()
    save(fig, out, "paper_fig3_repulsion.png")


def track_panel(ax, r, kind, track, title, agent=0):
    pos = r[f"{kind}_pos"]
    ser = r[f"{kind}_series"]
    tr = trajectories({k: v for k, v in pos.items() if k <= 200}).get(agent)
    if tr:
        ax.plot(tr[1], tr[2], "-", color="0.3", lw=0.9, label=f"agent {agent}")
    # the centre's path
    ts = np.linspace(0, 200, 201)
    cs = [centre(track, t) for t in ts]
    ax.plot([c[0] for c in cs], [c[1] for c in cs], ":", color="k", lw=0.8)
    for t, col in zip(E.SNAPSHOTS, SNAP_COLOURS):
        p = P.at_step(pos, t)
        c = centre(track, t)
        ax.plot([q[0] for q in p.values()], [q[1] for q in p.values()], "o", ms=4.5, color=col, label=f"t={t}")
        ax.plot(c[0], c[1], "o", ms=9, mfc="none", mec=col, mew=1.6)
        th = np.linspace(0, 2 * np.pi, 100)
        ax.plot(c[0] + 2 * np.cos(th), c[1] + 2 * np.sin(th), "--", color=col, lw=0.6, alpha=0.7)
    m = P.at_step(ser, 200)
    ax.set_title(f"{title}\nt=200: centroid error {P.fmt(m['centroid_error'])}, ring error "
                 f"{P.fmt(m['ring_error'])}", fontsize=9)
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(alpha=0.3)
    ax.tick_params(labelsize=7)


def centre(track, t):
    if track["path"] == "fixed":
        return track["point"]
    if track["path"] == "line":
        return (track["point"][0] + t * track["velocity"][0], track["point"][1] + t * track["velocity"][1])
    a = 2 * math.pi * t / track["period"]
    return (track["radius"] * math.cos(a), track["radius"] * math.sin(a))


def fig_track(data, out, path, variants, fname, title):
    fig, axs = plt.subplots(2, len(variants), figsize=(5.2 * len(variants), 10))
    axs = np.atleast_2d(axs)
    for j, (name, lab) in enumerate(variants):
        r = load(data, name)
        if not r:
            continue
        for i, (kind, klab) in enumerate((("dist", "agent processes"), ("sim", "simulator"))):
            track_panel(axs[i, j], r, kind, E.TRACK_PATH[path], f"{lab}: {klab}")
    axs[0, 0].legend(fontsize=7, loc="best")
    fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    save(fig, out, fname)


def band(ax, asy, key, K, color=ASYNC_C, label=None):
    if not asy or not asy["async"]:
        return
    arr = np.array([[np.nan if v is None else v for v in d[key][:K + 1]] for d in asy["async"]], float)
    if np.all(np.isnan(arr)):
        return
    lo, hi = np.nanmin(arr, axis=0), np.nanmax(arr, axis=0)
    ax.fill_between(np.arange(len(lo)), lo, hi, color=color, alpha=0.35, lw=0, label=label)


def series_xy(ser, key, K):
    ks = [k for k in sorted(ser) if k <= K]
    return ks, [np.nan if ser[k].get(key) is None else ser[k][key] for k in ks]


def fig_convergence(data, out, K):
    fig, axs = plt.subplots(2, 4, figsize=(16, 7))
    for j, s, r in shape_runs(data):
        for i, (key, lab) in enumerate((("shape_error_mean", "shape error (mean)"), ("gap_cv", "gap CV"))):
            ax = axs[i, j]
            band(ax, r["async"], key, K, label="model, asynchronous ticks (10 phasings)")
            ax.plot(*series_xy(r["dist_series"], key, K), "-", color=DIST_C, lw=1.2, label="agent processes")
            ax.plot(*series_xy(r["sim_series"], key, K), "--", color=SIM_C, lw=1.2, label="simulator (same start)")
            ax.set_yscale("log")
            ax.set_title(f"{s}: {lab}", fontsize=10)
            ax.set_xlabel("iteration")
            ax.grid(alpha=0.3, which="both")
            ax.set_xlim(0, K)
    axs[0, 0].legend(fontsize=7)
    fig.suptitle("Shape error and gap CV against time, 12 agents: processes vs simulator from the same start; grey: "
                 "the same law with the processes' schedule (each agent ticks at its own phase)", fontsize=11)
    fig.tight_layout()
    save(fig, out, "paper_convergence.png")


def fig_tracking_errors(data, out):
    cases = [("line", "paper start", ["track_line_paper", "track_line_ff", "track_line_fixed"]),
             ("line", "start around C(0)", ["track_line_ff_near", "track_line_fixed_near"]),
             ("circle", "paper start", ["track_circle_paper", "track_circle_ff", "track_circle_fixed"])]
    colours = {"paper": "tab:red", "ff": "tab:blue", "fixed": "tab:green"}
    fig, axs = plt.subplots(2, 3, figsize=(16, 8))
    for j, (path, lab, names) in enumerate(cases):
        for i, (key, klab) in enumerate((("centroid_error", "centroid error"), ("ring_error", "ring error"))):
            ax = axs[i, j]
            for name in names:
                r = load(data, name)
                if not r:
                    continue
                v = "paper" if "paper" in name else ("ff" if "_ff" in name else "fixed")
                vlab = {"paper": "paper law", "ff": "feed-forward", "fixed": "fixed centre C(0)"}[v]
                ax.plot(*series_xy(r["dist_series"], key, 200), "-", color=colours[v], lw=1.3,
                        label=f"{vlab}, processes")
                ax.plot(*series_xy(r["sim_series"], key, 200), "--", color=colours[v], lw=1.0,
                        label=f"{vlab}, simulator")
            for t in E.SNAPSHOTS:
                ax.axvline(t, color="0.85", lw=0.6, zorder=0)
            ax.set_yscale("log")
            ax.set_title(f"{path} path, {lab}: {klab}", fontsize=10)
            ax.set_xlabel("iteration")
            ax.set_xlim(0, 200)
            ax.grid(alpha=0.3, which="both")
            if i == 0:
                ax.legend(fontsize=7)
    fig.suptitle("Tracking, 10 agents, r0=2: errors against time (solid: processes, dashed: simulator)",
                 fontsize=11)
    fig.tight_layout()
    save(fig, out, "paper_tracking_errors.png")


def fig_limits(data, out):
    ld = data / "limits"
    if not (ld / "circle_n20_summary.json").exists():
        return
    fig, axs = plt.subplots(2, 3, figsize=(16, 10))
    for ax, n in ((axs[0, 0], 20), (axs[0, 1], 50)):
        pos = P.load_positions_csv(ld / f"circle_n{n}_positions.csv")
        j = json.loads((ld / f"circle_n{n}_summary.json").read_text())
        draw_formation(ax, pos, E.SHAPE["circle"], 500,
                       f"circle r0=4, {n} agents, step 500: shape error {P.fmt(j['shape_error_mean'])},\n"
                       f"extent {P.fmt(j['extent'], '{:.2f}')}, min separation {P.fmt(j['min_separation'])}")
    ax = axs[0, 2]
    for n, c in ((12, "tab:red"), (15, "tab:purple"), (20, "tab:green")):
        ser = P.load_series_csv(ld / f"line_n{n}_metrics.csv")
        ax.plot(*series_xy(ser, "extent", 1000), color=c, label=f"{n} agents")
    ax.set_title("line m=-1 c=5: extent (largest pairwise distance)", fontsize=10)
    ax.set_xlabel("iteration")
    ax.set_yscale("log")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    ax = axs[1, 0]
    r = load(data, "shape_circle")
    if r:
        ax.plot(*series_xy(r["sim_series"], "gap_cv", 500), color="tab:orange", label="Euler dt=1 (12 agents)")
    rk = P.read_csv(ld / "circle_rk4_metrics.csv")
    ax.plot([q["model_time"] for q in rk], [q["gap_cv"] for q in rk], color="tab:blue", label="RK4 dt=0.05")
    ax.set_yscale("log")
    ax.set_xlabel("model time")
    ax.set_title("circle, 12 agents: gap CV, Euler dt=1 vs RK4 dt=0.05", fontsize=10)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    ax = axs[1, 1]
    if r:
        K = max(r["sim_pos"])
        for i, c in ((0, "tab:blue"), (1, "tab:red")):
            tr = trajectories({k: v for k, v in r["sim_pos"].items() if K - 30 <= k <= K}).get(i)
            if not tr:
                continue
            th = np.unwrap([math.atan2(y, x) for x, y in zip(tr[1], tr[2])])
            s_arc = 4.0 * (th - th.mean())  # position along the ring, about its mean
            ax.plot(tr[0], s_arc, "-o", ms=3, color=c, label=f"agent {i}")
        ax.set_title("circle, 12 agents: position along the ring over the last 30 iterations\n"
                     "Euler dt=1 chatter: every agent hops back and forth by ~r*dt = 0.1", fontsize=10)
        ax.set_ylabel("arc position about its mean")
        ax.set_xlabel("iteration")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    ax = axs[1, 2]
    tr = trajectories(P.load_positions_csv(ld / "track_line_ff_long_positions.csv"))
    far = 0
    for i, (ks, xs, ys) in sorted(tr.items()):
        d = [math.hypot(x - (-10 + 0.1 * k), y - (-10 + 0.1 * k)) for k, x, y in zip(ks, xs, ys)]
        far += d[-1] > 5
        ax.plot(ks, d, lw=0.9)
    ax.axhline(2.0, color="k", ls=":", lw=0.8)
    ax.set_yscale("log")
    ax.set_title(f"line path, feed-forward, paper start: distance from C(t)\n{far} of {len(tr)} agents "
                 f"escape for ever (as around a fixed centre)", fontsize=10)
    ax.set_xlabel("iteration")
    ax.grid(alpha=0.3, which="both")
    fig.suptitle("Limits of the published law (simulator; Euler dt=1 unless said)", fontsize=11)
    fig.tight_layout()
    save(fig, out, "paper_limits.png")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                 usage="scripts/plot_paper.py --data DIR [--out DIR | --write-docs]")
    ap.add_argument("--data", required=True, help="a run folder of scripts/paper/run.py")
    ap.add_argument("--out", help="where the figures go (default DATA/figures)")
    ap.add_argument("--write-docs", action="store_true", help="rewrite the committed figures in docs/figures")
    a = ap.parse_args()
    data = Path(a.data).resolve()
    out = Path(a.out) if a.out else (E.REPO / "docs" / "figures" if a.write_docs else data / "figures")
    out.mkdir(parents=True, exist_ok=True)
    man = json.loads((data / "manifest.json").read_text())
    K = 200 if man["quick"] else 500
    Kr = 200 if man["quick"] else 1000
    fig1(data, out, K)
    fig2(data, out, K)
    fig3(data, out, Kr)
    fig_track(data, out, "line", [("track_line_paper", "paper law"), ("track_line_ff", "feed-forward"),
                                  ("track_line_ff_near", "feed-forward, start around C(0)")],
              "paper_fig4_track_line.png",
              "Fig. 4 analogue: centre on y=x from (-10,-10) at (0.1,0.1)/iteration; snapshots at t=40..200\n"
              "(centre: open circle, target ring dashed), one agent's trajectory (grey)")
    fig_track(data, out, "circle", [("track_circle_paper", "paper law"), ("track_circle_ff", "feed-forward")],
              "paper_fig5_track_circle.png",
              "Fig. 5 analogue: centre on the circle of radius 6, period 200; snapshots at t=40..200\n"
              "(centre: open circle, target ring dashed), one agent's trajectory (grey)")
    fig_convergence(data, out, K)
    fig_tracking_errors(data, out)
    fig_limits(data, out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
