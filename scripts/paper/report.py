#!/usr/bin/python3
"""Writes RESULTS.md from a reproduction's run folder (what scripts/paper/run.py recorded; the analysis is
scripts/paper/analyse.py). The text above and below the generated part of an existing file is kept.

  scripts/paper/report.py --data DIR [--results FILE] [--figures DIR] [--write-docs]

Default: DIR/RESULTS.md beside figures in DIR/figures; --write-docs: docs/RESULTS.md with docs/figures.
"""
import argparse
import json
import math
import os
import statistics
import sys
import time
from pathlib import Path

sys.dont_write_bytecode = True  # no __pycache__ in scripts/
sys.path.insert(0, str(Path(__file__).resolve().parent))
from analyse import (Data, acceptance, async_at, at, chatter, fmt, load_positions, plateau, rng,  # noqa: E402
                     shape_rows, yn)
from experiments import REPO, SNAPSHOTS  # noqa: E402

BEGIN = "<!-- BEGIN GENERATED: scripts/reproduce_paper.sh rewrites everything down to END GENERATED -->"
END = "<!-- END GENERATED -->"

DEFAULT_INTRO = """# Reproducing the paper: results

Goswami, Saha, Pal, Jana, Das, *Multi-Agent Shape Formation and Tracking Inspired from a Social Foraging
Dynamics* (arXiv 1410.3864), run on real `shapeform_agent` processes talking over Fast DDS on loopback,
and in the in-process simulator `shapeform_sim` from the same starting positions.

Regenerate everything below the marker (numbers, verdicts, figures) with `scripts/reproduce_paper.sh`.
"""


class Writer:
    """The generated part of RESULTS.md, line by line, and the run folder it is written from."""

    def __init__(self, data: Data, fig_rel: str):
        self.D = data
        self.man = data.manifest
        self.quick = self.man["quick"]
        self.draws = self.man.get("async_draws", 0)
        self.loaded = data.loaded
        self.fig_rel = fig_rel
        self.lines = []

    def w(self, line):
        self.lines.append(line)

    def section(self, title):
        """A heading and the blank line under it."""
        self.w(title)
        self.w("")

    def head(self, line):
        """A table's header line and the separator under it."""
        self.w(line)
        self.w("|" + "---|" * (line.count("|") - 1))

    def fig(self, name, alt):
        self.w(f"![{alt}]({self.fig_rel}/{name})")
        self.w("")


# ------------------------------------------------------------------ how the numbers were made

def write_intro(o, command):
    """The generator line and how the numbers were made."""
    data, man, w = o.D.dir, o.man, o.w
    where = f"`{os.path.relpath(data, REPO)}`" if str(data).startswith(str(REPO) + os.sep) else "a run folder"
    w(BEGIN)
    w("")
    w(f"*Generated {time.strftime('%Y-%m-%d %H:%M')} by `{command}"
      f"{' --quick' if o.quick else ''}` from the files it recorded in {where}: seed {man['seed']}, distributed runs "
      f"{'through `scripts/launch_swarm.sh`' if man['backend'] == 'launcher' else 'started directly by `scripts/paper/run.py`'}"
      f", experiments {man['seconds']:.0f} s in all on {man.get('cores', '?')} cores.*")
    w("")
    w("How the numbers were made:")
    w("")
    w("- **processes**: one `shapeform_agent` process per agent at 50 Hz (one tick = one Euler step of dt = 1, "
      "the paper's iteration) and a `shapeform_supervisor` recording every iteration "
      "(`supervisor.metrics_rate_hz=50`), on loopback, in lockstep (`agent.sync=lockstep`: each process takes "
      "step k+1 from its neighbours' step-k states, which is the simulator's synchronous update; free-running "
      "processes, which see a mix of steps k and k+1, are what the async model columns show); a neighbour is "
      "dropped after 0.5 s of silence (`agent.neighbour_timeout_periods=25`; no agent leaves here). A run in "
      "which the supervisor lost an agent or the machine stalled is made again (up to 3 times) and flagged "
      "in section 5 if it never ran clean.")
    w("- **simulator**: `shapeform_sim --init` from the same start (the simulator's seeded uniform start in "
      "[-5,5]^2, written to `start.csv` and given to both).")
    w(f"- **async model**: `scripts/paper/async_model.py`, the same law in numpy with the processes' schedule: "
      f"every agent ticks once per period at its own phase and uses the newest state of each neighbour, so it "
      f"sees some neighbours at step k+1 and others at step k. Median [min, max] over {o.draws} random phasings "
      f"from the same start. With all agents stepping together it reproduces the simulator's series to 1e-9 "
      f"(checked on every shape and both tracking paths).")
    w("- **plateau**: median over the last tenth of the run (at least 10 iterations), because Euler dt = 1 "
      "chatters with period 2 and the processes tick out of phase, so one sample depends on the phase it "
      "caught. **settling step**: the first step after which the shape error stays within max(0.02, 10 %) of "
      "its plateau and gap CV <= 0.15 (`core::settle_index`: the supervisor's and the simulator's own `settle_step`, "
      "from their JSON summaries; the async model has none).")
    w("")


# ------------------------------------------------------------------ summary

def shape_tables(o):
    """[(shape, None | (run, table lines))] of the four shapes."""
    tables = []
    for s in ("line", "circle", "ellipse", "square"):
        r = o.loaded(f"shape_{s}")
        if not r:
            tables.append((s, None))
            continue
        t = []
        for lab, dp, sp, ap, ok, cons in shape_rows(r):
            if lab == "settling step" and s == "line":
                t.append(f"| {lab} | {fmt(dp)} | {fmt(sp)} | - | n/a: the line keeps growing | |")
            elif lab == "settling step":
                t.append(f"| {lab} | {fmt(dp)} | {fmt(sp)} | - | {yn(ok)} | - |")
            elif ok is None:
                t.append(f"| {lab} | {fmt(dp)} | {fmt(sp)} | {rng(ap)} | | |")
            else:
                t.append(f"| {lab} | {fmt(dp)} | {fmt(sp)} | {rng(ap)} | {yn(ok)} | {yn(cons, '**no**')} |")
        tables.append((s, (r, t)))
    return tables


def _plateaus(r):
    """'shape error X, gap CV Y' of the processes and 'X, Y' of the simulator, at the plateau."""
    K = r["K"]
    dist = (f"shape error {fmt(plateau(r['dist']['series'], K, 'shape_error_mean'))}, gap CV "
            f"{fmt(plateau(r['dist']['series'], K, 'gap_cv'))}")
    sim = f"{fmt(plateau(r['sim']['series'], K, 'shape_error_mean'))}, {fmt(plateau(r['sim']['series'], K, 'gap_cv'))}"
    return dist, sim


def summary_shapes(o):
    """The summary's lines of the circle, the ellipse, the square and the line."""
    w, c = o.w, o.loaded("shape_circle")
    if c:
        fin = load_positions(o.D.dir / "shape_circle" / "sim", "sim").get(c["K"], {})
        radius = statistics.mean(math.hypot(*p) for p in fin.values()) if fin else None
        dist, sim = _plateaus(c)
        w(f"| circle r0=4, 12 agents | agents converge onto the circle, spread evenly | {dist} | {sim} | partly: "
          f"evenly spread, but the ring rests at radius {fmt(radius, '{:.2f}')} (simulator), inside the circle: "
          f"cohesion pulls it in |")
    for s in ("ellipse", "square"):
        r = o.loaded(f"shape_{s}")
        if r:
            dist, sim = _plateaus(r)
            w(f"| {r['exp']['label']}, 12 agents | the shape is formed | {dist} | {sim} | partly: recognisable and "
              f"evenly spread, but the agents rest inside the shape (mean distance to it = the shape error) |")
    ln = o.loaded("shape_line")
    if ln:
        K = ln["K"]
        e_d = ln["dist"]["summary"].get("shape_error_mean")
        e_s = ln["sim"]["summary"].get("shape_error_mean")
        on = e_d is not None and e_s is not None and e_d < 0.01 and e_s < 0.01
        w(f"| line m=-1 c=5, 12 agents | agents line up on the line | shape error {fmt(e_d, '{:.1e}')}, extent "
          f"{fmt(ln['dist']['summary'].get('extent'), '{:.0f}')} at step {K} | {fmt(e_s, '{:.1e}')}, extent "
          f"{fmt(ln['sim']['summary'].get('extent'), '{:.0f}')} | "
          f"{'partly: on the line' if on else 'not yet on the line at this step'}, and it never stops growing "
          f"(fewer than ~15 agents; section 4) |")


def summary_repulsion(o):
    """The summary's lines of the repulsion study: gap CV without and with repulsion."""
    for s in ("ellipse", "square"):
        r0, r1 = o.loaded(f"rep_{s}_r0"), o.loaded(f"rep_{s}_r01")
        if r0 and r1:
            g = {kind: (at(r0, kind, "gap_cv", 200), at(r1, kind, "gap_cv", 200)) for kind in ("dist", "sim")}

            def ratio(p):
                return None if p[0] is None or not p[1] else p[0] / p[1]

            ok = all(ratio(g[k]) is not None and ratio(g[k]) >= 10 for k in g)
            o.w(f"| repulsion, {s} | without repulsion the agents bunch up | gap CV at step 200: r=0 "
                f"{fmt(g['dist'][0])} vs r=0.1 {fmt(g['dist'][1])} | {fmt(g['sim'][0])} vs {fmt(g['sim'][1])} | "
                f"{'yes' if ok else '**no**'} (x{fmt(ratio(g['dist']), '{:.0f}')} / x{fmt(ratio(g['sim']), '{:.0f}')}) |")


def _errors_at_200(r, kind):
    return f"{fmt(at(r, kind, 'centroid_error', 200))}, ring error {fmt(at(r, kind, 'ring_error', 200))}"


def summary_tracking(o):
    """The summary's lines of tracking, with the paper's law and with feed-forward."""
    w = o.w
    for pth in ("line", "circle"):
        r = o.loaded(f"track_{pth}_paper")
        if r:
            w(f"| tracking, {pth} path, paper law | the swarm surrounds the moving centre | centroid error "
              f"{_errors_at_200(r, 'dist')} at t=200 | {fmt(at(r, 'sim', 'centroid_error', 200))}, "
              f"{fmt(at(r, 'sim', 'ring_error', 200))} | **no**: the centre outruns the swarm, which trails as a blob |")
    for name, lab in (("track_circle_ff", "circle path, feed-forward"),
                      ("track_line_ff_near", "line path, feed-forward, start around C(0)"),
                      ("track_line_ff", "line path, feed-forward, paper start")):
        r = o.loaded(name)
        if r:
            good = (at(r, "dist", "centroid_error", 200) or 9) < 0.5
            w(f"| tracking, {lab} (not in the paper) | the ring forms around the moving centre | centroid error "
              f"{_errors_at_200(r, 'dist')} | {fmt(at(r, 'sim', 'centroid_error', 200))}, "
              f"{fmt(at(r, 'sim', 'ring_error', 200))} | "
              f"{'yes' if good else 'not by t=200: some agents never reach the centre (the same happens around a fixed centre at C(0), see 3.)'} |")


def write_acceptance(o, acc):
    """The acceptance line under the summary, and what fails."""
    w = o.w
    n_ok = sum(1 for x in acc if x[4])
    bad = [x for x in acc if not x[4]]
    bad_cons = [x for x in acc if x[5] is False]
    w(f"**Acceptance, processes against the simulator: distributed plateau metrics within 10 % (or 0.02) of "
      f"the simulator's from the same start, settling steps within 20 %: {n_ok} of {len(acc)} checks pass.**"
      + (" (`--quick`: the runs stop at 200 iterations, before the plateau; the check is meant for the full run.)"
         if o.quick else ""))
    if bad:
        w("")
        w("Failing: " + "; ".join(f"{s} {lab} (processes {fmt(d)}, simulator {fmt(si)})" for s, lab, d, si, _, _ in bad)
          + ".")
        w("")
        if not bad_cons:
            w(f"Every failing value lies within the range that the same law gives under a free-running schedule "
              f"(async model, {o.draws} phasings, widened by the same tolerance): a process that lost its neighbours "
              f"for longer than the lockstep wait (the machine stalled) ran free for a while, and for these shapes "
              f"the resting formation depends on the order of the updates (see *Processes against simulator* at "
              f"the end).")
        else:
            w("Not explained by the schedule alone (outside the async model's range): " + "; ".join(
                f"{s} {lab} (processes {fmt(d)})" for s, lab, d, _, _, _ in bad_cons) + ".")
    w("")


def write_summary(o, acc):
    o.section("## Summary")
    o.head("| experiment | the paper's claim | processes | simulator | holds? |")
    summary_shapes(o)
    summary_repulsion(o)
    summary_tracking(o)
    o.w("")
    write_acceptance(o, acc)


# ------------------------------------------------------------------ 1. shapes, 2. repulsion

def write_shapes(o, tables):
    w = o.w
    o.section("## 1. Shapes (paper Figs. 1, 2)")
    for s, rt in tables:
        if rt is None:
            o.section(f"### {s}: the run is missing or failed")
            continue
        r, t = rt
        e = r["exp"]
        extra = ""
        if e.get("other_cores") is not None and e["other_cores"] > 0.3:
            extra = f" Other programs used {e['other_cores']:.1f} cores during the distributed run."
        if e.get("problem"):
            extra += f" **The distributed run is flagged: {e['problem']}.**"
        o.section(f"### {e['label']} ({e['agents']} agents, {r['K']} iterations)")
        if extra:
            w(extra.strip())
            w("")
        w("| metric (plateau) | processes | simulator | async model | processes within tolerance of simulator | "
          "processes within async range |")
        w("|---|---|---|---|---|---|")
        for line in t:
            w(line)
        w("")
    o.fig("paper_fig1_formations.png", "Final formations and trajectories")
    o.fig("paper_fig2_agent_states.png", "One agent's x1 and x2 against time")
    o.fig("paper_convergence.png", "Shape error and gap CV against time")


def _three(r, key, k):
    """'processes / simulator / async model median' of a metric at step k."""
    av = [v for v in async_at(r["async"], key, k) if v is not None]
    return f"{fmt(at(r, 'dist', key, k))} / {fmt(at(r, 'sim', key, k))} / {fmt(statistics.median(av)) if av else '-'}"


def write_repulsion(o):
    w = o.w
    Kr = 200 if o.quick else 1000
    o.section("## 2. Repulsion (paper Fig. 3)")
    w(f"Ellipse and square, 12 agents, r = 0 against r = 0.1, at iterations 200 and {Kr}: processes / simulator "
      f"/ async model median.")
    w("")
    o.head("| run | step | gap CV | clusters | min separation | shape error |")
    for s in ("ellipse", "square"):
        for rr in ("r0", "r01"):
            r = o.loaded(f"rep_{s}_{rr}")
            if not r:
                continue
            for k in sorted({200, r["K"]}):
                cells = [_three(r, key, k) for key in ("gap_cv", "clusters", "min_separation", "shape_error_mean")]
                w(f"| {r['exp']['label']} | {k} | " + " | ".join(cells) + " |")
    w("")
    w("A gap CV of `-` means undefined: every agent on one point (all gaps zero).")
    w("")
    o.fig("paper_fig3_repulsion.png", "Without and with repulsion")


# ------------------------------------------------------------------ 3. tracking

TRACK_GROUPS = [("line", "paper start", ["track_line_paper", "track_line_ff", "track_line_fixed"]),
                ("line", "start around C(0)", ["track_line_ff_near", "track_line_fixed_near"]),
                ("circle", "paper start", ["track_circle_paper", "track_circle_ff", "track_circle_fixed"])]
# (path, start, the feed-forward run, the fixed-centre run)
FF_VS_FIXED = [("line", "paper start", "track_line_ff", "track_line_fixed"),
               ("line", "start around C(0)", "track_line_ff_near", "track_line_fixed_near"),
               ("circle", "paper start", "track_circle_ff", "track_circle_fixed")]


def write_tracking(o):
    w = o.w
    o.section("## 3. Tracking (paper Figs. 4, 5)")
    w("10 agents, r0 = 2. Centroid error |mean(x) - C(t)| and ring error mean| |x_i - C(t)| - r0 | at the "
      "snapshot times: processes / simulator / async model median. *paper law*: no feed-forward, as published; "
      "*feed-forward*: each agent adds dC/dt (`tracking.feedforward=true`, console `track ... ff=on`); *fixed "
      "centre*: the same formation around C(0), from the same start, i.e. the static problem that feed-forward "
      "turns the moving one into (in the centre's frame).")
    w("")
    for pth, lab, names in TRACK_GROUPS:
        o.section(f"### Centre on the {pth} path, {lab}")
        for key, klab in (("centroid_error", "centroid error"), ("ring_error", "ring error")):
            w(f"| {klab} | " + " | ".join(f"t={t}" for t in SNAPSHOTS) + " |")
            w("|---|" + "---|" * len(SNAPSHOTS))
            for name in names:
                r = o.loaded(name)
                if r:
                    w(f"| {r['exp']['label']} | " + " | ".join(_three(r, key, t) for t in SNAPSHOTS) + " |")
            w("")
    write_ff_vs_fixed(o)
    o.fig("paper_fig4_track_line.png", "Tracking on the line path")
    o.fig("paper_fig5_track_circle.png", "Tracking on the circle path")
    o.fig("paper_tracking_errors.png", "Tracking errors against time")


def async_pairs(runs_a, runs_b):
    """Phasing j of runs_a against phasing j+1 of runs_b (two runs of processes never share their tick
    phases): the largest differences over t = 160 and 200, as 'centroid | ring | how many within 0.1 |'."""
    dcs, drs = [], []
    m = len(runs_b)
    for j, a1 in enumerate(runs_a):
        a2 = runs_b[(j + 1) % m]
        dcs.append(max(abs(a1["centroid_error"][t] - a2["centroid_error"][t]) for t in (160, 200)))
        drs.append(max(abs(a1["ring_error"][t] - a2["ring_error"][t]) for t in (160, 200)))
    ok = sum(1 for x, y in zip(dcs, drs) if x <= 0.1 and y <= 0.1)
    return f"{rng(dcs)} | {rng(drs)} | {ok} of {len(dcs)} |"


def write_ff_vs_fixed(o):
    """Feed-forward against the fixed centre: processes, simulator and the async model's phasings."""
    w = o.w
    w("Feed-forward against the fixed centre (its acceptance criterion: within 0.1 after the transient), "
      "largest difference over t = 160 and 200:")
    w("")
    o.head("| case | run | centroid error | ring error | within 0.1? |")
    for pth, lab, ffn, fxn in FF_VS_FIXED:
        ff, fx = o.loaded(ffn), o.loaded(fxn)
        if not ff or not fx:
            continue
        for kind, klab in (("dist", "processes"), ("sim", "simulator")):
            dc = max(abs(at(ff, kind, "centroid_error", t) - at(fx, kind, "centroid_error", t)) for t in (160, 200))
            dr = max(abs(at(ff, kind, "ring_error", t) - at(fx, kind, "ring_error", t)) for t in (160, 200))
            w(f"| {pth} path, {lab} | {klab} | {fmt(dc)} | {fmt(dr)} | {yn(dc <= 0.1 and dr <= 0.1)} |")
        if ff["async"] and fx["async"]:
            case = f"| {pth} path, {lab} |"
            w(f"{case} async model: feed-forward vs fixed centre, {len(ff['async']['async'])} pairs "
              f"of phasings | " + async_pairs(ff["async"]["async"], fx["async"]["async"]))
            if ff["async"].get("async_compensated"):
                w(f"{case} async model, feed-forward with stale neighbours moved into the "
                  f"centre's frame (what free-running agents do) vs fixed centre | "
                  + async_pairs(ff["async"]["async_compensated"], fx["async"]["async"]))
            w(f"{case} async model: fixed centre vs fixed centre (run-to-run spread of the "
              f"static problem itself) | " + async_pairs(fx["async"]["async"], fx["async"]["async"]))
    w("")


# ------------------------------------------------------------------ 4. limits, 5. runs

def limit_lines(o, lim):
    """The lines of the limits table: the plateau off the shape, chatter, RK4, larger swarms, the line."""
    w, data = o.w, o.D.dir
    cs = o.loaded("shape_circle")
    if cs:
        K = cs["K"]
        sp_pos = load_positions(data / "shape_circle" / "sim", "sim")
        dp_pos = load_positions(data / "shape_circle" / "dist", "dist")
        rad = [math.hypot(*p) for p in sp_pos.get(K, {}).values()]
        w(f"| plateau off the shape (circle r0=4, 12 agents) | the ring rests at radius {statistics.mean(rad):.3f} "
          f"(shape error {fmt(cs['sim']['summary']['shape_error_mean'])}): cohesion pulls it in |")
        w(f"| Euler dt=1 chatter | at the plateau an agent hops {fmt(chatter(sp_pos, K))} per iteration in the "
          f"simulator, {fmt(chatter(dp_pos, K))} in the processes (r*dt = 0.1): a period-2 oscillation of the "
          f"constant-magnitude repulsion |")
    if "circle_rk4" in lim:
        j = lim["circle_rk4"]
        w(f"| RK4 dt=0.05 to t=500 (circle, 12 agents) | gap CV {fmt(j['gap_cv'])}, shape error "
          f"{fmt(j['shape_error_mean'])}: the chatter goes, the off-shape plateau stays |")
    for n in (10, 20, 50):
        if f"circle_n{n}" in lim:
            j = lim[f"circle_n{n}"]
            w(f"| circle r0=4, {n} agents, step 500 | shape error {fmt(j['shape_error_mean'])}, gap CV "
              f"{fmt(j['gap_cv'])}, extent {fmt(j['extent'], '{:.2f}')}, min separation "
              f"{fmt(j['min_separation'])}, clusters (link 0.05) {fmt(j['clusters'])} |")
    for n in (12, 15, 20):
        if f"line_n{n}" in lim:
            j = lim[f"line_n{n}"]
            w(f"| line, {n} agents, step 1000 | extent {fmt(j['extent'], '{:.1f}')}, shape error "
              f"{fmt(j['shape_error_mean'], '{:.1e}')} |")
    if "track_line_ff_long" in lim:
        j = lim["track_line_ff_long"]
        w(f"| line path with feed-forward from the paper's start, step 1000 | centroid error "
          f"{fmt(j['centroid_error'])}, ring error {fmt(j['ring_error'])}: the agents that fall behind on the "
          f"14-unit approach escape for ever (the constant repulsion r beats the decaying attraction far away), "
          f"exactly as around a fixed centre at C(0) |")


def write_limits(o):
    """Section 4, when the run folder has the simulator-only studies."""
    w, ld = o.w, o.D.dir / "limits"
    if not (ld / "seeds.json").exists():
        return
    lim = {m["name"]: json.loads((ld / f"{m['name']}_summary.json").read_text()) for m in o.man["limits"]
           if (ld / f"{m['name']}_summary.json").exists()}
    o.section("## 4. Limits of the published law (simulator)")
    o.head("| study | result |")
    limit_lines(o, lim)
    w("")
    seeds = json.loads((ld / "seeds.json").read_text())
    w("Simulator, seeds 1-20, median [min, max]: the seed used above is typical.")
    w("")
    o.head("| scenario | step | shape error mean | gap CV | clusters | extent | centroid error | ring error |")
    for scen, d in seeds.items():
        runs = d["runs"]
        w(f"| {scen} | {d['steps']} | {rng([r['shape_error_mean'] for r in runs])} | "
          f"{rng([r['gap_cv'] for r in runs])} | {rng([r['clusters'] for r in runs], '{:.0f}')} | "
          f"{rng([r['extent'] for r in runs], '{:.2f}')} | {rng([r.get('centroid_error') for r in runs])} | "
          f"{rng([r.get('ring_error') for r in runs])} |")
    w("")
    o.fig("paper_limits.png", "Limits of the published law")


def write_runs(o):
    w = o.w
    o.section("## 5. The runs")
    w("| experiment | agents | iterations | distributed run (s) | other programs' CPU during it (cores) | attempts "
      "| status |")
    w("|---|---|---|---|---|---|---|")
    for e in o.man["experiments"]:
        st = "FAILED: " + e.get("error", "?") if not e.get("ok") else (
            f"**flagged**: {e['problem']}" if e.get("problem") else "ok")
        w(f"| {e['name']} | {e['agents']} | {e['steps']} | {fmt(e.get('dist_wall_s'), '{:.1f}')} | "
          f"{fmt(e.get('other_cores'), '{:.2f}')} | {e.get('attempts', 1)} | {st} |")
    w("")
    w("Agents tick on the wall clock (a late tick is skipped and counted, not made up), so CPU taken by other "
      "programs shows up as fewer iterations in the processes than in the supervisor's model time; "
      "the runner raises its own priority (`nice -10`, inherited by the processes) when it may.")
    w("")
    w(END)


# ------------------------------------------------------------------ the file

def write_file(res_path, generated):
    """Writes the generated part into res_path, keeping the text above and below it (or the default
    introduction for a new file)."""
    if res_path.exists():
        old = res_path.read_text()
        if BEGIN in old and END in old:
            head = old.split(BEGIN)[0]
            tail = old.split(END, 1)[1]
        else:
            head, tail = old.rstrip() + "\n\n", "\n"
    else:
        head, tail = DEFAULT_INTRO + "\n", "\n"
    res_path.parent.mkdir(parents=True, exist_ok=True)
    content = head + generated
    if tail.strip():
        content += "\n" + tail.lstrip("\n")
    res_path.write_text(content)


def write_report(data_dir, res_path, figures, command):
    """Writes the generated part of RESULTS.md at res_path (the text around it is kept) from a run folder."""
    res_path = Path(res_path)
    o = Writer(Data(data_dir), os.path.relpath(Path(figures).resolve(), res_path.resolve().parent))
    write_intro(o, command)
    acc = acceptance(o.D)  # (shape, metric, dist, sim, ok, consistent_with_async)
    tables = shape_tables(o)
    write_summary(o, acc)
    write_shapes(o, tables)
    write_repulsion(o)
    write_tracking(o)
    write_limits(o)
    write_runs(o)
    write_file(res_path, "\n".join(o.lines) + "\n")
    n_ok = sum(1 for x in acc if x[4])
    bad = [x for x in acc if not x[4]]
    print(f"report: wrote {res_path}: acceptance {n_ok} of {len(acc)} shape checks pass"
        + ("; failing: " + ", ".join(f"{s} {lab}" for s, lab, *_ in bad) if bad else ""))
    return 0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                 usage="scripts/paper/report.py --data DIR [--results FILE] [--figures DIR] [--write-docs]")
    ap.add_argument("--data", required=True, help="a run folder of scripts/paper/run.py")
    ap.add_argument("--results", help="the file to write (default DATA/RESULTS.md; docs/RESULTS.md with --write-docs)")
    ap.add_argument("--figures", help="where the figures are (default DATA/figures; docs/figures with --write-docs)")
    ap.add_argument("--write-docs", action="store_true", help="rewrite the committed docs/RESULTS.md")
    ap.add_argument("--command", default="scripts/reproduce_paper.sh", help="the command named as the generator")
    a = ap.parse_args()
    data = Path(a.data)
    docs = REPO / "docs"
    results = Path(a.results) if a.results else (docs / "RESULTS.md" if a.write_docs else data / "RESULTS.md")
    figures = Path(a.figures) if a.figures else (docs / "figures" if a.write_docs else data / "figures")
    if not a.write_docs and not a.results and not results.exists() and (docs / "RESULTS.md").exists():
        # A run folder's report keeps the committed file's hand-written text around the generated part.
        results.write_text((docs / "RESULTS.md").read_text())
    return write_report(data, results, figures, a.command)


if __name__ == "__main__":
    sys.exit(main())
