#!/usr/bin/env python3
"""Foxglove WebSocket throughput of shapeform_view (docs/BENCHMARKS.md, "Foxglove WebSocket").

For each swarm size: shapeform_agent_group processes (as scripts/bench.sh starts agents; no supervisor,
the agents publish their state without a command), shapeform_view --foxglove-port 0 --fps FPS (no
page), and one Foxglove client (tests/npm/foxglove_client.mjs, FoxgloveClient of @foxglove/ws-protocol,
from build/npm) subscribed to shapeform/scene, decoding every frame. Measured once every agent is drawn:
frames/s delivered to the client, bytes per frame, the view's CPU (% of one core, /proc) and the frames
the server dropped for the client.

usage: scripts/bench_foxglove.py [--build build] [--domain 151] [--agents 12,100,1000] [--fps 15]
                                 [--seconds 10] [--group-size 250] [--slow-client]
--slow-client adds a row: the largest size again with a second client that subscribes and then stops
reading; the measured client must keep its frame rate and the server count the dropped messages.
Prints one JSON line per size and a Markdown table.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "lib"))
import shapeform_procs as procs  # noqa: E402




def measure(args, n, work, stalled=0):
    bin_dir = os.path.join(args.build, "bin")
    npm = os.path.join(args.build, "npm")
    if not os.path.isdir(os.path.join(npm, "node_modules", "@foxglove", "ws-protocol")):
        sys.exit("bench_foxglove: the npm validators are missing in %s: run scripts/install_deps.sh" % npm)
    sets = ["--set", "swarm.agents=%d" % n]
    view = procs.Proc("view_%d" % n, [os.path.join(bin_dir, "shapeform_view"), "--foxglove-port", "0", "--json", "--fps",
                                      str(args.fps), "--domain", str(args.domain)] + sets, work)
    groups = []
    try:
        start = view.wait_event("start", 20)
        for first in range(0, n, args.group_size):
            last = min(n, first + args.group_size) - 1
            groups.append(procs.Proc("group_%d_%d" % (n, first), [os.path.join(bin_dir, "shapeform_agent_group"), "--ids",
                                                                   "%d-%d" % (first, last), "--seed", "1", "--domain",
                                                                   str(args.domain)] + sets, work))
        # Until every agent is drawn (discovery of 1000 agents takes seconds), then the measured window.
        frames_needed = int(args.seconds * args.fps)
        client = [shutil.which("node"), os.path.join(HERE, "..", "tests", "npm", "foxglove_client.mjs"), "--url",
                  start["foxglove_url"], "--npm", npm, "--topics", "shapeform/scene", "--brief", "--subprotocols",
                  "foxglove.sdk.v1", "--timeout", str(args.seconds + 120)]
        def all_drawn():
            r = subprocess.run(client + ["--count", "1"], capture_output=True, text=True, timeout=180)
            return any(json.loads(l).get("spheres") == n for l in r.stdout.splitlines() if l.strip())
        procs.poll(all_drawn, 180, "every one of %d agents drawn" % n, interval=1.0)
        cpu0, t0 = procs.cpu_s(view.popen.pid), time.monotonic()
        r = subprocess.run(client + ["--count", str(frames_needed), "--stalled", str(stalled)], capture_output=True, text=True, timeout=args.seconds + 180)
        cpu1, t1 = procs.cpu_s(view.popen.pid), time.monotonic()
        if r.returncode != 0:
            sys.exit("bench_foxglove: the client failed: " + r.stderr[-1000:])
        msgs = [json.loads(l) for l in r.stdout.splitlines() if l.strip()]
        msgs = [m for m in msgs if m["event"] == "message"]
        full = [m for m in msgs if m.get("spheres") == n]
        span_s = (msgs[-1]["recv_ms"] - msgs[0]["recv_ms"]) / 1000.0
        view.stop()
        stop = view.wait_event("stop", 10)
        return {"agents": n, "fps": args.fps, "stalled_clients": stalled, "frames": len(msgs), "frames_with_every_agent": len(full),
                "frames_per_s": round((len(msgs) - 1) / span_s, 2) if span_s > 0 else None,
                "bytes_per_frame": round(sum(m["bytes"] for m in msgs) / len(msgs)),
                "view_cpu_percent": round(100.0 * (cpu1 - cpu0) / (t1 - t0), 1),
                "dropped": stop["foxglove"]["messages_dropped"]}
    finally:
        procs.stop_all(groups, grace=5.0)
        if view.popen.poll() is None:
            view.stop()


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[1], formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog=__doc__)
    p.add_argument("--build", default=os.path.join(HERE, "..", "build"), help="the build folder (bin/, npm/)")
    p.add_argument("--domain", type=int, default=151, help="DDS domain id (default 151)")
    p.add_argument("--agents", default="12,100,1000", help="swarm sizes, comma separated")
    p.add_argument("--fps", type=float, default=15.0, help="the view's --fps (default 15)")
    p.add_argument("--seconds", type=float, default=10.0, help="measured window per size (default 10)")
    p.add_argument("--group-size", type=int, default=250, help="agents per shapeform_agent_group process (default 250)")
    p.add_argument("--slow-client", action="store_true",
                   help="also measure the largest size with a second client that stops reading (its messages are dropped)")
    args = p.parse_args()
    args.build = os.path.abspath(args.build)
    work = tempfile.mkdtemp(prefix="bench_foxglove_")
    rows = []
    for n in [int(x) for x in args.agents.split(",")]:
        row = measure(args, n, work)
        print(json.dumps(row), flush=True)
        rows.append(row)
    if args.slow_client:
        row = measure(args, rows[-1]["agents"], work, stalled=1)
        print(json.dumps(row), flush=True)
        rows.append(row)
    print("\n| agents | stalled clients | frames/s to one client | bytes per frame | view CPU (% of a core) | dropped |")
    print("|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        print("| %d | %d | %s | %d | %s | %d |" % (r["agents"], r["stalled_clients"], r["frames_per_s"], r["bytes_per_frame"],
                                               r["view_cpu_percent"], r["dropped"]))
    print("(logs in %s)" % work)


if __name__ == "__main__":
    main()
