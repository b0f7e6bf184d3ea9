#!/usr/bin/env python3
"""Two swarms at once on different DDS domains (the test's domain D and D+1) do not see each other.

Swarm A (agents 0..4, circle) and swarm B (agents 10..14, square) run side by side on the same host.
Each supervisor must list only its own five agents, each agent must hear only its four fellows,
each swarm forms its own shape, and a command in one swarm changes nothing in the other.
"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402

N = 5


class IsolationTest(harness.SwarmTestCase):

    def test_two_swarms_on_two_domains(self):
        da, db = self.domain, self.domain + 1
        self.assertEqual(harness.shapeform_processes_on_domain(db), [], "domain %d is free" % db)
        sets = ["--set", "swarm.agents=%d" % N]
        circle, square = harness.scenario("circle"), harness.scenario("square")
        sup_a = self.start_supervisor(circle, domain=da, extra=sets, name="supervisor_a")
        sup_b = self.start_supervisor(square, domain=db, extra=sets, name="supervisor_b")
        agents_a = self.start_agents(N, circle, domain=da, seed=1, extra=sets, prefix="a_agent_")
        # Swarm B uses other ids, so any crossing shows as extra rows.
        agents_b = self.start_agents(N, square, domain=db, seed=1, extra=sets, first=10, prefix="b_agent_")
        self.assertTrue(sup_a.wait_agents(N, 60))
        self.assertTrue(sup_b.wait_agents(N, 60))
        self.assertEqual(sup_a.command("start"), 1)
        self.assertEqual(sup_b.command("start"), 1)
        self.assertTrue(sup_a.wait_converged(60), "swarm A forms its circle")
        self.assertTrue(sup_b.wait_converged(60), "swarm B forms its square")

        # A command in A: A moves to epoch 2, B stays at epoch 1.
        self.assertEqual(sup_a.command("shape circle r=3"), 2)
        self.assertTrue(sup_a.wait_converged(60))

        def own_rows(sup, ids, epoch):
            rows, m = sup.status()
            ok = (sorted(rows) == ids and all(r["alive"] and r["heard"] == N - 1 and r["epoch"] == epoch
                                              for r in rows.values()))
            return (rows, m) if ok else None

        rows_a, m_a = harness.poll(lambda: own_rows(sup_a, list(range(N)), 2), 20,
                                   "supervisor A to list agents 0..4 only, each hearing 4, epoch 2", 0.5)
        rows_b, m_b = harness.poll(lambda: own_rows(sup_b, list(range(10, 10 + N)), 1), 20,
                                   "supervisor B to list agents 10..14 only, each hearing 4, epoch 1", 0.5)
        self.assertEqual((m_a["agents"], m_b["agents"]), (N, N))
        # A sits on the ring the law gives for r=3 (pulled in by cohesion: radius ~2.6, not ~3.55 as
        # for r=4); B on its square (the circle's formation would be 1.4 off it).
        sim = self.run_sim(circle, ["--agents", str(N), "--seed", "1", "--steps", "400", "--set", "shape.r0=3"])
        sim_radius = harness.mean([math.hypot(x, y) for x, y in sim["final_positions"]])
        radius_a = harness.mean([math.hypot(r["x1"], r["x2"]) for r in rows_a.values()])
        self.assertLess(abs(radius_a - sim_radius), 0.2, "A's ring radius %.3f, simulator %.3f" % (radius_a, sim_radius))
        self.assertLess(m_b["shape_error_mean"], 0.75, "B on its square")
        for a in agents_b:
            self.assertEqual(a.epochs(), [1], "%s followed only B's command" % a.name)
        self.assert_all_alive(agents_a + agents_b + [sup_a, sup_b])

    def tearDown(self):
        super().tearDown()
        self.assertEqual(harness.shapeform_processes_on_domain(self.domain + 1), [])


if __name__ == "__main__":
    harness.main()
