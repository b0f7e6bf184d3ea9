#!/usr/bin/env python3
"""The ROS 2 mirror (ros2.mirror; docs/ROS2.md) on a running swarm of 3 agent processes.

- On: the supervisor writes `rt/shapeform/agents` with the registered type name
  `geometry_msgs::msg::dds_::PoseArray_` and `rt/shapeform/markers` with
  `visualization_msgs::msg::dds_::MarkerArray_`, reliable and volatile (what `ros2 topic echo` and
  rviz2 subscribe with); a subscriber with those types (shapeform_echo) receives poses in frame `map`,
  one per agent in ascending id, each within one step of a state that agent published itself (the
  agents' own shapeform/state samples, read from before the first pose until after the last); the
  markers carry a sphere and an id text per agent and the commanded outline as a closed line strip.
- Off (the default): the swarm runs and nothing is written on either topic.
"""
import json
import math
import os
import signal
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402

AGENTS = 3
SETS = ["--set", "swarm.agents=%d" % AGENTS]
MIRROR = {"rt/shapeform/agents": "geometry_msgs::msg::dds_::PoseArray_",
          "rt/shapeform/markers": "visualization_msgs::msg::dds_::MarkerArray_"}


def run(argv, timeout=60):
    return harness.procs.run([str(a) for a in argv], timeout=timeout, check=False)


class Ros2MirrorTest(harness.SwarmTestCase):

    def topics(self):
        r = run([harness.bin_path("shapeform_topics"), "--domain", self.domain, "--json", "--wait", "2"])
        self.assertEqual(r.returncode, 0, r.stderr)
        return {t["name"]: t for t in harness.procs.events(r.stdout, "topic")}

    def swarm(self, supervisor_sets):
        config = harness.scenario("circle")
        sup = self.start_supervisor(config, extra=SETS + supervisor_sets)
        agents = self.start_agents(AGENTS, config, seed=1, extra=SETS)
        self.assertTrue(sup.wait_agents(AGENTS, 60), "the supervisor hears every agent")
        self.assertEqual(sup.command("start"), 1)
        return sup, agents

    def test_mirror_on(self):
        sup, agents = self.swarm(["--set", "ros2.mirror=true"])

        def seen():
            t = self.topics()
            return t if all(n in t and t[n]["writers"] for n in MIRROR) else None
        topics = harness.poll(seen, 60, "shapeform_topics to see the mirror's two topics with a writer", 0.5)
        for name, type_name in MIRROR.items():
            t = topics[name]
            self.assertEqual(t["types"], [type_name], name)
            self.assertEqual([w["participant"] for w in t["writers"]], ["shapeform_supervisor"], name)
            for w in t["writers"]:
                self.assertEqual((w["reliability"], w["durability"], w["type"]), ("reliable", "volatile", type_name))

        # The agents' own states, from well before the first pose is read until after the last one. The
        # mirror publishes the supervisor's latest view, which a loaded host can delay by a few steps: the
        # states begin 25 per agent (half a second at 50 Hz) before the poses are read, and a fixed count of
        # states could end before a slow subscriber's poses begin.
        states = self.start("echo_state", [harness.bin_path("shapeform_echo"), "shapeform/state", "--domain",
                                           self.domain])
        harness.poll(lambda: len(harness.procs.json_lines(states.out())) >= 25 * AGENTS, 60,
                     "shapeform_echo to print 25 states per agent")
        r = run([harness.bin_path("shapeform_echo"), "rt/shapeform/agents", "--domain", self.domain,
                 "--count", 5, "--timeout", "30"])
        self.assertEqual(r.returncode, 0, r.stderr)
        poses = [json.loads(line) for line in r.stdout.splitlines()]
        states.signal(signal.SIGTERM)
        self.assertEqual(states.wait(30), 0, states.log())
        by_id = {}
        for line in harness.procs.json_lines(states.out()):
            by_id.setdefault(line["data"]["id"], []).append(line["data"]["x"])
        self.assertEqual(sorted(by_id), list(range(AGENTS)))
        worst = 0.0  # the largest distance of a pose from its agent's nearest state, in steps
        for line in poses:
            self.assertEqual((line["event"], line["topic"]), ("sample", "rt/shapeform/agents"), line)
            d = line["data"]
            self.assertEqual(d["frame_id"], "map")
            self.assertGreater(d["stamp_ns"], 1.6e18, "a system-clock stamp (ROS time)")
            self.assertEqual(len(d["poses"]), AGENTS, d)
            for i, pose in enumerate(d["poses"]):  # ascending id: pose i is agent i
                xs = by_id[i]
                step = max(math.dist(a, b) for a, b in zip(xs, xs[1:]))
                self.assertGreater(step, 0.0, "agent %d moves while it is compared (forming)" % i)
                nearest = min(math.dist(pose["x"], x) for x in xs)
                self.assertLessEqual(nearest, step + 1e-9,
                                     "agent %d: pose %s is %.4g from its nearest state (one step: %.4g)"
                                     % (i, pose["x"], nearest, step))
                worst = max(worst, nearest / step)
                self.assertEqual(pose["z"], 0.0)
                self.assertIsNotNone(pose["yaw"])
        sys.stderr.write("ros2_mirror_on: %d poses of %d samples within %.3g steps of their agents' states\n"
                         % (AGENTS * len(poses), len(poses), worst))

        r = run([harness.bin_path("shapeform_echo"), "rt/shapeform/markers", "--domain", self.domain,
                 "--count", 1, "--timeout", "30"])
        self.assertEqual(r.returncode, 0, r.stderr)
        markers = json.loads(r.stdout.splitlines()[0])["data"]["markers"]
        self.assertEqual(markers[0]["action"], 3, "DELETEALL first")
        self.assertEqual(sorted(m["id"] for m in markers if m["ns"] == "agents"), list(range(AGENTS)))
        self.assertEqual(sorted(m["text"] for m in markers if m["ns"] == "agent_ids"),
                         [str(i) for i in range(AGENTS)])
        [outline] = [m for m in markers if m["ns"] == "outline"]
        self.assertEqual(outline["type"], 4)
        self.assertEqual(len(outline["points"]), 241)
        self.assertEqual(outline["points"][0], outline["points"][-1], "closed")
        for m in markers:
            self.assertEqual(m["frame_id"], "map")
        self.assert_all_alive(agents + [sup])
        sup.send("quit")
        self.assertEqual(sup.wait(20), 0)

    def test_mirror_off(self):
        sup, agents = self.swarm([])

        def ready():
            t = self.topics()
            return t if "shapeform/metrics" in t and t["shapeform/metrics"]["writers"] else None
        topics = harness.poll(ready, 60, "shapeform_topics to see the supervisor's metrics writer", 0.5)
        for name in MIRROR:
            self.assertNotIn(name, topics)
        # A subscriber hears nothing either.
        r = run([harness.bin_path("shapeform_echo"), "rt/shapeform/agents", "--domain", self.domain,
                 "--count", 1, "--timeout", "3"])
        self.assertEqual(r.returncode, 1, r.stdout)
        self.assertEqual(r.stdout, "")
        self.assert_all_alive(agents + [sup])
        sup.send("quit")
        self.assertEqual(sup.wait(20), 0)


if __name__ == "__main__":
    harness.main()
