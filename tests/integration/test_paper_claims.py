#!/usr/bin/env python3
"""The paper's claims on real agent processes, through scripts/launch_swarm.sh (one process per agent
and a supervisor on loopback; fixed seeds; each test's runs one after another on the test's domain, but
the free-running test's in pairs side by side on two).

- Repulsion: on the ellipse and the square (12 agents, 200 iterations) r = 0.1 lowers the gap CV at least
  tenfold against r = 0 (without repulsion the agents pile up in clumps). Both are medians over the last
  quarter of the run: with r = 0.1 the agents keep sliding along the ellipse, and its gap CV wanders
  between about 0.03 and 0.2 over tens of iterations, in the simulator as on processes, so a median over
  10 iterations caught one excursion (0.167 against 1.638 without repulsion).
- Tracking without feed-forward (the published law): the centre outruns the swarm, which trails as a
  blob on both paths. This documents the published behaviour.
- Tracking with feed-forward: after the transient, the formation around the moving centre matches the
  same formation around a fixed centre at C(0) from the same start (the static problem in the centre's
  frame), on both paths.

  The issue's bound, centroid and ring errors within 0.1 of the fixed-centre run, is a property of the
  law, checked in the simulator (on the line path the two runs are identical) and on processes in
  lockstep (agent.sync=lockstep: every process uses the same neighbour snapshot per iteration). Free-
  running processes (the default) tick at their own phases: each agent's centre is the supervisor's
  target moved on over the time since it was received, and each neighbour's state is moved with the
  centre by its age (AgentLogic::step), so the tracked problem is the static one in the centre's frame.
  A tracked run cannot be compared with a fixed-centre run of the same phasing (each run draws its own),
  so the free-running test holds each tracked run's centroid error (median after the transient) to at
  most 0.1 above the fixed-centre problem's, over 10 tracked phasings on both paths and both laws. Without
  feed-forward the centroid error is about 4.

  On the line path the swarm starts around C(0) (the seeded start shifted by C(0) = (-10, -10)): from
  the paper's start, 14 units away, agents that fall behind on the approach escape for ever under the
  published law, with a moving or a fixed centre alike, and which ones do depends on the tick phases.

Run directly: test_paper_claims.py --bin build/bin --source . --domain 140 [unittest args]
"""
import os
import statistics
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402

C0 = {"line": (-10.0, -10.0), "circle": (6.0, 0.0)}
RATE_HZ = 50.0
# The free-running test's tracked runs go beside its fixed-centre runs on this domain: paper_trailing's,
# a swarm test, so never in use while the free-running test (ALONE) runs (tests/integration/CMakeLists.txt).
SECOND_DOMAIN = 141
# For checking that the tests can fail: extra overrides for every launch, after the test's own, e.g.
# SHAPEFORM_IT_LAUNCH_SETS="tracking.feedforward=false" or "dynamics.r=0".
LAUNCH_MUTATION = os.environ.get("SHAPEFORM_IT_LAUNCH_SETS", "").split()


def launcher():
    return os.path.join(harness.CONFIG["source"], "scripts", "launch_swarm.sh")


def build_dir():
    return os.path.dirname(harness.CONFIG["bin"])


class PaperClaimsTest(harness.SwarmTestCase):

    def start_csv(self, scen, offset=(0.0, 0.0), seed=1):
        """The simulator's seeded start for the scenario, shifted by offset, as a CSV file."""
        pts = self.run_sim(harness.scenario(scen), ["--seed", str(seed), "--steps", "0"])["final_positions"]
        return self.write(f"start_{scen}_{offset[0]:g}_{offset[1]:g}.csv",
                          "".join(f"{x + offset[0]:.17g},{y + offset[1]:.17g}\n" for x, y in pts))

    def launch(self, tag, scen, n, steps, init, sets=()):
        """One swarm run of `steps` iterations; returns (summary, metric rows after the command)."""
        return self.finish(self.start_launch(tag, scen, n, steps, init, sets))

    def start_launch(self, tag, scen, n, steps, init, sets=(), domain=None):
        """Starts one swarm run of `steps` iterations (on `domain`, default the test's); finish() waits."""
        record = os.path.join(self.run_dir, "rec_" + tag)
        argv = ["bash", launcher(), "--build", build_dir(), "--runs", os.path.join(self.run_dir, "runs"),
                "--domain", str(self.domain if domain is None else domain), "-n", str(n), "--scenario", scen,
                "--steps", str(steps),
                "--init", init, "--record", record, "--json", "--set", f"supervisor.metrics_rate_hz={RATE_HZ:g}",
                # No agent leaves in these runs: a neighbour unheard for a moment on a busy machine is
                # kept (0.5 s) rather than dropped after 3 periods, so the law stays all-to-all.
                "--set", "agent.neighbour_timeout_periods=25"]
        for s in list(sets) + LAUNCH_MUTATION:
            argv += ["--set", s]
        return tag, self.start("launch_" + tag, argv), record, n, steps

    def finish(self, launch):
        """Waits for a run of start_launch; returns (summary, metric rows after the command)."""
        tag, p, record, n, steps = launch
        status = p.wait(steps / RATE_HZ * 4 + 120)
        summary = harness.summary(p.out())
        self.assertIsNotNone(summary, f"{tag}: no summary (launcher exit status {status})")
        self.assertGreaterEqual(summary["steps"], steps, f"{tag}: iterations done")
        # After its iterations the launcher exits with the verdict: 0 converged, 3 not.
        self.assertEqual(status, 0 if summary["converged"] else 3, f"{tag}: launcher exit status")
        self.assertEqual(summary["agents_seen"], n, f"{tag}: agents seen by the supervisor")
        rows = [r for r in harness.read_csv(os.path.join(record, "metrics.csv"), numeric=True)
                if r["epoch"] and r["epoch"] >= 1]
        return summary, rows

    def window(self, rows, key, t0, t1):
        """Median of a metric over the supervisor's samples with model time in [t0, t1]."""
        vals = [r[key] for r in rows if t0 <= r["model_time"] <= t1 and r[key] is not None]
        self.assertTrue(vals, f"no {key} samples in model time [{t0}, {t1}]")
        return statistics.median(vals)

    def test_repulsion_lowers_gap_cv_tenfold(self):
        for shape in ("ellipse", "square"):
            with self.subTest(shape=shape):
                start = self.start_csv(shape)
                s0, rows0 = self.launch(f"{shape}_r0", f"{shape}_no_repulsion", 12, 200, start)
                s1, rows1 = self.launch(f"{shape}_r01", shape, 12, 200, start)
                g1 = self.window(rows1, "gap_cv", 150, 200)
                self.assertEqual(s1["clusters"], 12, f"{shape} r=0.1: agents merged")
                self.assertLess(g1, 0.2, f"{shape} r=0.1: not spread along the shape")
                vals0 = [r["gap_cv"] for r in rows0 if 150 <= r["model_time"] <= 200]
                if all(v is None for v in vals0):
                    # Every agent on one point: gap CV undefined, the extreme of clumping.
                    self.assertEqual(s0["clusters"], 1, f"{shape} r=0: gap CV undefined but not one point")
                else:
                    g0 = self.window(rows0, "gap_cv", 150, 200)
                    self.assertGreaterEqual(g0, 1.0, f"{shape} r=0: gap CV {g0:.3f}, expected clumps")
                    self.assertGreaterEqual(g0, 10 * g1, f"{shape}: gap CV r=0 {g0:.3f} vs r=0.1 {g1:.3f}")

    def test_without_feedforward_the_swarm_trails(self):
        for path in ("line", "circle"):
            with self.subTest(path=path):
                _, rows = self.launch(f"{path}_paper", f"track_{path}", 10, 200, self.start_csv(f"track_{path}"))
                c = self.window(rows, "centroid_error", 180, 200)
                ring = self.window(rows, "ring_error", 180, 200)
                # The centre moves 0.14 (line) or 0.19 (circle) per iteration, faster than the swarm's
                # centroid can follow (~0.15): the swarm trails as a blob instead of surrounding it.
                self.assertGreater(c, 2.5, f"{path}: centroid error {c:.3f}; the published law trails")
                self.assertGreater(ring, 1.2, f"{path}: ring error {ring:.3f}")

    def sim_series(self, tag, cfg, args):
        """shapeform_sim's per-step metrics, as rows with model_time like the supervisor's."""
        path = os.path.join(self.run_dir, f"sim_{tag}.csv")
        self.run_sim(cfg, list(args) + ["--csv", path])
        return harness.read_csv(path, numeric=True)

    def test_feedforward_in_the_simulator_is_the_static_problem(self):
        for path in ("line", "circle"):
            with self.subTest(path=path):
                start = self.start_csv(f"track_{path}", C0[path] if path == "line" else (0.0, 0.0))
                cfg = harness.scenario(f"track_{path}")
                base = ["--init", start, "--steps", "300"]
                ff = self.sim_series(f"{path}_ff", cfg, base + ["--set", "tracking.feedforward=true"])
                fx = self.sim_series(f"{path}_fixed", cfg, base + [
                    "--set", "tracking.path=fixed", "--set", f"tracking.point=[{C0[path][0]:g},{C0[path][1]:g}]"])
                pa = self.sim_series(f"{path}_paper", cfg, base)
                for t0, t1 in ((160, 200), (200, 300)):
                    for key in ("centroid_error", "ring_error"):
                        a, b = self.window(ff, key, t0, t1), self.window(fx, key, t0, t1)
                        self.assertLessEqual(abs(a - b), 0.1, f"{path} {key} over [{t0}, {t1}]: {a:.3f} vs {b:.3f}")
                    self.assertLess(self.window(ff, "centroid_error", t0, t1), 0.5, path)
                    self.assertGreater(self.window(pa, "centroid_error", t0, t1), 2.0, path)  # without: trails

    def ff_against_fixed(self, tag, path, steps, sets):
        """One run with feed-forward and one around the fixed centre C(0), from the same start; checks
        that the first surrounds the moving centre like the second, and returns the differences of the
        medians over model time [200, steps] of their centroid and ring errors."""
        start = self.start_csv(f"track_{path}", C0[path] if path == "line" else (0.0, 0.0))
        _, ff = self.launch(f"{tag}_{path}_ff", f"track_{path}_ff", 10, steps, start, sets)
        _, fx = self.launch(f"{tag}_{path}_fixed", f"track_{path}", 10, steps, start,
                            sets + ["tracking.path=fixed", f"tracking.point=[{C0[path][0]:g},{C0[path][1]:g}]"])
        c_ff, c_fx = self.window(ff, "centroid_error", 200, steps), self.window(fx, "centroid_error", 200, steps)
        r_ff, r_fx = self.window(ff, "ring_error", 200, steps), self.window(fx, "ring_error", 200, steps)
        msg = (f"{tag} {path}: feed-forward centroid {c_ff:.3f} ring {r_ff:.3f}; fixed centre centroid {c_fx:.3f} "
               f"ring {r_fx:.3f}")
        sys.stderr.write(msg + "\n")
        self.assertLess(c_ff, 0.5, msg)  # surrounds the moving centre
        self.assertLess(r_ff, 0.7, msg)  # on a ring of radius about r0 around it
        return abs(c_ff - c_fx), abs(r_ff - r_fx), msg

    def test_feedforward_processes_match_a_fixed_centre(self):
        # Lockstep: every process takes the same neighbour snapshot per iteration (the simulator's
        # numbers), so the bound holds as it does in the simulator.
        for path in ("line", "circle"):
            with self.subTest(path=path):
                dc, dr, msg = self.ff_against_fixed("lockstep", path, 300, ["agent.sync=lockstep"])
                self.assertLessEqual(dr, 0.1, msg)
                self.assertLessEqual(dc, 0.1, msg)

    def test_feedforward_free_running_tracks_like_a_fixed_centre(self):
        # The default mode: free-running processes, each ticking at its own phase, so every run is a
        # fresh draw of tick phasings and no fixed-centre run shares a tracked run's. What a user tracking
        # a moving target expects is the swarm around it as around a still one: each tracked run's
        # centroid error (median over t = 200..300: the paper's law chatters, one instant is noise) at
        # most 0.1 above a fixed-centre run's, that is above the largest of the same figure over the
        # fixed-centre runs. The paper's law comes to rest off its centre by a phasing's draw, and the
        # draw depends on the host's load: on an idle host 10 fixed-centre runs measured 0.19 to 0.22,
        # beside the rest of the suite 0.073, 0.080 and 0.137, while tracked runs stayed at 0.11 to 0.22
        # (scripts/paper/free_running.py; docs/RESULTS.md). That spread is wider than the bound, so the
        # reference is the problem's range, not one draw or a median of three; a fixed-centre run and a
        # tracked run go side by side, on two domains, so that both sample the same conditions, and the
        # test runs with no other swarm beside it (ALONE). The arc law's fixed-centre figure is exact
        # (0). Closer to the centre is no failure. 10 tracked phasings in all, on both paths and both laws.
        cases = {("paper", "line"): (3, 3), ("paper", "circle"): (3, 3), ("arc", "line"): (2, 1),
                 ("arc", "circle"): (2, 1)}  # (tracked runs, fixed-centre runs)
        for (law, path), (runs, fixed_runs) in cases.items():
            start = self.start_csv(f"track_{path}", C0[path] if path == "line" else (0.0, 0.0))
            sets = [f"dynamics.law={law}"]
            fixed, tracked = [], []
            for k in range(max(runs, fixed_runs)):
                fx = ff = None
                if k < fixed_runs:
                    fx = self.start_launch(f"free_{law}_{path}_fixed{k}", f"track_{path}", 10, 300, start,
                                           sets + ["tracking.path=fixed",
                                                   f"tracking.point=[{C0[path][0]:g},{C0[path][1]:g}]"])
                if k < runs:
                    ff = self.start_launch(f"free_{law}_{path}_ff{k}", f"track_{path}_ff", 10, 300, start, sets,
                                           domain=SECOND_DOMAIN)
                if fx:
                    fixed.append(self.window(self.finish(fx)[1], "centroid_error", 200, 300))
                if ff:
                    rows = self.finish(ff)[1]
                    tracked.append((self.window(rows, "centroid_error", 200, 300),
                                    self.window(rows, "ring_error", 200, 300)))
            for j, (c_ff, r_ff) in enumerate(tracked):
                with self.subTest(law=law, path=path, run=j):
                    msg = (f"{law} {path} run {j}: centroid error tracked {c_ff:.3f}, fixed centre at most "
                           f"{max(fixed):.3f} (runs: {', '.join('%.3f' % c for c in fixed)}); ring error "
                           f"tracked {r_ff:.3f}")
                    sys.stderr.write(msg + "\n")
                    self.assertLessEqual(c_ff - max(fixed), 0.1, msg)
                    self.assertLess(r_ff, 0.7, msg)  # on a ring of radius about r0 around the centre


if __name__ == "__main__":
    harness.main()
