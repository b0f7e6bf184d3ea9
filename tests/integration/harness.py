"""Harness for shapeform's multi-process integration tests (standard library only).

Each test owns one DDS domain (given on the command line by CMake, so the assignment is visible in
tests/integration/CMakeLists.txt) and one run folder under the build tree. Every process it starts
runs in its own process group with its stdout and stderr in files of that folder; the test stops
only its own processes (SIGTERM, wait, SIGKILL). After each test the harness asserts that no
process of the test is left (no child alive, no shapeform process on the test's domain) and that no
new Fast DDS shared-memory file appeared; when a test fails it prints the last lines of every log.
Agents and supervisors run with --json: a test learns facts (who hears whom, which command an agent
follows, a wait's outcome, the status of every agent) from their JSON event lines on stdout, never from
log text. Processes are started, stopped and read through scripts/lib/shapeform_procs.py.

Run a test file directly:
    python3 tests/integration/test_x.py --bin build/bin --source . --domain 101 [unittest args]
"""

import argparse
import json
import os
import shutil
import signal
import sys
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts", "lib"))
import netlab  # noqa: E402
import shapeform_procs as procs  # noqa: E402
from shapeform_procs import (Proc, events, last_json_line, poll, processes_in_group, read_csv,  # noqa: E402,F401
                             read_text, shapeform_processes_on_domain, shm_files, summary)

# Filled in by main() from the command line.
CONFIG = {"bin": None, "source": None, "domain": None, "work": None}

LOG_TAIL_LINES = 30
OUT_TAIL_LINES = 6


def bin_path(name):
    return os.path.join(CONFIG["bin"], name)


def scenario(name):
    return os.path.join(CONFIG["source"], "config", "scenarios", name + ".yaml")


def tail(path, lines=LOG_TAIL_LINES):
    return read_text(path).splitlines()[-lines:]


def fnum(v):
    return None if v in (None, "") else float(v)


def mean(values):
    values = [v for v in values if v is not None]
    return sum(values) / len(values) if values else None


# ----------------------------------------------------------------------------------------------
# Processes that print JSON events (run with --json)

class Agent(Proc):
    """An agent process (or an agent group) run with --json: status and command events on stdout."""

    def heard(self, since=0):
        """{agent id: neighbours heard} from the newest status event of each hosted agent after `since`."""
        return procs.neighbours_heard(self.out()[since:])

    def hears(self, n, since=0):
        """True when every hosted agent's newest status (after `since`) reports n neighbours heard."""
        latest = self.heard(since)
        return bool(latest) and all(k == n for k in latest.values())

    def epochs(self, since=0):
        """Epochs of the commands this process adopted (its command events)."""
        return [e["epoch"] for e in self.events("command", since)]


def status_rows(status):
    """The agents of a supervisor's status event as {id: {alive, state, last_seen, x1, x2, epoch, shape_error,
    heard}}; state is "alive", "dead" (silent) or "left" (disposed its instance)."""
    return {a["id"]: {"alive": a["alive"], "state": a["state"], "last_seen": a["last_seen_s"], "x1": a["x"], "x2": a["y"],
                      "epoch": a["epoch"], "shape_error": a["shape_error"], "heard": a["neighbours_heard"]}
            for a in status["agents"]}


class Supervisor(Proc):
    """A supervisor run with --json and driven through its console (stdin pipe): every answer is a JSON
    event line on stdout."""

    def ask(self, command, kind, timeout=10.0, what=None):
        """Sends a console line; returns the first `kind` event printed after it."""
        since = self.mark()
        self.send(command)
        return self.wait_event(kind, timeout, since, what=what or "the supervisor's answer to '%s'" % command)

    def status(self):
        """(status rows as status_rows gives them, metrics event), asked one after the other."""
        rows = status_rows(self.ask("status", "status"))
        return rows, self.metrics()

    def metrics(self, timeout=10.0):
        return self.ask("metrics", "metrics", timeout)

    def wait_until(self, what, line, timeout):
        """Runs a console `wait`; True when it was met, False on its timeout."""
        since = self.mark()
        self.send(line)
        e = self.wait_event("wait", timeout + 30, since, where=lambda e: e["wait"] == what,
                            what="the answer to '%s'" % line)
        return e["ok"]

    def wait_converged(self, timeout):
        return self.wait_until("converged", "wait converged timeout=%g" % timeout, timeout)

    def wait_agents(self, n, timeout):
        return self.wait_until("agents", "wait agents %d timeout=%g" % (n, timeout), timeout)

    def command(self, line, timeout=10.0):
        """Sends a command that publishes an epoch; returns the epoch number announced."""
        return self.ask(line, "epoch", timeout, "the supervisor to publish '%s'" % line)["epoch"]

    def left(self, since=0):
        """Ids of the agents the supervisor reported as left (disposed; a silent agent is "lost")."""
        return {e["id"] for e in self.events("agent", since) if e["change"] == "left"}


class SwarmTestCase(unittest.TestCase):
    """Base class: a run folder, a domain, process bookkeeping and the after-test checks."""

    def setUp(self):
        self.domain = CONFIG["domain"]
        self.run_dir = os.path.join(CONFIG["work"], self.id().split(".")[-1])
        shutil.rmtree(self.run_dir, ignore_errors=True)
        os.makedirs(self.run_dir)
        self.procs = []
        self.shm_before = shm_files()
        self.t0 = time.monotonic()
        # Nothing of an earlier run may still be on this test's domain.
        leftovers = shapeform_processes_on_domain(self.domain)
        self.assertEqual(leftovers, [], "processes already on domain %d before the test" % self.domain)

    def tearDown(self):
        failed = self._failed()
        for p in reversed(self.procs):
            p.stop(grace=5.0)
        problems = []
        for p in self.procs:
            left = processes_in_group(p.pid)
            if left:
                problems.append("process group of %s (pgid %d) still has processes %s" % (p.name, p.pid, left))
                for pid in left:
                    try:
                        os.kill(pid, signal.SIGKILL)  # only members of our own group
                    except ProcessLookupError:
                        pass
        deadline = time.monotonic() + 10
        while shapeform_processes_on_domain(self.domain) and time.monotonic() < deadline:
            time.sleep(0.1)
        on_domain = shapeform_processes_on_domain(self.domain)
        if on_domain:
            problems.append("shapeform processes left on domain %d: %s" % (self.domain, on_domain))
        new_shm = sorted(shm_files() - self.shm_before)
        if new_shm:
            problems.append("new Fast DDS shared-memory files in %s: %s" % (procs.SHM_DIR, new_shm))
        if failed or problems:
            self.print_failure()
            self.print_logs()
        sys.stderr.write("[%s] %.1f s, run folder %s\n" % (self.id(), time.monotonic() - self.t0, self.run_dir))
        if problems:
            self.fail("after the test: " + "; ".join(problems))

    def _failures(self):
        """(test, traceback text) of this test's failures and errors so far; None when unknown."""
        outcome = getattr(self, "_outcome", None)
        result = getattr(outcome, "result", None)
        if result is None:
            return None
        # Sub-tests are recorded as _SubTest objects that point back to their test case.
        return [(t, text) for t, text in list(result.failures) + list(result.errors)
                if getattr(t, "test_case", t) is self]

    def _failed(self):
        failures = self._failures()
        return failures is None or bool(failures)

    def print_failure(self):
        """The failure's own message first, so that a log cut for length still shows what failed."""
        for _, text in self._failures() or []:
            lines = text.rstrip().splitlines()
            where = [l.strip() for l in lines if l.strip().startswith("File ")]
            sys.stderr.write("===== %s failed at %s: %s\n"
                             % (self.id(), where[-1] if where else "?", lines[-1] if lines else "?"))

    def print_logs(self):
        names = []
        for root, _, files in os.walk(self.run_dir):
            for f in sorted(files):
                if f.endswith((".log", ".out")):
                    names.append(os.path.join(root, f))
        for path in sorted(names):
            # Logs are prose; the JSON event lines of .out files are long, so fewer of them.
            lines = tail(path, LOG_TAIL_LINES if path.endswith(".log") else OUT_TAIL_LINES)
            if not lines:
                continue
            sys.stderr.write("----- last %d lines of %s\n" % (len(lines), os.path.relpath(path, self.run_dir)))
            for line in lines:
                sys.stderr.write("  " + line[:400] + "\n")
        sys.stderr.flush()

    # -- starting processes
    def start(self, name, argv, stdin=None, cls=Proc):
        p = cls(name, argv, self.run_dir, stdin=stdin)
        self.procs.append(p)
        return p

    def on_host(self, host, argv):
        """argv as run on `host` (LanSwarmTestCase); here every process runs on this host."""
        if host is not None:
            raise ValueError("host %r: only a LanSwarmTestCase has test hosts" % host)
        return argv

    def start_agent(self, i, config, domain=None, extra=(), seed=None, name=None, host=None):
        argv = [bin_path("shapeform_agent"), "--id", str(i), "--config", config, "--json",
                "--domain", str(self.domain if domain is None else domain)]
        if seed is not None:
            argv += ["--seed", str(seed)]
        argv += list(extra)
        return self.start(name or "agent_%d" % i, self.on_host(host, argv), cls=Agent)

    def start_group(self, ids, config, extra=(), seed=1, name="group"):
        """An agent group process hosting `ids` ("A-B"), run with --json."""
        argv = [bin_path("shapeform_agent_group"), "--ids", ids, "--config", config, "--json",
                "--domain", str(self.domain), "--seed", str(seed)] + list(extra)
        return self.start(name, argv, cls=Agent)

    def start_agents(self, n, config, domain=None, extra=(), seed=None, first=0, prefix="agent_"):
        agents = []
        for i in range(first, first + n):
            agents.append(self.start_agent(i, config, domain, extra, seed, name="%s%d" % (prefix, i)))
            time.sleep(0.02)  # stagger: no discovery storm
        return agents

    def start_meshed_agents(self, n, config, extra=(), timeout=60):
        """Starts agents 0..n-1 (seed 1) and waits until each reports hearing the n-1 others."""
        agents = self.start_agents(n, config, seed=1, extra=extra)
        poll(lambda: all(a.hears(n - 1) for a in agents), timeout, "the %d agents to hear each other" % n)
        return agents

    def start_commanded_swarm(self, n, config, extra=(), seed=1, record=None):
        """A supervisor and agents 0..n-1 (seeded start); once the supervisor hears all n, `start` publishes
        epoch 1. Returns (supervisor, agents)."""
        sup = self.start_supervisor(config, record=record, extra=extra)
        agents = self.start_agents(n, config, seed=seed, extra=extra)
        self.assertTrue(sup.wait_agents(n, 60), "the supervisor hears every agent")
        self.assertEqual(sup.command("start"), 1)
        return sup, agents

    def start_supervisor(self, config, domain=None, script=None, record=None, extra=(), console=True,
                         name="supervisor", host=None):
        """A supervisor run with --json (every answer, event and the summary are JSON lines on stdout)."""
        argv = [bin_path("shapeform_supervisor"), "--config", config, "--json",
                "--domain", str(self.domain if domain is None else domain)]
        if script is not None:
            argv += ["--script", script]
        if record is not None:
            argv += ["--record", record]
        argv += list(extra)
        return self.start(name, self.on_host(host, argv), stdin="pipe" if console else None, cls=Supervisor)

    def write(self, name, text):
        path = os.path.join(self.run_dir, name)
        with open(path, "w") as f:
            f.write(text)
        return path

    def run_sim(self, config, args=()):
        """Runs shapeform_sim; returns its JSON object."""
        argv = [bin_path("shapeform_sim"), "--config", config] + list(args)
        return json.loads(procs.run(argv, timeout=120).stdout)

    def assert_all_alive(self, processes):
        dead = ["%s (status %s)" % (p.name, p.returncode) for p in processes if not p.running()]
        self.assertEqual(dead, [], "processes that stopped")


def launcher():
    """scripts/launch_swarm.sh of the source tree."""
    return os.path.join(CONFIG["source"], "scripts", "launch_swarm.sh")


class LauncherTestCase(SwarmTestCase):
    """Tests that run scripts/launch_swarm.sh, which may make test hosts (a fleet's lab) of its own."""

    def setUp(self):
        super().setUp()
        self.labs = []  # test hosts a launch of this test may make

    def tearDown(self):
        # The launcher first, with time to stop its hosts' processes and remove its lab by itself; a lab
        # still there (the launcher killed) is removed here.
        for p in self.procs:
            p.stop(grace=30.0)
        try:
            super().tearDown()
        finally:
            for lab in self.labs:
                netlab.NetLab(lab, 1, "10.0.0").down()

    def use_lab(self, name):
        """A lab a launch of this test makes: one left by an earlier run that was itself killed is removed
        first (ours by name), and whatever is left of it after the test is removed."""
        netlab.NetLab(name, 1, "10.0.0").down()
        self.labs.append(name)


class LanSwarmTestCase(SwarmTestCase):
    """Processes on HOSTS test hosts (network namespaces on one private bridge, scripts/netlab.sh), each
    with the lan profile bound to its host's address. The lab is named after the test's domain and its
    subnet is 10.200.(2 * domain): tests never see each other. After the test, besides SwarmTestCase's
    checks: the lab is removed (its namespaces, links, bridges and rules) and nothing of it is left."""

    HOSTS = 4

    def setUp(self):
        why = netlab.available()
        if why:
            self.fail("test hosts cannot be made here: " + why)  # a failure, never a silent skip
        super().setUp()
        self.lab = netlab.NetLab("d%d" % self.domain, self.HOSTS, "10.200.%d" % (2 * self.domain))
        self.lab.up()

    def tearDown(self):
        try:
            super().tearDown()
        finally:
            self.lab.down()
            left = self.lab.leftovers()
            if left:
                self.fail("after the test, left on the machine: " + ", ".join(left))

    def on_host(self, host, argv):
        if host is None:
            raise ValueError("a LanSwarmTestCase runs every process on a test host (h1..h%d)" % self.HOSTS)
        return self.lab.on(host, list(argv) + self.lab.lan_sets(host))


def main():
    parser = argparse.ArgumentParser(add_help=False)
    parser.add_argument("--bin", required=True, help="folder of the shapeform executables")
    parser.add_argument("--source", required=True, help="the project's source folder")
    parser.add_argument("--domain", required=True, type=int, help="this test's DDS domain id")
    parser.add_argument("--work", default=None, help="folder for run folders (default: next to --bin)")
    args, rest = parser.parse_known_args()
    CONFIG["bin"] = os.path.abspath(args.bin)
    CONFIG["source"] = os.path.abspath(args.source)
    CONFIG["domain"] = args.domain
    CONFIG["work"] = os.path.abspath(args.work or os.path.join(os.path.dirname(CONFIG["bin"]),
                                                               "integration_runs", "domain_%d" % args.domain))
    os.makedirs(CONFIG["work"], exist_ok=True)
    for exe in ("shapeform_agent", "shapeform_supervisor", "shapeform_sim"):
        if not os.access(bin_path(exe), os.X_OK):
            sys.stderr.write("harness: %s not found or not executable\n" % bin_path(exe))
            sys.exit(2)
    unittest.main(argv=[sys.argv[0]] + rest, verbosity=2)
