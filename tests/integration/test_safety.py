#!/usr/bin/env python3
"""The safety filter on agent processes (docs/SAFETY.md): free-running agents that hear one another late.

- 12 agents 0.5 apart on the x1 axis commanded onto the x2 axis (every closest point is the origin: they
  all cross there), the arc law: with safety.min_separation = 0.25 no two agents ever come closer than
  0.25, by the agents' own measure at every step (the summary's min_separation_run) and by the
  supervisor's recorded positions; the filter intervened, and the swarm still converges. The same start
  without the filter comes closer than 0.25 (so the start does force the crossing the filter prevents).

- From the console, on a converged 12-agent arc circle: a keep-out zone over part of the circle (agents
  leave it and never enter it; the agent whose slot it covers is held at its edge, the verdict blocked
  and the status naming the zone); a fence that leaves part of the swarm outside with the action
  return (each counted as a breach, they come back inside and stay, held by the fence); a fence with
  the action hold (the supervisor holds the swarm and says so; after `resume` the agents outside
  return inside).

- Agent 5 paused 0.6 s as the filtered crossing starts: the line still forms, nobody held (a paused
  loop's skipped periods move its model time on).

Run directly: test_safety.py --bin build/bin --source . --domain 112
"""
import itertools
import math
import os
import signal
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402

AGENTS = 12
SEPARATION = 0.25
# Every agent to the origin: the line x1 = 0 (the x2 axis) from agents on the x1 axis.
LINE_90 = ["shape.kind=line", "shape.m=0", "shape.c=0", "shape.rotation_deg=90", "dynamics.max_speed=0.1"]
# A point mass at 0.05 per step with 0.01 per step^2 (one step = 1 s of vehicle time): it needs 5 steps
# and 0.125 to stop from full speed, half the separation.
DOUBLE_INTEGRATOR = ["vehicle.model=double_integrator", "vehicle.max_speed=0.05", "vehicle.max_accel=0.01"]


class SafetyTest(harness.LauncherTestCase):

    def launch(self, name, sets, init):
        argv = ["bash", harness.launcher(), "--build", os.path.dirname(harness.CONFIG["bin"]),
                "--runs", os.path.join(self.run_dir, "runs_" + name), "--domain", str(self.domain),
                "--scenario", "arc_circle", "--init", init, "--timeout", "90", "--json"]
        return self.start(name, argv + [a for s in sets for a in ("--set", s)])

    def recorded_min(self, run):
        """The smallest distance of two agents in the supervisor's recorded positions (one row per agent
        per metrics sample), over the samples in which every agent follows the command."""
        rows = harness.read_csv(os.path.join(run, "record", "positions.csv"), numeric=True)
        samples = {}
        for r in rows:
            if r["epoch"] >= 1:
                samples.setdefault(r["wall_s"], []).append((r["x1"], r["x2"]))
        full = [x for x in samples.values() if len(x) == AGENTS]
        self.assertGreater(len(full), 10, "recorded samples of the whole swarm")
        return min(math.dist(a, b) for x in full for a, b in itertools.combinations(x, 2))

    def line_start(self):
        init = os.path.join(self.run_dir, "line.csv")
        with open(init, "w") as f:
            for i in range(AGENTS):
                f.write("%.4f,0\n" % (0.5 * (i - (AGENTS - 1) / 2)))
        return init

    def test_crossing_kept_apart_on_processes(self):
        init = self.line_start()
        # Unfiltered first: the start forces agents closer than the separation.
        p = self.launch("off", LINE_90, init)
        self.assertEqual(p.wait(150), 0, "the unfiltered swarm converges")
        off = harness.summary(p.out())
        self.assertLess(off["min_separation_run"], SEPARATION, "without the filter the crossing comes closer")
        self.assertEqual(off["filter_interventions"], 0)
        # Filtered: never closer than the separation, by the agents' and by the supervisor's measure.
        p = self.launch("on", LINE_90 + ["safety.min_separation=%g" % SEPARATION], init)
        self.assertEqual(p.wait(150), 0, "the filtered swarm converges too")
        on = harness.summary(p.out())
        self.assertTrue(on["converged"])
        self.assertGreaterEqual(on["min_separation_run"], SEPARATION - 1e-9,
                                "no two agents closer than safety.min_separation at any step")
        self.assertGreater(on["filter_interventions"], 0, "the filter moved steps")
        self.assertEqual(on["promises_broken"], 0)
        self.assertEqual(on["agents_blocked"], 0, "nobody held at the end")
        run = harness.events(p.out(), "run")[0]["dir"]
        self.assertGreaterEqual(self.recorded_min(run), SEPARATION - 1e-9, "recorded positions kept apart")
        # The figures travel in the metrics: the recording's last row has them.
        last = harness.read_csv(os.path.join(run, "record", "metrics.csv"), numeric=True)[-1]
        self.assertEqual(last["min_separation_run"], on["min_separation_run"])
        self.assertEqual(last["filter_interventions"], on["filter_interventions"])

    def test_double_integrators_crossing_kept_apart_on_processes(self):
        """Point masses that cannot stop within a step keep their braking segments apart (docs/SAFETY.md,
        "Vehicles that cannot stop at once"): never closer than the separation."""
        init = self.line_start()
        p = self.launch("double_off", LINE_90 + DOUBLE_INTEGRATOR, init)
        self.assertEqual(p.wait(150), 0, "the unfiltered double integrators converge")
        self.assertLess(harness.summary(p.out())["min_separation_run"], SEPARATION,
                        "without the filter their crossing comes closer")
        p = self.launch("double", LINE_90 + ["safety.min_separation=%g" % SEPARATION] + DOUBLE_INTEGRATOR, init)
        # Converged (0), or not within the timeout (3): states late by many periods on a loaded host leave
        # a stale segment's margin no room, and such agents brake and are held (docs/SAFETY.md), which
        # the verdict must then say.
        self.assertIn(p.wait(150), (0, 3), "the filtered double integrators run to a verdict")
        on = harness.summary(p.out())
        self.assertGreaterEqual(on["min_separation_run"], SEPARATION - 1e-9,
                                "no two agents closer than safety.min_separation at any step")
        self.assertGreater(on["filter_interventions"], 0, "the filter moved steps")
        self.assertEqual(on["promises_broken"], 0)
        if not on["converged"]:
            self.assertGreater(on["agents_blocked"], 0, "not converged: the agents held say so")
        self.assertGreaterEqual(self.recorded_min(harness.events(p.out(), "run")[0]["dir"]), SEPARATION - 1e-9,
                                "recorded positions kept apart")

    def test_crossing_with_a_paused_agent(self):
        """An agent whose loop skips periods keeps its clock (docs/SAFETY.md, "Skipped periods keep the
        clock"): agent 5 stopped 0.6 s (30 periods) as the filtered crossing starts; the others do not take
        its states as 30 steps old for the rest of the command, so the line forms with nobody held. With
        the model time that stood still while the loop skipped periods, 5 agents stayed held by agent 5."""
        config = harness.scenario("arc_circle")
        sets = [a for s in ["swarm.agents=%d" % AGENTS] + LINE_90 + ["safety.min_separation=%g" % SEPARATION]
                for a in ("--set", s)]
        sup = self.start_supervisor(config, extra=sets)
        agents = [self.start_agent(i, config, extra=sets + ["--start", "%.4f,0" % (0.5 * (i - (AGENTS - 1) / 2))])
                  for i in range(AGENTS)]
        self.assertTrue(sup.wait_agents(AGENTS, 60), "the supervisor hears every agent")
        victim = agents[5]
        self.assertEqual(sup.command("start"), 1)
        # Stopped once it follows the command: its clock runs from there.
        harness.poll(lambda: 1 in victim.epochs(), 10, "agent 5 to follow epoch 1", 0.01)
        victim.signal(signal.SIGSTOP)
        try:
            harness.poll(lambda: victim.kernel_state() == "T", 5, "the kernel to stop agent 5", 0.01)
            time.sleep(0.6)  # the fault itself
        finally:
            victim.signal(signal.SIGCONT)
        self.assertTrue(sup.wait_converged(60), "the line forms")
        status = sup.ask("status", "status")
        self.assertEqual([a["safety"] for a in status["agents"] if a["safety"]], [], "nobody held")
        m = sup.metrics()
        self.assertGreater(m["filter_interventions"], 0, "the filter moved steps")
        self.assertGreaterEqual(m["min_separation_run"], SEPARATION - 1e-9)
        self.assert_all_alive(agents + [sup])

    def agents_where(self, sup, ok):
        """Whether every agent's position satisfies ok(x, y), by the supervisor's status."""
        rows = harness.status_rows(sup.ask("status", "status"))
        return len(rows) == AGENTS and all(ok(r["x1"], r["x2"]) for r in rows.values())

    def test_zones_and_fence_from_the_console(self):
        sets = ["--set", "swarm.agents=%d" % AGENTS, "--set", "dynamics.max_speed=0.2"]
        sup, _ = self.start_commanded_swarm(AGENTS, harness.scenario("arc_circle"), sets)
        self.assertTrue(sup.wait_converged(60))
        # A zone over a piece of the circle longer than the gap between slots: one slot at least is in it.
        self.assertEqual(sup.command("safety keep_out add circle 0,4 1.5"), 2)
        outside_zone = lambda x, y: math.dist((x, y), (0, 4)) >= 1.5 - 1e-6  # noqa: E731
        harness.poll(lambda: self.agents_where(sup, outside_zone), 30, "every agent out of the zone")
        harness.poll(lambda: sup.metrics()["verdict"] == "blocked", 30, "the verdict blocked")
        for _ in range(5):  # and they stay out
            self.assertTrue(self.agents_where(sup, outside_zone))
        rows = harness.status_rows(sup.ask("status", "status"))
        self.assertIn("held by zone 1", [a["safety"] for a in sup.ask("status", "status")["agents"]])
        self.assertEqual(len(rows), AGENTS)
        m = sup.metrics()
        self.assertFalse(m["converged"])
        self.assertGreater(m["filter_interventions"], 0)
        self.assertGreaterEqual(m["agents_blocked"], 1)
        # A fence that leaves the agents left of x1 = -2 outside, action return: breaches, they come back.
        sup.command("safety keep_out clear")
        left_out = sum(r["x1"] < -2 for r in harness.status_rows(sup.ask("status", "status")).values())
        self.assertGreaterEqual(left_out, 2, "the circle has agents left of x1 = -2")
        self.assertEqual(sup.command('safety fence polygon "-2,-6;6,-6;6,6;-2,6" action=return'), 4)
        harness.poll(lambda: self.agents_where(sup, lambda x, y: x >= -2 - 1e-6), 30, "every agent inside the fence")
        # The figures come with the agents' statuses, once a second each: an agent's breach is counted
        # when its next status arrives, so wait for every agent the fence left outside.
        harness.poll(lambda: (lambda m: m["fence_breaches"] is not None and m["fence_breaches"] >= left_out and
                              m["verdict"] == "blocked" and m["agents_beyond_fence"] == 0)(sup.metrics()),
                     30, "%d breaches counted, nobody beyond the fence, the verdict blocked" % left_out)
        self.assertIn("held by the fence", [a["safety"] for a in sup.ask("status", "status")["agents"]])
        # Action hold: the supervisor holds the swarm on the breach, and says which agent.
        since = sup.mark()
        sup.command('safety fence polygon "-6,-6;6,-6;6,2;-6,2" action=hold')
        breach = sup.wait_event("fence_breach", 30, since, what="the supervisor's fence_breach event")
        self.assertEqual(breach["action"], "hold")
        self.assertGreater(breach["y"], 2)
        held = sup.wait_event("epoch", 30, since, where=lambda e: e.get("hold"), what="the held epoch")
        harness.poll(lambda: all(r["epoch"] == held["epoch"] for r in harness.status_rows(sup.ask("status", "status")).values()),
                     30, "every agent on the held epoch")
        harness.poll(lambda: (sup.metrics()["agents_beyond_fence"] or 0) > 0, 30,
                     "agents beyond the fence, held where they were")
        sup.command("resume")
        harness.poll(lambda: self.agents_where(sup, lambda x, y: y <= 2 + 1e-6), 30, "every agent back inside")
        harness.poll(lambda: sup.metrics()["agents_beyond_fence"] == 0, 30, "nobody beyond the fence")


if __name__ == "__main__":
    harness.main()
