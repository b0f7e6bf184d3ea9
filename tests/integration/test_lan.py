#!/usr/bin/env python3
"""The swarm on a LAN of test hosts (network namespaces on one private bridge, scripts/netlab.sh): every
process runs the lan profile bound to its host's address.

Run directly (root): test_lan.py --bin build/bin --source . --domain 3 [unittest args]
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402

AGENT_HOSTS = ("h1", "h2", "h3")  # 4 agents each; the supervisor on h4
PER_HOST = 4


class LanTest(harness.LanSwarmTestCase):

    def start_lan_swarm(self, config, extra=()):
        """The supervisor on h4 and agents 0..11 on h1..h3 (seed 1); `start` once all 12 are heard."""
        sup = self.start_supervisor(config, record=os.path.join(self.run_dir, "record"), extra=extra, host="h4")
        agents = []
        for k, host in enumerate(AGENT_HOSTS):
            for i in range(k * PER_HOST, (k + 1) * PER_HOST):
                agents.append(self.start_agent(i, config, seed=1, extra=extra, host=host))
        n = len(agents)
        self.assertTrue(sup.wait_agents(n, 60), "the supervisor on h4 hears all %d agents" % n)
        self.assertEqual(sup.command("start"), 1)
        return sup, agents

    def test_circle_across_hosts(self):
        # 3 hosts of 4 agents, the supervisor on a 4th: the paper's circle reaches the simulator's plateau.
        circle = harness.scenario("circle")
        sim = self.run_sim(circle, ["--steps", "500"])
        sup, agents = self.start_lan_swarm(circle)
        harness.poll(lambda: all(a.hears(11) for a in agents), 30, "every agent to hear the 11 others")
        self.assertTrue(sup.wait_converged(120), "the swarm converges")
        m = sup.metrics()
        self.assertLessEqual(abs(m["shape_error_mean"] - sim["shape_error_mean"]), 0.02,
                             "processes %.4f, simulator %.4f" % (m["shape_error_mean"], sim["shape_error_mean"]))
        self.assertLessEqual(m["gap_cv"], 0.10)
        self.assert_all_alive(agents + [sup])


if __name__ == "__main__":
    harness.main()
