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
    band over seeds 1..40 at the same K, widened (a wrong shape or law lands far outside);
  - all closed shapes: the extent (the formation's size) in the simulator's band over seeds
    widened by 5 %, the gap CV as uniform as the simulator's, every agent apart (clusters = 12);
  - line: the swarm comes to lie on the line (shape error ~0; when depends on the run, as in the
    simulator) and then stays on it and keeps growing along it.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402
from harness import fnum, mean  # noqa: E402

AGENTS = 12
SEED = 1
SEEDS = 40  # the simulator's spread over seeds 1..SEEDS


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
        sup = self.start_supervisor(config, script=script, record=record, extra=sets,
                                    console=False)
        agents = self.start_agents(AGENTS, config, seed=SEED, extra=sets)
        status = sup.wait(timeout=120 + 3 * steps / rate)
        self.assertEqual(status, 0, "supervisor exit status")
        self.assert_all_alive(agents)
        summary = harness.summary(sup.out())
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

    def sim_windows(self, name, steps, t0, seed):
        """The simulator's run of this seed: (JSON result, {metric: mean over steps t0..steps})."""
        csv_path = os.path.join(self.run_dir, "sim_seed%d.csv" % seed)
        result = self.run_sim(harness.scenario(name), ["--seed", str(seed), "--steps", str(steps), "--csv", csv_path])
        rows = harness.read_csv(csv_path)
        return result, {k: self.window(rows, k, "step", t0, steps) for k in ("shape_error_mean", "gap_cv", "extent")}

    def sim_spread(self, name, steps, t0):
        """{metric: [windowed mean of seed 1, ..., of seed SEEDS]}."""
        runs = [self.sim_windows(name, steps, t0, seed)[1] for seed in range(1, SEEDS + 1)]
        return {k: [r[k] for r in runs] for k in runs[0]}

    @staticmethod
    def band(values, widen):
        """[min, max] of values widened by `widen` (relative, at least 0.02 absolute)."""
        lo, hi = min(values), max(values)
        return lo - max(widen * lo, 0.02), hi + max(widen * hi, 0.02)

    def check_closed_shape(self, name, steps, window, widen, same_seed_rel=None, rate=50.0):
        summary, rows = self.run_swarm(name, steps, rate)
        t0 = steps - window
        proc = {k: self.window(rows, k, "model_time", t0, steps) for k in ("shape_error_mean", "gap_cv", "extent")}
        spread = self.sim_spread(name, steps, t0)
        sim = {k: v[SEED - 1] for k, v in spread.items()}
        lo, hi = self.band(spread["shape_error_mean"], widen)
        ext_lo, ext_hi = self.band(spread["extent"], 0.05)
        sys.stderr.write("%s over t=%d..%d: processes shape_error %.4f gap_cv %.4f extent %.3f; simulator seed %d "
                         "%.4f / %.4f / %.3f; bands over seeds 1..%d: shape_error [%.4f, %.4f] extent [%.3f, %.3f]\n"
                         % (name, t0, steps, proc["shape_error_mean"], proc["gap_cv"], proc["extent"], SEED,
                            sim["shape_error_mean"], sim["gap_cv"], sim["extent"], SEEDS, lo, hi, ext_lo, ext_hi))
        if same_seed_rel is not None:
            self.assertLessEqual(abs(proc["shape_error_mean"] - sim["shape_error_mean"]),
                                 max(same_seed_rel * sim["shape_error_mean"], 0.02),
                                 "%s: mean shape error over t=%d..%d: processes %.4f, simulator (seed %d) %.4f"
                                 % (name, t0, steps, proc["shape_error_mean"], SEED, sim["shape_error_mean"]))
        self.assertTrue(lo <= proc["shape_error_mean"] <= hi,
                        "%s: mean shape error over t=%d..%d: processes %.4f, simulator's band over seeds [%.4f, %.4f]"
                        % (name, t0, steps, proc["shape_error_mean"], lo, hi))
        self.assertTrue(ext_lo <= proc["extent"] <= ext_hi,
                        "%s: extent over t=%d..%d: processes %.3f, simulator's band over seeds [%.3f, %.3f]"
                        % (name, t0, steps, proc["extent"], ext_lo, ext_hi))
        self.assertLessEqual(proc["gap_cv"], max(1.5 * max(spread["gap_cv"]), 0.10),
                             "%s: gap CV: processes %.4f, simulator up to %.4f" % (name, proc["gap_cv"], max(spread["gap_cv"])))
        self.assertEqual(summary["clusters"], AGENTS, "every agent apart from the others")

    def test_circle(self):
        # A true plateau (0.17 for 12 agents from step ~250): same seed, within 10 %.
        self.check_closed_shape("circle", steps=300, window=50, widen=0.10, same_seed_rel=0.10)

    def test_square(self):
        # The square's error keeps drifting up slowly (0.27 at 300, 0.36 at 500 for seed 1).
        self.check_closed_shape("square", steps=400, window=100, widen=0.10)

    def test_ellipse(self):
        # The law chatters around the ellipse: the error swings 0.35..0.52 from step to step, and its
        # mean over t=150..300 spreads over 0.38..0.55 across seeds in the simulator and lower in the
        # processes (0.32..0.48 measured): the error band is wide (20 %); the extent (5 %) is what
        # tells a wrongly sized ellipse (15 % too large: extent 9.05 against at most 8.44).
        self.check_closed_shape("ellipse", steps=300, window=150, widen=0.20)

    def test_line(self):
        # The line of 12 first hovers ~0.5 off the line in a zigzag, spreading along it; then it
        # lies on it (shape error ~0) and keeps growing. When it gets there depends on the run:
        # the simulator gets there by step ~800 for 38 of seeds 1..40 and by ~2000 for the rest
        # (seed 34: one agent runs ahead, the others hover until step ~1500); the processes
        # likewise (measured: mostly 300..600, sometimes beyond 1000). So the test waits for it
        # (up to 3000 iterations), then watches 200 more.
        rate, limit, more = 100.0, 3000.0, 200.0
        config = harness.scenario("line")
        sets = ["--set", "agent.rate_hz=%g" % rate, "--set", "supervisor.target_rate_hz=%g" % rate,
                "--set", "supervisor.agent_timeout_s=5"]
        sup = self.start_supervisor(config, record=os.path.join(self.run_dir, "record"), extra=sets)
        agents = self.start_agents(AGENTS, config, seed=SEED, extra=sets)
        self.assertTrue(sup.wait_agents(AGENTS, 60))
        self.assertEqual(sup.command("start"), 1)

        def on_line():
            m = sup.metrics()
            self.assertLess(m["model_time"], limit, "the swarm reaches the line within %d iterations" % limit)
            return m if m["shape_error_mean"] is not None and m["shape_error_mean"] < 0.02 else None

        reached = harness.poll(on_line, 3 * limit / rate + 30, "the swarm to lie on the line", 0.2)
        t_on = reached["model_time"]
        self.assertTrue(sup.wait_until("time", "wait time %g timeout=60" % (t_on + more), 60),
                        "%g more iterations on the line" % more)
        later = sup.metrics()
        sup.send("quit")
        self.assertEqual(sup.wait(30), 0)
        sim = self.run_sim(config, ["--seed", str(SEED), "--steps", "1000"])
        sys.stderr.write("line: processes on the line at t=%.0f (extent %.2f), at t=%.0f shape error %.6f extent %.2f; "
                         "simulator seed %d at step 1000: shape error %.6f extent %.2f\n"
                         % (t_on, reached["extent"], later["model_time"], later["shape_error_mean"], later["extent"],
                            SEED, sim["shape_error_mean"], sim["extent"]))
        self.assertLess(sim["shape_error_mean"], 0.01)  # the simulator's fact for this seed
        # `wait time` counts the agents' own iterations; the metrics are stamped with the supervisor's
        # wall-clock model time, which can trail the agents' count by a fraction of an iteration.
        self.assertGreaterEqual(later["model_time"], t_on + more - 1)
        self.assertEqual(later["agents"], AGENTS)
        self.assertLess(later["shape_error_mean"], 0.02, "the agents stay on the line")
        self.assertLess(later["shape_error_max"], 0.05, "every agent lies on the line")
        rows = harness.read_csv(os.path.join(self.run_dir, "record", "metrics.csv"))
        after = [fnum(r["shape_error_mean"]) for r in rows if float(r["model_time"]) >= t_on + 20 and r["epoch"] == "1"]
        self.assertTrue(after, "recorded metrics after reaching the line")
        self.assertLess(max(after), 0.05, "the swarm stays on the line")
        # Growing along the line (the simulator: ~0.19 per iteration once on the line).
        self.assertGreater(later["extent"] - reached["extent"], 0.05 * more,
                           "the line keeps growing: extent %.2f -> %.2f" % (reached["extent"], later["extent"]))
        self.assertEqual(later["clusters"], AGENTS, "every agent apart from the others")
        self.assert_all_alive(agents)


if __name__ == "__main__":
    harness.main()
