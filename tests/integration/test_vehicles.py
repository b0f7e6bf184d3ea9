#!/usr/bin/env python3
"""Agents that drive robots over ROS 2's topics (vehicle.interface ros2), on real processes over loopback.
shapeform_vehicle plays the robots' drivers (odom out, cmd_vel in, a watchdog): unicycles of 1 m/s and
2 rad/s facing anywhere, one law step per agent tick.

- Formation: 12 agent processes drive the 12 robots of one vehicle process onto the circle and the square
  with both laws, the commands changed by the supervisor: the arc law on the curve and evenly spaced by
  arc length, the paper's law by the supervisor's verdict. `hold`, sent while the robots drive, stops
  every robot: vehicles.csv shows each one still, its speeds zero.
- Faults, each robot in a vehicle process of its own: a robot whose driver is killed leaves its agent
  stopped and reported (pose_lost), and the swarm re-spaces without it; a driver paused (SIGSTOP) makes
  its agent command zero as soon as the pose is older than vehicle.pose_timeout_s, say so, and drive
  again when the poses return (its cmd_vel read by shapeform_echo); an agent killed leaves its robot
  stopped by the robot's watchdog.
- Bad poses on a robot's odom (shapeform_rogue_publisher: a far jump, a position that is not a number,
  another frame) are refused, reported and counted, and the agent stays where its robot is.
- A robot too slow for the law's steps (max_speed 0.05 m/s) is reported: its commands count as saturated.
"""
import math
import os
import signal
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402

AGENTS = 12
RATE_HZ = 20.0
SEED = 1
# The robots, and one law step (integration.dt = 1) per agent tick: seconds_per_model_time = 1 / rate.
ROBOT_SETS = ["vehicle.interface=ros2", "vehicle.model=unicycle", "vehicle.max_speed=1", "vehicle.max_yaw_rate=2",
              "vehicle.heading_spread_deg=180", "agent.rate_hz=%g" % RATE_HZ,
              "vehicle.seconds_per_model_time=%g" % (1.0 / RATE_HZ)]
# The verdict asks its conditions to hold over 20 steps (1 s) instead of 50: every formation is also held
# to its metrics here.
SUPERVISOR_SETS = ["supervisor.converge.hold=20"]
R0 = 4.0  # arc_circle.yaml: shape.r0
CURVE_ERROR_MAX = 0.1  # m: the arc law's mean distance to the curve
ARC_GAP_CV_MAX = 0.02  # the arc law's arc-length gap CV (about 1e-4 here; a missing agent's gap makes it ~0.3)
STILL_M = 1e-3  # m: a robot whose point stays within this is still
STILL_S = 2.0  # s: how long a stopped robot is watched


def sets(values):
    return [a for v in values for a in ("--set", v)]


def nonzero(samples):
    """Whether one of these cmd_vel samples (shapeform_echo lines) commands any motion."""
    return any(abs(e["data"]["vx"]) + abs(e["data"]["vy"]) + abs(e["data"]["wz"]) > 0 for e in samples)


def brief(samples):
    """cmd_vel samples as (vx, wz) pairs, for a failure's message."""
    return [(round(e["data"]["vx"], 3), round(e["data"]["wz"], 3)) for e in samples]


class Vehicles(harness.Proc):
    """A shapeform_vehicle process run with --json: a status event per robot each second (its controlled
    point x, y and its base), watchdog and resumed events."""

    def points(self, since=0):
        """{robot id: (x, y)} from the newest status event of each robot after `since`."""
        return {e["id"]: (e["x"], e["y"]) for e in self.events("status", since)}


class VehiclesTest(harness.SwarmTestCase):

    # -- processes
    def start_vehicles(self, ids, config, extra=(), record=None, name=None):
        argv = [harness.bin_path("shapeform_vehicle"), "--ids", ids, "--config", config, "--json",
                "--domain", str(self.domain), "--seed", str(SEED)] + list(extra)
        if record is not None:
            argv += ["--record", os.path.join(self.run_dir, record)]
        return self.start(name or "vehicles_" + ids, argv, cls=Vehicles)

    def swarm(self, robot_processes, agent_sets=()):
        """A supervisor, AGENTS agent processes and their robots: one vehicle process for all, recording
        (robot_processes 1), or one per robot, each recording into robot_K/ (AGENTS); once every agent
        drives its robot, `start` publishes the arc circle. Returns (supervisor, agents, vehicle processes)."""
        config = harness.scenario("arc_circle")
        extra = sets(ROBOT_SETS)
        sup = self.start_supervisor(config, extra=extra + sets(SUPERVISOR_SETS))
        if robot_processes == 1:
            robots = [self.start_vehicles("0-%d" % (AGENTS - 1), config, extra, record="robots")]
        else:
            robots = [self.start_vehicles(str(i), config, extra, record="robot_%d" % i, name="vehicle_%d" % i)
                      for i in range(AGENTS)]
        agents = self.start_agents(AGENTS, config, seed=SEED, extra=extra + sets(agent_sets))
        self.assertTrue(sup.wait_agents(AGENTS, 60), "the supervisor hears every agent")
        self.wait_driving(agents, range(AGENTS))
        self.assertEqual(sup.command("start"), 1)
        return sup, agents, robots

    # -- what the agents and robots say
    @staticmethod
    def agent_status(agent, rid, since=0):
        """The newest status event of agent `rid` printed by `agent` after `since` (None before one)."""
        found = [e for e in agent.events("status", since) if e["id"] == rid]
        return found[-1] if found else None

    def wait_driving(self, agents, ids, timeout=30):
        def all_driving():
            states = {e["id"]: e["vehicle"] for a in agents for e in a.events("status")}
            return all(states.get(i) == "driving" for i in ids)
        harness.poll(all_driving, timeout, "agents %s to report their robots driving" % list(ids))

    def converged_metrics(self, sup, agents_n, law, epoch, timeout=30):
        """Polls the supervisor's metrics until its verdict is converged with agents_n agents following
        `epoch` (for the arc law also on the curve and evenly spaced); returns them."""
        def converged():
            m = sup.metrics()
            ok = m["converged"] and m["agents"] == agents_n and m["epoch"] == epoch
            if law == "arc":
                ok = ok and m["curve_error_mean"] < CURVE_ERROR_MAX and m["arc_gap_cv"] < ARC_GAP_CV_MAX
            return m if ok else None
        return harness.poll(converged, timeout, "%d agents to converge on epoch %d (%s law%s)" % (
            agents_n, epoch, law, ", on the curve and evenly spaced" if law == "arc" else ""), 0.2)

    def assert_robots_on_circle(self, robots, r, tolerance):
        """Every robot's controlled point, as its driver reports it, is on the circle of radius r about 0."""
        since = robots.mark()
        harness.poll(lambda: len(robots.points(since)) == AGENTS, 10, "a status round of every robot")
        for i, (x, y) in robots.points(since).items():
            self.assertLess(abs(math.hypot(x, y) - r), tolerance, "robot %d on the circle of radius %g" % (i, r))

    def wait_moving(self, csv, robots_in_csv):
        """Until the newest row of some robot in vehicles.csv has a forward speed above 0.1 m/s."""
        harness.poll(lambda: any(abs(r["v"]) > 0.1 for r in harness.read_csv(csv, numeric=True)[-robots_in_csv:]),
                     10, "a robot of %s to drive" % csv)

    def assert_still(self, csv, ids, what):
        """Watches robots `ids` in vehicles.csv (10 Hz) for STILL_S seconds from one second on (the wheels'
        lag, vehicle_sim.response_s = 0.1 s, has died out by then): none moves, every speed ~0."""
        t_from = harness.read_csv(csv, numeric=True)[-1]["t_s"] + 1.0
        t_to = t_from + STILL_S
        harness.poll(lambda: harness.read_csv(csv, numeric=True)[-1]["t_s"] >= t_to, STILL_S + 10,
                     "%s to cover %.0f s more" % (csv, STILL_S + 1))
        window = [r for r in harness.read_csv(csv, numeric=True) if t_from <= r["t_s"] <= t_to]
        for i in ids:
            rows = [r for r in window if int(r["id"]) == i]
            # Rows over the whole window (10 Hz when the host keeps up).
            self.assertGreaterEqual(len(rows), 5, "rows of robot %d" % i)
            self.assertGreaterEqual(rows[-1]["t_s"] - rows[0]["t_s"], STILL_S - 0.5, "rows of robot %d" % i)
            xs, ys = [r["x"] for r in rows], [r["y"] for r in rows]
            self.assertLess(max(max(xs) - min(xs), max(ys) - min(ys)), STILL_M, "%s: robot %d moved" % (what, i))
            self.assertLess(max(abs(r["v"]) + abs(r["w"]) for r in rows), 1e-3, "%s: robot %d drives" % (what, i))

    # ------------------------------------------------------------------------------------------------
    def test_formation_and_hold_one_vehicle_process(self):
        sup, agents, (robots,) = self.swarm(robot_processes=1)
        csv = os.path.join(self.run_dir, "robots", "vehicles.csv")
        # The arc law's circle, the robots on it.
        self.converged_metrics(sup, AGENTS, "arc", 1)
        self.assert_robots_on_circle(robots, R0, CURVE_ERROR_MAX)

        # The square with the arc law, held while the robots drive there: every robot stops.
        self.assertEqual(sup.command("shape square a=4"), 2)
        self.wait_moving(csv, AGENTS)
        held = sup.ask("hold", "epoch", what="the supervisor to publish hold")
        self.assertEqual((held["epoch"], held["hold"]), (3, True), held)
        harness.poll(lambda: all(r["alive"] and r["epoch"] == 3
                                 for r in harness.status_rows(sup.ask("status", "status")).values()),
                     20, "every agent to follow the held epoch")
        self.assert_still(csv, range(AGENTS), "held")
        resumed = sup.ask("resume", "epoch", what="the supervisor to publish resume")
        self.assertEqual((resumed["epoch"], resumed["hold"]), (4, False), resumed)
        self.converged_metrics(sup, AGENTS, "arc", 4)

        # The paper's law on the square, then on the circle.
        self.assertEqual(sup.command("law paper"), 5)
        self.converged_metrics(sup, AGENTS, "paper", 5)
        self.assertEqual(sup.command("shape circle r=%g" % R0), 6)
        self.converged_metrics(sup, AGENTS, "paper", 6)
        # The paper's plateau on the circle is 0.17 (docs/VEHICLES.md).
        self.assert_robots_on_circle(robots, R0, 0.5)
        self.assert_all_alive(agents + [robots, sup])
        sup.send("quit")
        self.assertEqual(sup.wait(20), 0)
        s = harness.summary(sup.out())
        self.assertEqual((s["converged"], s["law"], s["shape"], s["epoch"]), (True, "paper", "circle", 6), s)

    def test_faults_one_vehicle_process_per_robot(self):
        # Statuses at 5 Hz: a paused driver's agent says so in its status within the pause.
        sup, agents, robots = self.swarm(robot_processes=AGENTS, agent_sets=["agent.status_rate_hz=5"])
        paused, killed_agent, killed_robot = 2, 7, 5
        commands = self.start_echo("rt/robot_%d/cmd_vel" % paused, "cmd_vel_%d" % paused)
        self.converged_metrics(sup, AGENTS, "arc", 1)

        # A robot's driver killed: its agent stops it and says so, and leaves; the others re-space.
        since = agents[killed_robot].mark()
        robots[killed_robot].kill_group()
        lost = agents[killed_robot].wait_event("vehicle", 10, since, where=lambda e: e["state"] == "pose_lost",
                                               what="agent %d to report its robot's pose lost" % killed_robot)
        self.assertEqual((lost["id"], lost["was"]), (killed_robot, "driving"), lost)
        self.assertIn("vehicle.pose_timeout_s", lost["why"])
        harness.poll(lambda: killed_robot in sup.left(), 10, "the supervisor to see agent %d leave" % killed_robot)
        self.converged_metrics(sup, AGENTS - 1, "arc", 1)
        st = agents[killed_robot].wait_event("status", 5, agents[killed_robot].mark(),
                                             what="a status of agent %d" % killed_robot)
        self.assertEqual(st["vehicle"], "pose_lost", st)

        # A circle 3 m away: every robot drives for seconds.
        self.assertEqual(sup.command("shape circle r=%g cx=3" % R0), 2)
        killed_csv = os.path.join(self.run_dir, "robot_%d" % killed_agent, "vehicles.csv")
        self.wait_moving(killed_csv, 1)
        harness.poll(lambda: nonzero(commands.events("sample")[-3:]), 10, "robot %d to be driven" % paused)

        # The command stream lost: the agent killed while its robot drives.
        since_w = robots[killed_agent].mark()
        agents[killed_agent].kill_group()
        # A driver paused: its agent commands zero once the pose is older than vehicle.pose_timeout_s.
        since_a, since_c = agents[paused].mark(), commands.mark()
        robots[paused].signal(signal.SIGSTOP)
        try:
            lost = agents[paused].wait_event("vehicle", 10, since_a, where=lambda e: e["state"] == "pose_lost",
                                             what="agent %d to report its robot's pose lost" % paused)
            since_z, since_l = commands.mark(), agents[paused].mark()
            st = agents[paused].wait_event("status", 5, since_l, what="a status of agent %d" % paused)
            harness.poll(lambda: len(commands.events("sample", since_z)) >= 10, 10,
                         "commands to robot %d after its pose was lost" % paused)
            during = commands.events("sample", since_c)
        finally:
            # Marked before the robot resumes: its agent drives again within a tick or two of it, and
            # "driving" is reported once (a mark taken after SIGCONT can miss it on a busy host).
            since_back, since_back_c = agents[paused].mark(), commands.mark()
            robots[paused].signal(signal.SIGCONT)
        self.assertEqual((lost["id"], lost["was"]), (paused, "driving"), lost)
        self.assertEqual(st["vehicle"], "pose_lost", st)
        # The stale pose's commands for at most the timeout (0.5 s at 20 Hz, and a margin), then zero only.
        first_zero = next((k for k, e in enumerate(during) if not nonzero([e])), len(during))
        self.assertLessEqual(first_zero, 0.5 * RATE_HZ + 6, brief(during))
        self.assertGreaterEqual(len(during) - first_zero, 10,
                                "zero commands while the pose is lost: %s" % brief(during))
        self.assertFalse(nonzero(during[first_zero:]), brief(during))
        # The poses return: driving again, toward the new circle.
        back = agents[paused].wait_event("vehicle", 10, since_back, where=lambda e: e["state"] == "driving",
                                         what="agent %d to drive again" % paused)
        self.assertEqual(back["was"], "pose_lost", back)
        harness.poll(lambda: nonzero(commands.events("sample", since_back_c)), 10,
                     "robot %d to be driven again" % paused)

        # The killed agent's robot: stopped by its watchdog, and still.
        watchdog = robots[killed_agent].wait_event("watchdog", 10, since_w, what="robot %d's watchdog" % killed_agent)
        self.assertEqual(watchdog["id"], killed_agent)
        self.assert_still(killed_csv, [killed_agent], "its agent killed")
        # The others (the paused robot back among them) converge on the new circle.
        self.converged_metrics(sup, AGENTS - 2, "arc", 2)
        self.assert_all_alive([sup, commands] + [a for i, a in enumerate(agents) if i != killed_agent]
                              + [r for i, r in enumerate(robots) if i != killed_robot])
        sup.send("quit")
        self.assertEqual(sup.wait(20), 0)

    def start_echo(self, topic, name):
        return self.start(name, [harness.bin_path("shapeform_echo"), topic, "--domain", str(self.domain)])

    # ------------------------------------------------------------------------------------------------
    def small_swarm(self, n, robot_sets=(), supervisor=False):
        """n agents in one group process driving n robots of one vehicle process (and a supervisor), once
        every agent drives its robot."""
        config = harness.scenario("arc_circle")
        extra = sets(ROBOT_SETS + ["swarm.agents=%d" % n] + list(robot_sets))
        sup = self.start_supervisor(config, extra=extra) if supervisor else None
        robots = self.start_vehicles("0-%d" % (n - 1), config, extra)
        group = self.start_group("0-%d" % (n - 1), config, extra, seed=SEED)
        self.wait_driving([group], range(n))
        return sup, robots, group

    def test_bad_poses_refused_and_counted(self):
        _, robots, group = self.small_swarm(3)
        victim = 1
        since = robots.mark()
        harness.poll(lambda: [e for e in robots.events("status", since) if e["id"] == victim], 5,
                     "a status of robot %d" % victim)
        real = [e for e in robots.events("status", since) if e["id"] == victim][-1]
        bx, by = real["base"]
        yaw = "yaw=%r" % real["heading"]
        cases = [
            # 5 m in one pose, where the robot can move 1 m/s x 0.02 s + vehicle.pose_jump_m (0.5 m).
            ("jump", ["x=%r" % (bx + 5.0), "y=%r" % by, yaw], "pose jumped 5 m"),
            # Not a number: refused by the conversion, which names the field.
            ("nan", ["x=nan", "y=%r" % by, yaw], "odom.pose.position.x: must be finite"),
            # Where the robot is, but in another frame than the swarm's (vehicle.frame: map).
            ("frame", ["x=%r" % bx, "y=%r" % by, yaw, "frame_id=odom"], "frame 'odom'"),
        ]
        first = group.mark()
        for name, fields, why in cases:
            since = group.mark()
            argv = [harness.bin_path("shapeform_rogue_publisher"), "--domain", str(self.domain), "--topic", "odom",
                    "--robot", str(victim), "--count", "20", "--rate", "40", "--wait-readers", "1"]
            rogue = self.start("rogue_" + name, argv + [a for f in fields for a in ("--field", f)])
            self.assertEqual(rogue.wait(20), 0, "the rogue publisher ran")
            e = group.wait_event("pose_refused", 10, since, where=lambda e, why=why: why in e["why"],
                                 what="agent %d to refuse the %s pose" % (victim, name))
            self.assertEqual(e["id"], victim, e)
        # Counted by the agent of that robot only.
        since = group.mark()
        harness.poll(lambda: all(self.agent_status(group, i, since) for i in range(3)), 10, "a status of every agent")
        st = {i: self.agent_status(group, i, since) for i in range(3)}
        self.assertGreaterEqual(st[victim]["poses_refused"], len(cases), st[victim])
        self.assertEqual([st[i]["poses_refused"] for i in (0, 2)], [0, 0], st)
        # The agent stayed where its robot is (at rest: no command): every status since the first bad pose.
        point = robots.points()[victim]
        statuses = [e for e in group.events("status", first) if e["id"] == victim]
        self.assertGreaterEqual(len(statuses), 2, "statuses of agent %d" % victim)
        for e in statuses:
            self.assertEqual(e["vehicle"], "driving", e)
            self.assertTrue(all(isinstance(e[k], float) and math.isfinite(e[k]) for k in ("x", "y")), e)
            self.assertLess(math.hypot(e["x"] - point[0], e["y"] - point[1]), 0.01, (e, point))
        self.assert_all_alive([robots, group])

    def test_slow_robot_reported_saturated(self):
        # Robots of 0.05 m/s: the law's steps ask up to 1 m/s of them, and every command is cut.
        sup, robots, group = self.small_swarm(3, ["vehicle.max_speed=0.05"], supervisor=True)
        self.assertTrue(sup.wait_agents(3, 30), "the supervisor hears every agent")
        since = group.mark()
        self.assertEqual(sup.command("start"), 1)
        for i in range(3):
            e = group.wait_event("saturated", 10, since, where=lambda e, i=i: e["id"] == i,
                                 what="agent %d to report its commands saturated" % i)
            self.assertGreater(e["commands"], 0, e)
        harness.poll(lambda: all((self.agent_status(group, i, since) or {}).get("commands_saturated", 0) > 0
                                 for i in range(3)), 10, "every agent's status to count saturated commands")
        self.assert_all_alive([sup, robots, group])

        # The agents stopped (SIGTERM) while their robots drive: the last command each robot gets is zero,
        # so a real robot stops at once rather than at its driver's timeout.
        commands = self.start_echo("rt/robot_0/cmd_vel", "cmd_vel_0")
        harness.poll(lambda: nonzero(commands.events("sample")[-3:]), 10, "robot 0 to be driven")
        group.signal(signal.SIGTERM)
        self.assertEqual(group.wait(20), 0, "the agents stop cleanly")
        # (The echo may print the last sample a moment after the agents exit.)
        harness.poll(lambda: not nonzero(commands.events("sample")[-1:]), 5,
                     "the agent's last command to robot 0 to be zero")


if __name__ == "__main__":
    harness.main()
