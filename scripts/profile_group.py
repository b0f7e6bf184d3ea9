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

Usage: scripts/profile_group.py [--agents 1000] [--group 50] [--rate 20] [--window 10] [--domain 50]
                                [--perf] [--build build] [--keep DIR]
Only the processes it started are stopped, by their pids. DDS domain: --domain (default 50).
"""
import argparse
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
CONVERGED = re.compile(r'"converged":\s*true')


def parse_profile(log: str):
    """The phases (name -> us per tick) and CPU split of a group's "profile:" line; None without one."""
    m = PROFILE.search(log)
    if not m:
        return None
    phases = {name: float(us) for name, us in PHASE.findall(m["phases"]) if name != "total"}
    return {"phases": phases, "ticks": int(m["ticks"]), "cpu": float(m["cpu"]), "loop": float(m["loop"]),
            "other": float(m["other"])}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    ap.add_argument("--agents", type=int, default=1000, help="swarm size (default 1000)")
    ap.add_argument("--group", type=int, default=50, help="agents per process (default 50)")
    ap.add_argument("--rate", type=float, default=20.0, help="agent.rate_hz (default 20)")
    ap.add_argument("--window", type=float, default=10.0, help="seconds measured after convergence (default 10)")
    ap.add_argument("--domain", type=int, default=50, help="DDS domain (default 50)")
    ap.add_argument("--perf", action="store_true", help="also perf-record one group process in the window")
    ap.add_argument("--build", default="build", help="build folder (default build)")
    ap.add_argument("--keep", help="keep the processes' logs in this folder (default: a temporary one, removed)")
    args = ap.parse_args()
    if args.agents < 2 or args.group < 2 or args.group > 1000:
        ap.error(f"--agents must be >= 2 and --group 2..1000, got {args.agents} and {args.group}")
    if not 0 <= args.domain <= 232:
        ap.error(f"--domain must be 0..232, got {args.domain}")
    bindir = (ROOT / args.build / "bin").resolve()
    for exe in ("shapeform_agent_group", "shapeform_supervisor"):
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
    try:
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
        perf = None
        if args.perf:
            # The window begins once converged: perf records the second half of the wait's budget at most.
            procs.poll(lambda: CONVERGED.search(sup.out()) or not sup.running(), 200, "the swarm to converge", 0.2)
            perf = subprocess.Popen(["perf", "record", "-g", "-o", str(rdir / "perf.data"), "-p",
                                     str(started[0].pid), "--", "sleep", f"{max(1.0, args.window - 2):g}"],
                                    stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        code = sup.wait(args.window + 300)
        if perf is not None:
            perf.wait(60)
        procs.stop_all(started[:-1], grace=20, spacing=0.05)
        if code != 0:
            print(f"profile_group.py: the supervisor exited {code} (not converged?); see {rdir}", file=sys.stderr)
    finally:
        procs.stop_all([p for p in started if p.running()], grace=10)
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
    sys.exit(main())
