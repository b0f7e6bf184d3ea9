#!/usr/bin/env python3
"""The benchmark's scale ladder (bench/bench_plan.py, bench/bench_report.py), without running anything:
`--only scale` selects the 2000, 4000, 5000 and 10000 agent rows and their baselines, each in 10 processes;
large rows get longer timeouts; a row's verdict follows the acceptance (delivery >= 99 %, data age p99
<= 100 ms, converged in every run) and the section names the largest swarm that met it.
"""
import argparse
import sys
import unittest
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "bench"))
import bench_plan  # noqa: E402
import bench_report  # noqa: E402


def args(**kw):
    a = argparse.Namespace(no_main=False, no_scale=False, levers=False, row=[], only=[], no_sim=True)
    for k, v in kw.items():
        setattr(a, k, v)
    return a


def entry(row, delivery, p99, converge_s, busy=50.0, cpu=0.03):
    return {"row": row.__dict__ | {"id": row.id},
            "agg": {"delivery": delivery, "age_p99_ms": p99, "converge_s": converge_s, "runs": 1,
                    "host_busy_pct": busy, "cpu_pct": cpu, "age_p50_ms": 1.0, "all_heard_s": 1.0}}


class ScaleLadderTest(unittest.TestCase):

    def test_only_scale_selects_the_ladder_in_10_processes(self):
        rows, sim = bench_plan.select_rows(args(only=["scale"]), {})
        self.assertFalse(sim)
        self.assertEqual([(r.kind, r.n, -(-r.n // r.group)) for r in rows],
                         [(k, n, 10) for n in (2000, 4000, 5000, 10000) for k in ("baseline", "group")])
        self.assertTrue(all(r.section == "scale" and r.rate == 20.0 for r in rows))
        # --no-scale leaves them out of a default invocation; the main rows stay.
        default, _ = bench_plan.select_rows(args(), {})
        without, _ = bench_plan.select_rows(args(no_scale=True), {})
        self.assertEqual({r.id for r in default} - {r.id for r in without}, {r.id for r in rows})

    def test_large_rows_wait_longer(self):
        small, big = bench_plan.Row("group", 1000, 20.0, group=100), bench_plan.Row("group", 10000, 20.0, group=1000)
        self.assertEqual(bench_plan.timeouts_of(small, False), (60.0, 60.0))
        self.assertEqual(bench_plan.timeouts_of(small, True), (40.0, 40.0))
        self.assertEqual(bench_plan.timeouts_of(big, False), (150.0, 150.0))

    def test_verdict_and_largest_swarm(self):
        rows = {r.id: r for r in bench_plan.scale_rows()}
        store = {"rows": {}}
        for rid, r in rows.items():
            if r.n == 2000:
                store["rows"][rid] = entry(r, 0.999, 15.0, 13.0 if r.kind == "group" else float("inf"))
            elif r.n == 5000:  # misses: the p99 and the convergence
                store["rows"][rid] = entry(r, 0.995, 104.0, float("inf"))
        text = bench_report.scale_section(store)
        self.assertIn("**2000 agents**", text)
        g5 = next(line for line in text.splitlines() if line.startswith("| `group-n5000") and "verdict" not in line
                  and "missed" in line)
        self.assertIn("data age p99 <= 100 ms (104 ms)", g5)
        self.assertIn("arc-law circle converged", g5)
        self.assertNotIn("delivery >= 99 %", g5)
        self.assertIn("| `group-n10000-r20-g1000-mcbufann` | not run", text)
        # Nobody met it: the section says so.
        for rid in list(store["rows"]):
            store["rows"][rid]["agg"]["delivery"] = 0.5
        self.assertIn(bench_plan.NOTES["scale"]["none_met"], bench_report.scale_section(store))


if __name__ == "__main__":
    unittest.main()
