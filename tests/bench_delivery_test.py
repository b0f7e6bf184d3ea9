#!/usr/bin/python3
"""bench/bench_measure.py: the delivery over a run's window, from statuses made here. A receiver's
statuses that end before the window does (a saturated host delays the last ones past the run's end)
measure it over the part they span; a receiver silent for the whole window received nothing in it.

  tests/bench_delivery_test.py SOURCE_DIR
"""
import sys
from pathlib import Path

sys.path.insert(0, str(Path(sys.argv[1]) / "bench"))
import bench_measure  # noqa: E402
import bench_plan  # noqa: E402

S = 1_000_000_000
RATE = 20.0
ROW = bench_plan.row_from_spec("agents:3:20")


def statuses(first_s, last_s, received_per_s):
    """One status a second from first_s to last_s: ticks at RATE, samples received at received_per_s."""
    return [{"stamp_ns": t * S, "ticks": RATE * t, "samples_received": received_per_s * t, "samples_lost": 0}
            for t in range(first_s, last_s + 1)]


def delivery(by_id, w0_s=10, w1_s=60):
    res = {}
    bench_measure._delivery(ROW, w0_s * S, w1_s * S, by_id, res)
    return res["delivery"]


failures = []


def check(what, got, want):
    if got is None or abs(got - want) > 1e-9:
        failures.append(f"{what}: delivery {got}, expected {want}")


# Each of 3 agents hears the 2 others' 20 samples a second: everything delivered.
check("statuses spanning the window", delivery({i: statuses(0, 70, 2 * RATE) for i in range(3)}), 1.0)
# The same, but every status of the last 4 s of the window missing (the old figure: 0).
check("statuses ending 4 s early", delivery({i: statuses(0, 56, 2 * RATE) for i in range(3)}), 1.0)
# Half of the others' samples received, statuses ending early: half delivered.
check("half delivered, statuses ending early", delivery({i: statuses(0, 56, RATE) for i in range(3)}), 0.5)
# Agent 2's statuses stop before the window: it received nothing in it, still published to at 20 Hz
# by the others: 2 of 3 receivers delivered.
silent = {0: statuses(0, 70, 2 * RATE), 1: statuses(0, 70, 2 * RATE), 2: statuses(0, 5, 2 * RATE)}
check("one receiver silent through the window", delivery(silent), 2.0 / 3.0)

if failures:
    print("\n".join(failures))
    sys.exit(1)
print("bench delivery: 4 cases as expected")
