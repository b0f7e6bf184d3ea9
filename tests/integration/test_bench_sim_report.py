#!/usr/bin/env python3
"""The simulator's section of the benchmark report (bench/bench_report.py), from made-up results, without
running anything: the bound from the peak (a row's own, measured beside its calls, where it has one), and
what the weight costs from the rows with beta = 0.
"""
import sys
import unittest
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "bench"))
import bench_report  # noqa: E402


def row(n, ns, beta=None, threads=1):
    return {"agents": n, "impl": "fast", "simd": "avx512", "threads": threads, "beta": beta, "ns_per_pair": ns,
            "steps_per_s": 1e9 / (ns * n * (n - 1) / 2)}


class SimReportTest(unittest.TestCase):

    def sim(self, with_zero=True):
        rows = [row(1000, 1.0), row(10000, 0.8), row(10000, 0.45, threads=2)]
        if with_zero:
            rows += [row(1000, 0.4, beta=0.0), row(10000, 0.3, beta=0.0)]
        return {"available": True, "peak": {"generic": 10e9, "avx2": 25e9, "avx512": 50e9}, "rows": rows}

    def test_weight_cost_and_the_floor_it_leaves(self):
        text = bench_report.sim_section(self.sim())
        # 25 multiply-adds per pair at 50 G/s: 0.5 ns; the paper's rows are 2 and 1.6 times that.
        self.assertIn("at least 0.50 ns", text)
        self.assertIn("N = 1000: 1.00 ns, x2.00 the bound; N = 10000: 0.80 ns, x1.60 the bound", text)
        weight = text[text.index("**What the weight costs.**"):]
        self.assertIn("N = 1000: 0.40 ns; N = 10000: 0.30 ns per pair", weight)  # the beta = 0 rows
        self.assertIn("is the difference: N = 1000: 0.60 ns; N = 10000: 0.50 ns", weight)
        # The weight's 19 multiply-adds at the peak: 0.38 ns; on top of the rest: 0.78 and 0.68 ns.
        self.assertIn("alone take 0.38 ns", weight)
        self.assertIn("N = 1000: 0.78 ns, x1.56 the bound, beyond the target even so; "
                      "N = 10000: 0.68 ns, x1.36 the bound, beyond the target even so", weight)
        self.assertIn("1.3 times the bound, 0.65 ns", weight)
        # A rest small enough: within the target, if the weight's other operations were free.
        sim = self.sim()
        sim["rows"][-1]["ns_per_pair"] = 0.25
        self.assertIn("N = 10000: 0.63 ns, x1.26 the bound, within the target only if", bench_report.sim_section(sim))

    def test_a_row_against_the_peak_measured_beside_it(self):
        # The host ran a fifth slower during the N = 10000 row: its own peak, 40 G/s, makes the bound 0.625 ns.
        sim = self.sim()
        sim["rows"][1]["peak_fma_per_s"] = 40e9
        text = bench_report.sim_section(sim)
        self.assertIn("N = 1000: 1.00 ns, x2.00 the bound; N = 10000: 0.80 ns, x1.28 the bound, its peak 40.0 G/s",
                      text)
        weight = text[text.index("**What the weight costs.**"):]
        # At 40 G/s the weight's 19 multiply-adds take 0.475 ns: 0.30 + 0.475 = 0.78 ns, x1.24 of 0.625 ns.
        self.assertIn("N = 10000: 0.78 ns, x1.24 the bound, within the target only if", weight)
        self.assertIn("1.3 times the bound, 0.81 ns", weight)

    def test_no_weight_paragraph_without_beta_zero_rows(self):
        text = bench_report.sim_section(self.sim(with_zero=False))
        self.assertIn("at least 0.50 ns", text)
        self.assertNotIn("What the weight costs", text)


if __name__ == "__main__":
    unittest.main()
