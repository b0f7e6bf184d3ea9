#!/usr/bin/env python3
"""The traffic tools on a running swarm (3 agent processes and a supervisor).

- `shapeform_topics --json` lists the five topics, each with its type, its writers and readers
  (participant name, host, pid) and their QoS as the topic table declares it.
- `shapeform_echo shapeform/state --count 5` prints 5 JSON lines, one sample each, and exits 0; the
  command topic gives the command in force at once (transient-local); metrics come through too.
- A shapeform_echo listed among a LAN swarm's processes (scripts/lib/lanswarm.py) is stopped with it
  and exits 0.
- A shapeform_echo printing thousands of samples a second (four publishers at 1000 Hz) exits 0 within
  10 s of its SIGTERM, its output whole JSON lines (measured: within 0.25 s, also with the publishers
  stopped at the same instant and the host loaded).
- Bad arguments (an unknown topic, a negative count, a missing topic, a negative wait): a message
  and exit status 2, without joining any domain.
"""
import json
import os
import signal
import socket
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402

AGENTS = 3
SETS = ["--set", "swarm.agents=%d" % AGENTS]
TOPICS = {  # name: (type, reliability, durability), as the rows of common/dds/topic_table.hpp declare them
    "shapeform/state": ("shapeform::msg::AgentState", "best_effort", "volatile"),
    "shapeform/state_batch": ("shapeform::msg::AgentStateBatch", "best_effort", "volatile"),
    "shapeform/command": ("shapeform::msg::ShapeCommand", "reliable", "transient_local"),
    "shapeform/target": ("shapeform::msg::TrackingTarget", "best_effort", "volatile"),
    "shapeform/metrics": ("shapeform::msg::SwarmMetrics", "reliable", "volatile"),
    "shapeform/status": ("shapeform::msg::AgentStatus", "reliable", "volatile"),
    "shapeform/status_batch": ("shapeform::msg::AgentStatusBatch", "reliable", "volatile"),
}
AGENT_NAMES = {"shapeform_agent_%d" % i for i in range(AGENTS)}


def run(argv, timeout=60):
    return harness.procs.run([str(a) for a in argv], timeout=timeout, check=False)


class ToolsTest(harness.SwarmTestCase):

    def topics(self):
        r = run([harness.bin_path("shapeform_topics"), "--domain", self.domain, "--json", "--wait", "2"])
        self.assertEqual(r.returncode, 0, r.stderr)
        found = harness.procs.events(r.stdout, "topic")
        self.assertEqual(len(found), len(harness.procs.json_lines(r.stdout)), "only topic lines")
        return {t["name"]: t for t in found}

    def echo(self, topic, count):
        r = run([harness.bin_path("shapeform_echo"), topic, "--domain", self.domain, "--count", count,
                 "--timeout", "30"])
        self.assertEqual(r.returncode, 0, r.stderr)
        lines = r.stdout.splitlines()
        self.assertEqual(len(lines), count, r.stdout)
        return [json.loads(line) for line in lines]

    def test_topics_and_echo_on_a_running_swarm(self):
        # A tracked scenario, so that the target topic has a writer too.
        config = harness.scenario("track_circle")
        sup, agents = self.start_commanded_swarm(AGENTS, config, SETS)

        def complete():
            t = self.topics()
            writers = {n: {w["participant"] for w in t[n]["writers"]} for n in t}
            return t if set(t) == set(TOPICS) and writers["shapeform/state"] == AGENT_NAMES \
                and writers["shapeform/target"] == {"shapeform_supervisor"} \
                and writers["shapeform/command"] == AGENT_NAMES | {"shapeform_supervisor"} else None
        topics = harness.poll(complete, 60, "shapeform_topics to see the seven topics and every writer", 0.5)
        host = socket.gethostname()
        pids = {"shapeform_supervisor": sup.pid}
        pids.update({"shapeform_agent_%d" % i: a.pid for i, a in enumerate(agents)})
        for name, (type_name, reliability, durability) in TOPICS.items():
            t = topics[name]
            self.assertEqual(t["types"], [type_name], name)
            for e in t["writers"] + t["readers"]:
                self.assertEqual((e["reliability"], e["durability"], e["type"]), (reliability, durability, type_name),
                                 "%s: %s" % (name, e))
                self.assertEqual(e["host"], host)
                self.assertEqual(e["pid"], pids[e["participant"]], e)
        participants = {n: ({w["participant"] for w in t["writers"]}, {r["participant"] for r in t["readers"]})
                        for n, t in topics.items()}
        sup_name = {"shapeform_supervisor"}
        self.assertEqual(participants["shapeform/state"], (AGENT_NAMES, AGENT_NAMES | sup_name))
        # One-agent processes publish no batches; every reader of state also reads batches.
        self.assertEqual(participants["shapeform/state_batch"], (set(), AGENT_NAMES | sup_name))
        # Every agent re-offers the command it follows; the supervisor reads the topic for the command in force.
        self.assertEqual(participants["shapeform/command"], (sup_name | AGENT_NAMES, AGENT_NAMES | sup_name))
        self.assertEqual(participants["shapeform/target"], (sup_name, AGENT_NAMES))
        self.assertEqual(participants["shapeform/metrics"], (sup_name, set()))
        self.assertEqual(participants["shapeform/status"], (AGENT_NAMES, sup_name))
        self.assertEqual(participants["shapeform/status_batch"], (set(), sup_name))

        # Five state samples, as JSON lines with every field.
        for line in self.echo("shapeform/state", 5):
            self.assertEqual((line["event"], line["topic"]), ("sample", "shapeform/state"), line)
            d = line["data"]
            self.assertIn(d["id"], range(AGENTS))
            self.assertEqual(sorted(d), sorted(["id", "seq", "stamp_ns", "epoch", "issuer", "model_time", "x", "v",
                                                "arc", "prev_x", "prev_arc"]))
            self.assertEqual(len(d["x"]), 2)
        # The command in force at once (transient-local), with its keys as the config file has them.
        [command] = self.echo("shapeform/command", 1)
        self.assertEqual(command["data"]["epoch"], 1)
        self.assertEqual(command["data"]["shape"]["kind"], "circle")
        self.assertTrue(command["data"]["tracking"]["enabled"])
        self.assertFalse(command["data"]["dynamics"]["hold"])
        for line in self.echo("shapeform/metrics", 2) + self.echo("shapeform/target", 2) + \
                self.echo("shapeform/status", 2):
            self.assertEqual(line["event"], "sample", line)
            self.assertEqual(line["data"]["epoch"], 1, line)
        self.assert_all_alive(agents + [sup])
        sup.send("quit")
        self.assertEqual(sup.wait(20), 0)

    def test_echo_stops_with_a_lan_swarm(self):
        # scripts/lib/lanswarm.py's stop() on a swarm whose processes include a measuring shapeform_echo
        # (as scripts/reliability.py adds one): every process it lists gets its SIGTERM, together, and
        # exits 0 within the grace period; none is left running. Loopback stands in for the test hosts.
        import lanswarm  # scripts/lib, on the path through harness
        sup, agents = self.start_commanded_swarm(AGENTS, harness.scenario("circle"), SETS)
        echo = self.start("echo_status", [harness.bin_path("shapeform_echo"), "shapeform/status", "--domain",
                                          self.domain])
        harness.poll(lambda: harness.procs.json_lines(echo.out()), 60, "shapeform_echo to print a status sample")
        swarm = lanswarm.LanSwarm(None, harness.CONFIG["bin"], None, self.domain, self.run_dir)
        swarm.sup, swarm.agents = sup, dict(enumerate(agents))
        swarm.procs = [sup] + agents + [echo]
        codes = swarm.stop()
        self.assertEqual(codes, {p.name: 0 for p in swarm.procs}, "exit statuses (None: still running)")

    def test_echo_exits_on_sigterm_while_busy(self):
        # No swarm: four test publishers of agent states at 1000 Hz each keep the echo printing and
        # flushing line after line when its SIGTERM comes. 8 participant slots: this test's domain may be
        # 232, where the ports of slots past 62 would pass 65535.
        slots = ["--set", "transport.max_participants=8"]
        pubs = [self.start("pub_%d" % i, [harness.bin_path("shapeform_rogue_publisher"), "--domain", self.domain,
                                          "--topic", "state", "--field", "id=%d" % i, "--count", "1000000",
                                          "--rate", "1000"] + slots) for i in range(4)]
        echo = self.start("echo_busy", [harness.bin_path("shapeform_echo"), "shapeform/state", "--domain",
                                        self.domain] + slots)
        harness.poll(lambda: echo.out().count("\n") >= 4000, 60, "shapeform_echo to print 4000 samples")
        self.assert_all_alive(pubs + [echo])
        echo.signal(signal.SIGTERM)
        harness.poll(lambda: echo.returncode is not None, 10, "shapeform_echo to exit within 10 s of its SIGTERM", 0.05)
        self.assertEqual(echo.returncode, 0, echo.log())
        out = echo.out()
        self.assertTrue(out.endswith("\n"), "the last line is whole")
        self.assertEqual({e["event"] for e in harness.procs.json_lines(out)}, {"sample"})
        self.assertEqual(len(harness.procs.json_lines(out)), out.count("\n"), "every line is JSON")
        harness.procs.stop_all(pubs, grace=10.0)

    def test_bad_arguments(self):
        bad = [
            (["shapeform_echo", "shapeform/nope"], "unknown topic 'shapeform/nope'"),
            (["shapeform_echo"], "topic"),
            (["shapeform_echo", "shapeform/state", "--count", "-1"], "count"),
            (["shapeform_topics", "--wait", "-1"], "wait"),
            (["shapeform_topics", "--frobnicate"], "frobnicate"),
        ]
        for argv, message in bad:
            r = run([harness.bin_path(argv[0])] + argv[1:] + ["--domain", self.domain], timeout=20)
            self.assertEqual(r.returncode, 2, "%s: %s" % (argv, r.stderr))
            self.assertIn(message, r.stderr, argv)
            self.assertEqual(r.stdout, "", argv)
        # The unknown topic's message names the topics there are.
        r = run([harness.bin_path("shapeform_echo"), "shapeform/nope", "--domain", self.domain], timeout=20)
        for name in TOPICS:
            self.assertIn(name, r.stderr)
        for prog in ("shapeform_echo", "shapeform_topics"):
            r = run([harness.bin_path(prog), "--help"], timeout=20)
            self.assertEqual(r.returncode, 0)
            self.assertIn("--domain", r.stdout)


if __name__ == "__main__":
    harness.main()
