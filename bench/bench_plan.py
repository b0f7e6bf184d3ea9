"""What the benchmark can run (see bench.py): the transport presets, the rows of the main table, the
levers (rows measured side by side), the simulator rows, and which of them an invocation runs.

The prose that goes with them (what each preset sets, each lever's question and reading) is in
bench/notes.toml, loaded here as NOTES; bench_report.py renders it.
"""
from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
NOTES: dict = tomllib.loads((Path(__file__).resolve().parent / "notes.toml").read_text())

# --------------------------------------------------------------------------------------------
# Transport presets: --set overrides given to every process of a run (agents, supervisor, probe,
# baseline). "ds" additionally starts a discovery server on 127.0.0.1 for the run.


def large_swarm_sets() -> list[str]:
    """The launcher's large-swarm overrides (config/large_swarm.sets, without its min_agents lines)."""
    lines = (ROOT / "config" / "large_swarm.sets").read_text().splitlines()
    return [ln for ln in lines if "=" in ln and not ln.startswith(("#", "min_agents=", "min_secured_agents="))]


LARGE_MIN = int(next(ln.split("=", 1)[1] for ln in (ROOT / "config" / "large_swarm.sets").read_text().splitlines()
                     if ln.startswith("min_agents=")))
PRESETS: dict[str, dict] = {}


def add_preset(name: str, sets: list[str], ds: bool = False, secure: bool = False) -> None:
    """A preset; what it sets, in words, is its entry of notes.toml [presets]."""
    about = NOTES["presets"][name].format(large_min=LARGE_MIN, large_sets=", ".join(large_swarm_sets()))
    PRESETS[name] = {"sets": sets, "ds": ds, "about": about, "secure": secure}


BUF = "transport.socket_buffer_bytes=4194304"
BUF1 = "transport.socket_buffer_bytes=1048576"
ANN = ["transport.lease_s=10", "transport.announce_s=3"]
MC = "transport.multicast_data=true"
SEDP = "transport.static_edp=true"
add_preset("default", [])
add_preset("buf", [BUF])
add_preset("mc", [MC])
add_preset("mcbuf", [MC, BUF])
add_preset("ann", ANN)
add_preset("bufann", [BUF] + ANN)
add_preset("mcann", [MC] + ANN)
add_preset("mcbuf1ann", [MC, BUF1] + ANN)
add_preset("mcbufann", [MC, BUF] + ANN)
# One AgentStateBatch sample per process and tick however many agents it hosts (up to 1000: 128 KB, which
# Fast DDS fragments), instead of the default parts of at most 500 states (one datagram each).
add_preset("mcbufannfrag", [MC, BUF] + ANN + ["agent.batch_max_states=1000"])
add_preset("mcbufannsec", [MC, BUF] + ANN, secure=True)  # one keystore for the benchmark (make_keystore.sh)
add_preset("large", large_swarm_sets())
add_preset("mcbufannsedp", [MC, BUF, SEDP] + ANN)
add_preset("largesedp", large_swarm_sets() + [SEDP])
add_preset("largequiet", large_swarm_sets() + ["agent.idle_rate_hz=0.2"])
add_preset("largeia1", large_swarm_sets() + ["transport.initial_announcements=1"])
add_preset("largeia20", large_swarm_sets() + ["transport.initial_announcements=20", "transport.initial_announce_s=0.25"])
add_preset("ds", [], ds=True)
add_preset("dsbuf", [BUF], ds=True)
add_preset("dsmcbufann", [MC, BUF] + ANN, ds=True)

# --------------------------------------------------------------------------------------------
# Rows.


@dataclass
class Row:
    """One benchmark row: `kind` processes of N agents at `rate` Hz with a transport preset."""
    kind: str            # baseline | agents | group
    n: int
    rate: float
    preset: str = "default"
    stagger_s: float = 0.0
    group: int = 0       # agents per process (group; baseline: > 0 for the grouped shape, one batch per process)
    section: str = "main"
    view: bool = False   # shapeform_view beside the swarm, one browser-like client reading its event stream
    runs: int = 0        # runs of a main row when not given by --runs (0: the default, 3)
    # The agents' vehicles: "" = the scenario's (the integrator, moving as the law steps); "internal" = the
    # robot model of VEHICLE_SETS integrated by each agent; "ros2" = the same model as robots of one
    # shapeform_vehicle process, driven over ROS 2's topics (vehicle.interface ros2)
    vehicle: str = ""

    @property
    def id(self) -> str:
        r = f"{self.rate:g}"
        s = f"{self.kind}-n{self.n}-r{r}"
        if self.group:
            s += f"-g{self.group}"
        if self.preset != "default":
            s += f"-{self.preset}"
        if self.stagger_s > 0:
            s += f"-st{int(round(self.stagger_s * 1000))}"
        if self.view:
            s += "-view"
        if self.vehicle:
            s += f"-{self.vehicle}"
        return s


# The configuration of the main table: the large-swarm settings the levers below arrived at.
MAIN_PRESET = "mcbufann"
MAIN_STAGGER = 0.0


def main_rows() -> list[Row]:
    rows = []
    for n in (10, 25, 50, 100):
        # At N = 100, what the launcher runs by default (config/large_swarm.sets, from LARGE_MIN agents on);
        # the N = 50 rows keep mcbufann, measured before those settings existed.
        preset = "large" if n >= 100 else MAIN_PRESET
        for rate in ((20.0, 50.0) if n <= 25 else (20.0,)):
            rows.append(Row("baseline", n, rate, preset, MAIN_STAGGER))
            rows.append(Row("agents", n, rate, preset, MAIN_STAGGER, runs=5 if n >= 100 else 0))
    # Several agents per process (shapeform_agent_group), measured the same way, each beside the bare
    # baseline of the same shape (one AgentStateBatch per process and tick). 1000 agents in 10 and in 20
    # processes; those use multicast state (lever 13), the few processes of N <= 100 the defaults.
    for n, k in ((50, 25), (100, 50), (100, 25), (1000, 100), (1000, 50)):
        preset = MAIN_PRESET if n >= 1000 else "default"
        rows.append(Row("baseline", n, 20.0, preset, 0.0, k))
        rows.append(Row("group", n, 20.0, preset, 0.0, k))
    return rows


# How far one host goes: the scale ladder, each grouped row beside its bare baseline of
# the same shape, all at 20 Hz with mcbufann. 10 processes each, the fewest of the 10 to 40 tried: every process
# receives, unpacks and tables every state every tick, so the host's receive work grows as N x processes
# (the 1000-agent rows: 22 % busy in 10 processes, 40 % in 20) and the fewest processes carry the largest N.
# 10000 in 10 is also the most agents a process hosts (1000: --ids, kMaxBatchStates). 4000, between 2000
# and 5000, was added where a first hand run put this host's wall (measured alone later, 5000 still met
# the acceptance: docs/BENCHMARKS.md).
SCALE_SHAPES = ((2000, 200), (4000, 400), (5000, 500), (10000, 1000))
SCALE_PRESET = MAIN_PRESET


def scale_rows() -> list[Row]:
    """The scale ladder (--only scale): for each (N, agents per process) of SCALE_SHAPES, the bare grouped
    baseline and the agents."""
    rows = []
    for n, k in SCALE_SHAPES:
        rows.append(Row("baseline", n, 20.0, SCALE_PRESET, 0.0, k, "scale"))
        rows.append(Row("group", n, 20.0, SCALE_PRESET, 0.0, k, "scale"))
    return rows


# The acceptance of a scale row: (label, key of the row's figures, "min" | "max" | ""
# (converged), limit).
SCALE_VERDICT = (("delivery >= 99 %", "delivery", "min", 0.99), ("data age p99 <= 100 ms", "age_p99_ms", "max", 100.0),
                 ("arc-law circle converged", "converged", "", 0))


def timeouts_of(row: Row, quick: bool) -> tuple[float, float]:
    """(discovery, convergence) timeouts of a row, s: 60 each (40 with --quick) up to 1000 agents, and 10 s
    more per 1000 agents beyond, for the start-up of a process hosting 1000 agents and a supervisor taking
    every state (the 10000-agent rows: 130 s each, 110 s with --quick)."""
    base = 40.0 if quick else 60.0
    extra = 10.0 * max(0, row.n - 1000) / 1000
    return base + extra, base + extra


VEHICLES = ("internal", "ros2")


def row_from_spec(spec: str) -> Row:
    """An ad-hoc row of --row KIND:N:RATE[:PRESET[:STAGGER_S[:GROUP[:FLAG...]]]], FLAG one of view,
    internal, ros2 (the vehicle: Row.vehicle)."""
    parts = spec.split(":")
    flags = parts[6:]
    for f in flags:
        if f not in ("view",) + VEHICLES:
            raise PlanError(f"--row {spec}: unknown flag {f!r}; known: view, {', '.join(VEHICLES)}")
    vehicle = next((f for f in flags if f in VEHICLES), "")
    if vehicle and parts[0] == "baseline":
        raise PlanError(f"--row {spec}: a baseline row has no vehicle")
    return Row(parts[0], int(parts[1]), float(parts[2]), parts[3] if len(parts) > 3 else "default",
               float(parts[4]) if len(parts) > 4 else 0.0, int(parts[5]) if len(parts) > 5 else 0, "experiment",
               "view" in flags, vehicle=vehicle)


# The robot both vehicle rows drive (Row.vehicle): the unicycle of the manual ROS 2 run (docs/VEHICLES.md),
# one law step per tick: seconds_per_model_time = 1 / (rate x integration.dt), the scenario's dt being 1.
VEHICLE_MODEL_SETS = ["vehicle.model=unicycle", "vehicle.max_speed=1", "vehicle.max_yaw_rate=2",
                      "vehicle.heading_spread_deg=180"]


def vehicle_sets(row: Row) -> list[str]:
    """The --set overrides of a row's vehicle, for its agents, its supervisor and its shapeform_vehicle."""
    if not row.vehicle:
        return []
    return VEHICLE_MODEL_SETS + [f"vehicle.seconds_per_model_time={1.0 / row.rate:g}",
                                 f"vehicle.interface={row.vehicle}"]


# --------------------------------------------------------------------------------------------
# Levers: each a set of rows measured side by side. Their names, questions and readings are in
# notes.toml [[levers]]; here, by the number a lever's name starts with, the rows it measures: "pairs"
# (a row and the row it is compared with), "rows" (the table's rows, unless the members of its pairs),
# "extra" (the table of the kernel's UDP counters), "view" (the table of the browser view's figures).


def _lv(kind, n, preset, stagger=0.0, group=0, rate=20.0, vehicle=""):
    return Row(kind, n, rate, preset, stagger, group, "lever", vehicle=vehicle)


B, A, G = "baseline", "agents", "group"
_VIEW = Row(A, 100, 20.0, "mcbufann", 0.0, 0, "lever", True)
LEVER_ROWS: dict[int, dict] = {
    1: {"pairs": [(_lv(B, 50, "default"), _lv(B, 50, "buf")), (_lv(B, 100, "mcann"), _lv(B, 100, "mcbuf1ann")),
                  (_lv(B, 100, "mcann"), _lv(B, 100, "mcbufann"))], "extra": True},
    2: {"pairs": [(_lv(B, 100, "bufann"), _lv(B, 100, "mcbufann")), (_lv(A, 50, "bufann"), _lv(A, 50, "mcbufann")),
                  (_lv(A, 25, "default"), _lv(A, 25, "mcbufann"))], "extra": True},
    3: {"pairs": [(_lv(B, 100, "buf"), _lv(B, 100, "bufann")), (_lv(B, 100, "mcbuf"), _lv(B, 100, "mcbufann"))],
        "extra": True},
    4: {"pairs": [(_lv(A, 50, "default"), _lv(A, 50, "ds")), (_lv(B, 100, "mcbufann"), _lv(B, 100, "dsmcbufann")),
                  (_lv(A, 100, "mcbufann"), _lv(A, 100, "dsmcbufann"))], "extra": True},
    5: {"pairs": [(_lv(B, 100, "mcbufann"), _lv(B, 100, "mcbufann", 0.05)),
                  (_lv(A, 100, "mcbufann"), _lv(A, 100, "mcbufann", 0.05))]},
    6: {"rows": [_lv(A, 100, "mcbufann"), _lv(G, 100, "default", 0.0, 50), _lv(G, 100, "default", 0.0, 25),
                 _lv(G, 100, "default", 0.0, 10)],
        "pairs": [(_lv(A, 100, "mcbufann"), _lv(G, 100, "default", 0.0, 50)),
                  (_lv(A, 100, "mcbufann"), _lv(G, 100, "default", 0.0, 10))]},
    7: {"pairs": []},
    8: {"rows": [_lv(A, 100, "mcbufann"), _VIEW], "pairs": [(_lv(A, 100, "mcbufann"), _VIEW)], "view": True},
    9: {"pairs": [(_lv(A, 10, "mcbufann"), _lv(A, 10, "mcbufannsec")),
                  (_lv(A, 25, "mcbufann"), _lv(A, 25, "mcbufannsec"))]},
    10: {"pairs": [(_lv(A, 100, "mcbufann"), _lv(A, 100, "large"))]},
    11: {"pairs": [(_lv(A, 100, "mcbufann"), _lv(A, 100, "large"))]},
    12: {"pairs": [(_lv(B, 100, "mcbufann"), _lv(B, 100, "mcbufannsedp")),
                   (_lv(A, 100, "mcbufann"), _lv(A, 100, "mcbufannsedp")),
                   (_lv(A, 100, "large"), _lv(A, 100, "largesedp"))], "extra": True},
    13: {"pairs": [(_lv(B, 1000, "default", 0.0, 100), _lv(B, 1000, MAIN_PRESET, 0.0, 100)),
                   (_lv(G, 1000, "default", 0.0, 100), _lv(G, 1000, MAIN_PRESET, 0.0, 100)),
                   (_lv(B, 1000, "default", 0.0, 50), _lv(B, 1000, MAIN_PRESET, 0.0, 50)),
                   (_lv(G, 1000, "default", 0.0, 50), _lv(G, 1000, MAIN_PRESET, 0.0, 50))], "extra": True},
    14: {"pairs": [(_lv(A, 100, "large"), _lv(A, 100, "largeia1")), (_lv(A, 100, "large"), _lv(A, 100, "largeia20"))],
         "extra": True},
    15: {"rows": [_lv(A, 50, "largequiet"), _lv(A, 75, "largequiet"), _lv(A, 100, "largequiet")], "pairs": [],
         "extra": True},
    16: {"pairs": [(_lv(A, n, MAIN_PRESET, vehicle="internal"), _lv(A, n, MAIN_PRESET, vehicle="ros2"))
                   for n in (12, 50)], "vehicle": True},
    # 1000 agents per process (128 KB of states per tick) in shapes this host runs at 20 Hz.
    17: {"pairs": [(_lv(B, 5000, MAIN_PRESET, 0.0, 1000), _lv(B, 5000, "mcbufannfrag", 0.0, 1000)),
                   (_lv(G, 2000, MAIN_PRESET, 0.0, 1000), _lv(G, 2000, "mcbufannfrag", 0.0, 1000))], "extra": True},
}


def _levers() -> list[dict]:
    """The levers in the order of notes.toml: {name, question, note (if any), pairs, rows, extra, view}."""
    levers = []
    for text in NOTES["levers"]:
        lever = {"name": text["name"], "question": text["question"].format(large_min=LARGE_MIN)}
        if "note" in text:
            lever["note"] = text["note"]
        lever.update(LEVER_ROWS[int(text["name"].split(".")[0])])
        # The rows of a lever, unless listed: the members of its pairs, in order.
        lever.setdefault("rows", list({r.id: r for pair in lever["pairs"] for r in pair}.values()))
        levers.append(lever)
    if len(levers) != len(LEVER_ROWS):
        raise RuntimeError("bench/notes.toml [[levers]] and bench_plan.LEVER_ROWS name different levers")
    return levers


LEVERS: list[dict] = _levers()


def lever_rows() -> list[Row]:
    """Every lever's rows, in order (a row may appear under several levers)."""
    return [r for lv in LEVERS for r in lv["rows"]]


# --------------------------------------------------------------------------------------------
# Simulator throughput (shapeform_bench_sim, one JSON object per call).

# (agents, impl, instruction set ("best": the one the simulator picks), threads, steps per call, beta
# (None: the paper's 1.2)). One thread runs on core 0 only (taskset -c 0), two on both cores. Steps
# chosen so one call takes about a second on this machine; --quick takes a quarter.
# A beta = 0 row (the pass without a weight) follows its paper row at once: the report subtracts one from
# the other, and this host's speed drifts by 10 to 20 % over minutes.
SIM_ROWS = [(100, "fast", "best", 1, 5000, None), (100, "reference", None, 1, 1000, None),
            (1000, "fast", "best", 1, 1500, None), (1000, "fast", "best", 1, 4000, 0.0),
            (1000, "fast", "best", 1, 4000, 1.0),
            (1000, "fast", "avx2", 1, 500, None), (1000, "fast", "generic", 1, 200, None),
            (1000, "reference", None, 1, 20, None),
            (10000, "fast", "best", 1, 20, None), (10000, "fast", "best", 1, 60, 0.0),
            (10000, "fast", "best", 2, 40, None),
            (10000, "reference", None, 1, 1, None)]

# --------------------------------------------------------------------------------------------
# What one invocation runs.

SCENARIO_SETS: list[str] = []  # --set overrides of the scenario for the agents and the supervisor


class PlanError(Exception):
    """A selection that names nothing runnable (bench.py prints it and exits 2)."""


def lever_of(name: str) -> dict | None:
    """The lever an --only value `leverK` names (K its number), else None."""
    if not (name.startswith("lever") and name[5:].isdigit()):
        return None
    return next((lv for lv in LEVERS if lv["name"].split(".")[0] == name[5:]), None)


def select_rows(args, stored: dict) -> tuple[list[Row], bool]:
    """The rows this invocation runs, in order and each once, and whether it runs the simulator rows.
    `stored`: the stored results by row id."""
    all_rows, levers, scale = main_rows(), lever_rows(), scale_rows()
    selected: list[Row] = []
    if not args.no_main:
        selected += all_rows
    if not getattr(args, "no_scale", False):
        selected += scale
    if args.levers:
        # With --no-main, a lever row that is also a main row keeps its stored main result (median of its runs).
        selected += [r for r in levers if not (args.no_main and r.id in {m.id for m in all_rows} and r.id in stored)]
    for spec in args.row:
        r = row_from_spec(spec)
        if r.preset not in PRESETS:
            raise PlanError(f"unknown preset {r.preset}; known: {', '.join(PRESETS)}")
        selected.append(r)
    run_sim = not args.no_sim and ((not args.only and not args.row) or "sim" in args.only)
    only_rows = [o for o in args.only if o != "sim"]
    if args.only:
        pool = all_rows + scale + levers + selected
        ids = {r.id for r in pool}
        # `leverK`: the rows of lever K; `scale`: the scale ladder.
        named = [r.id for o in only_rows if lever_of(o) for r in lever_of(o)["rows"]]
        named += [r.id for o in only_rows if o == "scale" for r in scale]
        bad = [o for o in only_rows if o.startswith("lever") and o[5:].isdigit() and not lever_of(o)]
        if bad:
            raise PlanError(f"--only {bad[0]}: no such lever (1..{len(LEVERS)})")
        # A row id selects that row; anything else is a prefix (agents-n100 selects every N = 100 agent row).
        selected = [r for r in dict((r.id, r) for r in pool).values()
                    if r.id in named or any(r.id == o or (o not in ids and r.id.startswith(o)) for o in only_rows)]
        if not selected and not run_sim:
            raise PlanError("--only matched no row (see --list)")
    seen = set()
    selected = [r for r in selected if not (r.id in seen or seen.add(r.id))]
    main_ids, scale_ids = {r.id for r in all_rows}, {r.id for r in scale}
    for row in selected:
        if row.id in main_ids:
            row.section = "main"
        elif row.id in scale_ids:
            row.section = "scale"
    return selected, run_sim


def runs_of(row: Row, args, runs: int) -> int:
    """Runs of a row: --runs, else a main or scale row's own count or `runs`, a lever row's --lever-runs."""
    return args.runs or (row.runs or runs if row.section in ("main", "scale") else args.lever_runs)


def window_of(row: Row, args) -> float:
    """The measurement window, s: --window, else 12 with --quick, else max(30 s, 1100 ticks)."""
    return args.window or (12.0 if args.quick else max(30.0, math.ceil(1100 / row.rate)))


def rerun_command(row: Row, args, runs: int) -> str:
    cmd = "scripts/bench.sh"
    if args.quick:
        cmd += " --quick"
    if row.section == "experiment":
        spec = (f"{row.kind}:{row.n}:{row.rate:g}:{row.preset}:{row.stagger_s:g}:{row.group}" + (":view" if row.view else "")
                + (f":{row.vehicle}" if row.vehicle else ""))
        return f"{cmd} --runs {runs} --row {spec} --only {row.id}"
    return f"{cmd} --runs {runs} --only {row.id}"
