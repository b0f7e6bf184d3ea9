#!/usr/bin/python3
"""Plots a recorded run: the final formation with the commanded shape dashed, the trajectories, and the
metric curves (shape error, gap CV, agents alive) against model time with the command changes marked.

usage: scripts/plot_run.py RUN_DIR [--out DIR] [--animate] [--sim PATH]

RUN_DIR is a recording (the supervisor's --record folder, or shapeform_sim --record's) or a launcher run
folder (its record/ subfolder is read). The layout is docs/RECORDING.md. The figures go to DIR (default
RUN_DIR/figures): formation.png, trajectories.png, metrics.png, and with --animate formation.gif (the
positions over the run, with the commanded shape of each moment). The commanded shape is drawn by the
project's own curve code: shapeform_sim --steps 0 --outline samples it for each recorded command (--sim, or
build/bin/shapeform_sim, or shapeform_sim on PATH).
Prints the path of every figure written, one a line. Exit status: 0 written, 1 a runtime failure (the
simulator failed on a recorded command), 2 bad input (a missing file or column, nothing recorded).
Needs Debian's python3-matplotlib, python3-numpy and python3-pil.
"""
import argparse
import bisect
import csv
import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
OUTLINE_POINTS = 240   # points along a commanded shape
MAX_FRAMES = 60        # GIF frames at most (the samples are thinned evenly)

# The columns this script needs in each file (others are ignored, so later columns do not break it).
NEEDED = {
    "metrics.csv": ("model_time", "epoch", "agents_alive", "shape_error_mean", "gap_cv"),
    "positions.csv": ("model_time", "epoch", "agent", "x1", "x2"),
    "commands.csv": ("model_time", "epoch", "command"),
    "centre.csv": ("model_time", "epoch", "c1", "c2"),
}


class BadInput(Exception):
    """A problem with the recording: exit status 2, the message names the file (and column)."""


def find_record(run_dir):
    """The recording folder of RUN_DIR: itself, or its record/ subfolder (a launcher run)."""
    run = Path(run_dir)
    if not run.is_dir():
        raise BadInput("%s: not a folder (give a recording or a launcher run folder)" % run)
    for candidate in (run, run / "record"):
        if (candidate / "metrics.csv").is_file():
            return candidate
    raise BadInput("%s: no metrics.csv (nor record/metrics.csv): not a recording (docs/RECORDING.md)"
                   % (run / "metrics.csv"))


def number(text):
    return None if text in (None, "") else float(text)


def read_table(rec, name, required=True):
    """The rows of rec/name as dicts of strings, after checking its header has the NEEDED columns.
    An optional file that is missing gives []."""
    path = rec / name
    if not path.is_file():
        if required:
            raise BadInput("%s: missing (a recording holds metrics.csv, positions.csv and commands.csv)" % path)
        return []
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        header = reader.fieldnames or []
        missing = [c for c in NEEDED[name] if c not in header]
        if missing:
            raise BadInput("%s: no column %s (header: %s)" % (path, ", ".join(missing), ",".join(header)))
        # A row cut short by a kill has None fields: skipped.
        return [r for r in reader if None not in r.values() and None not in r]


def read_recording(rec):
    """{metrics, positions, commands, centre}: numeric rows, epochs as int; commands with their settings."""
    data = {}
    for name in ("metrics.csv", "positions.csv", "centre.csv"):
        rows = []
        for r in read_table(rec, name, required=name != "centre.csv"):
            try:
                rows.append({k: (int(v) if k in ("epoch", "agent", "step") and v != "" else
                                 v if k in ("issuer", "issuer_name") else number(v)) for k, v in r.items()})
            except ValueError as e:
                raise BadInput("%s: %s in row %s" % (rec / name, e, r))
        data[name.split(".")[0]] = rows
    commands = {}
    for r in read_table(rec, "commands.csv"):
        try:
            settings = json.loads(r["command"])
        except json.JSONDecodeError as e:
            raise BadInput("%s: column command of epoch %s is not a JSON object: %s" % (rec / "commands.csv",
                                                                                     r["epoch"], e))
        commands[int(r["epoch"])] = settings  # a command recorded again (a new recording) is the same
    data["commands"] = commands
    if not data["positions"]:
        raise BadInput("%s: no rows (nothing was recorded)" % (rec / "positions.csv"))
    return data


def find_sim(given):
    if given:
        if not os.access(given, os.X_OK):
            raise BadInput("--sim %s: not an executable" % given)
        return given
    built = ROOT / "build" / "bin" / "shapeform_sim"
    if os.access(str(built), os.X_OK):
        return str(built)
    return shutil.which("shapeform_sim")


class Outlines:
    """The commanded shape's points for a recorded command at a model time, drawn by shapeform_sim (the
    project's curve code; a line is drawn over the stretch the given positions span)."""

    def __init__(self, sim, commands, centre_rows):
        self.sim = sim
        self.commands = commands
        self.centres = {}  # epoch -> ([model_time], [(c1, c2)]), model time ascending
        for r in centre_rows:
            ts, cs = self.centres.setdefault(r["epoch"], ([], []))
            if not ts or r["model_time"] >= ts[-1]:
                ts.append(r["model_time"])
                cs.append((r["c1"], r["c2"]))
        self.cache = {}
        self.tmp = tempfile.TemporaryDirectory(prefix="plot_run_")
        self.warned = False

    def at(self, epoch, model_time, positions):
        if epoch == 0:
            return None  # before any command: there is no commanded shape
        settings = self.commands.get(epoch)
        if settings is None or self.sim is None:
            if not self.warned:
                self.warned = True
                why = "no shapeform_sim found (give --sim)" if self.sim is None else \
                    "epoch %d is not in commands.csv" % epoch
                print("plot_run.py: the commanded shape is not drawn: %s" % why, file=sys.stderr)
            return None
        moving = settings.get("tracking.enabled") == "true"
        line = settings.get("shape.kind") == "line"
        centre = self.centre_at(epoch, model_time) if moving and not line else None
        if centre is not None:
            # A tracked shape is its shape placed at C(t) (core::shape_at): the shape once about the origin,
            # moved to the recorded centre of each moment.
            key = (epoch, "at the origin")
            if key not in self.cache:
                still = dict(settings, **{"tracking.enabled": "false", "shape.centre": "[0.0, 0.0]"})
                self.cache[key] = self._sample(still, 0.0, positions)
            return [(x + centre[0], y + centre[1]) for x, y in self.cache[key]]
        key = (epoch, model_time if moving else None, tuple(map(tuple, positions)) if line else None)
        if key not in self.cache:
            self.cache[key] = self._sample(settings, model_time, positions)
        return self.cache[key]

    def centre_at(self, epoch, model_time):
        """The recorded tracked centre of the epoch nearest model_time (None: none recorded)."""
        ts, cs = self.centres.get(epoch, ([], []))
        if not ts:
            return None
        k = bisect.bisect_left(ts, model_time)
        if k == len(ts) or (k > 0 and model_time - ts[k - 1] <= ts[k] - model_time):
            k -= 1
        return cs[k]

    def _sample(self, settings, model_time, positions):
        init = os.path.join(self.tmp.name, "init.csv")
        with open(init, "w") as f:
            f.writelines("%r,%r\n" % (x, y) for x, y in positions)
        argv = [self.sim, "--steps", "0", "--init", init, "--outline", str(OUTLINE_POINTS),
                "--outline-time", repr(max(model_time, 0.0))]
        for k, v in settings.items():
            argv += ["--set", "%s=%s" % (k, v)]
        r = subprocess.run(argv, capture_output=True, text=True, stdin=subprocess.DEVNULL)
        if r.returncode != 0:
            raise RuntimeError("shapeform_sim could not draw a recorded command (exit %d): %s"
                               % (r.returncode, r.stderr.strip()[-1000:]))
        return json.loads(r.stdout)["outline"]


def samples(positions):
    """The position samples in order: [(epoch, model_time, {agent: (x1, x2)})], one per recorded instant
    (wall_s when recorded, else model time)."""
    out = []
    key_of = (lambda r: (r["wall_s"], r["epoch"], r["model_time"])) if "wall_s" in positions[0] else \
        (lambda r: (r["epoch"], r["model_time"]))
    last = None
    for r in positions:
        k = key_of(r)
        if k != last:
            out.append((r["epoch"], r["model_time"], {}))
            last = k
        out[-1][2][r["agent"]] = (r["x1"], r["x2"])
    return out


def segments(rows):
    """The rows' runs of one epoch, in order, each with its offset on the run's model-time axis (the
    epochs laid end to end: each epoch's model time restarts at 0): [(epoch, offset, rows)]."""
    out = []
    offset = 0.0
    for r in rows:
        if not out or out[-1][0] != r["epoch"]:
            if out:
                offset += max((x["model_time"] or 0.0) for x in out[-1][2])
            out.append((r["epoch"], offset, []))
        out[-1][2].append(r)
    return out


def describe(settings):
    if not settings:
        return "no command"
    text = "%s, %s law" % (settings.get("shape.kind"), settings.get("dynamics.law"))
    if settings.get("tracking.enabled") == "true":
        text += ", tracking (%s path)" % settings.get("tracking.path")
    if settings.get("dynamics.hold") == "true":
        text += ", held"
    return text


def centre_path(data, epoch):
    return [(r["c1"], r["c2"]) for r in data["centre"] if r["epoch"] == epoch]


def draw_formation(ax, pts, outline, centre, title):
    if outline:
        ax.plot([p[0] for p in outline], [p[1] for p in outline], "--", color="0.35", lw=1.2,
                label="commanded shape")
    ids = sorted(pts)
    ax.scatter([pts[i][0] for i in ids], [pts[i][1] for i in ids], s=36, color="tab:blue", zorder=3,
               label="agents")
    for i in ids:
        ax.annotate(str(i), pts[i], textcoords="offset points", xytext=(4, 4), fontsize=7)
    if centre:
        ax.plot([centre[0]], [centre[1]], "x", color="tab:red", ms=8, label="tracked centre")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x1 (shape units)")
    ax.set_ylabel("x2 (shape units)")
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(loc="best", fontsize=8)


def plot(rec, out, animate, sim):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    data = read_recording(rec)
    outlines = Outlines(sim, data["commands"], data["centre"])
    out.mkdir(parents=True, exist_ok=True)
    written = []
    snaps = samples(data["positions"])
    epoch, t_end, final = snaps[-1]
    final_xy = [final[i] for i in sorted(final)]
    settings = data["commands"].get(epoch)
    path = centre_path(data, epoch)

    # The final formation.
    fig, ax = plt.subplots(figsize=(6.4, 6.0))
    draw_formation(ax, final, outlines.at(epoch, t_end, final_xy), path[-1] if path else None,
                   "final formation: %d agents, epoch %d (%s), model time %g"
                   % (len(final), epoch, describe(settings), t_end))
    written.append(out / "formation.png")
    fig.savefig(str(written[-1]), dpi=110, bbox_inches="tight")
    plt.close(fig)

    # The trajectories.
    fig, ax = plt.subplots(figsize=(6.4, 6.0))
    tracks = {}
    for _, _, pts in snaps:
        for i, p in pts.items():
            tracks.setdefault(i, []).append(p)
    cmap = plt.get_cmap("tab20")
    for n, (i, tr) in enumerate(sorted(tracks.items())):
        c = cmap(n % 20)
        ax.plot([p[0] for p in tr], [p[1] for p in tr], "-", color=c, lw=0.9, alpha=0.8)
        ax.plot([tr[0][0]], [tr[0][1]], "o", mfc="none", color=c, ms=5)
        ax.plot([tr[-1][0]], [tr[-1][1]], "o", color=c, ms=5)
    outline = outlines.at(epoch, t_end, final_xy)
    if outline:
        ax.plot([p[0] for p in outline], [p[1] for p in outline], "--", color="0.35", lw=1.2,
                label="commanded shape (end)")
    all_centres = [(r["c1"], r["c2"]) for r in data["centre"]]
    if all_centres:
        ax.plot([c[0] for c in all_centres], [c[1] for c in all_centres], ":", color="tab:red", lw=1.2,
                label="tracked centre")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x1 (shape units)")
    ax.set_ylabel("x2 (shape units)")
    ax.set_title("trajectories of %d agents (open circle: start, dot: end)" % len(tracks), fontsize=10)
    ax.grid(alpha=0.3)
    if outline or all_centres:
        ax.legend(loc="best", fontsize=8)
    written.append(out / "trajectories.png")
    fig.savefig(str(written[-1]), dpi=110, bbox_inches="tight")
    plt.close(fig)

    # The metrics against model time, the epochs laid end to end.
    fig, axes = plt.subplots(3, 1, figsize=(7.5, 7.0), sharex=True)
    series = (("shape_error_mean", "mean shape error\n(shape units)", True),
              ("gap_cv", "gap CV", True),
              ("agents_alive", "agents alive", False))
    segs = segments(data["metrics"])
    for col, label, log in series:
        ax = axes[series.index((col, label, log))]
        xs, ys = [], []
        for _, offset, rows in segs:
            for r in rows:
                if r[col] is not None and r["model_time"] is not None:
                    xs.append(offset + r["model_time"])
                    ys.append(r[col])
        ax.plot(xs, ys, "-", lw=1.1, color="tab:blue")
        if log and any(y > 0 for y in ys):
            ax.set_yscale("log")
        ax.set_ylabel(label, fontsize=9)
        ax.grid(alpha=0.3)
    for n, (ep, offset, _) in enumerate(s for s in segs if s[0] != 0):  # epoch 0: before any command
        for ax in axes:
            ax.axvline(offset, color="tab:red", ls="--", lw=0.8, alpha=0.7)
        axes[0].annotate("epoch %d: %s" % (ep, describe(data["commands"].get(ep))), (offset, 1.0),
                         xycoords=("data", "axes fraction"), xytext=(3, -10 - 9 * (n % 3)),
                         textcoords="offset points", fontsize=7, color="tab:red")
    axes[-1].set_xlabel("model time (each command's epoch from its start, laid end to end)")
    axes[0].set_title("convergence metrics; dashed: a command came in force", fontsize=10)
    written.append(out / "metrics.png")
    fig.savefig(str(written[-1]), dpi=110, bbox_inches="tight")
    plt.close(fig)

    if animate:
        written.append(out / "formation.gif")
        animate_run(plt, snaps, data, outlines, written[-1])
    return written


def animate_run(plt, snaps, data, outlines, path):
    from matplotlib.animation import FuncAnimation, PillowWriter
    step = max(1, -(-len(snaps) // MAX_FRAMES))
    frames = snaps[::step]
    if frames[-1] is not snaps[-1]:
        frames.append(snaps[-1])
    # The view holds every position, every recorded centre and the final commanded shape.
    seen = [p for _, _, pts in snaps for p in pts.values()] + [(r["c1"], r["c2"]) for r in data["centre"]]
    epoch, t, pts = snaps[-1]
    seen += outlines.at(epoch, t, [pts[i] for i in sorted(pts)]) or []
    xs, ys = [p[0] for p in seen], [p[1] for p in seen]
    pad = 0.05 * max(max(xs) - min(xs), max(ys) - min(ys), 1.0)
    fig, ax = plt.subplots(figsize=(5.0, 5.0), dpi=80)
    # One set of artists, updated per frame (redrawing the axes per frame is several times slower).
    shape, = ax.plot([], [], "--", color="0.35", lw=1.2, label="commanded shape")
    agents = ax.scatter([], [], s=30, color="tab:blue", zorder=3, label="agents")
    centre, = ax.plot([], [], "x", color="tab:red", ms=8, label="tracked centre")
    title = ax.set_title("", fontsize=9)
    ax.set_xlim(min(xs) - pad, max(xs) + pad)
    ax.set_ylim(min(ys) - pad, max(ys) + pad)
    ax.set_aspect("equal")
    ax.set_xlabel("x1 (shape units)")
    ax.set_ylabel("x2 (shape units)")
    ax.grid(alpha=0.3)
    ax.legend(loc="upper right", fontsize=7)

    def draw(k):
        epoch, t, pts = frames[k]
        xy = [pts[i] for i in sorted(pts)]
        outline = outlines.at(epoch, t, xy) or []
        shape.set_data([p[0] for p in outline], [p[1] for p in outline])
        agents.set_offsets(xy)
        c = outlines.centre_at(epoch, t) if data["commands"].get(epoch, {}).get("tracking.enabled") == "true" else None
        centre.set_data([c[0]] if c else [], [c[1]] if c else [])
        title.set_text("epoch %d (%s), model time %g" % (epoch, describe(data["commands"].get(epoch)), t))
        return shape, agents, centre, title

    FuncAnimation(fig, draw, frames=len(frames)).save(str(path), writer=PillowWriter(fps=10))
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 usage="scripts/plot_run.py RUN_DIR [--out DIR] [--animate] [--sim PATH]",
                                 epilog="The recording layout: docs/RECORDING.md.")
    ap.add_argument("run_dir", metavar="RUN_DIR",
                    help="a recording folder (supervisor or simulator --record) or a launcher run folder")
    ap.add_argument("--out", metavar="DIR", help="where the figures go (default RUN_DIR/figures)")
    ap.add_argument("--animate", action="store_true", help="also write formation.gif (the run as an animation)")
    ap.add_argument("--sim", metavar="PATH",
                    help="the shapeform_sim that draws the commanded shapes (default build/bin/shapeform_sim, "
                         "then PATH)")
    a = ap.parse_args()
    try:
        rec = find_record(a.run_dir)
        out = Path(a.out) if a.out else Path(a.run_dir) / "figures"
        for p in plot(rec, out, a.animate, find_sim(a.sim)):
            print(p)
    except BadInput as e:
        print("plot_run.py: %s" % e, file=sys.stderr)
        return 2
    except (RuntimeError, OSError) as e:
        print("plot_run.py: %s" % e, file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
