#!/usr/bin/env python3
"""scripts/launch_swarm.sh --fleet: the example fleet (config/fleets/lab4.yaml: 12 agents on three test
hosts, the supervisor on a fourth, hosts the launcher makes and removes) runs to convergence, and so
does a fleet of `run: local` hosts on loopback addresses (127.0.0.2, 127.0.0.3); Ctrl-C
mid-run on a secured fleet (--keystore) with an ssh host leaves nothing behind; bad fleet files are
refused naming the key.

There is no ssh server here: an ssh host is played by a stand-in `ssh` on PATH that runs the remote
command line with `sh -c` in a test host's namespace (the launcher's remote side -- setsid, process
group files, stopping them, the recording copied back -- runs for real; the ssh transport does not).

Run directly (root): test_fleet.py --bin build/bin --source . --domain 6 [unittest args]
"""
import contextlib
import glob
import io
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402
import fleet as fleet_reader  # noqa: E402  (scripts/lib, on the path through harness)

FAKE_SSH = r"""#!/bin/sh
# ssh stand-in: [-n] [-o OPT]... [--] [USER@]HOST WORDS... runs WORDS joined by spaces (as ssh sends
# them) with sh -c in the namespace sf-%(lab)s-HOST, as a child: like the ssh client, this process
# ending (a signal) does not end the remote command.
while [ $# -gt 0 ]; do
  case "$1" in -n) exec </dev/null; shift ;; -o) shift 2 ;; --) shift; break ;; *) break ;; esac
done
host=${1#*@}
shift
ip netns exec "sf-%(lab)s-$host" sh -c "$*"
"""


# Two hosts of this machine on loopback addresses; %s: the discovery.
LOCAL_FLEET = """schema_version: 1
hosts:
  - {name: a, address: 127.0.0.2, run: local, agents: 0-2}
  - {name: b, address: 127.0.0.3, run: local, agents: 3-5}
supervisor: b
transport: {discovery: %s}
"""


def source(*parts):
    return os.path.join(harness.CONFIG["source"], *parts)


class FleetTest(harness.LauncherTestCase):

    def launch(self, fleet, args, name="launcher", env=None):
        """The launcher with --fleet FILE, its own --runs folder (RUN_DIR/runs_NAME) and the test's domain."""
        argv = ["bash", harness.launcher(), "--build", os.path.dirname(harness.CONFIG["bin"]), "--fleet", fleet,
                "--runs", os.path.join(self.run_dir, "runs_" + name), "--domain", str(self.domain)] + list(args)
        p = harness.Proc(name, argv, self.run_dir, env=env)
        self.procs.append(p)
        return p


    def assert_nothing_left(self, proc, lab=None):
        self.assertEqual(harness.processes_in_group(proc.pid), [], "processes left in the launcher's group")
        self.assertEqual(harness.shapeform_processes_on_domain(self.domain), [], "shapeform processes left")
        self.assertEqual(sorted(harness.shm_files() - self.shm_before), [], "new Fast DDS shm files")
        if lab is None:
            return
        netns = subprocess.run(["ip", "netns", "list"], stdout=subprocess.PIPE, text=True).stdout
        self.assertEqual([line for line in netns.splitlines() if line.startswith("sf-%s-" % lab)], [],
                         "namespaces of the lab left")
        self.assertFalse(os.path.exists(os.path.join(harness.netlab.STATE_ROOT, lab)), "the lab's state file left")

    def agent_events(self, run, i, kind):
        return harness.events(harness.read_text(os.path.join(run, "agent_%d.out" % i)), kind)

    def test_example_fleet_converges(self):
        # The README's command: the example fleet, the paper's circle, until converged.
        fleet = source("config", "fleets", "lab4.yaml")
        self.use_lab("lab4")
        sim = self.run_sim(harness.scenario("circle"), ["--steps", "500"])
        p = self.launch(fleet, ["--scenario", "circle", "--json"])
        self.assertEqual(p.wait(90), 0, "launcher exit status (0: converged)")
        lines = p.out().splitlines()
        run_event = json.loads(lines[0])
        self.assertEqual((run_event["event"], run_event["agents"], run_event["domain"], run_event["fleet"]),
                         ("run", 12, self.domain, "lab4"))
        run = run_event["dir"]
        summary = harness.summary(p.out())
        self.assertTrue(summary["converged"])
        self.assertEqual((summary["agents"], summary["agents_seen"]), (12, 12))
        self.assertLessEqual(abs(summary["shape_error_mean"] - sim["shape_error_mean"]), 0.02)
        self.assertLessEqual(summary["gap_cv"], 0.10)
        # Every process ran on its host with the lan profile bound to that host's address, heard every
        # other agent across the hosts, and stopped cleanly; all logs are in the run folder.
        for i in range(12):
            start = self.agent_events(run, i, "start")
            self.assertEqual(len(start), 1, "agent %d's start event" % i)
            transport = start[0]["config"]["transport"]
            self.assertEqual((transport["profile"], transport["interfaces"], transport["peers"]),
                             ("lan", ["10.200.40.%d" % (1 + i // 4)], []), "agent %d's transport" % i)
            heard = [e["neighbours_heard"] for e in self.agent_events(run, i, "status")]
            self.assertIn(11, heard, "agent %d hears the 11 others" % i)
            self.assertEqual(len(self.agent_events(run, i, "stop")), 1, "agent %d stopped cleanly" % i)
            self.assertIn("[agent %d]" % i, harness.read_text(os.path.join(run, "agent_%d.log" % i)))
        sup_start = harness.events(harness.read_text(os.path.join(run, "supervisor.out")), "start")[0]
        self.assertEqual(sup_start["config"]["transport"]["interfaces"], ["10.200.40.4"])
        self.assertIn("[supervisor]", harness.read_text(os.path.join(run, "supervisor.log")))
        self.assertTrue(harness.read_csv(os.path.join(run, "record", "metrics.csv")), "the recording")
        self.assertEqual(harness.read_text(os.path.join(run, "fleet.yaml")), harness.read_text(fleet))
        self.assertIn("supervisor h4", harness.read_text(os.path.join(run, "fleet.txt")))
        self.assertNotIn("exited with status", p.log())
        self.assertIn("lab lab4 down", p.log())
        self.assert_nothing_left(p, "lab4")

        # The same fleet secured (the arc law's circle, which settles sooner): the launcher discovers by
        # unicast to the four hosts, and every agent hears the 11 others. With the fleet file's multicast
        # discovery, Fast DDS 2.9.1 left one to four pairs unauthenticated in 12 of 13 launches
        # (docs/SECURITY.md, Deploying on real hosts).
        p = self.launch(fleet, ["--scenario", "arc_circle", "--secure", "--json"], "launcher_secure")
        self.assertEqual(p.wait(150), 0, "secured: launcher exit status (0: converged)")
        self.assertIn("secured: discovery by unicast to the fleet's hosts", p.log())
        run = json.loads(p.out().splitlines()[0])["dir"]
        summary = harness.summary(p.out())
        self.assertEqual((summary["converged"], summary["agents_seen"]), (True, 12))
        for i in range(12):
            config = self.agent_events(run, i, "start")[0]["config"]
            self.assertEqual((config["transport"]["peers"], config["security"]["enabled"]),
                             (["10.200.40.%d" % h for h in range(1, 5)], True), "secured agent %d" % i)
            heard = [e["neighbours_heard"] for e in self.agent_events(run, i, "status")]
            self.assertIn(11, heard, "secured agent %d hears the 11 others" % i)
        self.assert_nothing_left(p, "lab4")

    def test_local_hosts_on_loopback_addresses(self):
        # Two `run: local` hosts on 127.0.0.2 and 127.0.0.3: both are this machine's lo (no namespace, no
        # root), which carries 127.0.0.1 alone. With either discovery the six agents meet across the two
        # hosts and the swarm converges.
        for discovery in ("multicast", "unicast"):
            with self.subTest(discovery=discovery):
                fleet = self.write("local_%s.yaml" % discovery, LOCAL_FLEET % discovery)
                p = self.launch(fleet, ["--scenario", "arc_circle", "--json"], "launcher_" + discovery)
                self.assertEqual(p.wait(120), 0, "launcher exit status (0: converged)")
                run = json.loads(p.out().splitlines()[0])["dir"]
                summary = harness.summary(p.out())
                self.assertEqual((summary["converged"], summary["agents_seen"]), (True, 6))
                for i in range(6):
                    transport = self.agent_events(run, i, "start")[0]["config"]["transport"]
                    self.assertEqual(transport["interfaces"], ["127.0.0.%d" % (2 + i // 3)], "agent %d" % i)
                    heard = [e["neighbours_heard"] for e in self.agent_events(run, i, "status")]
                    self.assertIn(5, heard, "agent %d hears the 5 others" % i)
                self.assertNotIn("exited with status", p.log())
                self.assert_nothing_left(p)

    def test_ctrl_c_with_an_ssh_host(self):
        # Two test hosts: h1 a namespace running agents 0..2; h2 an ssh host (the stand-in) running agents
        # 3..5 and the supervisor. DDS Security (--keystore): the command reaches every agent across the
        # hosts encrypted. The fleet file leaves discovery at multicast, which security refuses: the
        # launcher gives every process the fleet's hosts as unicast peers. Ctrl-C to the launcher alone,
        # mid-run.
        lab = "d%d" % self.domain
        self.use_lab(lab)
        subnet = "10.200.%d" % (2 * self.domain)
        bindir = os.path.join(self.run_dir, "fake_bin")
        os.makedirs(bindir)
        with open(os.path.join(bindir, "ssh"), "w") as f:
            f.write(FAKE_SSH % {"lab": lab})
        os.chmod(os.path.join(bindir, "ssh"), 0o755)
        fleet = self.write("ctrl_c.yaml", "\n".join([
            "schema_version: 1",
            "lab: {name: %s, hosts: 2, subnet: %s}" % (lab, subnet),
            "hosts:",
            "  - {name: h1, address: %s.1, run: netns sf-%s-h1, agents: 0-2}" % (subnet, lab),
            "  - {name: h2, address: %s.2, run: ssh root@h2, agents: [3, 4-5]}" % subnet,
            "supervisor: h2", ""]))
        env = dict(os.environ, PATH=bindir + os.pathsep + os.environ.get("PATH", ""))
        # A keystore at one path for both hosts (an ssh host needs it there: the launcher refuses --secure alone).
        keystore = os.path.join(self.run_dir, "keystore")
        harness.procs.run([source("scripts", "make_keystore.sh"), keystore, "--agents", "6"], timeout=60)
        p = self.launch(fleet, ["--scenario", "circle", "--timeout", "300", "--keystore", keystore,
                                "--set", "supervisor.converge.hold=100000"], env=env)
        run = harness.poll(lambda: glob.glob(os.path.join(self.run_dir, "runs_" + p.name, "*", "")), 30,
                           "the launcher's run folder")[0]
        remote = "/tmp/shapeform-" + os.path.basename(run.rstrip("/"))
        harness.poll(lambda: all(self.agent_events(run, i, "command") for i in range(6)), 60,
                     "the 6 agents following the command")
        self.assertTrue(os.path.exists(os.path.join(remote, "supervisor.pid")), "the ssh host's process groups")
        os.kill(p.pid, signal.SIGINT)
        self.assertEqual(p.wait(30), 130, "exit status after Ctrl-C")
        for i in range(6):
            config = self.agent_events(run, i, "start")[0]["config"]
            start = config["transport"]
            self.assertEqual((start["interfaces"], start["peers"]), ([subnet + ".%d" % (1 + (i >= 3))],
                                                                     [subnet + ".1", subnet + ".2"]),
                             "agent %d's transport" % i)
            self.assertEqual((config["security"]["enabled"], config["security"]["keystore"]),
                             (True, keystore), "agent %d's security" % i)
            self.assertEqual(len(self.agent_events(run, i, "stop")), 1, "agent %d stopped cleanly" % i)
        self.assertIn("summary:", harness.read_text(os.path.join(run, "supervisor.out")),
                      "the supervisor on the ssh host printed its summary, streamed back")
        self.assertTrue(harness.read_csv(os.path.join(run, "record", "metrics.csv")),
                        "the recording copied back from the ssh host")
        self.assertIn("interrupted", p.log())
        self.assertIn("secured: discovery by unicast to the fleet's hosts", p.log())
        # The remote processes were stopped there: each ssh client then ended by itself, with status 0
        # (a client the launcher had to stop would be reported, and its remote process left to the lab's
        # removal).
        self.assertNotIn("exited with status", p.log())
        self.assertFalse(os.path.exists(remote), "the ssh host's folder removed")
        self.assert_nothing_left(p, lab)


class FleetFileTest(unittest.TestCase):
    """Bad fleet files: nothing starts, so no swarm checks (and this test may run beside the others)."""

    # (fleet file text, the key the one-line error names)
    HOSTS = ("hosts:\n  - {name: a, address: 10.1.0.1, run: local, agents: 0-1}\n"
             "  - {name: b, address: 10.1.0.2, run: ssh me@b.lan, agents: 2}\n")
    GOOD = "schema_version: 1\n" + HOSTS + "supervisor: b\n"
    BAD_FLEETS = [
        (GOOD + "extra: 1\n", r"extra: unknown key"),
        (GOOD.replace("schema_version: 1\n", ""), r"schema_version: required"),
        (GOOD.replace("10.1.0.2", "10.1.0.256"), r"hosts\[1\] \(b\)\.address: expected a host's IPv4 address"),
        (GOOD.replace("10.1.0.2", "10.1.0.1"), r"hosts\[1\] \(b\)\.address: 10\.1\.0\.1 is also the address of host 'a'"),
        (GOOD.replace("agents: 2}", "agents: 1-2}"), r"hosts\[1\] \(b\)\.agents: agent 1 runs on host 'a' too"),
        (GOOD.replace("agents: 2}", "agents: 3}"), r"hosts\[\]\.agents: the 3 agents must be ids 0\.\.2.*missing 2"),
        (GOOD.replace("supervisor: b", "supervisor: c"), r"supervisor: expected the name of a host \(a, b\)"),
        (GOOD.replace("run: local", "run: telnet a"), r"hosts\[0\] \(a\)\.run: expected 'netns NAME', 'ssh"),
        (GOOD.replace("name: b,", "name: a,"), r"hosts\[1\] \(a\)\.name: host 'a' is also hosts\[0\]"),
        (GOOD.replace("run: local,", "run: local, port: 22,"), r"hosts\[0\] \(a\)\.port: unknown key"),
        (GOOD + "transport: {discovery: broadcast}\n", r"transport\.discovery: expected multicast or unicast"),
        (GOOD + "supervisor: a\n", r"supervisor: duplicate key"),
        (GOOD + "lab: {name: Lab-1, hosts: 2, subnet: 10.1.0}\n", r"lab\.name: expected 1\.\.8 lowercase"),
        (GOOD.replace("run: local", "run: netns sf-x-h1") + "lab: {name: x, hosts: 2, subnet: 10.1.5}\n",
         r"hosts\[0\] \(a\)\.address: sf-x-h1 of the lab has the address 10\.1\.5\.1, got 10\.1\.0\.1"),
        ("schema_version: 1\nhosts: [\n", r"yaml: not valid YAML"),
    ]

    def test_shipped_fleet_files(self):
        """Every example fleet (config/fleets/*.yaml) is a valid file, listed in config/fleets/README.md."""
        folder = source("config", "fleets")
        with open(os.path.join(folder, "README.md")) as f:
            readme = f.read()
        files = sorted(n for n in os.listdir(folder) if n.endswith(".yaml"))
        self.assertIn("robots_lan.yaml", files)
        for name in files:
            with self.subTest(fleet=name):
                out, err = io.StringIO(), io.StringIO()
                with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
                    status = fleet_reader.main([os.path.join(folder, name)])
                self.assertEqual(status, 0, err.getvalue())
                self.assertRegex(out.getvalue(), r"^fleet %s \d+\n" % re.escape(name[:-5]))
                self.assertIn("`%s`" % name, readme, "config/fleets/README.md lists it")

    def test_bad_fleet_files_exit_2(self):
        run_dir = os.path.join(harness.CONFIG["work"], "test_bad_fleet_files_exit_2")
        shutil.rmtree(run_dir, ignore_errors=True)
        os.makedirs(run_dir)

        def write(name, text):
            with open(os.path.join(run_dir, name), "w") as f:
                f.write(text)
            return os.path.join(run_dir, name)

        # Every file through the one reader's command line, as the launcher runs it (in this process:
        # fast) ...
        for k, (text, message) in enumerate(self.BAD_FLEETS):
            path = write("bad_%d.yaml" % k, text)
            with self.subTest(case=k, message=message):
                out, err = io.StringIO(), io.StringIO()
                with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
                    status = fleet_reader.main([path, "--prog", "launch_swarm: --fleet"])
                self.assertEqual(status, 2, "exit status (stderr %r)" % err.getvalue())
                self.assertEqual(len(err.getvalue().splitlines()), 1, "one line, got %r" % err.getvalue())
                self.assertRegex(err.getvalue(), "^launch_swarm: --fleet: " + re.escape(path) + ": " + message)
                self.assertEqual(out.getvalue(), "")
        # ... and a few through the launcher: the same one line, exit 2, nothing started.
        runs = os.path.join(run_dir, "runs")
        bad = os.path.join(run_dir, "bad_4.yaml")
        cases = [([bad], "^launch_swarm: --fleet: " + re.escape(bad) + r": hosts\[1\] \(b\)\.agents: agent 1 runs"),
                 ([os.path.join(run_dir, "missing.yaml")], r"^launch_swarm: --fleet: cannot read"),
                 ([write("good.yaml", self.GOOD), "-n", "3"], r"^launch_swarm: -n: not with --fleet")]
        for k, (args, message) in enumerate(cases):
            with self.subTest(args=args):
                p = harness.Proc("launcher_%d" % k, ["bash", harness.launcher(), "--build", os.path.dirname(harness.CONFIG["bin"]),
                                                     "--runs", runs, "--domain", str(harness.CONFIG["domain"]),
                                                     "--scenario", "circle", "--fleet"] + args, run_dir)
                try:
                    self.assertEqual(p.wait(30), 2, "exit status (stderr %r)" % p.log())
                    self.assertEqual(len(p.log().splitlines()), 1, "one line, got %r" % p.log())
                    self.assertRegex(p.log(), message)
                    self.assertEqual(p.out(), "")
                finally:
                    p.stop(grace=5.0)  # were a bad file let through: what it started is stopped
        self.assertFalse(os.path.exists(runs) and os.listdir(runs), "no run folder for a bad fleet file")


if __name__ == "__main__":
    harness.main()
