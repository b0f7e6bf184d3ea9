#!/usr/bin/env python3
"""scripts/launch_swarm.sh: every scenario runs through it, starts are reproducible, Ctrl-C and bad
arguments are handled, and it leaves no process and no shared-memory file behind.

The launcher runs in its own process group; its children (agents, supervisor, progress tails) stay
in that group, so "nothing left" is checked as "no live process in the launcher's group and no
shapeform process on the test's domain".
"""
import glob
import json
import os
import signal
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402


# test_every_scenario_runs runs two launches at a time: the second on this domain, kept for it in
# tests/integration/CMakeLists.txt.
SECOND_DOMAIN = 145


def launcher():
    return os.path.join(harness.CONFIG["source"], "scripts", "launch_swarm.sh")


def build_dir():
    return os.path.dirname(harness.CONFIG["bin"])


class LauncherTest(harness.SwarmTestCase):

    def launch(self, args, name="launcher", domain=None):
        """Starts the launcher with its own --runs folder (RUN_DIR/runs_NAME), on the test's domain unless
        another is given."""
        argv = ["bash", launcher(), "--build", build_dir(), "--runs", os.path.join(self.run_dir, "runs_" + name),
                "--domain", str(self.domain if domain is None else domain)] + list(args)
        return self.start(name, argv)

    def run_folder(self, proc):
        """The launch's run folder: its "run" event with --json, else the one folder in its --runs."""
        run = harness.events(proc.out(), "run")
        if run:
            return run[0]["dir"]
        runs = os.path.join(self.run_dir, "runs_" + proc.name)
        folders = glob.glob(os.path.join(runs, "*", ""))
        self.assertEqual(len(folders), 1, "one run folder in %s" % runs)
        return folders[0].rstrip("/")

    def agent_epochs(self, run, i):
        """Epochs of the commands agent i adopted (its JSON event lines in the run folder)."""
        return [e["epoch"] for e in harness.events(harness.read_text(os.path.join(run, "agent_%d.out" % i)),
                                                   "command")]

    def assert_nothing_left(self, proc, domain=None):
        self.assertEqual(harness.processes_in_group(proc.pid), [], "processes left by the launcher")
        self.assertEqual(harness.shapeform_processes_on_domain(self.domain if domain is None else domain), [],
                         "shapeform processes left")
        self.assertEqual(sorted(harness.shm_files() - self.shm_before), [], "new Fast DDS shm files")

    def test_every_scenario_runs(self):
        scenarios = sorted(glob.glob(os.path.join(harness.CONFIG["source"], "config", "scenarios", "*.yaml")))
        self.assertGreaterEqual(len(scenarios), 8)
        # Two launches at a time, one on the test's domain and one on SECOND_DOMAIN: two small swarms
        # side by side, each run checked as if alone.
        for pair in (scenarios[k:k + 2] for k in range(0, len(scenarios), 2)):
            runs = []
            for path, domain in zip(pair, (self.domain, SECOND_DOMAIN)):
                name = os.path.basename(path)[:-5]
                expected = self.run_sim(path, ["--steps", "0"])  # the scenario's shape and size
                # agent_timeout_s=5: an agent stalled by an overloaded host is still counted alive.
                p = self.launch(["--scenario", name, "--steps", "60", "--rate", "50", "--json",
                                 "--set", "supervisor.agent_timeout_s=5"], "launcher_" + name, domain)
                runs.append((name, expected, p, domain))
            for name, expected, p, domain in runs:
                with self.subTest(scenario=name):
                    self.check_scenario_run(name, expected, p, domain)

    def check_scenario_run(self, name, expected, p, domain):
        status = p.wait(120)
        lines = p.out().splitlines()
        self.assertTrue(lines, "%s: no output (exit status %s)" % (name, status))
        # After its 60 iterations a run exits with its verdict: 0 converged, 3 not (most, this early).
        verdict = json.loads(lines[-1]).get("converged")
        self.assertEqual(status, 0 if verdict else 3, "%s: launcher exit status, converged=%s" % (name, verdict))
        self.assertEqual([e.get("event") for e in map(json.loads, lines)], ["run", "summary"],
                         "%s: stdout is the run line and the JSON summary" % name)
        summary = json.loads(lines[-1])
        self.assertEqual(summary["name"], expected["name"])
        self.assertEqual(summary["shape"], expected["shape"], name)
        self.assertEqual(summary["tracking"], expected["tracking"], name)
        self.assertEqual(summary["agents"], expected["agents"], name)
        self.assertEqual(summary["agents_seen"], expected["agents"], name)
        self.assertEqual(summary["epoch"], 1)
        self.assertEqual(summary["exit_status"], status)
        self.assertGreaterEqual(summary["steps"], 60)
        run = self.run_folder(p)
        self.assertEqual(json.loads(lines[0]), {"event": "run", "dir": run, "domain": domain,
                                                "agents": expected["agents"]})
        self.assertTrue(os.path.basename(run).endswith("-%s-n%d" % (name, expected["agents"])), run)
        for i in range(expected["agents"]):
            self.assertEqual(self.agent_epochs(run, i), [1], "%s: agent %d follows epoch 1" % (name, i))
        self.assertIn("wait time 60", harness.read_text(os.path.join(run, "script.txt")))
        rows = harness.read_csv(os.path.join(run, "record", "metrics.csv"))
        self.assertTrue(any(r["epoch"] == "1" for r in rows), "%s: recorded metrics" % name)
        self.assertEqual(summary["recording"], os.path.join(run, "record"))
        self.assertIn("recording: " + os.path.join(run, "record"), p.log())
        self.assert_nothing_left(p, domain)

    def test_readme_main_command(self):
        # The README's main job, as written there (12 agent processes, the paper's circle, until
        # converged), with --json for the summary. The acceptance criterion of the swarm against the
        # simulator: converged, shape error mean within 0.02 of the simulator's plateau for the same
        # scenario and starts, gap CV <= 0.10.
        sim = self.run_sim(harness.scenario("circle"), ["--steps", "500"])
        p = self.launch(["-n", "12", "--scenario", "circle", "--json"])
        self.assertEqual(p.wait(150), 0, "launcher exit status (0: converged)")
        summary = harness.summary(p.out())
        self.assertTrue(summary["converged"])
        self.assertEqual(summary["agents"], 12)
        self.assertLessEqual(abs(summary["shape_error_mean"] - sim["shape_error_mean"]), 0.02,
                             "processes %.4f, simulator %.4f" % (summary["shape_error_mean"], sim["shape_error_mean"]))
        self.assertLessEqual(summary["gap_cv"], 0.10)
        waits = harness.events(harness.read_text(os.path.join(self.run_folder(p), "supervisor.out")), "wait")
        self.assertEqual([(w["wait"], w["ok"]) for w in waits if w["wait"] != "agents"], [("converged", True)])
        self.assert_nothing_left(p)

    def start_event(self, run, name):
        """The "start" event a process of the run printed (its start positions and effective config)."""
        found = harness.events(harness.read_text(os.path.join(run, name + ".out")), "start")
        self.assertEqual(len(found), 1, "%s prints one start event" % name)
        return found[0]

    def agent_starts(self, run, n):
        return [tuple(self.start_event(run, "agent_%d" % i)["starts"][0]) for i in range(n)]

    def test_seeded_and_csv_starts(self):
        # --seed S: agent i starts where shapeform_sim --agents N --seed S puts agent i.
        n, seed = 6, 7
        sim = self.run_sim(harness.scenario("circle"), ["--agents", str(n), "--seed", str(seed), "--steps", "0"])
        # Also: --rate, --set and --record reach the processes.
        record = os.path.join(self.run_dir, "my_record")
        p = self.launch(["-n", str(n), "--scenario", "circle", "--seed", str(seed), "--steps", "5", "--json",
                         "--rate", "40", "--set", "transport.lease_s=3", "--record", record], "launcher_seed")
        self.assertEqual(p.wait(90), 3, "5 iterations: done, not converged")
        run = self.run_folder(p)
        for i, (got, want) in enumerate(zip(self.agent_starts(run, n), sim["final_positions"])):
            self.assertAlmostEqual(got[0], want[0], delta=1e-4, msg="agent %d x1" % i)
            self.assertAlmostEqual(got[1], want[1], delta=1e-4, msg="agent %d x2" % i)
        for i in range(n):
            config = self.start_event(run, "agent_%d" % i)["config"]
            self.assertEqual(config["agent"]["rate_hz"], 40, "agent %d runs at --rate" % i)
            self.assertEqual(config["transport"]["lease_s"], 3, "agent %d got --set" % i)
        self.assertEqual(self.start_event(run, "supervisor")["config"]["transport"]["lease_s"], 3,
                         "the supervisor got --set")
        self.assertEqual(harness.summary(p.out())["recording"], record)
        self.assertTrue(harness.read_csv(os.path.join(record, "metrics.csv")), "recorded into --record")
        self.assertFalse(os.path.exists(os.path.join(run, "record")))
        self.assert_nothing_left(p)
        # --init CSV: agent i starts at row i; -n is the row count.
        rows = [(1.5, -2.0), (-3.25, 0.5), (0.0, 4.0), (2.75, 2.75)]
        csv_path = self.write("init.csv", "x1,x2\n" + "".join("%g,%g\n" % r for r in rows))
        p = self.launch(["--scenario", "square", "--init", csv_path, "--steps", "5", "--json"], "launcher_init")
        self.assertEqual(p.wait(90), 3, "5 iterations: done, not converged")
        self.assertEqual(harness.summary(p.out())["agents"], len(rows))
        for i, (got, want) in enumerate(zip(self.agent_starts(self.run_folder(p), len(rows)), rows)):
            self.assertAlmostEqual(got[0], want[0], delta=1e-9, msg="agent %d x1" % i)
            self.assertAlmostEqual(got[1], want[1], delta=1e-9, msg="agent %d x2" % i)
        self.assert_nothing_left(p)

    def test_not_converged_exit_3(self):
        # A scenario given as a path; convergence made impossible (hold longer than the run):
        # the launcher's exit status is the supervisor's 3, the summary says not converged.
        p = self.launch(["-n", "4", "--scenario", harness.scenario("square"), "--timeout", "3", "--json",
                         "--set", "supervisor.converge.hold=1000000"], "launcher_timeout")
        self.assertEqual(p.wait(90), 3)
        summary = harness.summary(p.out())
        self.assertEqual((summary["converged"], summary["exit_status"], summary["agents"]), (False, 3, 4))
        self.assertEqual(summary["shape"], "square")
        self.assertIn("wait converged timeout=3", harness.read_text(os.path.join(self.run_folder(p), "script.txt")))
        self.assertIn("exit status 3", p.log())
        self.assert_nothing_left(p)

    def test_steps_exit_is_the_verdict(self):
        # --steps K: exactly K iterations, then the verdict as it stands (`wait converged timeout=0`), as the
        # exit status: 3 when the swarm cannot converge in its K iterations (a hold longer than the run),
        # 0 when it has converged by then (the arc law's circle of 6: converged after about 220 of its 600
        # iterations).
        cases = (("not_converged", ["-n", "4", "--scenario", "square", "--steps", "30",
                                    "--set", "supervisor.converge.hold=1000000"], 3, False),
                 ("converged", ["-n", "6", "--scenario", "arc_circle", "--steps", "600"], 0, True))
        for name, args, status, converged in cases:
            with self.subTest(name):
                # 8 participant slots: this test's domain may be 232, where slots past 62 pass port 65535.
                p = self.launch(args + ["--rate", "50", "--json", "--set", "transport.max_participants=8"],
                                "launcher_steps_" + name)
                self.assertEqual(p.wait(150), status, "launcher exit status")
                summary = harness.summary(p.out())
                self.assertEqual((summary["converged"], summary["exit_status"]), (converged, status))
                self.assertGreaterEqual(summary["steps"], int(args[args.index("--steps") + 1]), "iterations done")
                run = self.run_folder(p)
                waits = harness.events(harness.read_text(os.path.join(run, "supervisor.out")), "wait")
                self.assertEqual([(w["wait"], w["ok"]) for w in waits],
                                 [("agents", True), ("time", True), ("converged", converged)])
                self.assertIn("exit status %d" % status, p.log())
                self.assert_nothing_left(p)

    def interrupt(self, to_group):
        """Starts a run to convergence (it would end by itself much later), interrupts it mid-run."""
        p = self.launch(["-n", "10", "--scenario", "circle", "--timeout", "300", "--set", "supervisor.converge.hold=100000"],
                        "launcher_group" if to_group else "launcher")
        # Mid-run: every agent started and the command out and followed (the agents' discovery is
        # not what this test is about, so not all ten need to be heard).
        run = harness.poll(lambda: glob.glob(os.path.join(self.run_dir, "runs_" + p.name, "*", "")), 30,
                           "the launcher's run folder")[0]
        harness.poll(lambda: all(os.path.exists(os.path.join(run, "agent_%d.out" % i)) for i in range(10))
                     and any(self.agent_epochs(run, i) == [1] for i in range(10)), 60,
                     "the 10 agents started, some following the command")
        if to_group:
            os.killpg(p.pid, signal.SIGINT)  # a terminal's Ctrl-C: every process of the group
        else:
            os.kill(p.pid, signal.SIGINT)  # the launcher alone: it must stop its children
        status = p.wait(30)
        self.assertEqual(status, 130, "exit status after Ctrl-C")
        self.assert_nothing_left(p)
        for i in range(10):
            stops = harness.events(harness.read_text(os.path.join(run, "agent_%d.out" % i)), "stop")
            self.assertEqual(len(stops), 1, "agent %d stopped cleanly" % i)
            self.assertGreater(stops[0]["ticks"], 0)
        self.assertIn("summary:", harness.read_text(os.path.join(run, "supervisor.out")),
                      "the supervisor printed its summary")
        self.assertIn("summary:", p.out(), "the launcher shows the summary")
        self.assertIn("interrupted", p.log())
        self.assertGreater(len(harness.read_csv(os.path.join(run, "record", "metrics.csv"))), 0)

    def test_ctrl_c_to_launcher(self):
        self.interrupt(to_group=False)

    def test_ctrl_c_to_terminal_group(self):
        self.interrupt(to_group=True)

    BAD_ARGS = [
        ([], r"--scenario: required"),
        (["--scenario", "no_such_scenario"], r"--scenario: no scenario 'no_such_scenario'"),
        (["--scenario", "circle", "-n", "0"], r"^launch_swarm: -n: "),
        (["--scenario", "circle", "-n", "twelve"], r"^launch_swarm: -n: "),
        (["--scenario", "circle", "-n"], r"^launch_swarm: -n: missing value"),
        (["--scenario", "circle", "--domain", "233"], r"^launch_swarm: --domain: "),
        (["--scenario", "circle", "--rate", "0"], r"^launch_swarm: --rate: "),
        (["--scenario", "circle", "--rate", "fast"], r"^launch_swarm: --rate: "),
        (["--scenario", "circle", "--steps", "-5"], r"^launch_swarm: --steps: "),
        (["--scenario", "circle", "--seed", "x"], r"^launch_swarm: --seed: "),
        (["--scenario", "circle", "--timeout", "0"], r"^launch_swarm: --timeout: "),
        (["--scenario", "circle", "--set", "dynamics.r"], r"^launch_swarm: --set: expected key=value"),
        (["--scenario", "circle", "--set", "dynamics.r=-1"], r"^launch_swarm: dynamics\.r: must be >= 0"),
        (["--scenario", "circle", "--set", "dynamics.speed=1"], r"^launch_swarm: .*unknown key"),
        (["--scenario", "circle", "--init", "/nonexistent/init.csv"], r"^launch_swarm: --init: "),
        (["--scenario", "circle", "--frobnicate"], r"^launch_swarm: unknown argument '--frobnicate'"),
        (["--scenario", "circle", "-n", "120"], r"^launch_swarm: -n 120: .* need 121 participants on this host, "
                                                r"transport\.max_participants is 120"),
        (["--scenario", "circle", "--vehicles", "real"], r"^launch_swarm: --vehicles: expected sim .*got 'real'"),
        (["--scenario", "circle", "--vehicles"], r"^launch_swarm: --vehicles: missing value"),
        (["--scenario", "circle", "--vehicles", "sim", "--set", "vehicle.interface=internal"],
         r"^launch_swarm: --set vehicle\.interface=internal: not with --vehicles sim"),
        # --vehicles sets vehicle.interface=ros2 for every process, and the configuration is checked with it.
        (["--scenario", "circle", "--vehicles", "sim"], r"^launch_swarm: vehicle\.max_speed: must be > 0 with "
                                                        r"vehicle\.interface: ros2"),
        (["--scenario", "circle", "--vehicles", "sim", "--set", "vehicle.max_speed=1", "-n", "119"],
         r"^launch_swarm: -n 119: 119 agents, the supervisor and the vehicle process need 121 participants"),
    ]

    def test_paper_law_past_its_gains_is_noted(self):
        # 20 agents or more with the paper's law get a note once the arguments are checked; the arc law
        # and 12 agents do not. Each launch then stops at its run folder (--runs names a file, exit 2):
        # no swarm is needed.
        not_a_folder = self.write("not_a_folder", "")
        for scenario, n, noted in (("circle", 20, True), ("arc_circle", 20, False), ("circle", 12, False)):
            with self.subTest(scenario=scenario, n=n):
                p = self.start("note_%s_%d" % (scenario, n),
                               ["bash", launcher(), "--build", build_dir(), "--runs", not_a_folder,
                                "--domain", str(self.domain), "--scenario", scenario, "-n", str(n)])
                self.assertEqual(p.wait(60), 2, p.log())
                self.assertIn("--runs: cannot write into the folder", p.log())
                self.assertEqual("note: %d agents with the paper's law" % n in p.log(), noted, p.log())

    def test_bad_arguments_exit_2(self):
        runs = os.path.join(self.run_dir, "runs")
        csv_path = self.write("three.csv", "0,0\n1,1\n2,2\n")
        cases = self.BAD_ARGS + [(["--scenario", "circle", "-n", "4", "--init", csv_path],
                                  r"^launch_swarm: --init: .* has 3 positions but -n is 4"),
                                 (["--scenario", "circle", "--vehicles", "sim", "--init", csv_path],
                                  r"^launch_swarm: --init: not with --vehicles sim")]
        for k, (args, message) in enumerate(cases):
            with self.subTest(args=args):
                # Own process group and the test's domain: were a bad argument let through, the
                # swarm it started would still be found and stopped.
                p = self.start("bad_args_%d" % k, ["bash", launcher(), "--build", build_dir(), "--runs", runs,
                                                   "--domain", str(self.domain)] + args)
                self.assertEqual(p.wait(60), 2, "%s: exit status (stderr %r)" % (args, p.log()))
                self.assertEqual(len(p.log().splitlines()), 1, "%s: one line, got %r" % (args, p.log()))
                self.assertRegex(p.log(), message)
                self.assertEqual(p.out(), "")
        self.assertFalse(os.path.exists(runs) and os.listdir(runs), "no run folder for bad arguments")

if __name__ == "__main__":
    harness.main()
