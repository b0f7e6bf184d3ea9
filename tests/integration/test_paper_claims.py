#!/usr/bin/python3
"""The paper's claims on real agent processes (scripts/launch_swarm.sh: one process per agent and a
supervisor, loopback, fixed seeds, DDS domains 140..149).

- Repulsion: on the ellipse and the square (12 agents, step 200) r = 0.1 lowers the gap CV at least
  tenfold against r = 0 (without repulsion the agents pile up in clumps).
- Tracking without feed-forward (the published law): the centre outruns the swarm, which trails as a
  blob on both paths (documents the published behaviour).
- Tracking with feed-forward: after the transient the formation around the moving centre matches the
  same formation around a fixed centre from the same start in the centre's frame.

  The issue's bound (centroid and ring errors within 0.1 of the fixed-centre run) is checked exactly
  where it is a property of the law: in the simulator (deterministic; on the line path the two runs are
  identical). Between two runs of asynchronous processes the ring error keeps to 0.1, but the centroid
  error does not: each process ticks at its own phase, so every agent sees some neighbours one step
  older than others, and the resting ring settles a little off-centre by an amount that depends on the
  phases (fixed-centre runs alone spread over 0.05..0.25; with feed-forward a stale neighbour is also
  one step of the centre's motion behind, spreading 0.1..0.4). The process check therefore asks for the
  ring error within 0.1, the centroid error within 0.3 and below 0.5 (without feed-forward it is ~4).
  docs/RESULTS.md has the numbers and the asynchronous model that reproduces them.

  On the line path the swarm starts around C(0) (the seeded start shifted by C(0) = (-10, -10)): from
  the paper's start, 14 units away, agents that fall behind escape for ever under the published law,
  with or without a moving centre, and which ones do depends on the tick phases.

Usage: test_paper_claims.py --bin BUILD/bin --source SOURCE_DIR [unittest args]
"""
import argparse
import csv
import glob
import json
import os
import statistics
import subprocess
import sys
import tempfile
import unittest

ARGS = None
TMP = None
C0 = {"line": (-10.0, -10.0), "circle": (6.0, 0.0)}


def launcher():
    return os.path.join(ARGS.source, "scripts", "launch_swarm.sh")


def build_dir():
    return os.path.dirname(os.path.abspath(ARGS.bin))


def sim(*args):
    p = subprocess.run([os.path.join(ARGS.bin, "shapeform_sim"), *args], capture_output=True, text=True,
                       timeout=120)
    if p.returncode != 0:
        raise AssertionError(f"shapeform_sim {args}: status {p.returncode}: {p.stderr}")
    return json.loads(p.stdout)


def scenario(name):
    return os.path.join(ARGS.source, "config", "scenarios", name + ".yaml")


def seeded_start(scen, offset=(0.0, 0.0), seed=1):
    """The simulator's seeded start for the scenario, shifted by offset, as a CSV file."""
    pts = sim("--config", scenario(scen), "--seed", str(seed), "--steps", "0")["final_positions"]
    path = os.path.join(TMP, f"start_{scen}_{offset[0]:g}_{offset[1]:g}_{seed}.csv")
    with open(path, "w") as f:
        for x, y in pts:
            f.write(f"{x + offset[0]:.17g},{y + offset[1]:.17g}\n")
    return path


def log_tails(runs_dir, lines=15):
    out = []
    for path in sorted(glob.glob(os.path.join(runs_dir, "*", "*.log"))):
        with open(path, errors="replace") as f:
            tail = f.read().splitlines()[-lines:]
        out.append(f"--- {path}\n" + "\n".join(tail))
    return "\n".join(out)


def launch(scen, n, domain, steps, init=None, sets=()):
    """One swarm run through the project's launcher; returns (summary, per-step metric rows)."""
    tag = f"{scen}_d{domain}"
    runs = os.path.join(TMP, "runs_" + tag)
    record = os.path.join(TMP, "rec_" + tag)
    cmd = [launcher(), "-n", str(n), "--scenario", scen, "--domain", str(domain), "--steps", str(steps),
           "--record", record, "--json", "--build", build_dir(), "--runs", runs,
           "--set", "supervisor.metrics_rate_hz=50"]
    if init:
        cmd += ["--init", init]
    for s in sets:
        cmd += ["--set", s]
    timeout = steps / 50.0 * 4 + 120
    p = subprocess.run(cmd, stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=timeout)
    if p.returncode != 0:
        raise AssertionError(f"launch_swarm.sh {scen} exited {p.returncode}\n{p.stderr[-3000:]}\n"
                             f"{log_tails(runs)}")
    lines = [l for l in p.stdout.splitlines() if l.strip().startswith("{")]
    if not lines:
        raise AssertionError(f"no JSON summary from launch_swarm.sh\n{p.stdout}\n{p.stderr[-3000:]}")
    summary = json.loads(lines[-1])
    rows = []
    with open(os.path.join(record, "metrics.csv"), newline="") as f:
        for r in csv.DictReader(f):
            if r["epoch"] and int(float(r["epoch"])) >= 1:
                rows.append({k: (float(v) if v != "" else None) for k, v in r.items()})
    if summary.get("agents_seen") != n:
        raise AssertionError(f"{scen}: supervisor saw {summary.get('agents_seen')} of {n} agents\n{log_tails(runs)}")
    return summary, rows


def window(rows, key, t0, t1):
    """Median of a metric over supervisor samples with model time in [t0, t1]."""
    vals = [r[key] for r in rows if t0 <= r["model_time"] <= t1 and r[key] is not None]
    if not vals:
        raise AssertionError(f"no {key} samples in model time [{t0}, {t1}]")
    return statistics.median(vals)


class Repulsion(unittest.TestCase):
    def test_repulsion_lowers_gap_cv_tenfold(self):
        domain = 140
        for shape in ("ellipse", "square"):
            with self.subTest(shape=shape):
                start = seeded_start(shape)
                s0, rows0 = launch(f"{shape}_no_repulsion", 12, domain, 200, init=start)
                s1, rows1 = launch(shape, 12, domain + 1, 200, init=start)
                domain += 2
                g1 = window(rows1, "gap_cv", 190, 200)
                self.assertEqual(s1["clusters"], 12, f"{shape} r=0.1: agents merged: {s1}")
                self.assertLess(g1, 0.2, f"{shape} r=0.1: not spread along the shape")
                vals0 = [r["gap_cv"] for r in rows0 if 190 <= r["model_time"] <= 200]
                if all(v is None for v in vals0):
                    # Every agent on one point: the gap CV is undefined; that is the extreme of clumping.
                    self.assertEqual(s0["clusters"], 1, f"{shape} r=0: gap CV undefined but {s0['clusters']} clusters")
                else:
                    g0 = window(rows0, "gap_cv", 190, 200)
                    self.assertGreaterEqual(g0, 10 * g1, f"{shape}: gap CV r=0 {g0:.3f} vs r=0.1 {g1:.3f}")
                    self.assertGreaterEqual(g0, 1.0, f"{shape}: r=0 should clump (gap CV {g0:.3f})")


class Tracking(unittest.TestCase):
    T = 300  # model time of the run; the transient is over by 200

    def test_without_feedforward_the_swarm_trails(self):
        domain = 144
        for path in ("line", "circle"):
            with self.subTest(path=path):
                s, rows = launch(f"track_{path}", 10, domain, 200, init=seeded_start(f"track_{path}"))
                domain += 1
                c = window(rows, "centroid_error", 180, 200)
                ring = window(rows, "ring_error", 180, 200)
                # The centre moves 0.14 (line) or 0.19 (circle) per iteration, faster than the swarm's
                # centroid can follow (~0.15): the swarm trails as a blob instead of surrounding it.
                self.assertGreater(c, 2.5, f"{path}: centroid error {c:.3f}: the published law should trail")
                self.assertGreater(ring, 1.2, f"{path}: ring error {ring:.3f}")

    def test_feedforward_in_the_simulator_is_the_static_problem(self):
        # The bound, exactly, where it is a property of the law (no tick phases).
        for path in ("line", "circle"):
            with self.subTest(path=path):
                off = C0[path] if path == "line" else (0.0, 0.0)
                start = seeded_start(f"track_{path}", off)
                for t in (200, 300):
                    ff = sim("--config", scenario(f"track_{path}"), "--init", start, "--steps", str(t),
                             "--set", "tracking.feedforward=true")
                    fx = sim("--config", scenario(f"track_{path}"), "--init", start, "--steps", str(t),
                             "--set", "tracking.path=fixed", "--set", f"tracking.point=[{C0[path][0]},{C0[path][1]}]")
                    self.assertLessEqual(abs(ff["centroid_error"] - fx["centroid_error"]), 0.1, (t, ff, fx))
                    self.assertLessEqual(abs(ff["ring_error"] - fx["ring_error"]), 0.1, (t, ff, fx))
                    self.assertLess(ff["centroid_error"], 0.5)

    def test_feedforward_processes_match_a_fixed_centre(self):
        domain = 146
        for path in ("line", "circle"):
            with self.subTest(path=path):
                off = C0[path] if path == "line" else (0.0, 0.0)
                start = seeded_start(f"track_{path}", off)
                _, ff = launch(f"track_{path}", 10, domain, self.T, init=start, sets=["tracking.feedforward=true"])
                _, fx = launch(f"track_{path}", 10, domain + 1, self.T, init=start,
                               sets=["tracking.path=fixed", f"tracking.point=[{C0[path][0]},{C0[path][1]}]"])
                domain += 2
                c_ff, c_fx = window(ff, "centroid_error", 200, self.T), window(fx, "centroid_error", 200, self.T)
                r_ff, r_fx = window(ff, "ring_error", 200, self.T), window(fx, "ring_error", 200, self.T)
                msg = f"{path}: feed-forward centroid {c_ff:.3f} ring {r_ff:.3f}; fixed centre {c_fx:.3f} {r_fx:.3f}"
                self.assertLess(c_ff, 0.5, msg)  # surrounds the moving centre
                self.assertLess(r_ff, 0.7, msg)  # a ring of radius ~r0 around it
                self.assertLessEqual(abs(r_ff - r_fx), 0.1, msg)
                self.assertLessEqual(abs(c_ff - c_fx), 0.3, msg)


if __name__ == "__main__":
    parser = argparse.ArgumentParser()
    parser.add_argument("--bin", required=True)
    parser.add_argument("--source", required=True)
    ARGS, rest = parser.parse_known_args()
    with tempfile.TemporaryDirectory(prefix="paper_claims_") as d:
        TMP = d
        prog = unittest.main(argv=[sys.argv[0], "-v", *rest], exit=False)
    sys.exit(0 if prog.result.wasSuccessful() else 1)
