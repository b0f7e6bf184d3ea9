"""Running the benchmark's rows (see bench.py): one run starts the probe, the supervisor (agent rows),
the view (view rows) and the N processes on loopback in a DDS domain of its own, waits out the
measurement window and stops only the processes it started (scripts/lib/shapeform_procs.py); the
simulator rows call shapeform_bench_sim.
"""
from __future__ import annotations

import datetime as dt
import json
import math
import os
import resource
import shutil
import statistics
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from bench_measure import (EventClient, Sampler, aggregate, analyse, git_commit, host_busy_over, log, now_ns,
                           read_csv, read_host_cpu)
from bench_plan import PRESETS, ROOT, SIM_ROWS, Row, vehicle_sets

sys.path.insert(0, str(ROOT / "scripts" / "lib"))
import shapeform_procs as procs  # noqa: E402


@dataclass
class Ctx:
    bin: Path
    runs_dir: Path
    window_s: float
    disc_timeout_s: float
    conv_timeout_s: float
    scenario: Path
    scenario_sets: list[str]
    status_rate_hz: float
    domain_base: int
    domain_count: int = 30
    next_domain: int = 0
    quiet_busy: float = 0.15
    max_other_pct: float = 25.0
    retries: int = 2
    quiet_wait_s: float = 600.0

    def domain(self) -> int:
        d = self.domain_base + self.next_domain % self.domain_count
        self.next_domain += 1
        return d


def ds_xml(path: Path, port: int) -> None:
    path.write_text(f"""<?xml version="1.0" encoding="UTF-8"?>
<dds><profiles xmlns="http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles">
  <transport_descriptors>
    <transport_descriptor><transport_id>udp_lo</transport_id><type>UDPv4</type>
      <interfaceWhiteList><address>127.0.0.1</address></interfaceWhiteList>
    </transport_descriptor>
  </transport_descriptors>
  <participant profile_name="bench_ds" is_default_profile="true"><rtps>
    <userTransports><transport_id>udp_lo</transport_id></userTransports>
    <useBuiltinTransports>false</useBuiltinTransports>
    <builtin>
      <discovery_config><discoveryProtocol>SERVER</discoveryProtocol></discovery_config>
      <metatrafficUnicastLocatorList><locator><udpv4><address>127.0.0.1</address><port>{port}</port></udpv4></locator></metatrafficUnicastLocatorList>
    </builtin>
  </rtps></participant>
</profiles></dds>
""")


def udp_port_bound(port: int) -> bool:
    try:
        with open("/proc/net/udp") as f:
            next(f)
            for line in f:
                local = line.split()[1]
                if int(local.split(":")[1], 16) == port:
                    return True
    except OSError:
        pass
    return False


def wait_quiet(ctx: Ctx) -> float:
    """Waits (up to ctx.quiet_wait_s) until the host is nearly idle, so other jobs do not skew a run.
    Returns the busy fraction seen last."""
    end = time.monotonic() + ctx.quiet_wait_s
    busy = host_busy_over(2.0)
    warned = False
    while busy > ctx.quiet_busy and time.monotonic() < end:
        if not warned:
            log(f"host {100 * busy:.0f} % busy with other work; waiting up to {ctx.quiet_wait_s:.0f} s for it to calm down")
            warned = True
        busy = host_busy_over(5.0)
    return busy


# --------------------------------------------------------------------------------------------
# One run.


class Run:
    """The processes of one run of a row, each started here and stopped by its pid, and the Sampler
    that watches them. Creating it makes the run's keystore for a secured preset."""

    def __init__(self, ctx: Ctx, row: Row, rdir: Path, domain: int):
        self.ctx, self.row, self.rdir = ctx, row, rdir
        self.preset = PRESETS[row.preset]
        self.port = 12000 + domain  # the discovery server's, for a preset that has one
        self.common = ["--domain", str(domain)] + procs.sets_args(self._transport_sets())
        self.rate_sets = [f"agent.rate_hz={row.rate:g}", f"agent.status_rate_hz={ctx.status_rate_hz:g}",
                          f"swarm.agents={row.n}"] + vehicle_sets(row)
        self.sampler = Sampler()
        self.started: list[procs.Proc] = []
        self.client: EventClient | None = None
        self.ds: procs.Proc | None = None

    def _transport_sets(self) -> list[str]:
        tsets = list(self.preset["sets"])
        if self.preset["ds"]:
            tsets += ["transport.profile=discovery-server", f"transport.discovery_server=127.0.0.1:{self.port}"]
        if self.preset["secure"]:
            # One keystore for the benchmark, extended to this row's agents (make_keystore.sh keeps what exists).
            keystore = self.ctx.runs_dir / "keystore"
            procs.run([ROOT / "scripts" / "make_keystore.sh", keystore, "--agents", str(self.row.n)], timeout=600)
            tsets += ["security.enabled=true", f"security.keystore={keystore}"]
        return tsets

    def spawn(self, name: str, argv: list[str]) -> procs.Proc:
        p = procs.Proc(name, argv, self.rdir, cwd=self.rdir, err_suffix=".err")
        self.sampler.ours.append(p.pid)
        self.started.append(p)
        return p

    def agent_args(self) -> list[str]:
        """The --config, --seed and overrides of an agent or group process (after its --id / --ids)."""
        return (["--config", str(self.ctx.scenario), "--seed", "1"] + self.common
                + procs.sets_args(self.rate_sets + self.ctx.scenario_sets))

    def start_ds(self) -> None:
        xml = self.rdir / "ds.xml"
        ds_xml(xml, self.port)
        self.ds = self.spawn("ds", ["fast-discovery-server", "-i", "0", "-l", "127.0.0.1", "-p", str(self.port),
                                    "-x", str(xml)])
        if not procs.wait_for(lambda: udp_port_bound(self.port), 10):
            raise RuntimeError(f"discovery server did not bind 127.0.0.1:{self.port}")
        self.sampler.pids["ds"] = self.ds.pid

    def start_probe(self) -> procs.Proc:
        probe = self.spawn("probe", [str(self.ctx.bin / "shapeform_bench_probe"), "--out", str(self.rdir)] + self.common)
        line = procs.wait_for(lambda: probe.out() if "\n" in probe.out() or not probe.running() else "", 30)
        if not line.startswith("ready"):
            raise RuntimeError(f"probe did not start: {line!r}")
        return probe

    def start_supervisor(self) -> procs.Proc:
        ctx, row = self.ctx, self.row
        script = self.rdir / "script.txt"
        script.write_text(f"wait agents {row.n} timeout={ctx.disc_timeout_s:g}\nstart\n"
                          f"wait converged timeout={ctx.conv_timeout_s:g}\nsleep {ctx.window_s:g}\nquit\n")
        sup = self.spawn("supervisor", [str(ctx.bin / "shapeform_supervisor"), "--config", str(ctx.scenario),
                                        "--script", str(script), "--json"] + self.common +
                         procs.sets_args(self.rate_sets + ctx.scenario_sets))
        self.sampler.pids["sup"] = sup.pid
        return sup

    def start_view(self) -> None:
        """shapeform_view and one client reading its event stream as a browser does."""
        ctx = self.ctx
        view = self.spawn("view", [str(ctx.bin / "shapeform_view"), "--config", str(ctx.scenario), "--port", "0",
                                   "--json"] + self.common + procs.sets_args(self.rate_sets + ctx.scenario_sets))
        start = view.wait_event("start", 30)
        self.sampler.pids["view"] = view.pid
        self.client = EventClient(start["url"])
        self.client.start()

    def start_vehicles(self) -> procs.Proc:
        """One shapeform_vehicle hosting the row's N robots (robot i where agent i starts), before the
        agents, so that each finds its robot's pose."""
        ctx, row = self.ctx, self.row
        veh = self.spawn("vehicle", [str(ctx.bin / "shapeform_vehicle"), "--ids", f"0-{row.n - 1}", "--json"]
                         + self.agent_args())
        try:
            veh.wait_event("start", 30)
        except AssertionError:
            raise RuntimeError(f"shapeform_vehicle did not start: {veh.log()[-500:]!r}") from None
        self.sampler.pids["vehicle"] = veh.pid
        return veh

    def start_workers(self) -> list[procs.Proc]:
        """The row's N agents (or baseline processes): one process each, or `group` per process."""
        row, bindir = self.row, self.ctx.bin
        workers: list[procs.Proc] = []
        if row.group:
            for first in range(0, row.n, row.group):
                ids = f"{first}-{min(row.n, first + row.group) - 1}"
                if row.kind == "group":
                    argv = [str(bindir / "shapeform_agent_group"), "--ids", ids] + self.agent_args()
                else:
                    argv = [str(bindir / "shapeform_bench_baseline"), "--ids", ids] + self.common + \
                        procs.sets_args(self.rate_sets)
                workers.append(self.spawn(f"group{first}", argv))
                if row.stagger_s > 0:
                    time.sleep(row.stagger_s)
        else:
            for i in range(row.n):
                if row.kind == "agents":
                    argv = [str(bindir / "shapeform_agent"), "--id", str(i)] + self.agent_args()
                else:
                    argv = [str(bindir / "shapeform_bench_baseline"), "--id", str(i)] + self.common + \
                        procs.sets_args(self.rate_sets)
                workers.append(self.spawn(f"p{i}", argv))
                if row.stagger_s > 0:
                    time.sleep(row.stagger_s)
        return workers

    def wait_end(self, sup: procs.Proc | None) -> int:
        """Waits for the supervisor's script to end (agent rows), or (baseline rows) until every process
        hears all others (or the discovery timeout) and then the window. Returns the end (ns)."""
        ctx, row = self.ctx, self.row
        if sup is not None:
            limit = ctx.disc_timeout_s + ctx.conv_timeout_s + ctx.window_s + 60
            try:
                sup.wait(timeout=limit)
            except AssertionError:
                log(f"{row.id}: supervisor still running after {limit:.0f} s; stopping it")
            return now_ns()

        def all_heard() -> bool:
            rows = read_csv(self.rdir / "status.csv")
            full = {int(r["id"]) for r in rows if r["neighbours_heard"] >= row.n - 1}
            return len(full) >= row.n
        procs.wait_for(all_heard, ctx.disc_timeout_s, 0.5)
        time.sleep(ctx.window_s)
        return now_ns()

    def measure(self, result: dict) -> None:
        """Starts everything, waits for the end, stops everything: t0, launch_s, t_end and the exits
        into `result`."""
        if self.preset["ds"]:
            self.start_ds()
        probe = self.start_probe()
        self.sampler.start()
        t0 = now_ns()
        result["t0"] = t0
        sup = self.start_supervisor() if self.row.kind in ("agents", "group") else None
        if self.row.view:
            self.start_view()
        veh = self.start_vehicles() if self.row.vehicle == "ros2" else None
        workers = self.start_workers()
        result["launch_s"] = (now_ns() - t0) / 1e9
        result["t_end"] = self.wait_end(sup)
        early = [i for i, p in enumerate(workers) if not p.running()]
        codes = procs.stop_all(workers, grace=20, spacing=0.01)
        result["exit_codes"] = codes
        result["died_early"] = early
        if veh is not None:
            result["vehicle_exit"] = procs.stop_all([veh], grace=10)[0]
        if sup is not None:
            result["supervisor_exit"] = procs.stop_all([sup], grace=10)[0]
        procs.stop_all([probe], grace=10)

    def close(self) -> None:
        """Stops the sampler, the client and whatever this run started and is still alive (ours only:
        after an error part-way)."""
        if self.sampler.is_alive():
            self.sampler.stop()
        if self.client is not None:
            self.client.stop()
        procs.stop_all([p for p in self.started if p is not self.ds and p.running()], grace=10)
        if self.ds is not None:
            procs.stop_all([self.ds], grace=5)


def run_once(ctx: Ctx, row: Row, run_idx: int) -> dict:
    busy_before = wait_quiet(ctx)
    domain = ctx.domain()
    rdir = ctx.runs_dir / row.id / f"run{run_idx}"
    if rdir.exists():
        shutil.rmtree(rdir)  # no stale logs of an earlier run (they are scanned for asserts)
    rdir.mkdir(parents=True)
    run = Run(ctx, row, rdir, domain)
    result: dict = {"row": row.id, "run": run_idx, "domain": domain, "dir": str(rdir)}
    result["load_before"] = os.getloadavg()[0]
    result["busy_before_pct"] = 100 * busy_before
    try:
        run.measure(result)
    finally:
        run.close()
    analyse(ctx.window_s, row, rdir, result, run.sampler)
    if run.client is not None:
        w1 = result["t_end"] - 0.5e9
        result["view_fps"] = run.client.rate(max(result["t0"], w1 - ctx.window_s * 1e9 + 1e9), w1)
    return result


# --------------------------------------------------------------------------------------------
# Rows.


def fmt(v, kind: str) -> str:
    if v is None:
        return "-"
    if isinstance(v, float) and math.isinf(v):
        return "never"
    if kind == "s":
        return f"{v:.1f} s"
    if kind == "r":
        return f"{100 * v:.2f} %"
    if kind == "ms":
        return f"{v:.2f} ms" if v < 10 else f"{v:.0f} ms"
    if kind == "%":
        return f"{v:.1f} %"
    if kind == "n":
        return f"{v:.0f}"
    return str(v)


def log_run(row: Row, k: int, r: dict) -> None:
    log(f"{row.id}: run {k + 1}: heard {fmt(r.get('all_heard_s'), 's')} deliv {fmt(r.get('delivery'), 'r')} "
        f"age p50 {fmt(r.get('age_p50_ms'), 'ms')} p99 {fmt(r.get('age_p99_ms'), 'ms')} "
        f"cpu {fmt(r.get('cpu_pct'), '%')} host {fmt(r.get('host_busy_pct'), '%')} "
        f"rcvbuf err/s {fmt(r.get('udp_rcvbuf_errors_per_s'), 'n')} conv {fmt(r.get('converge_s'), 's')} "
        f"aborts {r.get('aborts')} other load {fmt(r.get('other_cpu_pct'), '%')}")


def run_rows(ctx: Ctx, rows: list[Row], runs: int, store: dict) -> None:
    for row in rows:
        per = []
        for k in range(runs):
            for attempt in range(ctx.retries + 1):
                log(f"{row.id}: run {k + 1}/{runs}" + (f" (retry {attempt})" if attempt else ""))
                r = run_once(ctx, row, k)
                log_run(row, k, r)
                other = r.get("other_cpu_pct") or 0.0
                if other <= ctx.max_other_pct:
                    break
                log(f"{row.id}: run {k + 1}: other jobs used {other:.0f} % of a core during the window "
                    f"(limit {ctx.max_other_pct:.0f} %)" + ("; repeating it" if attempt < ctx.retries else "; keeping it"))
            r["attempts"] = attempt + 1
            per.append(r)

        entry = {"row": row.__dict__ | {"id": row.id}, "agg": aggregate(per), "runs": per,
                 "when": dt.datetime.now().isoformat(timespec="seconds"), "commit": git_commit()}
        store[row.id] = entry


# --------------------------------------------------------------------------------------------
# Simulator rows (shapeform_bench_sim, one JSON object per call).


def sim_call(exe: Path, args: list[str], cores: str, before=None) -> tuple[dict | None, str | None, float | None]:
    """One call of shapeform_bench_sim on `cores`; repeated (up to twice) when other jobs used more than a
    quarter of a core during it. Returns its JSON (with `other_load`: other jobs' CPU in cores), an error,
    and how busy the host was (what `before` returned)."""
    for attempt in range(3):
        busy = before() if before else None
        t0, c0, r0 = time.monotonic(), read_host_cpu(), resource.getrusage(resource.RUSAGE_CHILDREN)
        try:
            p = procs.run(["taskset", "-c", cores, str(exe)] + args, timeout=600, check=False)
            if p.returncode != 0:
                return None, (p.stderr.strip().splitlines() or ["exit %d" % p.returncode])[-1], busy
            res = json.loads(p.stdout.strip().splitlines()[-1])
        except (subprocess.TimeoutExpired, json.JSONDecodeError, IndexError, OSError) as e:
            return None, str(e), busy
        wall, c1, r1 = time.monotonic() - t0, read_host_cpu(), resource.getrusage(resource.RUSAGE_CHILDREN)
        ours = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
        host = ((c1[0] - c0[0]) - (c1[1] - c0[1])) / os.sysconf("SC_CLK_TCK")
        res["other_load"] = max(0.0, host - ours) / wall
        if res["other_load"] <= 0.25:
            break
    return res, None, busy


def sim_rows(bindir: Path, quick: bool, before=None) -> dict:
    """Runs the simulator rows (3 calls each, 1 with --quick; median) and the peak probes. `before`
    (optional) is called before each call: bench.py waits there for a quiet host and returns how busy
    it was."""
    exe = bindir / "shapeform_bench_sim"
    out: dict = {"available": exe.exists(), "rows": [], "peak": {},
                 "when": dt.datetime.now().isoformat(timespec="seconds")}
    if not exe.exists():
        return out
    available = None
    for simd in ("generic", "avx2", "avx512"):
        res, err, _ = sim_call(exe, ["--peak", "--simd", simd], "0", before)
        if res:
            out["peak"][simd] = res["fma_per_s"]
            available = simd
    for spec in SIM_ROWS:
        row = sim_row(exe, spec, available, out["peak"], 1 if quick else 3, quick, before)
        if row is not None:
            out["rows"].append(row)
    return out


def sim_row(exe: Path, spec: tuple, available: str | None, peak: dict, runs: int, quick: bool, before) -> dict | None:
    """One simulator row of SIM_ROWS: the median of `runs` calls; None when this CPU lacks its
    instruction set."""
    n, impl, simd, threads, steps, beta = spec
    if simd == "best":
        simd = available
    elif simd is not None and simd not in peak:
        return None  # this CPU lacks it
    if quick:
        steps = max(1, steps // 4)
    args = ["--agents", str(n), "--steps", str(steps), "--impl", impl]
    if simd:
        args += ["--simd", simd, "--threads", str(threads)]
    if beta is not None:
        args += ["--beta", f"{beta:g}"]
    cores = "0" if threads == 1 else ",".join(str(c) for c in range(threads))
    results, error, busy, peaks = [], None, [], []
    for _ in range(runs):
        if simd:
            # The core's peak right before the call: this host's speed drifts (by a third between hours),
            # so the row is set against the peak of its own minutes.
            p, _, _ = sim_call(exe, ["--peak", "--simd", simd], "0", before)
            if p:
                peaks.append(p["fma_per_s"])
        res, error, b = sim_call(exe, args, cores, before)
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
        if peaks:
            row["peak_fma_per_s"] = statistics.median(peaks)
    if error:
        row["error"] = error
    return row
