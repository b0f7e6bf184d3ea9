#!/usr/bin/env python3
"""Each paper shape formed by 12 agent processes reaches the simulator's plateau metrics.

The supervisor runs a script: wait for the 12 agents, `start` (the scenario's command), `wait time K`
(K iterations of model time, like `shapeform_sim --steps K`), quit; it records metrics.csv. The
agents start where the simulator with the same seed starts them. The processes are not a replay of
the simulator (each agent integrates on its own clock with neighbour positions up to one tick old),
and the law is chaotic enough that their trajectories part, so plateau statistics are compared,
averaged over the last part of the run (the metrics of both come from the same core functions):
  - circle: a true plateau; mean shape error within 10 % (or 0.02) of the simulator's, same seed;
  - square, ellipse: the error keeps drifting (square: 0.27 at step 300, 0.36 at 500) or swings
    from step to step (ellipse: 0.35..0.52), so the processes' mean must lie in the simulator's
    band over seeds 1..12 at the same K, widened by 10 % (a wrong shape or law lands far outside);
  - all: the gap CV as uniform as the simulator's, every agent apart (clusters = 12);
  - line: the swarm comes to lie on the line (shape error ~0, from step ~600 at worst) and keeps
    growing along it.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402
from harness import fnum, mean  # noqa: E402

AGENTS = 12
SEED = 1
SEEDS = 12  # the simulator's spread over seeds 1..SEEDS


class ShapesTest(harness.SwarmTestCase):

    def run_swarm(self, name, steps, rate):
        """Runs the scenario with processes for `steps` iterations; returns (summary, metric rows)."""
        config = harness.scenario(name)
        # agent_timeout_s=5: on an overloaded host a stalled agent is still counted (liveness is
        # not what this test is about).
        sets = ["--set", "agent.rate_hz=%g" % rate, "--set", "supervisor.target_rate_hz=%g" % rate,
                "--set", "supervisor.agent_timeout_s=5"]
        record = os.path.join(self.run_dir, "record")
        script = self.write("script.txt",
                            "wait agents %d timeout=60\nstart\nwait time %d timeout=%d\nstatus\nquit\n"
                            % (AGENTS, steps, 60 + 3 * steps / rate))
        sup = self.start_supervisor(config, script=script, record=record, json_mode=True, extra=sets,
                                    console=False)
        agents = self.start_agents(AGENTS, config, seed=SEED, extra=sets)
        status = sup.wait(timeout=120 + 3 * steps / rate)
        self.assertEqual(status, 0, "supervisor exit status")
        self.assert_all_alive(agents)
        summary = harness.last_json_line(sup.out())
        self.assertIsNotNone(summary, "no JSON summary")
        self.assertEqual(summary["shape"], name)
        self.assertEqual(summary["agents"], AGENTS)
        self.assertEqual(summary["epoch"], 1)
        self.assertGreaterEqual(summary["model_time"], steps)
        rows = [r for r in harness.read_csv(os.path.join(record, "metrics.csv")) if r["epoch"] == "1"]
        self.assertTrue(rows, "no recorded metrics of epoch 1")
        for r in rows[-5:]:
            self.assertEqual(int(r["agents_alive"]), AGENTS)
        return summary, rows

    @staticmethod
    def window(rows, key, time_key, t0, t1):
        return mean([fnum(r[key]) for r in rows if t0 <= float(r[time_key]) <= t1])

    def sim_window(self, name, steps, key, t0, seed):
        csv_path = os.path.join(self.run_dir, "sim_seed%d.csv" % seed)
        result = self.run_sim(harness.scenario(name), ["--seed", str(seed), "--steps", str(steps), "--csv", csv_path])
        return self.window(harness.read_csv(csv_path), key, "step", t0, steps), result

    def sim_band(self, name, steps, key, t0, widen):
        """The simulator's windowed mean of `key` over seeds 1..SEEDS, widened by `widen` (relative,
        at least 0.02)."""
        values = [self.sim_window(name, steps, key, t0, seed)[0] for seed in range(1, SEEDS + 1)]
        lo, hi = min(values), max(values)
        return lo - max(widen * lo, 0.02), hi + max(widen * hi, 0.02)

    def check_closed_shape(self, name, steps, window, widen, same_seed_rel=None, rate=50.0):
        summary, rows = self.run_swarm(name, steps, rate)
        t0 = steps - window
        proc_err = self.window(rows, "shape_error_mean", "model_time", t0, steps)
        proc_gap = self.window(rows, "gap_cv", "model_time", t0, steps)
        sim_err, _ = self.sim_window(name, steps, "shape_error_mean", t0, SEED)
        sim_gap, _ = self.sim_window(name, steps, "gap_cv", t0, SEED)
        lo, hi = self.sim_band(name, steps, "shape_error_mean", t0, widen)
        proc_ext = self.window(rows, "extent", "model_time", t0, steps)
        ext_lo, ext_hi = self.sim_band(name, steps, "extent", t0, 0.05)
        sys.stderr.write("%s: processes shape_error %.4f gap_cv %.4f over t=%d..%d; simulator seed %d %.4f / %.4f, "
                         "seeds 1..%d band [%.4f, %.4f]\n"
                         % (name, proc_err, proc_gap, t0, steps, SEED, sim_err, sim_gap, SEEDS, lo, hi))
        sys.stderr.write("%s: processes extent %.3f, simulator band [%.3f, %.3f]\n" % (name, proc_ext, ext_lo, ext_hi))
        if same_seed_rel is not None:
            self.assertLessEqual(abs(proc_err - sim_err), max(same_seed_rel * sim_err, 0.02),
                                 "%s: mean shape error over t=%d..%d: processes %.4f, simulator (seed %d) %.4f"
                                 % (name, t0, steps, proc_err, SEED, sim_err))
        self.assertTrue(lo <= proc_err <= hi, "%s: mean shape error over t=%d..%d: processes %.4f, simulator's "
                        "band over seeds [%.4f, %.4f]" % (name, t0, steps, proc_err, lo, hi))
        self.assertTrue(ext_lo <= proc_ext <= ext_hi, "%s: extent over t=%d..%d: processes %.3f, simulator's band "
                        "over seeds [%.3f, %.3f]" % (name, t0, steps, proc_ext, ext_lo, ext_hi))
        self.assertLessEqual(proc_gap, max(1.5 * sim_gap, 0.10),
                             "%s: gap CV: processes %.4f, simulator %.4f" % (name, proc_gap, sim_gap))
        self.assertEqual(summary["clusters"], AGENTS, "every agent apart from the others")

    def test_circle(self):
        # A true plateau (0.17 for 12 agents from step ~250): same seed, within 10 %.
        self.check_closed_shape("circle", steps=300, window=50, widen=0.10, same_seed_rel=0.10)

    def test_square(self):
        # The square's error keeps drifting up slowly (0.27 at 300, 0.36 at 500 for seed 1).
        self.check_closed_shape("square", steps=400, window=100, widen=0.10)

    def test_ellipse(self):
        # The law chatters around the ellipse: the error swings 0.35..0.52 from step to step.
        self.check_closed_shape("ellipse", steps=300, window=150, widen=0.05)

    def test_line(self):
        # The line of 12 first hovers ~0.5 off the line (step 300: 0.48 for seed 1), then spreads
        # along it and lies on it: by step 800 for all of seeds 1..20 in the simulator, by ~600 at
        # worst in the processes' runs. K = 1000 at 100 Hz leaves that margin.
        steps, rate = 1000, 100.0
        summary, rows = self.run_swarm("line", steps, rate)
        sim_err, sim = self.sim_window("line", steps, "shape_error_mean", steps, SEED)
        extents = [self.sim_window("line", steps, "extent", steps, seed)[0] for seed in range(1, SEEDS + 1)]
        off = [float(r["model_time"]) for r in rows if (fnum(r["shape_error_mean"]) or 0.0) > 0.02]
        sys.stderr.write("line: processes shape_error %.6f extent %.2f, last sample off the line at t=%s; "
                         "simulator seed %d %.6f extent %.2f, seeds 1..%d extents %.1f..%.1f\n"
                         % (summary["shape_error_mean"], summary["extent"], max(off) if off else None, SEED,
                            sim["shape_error_mean"], sim["extent"], SEEDS, min(extents), max(extents)))
        self.assertLess(sim["shape_error_mean"], 0.01)  # the simulator's fact this test relies on
        self.assertLess(summary["shape_error_mean"], 0.02, "the agents lie on the line")
        self.assertLess(summary["shape_error_max"], 0.05, "every agent lies on the line")
        late = [r for r in rows if float(r["model_time"]) >= 0.8 * steps]
        self.assertTrue(late, "no metrics recorded after t=%d" % (0.8 * steps))
        self.assertLessEqual(max(fnum(r["shape_error_mean"]) for r in late), 0.02, "the swarm stays on the line")
        # Growing: the extent keeps increasing along the run, as in the simulator.
        half = [fnum(r["extent"]) for r in rows if abs(float(r["model_time"]) - steps / 2) < 10]
        self.assertTrue(half, "no metrics near t=%d" % (steps / 2))
        self.assertGreater(summary["extent"], mean(half) * 1.5, "the line keeps growing")
        self.assertTrue(0.9 * min(extents) <= summary["extent"] <= 1.1 * max(extents),
                        "extent %.2f outside the simulator's %.1f..%.1f" % (summary["extent"], min(extents), max(extents)))
        self.assertEqual(summary["clusters"], AGENTS, "every agent apart from the others")


if __name__ == "__main__":
    harness.main()
