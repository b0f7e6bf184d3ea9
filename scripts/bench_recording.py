#!/usr/bin/env python3
"""What recording costs the supervisor (docs/BENCHMARKS.md, "Recording: the supervisor's cost").

For each swarm size: shapeform_agent_group processes (groups of --group-size, as scripts/bench.sh starts
agents) and a supervisor run with a console script: once it hears every agent, `start` (the config's
circle), a window of --seconds without recording, `record start DIR`, the same window recording, `record
stop`, `quit`. Measured per window from /proc: the supervisor's CPU (% of one core); and the recording's
bytes per agent-second (run.mcap, and the four CSV files together). Run it alone: the CPU share is of a
2-core host shared with the agents.

usage: scripts/bench_recording.py [--build build] [--domain 152] [--agents 12,100,1000] [--seconds 15]
                                  [--group-size 250]
Prints one JSON line per size and a Markdown table.
"""
import argparse
import json
import os
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "lib"))
import shapeform_procs as procs  # noqa: E402




def measure(args, n, work):
    bin_dir = os.path.join(args.build, "bin")
    record = os.path.join(work, "record_%d" % n)
    script = os.path.join(work, "script_%d.txt" % n)
    with open(script, "w") as f:
        f.write("wait agents %d timeout=180\nstart\nsleep %g\nrecord start %s\nsleep %g\nrecord stop\nquit\n"
                % (n, args.seconds, record, args.seconds))
    sets = ["--set", "swarm.agents=%d" % n, "--domain", str(args.domain)]
    groups = []
    for first in range(0, n, args.group_size):
        last = min(n, first + args.group_size) - 1
        groups.append(procs.Proc("group_%d_%d" % (n, first), [os.path.join(bin_dir, "shapeform_agent_group"), "--ids",
                                                               "%d-%d" % (first, last), "--seed", "1"] + sets, work))
    sup = procs.Proc("supervisor_%d" % n, [os.path.join(bin_dir, "shapeform_supervisor"), "--json", "--script", script]
                     + sets, work)
    try:
        # The command's epoch, then the two windows between the events that bound them.
        sup.wait_event("epoch", 240)
        c0, t0 = procs.cpu_s(sup.pid), time.monotonic()
        sup.wait_event("record", args.seconds + 60)
        c1, t1 = procs.cpu_s(sup.pid), time.monotonic()
        mark = sup.mark()
        sup.wait_event("record", args.seconds + 60, since=mark)
        c2, t2 = procs.cpu_s(sup.pid), time.monotonic()
        sup.wait(30)
    finally:
        procs.stop_all([sup] + groups)
    mcap = os.path.getsize(os.path.join(record, "run.mcap"))
    csv = sum(os.path.getsize(os.path.join(record, f)) for f in ("metrics.csv", "positions.csv", "commands.csv",
                                                                  "centre.csv"))
    return {"agents": n, "cpu_plain_percent": 100 * (c1 - c0) / (t1 - t0),
            "cpu_recording_percent": 100 * (c2 - c1) / (t2 - t1), "seconds": t2 - t1,
            "mcap_bytes_per_agent_s": mcap / (n * (t2 - t1)), "csv_bytes_per_agent_s": csv / (n * (t2 - t1))}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", default=os.path.join(HERE, "..", "build"))
    ap.add_argument("--domain", type=int, default=152)
    ap.add_argument("--agents", default="12,100,1000")
    ap.add_argument("--seconds", type=float, default=15.0)
    ap.add_argument("--group-size", type=int, default=250)
    args = ap.parse_args()
    try:
        sizes = [int(x) for x in args.agents.split(",")]
    except ValueError:
        ap.error("--agents: expected sizes like 12,100,1000, got %r" % args.agents)
    if any(n < 1 or n > 5000 for n in sizes):
        ap.error("--agents: each size in 1..5000")
    rows = []
    with tempfile.TemporaryDirectory(prefix="bench_recording_") as work:
        for n in sizes:
            print("bench_recording: %d agents..." % n, file=sys.stderr, flush=True)
            r = measure(args, n, work)
            print(json.dumps(r), flush=True)
            rows.append(r)
    print("\n| agents | supervisor CPU, not recording (% of one core) | recording | run.mcap bytes per agent-second "
          "| CSV bytes per agent-second |\n|---:|---:|---:|---:|---:|")
    for r in rows:
        print("| %d | %.1f | %.1f | %.0f | %.0f |" % (r["agents"], r["cpu_plain_percent"], r["cpu_recording_percent"],
                                                 r["mcap_bytes_per_agent_s"], r["csv_bytes_per_agent_s"]))


if __name__ == "__main__":
    main()
