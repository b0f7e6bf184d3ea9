#!/usr/bin/env python3
"""Identity and input hygiene on real processes.

- A second agent started with an --id already in use listens before its first publication, hears the
  id from another participant, says so (a "duplicate" event naming the id and both participants) and
  exits 2 without ever publishing; the supervisor reports the same pair of participants; the incumbent
  keeps running and the formation keeps its spacing.
- A rogue participant built from the project's own types (tests/tools/rogue_publisher.cpp) publishing
  AgentState samples with id 2^31-1, or with model time 1e300: every agent and the supervisor refuse
  and count them, and no new agent appears. A 1 MB console line is refused in a short error line.
- Bad inputs that must be refused fast with exit 2 and the path or key named, before anything starts:
  every program that reads a config given /dev/zero, a FIFO, a directory, a file above 1 MiB, two YAML
  documents, supervisor.target_rate_hz 1e9; an unwritable --record for the supervisor (before its DDS
  participant exists) and for the launcher (before any agent starts); a 1 MB flag value is quoted in at
  most a few hundred characters.
"""
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402
from harness import procs  # noqa: E402

AGENTS = 6
# Programs that read a config, with the arguments each needs besides --config.
CONFIG_READERS = [
    ("shapeform_agent", ["--id", "0"]),
    ("shapeform_agent_group", ["--ids", "0-1"]),
    ("shapeform_supervisor", []),
    ("shapeform_sim", []),
    ("shapeform_bench_baseline", ["--id", "0"]),
    ("shapeform_bench_probe", ["--out", "{run_dir}/probe"]),
    ("shapeform_topics", []),
    ("shapeform_echo", ["shapeform/state"]),
    ("shapeform_view", ["--port", "0"]),
    ("shapeform_rogue_publisher", ["--topic", "state"]),
]


class IdentityTest(harness.SwarmTestCase):

    def test_duplicate_id_refused_and_reported(self):
        config = harness.scenario("circle")
        sets = ["--set", "swarm.agents=%d" % AGENTS]
        sup, agents = self.start_commanded_swarm(AGENTS, config, sets)
        self.assertTrue(sup.wait_converged(40), "the circle converges")
        spacing = sup.metrics()["min_separation"]
        self.assertGreater(spacing, 2.0, "the converged circle's agents are well apart")

        dup = self.start_agent(2, config, seed=1, extra=sets, name="duplicate_2")
        self.assertEqual(dup.wait(15), 2, "the duplicate refuses to run (exit 2)")
        mine = dup.events("duplicate")
        self.assertEqual(len(mine), 1, "the duplicate says so once")
        self.assertEqual((mine[0]["id"], mine[0]["action"]), (2, "exit"))
        self.assertIn("refusing to run", dup.log())
        # It never published a state: no agent heard more than its AGENTS - 1 neighbours.
        self.assertEqual(dup.events("status"), [])
        seen = sup.wait_event("duplicate", 10, what="the supervisor to report the duplicate id")
        self.assertEqual(seen["id"], 2)
        # Both name the same two participants: the incumbent ("source" to the supervisor) and the newcomer.
        self.assertEqual((seen["source"], seen["other"]), (mine[0]["other"], mine[0]["source"]))
        self.assertNotEqual(seen["source"], seen["other"])

        # The incumbent runs on, the supervisor still counts AGENTS agents, and the spacing is normal.
        mark = agents[2].mark()
        harness.poll(lambda: agents[2].hears(AGENTS - 1, mark), 10, "the incumbent agent 2 to report its status")
        self.assert_all_alive(agents + [sup])
        rows, m = sup.status()
        self.assertEqual(sorted(rows), list(range(AGENTS)))
        self.assertTrue(all(r["alive"] for r in rows.values()))
        self.assertEqual(m["agents"], AGENTS)
        self.assertGreater(m["min_separation"], 0.8 * spacing, "the formation keeps its spacing")
        self.assertTrue(m["converged"])

    def rejected(self, agents):
        return [max([e["samples_rejected"] for e in a.events("status")] or [0]) for a in agents]

    def test_rogue_ids_and_model_times_refused_and_counted(self):
        config = harness.scenario("circle")
        sets = ["--set", "swarm.agents=3", "--set", "agent.status_rate_hz=5"]
        sup = self.start_supervisor(config, extra=sets)
        agents = self.start_agents(3, config, seed=1, extra=sets)
        self.assertTrue(sup.wait_agents(3, 30), "the supervisor hears every agent")
        for fields, why in ((["id=2147483647"], "state.id: must be in 0..9999, got 2147483647"),
                            (["id=7", "model_time=1e300"], "state.model_time: must be in [0, 1000000000], got 1e+300")):
            before = self.rejected(agents)
            argv = [harness.bin_path("shapeform_rogue_publisher"), "--domain", str(self.domain), "--topic", "state",
                    "--count", "20", "--rate", "50", "--wait-readers", "4"]
            for f in fields:
                argv += ["--field", f]
            rogue = self.start("rogue_" + fields[0].replace("=", "_"), argv)
            self.assertEqual(rogue.wait(20), 0, "the rogue publisher ran")
            # Every agent counts the refused samples (a few of the 20 best-effort samples may be lost).
            harness.poll(lambda: all(after >= b + 10 for after, b in zip(self.rejected(agents), before)), 10,
                         "every agent to count the rogue samples as rejected (%s)" % why)
            self.assertTrue(any(why in e["why"] for a in agents for e in a.events("rejected")),
                            "an agent names the refused field: " + why)
        for why in ("state.id: must be in 0..9999, got 2147483647", "state.model_time: must be in [0, 1000000000]"):
            self.assertIn(why, sup.log(), "the supervisor names the refused field")
        # No new agent: neither the supervisor nor any agent took the rogue for one.
        rows, m = sup.status()
        self.assertEqual(sorted(rows), [0, 1, 2])
        self.assertTrue(all(a.hears(2) for a in agents))
        # A 1 MB console line: its error line quotes a few hundred characters of it, not the megabyte.
        since = len(sup.log())
        sup.send("shape circle r=" + "q" * 1000000)
        harness.poll(lambda: "qqq" in sup.log()[since:], 10, "the supervisor to refuse the long console line")
        new_lines = sup.log()[since:].splitlines()
        self.assertTrue(new_lines and max(len(line) for line in new_lines) < 1000, [line[:300] for line in new_lines])
        sup.send("quit")
        self.assertEqual(sup.wait(15), 0)
        s = harness.summary(sup.out())
        self.assertGreaterEqual(s["samples_rejected"], 20, "the supervisor counts the refused samples")
        self.assertEqual(s["agents_seen"], 3)


class InputHygieneTest(harness.SwarmTestCase):

    def run_fast(self, argv, timeout=10):
        t0 = time.monotonic()
        r = procs.run(argv, timeout=timeout, check=False)
        return r, time.monotonic() - t0

    def test_bad_config_files_exit_2_in_every_program(self):
        fifo = os.path.join(self.run_dir, "config.fifo")
        os.mkfifo(fifo)
        big = self.write("big.yaml", "schema_version: 1\n#" + "x" * (1 << 20) + "\n")
        two = self.write("two.yaml", "schema_version: 1\n---\nname: second\n")
        rate = self.write("rate.yaml", "schema_version: 1\nsupervisor:\n  target_rate_hz: 1e9\n")
        cases = [("/dev/zero", "'/dev/zero': is a character device, not a regular file"),
                 (fifo, "'%s': is a FIFO, not a regular file" % fifo),
                 (self.run_dir, "'%s': is a directory, not a regular file" % self.run_dir),
                 (big, "'%s': %d bytes, more than the 1048576 (1 MiB)" % (big, os.path.getsize(big))),
                 (two, "'%s': a second YAML document starts at line 2" % two),
                 (rate, "supervisor.target_rate_hz: must be in (0, 1000], got 1e9 (line 3)")]
        for exe, args in CONFIG_READERS:
            for path, message in cases:
                with self.subTest(program=exe, config=path):
                    argv = [harness.bin_path(exe), "--config", path, "--domain", str(self.domain)]
                    argv += [a.format(run_dir=self.run_dir) for a in args]
                    if exe == "shapeform_sim":
                        argv.remove("--domain")
                        argv.remove(str(self.domain))
                    r, took = self.run_fast(argv)
                    self.assertEqual(r.returncode, 2, r.stderr)
                    self.assertIn(message, r.stderr)
                    self.assertLess(took, 5.0, "refused at once")
                    self.assertLess(len(r.stderr), 2000, "the error quotes little")

    def test_unwritable_record_refused_before_anything_starts(self):
        plain = self.write("plain_file", "x")
        for record in (os.path.join(plain, "record"), "/proc/shapeform_record"):
            with self.subTest(record=record):
                r, took = self.run_fast([harness.bin_path("shapeform_supervisor"), "--domain", str(self.domain),
                                         "--record", record])
                self.assertEqual(r.returncode, 2, r.stderr)
                self.assertIn("--record", r.stderr)
                self.assertIn(record, r.stderr)
                # Refused at parse time: no participant was created, so nothing was logged about the transport.
                self.assertNotIn("transport:", r.stderr)
                self.assertLess(took, 5.0)
        runs = os.path.join(self.run_dir, "runs")
        r, _ = self.run_fast([os.path.join(harness.CONFIG["source"], "scripts", "launch_swarm.sh"), "-n", "2", "--scenario",
                              "circle", "--domain", str(self.domain), "--record", os.path.join(plain, "record"),
                              "--build", os.path.dirname(harness.CONFIG["bin"]), "--runs", runs], timeout=60)
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn("--record: cannot write into the folder", r.stderr)
        self.assertNotIn("started", r.stderr)  # no agent, no supervisor
        self.assertFalse(os.path.exists(runs) and os.listdir(runs), "no run folder was made")

    def test_long_flag_values_are_quoted_briefly(self):
        huge = "z" * 100000  # a single argument is at most 128 KiB
        for argv in ([harness.bin_path("shapeform_agent"), "--id", "0", "--start", huge],
                     [harness.bin_path("shapeform_agent_group"), "--ids", huge],
                     [harness.bin_path("shapeform_sim"), "--set", "name" + huge],
                     [harness.bin_path("shapeform_sim"), "--set", "agent.rate_hz=" + huge]):
            with self.subTest(program=os.path.basename(argv[0]), flag=argv[1]):
                r, _ = self.run_fast(argv)
                self.assertEqual(r.returncode, 2)
                self.assertIn("zzz", r.stderr)
                self.assertLess(len(r.stderr), 1000, r.stderr[:2000])


if __name__ == "__main__":
    harness.main()
