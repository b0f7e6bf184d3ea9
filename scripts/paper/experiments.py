#!/usr/bin/python3
"""The experiments of Goswami et al. (arXiv 1410.3864) that scripts/paper/run.py runs on agent processes
and in the simulator, and the simulator-only studies of the published law's limits (shared by run.py,
analyse.py, report.py and scripts/plot_paper.py)."""
from dataclasses import dataclass, field
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
SCEN = REPO / "config" / "scenarios"
AGENT_RATE_HZ = 50.0  # agent.rate_hz of every scenario (the default)

# ---------------------------------------------------------------------------------------------
# The experiments


@dataclass
class Experiment:
    name: str
    group: str  # shape | repulsion | tracking
    scenario: str  # config/scenarios/<scenario>.yaml
    agents: int
    steps: int
    sets: list = field(default_factory=list)  # --set overrides, for both runs
    label: str = ""
    model: dict = field(default_factory=dict)  # the same experiment for async_model.run
    start_offset: tuple = (0.0, 0.0)  # added to the simulator's seeded start


TRACK_C0 = {"line": (-10.0, -10.0), "circle": (6.0, 0.0)}
TRACK_PATH = {"line": dict(path="line", point=(-10.0, -10.0), velocity=(0.1, 0.1)),
              "circle": dict(path="circle", radius=6.0, period=200.0)}
SNAPSHOTS = [40, 80, 120, 160, 200]
SHAPE = {"line": dict(kind="line", m=-1.0, c=5.0), "circle": dict(kind="circle", r0=4.0),
         "ellipse": dict(kind="ellipse", a=4.0, b=2.0), "square": dict(kind="square", a=5.0)}
RING = dict(kind="circle", r0=2.0)


def experiments(quick):
    k_shape = 200 if quick else 500
    k_rep = 200 if quick else 1000
    out = []
    for s, lab in [("line", "line m=-1 c=5"), ("circle", "circle r0=4"), ("ellipse", "ellipse a=4 b=2"),
                   ("square", "square a=5")]:
        out.append(Experiment(f"shape_{s}", "shape", s, 12, k_shape, label=lab, model=dict(shape=SHAPE[s])))
    for s in ("ellipse", "square"):
        out.append(Experiment(f"rep_{s}_r0", "repulsion", f"{s}_no_repulsion", 12, k_rep, label=f"{s}, r=0",
                              model=dict(shape=SHAPE[s], r=0.0)))
        out.append(Experiment(f"rep_{s}_r01", "repulsion", s, 12, k_rep, label=f"{s}, r=0.1",
                              model=dict(shape=SHAPE[s])))
    for p in ("line", "circle"):
        c0 = TRACK_C0[p]
        fixed = dict(path="fixed", point=c0)
        fixed_sets = ["tracking.path=fixed", f"tracking.point=[{c0[0]:g},{c0[1]:g}]"]
        out.append(Experiment(f"track_{p}_paper", "tracking", f"track_{p}", 10, 200,
                              label=f"{p} path, paper law (no feed-forward)",
                              model=dict(shape=RING, track=TRACK_PATH[p])))
        out.append(Experiment(f"track_{p}_ff", "tracking", f"track_{p}", 10, 200, ["tracking.feedforward=true"],
                              label=f"{p} path, feed-forward", model=dict(shape=RING, track=TRACK_PATH[p], ff=True)))
        out.append(Experiment(f"track_{p}_fixed", "tracking", f"track_{p}", 10, 200, fixed_sets,
                              label=f"fixed centre at C(0) = ({c0[0]:g}, {c0[1]:g})",
                              model=dict(shape=RING, track=fixed)))
        if p == "line":
            # The paper's start is 14 units from C(0); the same swarm started around C(0) shows
            # feed-forward on the line path without the far-field escape of the published law.
            out.append(Experiment("track_line_ff_near", "tracking", "track_line", 10, 200,
                                  ["tracking.feedforward=true"], label="line path, feed-forward, start around C(0)",
                                  model=dict(shape=RING, track=TRACK_PATH[p], ff=True), start_offset=c0))
            out.append(Experiment("track_line_fixed_near", "tracking", "track_line", 10, 200, fixed_sets,
                                  label="fixed centre at C(0), start around C(0)",
                                  model=dict(shape=RING, track=fixed), start_offset=c0))
    return out


# Simulator-only studies of the published model's limits (name, scenario, agents, steps, extra args).
def limit_runs(quick):
    k = 500
    return [
        ("circle_n10", "circle", 10, k, []),
        ("circle_n20", "circle", 20, k, []),
        ("circle_n50", "circle", 50, k, []),
        ("line_n12", "line", 12, 1000, []),
        ("line_n15", "line", 15, 1000, []),
        ("line_n20", "line", 20, 1000, []),
        ("circle_rk4", "circle", 12, 10000, ["--integrator", "rk4", "--dt", "0.05"]),
        ("track_line_ff_long", "track_line", 10, 1000, ["--set", "tracking.feedforward=true"]),
    ]


if __name__ == "__main__":
    # A module, not a program: it only says so (scripts/ holds nothing that cannot answer --help).
    import sys as _sys
    print("usage: import experiments -- experiments.py is a module: the table of the reproduction's experiments (scripts/paper/run.py, analyse.py, report.py); it runs nothing itself")
    _sys.exit(0 if _sys.argv[1:] in ([], ["--help"], ["-h"]) else 2)
