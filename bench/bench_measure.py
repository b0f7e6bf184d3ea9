"""What the benchmark measures (see bench.py): the kernel's counters (/proc) sampled during a run, the
browser view's frame rate, the figures of one run from the processes' own reports (the probe's
status.csv and metrics.csv, the supervisor's summary), the median over runs, and the machine.
"""
from __future__ import annotations

import math
import os
import platform
import signal
import statistics
import subprocess
import sys
import threading
import time
import urllib.request
from pathlib import Path

from bench_plan import ROOT, Row

sys.path.insert(0, str(ROOT / "scripts" / "lib"))
import shapeform_procs as procs  # noqa: E402

CLK_TCK = os.sysconf("SC_CLK_TCK")
PF_KTHREAD = 0x00200000

# --------------------------------------------------------------------------------------------
# Small helpers.


def now_ns() -> int:
    # CLOCK_MONOTONIC: the same clock as std::chrono::steady_clock and every *_stamp_ns.
    return time.monotonic_ns()


def log(msg: str) -> None:
    print(f"[bench] {msg}", file=sys.stderr, flush=True)


def median(xs):
    xs = [x for x in xs if x is not None]
    if not xs:
        return None
    return statistics.median(xs)


def read_proc_cpu_ticks(pid: int) -> int | None:
    try:
        with open(f"/proc/{pid}/stat") as f:
            parts = f.read().rsplit(")", 1)[1].split()
        return int(parts[11]) + int(parts[12])  # utime + stime
    except (OSError, IndexError, ValueError):
        return None


def read_proc_rss_mb(pid: int) -> float | None:
    try:
        with open(f"/proc/{pid}/statm") as f:
            return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20
    except (OSError, IndexError, ValueError):
        return None


def read_user_proc_ticks(pid: int) -> int | None:
    """utime + stime of a user-space process; None for kernel threads (ksoftirqd, kworkers: they mostly
    carry our own network traffic) and vanished processes."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            parts = f.read().rsplit(")", 1)[1].split()
        if int(parts[6]) & PF_KTHREAD:
            return None
        return int(parts[11]) + int(parts[12])
    except (OSError, IndexError, ValueError):
        return None


def read_host_cpu() -> tuple[int, int]:
    """(all, idle) CPU ticks of the host since boot."""
    with open("/proc/stat") as f:
        vals = [int(v) for v in f.readline().split()[1:]]
    idle = vals[3] + vals[4]
    return sum(vals), idle


def read_udp_counters() -> dict[str, int]:
    with open("/proc/net/snmp") as f:
        lines = [l.split() for l in f if l.startswith("Udp:")]
    return dict(zip(lines[0][1:], (int(v) for v in lines[1][1:])))


def host_busy_over(seconds: float) -> float:
    """Host CPU busy fraction (0..1) over the next `seconds`."""
    t1, i1 = read_host_cpu()
    time.sleep(seconds)
    t2, i2 = read_host_cpu()
    return 1 - (i2 - i1) / max(1, t2 - t1)


def read_csv(path: Path) -> list[dict]:
    """A probe CSV as rows of floats; rows cut by a kill are skipped."""
    return [r for r in procs.read_csv(path, numeric=True) if None not in r.values()]


# --------------------------------------------------------------------------------------------
# Sampled during a run.


class Sampler(threading.Thread):
    """Samples host CPU, UDP counters and the CPU of a few named processes every 0.5 s."""

    def __init__(self):
        super().__init__(daemon=True)
        self.pids: dict[str, int] = {}
        self.ours: list[int] = []
        self.samples: list[dict] = []
        self._halt = threading.Event()

    def run(self):
        while not self._halt.is_set():
            s = {"t": now_ns()}
            s["host_total"], s["host_idle"] = read_host_cpu()
            s["udp"] = read_udp_counters()
            for name, pid in list(self.pids.items()):
                s[name] = read_proc_cpu_ticks(pid)
                s[name + "_rss"] = read_proc_rss_mb(pid)
            # CPU of every process this run started (to tell our load from other jobs on the host).
            s["ours"] = {pid: read_proc_cpu_ticks(pid) for pid in list(self.ours)}
            s["foreign"] = {}
            ours = set(self.ours)
            for name in os.listdir("/proc"):
                if name.isdigit() and int(name) not in ours and int(name) != os.getpid():
                    t = read_user_proc_ticks(int(name))
                    if t is not None:
                        s["foreign"][int(name)] = t
            self.samples.append(s)
            self._halt.wait(0.5)

    def stop(self):
        self._halt.set()
        self.join()

    def window(self, t0: int, t1: int):
        inside = [s for s in self.samples if t0 <= s["t"] <= t1]
        return (inside[0], inside[-1]) if len(inside) >= 2 else (None, None)


class EventClient(threading.Thread):
    """Reads a shapeform_view event stream (/events) as a browser does and counts the frames."""

    def __init__(self, url: str):
        super().__init__(daemon=True)
        self.url = url
        self.frames: list[int] = []  # arrival times, ns
        self._halt = threading.Event()

    def run(self):
        try:
            with urllib.request.urlopen(self.url + "events", timeout=10) as stream:
                for line in stream:
                    if line.startswith(b"data: "):
                        self.frames.append(now_ns())
                    if self._halt.is_set():
                        return
        except OSError as e:
            log(f"view client: {e}")

    def stop(self):
        self._halt.set()
        self.join(5)

    def rate(self, t0: int, t1: int) -> float | None:
        n = sum(1 for t in self.frames if t0 <= t <= t1)
        return n / ((t1 - t0) / 1e9) if t1 > t0 else None


# --------------------------------------------------------------------------------------------
# Figures of one run: analyse() fills the run's result from its folder and its Sampler.


def interp_counter(statuses: list[dict], key: str, t: float) -> float | None:
    """Linear interpolation of a cumulative counter at steady time t (ns); None outside the range."""
    if not statuses or t < statuses[0]["stamp_ns"] or t > statuses[-1]["stamp_ns"]:
        return None
    for a, b in zip(statuses, statuses[1:]):
        if a["stamp_ns"] <= t <= b["stamp_ns"]:
            span = b["stamp_ns"] - a["stamp_ns"]
            f = 0.0 if span <= 0 else (t - a["stamp_ns"]) / span
            return a[key] + f * (b[key] - a[key])
    return statuses[-1][key]


def analyse(window_s: float, row: Row, rdir: Path, res: dict, sampler: Sampler) -> None:
    """The figures of one run into `res` (which holds its t0 and t_end): the measurement window is the
    last `window_s` seconds, less half a second at either end."""
    t0, t_end = res["t0"], res["t_end"]
    w1 = t_end - 0.5e9
    w0 = max(t0, t_end - window_s * 1e9 + 0.5e9)
    res["window_s"] = (w1 - w0) / 1e9
    status = read_csv(rdir / "status.csv")
    by_id: dict[int, list[dict]] = {}
    for s in status:
        by_id.setdefault(int(s["id"]), []).append(s)
    for v in by_id.values():
        v.sort(key=lambda s: s["stamp_ns"])
    res["agents_reporting"] = len(by_id)
    _hearing(row.n, t0, by_id, res)
    _delivery(row, w0, w1, by_id, res)
    _data_age(w0, w1, status, res)
    _control_latency(w0, w1, status, res)
    _loop(w0, w1, by_id, res)
    a, b = sampler.window(w0, w1)
    if a is not None:
        _host(a, b, sampler.samples, res)
    started = _convergence(rdir, t0, res)
    _discovery_traffic(sampler.samples, t0, t_end, started, res)
    j = procs.summary(procs.read_text(rdir / "supervisor.out"))
    if j:
        for key in ("converged", "shape_error_mean", "gap_cv", "agents_seen"):
            res["sup_converged" if key == "converged" else key] = j.get(key)
    _exits(rdir, res)


def _hearing(n: int, t0: int, by_id: dict, res: dict) -> None:
    """Everyone hears everyone: per agent, the first status reporting all n-1 others; the latest of those."""
    firsts = []
    for i in range(n):
        f = next((s["stamp_ns"] for s in by_id.get(i, []) if s["neighbours_heard"] >= n - 1), None)
        firsts.append(f)
    res["all_heard_s"] = None if any(f is None for f in firsts) else (max(firsts) - t0) / 1e9
    res["heard_min"] = min((max((s["neighbours_heard"] for s in by_id.get(i, [])), default=0) for i in range(n)),
                           default=0)


def covered(statuses: list[dict], w0: float, w1: float) -> tuple[float, float] | None:
    """The part of the window [w0, w1] (ns) a process's statuses span, or None if they span none of it."""
    if not statuses:
        return None
    a, b = max(w0, statuses[0]["stamp_ns"]), min(w1, statuses[-1]["stamp_ns"])
    return (a, b) if b > a else None


def _delivery(row: Row, w0: float, w1: float, by_id: dict, res: dict) -> None:
    """Delivery over the window: each receiver's received count against what the others published in the
    same time. A process whose statuses end before the window does (on a saturated host the last ones
    can come seconds late, or not before the run ends) is measured over the part they span; one whose
    statuses span none of the window received nothing in it."""
    n = row.n
    spans = {i: covered(ss, w0, w1) for i, ss in by_id.items()}
    rates = {}
    for i, span in spans.items():
        if span is not None:
            a, b = span
            rates[i] = (interp_counter(by_id[i], "ticks", b) - interp_counter(by_id[i], "ticks", a)) / ((b - a) / 1e9)
    # What everyone published per second; a sender that never reported is still owed to everyone: assume
    # the nominal rate. Each receiver is owed all of it but its own.
    published = sum(rates.values()) + row.rate * sum(1 for j in range(n) if j not in rates)
    expected = 0.0
    got = 0.0
    for i in range(n):
        span = spans.get(i)
        a, b = span if span is not None else (w0, w1)
        expected += (published - rates.get(i, row.rate)) * (b - a) / 1e9
        if span is not None:
            got += interp_counter(by_id[i], "samples_received", b) - interp_counter(by_id[i], "samples_received", a)
    res["delivery"] = got / expected if expected > 0 else None
    win = (w1 - w0) / 1e9
    lost = [interp_counter(ss, "samples_lost", w1) - interp_counter(ss, "samples_lost", w0)
            for ss in by_id.values() if interp_counter(ss, "samples_lost", w0) is not None
            and interp_counter(ss, "samples_lost", w1) is not None]
    res["seq_gaps_per_s"] = sum(lost) / win if lost else None


def _data_age(w0: float, w1: float, status: list[dict], res: dict) -> None:
    inwin = [s for s in status if w0 <= s["stamp_ns"] <= w1]
    p50s = [s["age_p50_us"] for s in inwin if s["age_p50_us"] >= 0]
    p99s = [s["age_p99_us"] for s in inwin if s["age_p99_us"] >= 0]
    res["age_p50_ms"] = median(p50s) / 1e3 if p50s else None
    res["age_p99_ms"] = median(p99s) / 1e3 if p99s else None
    res["age_p99_worst_ms"] = max(p99s) / 1e3 if p99s else None
    res["age_p99_p90_ms"] = (sorted(p99s)[int(0.9 * (len(p99s) - 1))] / 1e3) if p99s else None


def _control_latency(w0: float, w1: float, status: list[dict], res: dict) -> None:
    """Agents driving robots over ROS 2 (vehicle.interface ros2): from a pose's receipt to the command
    computed from it being published, as each agent reports p50 and p99 per status period (-1: no command
    from a new pose in the period, and always for the internal vehicle). Median over agents and periods of
    the window, and the worst period's p99; absent for agents that drive nothing outside."""
    if not status or "control_latency_p50_us" not in status[0]:
        return  # a status.csv of a probe older than the column
    inwin = [s for s in status if w0 <= s["stamp_ns"] <= w1]
    p50s = [s["control_latency_p50_us"] for s in inwin if s["control_latency_p50_us"] >= 0]
    p99s = [s["control_latency_p99_us"] for s in inwin if s["control_latency_p99_us"] >= 0]
    if not p50s:
        return
    res["control_p50_ms"] = median(p50s) / 1e3
    res["control_p99_ms"] = median(p99s) / 1e3 if p99s else None
    res["control_p99_worst_ms"] = max(p99s) / 1e3 if p99s else None
    res["control_periods"] = len(p50s)


def _loop(w0: float, w1: float, by_id: dict, res: dict) -> None:
    """Loop lateness (each agent's p99 over its last 1024 ticks, at the end of the window), overruns,
    CPU and RSS."""
    lat = []
    over = 0.0
    ticks = 0.0
    cpu = []
    rss = []
    for i, ss in by_id.items():
        last = [s for s in ss if s["stamp_ns"] <= w1]
        if last:
            lat.append(last[-1]["lateness_p99_us"])
            rss.append(last[-1]["rss_mb"])
        oa, ob = interp_counter(ss, "overruns", w0), interp_counter(ss, "overruns", w1)
        ta, tb = interp_counter(ss, "ticks", w0), interp_counter(ss, "ticks", w1)
        if None not in (oa, ob, ta, tb):
            over += ob - oa
            ticks += tb - ta
        c = [s["cpu_percent"] for s in ss if w0 <= s["stamp_ns"] <= w1]
        if c:
            cpu.append(sum(c) / len(c))
    res["lateness_p99_ms"] = median(lat) / 1e3 if lat else None
    res["lateness_p99_worst_ms"] = max(lat) / 1e3 if lat else None
    res["overruns"] = over
    res["overrun_pct"] = 100 * over / (over + ticks) if ticks > 0 else None
    res["cpu_pct"] = statistics.mean(cpu) if cpu else None
    res["cpu_pct_total"] = sum(cpu) if cpu else None
    res["rss_mb"] = median(rss)
    res["rss_mb_max"] = max(rss) if rss else None


def _host(a: dict, b: dict, samples: list[dict], res: dict) -> None:
    """The host over the window from its first sample a to its last b: busy, the CPU of the named
    processes, of ours and of other jobs, the kernel's UDP counters."""
    span_s = (b["t"] - a["t"]) / 1e9
    dt_total = b["host_total"] - a["host_total"]
    res["host_busy_pct"] = 100 * (1 - (b["host_idle"] - a["host_idle"]) / dt_total) if dt_total else None
    for name in ("sup", "ds", "view", "vehicle"):
        if a.get(name) is not None and b.get(name) is not None:
            res[f"{name}_cpu_pct"] = 100 * (b[name] - a[name]) / CLK_TCK / span_s
            res[f"{name}_rss_mb"] = b.get(name + "_rss")
    ours = 0.0
    for pid, tb in b["ours"].items():
        ta = a["ours"].get(pid)
        if ta is not None and tb is not None:
            ours += tb - ta
    res["ours_cpu_pct"] = 100 * ours / CLK_TCK / span_s  # % of one core
    # Other jobs: user-space processes this run did not start (present at both ends of the window,
    # plus the part a process that appeared or vanished in between used while it was sampled).
    foreign = 0
    inside = [x for x in samples if a["t"] <= x["t"] <= b["t"]]
    for prev, cur in zip(inside, inside[1:]):
        for pid, tc in cur["foreign"].items():
            tp = prev["foreign"].get(pid)
            if tp is not None and tc >= tp:
                foreign += tc - tp
    res["other_cpu_pct"] = 100 * foreign / CLK_TCK / span_s
    if res.get("host_busy_pct") is not None:
        res["kernel_and_unattributed_pct"] = max(0.0, res["host_busy_pct"] * (os.cpu_count() or 1)
                                                  - res["ours_cpu_pct"] - res["other_cpu_pct"])
    ua, ub = a["udp"], b["udp"]
    res["udp_in_per_s"] = (ub["InDatagrams"] - ua["InDatagrams"]) / span_s
    res["udp_rcvbuf_errors_per_s"] = (ub["RcvbufErrors"] - ua["RcvbufErrors"]) / span_s
    res["udp_out_per_s"] = (ub["OutDatagrams"] - ua["OutDatagrams"]) / span_s


def _convergence(rdir: Path, t0: int, res: dict) -> float | None:
    """Convergence (agents): the first SwarmMetrics sample with converged set. Returns when the command
    was first seen (ns), or None."""
    metrics = read_csv(rdir / "metrics.csv")
    started = next((m["recv_ns"] for m in metrics if m["epoch"] >= 1), None)
    conv = next((m["recv_ns"] for m in metrics if m["epoch"] >= 1 and m["converged"] >= 1), None)
    res["start_s"] = (started - t0) / 1e9 if started else None
    res["converge_s"] = (conv - t0) / 1e9 if conv else None
    return started


def _discovery_traffic(samples: list[dict], t0: int, t_end: int, started, res: dict) -> None:
    """Discovery's traffic: datagrams the host received from the first launch until everyone heard
    everyone, or until the supervisor's command when that came first (agents then publish at full rate)."""
    ends = [t0 + res["all_heard_s"] * 1e9] if res.get("all_heard_s") is not None else []
    ends += [started] if started else []
    first = next((x for x in samples if x["t"] >= t0), None)
    last = next((x for x in reversed(samples) if x["t"] <= min(ends + [t_end]) + 0.5e9), None)
    if first is not None and last is not None and last["t"] > first["t"]:
        res["disc_udp_in"] = last["udp"]["InDatagrams"] - first["udp"]["InDatagrams"]
        res["disc_udp_s"] = (last["t"] - first["t"]) / 1e9


def _exits(rdir: Path, res: dict) -> None:
    """Aborted processes (a signal other than our SIGTERM), bad exits, and logs with an assert."""
    codes = res.get("exit_codes", [])
    res["aborts"] = sum(1 for c in codes if c is not None and c < 0 and c != -signal.SIGTERM)
    res["bad_exits"] = sum(1 for c in codes if c is None or c != 0)
    asserts = 0
    for f in rdir.glob("*.err"):
        try:
            if "Assertion" in f.read_text(errors="replace"):
                asserts += 1
        except OSError:
            pass
    res["assert_lines"] = asserts


# --------------------------------------------------------------------------------------------
# Over runs, and the machine.

TIME_KEYS = ("all_heard_s", "converge_s")


def aggregate(runs: list[dict]) -> dict:
    agg: dict = {"runs": len(runs)}
    keys = sorted({k for r in runs for k, v in r.items() if isinstance(v, (int, float)) and not isinstance(v, bool)}
                  | set(TIME_KEYS))
    for k in keys:
        if k in ("run", "domain", "t0", "t_end"):
            continue
        vals = [r.get(k) for r in runs]
        if k in TIME_KEYS:  # not reached within the run's limit: never
            vals = [math.inf if v is None else v for v in vals]
        vals = [v for v in vals if v is not None]
        if not vals:
            continue
        agg[k] = statistics.median(vals)
        agg[k + "_range"] = [min(vals), max(vals)]
    for k in ("aborts", "bad_exits", "assert_lines"):
        agg[k + "_total"] = sum(r.get(k, 0) for r in runs)
    agg["sup_converged_runs"] = sum(1 for r in runs if r.get("sup_converged"))
    agg["converged_runs"] = sum(1 for r in runs if r.get("converge_s") is not None)
    return agg


def machine_info() -> dict:
    info = {"host_cpus": os.cpu_count(), "kernel": platform.release()}
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                info["cpu"] = line.split(":", 1)[1].strip()
                break
        for line in open("/proc/meminfo"):
            if line.startswith("MemTotal"):
                info["mem_gb"] = round(int(line.split()[1]) / 2**20, 1)
    except OSError:
        pass
    try:
        info["os"] = [l.split("=", 1)[1].strip().strip('"') for l in open("/etc/os-release")
                      if l.startswith("PRETTY_NAME")][0]
    except (OSError, IndexError):
        pass
    for k in ("rmem_max", "wmem_max", "rmem_default"):
        try:
            info[k] = int(open(f"/proc/sys/net/core/{k}").read())
        except OSError:
            pass
    try:
        out = subprocess.run(["dpkg-query", "-W", "-f=${Version}", "libfastrtps2.9"], capture_output=True, text=True)
        info["fastdds"] = out.stdout.strip() or None
    except OSError:
        pass
    return info


def git_commit() -> str:
    try:
        c = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True,
                           text=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(ROOT), "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True).stdout.strip()
        return c + ("+local changes" if dirty else "")
    except OSError:
        return "unknown"
