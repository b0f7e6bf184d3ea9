#!/usr/bin/env python3
"""Recordings a user can read (docs/RECORDING.md), and scripts/plot_run.py on them.

One 4-agent arc_circle swarm, its centre tracked along a slow line, recorded by the supervisor; `hold`
publishes epoch 2:
- commands.csv holds both commands in full, with the supervisor's GUID prefix as issuer; the epoch-1
  command is the one shapeform_sim --record writes for the same configuration, and its --set settings
  rebuild it exactly (fed back to shapeform_sim, they are recorded identically); the hold is recorded
  (dynamics.hold);
- positions.csv carries for every agent the epoch it follows: 1, then 2 (never back), each epoch's rows
  after that command came in force; centre.csv holds C(t) = C(0) + v t of epoch 1;
- every column of the four files is documented in docs/RECORDING.md;
- plot_run.py draws it (and a simulator recording): non-trivial PNGs and a GIF of several frames; a
  missing file or column exits 2 naming it.
"""
import csv
import json
import os
import re
import shutil
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402

AGENTS = 4
VELOCITY = 0.01  # shape units per model time: the tracked centre's drift along x1
SETS = ["--set", "swarm.agents=%d" % AGENTS, "--set", "tracking.enabled=true", "--set", "tracking.path=line",
        "--set", "tracking.velocity=[%r, 0]" % VELOCITY, "--set", "tracking.feedforward=true"]
FILES = ("metrics.csv", "positions.csv", "commands.csv", "centre.csv")


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def header(path):
    with open(path, newline="") as f:
        return next(csv.reader(f))


def commands(record):
    return {int(r["epoch"]): r for r in rows(os.path.join(record, "commands.csv"))}


def set_args(command):
    return [a for k, v in json.loads(command).items() for a in ("--set", "%s=%s" % (k, v))]


class RecordingTest(harness.SwarmTestCase):

    def sim_record(self, name, args):
        """shapeform_sim --record into a fresh folder of the run; returns the folder."""
        out = os.path.join(self.run_dir, name)
        harness.procs.run([harness.bin_path("shapeform_sim"), "--record", out] + list(args), timeout=60)
        return out

    def plot(self, run_dir, out, *extra):
        script = os.path.join(harness.CONFIG["source"], "scripts", "plot_run.py")
        return subprocess.run([sys.executable, script, run_dir, "--out", out, "--sim",
                               harness.bin_path("shapeform_sim")] + list(extra),
                              capture_output=True, text=True, timeout=120, stdin=subprocess.DEVNULL)

    def assert_figures(self, out, names):
        from PIL import Image  # Debian's python3-pil, which plot_run.py needs too
        for name in names:
            path = os.path.join(out, name)
            self.assertTrue(os.path.isfile(path), path)
            with Image.open(path) as im:
                self.assertGreaterEqual(min(im.size), 300, path)
                frames = getattr(im, "n_frames", 1)
                if name.endswith(".gif"):
                    self.assertGreater(frames, 5, "%s: an animation" % path)
                colours = im.convert("RGB").getcolors(1 << 20)
                self.assertGreater(len(colours), 20, "%s: more than a blank canvas" % path)

    def test_record_and_plot(self):
        config = harness.scenario("arc_circle")
        record = os.path.join(self.run_dir, "record")
        sup, agents = self.start_commanded_swarm(AGENTS, config, SETS, record=record)
        self.assertTrue(sup.wait_until("time", "wait time 20 timeout=30", 30))
        e = sup.ask("hold", "epoch", what="the supervisor to publish hold")
        self.assertEqual((e["epoch"], e["hold"]), (2, True))
        pos_path = os.path.join(record, "positions.csv")

        def held_recorded():
            got = [r for r in harness.read_csv(pos_path) if r["epoch"] == "2"]
            return len({r["agent"] for r in got}) == AGENTS
        harness.poll(held_recorded, 30, "every agent recorded on the held epoch")
        sup.send("quit")
        self.assertEqual(sup.wait(20), 0)

        # commands.csv: both commands, in full, with their issuer.
        self.assertEqual(header(os.path.join(record, "commands.csv")),
                         ["wall_s", "model_time", "epoch", "issuer", "issuer_name", "command"])
        cmds = commands(record)
        self.assertEqual(sorted(cmds), [1, 2])
        for c in cmds.values():
            self.assertRegex(c["issuer"], r"^[0-9a-f]{2}(\.[0-9a-f]{2}){11}$")  # as the "epoch" events show it
            self.assertIn("shapeform_supervisor", c["issuer_name"])
            self.assertEqual(float(c["model_time"]), 0.0)
        first, held = json.loads(cmds[1]["command"]), json.loads(cmds[2]["command"])
        self.assertEqual((first["dynamics.hold"], held["dynamics.hold"]), ("false", "true"))
        self.assertEqual((first["shape.kind"], first["dynamics.law"], first["shape.r0"]), ("circle", "arc", "4.0"))
        # The same configuration in the simulator records the same command; its settings rebuild it.
        sim_rec = self.sim_record("sim_same", ["--config", config, "--steps", "0"] + SETS)
        self.assertEqual(json.loads(commands(sim_rec)[1]["command"]), first)
        rebuilt = self.sim_record("sim_rebuilt", ["--steps", "0"] + set_args(cmds[2]["command"]))
        self.assertEqual(commands(rebuilt)[1]["command"], cmds[2]["command"])

        # positions.csv: each agent's epoch goes 1 then 2, each epoch's rows after it came in force.
        self.assertEqual(header(pos_path), ["wall_s", "model_time", "step", "epoch", "agent", "x1", "x2"])
        pos = harness.read_csv(pos_path, numeric=True)
        since = {ep: float(c["wall_s"]) for ep, c in cmds.items()}
        for agent in range(AGENTS):
            epochs = [r["epoch"] for r in pos if r["agent"] == agent]
            self.assertEqual(sorted(set(epochs) - {0}), [1, 2], "agent %d (0: before any command)" % agent)
            self.assertEqual(epochs, sorted(epochs), "agent %d: epochs in order" % agent)
        for r in pos:
            if r["epoch"] != 0:
                self.assertGreaterEqual(r["wall_s"], since[r["epoch"]], r)
        # centre.csv: C(t) of epoch 1's line path (it starts at the scenario's centre, the origin).
        centre = harness.read_csv(os.path.join(record, "centre.csv"), numeric=True)
        self.assertGreater(len([r for r in centre if r["epoch"] == 1]), 10)
        for r in centre:
            self.assertEqual(r["epoch"], 1, "a held command publishes no target")
            self.assertAlmostEqual(r["c1"], VELOCITY * r["model_time"], delta=1e-9)
            self.assertEqual(r["c2"], 0.0)
        metrics = harness.read_csv(os.path.join(record, "metrics.csv"), numeric=True)
        self.assertEqual({r["epoch"] for r in metrics if r["agents_alive"] == AGENTS} - {0}, {1, 2})

        # Every column is documented.
        with open(os.path.join(harness.CONFIG["source"], "docs", "RECORDING.md")) as f:
            doc = f.read()
        for name in FILES:
            for col in header(os.path.join(record, name)):
                self.assertIn("`%s`" % col, doc, "docs/RECORDING.md: column %s of %s" % (col, name))

        # The plots: of this recording (with the animation), of a simulator recording.
        figures = os.path.join(self.run_dir, "figures")
        r = self.plot(self.run_dir, figures, "--animate")  # the run folder: its record/ is read
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertNotIn("not drawn", r.stderr)
        self.assert_figures(figures, ["formation.png", "trajectories.png", "metrics.png", "formation.gif"])
        sim_run = self.sim_record("sim_track", ["--config", harness.scenario("track_circle"), "--agents", "6",
                                                "--steps", "60"])
        self.assertEqual(len(harness.read_csv(os.path.join(sim_run, "centre.csv"))), 61)
        r = self.plot(sim_run, os.path.join(sim_run, "figures"))
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assert_figures(os.path.join(sim_run, "figures"), ["formation.png", "trajectories.png", "metrics.png"])

        # Bad input: exit 2, the missing file or column named.
        broken = os.path.join(self.run_dir, "broken")
        shutil.copytree(sim_run, broken)
        os.remove(os.path.join(broken, "positions.csv"))
        r = self.plot(broken, os.path.join(broken, "figures"))
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn(os.path.join(broken, "positions.csv"), r.stderr)
        shutil.copy(os.path.join(sim_run, "positions.csv"), broken)
        with open(os.path.join(broken, "metrics.csv")) as f:
            text = f.read()
        with open(os.path.join(broken, "metrics.csv"), "w") as f:
            f.write(re.sub(r"\bgap_cv\b", "gap_cv_renamed", text, count=1))
        r = self.plot(broken, os.path.join(broken, "figures"))
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn("no column gap_cv", r.stderr)
        r = self.plot(os.path.join(self.run_dir, "nowhere"), figures)
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn("nowhere", r.stderr)


    # -- run.mcap

    def mcap_check(self, path, decode=True):
        """tests/npm/mcap_check.mjs (readers by Foxglove and MCAP) on path: its JSON lines, or its summary
        object without decode. Fails (never skips) when node or the validators are missing."""
        npm = os.path.join(os.path.dirname(harness.CONFIG["bin"]), "npm", "node_modules")
        self.assertTrue(os.path.isdir(os.path.join(npm, "@mcap", "core")),
                        "the npm validators are missing in %s: run scripts/install_deps.sh" % npm)
        node = shutil.which("node")
        self.assertIsNotNone(node, "node is not installed: run scripts/install_deps.sh")
        script = os.path.join(harness.CONFIG["source"], "tests", "npm", "mcap_check.mjs")
        r = subprocess.run([node, script, path] + (["--decode"] if decode else []), capture_output=True, text=True,
                           timeout=120, env=dict(os.environ, SHAPEFORM_NPM=npm), stdin=subprocess.DEVNULL)
        self.assertEqual(r.returncode, 0, "mcap_check %s: %s" % (path, r.stderr[-2000:]))
        lines = [json.loads(l) for l in r.stdout.splitlines() if l.strip()]
        return lines if decode else lines[0]

    def mcap_tool(self, *args, check=True):
        return harness.procs.run([harness.bin_path("shapeform_mcap")] + list(args), timeout=60, check=check)

    def assert_positions_match(self, messages, record):
        """The shapeform/record/positions messages hold exactly the rows of positions.csv."""
        from_mcap = sorted((m["message"]["wall_s"], a["id"], a["epoch"], a["x1"], a["x2"])
                           for m in messages if m["topic"] == "shapeform/record/positions"
                           for a in m["message"]["agents"])
        from_csv = sorted((r["wall_s"], int(r["agent"]), int(r["epoch"]), r["x1"], r["x2"])
                          for r in harness.read_csv(os.path.join(record, "positions.csv"), numeric=True))
        self.assertGreater(len(from_csv), 50)
        self.assertEqual(from_mcap, from_csv)

    def test_run_mcap(self):
        config = harness.scenario("arc_circle")
        first, second = os.path.join(self.run_dir, "first"), os.path.join(self.run_dir, "second")
        sup, agents = self.start_commanded_swarm(AGENTS, config, SETS + ["--set", "agent.status_rate_hz=10"],
                                                 record=first)
        self.assertTrue(sup.wait_until("time", "wait time 60 timeout=60", 60))
        # A second recording closes the first (complete), then the supervisor is killed hard in it.
        self.assertTrue(sup.ask("record start " + second, "record")["open"])
        harness.poll(lambda: os.path.getsize(os.path.join(second, "run.mcap")) > 20000, 30,
                     "the second run.mcap to hold flushed chunks", 0.2)
        sup.kill_group()
        sup.wait(10)

        # The complete recording: every schema parses and every message decodes with the others' readers.
        summary = self.mcap_check(os.path.join(first, "run.mcap"), decode=False)
        self.assertEqual(summary["mode"], "indexed")
        for topic in ("shapeform/record/metrics", "shapeform/record/positions", "shapeform/record/commands",
                      "shapeform/record/centre", "shapeform/scene", "shapeform/agent_poses", "shapeform/state",
                      "shapeform/command", "shapeform/status", "shapeform/metrics", "shapeform/target",
                      "shapeform/events"):
            self.assertGreater(summary["per_topic"].get(topic, 0), 0, topic)
        messages = self.mcap_check(os.path.join(first, "run.mcap"))
        self.assert_positions_match(messages, first)
        # The agents' states as they came off the wire (CDR), decoded by Foxglove's omgidl reader, are the
        # states each agent reported itself at the same step.
        own = {}
        for a in agents:
            for e in a.events("status"):
                own[(e["id"], e["epoch"], e["model_time"])] = (e["x"], e["y"])
        matched = 0
        for m in messages:
            if m["topic"] != "shapeform/state":
                continue
            s = m["message"]
            key = (s["id"], int(s["epoch"]), s["model_time"])
            if key in own:
                self.assertEqual((s["x"], s["y"]), own[key], key)
                matched += 1
        self.assertGreater(matched, 10, "recorded states at the model times the agents reported")
        # The command in force and the tracked centre, as CDR and as the recorder's table.
        commands = [m["message"] for m in messages if m["topic"] == "shapeform/record/commands"]
        self.assertEqual([c["epoch"] for c in commands], [1])
        self.assertEqual(commands[0]["command"]["shape.kind"], "circle")
        for m in messages:
            if m["topic"] == "shapeform/record/centre":
                c = m["message"]
                self.assertAlmostEqual(c["c1"], VELOCITY * c["model_time"], delta=1e-9)
        scenes = [m["message"] for m in messages if m["topic"] == "shapeform/scene"]
        agents_drawn = [e for e in scenes[-1]["entities"] if e["id"] == "agents"][0]
        self.assertEqual(len(agents_drawn["spheres"]), AGENTS)
        self.assertEqual(agents_drawn["frame_id"], "shapeform")

        # The killed recording: no summary; the others' stream reader and ours keep every complete chunk.
        killed = os.path.join(second, "run.mcap")
        summary = self.mcap_check(killed, decode=False)
        self.assertEqual(summary["mode"], "stream")
        self.assertGreater(summary["per_topic"].get("shapeform/state", 0), 0)
        info = json.loads(self.mcap_tool("info", killed, "--json").stdout)
        self.assertFalse(info["complete"])
        recovered = os.path.join(self.run_dir, "recovered.mcap")
        self.mcap_tool("recover", killed, recovered)
        self.assertEqual(self.mcap_check(recovered, decode=False)["mode"], "indexed")
        self.assertEqual(self.mcap_check(recovered, decode=False)["messages"], summary["messages"])
        # Replay reads it as it is.
        view = self.start("view", [harness.bin_path("shapeform_view"), "--replay", killed, "--port", "0", "--json"])
        start = view.wait_event("start", 20)
        self.assertEqual(start["mode"], "replay")
        view.stop()

        # An old CSV recording converted: the same tables and the drawing; never over an existing file.
        converted = os.path.join(self.run_dir, "converted.mcap")
        self.mcap_tool("convert", first, converted)
        got = self.mcap_check(converted)
        self.assert_positions_match(got, first)
        self.assertEqual([m["message"]["epoch"] for m in got if m["topic"] == "shapeform/record/commands"], [1])
        self.assertGreater(len([m for m in got if m["topic"] == "shapeform/scene"]), 10)
        again = self.mcap_tool("convert", first, converted, check=False)
        self.assertEqual(again.returncode, 2)
        self.assertIn("exists", again.stderr)

if __name__ == "__main__":
    harness.main()
