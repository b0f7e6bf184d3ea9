#!/usr/bin/env python3
"""Several agents in one process (`shapeform_agent_group`), the mode the benchmarks use for N = 100.

- One group process hosting agents 0..5 and two single agent processes (6, 7) make one swarm: the
  supervisor hears 8 agents, every hosted agent hears the 7 others (in the process and over DDS), the
  circle converges and every agent stands apart.
- The group's states travel as one batch per tick (shapeform/state_batch: agents 0..5 in one sample,
  one sequence number), the single agents' as one sample each on shapeform/state, which carries none of
  the hosted agents.
- The hosted agents' statuses travel as one batch per status period (shapeform/status_batch: agents
  0..5 in one sample), a period apart; shapeform/status carries the single agents' only.
- SIGTERM to the group process disposes every hosted agent: the supervisor sees the 6 leave at once and
  the two single agents go on, hearing only each other.
- With agent.batch_max_states below the hosted count, the states go in several samples per tick, each
  its own instance keyed by its first id; the swarm is the same, and SIGTERM disposes every part.
- A bad --ids list exits with status 2 and a message naming --ids.
"""
import os
import signal
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402

HOSTED, SINGLE = 6, 2
N = HOSTED + SINGLE


class GroupTest(harness.SwarmTestCase):

    def test_group_and_single_agents_form_one_swarm(self):
        config = harness.scenario("circle")
        sets = ["--set", "swarm.agents=%d" % N]
        sup = self.start_supervisor(config, extra=sets)
        group = self.start_group("0-%d" % (HOSTED - 1), config, sets)
        singles = self.start_agents(SINGLE, config, seed=1, extra=sets, first=HOSTED)
        self.assertTrue(sup.wait_agents(N, 60), "the supervisor hears all %d agents" % N)
        harness.poll(lambda: len(group.heard()) == HOSTED and min(group.heard().values()) >= N - 1, 60,
                     "every hosted agent to hear the %d others" % (N - 1))
        self.assertEqual(sup.command("start"), 1)
        self.assertTrue(sup.wait_converged(60), "the circle converges")
        m = sup.metrics()
        self.assertEqual(m["agents"], N)
        self.assertEqual(m["clusters"], N, "every agent apart from the others")
        self.assert_all_alive([group] + singles)

        batches = self.echo("shapeform/state_batch", 3)
        for b in batches:
            self.assertEqual(b["event"], "sample", b)
            self.assertEqual(b["data"]["first_id"], 0)
            self.assertEqual([s["id"] for s in b["data"]["states"]], list(range(HOSTED)))
            self.assertEqual(len({s["seq"] for s in b["data"]["states"]}), 1, "one tick per batch")
        self.assertEqual(len({b["source"] for b in batches}), 1, "from the group's one participant")
        # A fresh reader may match one single agent's writer a moment before the other's, so its first
        # samples can all be one agent's: read until both are heard, and never a hosted agent.
        heard = set()

        def both_single_agents_heard():
            ids = {s["data"]["id"] for s in self.echo("shapeform/state", 50)}
            self.assertLessEqual(ids, set(range(HOSTED, N)), "shapeform/state carries the single agents only")
            heard.update(ids)
            return heard == set(range(HOSTED, N))
        harness.poll(both_single_agents_heard, 60, "an echo of shapeform/state to hear both single agents")

        # The hosted agents' statuses travel as one AgentStatusBatch per status period (agents 0..5 in one
        # sample, stamped once), a period apart (1 s: agent.status_rate_hz); the supervisor heard them
        # (`wait agents` above waits for every agent's status to report the others). shapeform/status
        # carries the single agents' only.
        status_batches = [b for b in self.echo("shapeform/status_batch", 3) if b["event"] == "sample"]
        self.assertEqual(len(status_batches), 3, status_batches)
        for b in status_batches:
            self.assertEqual(b["data"]["first_id"], 0)
            self.assertEqual([st["id"] for st in b["data"]["statuses"]], list(range(HOSTED)))
            self.assertEqual(len({st["stamp_ns"] for st in b["data"]["statuses"]}), 1, "one period per batch")
            self.assertTrue(all(st["neighbours_heard"] == N - 1 for st in b["data"]["statuses"]), b)
        stamps = [b["data"]["statuses"][0]["stamp_ns"] for b in status_batches]
        gaps = [b - a for a, b in zip(stamps, stamps[1:])]
        self.assertTrue(all(g > 0.5e9 for g in gaps), "one batch a period: gaps %s ns" % gaps)
        singles_status = {st["data"]["id"] for st in self.echo("shapeform/status", 2 * SINGLE) if st["event"] == "sample"}
        self.assertLessEqual(singles_status, set(range(HOSTED, N)), "shapeform/status carries the single agents only")

        before = {a.name: a.mark() for a in singles}
        group.signal(signal.SIGTERM)
        self.assertEqual(group.wait(30), 0, "the group process stops cleanly")
        harness.poll(lambda: sup.metrics()["agents"] == SINGLE, 30, "the supervisor to drop the hosted agents")
        # Disposed, not timed out: the supervisor says each one left.
        self.assertEqual(sup.left(), set(range(HOSTED)))
        for a in singles:
            harness.poll(lambda a=a: a.hears(SINGLE - 1, before[a.name]), 30,
                         "%s to hear only the other single agent" % a.name)
        self.assert_all_alive(singles)

    def test_group_in_parts_of_batch_max_states(self):
        # agent.batch_max_states 4: the 6 hosted agents go in 2 samples per tick (0..2 and 3..5, cut
        # evenly), each its own instance keyed by its first id, and the swarm is the same one swarm.
        config = harness.scenario("circle")
        sets = ["--set", "swarm.agents=%d" % N]
        sup = self.start_supervisor(config, extra=sets)
        group = self.start_group("0-%d" % (HOSTED - 1), config, sets + ["--set", "agent.batch_max_states=4"])
        singles = self.start_agents(SINGLE, config, seed=1, extra=sets, first=HOSTED)
        self.assertTrue(sup.wait_agents(N, 60), "the supervisor hears all %d agents" % N)
        harness.poll(lambda: len(group.heard()) == HOSTED and min(group.heard().values()) >= N - 1, 60,
                     "every hosted agent to hear the %d others" % (N - 1))
        for a in singles:
            harness.poll(lambda a=a: a.hears(N - 1), 60, "%s to hear the %d others" % (a.name, N - 1))
        self.assertEqual(sup.command("start"), 1)
        self.assertTrue(sup.wait_converged(60), "the circle converges")
        batches = self.echo("shapeform/state_batch", 6)
        parts = {}
        for b in batches:
            self.assertEqual(b["event"], "sample", b)
            parts.setdefault(b["data"]["first_id"], []).append([s["id"] for s in b["data"]["states"]])
        self.assertEqual(set(parts), {0, 3}, "two instances, keyed 0 and 3")
        self.assertTrue(all(ids == [0, 1, 2] for ids in parts[0]), parts)
        self.assertTrue(all(ids == [3, 4, 5] for ids in parts[3]), parts)

        group.signal(signal.SIGTERM)
        self.assertEqual(group.wait(30), 0, "the group process stops cleanly")
        harness.poll(lambda: sup.metrics()["agents"] == SINGLE, 30, "the supervisor to drop the hosted agents")
        # Both instances disposed, not timed out: the supervisor says each of the 6 left.
        self.assertEqual(sup.left(), set(range(HOSTED)))
        self.assert_all_alive(singles)

    def echo(self, topic, count):
        """count samples of topic as shapeform_echo prints them."""
        r = harness.procs.run([harness.bin_path("shapeform_echo"), topic, "--domain", str(self.domain), "--count",
                               str(count), "--timeout", "20"], timeout=40, check=False)
        self.assertEqual(r.returncode, 0, r.stderr)
        return harness.procs.json_lines(r.stdout)

    def test_bad_ids_exit_2(self):
        for ids in ("5-2", "1,1", "x", "0-10000", ""):
            r = subprocess.run([harness.bin_path("shapeform_agent_group"), "--ids", ids, "--domain",
                                str(self.domain)], capture_output=True, text=True, timeout=30)
            self.assertEqual(r.returncode, 2, "--ids %r: %s" % (ids, r.stderr))
            self.assertIn("--ids", r.stderr, "--ids %r" % ids)


if __name__ == "__main__":
    harness.main()
