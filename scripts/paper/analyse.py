#!/usr/bin/python3
"""Analysis of a reproduction's run folder (what scripts/paper/run.py recorded): per-step series,
plateaus, the acceptance checks (processes against the simulator). Imported by report.py and
scripts/plot_paper.py; run on its own it prints the acceptance checks, one JSON object per line.

  scripts/paper/analyse.py --data DIR

Settling steps are the programs' own (`settle_step` in the simulator's JSON and in the supervisor's
summary, both `core::settle_index`); nothing here re-implements a detector of the core.
"""
import argparse
import csv
import json
import math
import statistics
import sys
from pathlib import Path

sys.dont_write_bytecode = True  # no __pycache__ in scripts/
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "lib"))
import shapeform_procs as procs  # noqa: E402


def read_csv(path):
    """Rows of a CSV as dicts of floats (empty field -> None)."""
    return procs.read_csv(path, numeric=True)


def fmt(v, f="{:.3f}"):
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "-"
    if isinstance(v, int) or (isinstance(v, float) and v.is_integer() and abs(v) >= 1):
        return str(int(v))
    return f.format(v)


def load_series_csv(path):
    """A simulator --csv file as dict step -> row."""
    return {int(r["step"]): r for r in read_csv(path)}


def load_positions_csv(path):
    """A simulator --positions file as dict step -> {agent: (x1, x2)}."""
    out = {}
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            out.setdefault(int(r["step"]), {})[int(r["agent"])] = (float(r["x1"]), float(r["x2"]))
    return out


def load_series(run_dir, kind):
    """Per-step metrics of one run: dict step -> row (dist: the supervisor row nearest each integer step
    of model time, after the command was published; sim: its --csv rows)."""
    rows = read_csv(run_dir / "metrics.csv")
    if kind == "sim":
        return {int(r["step"]): r for r in rows}
    best = {}
    for r in rows:
        if not r["epoch"] or r["epoch"] < 1:
            continue
        k = int(round(r["model_time"]))
        d = abs(r["model_time"] - k)
        if k not in best or d < best[k][0]:
            best[k] = (d, r)
    return {k: v[1] for k, v in sorted(best.items())}


def load_positions(run_dir, kind):
    """Positions per step: dict step -> {agent: (x1, x2)} (dist: rows nearest each integer step after
    the command was published)."""
    out = {}
    if kind == "sim":
        return load_positions_csv(run_dir / "positions.csv")
    # The recorder's positions carry no epoch: keep the rows written at or after the first metrics
    # row of epoch >= 1 (same wall_s stamps).
    t_first = None
    with open(run_dir / "metrics.csv", newline="") as f:
        for r in csv.DictReader(f):
            if r["epoch"] and int(r["epoch"]) >= 1:
                t_first = float(r["wall_s"])
                break
    if t_first is None:
        return out
    by_wall = {}
    with open(run_dir / "positions.csv", newline="") as f:
        for r in csv.DictReader(f):
            w = float(r["wall_s"])
            if w < t_first:
                continue
            by_wall.setdefault(w, (float(r["model_time"]), {}))[1][int(r["agent"])] = (float(r["x1"]), float(r["x2"]))
    best = {}
    for w, (t, pos) in by_wall.items():
        k = int(round(t))
        d = abs(t - k)
        if k not in best or d < best[k][0]:
            best[k] = (d, pos)
    return {k: v[1] for k, v in sorted(best.items())}


def at_step(series, k):
    """The row of the step nearest k (series: dict step -> row)."""
    if not series:
        return None
    if k in series:
        return series[k]
    kk = min(series, key=lambda s: abs(s - k))
    return series[kk]


def plateau(series, steps, key):
    """Median of a metric over the last tenth of the run (at least 10 steps): Euler dt=1 chatters with
    period 2 and the agent processes tick out of phase, so a single sample depends on the phase."""
    lo = steps - max(10, steps // 10)
    vals = [r[key] for k, r in series.items() if lo <= k <= steps and r.get(key) is not None]
    return statistics.median(vals) if vals else None


def chatter(positions, steps):
    """Median over agents and the last tenth of the run of |x(k+1) - x(k)|: at the plateau of Euler dt=1
    each agent hops back and forth by about r*dt."""
    lo = steps - max(10, steps // 10)
    hops = []
    for k in range(lo, steps):
        a, b = positions.get(k), positions.get(k + 1)
        if not a or not b:
            continue
        for i in a:
            if i in b:
                hops.append(math.hypot(b[i][0] - a[i][0], b[i][1] - a[i][1]))
    return statistics.median(hops) if hops else None


def tolerance_ok(d, s, rel=0.10, abs_=0.02):
    if d is None or s is None:
        return d is None and s is None
    return abs(d - s) <= max(abs_, rel * abs(s))


def settle_ok(d, s, rel=0.20):
    if d is None or s is None:
        return d is None and s is None
    return abs(d - s) <= rel * max(abs(s), 1)


def async_plateaus(asy, key, K):
    """Per phasing of the asynchronous model: the plateau (median of the last tenth) of a metric."""
    if not asy:
        return []
    lo = K - max(10, K // 10)
    out = []
    for d in asy["async"]:
        vals = [v for v in d[key][lo:K + 1] if v is not None]
        out.append(statistics.median(vals) if vals else None)
    return out


def async_at(asy, key, k):
    if not asy:
        return []
    return [d[key][k] if k < len(d[key]) else None for d in asy["async"]]


def rng(vals, f="{:.3f}"):
    v = [x for x in vals if x is not None]
    if not v:
        return "-"
    return f"{fmt(statistics.median(v), f)} [{fmt(min(v), f)}, {fmt(max(v), f)}]"


def in_range(x, vals, rel=0.10, abs_=0.02):
    """x within the [min, max] of vals, widened by the acceptance tolerance."""
    v = [y for y in vals if y is not None]
    if x is None or not v:
        return None
    lo, hi = min(v), max(v)
    tol = max(abs_, rel * max(abs(lo), abs(hi)))
    return lo - tol <= x <= hi + tol


def yn(b, bad="**NO**"):
    return "-" if b is None else ("yes" if b else bad)


# ---------------------------------------------------------------------------------------------
# One run folder

class Data:
    """A run folder: its manifest and, loaded on first use, each experiment's series and summaries."""

    def __init__(self, folder):
        self.dir = Path(folder).resolve()
        self.manifest = json.loads((self.dir / "manifest.json").read_text())
        self.exps = {e["name"]: e for e in self.manifest["experiments"]}
        self._cache = {}

    def loaded(self, name):
        """{exp, K, sim: {summary, series}, dist: {summary, series}, async} of an experiment that ran,
        None otherwise."""
        if name not in self._cache:
            e = self.exps.get(name)
            r = None
            if e and e.get("ok"):
                d = self.dir / name
                r = {"exp": e, "K": e["steps"]}
                for kind in ("sim", "dist"):
                    r[kind] = {"summary": json.loads((d / kind / "summary.json").read_text()),
                               "series": load_series(d / kind, kind)}
                r["async"] = json.loads((d / "async.json").read_text()) if (d / "async.json").exists() else None
            self._cache[name] = r
        return self._cache[name]


def at(r, kind, key, k):
    """A metric of one run (kind: dist | sim) at the step nearest k."""
    row = at_step(r[kind]["series"], k)
    return row.get(key) if row else None


PLATEAU_METRICS = (("shape error mean", "shape_error_mean"), ("shape error max", "shape_error_max"),
                   ("gap CV", "gap_cv"), ("min separation", "min_separation"), ("clusters", "clusters"),
                   ("extent", "extent"))
CHECKED = ("shape_error_mean", "shape_error_max", "gap_cv", "min_separation")


def shape_rows(r):
    """The rows of one shape's table: (label, processes, simulator, async values, ok, consistent).
    ok / consistent are None for a row that is not checked. Settling steps are the programs' own."""
    K = r["K"]
    rows = []
    for lab, key in PLATEAU_METRICS:
        dp, sp = plateau(r["dist"]["series"], K, key), plateau(r["sim"]["series"], K, key)
        ap = async_plateaus(r["async"], key, K)
        if key in CHECKED:
            rows.append((lab, dp, sp, ap, tolerance_ok(dp, sp), in_range(dp, ap)))
        else:
            rows.append((lab, dp, sp, ap, None, None))
    ds, ss = r["dist"]["summary"].get("settle_step"), r["sim"]["summary"].get("settle_step")
    rows.append(("settling step", ds, ss, [], settle_ok(ds, ss), None))
    return rows


def acceptance(data):
    """The acceptance checks, processes against the simulator: [(shape, metric, processes, simulator, ok,
    consistent with the async model)].
    The line's settling step is left out: the line never settles (it keeps growing), so the rule's
    plateau is a moving target and a step found by it is an accident of when the gap CV dips."""
    acc = []
    for s in ("line", "circle", "ellipse", "square"):
        r = data.loaded(f"shape_{s}")
        if not r:
            continue
        for lab, dp, sp, _, ok, cons in shape_rows(r):
            if ok is None or (s == "line" and lab == "settling step"):
                continue
            acc.append((s, lab, dp, sp, ok, cons))
    return acc


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0], epilog="usage: scripts/paper/analyse.py --data DIR")
    ap.add_argument("--data", required=True, help="a run folder of scripts/paper/run.py")
    a = ap.parse_args()
    acc = acceptance(Data(a.data))
    for s, lab, dp, sp, ok, cons in acc:
        print(json.dumps({"shape": s, "metric": lab, "processes": dp, "simulator": sp, "ok": ok,
                          "within_async_range": cons}))
    return 0 if all(x[4] for x in acc) else 1


if __name__ == "__main__":
    sys.exit(main())
