#!/usr/bin/python3
"""Where a shapeform_agent_group process's time goes, per tick.

Runs a grouped swarm on loopback as the benchmark's group rows do (bench/bench_run.py: the arc-law
circle scenario, transport preset mcbufann, 20 Hz, a supervisor that starts it once every agent is
heard, waits for convergence and then for --window seconds), then stops the groups (SIGTERM) and reads
the "profile:" line each one logs at exit (agent/agent_node.cpp: the loop's phases timed per tick in the loop thread's CPU time,
and the process's CPU split between the loop thread and Fast DDS's threads). Prints one table: the
mean over the group processes of each phase, in microseconds per tick.

With --perf, also `perf record -g` one group process during the window and prints the top symbols
of `perf report` (needs perf and a kernel.perf_event_paranoid that lets the user profile its own
processes).

With --baseline, then also runs the bare grouped baseline of the same shape (bench/baseline.cpp, as the
benchmark's baseline rows run it: same ids per process, transport, rate and batches, no agent logic),
each run beside the benchmark's probe (bench/probe.cpp, which reads every status), and prints both
swarms' CPU per process over their windows, read from /proc (each thread's utime + stime): the main
thread (the group's loop; the baseline's publishing loop) apart from Fast DDS's threads. The baseline's
window begins as long after its launch as the group's did (at convergence) and is as long.

Usage: scripts/profile_group.py [--agents 1000] [--group 50] [--rate 20] [--window 10] [--domain 50]
                                [--perf] [--baseline] [--build build] [--keep DIR]
Only the processes it started are stopped, by their pids. DDS domain: --domain (default 50).
"""
import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "scripts" / "lib"))
import shapeform_procs as procs  # noqa: E402

# The benchmark's mcbufann preset (bench/bench_plan.py), the transport of the rows this profiles.
MCBUFANN = ["transport.multicast_data=true", "transport.socket_buffer_bytes=4194304", "transport.lease_s=10",
            "transport.announce_s=3"]
PROFILE = re.compile(r"profile: (?P<phases>.*) per tick over (?P<ticks>\d+) ticks; cpu (?P<cpu>[\d.]+) % of a core: "
                     r"loop thread (?P<loop>[\d.-]+) %, other threads (?P<other>[\d.-]+) %")
PHASE = re.compile(r"(\w+) ([\d.]+) us")
CONVERGED = re.compile(r'"ok":\s*true,\s*"wait":\s*"converged"')  # the script's `wait converged` met


def parse_profile(log: str):
    """The phases (name -> us per tick) and CPU split of a group's "profile:" line; None without one."""
    m = PROFILE.search(log)
    if not m:
        return None
    phases = {name: float(us) for name, us in PHASE.findall(m["phases"]) if name != "total"}
    return {"phases": phases, "ticks": int(m["ticks"]), "cpu": float(m["cpu"]), "loop": float(m["loop"]),
            "other": float(m["other"])}


def thread_ticks(pids):
    """Per pid: the clock ticks (utime + stime) of its main thread and of its other threads, from /proc
    (a process that is gone counts 0)."""
    out = {}
    for pid in pids:
        main = other = 0
        try:
            for tid in os.listdir(f"/proc/{pid}/task"):
                with open(f"/proc/{pid}/task/{tid}/stat") as f:
                    fields = f.read().rsplit(")", 1)[1].split()
                ticks = int(fields[11]) + int(fields[12])  # utime, stime (fields 14 and 15 of stat)
                if int(tid) == pid:
                    main += ticks
                else:
                    other += ticks
        except OSError:
            pass
        out[pid] = (main, other)
    return out


def cpu_split(before, after, seconds):
    """Mean % of a core per process over `seconds`: (main thread, other threads)."""
    hz = os.sysconf("SC_CLK_TCK")
    pids = [p for p in before if p in after]
    if not pids or seconds <= 0:
        return 0.0, 0.0
    main = sum(after[p][0] - before[p][0] for p in pids) / hz / seconds / len(pids) * 100
    other = sum(after[p][1] - before[p][1] for p in pids) / hz / seconds / len(pids) * 100
    return main, other


def start_probe(bindir, rdir, sets, name):
    """The benchmark's probe (bench/probe.cpp: it reads every status and metrics sample, as in the
    benchmark's rows), once its readers exist."""
    probe = procs.Proc(name, [bindir / "shapeform_bench_probe", "--out", rdir / name] + sets, rdir)
    line = procs.wait_for(lambda: probe.out() if "\n" in probe.out() or not probe.running() else "", 30)
    if not line.startswith("ready"):
        procs.stop_all([probe], grace=5)
        raise RuntimeError(f"the probe did not start: {line!r}; see {rdir}")
    return probe


def run_baseline(args, bindir, rdir, sets, start_s, window_s):
    """The bare grouped baseline of the same shape, beside a probe: (main, other) % of a core per process
    over a window that begins start_s after its launch and lasts window_s."""
    started = [start_probe(bindir, rdir, sets, "baseline_probe")]
    try:
        launched = time.monotonic()
        for first in range(0, args.agents, args.group):
            ids = f"{first}-{min(args.agents, first + args.group) - 1}"
            started.append(procs.Proc(f"baseline{first}", [bindir / "shapeform_bench_baseline", "--ids", ids] + sets,
                                      rdir))
        time.sleep(max(0.0, launched + start_s - time.monotonic()))
        dead = [p.name for p in started if not p.running()]  # the probe included
        if dead:
            raise RuntimeError(f"baseline processes exited early: {', '.join(dead)}; see {rdir}")
        workers = [p.pid for p in started[1:]]
        t0, before = time.monotonic(), thread_ticks(workers)
        time.sleep(window_s)
        t1, after = time.monotonic(), thread_ticks(workers)
        return cpu_split(before, after, t1 - t0)
    finally:
        procs.stop_all(started, grace=10, spacing=0.05)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    ap.add_argument("--agents", type=int, default=1000, help="swarm size (default 1000)")
    ap.add_argument("--group", type=int, default=50, help="agents per process (default 50)")
    ap.add_argument("--rate", type=float, default=20.0, help="agent.rate_hz (default 20)")
    ap.add_argument("--window", type=float, default=10.0, help="seconds measured after convergence (default 10)")
    ap.add_argument("--domain", type=int, default=50, help="DDS domain (default 50)")
    ap.add_argument("--perf", action="store_true", help="also perf-record one group process in the window")
    ap.add_argument("--baseline", action="store_true",
                    help="then also run the bare grouped baseline of the same shape and compare CPU per process")
    ap.add_argument("--build", default="build", help="build folder (default build)")
    ap.add_argument("--keep", help="keep the processes' logs in this folder (default: a temporary one, removed)")
    args = ap.parse_args()
    if args.agents < 2 or args.group < 2 or args.group > 1000:
        ap.error(f"--agents must be >= 2 and --group 2..1000, got {args.agents} and {args.group}")
    if not 0 <= args.domain <= 232:
        ap.error(f"--domain must be 0..232, got {args.domain}")
    bindir = (ROOT / args.build / "bin").resolve()
    needed = ("shapeform_agent_group", "shapeform_supervisor")
    if args.baseline:
        needed += ("shapeform_bench_baseline", "shapeform_bench_probe")
    for exe in needed:
        if not (bindir / exe).exists():
            print(f"profile_group.py: {bindir / exe} missing: build it first (scripts/build.sh)", file=sys.stderr)
            return 2
    if args.perf and not shutil.which("perf"):
        print("profile_group.py: --perf needs perf (apt-get install linux-perf)", file=sys.stderr)
        return 2
    rdir = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="profile_group-"))
    rdir.mkdir(parents=True, exist_ok=True)
    scenario = ROOT / "config" / "scenarios" / "arc_circle.yaml"
    sets = ["--domain", str(args.domain)] + procs.sets_args(
        MCBUFANN + [f"agent.rate_hz={args.rate:g}", "agent.status_rate_hz=2", f"swarm.agents={args.agents}"])
    started = []
    probe = None
    try:
        probe = start_probe(bindir, rdir, sets, "probe") if args.baseline else None
        for first in range(0, args.agents, args.group):
            ids = f"{first}-{min(args.agents, first + args.group) - 1}"
            started.append(procs.Proc(f"group{first}", [bindir / "shapeform_agent_group", "--ids", ids, "--config",
                                                        scenario, "--seed", "1"] + sets, rdir))
        script = rdir / "script.txt"
        script.write_text(f"wait agents {args.agents} timeout=120\nstart\nwait converged timeout=60\n"
                          f"sleep {args.window:g}\nquit\n")
        sup = procs.Proc("supervisor", [bindir / "shapeform_supervisor", "--config", scenario, "--script", script,
                                        "--json"] + sets, rdir)
        started.append(sup)
        launched = time.monotonic()
        # The window begins once converged (the supervisor's script then sleeps --window seconds).
        procs.poll(lambda: CONVERGED.search(sup.out()) or not sup.running(), 200, "the swarm to converge", 0.2)
        t0, before = time.monotonic(), thread_ticks([g.pid for g in started[:-1]])
        perf = None
        if args.perf:
            perf = subprocess.Popen(["perf", "record", "-g", "-o", str(rdir / "perf.data"), "-p",
                                     str(started[0].pid), "--", "sleep", f"{max(1.0, args.window - 2):g}"],
                                    stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        code = sup.wait(args.window + 300)
        t1, after = time.monotonic(), thread_ticks([g.pid for g in started[:-1]])
        if perf is not None:
            perf.wait(60)
        procs.stop_all(started[:-1], grace=20, spacing=0.05)
        if code != 0:
            print(f"profile_group.py: the supervisor exited {code} (not converged?); see {rdir}", file=sys.stderr)
    finally:
        procs.stop_all([p for p in started + [probe] if p is not None and p.running()], grace=10)
    group_split = cpu_split(before, after, t1 - t0)
    base_split = None
    if args.baseline and code == 0:
        base_split = run_baseline(args, bindir, rdir, sets, t0 - launched, t1 - t0)
    profiles = [p for p in (parse_profile(g.log()) for g in started[:-1]) if p]
    if not profiles:
        print(f"profile_group.py: no group logged a profile line; see {rdir}", file=sys.stderr)
        return 1
    names = list(profiles[0]["phases"])
    mean = {n: sum(p["phases"][n] for p in profiles) / len(profiles) for n in names}
    total = sum(mean.values())
    print(f"{args.agents} agents in {len(started) - 1} processes of {args.group}, {args.rate:g} Hz, mcbufann; "
          f"mean of {len(profiles)} processes over {profiles[0]['ticks']} ticks each")
    print(f"{'phase (loop thread CPU)':24} {'us/tick':>9} {'share':>7}")
    for n in names:
        print(f"{n:24} {mean[n]:9.1f} {100 * mean[n] / total if total else 0:6.1f}%")
    print(f"{'phases total':24} {total:9.1f}")
    avg = lambda k: sum(p[k] for p in profiles) / len(profiles)  # noqa: E731
    period_us = 1e6 / args.rate
    print(f"CPU per process, % of a core: {avg('cpu'):.2f} (loop thread {avg('loop'):.2f}, Fast DDS's threads "
          f"{avg('other'):.2f}); the loop thread's {avg('loop') * period_us / 100:.0f} us per tick include its "
          f"sleep's wake-up, which the phases do not time")
    if base_split is not None:
        print(f"CPU per process over the window (/proc), % of a core: {'group':>8} {'baseline':>9} {'ratio':>7}")
        rows = [("main thread", group_split[0], base_split[0]), ("Fast DDS's threads", group_split[1], base_split[1]),
                ("all", sum(group_split), sum(base_split))]
        for name, g, b in rows:
            print(f"  {name:52} {g:8.2f} {b:9.2f} {'x%.2f' % (g / b) if b > 0 else 'n/a':>7}")
    if args.perf:
        report = subprocess.run(["perf", "report", "-i", str(rdir / "perf.data"), "--no-children", "--stdio",
                                 "--percent-limit", "1", "-g", "none", "--sort", "dso,symbol"],
                                capture_output=True, text=True)
        lines = [ln for ln in report.stdout.splitlines() if ln.strip() and not ln.startswith("#")]
        print("perf report (one process, self time >= 1 %):")
        print("\n".join(lines[:40]))
    if not args.keep:
        shutil.rmtree(rdir, ignore_errors=True)
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except (AssertionError, RuntimeError) as e:  # a swarm that did not converge, a process that did not start
        print(f"profile_group.py: {e}", file=sys.stderr)
        sys.exit(1)
