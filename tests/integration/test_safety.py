#!/usr/bin/env python3
"""The safety filter on agent processes (docs/SAFETY.md): free-running agents that hear one another late.

- 12 agents 0.5 apart on the x1 axis commanded onto the x2 axis (every closest point is the origin: they
  all cross there), the arc law: with safety.min_separation = 0.25 no two agents ever come closer than
  0.25, by the agents' own measure at every step (the summary's min_separation_run) and by the
  supervisor's recorded positions; the filter intervened, and the swarm still converges. The same start
  without the filter comes closer than 0.25 (so the start does force the crossing the filter prevents).

Run directly: test_safety.py --bin build/bin --source . --domain 112
"""
import itertools
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402

AGENTS = 12
SEPARATION = 0.25
# Every agent to the origin: the line x1 = 0 (the x2 axis) from agents on the x1 axis.
LINE_90 = ["shape.kind=line", "shape.m=0", "shape.c=0", "shape.rotation_deg=90", "dynamics.max_speed=0.1"]


class SafetyTest(harness.LauncherTestCase):

    def launch(self, name, sets, init):
        argv = ["bash", harness.launcher(), "--build", os.path.dirname(harness.CONFIG["bin"]),
                "--runs", os.path.join(self.run_dir, "runs_" + name), "--domain", str(self.domain),
                "--scenario", "arc_circle", "--init", init, "--timeout", "90", "--json"]
        return self.start(name, argv + [a for s in sets for a in ("--set", s)])

    def recorded_min(self, run):
        """The smallest distance of two agents in the supervisor's recorded positions (one row per agent
        per metrics sample), over the samples in which every agent follows the command."""
        rows = harness.read_csv(os.path.join(run, "record", "positions.csv"), numeric=True)
        samples = {}
        for r in rows:
            if r["epoch"] >= 1:
                samples.setdefault(r["wall_s"], []).append((r["x1"], r["x2"]))
        full = [x for x in samples.values() if len(x) == AGENTS]
        self.assertGreater(len(full), 10, "recorded samples of the whole swarm")
        return min(math.dist(a, b) for x in full for a, b in itertools.combinations(x, 2))

    def test_crossing_kept_apart_on_processes(self):
        init = os.path.join(self.run_dir, "line.csv")
        with open(init, "w") as f:
            for i in range(AGENTS):
                f.write("%.4f,0\n" % (0.5 * (i - (AGENTS - 1) / 2)))
        # Unfiltered first: the start forces agents closer than the separation.
        p = self.launch("off", LINE_90, init)
        self.assertEqual(p.wait(150), 0, "the unfiltered swarm converges")
        off = harness.summary(p.out())
        self.assertLess(off["min_separation_run"], SEPARATION, "without the filter the crossing comes closer")
        self.assertEqual(off["filter_interventions"], 0)
        # Filtered: never closer than the separation, by the agents' and by the supervisor's measure.
        p = self.launch("on", LINE_90 + ["safety.min_separation=%g" % SEPARATION], init)
        self.assertEqual(p.wait(150), 0, "the filtered swarm converges too")
        on = harness.summary(p.out())
        self.assertTrue(on["converged"])
        self.assertGreaterEqual(on["min_separation_run"], SEPARATION - 1e-9,
                                "no two agents closer than safety.min_separation at any step")
        self.assertGreater(on["filter_interventions"], 0, "the filter moved steps")
        self.assertEqual(on["promises_broken"], 0)
        self.assertEqual(on["agents_blocked"], 0, "nobody held at the end")
        run = harness.events(p.out(), "run")[0]["dir"]
        self.assertGreaterEqual(self.recorded_min(run), SEPARATION - 1e-9, "recorded positions kept apart")
        # The figures travel in the metrics: the recording's last row has them.
        last = harness.read_csv(os.path.join(run, "record", "metrics.csv"), numeric=True)[-1]
        self.assertEqual(last["min_separation_run"], on["min_separation_run"])
        self.assertEqual(last["filter_interventions"], on["filter_interventions"])


if __name__ == "__main__":
    harness.main()
