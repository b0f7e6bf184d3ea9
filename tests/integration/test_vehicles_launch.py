#!/usr/bin/env python3
"""scripts/launch_swarm.sh --vehicles sim: 12 agent processes drive 12 simulated unicycles
(shapeform_vehicle, started by the launcher before the agents, over ROS 2's topics and types).

- loopback, the arc law (arc_circle), with --view: the swarm forms the circle exactly; the robots'
  poses are recorded in RECORD/vehicles.csv, each robot starting at its agent's seeded start and ending
  at its agent's final position; the view's newest frame (GET /frame, what the page draws) carries
  every agent's heading, read from its robot's pose topic; the vehicle process stops with the run.
- a fleet of test hosts, the paper's law (circle): one vehicle process on each host that runs agents,
  hosting that host's robots; their recordings merged into one vehicles.csv.

Run directly (the fleet test: root): test_vehicles_launch.py --bin build/bin --source . --domain 144
"""
import json
import math
import os
import sys
import time
import urllib.request

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402

AGENTS = 12
# Unicycles with limits; one law step per agent tick (vehicle.seconds_per_model_time = 1 / (rate x dt)).
UNICYCLE = ["vehicle.model=unicycle", "vehicle.max_speed=1", "vehicle.max_yaw_rate=2", "agent.rate_hz=20",
            "vehicle.seconds_per_model_time=0.05", "vehicle.heading_spread_deg=180"]
VEHICLE_COLUMNS = ["t_s", "id", "x", "y", "base_x", "base_y", "heading", "v", "vy", "w", "stopped"]

# Two hosts running six agents (and a robot simulator) each, the supervisor on a third. Its own lab and
# subnet (tests/integration/CMakeLists.txt).
LAB = "vehicles"
FLEET = """schema_version: 1
lab: {name: vehicles, hosts: 3, subnet: 10.200.50}
hosts:
  - {name: h1, address: 10.200.50.1, run: netns sf-vehicles-h1, agents: 0-5}
  - {name: h2, address: 10.200.50.2, run: netns sf-vehicles-h2, agents: 6-11}
  - {name: h3, address: 10.200.50.3, run: netns sf-vehicles-h3}
supervisor: h3
"""


def angle_diff(a, b):
    return abs(math.remainder(a - b, 2 * math.pi))


def get_frame(url):
    """The view's newest frame (GET /frame: a snapshot, view/scene.hpp) with its agents as objects of their
    columns, or None while it cannot answer."""
    try:
        with urllib.request.urlopen(url + "frame", timeout=3) as r:
            text = r.read().decode()
        frame = json.loads(text) if text else None
    except (OSError, ValueError):
        return None
    if frame:
        frame["agents"] = [dict(zip(frame["agent_columns"], row)) for row in frame["agents"]]
    return frame


class VehiclesLaunchTest(harness.LauncherTestCase):

    def launch(self, args, name="launcher"):
        argv = ["bash", harness.launcher(), "--build", os.path.dirname(harness.CONFIG["bin"]),
                "--runs", os.path.join(self.run_dir, "runs_" + name), "--domain", str(self.domain),
                "--vehicles", "sim", "--json"] + list(args) + [a for s in UNICYCLE for a in ("--set", s)]
        return self.start(name, argv)

    def assert_nothing_left(self, proc):
        self.assertEqual(harness.processes_in_group(proc.pid), [], "processes left in the launcher's group")
        left = harness.shapeform_processes_on_domain(self.domain)
        self.assertEqual([q for q in left if "shapeform_vehicle" in q[1]], [], "shapeform_vehicle left")
        self.assertEqual(left, [], "shapeform processes left")
        self.assertEqual(sorted(harness.shm_files() - self.shm_before), [], "new Fast DDS shm files")

    def check_run(self, p, scenario):
        """Checks common to both runs: the launcher's verdict, its stdout, every agent driving its robot over
        ROS 2, vehicles.csv with every robot. Returns (run folder, summary, {id: [rows]})."""
        self.assertEqual(p.wait(120), 0, "launcher exit status (0: converged)")
        run_event = harness.events(p.out(), "run")[0]
        self.assertEqual((run_event["agents"], run_event["vehicles"]), (AGENTS, "sim"))
        run = run_event["dir"]
        summary = harness.summary(p.out())
        self.assertTrue(summary["converged"])
        self.assertEqual((summary["agents"], summary["agents_seen"], summary["exit_status"]), (AGENTS, AGENTS, 0))
        for i in range(AGENTS):
            out = harness.read_text(os.path.join(run, "agent_%d.out" % i))
            vehicle = harness.events(out, "start")[0]["config"]["vehicle"]
            self.assertEqual((vehicle["interface"], vehicle["model"]), ("ros2", "unicycle"), "agent %d" % i)
            self.assertIn("driving", [e["vehicle"] for e in harness.events(out, "status")],
                          "agent %d drove its robot" % i)
        rows = harness.read_csv(os.path.join(run, "record", "vehicles.csv"), numeric=True)
        self.assertTrue(rows, "vehicles.csv has rows")
        self.assertEqual(list(rows[0].keys()), VEHICLE_COLUMNS)
        by_id = {}
        for r in rows:
            by_id.setdefault(int(r["id"]), []).append(r)
        self.assertEqual(sorted(by_id), list(range(AGENTS)), "a robot of every agent recorded")
        self.assertIn("vehicles.csv", p.log(), "the launcher names the robots' recording")
        self.assertNotIn("exited with status", p.log())
        # Each robot started where its agent starts (the seeded start of shapeform_sim --steps 0), at rest.
        starts = self.run_sim(harness.scenario(scenario), ["--steps", "0"] + [a for s in UNICYCLE for a in ("--set", s)])
        for i in range(AGENTS):
            first = by_id[i][0]
            self.assertLessEqual(math.dist((first["x"], first["y"]), starts["final_positions"][i]), 1e-5,
                                 "robot %d starts at agent %d's start" % (i, i))
        return run, summary, by_id

    def assert_final_positions(self, summary, by_id, tol, last_s):
        """Each agent's final position is where its robot was in the last `last_s` seconds of its rows."""
        for i, x in zip(summary["final_ids"], summary["final_positions"]):
            rows = by_id[i]
            recent = [r for r in rows if r["t_s"] >= rows[-1]["t_s"] - last_s]
            near = min(math.dist(x, (r["x"], r["y"])) for r in recent)
            self.assertLessEqual(near, tol, "agent %d's final position (%g, %g) and its robot's recorded path"
                                 % (i, x[0], x[1]))

    def test_unicycles_form_the_arc_circle(self):
        p = self.launch(["-n", str(AGENTS), "--scenario", "arc_circle", "--timeout", "60", "--view"])
        url = harness.poll(lambda: (harness.events(p.out(), "view") or [None])[0], 30, "the view's URL")["url"]
        # The view's frames while the swarm forms, until the launcher stops it: the newest one in which
        # every agent has a heading.
        last = None
        deadline = time.monotonic() + 120
        while p.running() and time.monotonic() < deadline:
            frame = get_frame(url)
            if frame and len(frame["agents"]) == AGENTS and all(a["heading"] is not None for a in frame["agents"]):
                last = frame
            time.sleep(0.2)
        run, summary, by_id = self.check_run(p, "arc_circle")
        self.assertLess(summary["curve_error_mean"], 0.1, "the unicycles on the circle")
        self.assertLess(summary["arc_gap_cv"], 0.1, "evenly spaced")
        # Converged and holding still: each robot's last row is its agent's final position.
        for i, x in zip(summary["final_ids"], summary["final_positions"]):
            self.assertLessEqual(math.dist(x, (by_id[i][-1]["x"], by_id[i][-1]["y"])), 0.02, "robot %d" % i)
        self.assert_final_positions(summary, by_id, 0.02, 1.0)
        # The view drew every agent's heading, its robot's: the newest frame's headings are the robots' at one
        # moment of their recording (10 rows a second, each robot's within a row of that moment), each within
        # 0.05 rad. Not the robots' last headings: under load the newest frame can be seconds older than the
        # end, and the robots still turn then.
        self.assertIsNotNone(last, "a frame of the view with the heading of every agent")
        for a in last["agents"]:
            self.assertEqual(a["state"], "alive")
        drawn = {a["id"]: a["heading"] for a in last["agents"]}
        n_rows = min(len(rows) for rows in by_id.values())

        def worst_at(k):
            return max(min(angle_diff(drawn[i], by_id[i][j]["heading"]) for j in range(max(0, k - 1), min(n_rows, k + 2)))
                       for i in drawn)
        best = min(range(n_rows), key=worst_at)
        self.assertLessEqual(worst_at(best), 0.05, "the newest frame's headings and the robots' at t = %g s: %s"
                             % (by_id[0][best]["t_s"], {i: (round(drawn[i], 3), round(by_id[i][best]["heading"], 3))
                                                         for i in sorted(drawn)}))
        # The robot simulator: one process for the 12, logs in the run folder, stopped cleanly with the run.
        out = harness.read_text(os.path.join(run, "vehicle.out"))
        self.assertEqual(harness.events(out, "start")[0]["ids"], list(range(AGENTS)))
        self.assertEqual(len(harness.events(out, "stop")), 1, "shapeform_vehicle stopped cleanly")
        self.assertIn("[vehicle 0..11]", harness.read_text(os.path.join(run, "vehicle.log")))
        self.assert_nothing_left(p)

    def test_fleet_paper_circle(self):
        # Test hosts the launcher makes (root): an earlier killed run's lab is removed first.
        why = harness.netlab.available()
        if why:
            self.fail("test hosts cannot be made here: " + why)  # a failure, never a silent skip
        harness.netlab.NetLab(LAB, 1, "10.0.0").down()
        self.use_lab(LAB)
        fleet = self.write("fleet.yaml", FLEET)
        p = self.launch(["--fleet", fleet, "--scenario", "circle", "--timeout", "90"])
        run, summary, by_id = self.check_run(p, "circle")
        # One robot simulator on each host that runs agents, hosting that host's robots (driven from there:
        # each robot had its agent's command writer), none on the supervisor's host.
        for host, ids in (("h1", list(range(0, 6))), ("h2", list(range(6, 12)))):
            out = harness.read_text(os.path.join(run, "vehicle_%s.out" % host))
            self.assertEqual(harness.events(out, "start")[0]["ids"], ids, host)
            status = harness.events(out, "status")
            for i in ids:
                self.assertIn(1, [e["command_writers"] for e in status if e["id"] == i], "robot %d's agent" % i)
            self.assertEqual(len(harness.events(out, "stop")), 1, "%s's vehicle process stopped cleanly" % host)
        self.assertFalse(os.path.exists(os.path.join(run, "vehicle_h3.out")), "no robots on the supervisor's host")
        # The hosts' recordings merged in order of time, their folders removed.
        times = [r["t_s"] for rows in by_id.values() for r in rows]
        merged = harness.read_csv(os.path.join(run, "record", "vehicles.csv"), numeric=True)
        self.assertEqual(len(merged), len(times))
        self.assertEqual([r["t_s"] for r in merged], sorted(times))
        self.assertEqual(sorted(os.listdir(os.path.join(run, "record"))),
                         ["centre.csv", "commands.csv", "metrics.csv", "positions.csv", "run.mcap", "vehicles.csv"])
        # The paper's law still moves the agents at the end: each final position lies on its robot's path.
        self.assert_final_positions(summary, by_id, 0.1, 3.0)
        self.assertIn("lab %s down" % LAB, p.log())
        self.assert_nothing_left(p)
        netns = harness.procs.run(["ip", "netns", "list"], timeout=10).stdout
        self.assertEqual([line for line in netns.splitlines() if line.startswith("sf-%s-" % LAB)], [],
                         "the lab's namespaces left")


if __name__ == "__main__":
    harness.main()
