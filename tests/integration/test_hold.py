#!/usr/bin/env python3
"""The operator's hold, stop and resume on a 12-agent swarm of agent processes.

- `hold` while the swarm is still forming: a new epoch with hold set; once every agent follows it,
  no agent moves (positions from the supervisor's status event, several times over a few seconds,
  equal to the last digit), and model time stands still.
- An agent started while the swarm is held gets the held command (transient-local) and stays at its
  start.
- `resume`: a new epoch with hold off; the swarm moves again and converges.
- `stop`, the emergency alias, freezes the converged swarm the same way; `resume` without a hold
  sends nothing.
"""
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402

AGENTS = 12
# 20 Hz: the swarm is still forming a second after `start`, when it is held.
SETS = ["--set", "swarm.agents=%d" % AGENTS, "--set", "agent.rate_hz=20"]
STILL_S = 3.0  # how long a held swarm is watched


def positions(rows):
    return {i: (r["x1"], r["x2"]) for i, r in rows.items()}


def largest_move(a, b):
    return max(max(abs(a[i][0] - b[i][0]), abs(a[i][1] - b[i][1])) for i in a)


class HoldTest(harness.SwarmTestCase):

    def held(self, sup, word, n):
        """Sends `hold` or `stop`; waits until the n agents follow the held epoch; returns the epoch."""
        e = sup.ask(word, "epoch", what="the supervisor to publish '%s'" % word)
        self.assertTrue(e["hold"], e)
        harness.poll(lambda: self.all_follow(sup, e["epoch"], n), 30, "%d agents to follow the held epoch" % n)
        return e["epoch"]

    def all_follow(self, sup, epoch, n):
        rows = harness.status_rows(sup.ask("status", "status"))
        return len(rows) == n and all(r["alive"] and r["epoch"] == epoch for r in rows.values())

    def assert_still(self, sup, n):
        """Watches the held swarm for STILL_S seconds: nobody moves, model time stays 0."""
        first = sup.ask("status", "status")
        before = positions(harness.status_rows(first))
        self.assertEqual(len(before), n)
        deadline = time.monotonic() + STILL_S
        snapshots = 0
        while time.monotonic() < deadline or snapshots < 3:
            status = sup.ask("status", "status")
            self.assertEqual(status["model_time"], 0.0, "model time stands still while held")
            now = positions(harness.status_rows(status))
            self.assertEqual(sorted(now), sorted(before))
            self.assertLessEqual(largest_move(before, now), 1e-12, "a held agent moved")
            snapshots += 1
            time.sleep(0.5)  # samples spread over the watch; the check itself is the count above
        return before

    def test_hold_resume_stop(self):
        config = harness.scenario("circle")
        sup, agents = self.start_commanded_swarm(AGENTS, config, SETS)
        # Still forming: the agents move (so a frozen swarm below is the hold's doing).
        self.assertTrue(sup.wait_until("time", "wait time 3 timeout=30", 30))
        moving = positions(harness.status_rows(sup.ask("status", "status")))
        harness.poll(lambda: largest_move(moving, positions(harness.status_rows(sup.ask("status", "status")))) > 1e-3,
                     10, "the forming swarm to move")
        self.assertFalse(sup.metrics()["converged"])

        held = self.held(sup, "hold", AGENTS)
        self.assertEqual(held, 2)
        frozen = self.assert_still(sup, AGENTS)
        self.assertFalse(sup.metrics()["converged"], "a held swarm is not called converged")

        # A late joiner obeys the hold too: it stays at its start.
        late = self.start_agent(AGENTS, config, seed=1, extra=SETS)
        harness.poll(lambda: late.epochs() == [held], 30, "the late agent to adopt the held command")
        harness.poll(lambda: self.all_follow(sup, held, AGENTS + 1), 30, "the supervisor to hear the late agent")
        start = late.wait_event("start", 10)["starts"][0]
        after = self.assert_still(sup, AGENTS + 1)
        self.assertEqual(after[AGENTS], tuple(start), "the late agent stayed at its start")
        self.assertLessEqual(largest_move(frozen, {i: after[i] for i in frozen}), 1e-12)

        # resume: a new epoch with hold off; the swarm moves again and converges.
        e = sup.ask("resume", "epoch", what="the supervisor to publish resume")
        self.assertEqual((e["epoch"], e["hold"]), (3, False))
        self.assertTrue(sup.wait_converged(90), "the swarm converges after resume")
        rows = harness.status_rows(sup.ask("status", "status"))
        self.assertEqual(sorted(rows), list(range(AGENTS + 1)))
        # On the circle (r0 = 4) by the verdict's own measure, the mean shape error within its on-shape bound
        # (supervisor.converge.on_shape_rel 0.2 x 4); each agent within 1.5 of it: the paper's law with the
        # late joiner (13 agents) was seen converged with one agent 1.01 off (a per-agent 1.0 was flaky).
        self.assertTrue(all(r["epoch"] == 3 for r in rows.values()), rows)
        errors = [r["shape_error"] for r in rows.values()]
        self.assertLessEqual(sum(errors) / len(errors), 0.8, rows)
        self.assertLess(max(errors), 1.5, rows)
        self.assertGreater(largest_move(after, positions(rows)), 0.1, "the swarm moved after resume")

        # stop, the emergency alias: the same freeze.
        self.assertEqual(self.held(sup, "stop", AGENTS + 1), 4)
        self.assert_still(sup, AGENTS + 1)
        # resume twice: the second has nothing to release and publishes nothing.
        self.assertEqual(sup.command("resume"), 5)
        since = sup.mark()
        sup.send("resume")
        self.assertEqual(sup.metrics()["epoch"], 5)
        self.assertEqual(sup.events("epoch", since), [])

        self.assert_all_alive(agents + [late, sup])
        harness.poll(lambda: all(a.epochs() == [1, 2, 3, 4, 5] for a in agents) and late.epochs() == [2, 3, 4, 5],
                     30, "every agent to follow every epoch in turn")
        sup.send("quit")
        self.assertEqual(sup.wait(20), 0)


if __name__ == "__main__":
    harness.main()
