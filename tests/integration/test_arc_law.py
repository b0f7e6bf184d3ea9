#!/usr/bin/env python3
"""The arc law on agent processes: a polar star and a polygon formed by 12 processes through the
launcher meet the law's acceptance criteria at the plateau (on the curve, evenly spaced by arc length)."""
import argparse
import glob
import os
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts", "lib"))
import shapeform_procs as procs  # noqa: E402

ARGS = None


class ArcLawOnProcesses(unittest.TestCase):
    def launch(self, scenario, domain, size):
        os.makedirs(ARGS.workdir, exist_ok=True)
        runs = tempfile.mkdtemp(prefix="arc-", dir=ARGS.workdir)
        cmd = [os.path.join(ARGS.source, "scripts", "launch_swarm.sh"), "-n", "12", "--scenario", scenario,
               "--domain", str(domain), "--json", "--timeout", "90", "--build", ARGS.build, "--runs", runs]
        p = subprocess.run(cmd, stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=240)
        s = procs.summary(p.stdout)
        if p.returncode != 0 or s is None:
            for log in sorted(glob.glob(os.path.join(runs, "*", "*.log"))):
                with open(log) as f:
                    tail = f.read().splitlines()[-15:]
                print(f"--- {log}\n" + "\n".join(tail), file=sys.stderr)
            self.fail(f"{scenario}: launcher exit {p.returncode}\n{p.stderr[-3000:]}")
        self.assertEqual(s["agents"], 12)
        self.assertEqual(s["law"], "arc")
        self.assertTrue(s["converged"], s)
        # The plateau criteria of the arc law, on real processes.
        self.assertLessEqual(s["curve_error_mean"], 1e-3 * size, s)
        self.assertLessEqual(s["arc_gap_cv"], 0.01, s)
        self.assertGreater(s["min_separation"], 0.5, s)
        return s

    def test_polar_star(self):
        self.launch("polar_star", ARGS.domain, 5.0)

    def test_polygon(self):
        self.launch("polygon", ARGS.domain, 5.0)


if __name__ == "__main__":
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin", required=True)
    ap.add_argument("--source", required=True)
    ap.add_argument("--domain", type=int, default=144)
    ap.add_argument("--workdir", default=tempfile.gettempdir())
    ARGS, rest = ap.parse_known_args()
    ARGS.build = os.path.dirname(os.path.abspath(ARGS.bin))
    unittest.main(argv=[sys.argv[0], "-v", *rest])
