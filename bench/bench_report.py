#!/usr/bin/python3
"""Simulator rows and the Markdown report of the benchmark (see bench.py).

render() turns a results file (bench_results.json) into BENCHMARKS.md; every number in the report comes
from that file, which bench.py fills from the processes' own reports, and its prose from bench/notes.toml
(report_plan() pairs the two). Run on its own it renders a report:

usage: bench/bench_report.py [RESULTS_JSON] [--out MD | --write-docs]

RESULTS_JSON defaults to the committed docs/figures/bench_results.json; the report goes to MD (default
runs/<UTC time>-bench/BENCHMARKS.md), or with --write-docs to the committed docs/BENCHMARKS.md.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

sys.dont_write_bytecode = True  # no __pycache__ beside the sources
sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_plan import (LARGE_MIN, LEVERS, MAIN_PRESET, NOTES, PRESETS, ROOT, SCALE_VERDICT, main_rows,  # noqa: E402
                        scale_rows)

# --------------------------------------------------------------------------------------------
# The simulator's rows (bench_run.sim_rows measures them).

# The simulator's throughput targets, Euler steps/s: N = 1000 on one core, N = 10000 on one core or both.
SIM_TARGETS = {1000: 1000.0, 10000: 20.0}
# Multiply-adds and multiplies per pair in the AVX-512 pair pass (common/core/batch_avx512.cpp), counted
# in its compiled loops by bench/sim_loop_count.py (objdump of batch_avx512.cpp.o; the test
# sim_loop_count fails while they differ). 2026-12-05, the three sweeps: 50 vfmadd/vfnmadd/vmulpd
# among 125 vector instructions per 16 pairs (2 rows x 8 lanes): the power 19 (the logarithm's reduction
# and degree-6 polynomial with its powers of r, the exponential's degree-5 polynomial, the table factor),
# the squared distance 2, the four sums 4. The least time a pair can take on this core is that many over
# the peak multiply-add rate.
SIM_FMA_PER_PAIR = 25
# Of those, the weight's (sigma^2 + d^2)^-beta: the power's 19. The rest (squared distance, sums) is all a
# pass with beta = 0 computes (weight 1: batch_kernel.hpp, HalfBeta<0>).
SIM_FMA_WEIGHT = 19
# The simulator's target against that bound: a pair within this many times the time the peak allows.
SIM_BOUND_TARGET = 1.3


def sim_label(r: dict) -> str:
    if r["impl"] == "reference":
        return f"sim {r['agents']} reference"
    return (f"sim {r['agents']} fast {r.get('simd') or '?'}" + (f" {r['threads']} threads" if r["threads"] > 1 else "")
            + (f" beta {r['beta']:g}" if r.get("beta") is not None else ""))


def sim_best(sim: dict, n: int, threads: int) -> dict | None:
    """The default fast row (the instruction set the simulator picks) at N = n on `threads` threads."""
    best = None
    for simd in ("generic", "avx2", "avx512"):
        if simd in (sim.get("peak") or {}):
            best = simd
    for r in sim.get("rows", []):
        if (r["agents"] == n and r["impl"] == "fast" and r.get("simd") == best and r.get("threads", 1) == threads
                and r.get("beta") is None):
            return r
    return None


def sim_target_rows(sim: dict) -> str:
    """The simulator's lines of the targets table."""
    if not sim.get("available"):
        return ("| Simulator N=1000: >= 1000 Euler steps/s on one core | - | not run | - |\n"
                "| Simulator N=10000: >= 20 Euler steps/s | - | not run | - |\n")
    o = ""
    one = sim_best(sim, 1000, 1)
    v = one.get("steps_per_s") if one else None
    txt, verdict = verdict_min(v, SIM_TARGETS[1000], lambda x: f"{x:,.0f} steps/s")
    o += f"| Simulator N=1000: >= 1000 Euler steps/s on one core | `{sim_label(one) if one else '-'}` | {txt} | {verdict} |\n"
    one, two = sim_best(sim, 10000, 1), sim_best(sim, 10000, 2)
    v1 = one.get("steps_per_s") if one else None
    v2 = two.get("steps_per_s") if two else None
    t1, d1 = verdict_min(v1, SIM_TARGETS[10000], lambda x: f"{x:.1f} steps/s")
    t2, d2 = verdict_min(v2, SIM_TARGETS[10000], lambda x: f"{x:.1f} steps/s")
    o += (f"| Simulator N=10000: >= 20 Euler steps/s | `{sim_label(one) if one else '-'}`, "
          f"`{sim_label(two) if two else '-'}` | one core: {t1}; both cores: {t2} | one core: {d1}; both cores: {d2} |\n")
    return o


def sim_line(sim: dict, r: dict, ref: dict) -> str:
    """One simulator row of the table; ref: the reference rows' steps/s by N."""
    sps = r.get("steps_per_s")
    n, fast = r["agents"], r["impl"] == "fast"
    speed = f"x{sps / ref[n]:.1f}" if fast and sps and ref.get(n) and r.get("beta") is None else ""
    target = SIM_TARGETS.get(n) if fast and r is sim_best(sim, n, r.get("threads", 1)) else None
    if target is None or (n == 1000 and r.get("threads", 1) != 1):
        tgt, verdict = "", ""
    else:
        tgt = f">= {target:g}/s"
        verdict = "met" if sps is not None and sps >= target else (
            f"**missed** by {target - sps:.1f}/s" if sps is not None else "not measured")
    val = f"{sps:,.1f}" if sps is not None else f"failed: {r.get('error', '?')}"
    beta = "1.2 (paper)" if r.get("beta") is None else f"{r['beta']:g}"
    return (f"| {n} | {r['impl']} | {beta} | {r.get('simd') or 'scalar'} | {r.get('threads', 1)} | {val} "
            f"| {f_num(r.get('ns_per_pair'), '{:.2f}')} | {f_num(r.get('rss_mb'))} | {speed} "
            f"| {f_num(r.get('other_load'), '{:.2f}')} | {tgt} | {verdict} |\n")


def row_peak(row: dict, peak: float) -> float:
    """The peak multiply-add rate to set a simulator row against: the one measured beside its calls, else
    the section's (results stored before rows carried their own)."""
    return row.get("peak_fma_per_s") or peak


def sim_weight_text(sim: dict, template: str, rows: list, peak: float) -> str:
    """What the weight costs of a pair: the paper's rows against the rows with beta = 0 (no weight), and
    what a pair would take with the weight at the peak (each row's own); "" without beta = 0 rows."""
    zero = {r["agents"]: r for r in sim.get("rows", [])
            if r["impl"] == "fast" and r.get("beta") == 0.0 and r.get("threads", 1) == 1 and r.get("simd") == "avx512"}
    cases = [(n, r["ns_per_pair"], zero[n]["ns_per_pair"], row_peak(r, peak)) for n, r in rows
             if r and r.get("ns_per_pair") and n in zero and zero[n].get("ns_per_pair")]
    if not cases:
        return ""
    each = lambda f: "; ".join(f"N = {n}: {f(paper, rest):.2f} ns" for n, paper, rest, _ in cases)

    def floor(rest, pk):
        at_peak, bound = SIM_FMA_WEIGHT / pk * 1e9, SIM_FMA_PER_PAIR / pk * 1e9
        x = (rest + at_peak) / bound
        reach = ("within the target only if the weight's other operations took no time" if x <= SIM_BOUND_TARGET
                 else "beyond the target even so")
        return f"{rest + at_peak:.2f} ns, x{x:.2f} the bound, {reach}"

    pk = cases[-1][3]
    return template.format(rest=each(lambda paper, rest: rest), weight=each(lambda paper, rest: paper - rest),
                           wfma=SIM_FMA_WEIGHT, wpeak=SIM_FMA_WEIGHT / pk * 1e9,
                           floor="; ".join(f"N = {n}: {floor(rest, p)}" for n, _, rest, p in cases),
                           factor=SIM_BOUND_TARGET, target=SIM_BOUND_TARGET * SIM_FMA_PER_PAIR / pk * 1e9)


def sim_section(sim: dict) -> str:
    o = ["## Simulator\n\n"]
    if not sim.get("available"):
        o.append("`build/bin/shapeform_bench_sim` was not built when this report was generated.\n\n")
        return "".join(o)
    peak = sim.get("peak") or {}
    text = NOTES["sim"]
    o.append(text["intro"] + "\n\n")
    o.append("| N | impl | beta | instruction set | cores | Euler steps/s | ns per pair | RSS MB | speed-up vs reference "
             "| other load | target | verdict |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n")
    ref = {r["agents"]: r.get("steps_per_s") for r in sim["rows"] if r["impl"] == "reference"}
    for r in sim["rows"]:
        o.append(sim_line(sim, r, ref))
    o.append("\n")
    if peak:
        o.append(text["peak"].format(peaks=", ".join(f"{k} {v / 1e9:.1f} G/s" for k, v in peak.items())))
        # The two sizes of the simulator's targets (1000 and 10000 agents), on one core with AVX-512, against the bound.
        bound = SIM_FMA_PER_PAIR / peak["avx512"] * 1e9 if "avx512" in peak else None
        rows = [(n, sim_best(sim, n, 1)) for n in (1000, 10000)]

        def against(r):
            pk = row_peak(r, peak["avx512"])
            own = f", its peak {pk / 1e9:.1f} G/s" if r.get("peak_fma_per_s") else ""
            return f"{r['ns_per_pair']:.2f} ns, x{r['ns_per_pair'] / (SIM_FMA_PER_PAIR / pk * 1e9):.2f} the bound{own}"

        measured = "; ".join(f"N = {n}: {against(r)}" for n, r in rows
                             if bound and r and r.get("simd") == "avx512" and r.get("ns_per_pair"))
        if measured:
            o.append(text["bound"].format(fma=SIM_FMA_PER_PAIR, bound=bound, measured=measured))
        o.append(text["limits"] + "\n\n")
        if measured:
            weight = sim_weight_text(sim, text["weight"], rows, peak["avx512"])
            o.append(weight + "\n\n" if weight else "")
    return "".join(o)


# --------------------------------------------------------------------------------------------
# Formatting.


def f_s(v):
    if v is None:
        return "-"
    if isinstance(v, float) and math.isinf(v):
        return "never"
    return f"{v:.1f} s"


def f_pct(v, digits=2):
    return "-" if v is None else f"{100 * v:.{digits}f} %"


def f_ms(v):
    if v is None:
        return "-"
    if v < 1:
        return f"{v:.2f} ms"
    if v < 10:
        return f"{v:.1f} ms"
    return f"{v:.0f} ms"


def f_num(v, fmt="{:.1f}"):
    return "-" if v is None else fmt.format(v)


def _disc(a: dict) -> str:
    """Datagrams received from launch to all hear all (or the command), and in how many seconds."""
    if a.get("disc_udp_in") is None:
        return "-"
    return f"{a['disc_udp_in']:,.0f}" + (f" in {a['disc_udp_s']:.0f} s" if a.get("disc_udp_s") is not None else "")


def ratio(a, b):
    if a is None or b is None:
        return "-"
    if isinstance(a, float) and math.isinf(a):
        return "never"
    if isinstance(b, float) and math.isinf(b):
        return "-"
    if b == 0:
        return "-"
    return f"x{a / b:.2f}"


def processes(row: dict) -> str:
    if row.get("group"):
        k = row["group"]
        return f"{math.ceil(row['n'] / k)} x {k} agents"
    return f"{row['n']}"


def row_label(row: dict) -> str:
    kind = {"baseline": "baseline", "agents": "agents", "group": "agents (grouped)"}[row["kind"]]
    return "baseline (grouped)" if row["kind"] == "baseline" and row.get("group") else kind


TABLE_HEAD = ("| row | kind | N | rate | processes | config | all hear all | delivery | age p50 | age p99 | age p99 worst window "
              "| lateness p99 | overruns | CPU %/agent | RSS MB/agent | supervisor CPU % | launch to converged "
              "| aborts | host busy | other load |\n"
              "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n")


def table_line(rid: str, e: dict) -> str:
    r, a = e["row"], e["agg"]
    conv = a.get("converge_s")
    conv_txt = f_s(conv) if r["kind"] != "baseline" else "n/a"
    st = f" +{r['stagger_s'] * 1000:.0f} ms stagger" if r.get("stagger_s") else ""
    aborts = a.get("aborts_total", 0)
    runs = a.get("runs", 1)
    veh = f", vehicle {r['vehicle']}" if r.get("vehicle") else ""
    return (f"| `{rid}` | {row_label(r)} | {r['n']} | {r['rate']:g} Hz | {processes(r)} | {r['preset']}{st}{veh} "
            f"| {f_s(a.get('all_heard_s'))} | {f_pct(a.get('delivery'))} | {f_ms(a.get('age_p50_ms'))} "
            f"| {f_ms(a.get('age_p99_ms'))} | {f_ms(a.get('age_p99_worst_ms'))} | {f_ms(a.get('lateness_p99_ms'))} "
            f"| {f_num(a.get('overrun_pct'), '{:.2f} %')} | {f_num(a.get('cpu_pct'), '{:.2f}')} "
            f"| {f_num(a.get('rss_mb'))} | {f_num(a.get('sup_cpu_pct')) if r['kind'] != 'baseline' else 'n/a'} "
            f"| {conv_txt} | {aborts} in {runs} run{'s' if runs != 1 else ''} | {f_num(a.get('host_busy_pct'), '{:.0f} %')} "
            f"| {f_num(a.get('other_cpu_pct'), '{:.0f} %')} |\n")


def ratio_line(rid: str, e: dict, base: dict | None) -> str:
    a = e["agg"]
    b = base["agg"] if base else {}
    return (f"| `{rid}` | `{base['row']['id'] if base else '-'}` | {ratio(a.get('all_heard_s'), b.get('all_heard_s'))} "
            f"| {ratio(a.get('delivery'), b.get('delivery'))} | {ratio(a.get('age_p50_ms'), b.get('age_p50_ms'))} "
            f"| {ratio(a.get('age_p99_ms'), b.get('age_p99_ms'))} | {ratio(a.get('lateness_p99_ms'), b.get('lateness_p99_ms'))} "
            f"| {ratio(a.get('cpu_pct'), b.get('cpu_pct'))} | {ratio(a.get('rss_mb'), b.get('rss_mb'))} "
            f"| {ratio(a.get('ours_cpu_pct'), b.get('ours_cpu_pct'))} "
            f"| {ratio(a.get('host_busy_pct'), b.get('host_busy_pct'))} |\n")


RATIO_HEAD = ("| agent row | baseline row | all hear all | delivery | age p50 | age p99 | lateness p99 | CPU/agent | RSS/agent "
              "| CPU, all processes | host busy |\n"
              "|---|---|---|---|---|---|---|---|---|---|---|\n")


def baseline_for(rows: dict, e: dict) -> dict | None:
    """The baseline row of the same N, rate, transport and shape (agents per process), with the same
    stagger if measured, else without."""
    r = e["row"]
    bid = f"baseline-n{r['n']}-r{r['rate']:g}" + (f"-g{r['group']}" if r.get("group") else "") + \
        (f"-{r['preset']}" if r["preset"] != "default" else "")
    if r.get("stagger_s") and bid + f"-st{int(round(r['stagger_s'] * 1000))}" in rows:
        return rows[bid + f"-st{int(round(r['stagger_s'] * 1000))}"]
    return rows.get(bid)


def pair_effect(rows: dict, a_id: str, b_id: str) -> str:
    """One line: how the key figures changed from row a to row b."""
    a, b = rows[a_id]["agg"], rows[b_id]["agg"]

    def ch(key, f):
        va, vb = a.get(key), b.get(key)
        if va is None and vb is None:
            return None
        return f"{f(va)} -> {f(vb)}"

    parts = [("delivery", ch("delivery", f_pct)), ("age p50", ch("age_p50_ms", f_ms)), ("age p99", ch("age_p99_ms", f_ms)),
             ("all hear all", ch("all_heard_s", f_s)),
             ("receive-buffer drops/s", ch("udp_rcvbuf_errors_per_s", lambda v: f_num(v, "{:,.0f}"))),
             ("UDP datagrams received/s", ch("udp_in_per_s", lambda v: f_num(v, "{:,.0f}"))),
             ("CPU %/agent", ch("cpu_pct", lambda v: f_num(v, "{:.2f}"))),
             ("control latency p50", ch("control_p50_ms", f_ms)), ("control latency p99", ch("control_p99_ms", f_ms)),
             ("aborts", ch("aborts_total", lambda v: "-" if v is None else str(int(v))))]
    return f"`{a_id}` -> `{b_id}`: " + ", ".join(f"{k} {v}" for k, v in parts if v)


# --------------------------------------------------------------------------------------------
# Targets.


def verdict_max(v, limit, unit_fmt):
    if v is None:
        return "not measured", "-"
    if isinstance(v, float) and math.isinf(v):
        return "never", "**missed**"
    if v <= limit:
        return unit_fmt(v), "met"
    return unit_fmt(v), f"**missed** by {unit_fmt(v - limit)} (x{v / limit:.2f})"


def verdict_min(v, limit, unit_fmt):
    if v is None:
        return "not measured", "-"
    if v >= limit:
        return unit_fmt(v), "met"
    return unit_fmt(v), f"**missed** by {unit_fmt(limit - v)}"


def target_line(rows: dict, rid: str, e: dict, target: tuple) -> str:
    """One target's line for the measured row e."""
    label, key, kind, limit, fmt = target
    a = e["agg"]
    if key == "aborts_total":
        v = a.get("aborts_total", 0)
        runs = a.get("runs", 1)
        return f"| {label} | `{rid}` | {v} in {runs} run{'s' if runs != 1 else ''} | {'met' if v == 0 else '**missed**'} |\n"
    if key == "converged":
        # Met only when every run converged (the first converged SwarmMetrics sample); the median
        # time and the supervisor's final verdict are shown beside it.
        c, runs = a.get("converge_s"), a.get("runs", 1)
        n_conv = a.get("converged_runs", 0 if c is None or math.isinf(c) else runs)
        ok = n_conv == runs
        return (f"| {label} | `{rid}` | converged in {n_conv} of {runs} runs, median {f_s(c)} (the supervisor's "
                f"final summary: converged in {a.get('sup_converged_runs', 0)}) | {'met' if ok else '**missed**'} |\n")
    if key.startswith("ratio:"):  # the row's figure over its baseline's (same N, rate, transport, shape)
        base = baseline_for(rows, e)
        k = key[len("ratio:"):]
        if base is None or a.get(k) is None or not base["agg"].get(k):
            return f"| {label} | `{rid}` | no baseline | - |\n"
        v = a[k] / base["agg"][k]
        txt, verdict = verdict_max(v, limit, lambda x: f"{x:.2f}")
        return f"| {label} | `{rid}` vs `{base['row']['id']}` | x{txt} | {verdict} |\n"
    v = a.get(key)
    txt, verdict = (verdict_min if kind == "min" else verdict_max)(v, limit, fmt)
    return f"| {label} | `{rid}` | {txt} | {verdict} |\n"


def target_rows(rows: dict, rid: str, targets: list) -> str:
    e = rows.get(rid)
    if e is None:
        return "".join(f"| {t[0]} | `{rid}` | not run | - |\n" for t in targets)
    return "".join(target_line(rows, rid, e, t) for t in targets)


def _pct(v):
    return f"{100 * v:.2f} %"


def _secs(v):
    return f"{v:.1f} s"


# (label, key of the row's figures, "min" | "max" | "" (special), limit, format of the measured value)
TARGETS_100 = [
    ("N=100 at 20 Hz: delivery >= 99 %", "delivery", "min", 0.99, _pct),
    ("N=100 at 20 Hz: data age p99 <= 100 ms", "age_p99_ms", "max", 100.0, f_ms),
    ("N=100 at 20 Hz: everyone hears everyone within 10 s", "all_heard_s", "max", 10.0, _secs),
    ("N=100 at 20 Hz: no process aborts", "aborts_total", "max", 0, str),
    ("N=100 at 20 Hz: the circle converges", "converged", "", 0, str),
]
TARGETS_1000 = [
    ("N=1000 at 20 Hz, 10-20 processes: delivery >= 99 %", "delivery", "min", 0.99, _pct),
    ("N=1000 at 20 Hz, 10-20 processes: data age p99 <= 100 ms", "age_p99_ms", "max", 100.0, f_ms),
    ("N=1000 at 20 Hz, 10-20 processes: everyone hears everyone within 10 s", "all_heard_s", "max", 10.0, _secs),
    ("N=1000 at 20 Hz, 10-20 processes: the arc-law circle converges", "converged", "", 0, str),
    ("N=1000 at 20 Hz, 10-20 processes: the host at most half busy", "host_busy_pct", "max", 50.0,
     lambda v: f"{v:.0f} %"),
    # A grouped swarm at the transport's floor: within 1.2x of its bare baseline of the same shape.
    ("N=1000 at 20 Hz, 10-20 processes: host busy within 1.2x of the baseline", "ratio:host_busy_pct", "max", 1.2,
     str),
    ("N=1000 at 20 Hz, 10-20 processes: CPU per agent within 1.2x of the baseline", "ratio:cpu_pct", "max", 1.2, str),
    # The CPU time of every process of the run (agents, supervisor, probe), which each process's own
    # accounting gives exactly; the host's /proc/stat figure samples at the timer tick.
    ("N=1000 at 20 Hz, 10-20 processes: CPU of all the run's processes within 1.2x of the baseline",
     "ratio:ours_cpu_pct", "max", 1.2, str),
    ("N=1000 at 20 Hz, 10-20 processes: data age p99 within 1.2x of the baseline", "ratio:age_p99_ms", "max", 1.2,
     str),
]
TARGETS_25 = [
    ("N=25 at 20 Hz: data age p50 <= 1 ms", "age_p50_ms", "max", 1.0, f_ms),
    ("N=25 at 20 Hz: data age p99 <= 5 ms", "age_p99_ms", "max", 5.0, f_ms),
    ("N=25 at 20 Hz: p50 age within 1.5x of the baseline", "ratio:age_p50_ms", "max", 1.5, str),
    ("N=25 at 20 Hz: p99 age within 1.5x of the baseline", "ratio:age_p99_ms", "max", 1.5, str),
    ("N=25 at 20 Hz: RSS <= 20 MB per agent", "rss_mb", "max", 20.0, lambda v: f"{v:.1f} MB"),
    ("N=25 at 20 Hz: loop lateness p99 <= 1 ms", "lateness_p99_ms", "max", 1.0, f_ms),
]

# --------------------------------------------------------------------------------------------
# What the report says about the measured rows: report_plan() pairs the rows of bench_plan and the
# prose of notes.toml with the stored results.

MP = MAIN_PRESET
# The rows the headline, the targets and 'what limits' speak of, by the names notes.toml uses.
ROW_NAMES = {
    "n100": "agents-n100-r20-large", "ds100": f"agents-n100-r20-ds{MP}", "b100": "baseline-n100-r20-large",
    "g1000": f"group-n1000-r20-g100-{MP}", "bg1000": f"baseline-n1000-r20-g100-{MP}",
    "g1000b": f"group-n1000-r20-g50-{MP}", "bg1000b": f"baseline-n1000-r20-g50-{MP}",
    "g50": "group-n100-r20-g50", "g25": "group-n100-r20-g25",
    "n25": f"agents-n25-r20-{MP}", "b25": f"baseline-n25-r20-{MP}",
}


def _get(store, rid, key):
    e = store.get("rows", {}).get(rid)
    return e["agg"].get(key) if e else None


def _summary(store, rid) -> str:
    e = store.get("rows", {}).get(rid)
    if not e:
        return f"`{rid}`: not run yet"
    a = e["agg"]
    conv = f_s(a.get("converge_s")) if e["row"]["kind"] != "baseline" else "n/a"
    return (f"delivery {f_pct(a.get('delivery'))}, data age p50 {f_ms(a.get('age_p50_ms'))} / p99 "
            f"{f_ms(a.get('age_p99_ms'))}, everyone hears everyone: {f_s(a.get('all_heard_s'))}, "
            f"launch to converged: {conv}, {a.get('aborts_total', 0)} aborted processes in {a.get('runs', 1)} runs, "
            f"host {a.get('host_busy_pct', 0) or 0:.0f} % busy (`{rid}`)")


def headline(store: dict) -> list[str]:
    """The headline's lines: its heading, then a bullet per notes.toml [report] headline."""
    summaries = {name: _summary(store, rid) for name, rid in ROW_NAMES.items()}
    return ["## Headline\n"] + [line.format(**summaries) for line in NOTES["report"]["headline"]]


def _disc_reading(store: dict) -> str:
    """The measured cost of discovery (lever 15), as a clause; empty until measured."""
    parts = []
    for n in (50, 75, 100):
        rid = f"agents-n{n}-r20-largequiet"
        d, t, heard = _get(store, rid, "disc_udp_in"), _get(store, rid, "disc_udp_s"), _get(store, rid, "all_heard_s")
        if d is None or t is None:
            continue
        done = heard is not None and not math.isinf(heard)
        parts.append(f"N = {n}: {d / 1e6:.1f} million in {t:.0f} s" + ("" if done else " without finishing"))
    if not parts:
        return ""
    return NOTES["limits"]["discovery_cost"].format(readings="; ".join(parts))


def _limits_1000(store: dict) -> str:
    """What limits 1000 agents in groups, from the measured rows (empty until they are measured)."""
    text = NOTES["limits"]
    names = {"g100": "g1000", "g50": "g1000b", "b100": "bg1000", "b50": "bg1000b"}
    busy = {k: _get(store, ROW_NAMES[name], "host_busy_pct") for k, name in names.items()}
    if None in busy.values():
        return ""
    uni = {f"g{k}": _get(store, f"group-n1000-r20-g{k}", "host_busy_pct") for k in (100, 50)}
    uni_txt = text["groups_1000_unicast"].format(**uni) if None not in uni.values() else ""
    return text["groups_1000"].format(**busy) + uni_txt


def _meets_100(store: dict, rid: str) -> bool:
    """Whether a row meets every N = 100 target."""
    d, p99, heard = _get(store, rid, "delivery"), _get(store, rid, "age_p99_ms"), _get(store, rid, "all_heard_s")
    conv, aborts = _get(store, rid, "converge_s"), _get(store, rid, "aborts_total")
    return (None not in (d, p99, heard, conv) and d >= 0.99 and p99 <= 100 and heard <= 10
            and not math.isinf(conv) and not aborts)


def limits_text(store: dict) -> str:
    """'What limits N = 100 processes': the pieces of notes.toml [limits], with the measured figures."""
    text = NOTES["limits"]
    b100 = ROW_NAMES["b100"]
    busy, udp_in, ours = (_get(store, b100, k) for k in ("host_busy_pct", "udp_in_per_s", "ours_cpu_pct"))
    ds_busy = _get(store, ROW_NAMES["ds100"], "host_busy_pct")
    g_busy = _get(store, ROW_NAMES["g50"], "host_busy_pct")
    o = [text["opening"]]
    if None not in (busy, udp_in, ours):
        o.append(text["baseline_floor"].format(udp_in=udp_in, ours=ours, busy=busy))
    o.append(text["load"])
    if ds_busy is not None:
        o.append(text["ds_busy"].format(busy=ds_busy))
    o.append(text["grouping"])
    if g_busy is not None:
        o.append(text["group_busy"].format(busy=g_busy))
    o.append(text["group_meets"] if _meets_100(store, ROW_NAMES["g50"]) else ".")
    if _meets_100(store, ROW_NAMES["n100"]):
        o.append(text["agents_meet"])
    o += [text["discovery"], _disc_reading(store), ".", _limits_1000(store)]
    return "".join(o)


def report_plan(store: dict) -> dict:
    """What render() writes besides the tables: {"main": [row ids], "targets": [(row id, targets)],
    "headline": [lines], "limits", "main_intro", "levers": [{name, question, rows, pairs, note, extra,
    view, vehicle}], "levers_intro", "presets": {name: about}, "method"}."""
    r, report = ROW_NAMES, NOTES["report"]
    main_intro = report["main_intro"].format(main_preset=MAIN_PRESET, main_about=PRESETS[MAIN_PRESET]["about"],
                                             large_min=LARGE_MIN, large_about=PRESETS["large"]["about"])
    return {"main": [row.id for row in main_rows()],
            "targets": [(r["n100"], TARGETS_100), (r["ds100"], TARGETS_100), (r["g50"], TARGETS_100),
                        (r["g1000"], TARGETS_1000), (r["g1000b"], TARGETS_1000), (r["n25"], TARGETS_25)],
            "headline": headline(store), "limits": limits_text(store), "main_intro": main_intro,
            "levers": [{"name": lv["name"], "question": lv["question"], "rows": [row.id for row in lv["rows"]],
                        "pairs": [(a.id, b.id) for a, b in lv.get("pairs", [])],
                        "note": lv.get("note", ""), "extra": lv.get("extra", False),
                        "view": lv.get("view", False), "vehicle": lv.get("vehicle", False)} for lv in LEVERS],
            "levers_intro": report["levers_intro"],
            "presets": {k: v["about"] for k, v in PRESETS.items()}, "method": report["method"]}


# --------------------------------------------------------------------------------------------
# The report.


def _header(store: dict, plan: dict) -> list[str]:
    """The title, the preamble, date, machine and runs, and the headline."""
    rows = store.get("rows", {})
    m = store.get("machine", {})
    o = ["# Benchmarks\n\n", NOTES["report"]["preamble"] + "\n\n"]
    quick = sorted(k for k, e in rows.items() if e.get("quick"))
    o.append(f"- **Date**: {store.get('date', '-')}; **commit**: `{store.get('commit', '-')}` (of the last invocation; "
             "each row's own commit and time are in the last table)"
             + (f"; **quick mode** (1 run, short window) for {', '.join(f'`{k}`' for k in quick)}" if quick else "")
             + "\n")
    o.append(f"- **Machine**: {m.get('cpu', '?')}, {m.get('host_cpus', '?')} CPUs, {m.get('mem_gb', '?')} GB RAM, "
             f"{m.get('os', '?')}, kernel {m.get('kernel', '?')}, Fast DDS {m.get('fastdds', '?')}\n")
    o.append(f"- **Kernel socket limits**: net.core.rmem_max = {m.get('rmem_max', '?')}, wmem_max = {m.get('wmem_max', '?')}, "
             f"rmem_default = {m.get('rmem_default', '?')} (bench.sh does not change them)\n")
    o.append("- **Runs**: each row is the median of its runs (the per-run values are in "
             "`docs/figures/bench_results.json`); rerun one row with the command in the last table.\n\n")
    o += [note + "\n" for note in plan.get("headline", [])]
    o.append("\n")
    return o


def _targets(store: dict, plan: dict) -> list[str]:
    """The targets table and what limits them."""
    rows = store.get("rows", {})
    o = ["## Targets\n\n| target | row | measured | verdict |\n|---|---|---|---|\n"]
    o += [target_rows(rows, rid, targets) for rid, targets in plan.get("targets", [])]
    o.append(sim_target_rows(store.get("sim") or {}))
    o.append("\n")
    if plan.get("limits"):
        o.append(plan["limits"] + "\n\n")
    return o


def _main_table(rows: dict, plan: dict) -> list[str]:
    """The main rows, and the agent rows as ratios to their baselines."""
    o = ["## Agents and baseline\n\n", plan.get("main_intro", "") + "\n\n", TABLE_HEAD]
    o += [table_line(rid, rows[rid]) for rid in plan.get("main", []) if rid in rows]
    o.append("\n")
    o.append("### Agent figures as a ratio to the baseline (same N, rate, transport and agents per process)\n\n")
    o.append(RATIO_HEAD)
    for rid in plan.get("main", []):
        e = rows.get(rid)
        if e and e["row"]["kind"] in ("agents", "group"):
            o.append(ratio_line(rid, e, baseline_for(rows, e)))
    o.append("\n![delivery and p99 data age against N](figures/bench_scaling.png)\n\n")
    return o


def scale_checks(e: dict) -> list[tuple[str, str, bool | None]]:
    """The acceptance of a scale row (bench_plan.SCALE_VERDICT): (label, measured, met) per check; met is
    None when not measured. Converged: in every run."""
    a, out = e["agg"], []
    for label, key, kind, limit in SCALE_VERDICT:
        if key == "converged":
            c, runs = a.get("converge_s"), a.get("runs", 1)
            n_conv = a.get("converged_runs", 0 if c is None or math.isinf(c) else runs)
            out.append((label, f"{n_conv} of {runs} runs, median {f_s(c)}", n_conv == runs))
            continue
        v = a.get(key)
        txt = "not measured" if v is None else (f_pct(v) if key == "delivery" else f_ms(v))
        ok = None if v is None else (v >= limit if kind == "min" else v <= limit)
        out.append((label, txt, ok))
    return out


def scale_met(e: dict | None, baseline: bool = False) -> bool:
    """Whether a scale row met every check (a baseline row: delivery and data age; it has no law)."""
    if e is None:
        return False
    checks = scale_checks(e)
    if baseline:
        checks = [c for c in checks if c[0] != SCALE_VERDICT[2][0]]
    return all(ok for _, _, ok in checks)


SCALE_HEAD = ("| row | delivery | age p99 | converged | verdict | x host busy | x CPU/agent | x age p99 |\n"
              "|---|---|---|---|---|---|---|---|\n")


def scale_section(store: dict) -> str:
    """'How far one host goes': the scale ladder's rows, each row's verdict and ratios to its baseline, the
    largest swarm that met every check and its baseline's, and where the wall is (notes.toml [scale])."""
    rows, notes = store.get("rows", {}), NOTES["scale"]
    ids = [r.id for r in scale_rows()]
    o = ["## How far one host goes\n\n", notes["intro"] + "\n\n", TABLE_HEAD]
    o += [table_line(rid, rows[rid]) for rid in ids if rid in rows]
    o.append("\n" + SCALE_HEAD)
    largest = None
    for rid in ids:
        e = rows.get(rid)
        if e is None:
            o.append(f"| `{rid}` | not run | | | | | | |\n")
            continue
        base = baseline_for(rows, e) if e["row"]["kind"] == "group" else None
        b = base["agg"] if base else {}
        checks = scale_checks(e)
        if e["row"]["kind"] == "baseline":
            checks[2] = (checks[2][0], "n/a", True)
        met = all(ok for _, _, ok in checks)
        missed = [f"{label} ({txt})" for label, txt, ok in checks if ok is False]
        verdict = "met" if met else ("**missed**: " + "; ".join(missed) if missed else "not measured")
        a = e["agg"]
        o.append(f"| `{rid}` | {checks[0][1]} | {checks[1][1]} | {checks[2][1]} | {verdict} "
                 f"| {ratio(a.get('host_busy_pct'), b.get('host_busy_pct')) if base else '-'} "
                 f"| {ratio(a.get('cpu_pct'), b.get('cpu_pct')) if base else '-'} "
                 f"| {ratio(a.get('age_p99_ms'), b.get('age_p99_ms')) if base else '-'} |\n")
        if e["row"]["kind"] == "group" and met and (largest is None or e["row"]["n"] > largest[1]["row"]["n"]):
            largest = (rid, e, base)
    o.append("\n")
    if largest is None:
        o.append(notes["none_met"] + " ")
    else:
        rid, e, base = largest
        a = e["agg"]
        o.append(notes["largest"].format(n=e["row"]["n"], processes=processes(e["row"]), row=rid,
                                         summary=_summary(store, rid), busy=a.get("host_busy_pct") or 0.0) + " ")
        if base is not None:
            o.append(notes["largest_baseline"].format(row=base["row"]["id"], summary=_summary(store, base["row"]["id"]),
                                                      met="met" if scale_met(base, True) else "did not meet") + " ")
    o.append(notes["wall"] + "\n\n")
    return "".join(o)


def _lever(rows: dict, lv: dict) -> list[str]:
    """One lever: its question, its rows' tables, the measured effect of each pair and the reading."""
    o = [f"### {lv['name']}\n\n{lv['question']}\n\n"]
    present = [rid for rid in lv["rows"] if rid in rows]
    if not lv["rows"]:
        return o + ([lv["note"] + "\n\n"] if lv.get("note") else [])
    if not present:
        return o + [f"_not run yet: `scripts/bench.sh --only lever{lv['name'].split('.')[0]}`_\n\n"]
    o += [TABLE_HEAD] + [table_line(rid, rows[rid]) for rid in present] + ["\n"]
    if lv.get("view") and any(rows[rid]["row"].get("view") for rid in present):
        o.append("| row | viewer CPU (% of one core) | viewer RSS MB | frames/s received |\n|---|---|---|---|\n")
        for rid in present:
            a = rows[rid]["agg"]
            if rows[rid]["row"].get("view"):
                o.append(f"| `{rid}` | {f_num(a.get('view_cpu_pct'))} | {f_num(a.get('view_rss_mb'))} "
                         f"| {f_num(a.get('view_fps'))} |\n")
        o.append("\n")
    if lv.get("vehicle"):
        o += vehicle_table(rows, present)
    if lv.get("extra"):
        o.append("| row | UDP datagrams in/s | UDP out/s | receive-buffer drops/s | our CPU (% of one core) "
                 "| datagrams received from launch to all hear all (or to the command) |\n|---|---|---|---|---|---|\n")
        for rid in present:
            a = rows[rid]["agg"]
            o.append(f"| `{rid}` | {f_num(a.get('udp_in_per_s'), '{:.0f}')} | {f_num(a.get('udp_out_per_s'), '{:.0f}')} "
                     f"| {f_num(a.get('udp_rcvbuf_errors_per_s'), '{:.0f}')} | {f_num(a.get('ours_cpu_pct'), '{:.0f}')} "
                     f"| {_disc(a)} |\n")
        o.append("\n")
    effects = [pair_effect(rows, a, b) for a, b in lv.get("pairs", []) if a in rows and b in rows]
    if effects:
        o.append("Measured effect:\n\n" + "".join(f"- {e}\n" for e in effects) + "\n")
    if lv.get("note"):
        o.append(lv["note"] + "\n\n")
    return o


VEHICLE_HEAD = ("| row | vehicle | N | control latency p50 | control latency p99 | p99 worst period | CPU %/agent "
                "| agents' CPU (% of one core) | shapeform_vehicle CPU (% of one core) | its RSS MB | launch to converged "
                "|\n|---|---|---|---|---|---|---|---|---|---|---|\n")


def vehicle_table(rows: dict, present: list[str]) -> list[str]:
    """Rows with a vehicle (Row.vehicle): the control latency the agents report (pose received to command
    published), their CPU, and the CPU of the process that simulates the robots, apart."""
    o = [VEHICLE_HEAD]
    for rid in present:
        r, a = rows[rid]["row"], rows[rid]["agg"]
        if not r.get("vehicle"):
            continue
        ros2 = r["vehicle"] == "ros2"
        o.append(f"| `{rid}` | {'robots over ROS 2' if ros2 else 'integrated by each agent'} | {r['n']} "
                 f"| {f_ms(a.get('control_p50_ms')) if ros2 else 'n/a'} | {f_ms(a.get('control_p99_ms')) if ros2 else 'n/a'} "
                 f"| {f_ms(a.get('control_p99_worst_ms')) if ros2 else 'n/a'} | {f_num(a.get('cpu_pct'), '{:.2f}')} "
                 f"| {f_num(a.get('cpu_pct_total'))} | {f_num(a.get('vehicle_cpu_pct')) if ros2 else 'n/a'} "
                 f"| {f_num(a.get('vehicle_rss_mb')) if ros2 else 'n/a'} | {f_s(a.get('converge_s'))} |\n")
    return o + ["\n"]


def _levers(rows: dict, plan: dict) -> list[str]:
    """The levers, then the ad-hoc rows (--row) under 'Other measured rows'."""
    o = ["## Levers, measured one at a time\n\n", plan.get("levers_intro", "") + "\n\n"]
    for lv in plan.get("levers", []):
        o += _lever(rows, lv)
    exp = [rid for rid, e in rows.items() if e["row"].get("section") == "experiment"]
    if exp:
        o.append("### Other measured rows\n\n" + TABLE_HEAD)
        o += [table_line(rid, rows[rid]) for rid in sorted(exp)]
        o.append("\n")
    return o


def _rerun_and_method(store: dict, plan: dict) -> list[str]:
    """The command that reruns each row, the method and the transport configurations."""
    rows = store.get("rows", {})
    o = ["## Rerun a row\n\n| row | measured | command |\n|---|---|---|\n"]
    for rid in sorted(rows):
        e = rows[rid]
        o.append(f"| `{rid}` | {e.get('when', '-')}, `{e.get('commit', '-')}` | `{e.get('command', '-')}` |\n")
    sim = store.get("sim") or {}
    if sim.get("available"):
        for r in sim["rows"]:
            o.append(f"| {sim_label(r)} | {sim.get('when', '-')}, `{sim.get('commit', '-')}` | `{r['command']}` |\n")
    o.append("\n")
    o.append("## Method\n\n" + plan.get("method", "") + "\n")
    o.append("\n### Transport configurations\n\n| config | what it sets |\n|---|---|\n")
    o += [f"| `{name}` | {about} |\n" for name, about in plan.get("presets", {}).items()]
    o.append("\n")
    return o


def foxglove_section() -> str:
    """The Foxglove WebSocket server, measured by scripts/bench_foxglove.py (notes.toml [foxglove])."""
    return "## Foxglove WebSocket\n\n" + NOTES["foxglove"]["section"] + "\n\n"


def recording_section() -> str:
    """The supervisor's recording cost, measured by scripts/bench_recording.py (notes.toml [recording])."""
    return "## Recording: the supervisor's cost\n\n" + NOTES["recording"]["section"] + "\n\n"


def mcap_section() -> str:
    """The MCAP recording's compression, measured by hand (notes.toml [mcap])."""
    return "## MCAP recording: compression\n\n" + NOTES["mcap"]["section"] + "\n\n"


# The viewer's page (scripts/bench_page.py --save writes this file: {label: {"when", "commit", "view",
# "load", "command", "rows": [{agents, received_per_s, drawn_per_s, chars_per_frame, view_cpu_percent}]}}).
PAGE_JSON = ROOT / "docs" / "figures" / "page_results.json"


def page_section(page: dict) -> str:
    """'The page at 12, 100 and 1000 agents': every measured version of the page, one row per N."""
    if not page:
        return ""
    o = ["## The page at 12, 100 and 1000 agents\n\n", NOTES["page"]["intro"] + "\n\n",
         "| version | agents | frames/s received | frames/s drawn | characters per frame | view CPU (% of one core) "
         "| host load (1 min) |\n|---|---|---|---|---|---|---|\n"]
    for label, run in page.items():
        for r in run["rows"]:
            o.append(f"| {label} (`{run['commit']}`, {run['when']}) | {r['agents']} | {r['received_per_s']:.1f} "
                     f"| {r['drawn_per_s']:.1f} | {r['chars_per_frame']:,.0f} | {r['view_cpu_percent']:.1f} "
                     f"| {run['load']:.1f} |\n")
    o.append("\n" + NOTES["page"]["after"] + "\n\n")
    o.append("Commands: " + ", ".join(f"{label}: `{run['command']}`" for label, run in page.items()) + ".\n\n")
    return "".join(o)


def render(store: dict, path: Path, plan: dict) -> None:
    """Writes the report of `store` (a results file's contents) to `path`; plan: report_plan(store)."""
    rows = store.get("rows", {})
    page = json.loads(PAGE_JSON.read_text()) if PAGE_JSON.exists() else {}
    o = (_header(store, plan) + _targets(store, plan) + _main_table(rows, plan) + [scale_section(store)]
         + _levers(rows, plan)
         + [foxglove_section(), page_section(page), sim_section(store.get("sim") or {}), recording_section(), mcap_section()] + _rerun_and_method(store, plan))
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("".join(o))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                 usage="bench/bench_report.py [RESULTS_JSON] [--out MD | --write-docs]")
    ap.add_argument("results", nargs="?", default=str(ROOT / "docs" / "figures" / "bench_results.json"))
    ap.add_argument("--out", help="the report to write (default runs/<UTC time>-bench/BENCHMARKS.md)")
    ap.add_argument("--write-docs", action="store_true", help="rewrite the committed docs/BENCHMARKS.md")
    a = ap.parse_args(argv)
    out = Path(a.out) if a.out else (ROOT / "docs" / "BENCHMARKS.md" if a.write_docs else
                                     ROOT / "runs" / (time.strftime("%Y%m%dT%H%M%SZ", time.gmtime()) + "-bench")
                                     / "BENCHMARKS.md")
    store = json.loads(Path(a.results).read_text())
    out.parent.mkdir(parents=True, exist_ok=True)
    render(store, out, report_plan(store))
    print(f"bench_report: wrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
