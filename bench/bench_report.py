#!/usr/bin/python3
"""Simulator rows and the Markdown report of the benchmark (see bench.py).

render() turns a results file (bench_results.json) into BENCHMARKS.md; every number in the report comes
from that file, which bench.py fills from the processes' own reports. Run on its own it renders a report:

usage: bench/bench_report.py [RESULTS_JSON] [--out MD | --write-docs]

RESULTS_JSON defaults to the committed docs/figures/bench_results.json; the report goes to MD (default
runs/<UTC time>-bench/BENCHMARKS.md), or with --write-docs to the committed docs/BENCHMARKS.md.
"""
from __future__ import annotations

import datetime
import json
import math
import os
import resource
import statistics
import subprocess
import time
from pathlib import Path

# --------------------------------------------------------------------------------------------
# Simulator throughput (shapeform_bench_sim, one JSON object per call).

# (agents, impl, instruction set ("best": the one the simulator picks), threads, steps per call, beta
# (None: the paper's 1.2)). One thread runs on core 0 only (taskset -c 0), two on both cores. Steps
# chosen so one call takes about a second on this machine; --quick takes a quarter.
SIM_ROWS = [(100, "fast", "best", 1, 5000, None), (100, "reference", None, 1, 1000, None),
            (1000, "fast", "best", 1, 1500, None), (1000, "fast", "best", 1, 4000, 1.0),
            (1000, "fast", "avx2", 1, 500, None), (1000, "fast", "generic", 1, 200, None),
            (1000, "reference", None, 1, 20, None),
            (10000, "fast", "best", 1, 20, None), (10000, "fast", "best", 2, 40, None),
            (10000, "reference", None, 1, 1, None)]
SIM_SIZES = (100, 1000, 10000)
SIM_TARGETS = {1000: 1000.0, 10000: 20.0}  # Euler steps/s (issue 17): N = 1000 on one core
# Multiply-adds and multiplies per pair in the AVX-512 pair pass (common/core/batch_avx512.cpp), counted
# in its compiled inner loop (objdump of batch_avx512.cpp.o, 2026-12-02: 50 vfmadd/vfnmadd/vmulpd among 119
# vector instructions per 16 pairs): the power 19 (the logarithm's reduction and degree-6 polynomial with
# its powers of r, the exponential's degree-5 polynomial, the table factor), the squared distance 2, the
# four sums 4. The least time a pair can take on this core is that many over the peak multiply-add rate.
SIM_FMA_PER_PAIR = 25


def _host_cpu() -> tuple[int, int]:
    """(all, idle) CPU ticks of the host since boot."""
    with open("/proc/stat") as f:
        vals = [int(v) for v in f.readline().split()[1:]]
    return sum(vals), vals[3] + vals[4]


def sim_label(r: dict) -> str:
    if r["impl"] == "reference":
        return f"sim {r['agents']} reference"
    return (f"sim {r['agents']} fast {r.get('simd') or '?'}" + (f" {r['threads']} threads" if r["threads"] > 1 else "")
            + (f" beta {r['beta']:g}" if r.get("beta") is not None else ""))


def sim_rows(bindir: Path, quick: bool, before=None) -> dict:
    """Runs the simulator rows (3 calls each, 1 with --quick; median) and the peak probes. `before`
    (optional) is called before each call: bench.py waits there for a quiet host and returns how busy
    it was."""
    exe = bindir / "shapeform_bench_sim"
    out: dict = {"available": exe.exists(), "rows": [], "peak": {},
                 "when": datetime.datetime.now().isoformat(timespec="seconds")}
    if not exe.exists():
        return out
    runs = 1 if quick else 3

    def call(args: list[str], cores: str) -> tuple[dict | None, str | None, float | None]:
        """One call; repeated (up to twice) when other jobs used more than a quarter of a core during it.
        Returns its JSON (with `other_load`: other jobs' CPU in cores), an error, and how busy the host was."""
        for attempt in range(3):
            busy = before() if before else None
            t0, c0, r0 = time.monotonic(), _host_cpu(), resource.getrusage(resource.RUSAGE_CHILDREN)
            try:
                p = subprocess.run(["taskset", "-c", cores, str(exe)] + args, capture_output=True, text=True,
                                   timeout=600)
                if p.returncode != 0:
                    return None, (p.stderr.strip().splitlines() or ["exit %d" % p.returncode])[-1], busy
                res = json.loads(p.stdout.strip().splitlines()[-1])
            except (subprocess.TimeoutExpired, json.JSONDecodeError, IndexError, OSError) as e:
                return None, str(e), busy
            wall, c1, r1 = time.monotonic() - t0, _host_cpu(), resource.getrusage(resource.RUSAGE_CHILDREN)
            ours = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
            host = ((c1[0] - c0[0]) - (c1[1] - c0[1])) / os.sysconf("SC_CLK_TCK")
            res["other_load"] = max(0.0, host - ours) / wall
            if res["other_load"] <= 0.25:
                break
        return res, None, busy

    available = None
    for simd in ("generic", "avx2", "avx512"):
        res, err, _ = call(["--peak", "--simd", simd], "0")
        if res:
            out["peak"][simd] = res["fma_per_s"]
            available = simd
    for n, impl, simd, threads, steps, beta in SIM_ROWS:
        if simd == "best":
            simd = available
        elif simd is not None and simd not in out["peak"]:
            continue  # this CPU lacks it
        if quick:
            steps = max(1, steps // 4)
        args = ["--agents", str(n), "--steps", str(steps), "--impl", impl]
        if simd:
            args += ["--simd", simd, "--threads", str(threads)]
        if beta is not None:
            args += ["--beta", f"{beta:g}"]
        cores = "0" if threads == 1 else ",".join(str(c) for c in range(threads))
        results, error, busy = [], None, []
        for _ in range(runs):
            res, error, b = call(args, cores)
            if res is None:
                break
            results.append(res)
            busy.append(b)
        row = {"agents": n, "impl": impl, "simd": simd, "threads": threads, "beta": beta, "steps": steps, "runs": len(results),
               "command": f"taskset -c {cores} build/bin/shapeform_bench_sim " + " ".join(args)}
        if results:
            for k in ("steps_per_s", "rss_mb", "seconds", "ns_per_pair", "other_load"):
                row[k] = statistics.median(r[k] for r in results)
            if any(b is not None for b in busy):
                row["host_busy_before"] = max(b for b in busy if b is not None)
        if error:
            row["error"] = error
        out["rows"].append(row)
    return out


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


def sim_section(sim: dict) -> str:
    o = ["## Simulator\n\n"]
    if not sim.get("available"):
        o.append("`build/bin/shapeform_bench_sim` was not built when this report was generated.\n\n")
        return "".join(o)
    peak = sim.get("peak") or {}
    o.append("Paper law, Euler dt = 1, the paper's circle, uniform start (`shapeform_bench_sim`; run alone: "
             "`scripts/bench.sh --only sim`). `fast`: the batched kernel the simulator uses from 64 agents on "
             "(`core::paper_velocities_batch`: each pair once, in vectors of the instruction set picked at run time, "
             "O(N) memory; equal to the per-agent law within 6e-15 of the sum of the terms' magnitudes on the unit tests' swarms, asserted to 1e-13, with the same nearest neighbours); `reference`: "
             "every agent through `core::agent_step` as an agent process computes it (each pair twice). One thread runs "
             "on core 0 alone (`taskset -c 0`); two threads split the pairs over both cores. ns per pair: time per step "
             "over N (N - 1) / 2 pairs, the per-agent work (attraction, repulsion, integration) included. Each figure is "
             "the median of 3 calls; before each call the host must be quiet (up to 2 minutes of waiting), and a call "
             "during which other jobs took more than a quarter of a core is repeated (twice at most); other load: what "
             "they took (median, in cores).\n\n")
    o.append("| N | impl | beta | instruction set | cores | Euler steps/s | ns per pair | RSS MB | speed-up vs reference "
             "| other load | target | verdict |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n")
    ref = {r["agents"]: r.get("steps_per_s") for r in sim["rows"] if r["impl"] == "reference"}
    for r in sim["rows"]:
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
        o.append(f"| {n} | {r['impl']} | {beta} | {r.get('simd') or 'scalar'} | {r.get('threads', 1)} | {val} "
                 f"| {f_num(r.get('ns_per_pair'), '{:.2f}')} | {f_num(r.get('rss_mb'))} | {speed} "
                 f"| {f_num(r.get('other_load'), '{:.2f}')} | {tgt} | {verdict} |\n")
    o.append("\n")
    if peak:
        o.append("**Against the machine's limit.** Peak double-precision multiply-adds one thread sustains on core 0 "
                 "(independent chains, `shapeform_bench_sim --peak`): "
                 + ", ".join(f"{k} {v / 1e9:.1f} G/s" for k, v in peak.items()) + ". ")
        big = sim_best(sim, 10000, 1)
        if "avx512" in peak and big and big.get("simd") == "avx512" and big.get("ns_per_pair"):
            bound = SIM_FMA_PER_PAIR / peak["avx512"] * 1e9
            o.append(f"The AVX-512 pair pass executes {SIM_FMA_PER_PAIR} multiply-adds or multiplies per pair (counted "
                     f"in its compiled loop), so at that peak a pair takes at least {bound:.2f} ns; measured at N = 10000 "
                     f"on one core: {big['ns_per_pair']:.2f} ns, x{big['ns_per_pair'] / bound:.1f} the bound. ")
        o.append(SIM_LIMITS + "\n\n")
    return "".join(o)


SIM_LIMITS = (
    "What separates the two: each pair's weight (sigma^2 + d^2)^-beta, computed as 2^(-beta log2(sigma^2 + d^2)) "
    "with 16-entry tables read by one permute and polynomials of degree 6 and 5, is a chain of some 20 dependent "
    "operations (about 70 cycles), and the core's out-of-order window holds only a few pairs' chains at once "
    "(evaluating the polynomials in Horner's order, a longer chain with fewer operations, was slower); the other "
    "vector operations (permutes, compares, blends, the nearest-neighbour bookkeeping, loads and stores) share the "
    "pipes, 119 vector instructions per 16 pairs in all. More rows per pass (one row shares j's loads and "
    "stores with the next) spilled registers: two rows measured fastest. The paper's beta = 1.2 has no cheaper form; "
    "beta = 1/2, 1, 3/2 or 2 take a square root and a division instead (within 2 ulp of std::pow), the row with "
    "beta = 1 shows the gain. The other instruction sets use the same scheme without the tables (AVX2, generic) "
    "and a division in the logarithm.")


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


def agg_val(entry, key):
    return entry["agg"].get(key) if entry else None


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
    return (f"| `{rid}` | {row_label(r)} | {r['n']} | {r['rate']:g} Hz | {processes(r)} | {r['preset']}{st} "
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
            f"| {ratio(a.get('cpu_pct'), b.get('cpu_pct'))} | {ratio(a.get('rss_mb'), b.get('rss_mb'))} |\n")


RATIO_HEAD = ("| agent row | baseline row | all hear all | delivery | age p50 | age p99 | lateness p99 | CPU/agent | RSS/agent |\n"
              "|---|---|---|---|---|---|---|---|---|\n")


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


def target_rows(rows: dict, rid: str, targets: list) -> str:
    e = rows.get(rid)
    out = ""
    for label, key, kind, limit, fmt in targets:
        if e is None:
            out += f"| {label} | `{rid}` | not run | - |\n"
            continue
        a = e["agg"]
        if key == "aborts_total":
            v = a.get("aborts_total", 0)
            runs = a.get("runs", 1)
            out += f"| {label} | `{rid}` | {v} in {runs} run{'s' if runs != 1 else ''} | {'met' if v == 0 else '**missed**'} |\n"
            continue
        if key == "converged":
            # Met only when every run converged (the first converged SwarmMetrics sample); the median
            # time and the supervisor's final verdict are shown beside it.
            c, runs = a.get("converge_s"), a.get("runs", 1)
            n_conv = a.get("converged_runs", 0 if c is None or math.isinf(c) else runs)
            ok = n_conv == runs
            out += (f"| {label} | `{rid}` | converged in {n_conv} of {runs} runs, median {f_s(c)} (the supervisor's "
                    f"final summary: converged in {a.get('sup_converged_runs', 0)}) | {'met' if ok else '**missed**'} |\n")
            continue
        if key == "ratio_p50" or key == "ratio_p99":
            base = baseline_for(rows, e)
            k = "age_p50_ms" if key == "ratio_p50" else "age_p99_ms"
            if base is None or a.get(k) is None or not base["agg"].get(k):
                out += f"| {label} | `{rid}` | no baseline | - |\n"
                continue
            v = a[k] / base["agg"][k]
            txt, verdict = verdict_max(v, limit, lambda x: f"{x:.2f}")
            out += f"| {label} | `{rid}` vs `{base['row']['id']}` | x{txt} | {verdict} |\n"
            continue
        v = a.get(key)
        txt, verdict = (verdict_min if kind == "min" else verdict_max)(v, limit, fmt)
        out += f"| {label} | `{rid}` | {txt} | {verdict} |\n"
    return out


# --------------------------------------------------------------------------------------------


def render(store: dict, path: Path, plan: dict) -> None:
    """plan: {"main": [row ids], "levers": [{"name", "question", "rows": [ids], "note"}], "targets": {...},
    "presets": {name: about}, "notes": [str], "limits": str}"""
    rows = store.get("rows", {})
    m = store.get("machine", {})
    o = []
    o.append("# Benchmarks\n\n")
    o.append("Generated by `scripts/bench.sh` (do not edit by hand: rerun it). Every figure below comes from the "
             "processes themselves: agents and baseline processes publish `AgentStatus` (loop ticks, overruns, "
             "lateness, neighbours heard, samples received, data age percentiles, CPU, RSS), recorded by "
             "`shapeform_bench_probe`; convergence from the supervisor's `SwarmMetrics`; supervisor and host CPU and "
             "the kernel's UDP counters from `/proc`.\n\n")
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

    for note in plan.get("headline", []):
        o.append(note + "\n")
    o.append("\n")

    # Targets
    o.append("## Targets\n\n| target | row | measured | verdict |\n|---|---|---|---|\n")
    for rid, targets in plan.get("targets", []):
        o.append(target_rows(rows, rid, targets))
    o.append(sim_target_rows(store.get("sim") or {}))
    o.append("\n")
    if plan.get("limits"):
        o.append(plan["limits"] + "\n\n")

    # Main table
    o.append("## Agents and baseline\n\n")
    o.append(plan.get("main_intro", "") + "\n\n")
    o.append(TABLE_HEAD)
    for rid in plan.get("main", []):
        if rid in rows:
            o.append(table_line(rid, rows[rid]))
    o.append("\n")
    o.append("### Agent figures as a ratio to the baseline (same N, rate, transport and agents per process)\n\n")
    o.append(RATIO_HEAD)
    for rid in plan.get("main", []):
        e = rows.get(rid)
        if e and e["row"]["kind"] in ("agents", "group"):
            o.append(ratio_line(rid, e, baseline_for(rows, e)))
    o.append("\n![delivery and p99 data age against N](figures/bench_scaling.png)\n\n")

    # Levers
    o.append("## Levers, measured one at a time\n\n")
    o.append(plan.get("levers_intro", "") + "\n\n")
    for lv in plan.get("levers", []):
        o.append(f"### {lv['name']}\n\n{lv['question']}\n\n")
        present = [rid for rid in lv["rows"] if rid in rows]
        if not lv["rows"]:
            if lv.get("note"):
                o.append(lv["note"] + "\n\n")
            continue
        if not present:
            o.append("_not run yet: `scripts/bench.sh --levers`_\n\n")
            continue
        o.append(TABLE_HEAD)
        for rid in present:
            o.append(table_line(rid, rows[rid]))
        o.append("\n")
        if lv.get("view") and any(rows[rid]["row"].get("view") for rid in present):
            o.append("| row | viewer CPU (% of one core) | viewer RSS MB | frames/s received |\n|---|---|---|---|\n")
            for rid in present:
                a = rows[rid]["agg"]
                if rows[rid]["row"].get("view"):
                    o.append(f"| `{rid}` | {f_num(a.get('view_cpu_pct'))} | {f_num(a.get('view_rss_mb'))} "
                             f"| {f_num(a.get('view_fps'))} |\n")
            o.append("\n")
        extra = lv.get("extra")
        if extra:
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

    # Experiments
    exp = [rid for rid, e in rows.items() if e["row"].get("section") == "experiment"]
    if exp:
        o.append("### Other measured rows\n\n" + TABLE_HEAD)
        for rid in sorted(exp):
            o.append(table_line(rid, rows[rid]))
        o.append("\n")

    o.append(sim_section(store.get("sim") or {}))

    # Rerun commands
    o.append("## Rerun a row\n\n| row | measured | command |\n|---|---|---|\n")
    for rid in sorted(rows):
        e = rows[rid]
        o.append(f"| `{rid}` | {e.get('when', '-')}, `{e.get('commit', '-')}` | `{e.get('command', '-')}` |\n")
    sim = store.get("sim") or {}
    if sim.get("available"):
        for r in sim["rows"]:
            o.append(f"| {sim_label(r)} | {sim.get('when', '-')}, `{sim.get('commit', '-')}` | `{r['command']}` |\n")
    o.append("\n")

    # Method
    o.append("## Method\n\n" + plan.get("method", "") + "\n")
    o.append("\n### Transport configurations\n\n| config | what it sets |\n|---|---|\n")
    for name, about in plan.get("presets", {}).items():
        o.append(f"| `{name}` | {about} |\n")
    o.append("\n")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("".join(o))


def main(argv=None) -> int:
    import argparse
    import sys
    import time
    root = Path(__file__).resolve().parent.parent
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                 usage="bench/bench_report.py [RESULTS_JSON] [--out MD | --write-docs]")
    ap.add_argument("results", nargs="?", default=str(root / "docs" / "figures" / "bench_results.json"))
    ap.add_argument("--out", help="the report to write (default runs/<UTC time>-bench/BENCHMARKS.md)")
    ap.add_argument("--write-docs", action="store_true", help="rewrite the committed docs/BENCHMARKS.md")
    a = ap.parse_args(argv)
    out = Path(a.out) if a.out else (root / "docs" / "BENCHMARKS.md" if a.write_docs else
                                     root / "runs" / (time.strftime("%Y%m%dT%H%M%SZ", time.gmtime()) + "-bench")
                                     / "BENCHMARKS.md")
    sys.dont_write_bytecode = True
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from bench import report_plan  # noqa: E402 (same folder)
    store = json.loads(Path(a.results).read_text())
    out.parent.mkdir(parents=True, exist_ok=True)
    render(store, out, report_plan(store))
    print(f"bench_report: wrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
