#!/usr/bin/env python3
"""shapeform_sim as a user runs it: one JSON object, determinism, --init/--csv/--positions, bad input."""
import argparse
import json
import os
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts", "lib"))
import shapeform_procs as procs  # noqa: E402

ARGS = None


def sim(*args, timeout=120):
    return procs.run([os.path.join(ARGS.bin, "shapeform_sim"), *args], timeout=timeout, check=False)


def read(path):
    with open(path) as f:
        return f.read().splitlines()


def scenario(name):
    return os.path.join(ARGS.source, "config", "scenarios", name + ".yaml")


class SimOutput(unittest.TestCase):
    def test_one_json_object_with_every_field(self):
        p = sim("--config", scenario("circle"), "--steps", "50")
        self.assertEqual(p.returncode, 0, p.stderr)
        lines = [l for l in p.stdout.splitlines() if l.strip()]
        self.assertEqual(len(lines), 1, p.stdout)
        j = json.loads(lines[0])
        for key in ["shape", "agents", "steps", "dt", "seed", "shape_error_mean", "shape_error_max", "gap_cv",
                    "nn_cv", "min_separation", "clusters", "extent", "settle_step", "final_positions"]:
            self.assertIn(key, j)
        self.assertEqual(j["shape"], "circle")
        self.assertEqual(j["agents"], 12)
        self.assertEqual(j["steps"], 50)
        self.assertEqual(len(j["final_positions"]), 12)
        self.assertNotIn("centroid_error", j)

    def test_tracking_reports_centroid_and_ring(self):
        p = sim("--config", scenario("track_line"))
        self.assertEqual(p.returncode, 0, p.stderr)
        j = json.loads(p.stdout)
        self.assertEqual(j["agents"], 10)
        self.assertGreater(j["centroid_error"], 2.0)  # the published law trails the centre
        self.assertIn("ring_error", j)

    def test_same_seed_same_run(self):
        a = sim("--config", scenario("square"), "--seed", "5", "--steps", "80").stdout
        b = sim("--config", scenario("square"), "--seed", "5", "--steps", "80").stdout
        c = sim("--config", scenario("square"), "--seed", "6", "--steps", "80").stdout
        self.assertEqual(a, b)
        self.assertNotEqual(json.loads(a)["final_positions"], json.loads(c)["final_positions"])

    def test_flags_override_the_file(self):
        j = json.loads(sim("--config", scenario("circle"), "--agents", "5", "--steps", "3", "--dt", "0.5",
                           "--integrator", "rk4", "--set", "shape.r0=2").stdout)
        self.assertEqual((j["agents"], j["steps"], j["dt"], j["integrator"]), (5, 3, 0.5, "rk4"))

    def test_init_csv_and_outputs(self):
        with tempfile.TemporaryDirectory() as d:
            init = os.path.join(d, "start.csv")
            with open(init, "w") as f:
                f.write("x1,x2\n1.5,-2\n0,0\n3,3\n")
            j = json.loads(sim("--config", scenario("circle"), "--init", init, "--steps", "0").stdout)
            self.assertEqual(j["agents"], 3)
            self.assertEqual(j["final_positions"], [[1.5, -2.0], [0.0, 0.0], [3.0, 3.0]])
            csv, pos = os.path.join(d, "m.csv"), os.path.join(d, "p.csv")
            p = sim("--config", scenario("circle"), "--init", init, "--steps", "10", "--csv", csv, "--positions", pos)
            self.assertEqual(p.returncode, 0, p.stderr)
            rows = read(csv)
            self.assertTrue(rows[0].startswith("step,model_time,shape_error_mean"))
            self.assertEqual(len(rows), 1 + 11)
            prow = read(pos)
            self.assertEqual(prow[0], "step,agent,x1,x2")
            self.assertEqual(len(prow), 1 + 11 * 3)
            self.assertEqual(prow[1].split(",")[:2], ["0", "0"])

    def test_vehicle_model_and_headings(self):
        j = json.loads(sim("--config", scenario("circle"), "--steps", "5").stdout)
        self.assertEqual(j["vehicle"], "integrator")
        self.assertNotIn("final_headings", j)
        j = json.loads(sim("--config", scenario("arc_circle"), "--steps", "5", "--set", "vehicle.model=unicycle",
                           "--set", "vehicle.heading_spread_deg=180").stdout)
        self.assertEqual((j["vehicle"], j["kernel"]), ("unicycle", "agent"))
        self.assertEqual(len(j["final_headings"]), 12)
        self.assertTrue(all(-3.15 < h < 3.15 for h in j["final_headings"]))
        # From 64 agents auto batches the integrator model only.
        j = json.loads(sim("--config", scenario("circle"), "--agents", "64", "--steps", "1").stdout)
        self.assertEqual(j["kernel"], "batch")
        j = json.loads(sim("--config", scenario("circle"), "--agents", "64", "--steps", "1",
                           "--set", "vehicle.model=double_integrator").stdout)
        self.assertEqual(j["kernel"], "agent")

    def test_safety_summary(self):
        # Off (the default): no safety object unless asked for with --separation.
        j = json.loads(sim("--config", scenario("arc_circle"), "--steps", "20").stdout)
        self.assertNotIn("safety", j)
        j = json.loads(sim("--config", scenario("arc_circle"), "--steps", "20", "--separation").stdout)
        self.assertFalse(j["safety"]["filter"])
        self.assertEqual(j["safety"]["interventions"], 0)
        # On: the smallest separation over every step, when, and the filter's counts; auto never batches it.
        j = json.loads(sim("--config", scenario("circle"), "--agents", "64", "--steps", "100", "--set",
                           "safety.min_separation=0.3", "--set", "safety.keep_out=[{circle: [0, 0, 1]}]").stdout)
        s = j["safety"]
        self.assertEqual(j["kernel"], "agent")
        self.assertTrue(s["filter"])
        # The uniform start has pairs closer than 0.3: they step apart (counted), never closer than at the start.
        self.assertLess(s["run_min_separation"], 0.3)
        self.assertEqual((s["run_min_step"], s["run_min_time"]), (0, 0))
        self.assertGreater(s["broken"], 0)
        self.assertEqual(s["keep_out_zones"], 1)
        for key in ("run_min_step", "run_min_time", "zone_entries", "zone_depth", "interventions", "sidesteps",
                    "broken", "held", "vehicle_outside", "blocked_agents", "blocked_by"):
            self.assertIn(key, s)
        self.assertIn(j["verdict"], ("converged", "blocked", "holding", "unsteady", "uneven", "off the shape"))


class BadInput(unittest.TestCase):
    def assert_rejected(self, args, *needles):
        p = sim(*args)
        self.assertEqual(p.returncode, 2, f"{args}: rc={p.returncode} stderr={p.stderr}")
        self.assertEqual(p.stdout, "")
        err = p.stderr.strip()
        self.assertTrue(err, args)
        for n in needles:
            self.assertIn(n, err, args)
        for bad in ("terminate called", "Traceback", "Aborted", "what()"):
            self.assertNotIn(bad, err)

    def test_bad_flags(self):
        self.assert_rejected(["--agents", "many"], "--agents")
        self.assert_rejected(["--agents", "0"], "swarm.agents")
        self.assert_rejected(["--integrator", "midpoint"], "integration.integrator")
        self.assert_rejected(["--dt", "-1"], "integration.dt")
        self.assert_rejected(["--dt", "nan"], "integration.dt")
        self.assert_rejected(["--steps", "-3"], "sim.steps")
        self.assert_rejected(["--steps", "99999999999999999999"], "got 99999999999999999999")
        # Seeds are 64-bit: one beyond that, or negative, is refused, not clamped or wrapped.
        self.assert_rejected(["--seed", "18446744073709551616"], "swarm.seed")
        self.assert_rejected(["--seed", "-1"], "swarm.seed")
        self.assert_rejected(["--bogus"], "--bogus")
        self.assert_rejected(["--set", "shape.radius=3"], "shape.radius")
        self.assert_rejected(["--set", "nonsense"], "nonsense")
        self.assert_rejected(["--config", "/nonexistent/x.yaml"], "/nonexistent/x.yaml")
        self.assert_rejected(["--init", "/nonexistent/start.csv"], "/nonexistent/start.csv")
        self.assert_rejected(["--kernel", "batch", "--set", "vehicle.model=unicycle"], "--kernel batch",
                             "integrator model only", "vehicle.model is unicycle")
        self.assert_rejected(["--set", "vehicle.model=car"], "vehicle.model", "car", "unicycle")
        self.assert_rejected(["--kernel", "batch", "--set", "safety.min_separation=0.3"], "--kernel batch",
                             "safety.min_separation is 0.3", "--kernel agent")
        self.assert_rejected(["--set", "safety.keep_out=[{circle: [0, 0, -1]}]"], "safety.keep_out[0].circle[2]",
                             "must be > 0", "got -1")

    def test_bad_init_and_yaml_files(self):
        with tempfile.TemporaryDirectory() as d:
            def write(name, text):
                path = os.path.join(d, name)
                with open(path, "w") as f:
                    f.write(text)
                return path
            self.assert_rejected(["--init", write("a.csv", "1,2\n3,x\n")], "line 2")
            self.assert_rejected(["--init", write("b.csv", "1,2\nnan,1\n")], "line 2", "non-finite")
            self.assert_rejected(["--init", write("c.csv", "1,2\n"), "--agents", "4"], "--agents")
            self.assert_rejected(["--config", write("u.yaml", "schema_version: 1\nshape:\n  radius: 3\n")],
                                 "shape.radius", "line 3")
            self.assert_rejected(["--config", write("t.yaml", "schema_version: 1\nswarm:\n  agents: many\n")],
                                 "swarm.agents", "line 3")
            self.assert_rejected(["--config", write("r.yaml", "schema_version: 1\ndynamics:\n  sigma: -1\n")],
                                 "dynamics.sigma", "line 3")
            self.assert_rejected(["--config", write("n.yaml", "schema_version: 1\ndynamics:\n  k1: .nan\n")],
                                 "dynamics.k1", "line 3")
            self.assert_rejected(["--config", write("s.yaml", "schema_version: 1\nshape: [\n")], "s.yaml")


if __name__ == "__main__":
    parser = argparse.ArgumentParser()
    parser.add_argument("--bin", required=True)
    parser.add_argument("--source", required=True)
    ARGS, rest = parser.parse_known_args()
    unittest.main(argv=[sys.argv[0], "-v", *rest])
