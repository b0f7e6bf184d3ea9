#!/usr/bin/env python3
"""shapeform_view's Foxglove WebSocket server, read by a client written by others.

A 6-agent lockstep swarm with the supervisor recording, and `shapeform_view --foxglove-port 0 --json`
(no page: no --port). tests/npm/foxglove_client.mjs (FoxgloveClient of @foxglove/ws-protocol over `ws`,
from build/npm) connects two clients at once, one per subprotocol (foxglove.sdk.v1 and the older
foxglove.websocket.v1), subscribes each to the scene (foxglove.SceneUpdate, json) and to shapeform/state
(cdr, decoded with the advertised omgidl schema by @foxglove/omgidl-serialization), and prints what it got.
The test checks: both clients got scene frames with every agent drawn in frame "shapeform" and state
samples; a client asking for no Foxglove subprotocol is refused; an op the server does not serve gets a
status; every decoded state with a recorded row of that agent at its model time equals it within 1e-9,
or that row holds the state received a step before or after it (the supervisor labels a row with the
slowest agent's model time, test_view.py says why), and most are equal. Then the same scene channel from `--replay` of the recording.
"""
import json
import os
import shutil
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402
from harness import bin_path, read_csv  # noqa: E402

AGENTS = 6
EXACT = 1e-9


class FoxgloveTest(harness.SwarmTestCase):

    def client(self, url, topics, count, name, timeout=60):
        """Runs the node client to the end; returns its JSON lines (AssertionError with its stderr when it fails)."""
        npm = os.path.join(os.path.dirname(harness.CONFIG["bin"]), "npm")
        self.assertTrue(os.path.isdir(os.path.join(npm, "node_modules", "@foxglove", "ws-protocol")),
                        "the npm validators are missing in %s: run scripts/install_deps.sh" % npm)
        node = shutil.which("node")
        self.assertIsNotNone(node, "node is not installed: run scripts/install_deps.sh")
        script = os.path.join(harness.CONFIG["source"], "tests", "npm", "foxglove_client.mjs")
        r = harness.procs.run([node, script, "--url", url, "--npm", npm, "--topics", ",".join(topics),
                               "--count", str(count), "--timeout", str(timeout), "--refused-check"],
                              timeout=timeout + 30, check=False)
        with open(os.path.join(self.run_dir, name + ".jsonl"), "w") as f:
            f.write(r.stdout)
        self.assertEqual(r.returncode, 0, "the Foxglove client failed: " + r.stderr[-2000:])
        return [json.loads(line) for line in r.stdout.splitlines() if line.strip()]

    def test_live_and_replay(self):
        help_text = harness.procs.run([bin_path("shapeform_view"), "--help"], timeout=10).stdout
        for word in ("--foxglove-port", "foxglove.sdk.v1", "shapeform/scene"):
            self.assertIn(word, help_text)
        config = harness.scenario("circle")
        extra = [a for s in ("agent.sync=lockstep", "supervisor.agent_timeout_s=5") for a in ("--set", s)]
        record = os.path.join(self.run_dir, "record")
        view = self.start("view", [bin_path("shapeform_view"), "--foxglove-port", "0", "--json", "--config", config,
                                   "--domain", str(self.domain)] + extra)
        start = view.wait_event("start", 20)
        self.assertNotIn("url", start, "no page without --port")
        self.assertEqual(start["foxglove_url"], "ws://127.0.0.1:%d" % start["foxglove_port"])
        sup, agents = self.start_commanded_swarm(AGENTS, config, extra=extra, record=record)

        lines = self.client(start["foxglove_url"], ["shapeform/scene", "shapeform/state"], 15 * AGENTS, "live")
        self.assertTrue(any(e["event"] == "refused" for e in lines), "a client without a Foxglove subprotocol is refused")
        self.assertTrue(any(e["event"] == "status" and e["level"] == 2 and "not supported" in e["message"] for e in lines),
                        "an op the server does not serve gets an error status")
        advertised = next(e for e in lines if e["event"] == "advertise")["channels"]
        by_topic = {c["topic"]: c for c in advertised}
        self.assertEqual(by_topic["shapeform/scene"]["schemaName"], "foxglove.SceneUpdate")
        for topic, schema in (("shapeform/state", "shapeform::msg::AgentState"),
                              ("shapeform/state_batch", "shapeform::msg::AgentStateBatch"),
                              ("shapeform/status_batch", "shapeform::msg::AgentStatusBatch"),
                              ("shapeform/command", "shapeform::msg::ShapeCommand")):
            self.assertEqual((by_topic[topic]["encoding"], by_topic[topic]["schemaEncoding"], by_topic[topic]["schemaName"]),
                             ("cdr", "omgidl", schema))
        messages = [e for e in lines if e["event"] == "message"]
        self.assertEqual({e["protocol"] for e in messages}, {"foxglove.sdk.v1", "foxglove.websocket.v1"})
        states = []
        for client in (0, 1):
            scene = [e for e in messages if e["client"] == client and e["topic"] == "shapeform/scene"]
            self.assertGreaterEqual(len(scene), 15 * AGENTS, "client %d: scene frames" % client)
            self.assertTrue(all(e["frame_id"] == "shapeform" for e in scene))
            self.assertTrue(any(len(e["spheres"]) == AGENTS for e in scene), "client %d: a frame with every agent" % client)
            got = [s for e in messages if e["client"] == client and e["topic"] == "shapeform/state" for s in e["states"]]
            self.assertGreaterEqual(len(got), 15 * AGENTS, "client %d: decoded states" % client)
            states += got

        sup.stop()  # flushes the recording
        harness.procs.stop_all(agents, grace=5.0)
        rows = {}
        for r in read_csv(os.path.join(record, "positions.csv"), numeric=True):
            rows.setdefault(int(r["agent"]), {})[r["model_time"]] = (r["x1"], r["x2"])
        dt = 1.0  # the circle scenario's integration.dt
        received = {(st["id"], st["model_time"]): (st["x"], st["y"]) for st in states}
        same = lambda a, b: abs(a[0] - b[0]) <= EXACT and abs(a[1] - b[1]) <= EXACT  # noqa: E731
        exact, near, compared = 0, 0, 0
        for (i, t), pos in sorted(received.items()):
            row = rows.get(i, {}).get(t)
            if row is None:
                continue  # the supervisor records at its own rate, not every step
            compared += 1
            if same(row, pos):
                exact += 1
                continue
            # A row labelled a step off holds the agent's state of the step before or after.
            off = [received.get((i, t + k * dt)) for k in (-1, 1)]
            self.assertTrue(any(o is not None and same(row, o) for o in off),
                            "agent %d at model time %g received at (%r, %r), recorded at (%r, %r), and that row is "
                            "neither state received a step before or after (%r)" % (i, t, pos[0], pos[1], row[0], row[1], off))
            near += 1
        sys.stderr.write("states: %d compared with the recorded row of their model time: %d equal, %d a step off\n"
                         % (compared, exact, near))
        self.assertGreaterEqual(compared, 2 * AGENTS, "received states with a recorded row at their model time")
        self.assertGreater(exact, near, "most states equal the row of their own model time")
        view.stop()
        stop = view.wait_event("stop", 10)
        self.assertGreater(stop["foxglove"]["messages_sent"], 0)
        self.assertEqual(stop["foxglove"]["connections"], 2)

        # -- the same scene channel from a replay of the recording
        replay = self.start("replay", [bin_path("shapeform_view"), "--replay", record, "--foxglove-port", "0", "--json"])
        start = replay.wait_event("start", 20)
        self.assertEqual(start["mode"], "replay")
        # Playing from the recording's first row (of any table): the agents come within seconds.
        lines = self.client(start["foxglove_url"], ["shapeform/scene"], 60, "replay")
        topics = {c["topic"] for e in lines if e["event"] == "advertise" for c in e["channels"]}
        self.assertEqual(topics, {"shapeform/scene", "shapeform/agent_poses"}, "replay: the scene's channels only")
        scene = [e for e in lines if e["event"] == "message"]
        self.assertTrue(any(len(e["spheres"]) == AGENTS for e in scene), "replay: every recorded agent drawn")
        replay.stop()


if __name__ == "__main__":
    harness.main()
