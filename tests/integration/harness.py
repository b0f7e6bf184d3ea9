"""Harness for shapeform's multi-process integration tests (standard library only).

Each test owns one DDS domain (given on the command line by CMake, so the assignment is visible in
tests/integration/CMakeLists.txt) and one run folder under the build tree. Every process it starts
runs in its own process group with its stdout and stderr in files of that folder; the test stops
only its own processes (SIGTERM, wait, SIGKILL). After each test the harness asserts that no
process of the test is left (no child alive, no shapeform process on the test's domain) and that no
new Fast DDS shared-memory file appeared; when a test fails it prints the last lines of every log.

Run a test file directly:
    python3 tests/integration/test_x.py --bin build/bin --source . --domain 101 [unittest args]
"""

import argparse
import csv
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
import unittest

# Filled in by main() from the command line.
CONFIG = {"bin": None, "source": None, "domain": None, "work": None}

SHM_DIR = "/dev/shm"
SHM_PATTERN = re.compile(r"^(sem\.)?(fastrtps|fast_datasharing|fastdds)")
LOG_TAIL_LINES = 30


def bin_path(name):
    return os.path.join(CONFIG["bin"], name)


def scenario(name):
    return os.path.join(CONFIG["source"], "config", "scenarios", name + ".yaml")


def shm_files():
    try:
        return {f for f in os.listdir(SHM_DIR) if SHM_PATTERN.match(f)}
    except FileNotFoundError:
        return set()


def poll(predicate, timeout, what, interval=0.1):
    """Calls predicate() until it returns a truthy value (returned) or timeout seconds pass."""
    deadline = time.monotonic() + timeout
    while True:
        value = predicate()
        if value:
            return value
        if time.monotonic() >= deadline:
            raise AssertionError("timed out after %.0f s waiting for %s" % (timeout, what))
        time.sleep(interval)


def read_text(path):
    try:
        with open(path, "r", errors="replace") as f:
            return f.read()
    except FileNotFoundError:
        return ""


def tail(path, lines=LOG_TAIL_LINES):
    return read_text(path).splitlines()[-lines:]


class Proc:
    """One process of a test: its own process group, stdout in NAME.out and stderr in NAME.log."""

    def __init__(self, name, argv, run_dir, stdin=None, env=None):
        self.name = name
        self.argv = argv
        self.out_path = os.path.join(run_dir, name + ".out")
        self.log_path = os.path.join(run_dir, name + ".log")
        self._out = open(self.out_path, "wb")
        self._log = open(self.log_path, "wb")
        self.popen = subprocess.Popen(
            argv,
            stdin=subprocess.PIPE if stdin == "pipe" else subprocess.DEVNULL,
            stdout=self._out,
            stderr=self._log,
            start_new_session=True,  # own session and process group: signals reach only it
            env=env,
        )
        self.pid = self.popen.pid

    # -- state
    def running(self):
        return self.popen.poll() is None

    @property
    def returncode(self):
        return self.popen.poll()

    def wait(self, timeout):
        """Waits for the exit; returns the exit status (raises AssertionError on timeout)."""
        try:
            return self.popen.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            raise AssertionError("%s did not exit within %.0f s" % (self.name, timeout))

    # -- output
    def out(self):
        return read_text(self.out_path)

    def log(self):
        return read_text(self.log_path)

    # -- input (console)
    def send(self, line):
        assert self.popen.stdin is not None, self.name + " has no stdin pipe"
        self.popen.stdin.write((line + "\n").encode())
        self.popen.stdin.flush()

    def close_stdin(self):
        if self.popen.stdin is not None and not self.popen.stdin.closed:
            try:
                self.popen.stdin.close()
            except BrokenPipeError:
                pass

    # -- stopping (only this process)
    def signal(self, sig):
        if self.running():
            os.kill(self.pid, sig)

    def stop(self, grace=5.0):
        """SIGTERM, wait up to grace seconds, then SIGKILL; returns the exit status."""
        if self.running():
            try:
                os.kill(self.pid, signal.SIGTERM)
            except ProcessLookupError:
                pass
            try:
                self.popen.wait(timeout=grace)
            except subprocess.TimeoutExpired:
                self.kill_group()
        self.popen.wait()
        self.close_stdin()
        self._out.close()
        self._log.close()
        return self.popen.returncode

    def kill_group(self):
        """SIGKILL to the process group this process leads (its own session)."""
        try:
            os.killpg(self.pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass
        try:
            self.popen.wait(timeout=5)
        except subprocess.TimeoutExpired:
            pass


def processes_in_group(pgid):
    """Pids of live processes (not zombies) whose process group is pgid."""
    pids = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open("/proc/%s/stat" % entry) as f:
                stat = f.read()
        except OSError:
            continue
        fields = stat[stat.rfind(")") + 2:].split()
        state, pgrp = fields[0], int(fields[2])
        if pgrp == pgid and state != "Z":
            pids.append(int(entry))
    return pids


def shapeform_processes_on_domain(domain):
    """(pid, cmdline) of live shapeform processes whose command line names this domain."""
    found = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open("/proc/%s/cmdline" % entry, "rb") as f:
                argv = f.read().decode(errors="replace").split("\0")
            with open("/proc/%s/stat" % entry) as f:
                stat = f.read()
        except OSError:
            continue
        if stat[stat.rfind(")") + 2] == "Z" or not argv or "shapeform_" not in os.path.basename(argv[0]):
            continue
        for i, a in enumerate(argv[:-1]):
            if a == "--domain" and argv[i + 1] == str(domain):
                found.append((int(entry), " ".join(argv)))
    return found


# ----------------------------------------------------------------------------------------------
# Output parsing

def parse_status_table(text):
    """Rows of the supervisor's `status` table: {id: {alive, x1, x2, epoch, shape_error, heard}}."""
    rows = {}
    for line in text.splitlines():
        parts = line.split()
        if len(parts) != 8 or not parts[0].isdigit():
            continue
        rows[int(parts[0])] = {
            "alive": parts[1],
            "last_seen": parts[2],
            "x1": float(parts[3]),
            "x2": float(parts[4]),
            "epoch": int(parts[5]),
            "shape_error": None if parts[6] == "-" else float(parts[6]),
            "heard": None if parts[7] == "-" else int(parts[7]),
        }
    return rows


def last_json_line(text):
    for line in reversed(text.splitlines()):
        line = line.strip()
        if line.startswith("{"):
            return json.loads(line)
    return None


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def fnum(v):
    return None if v in (None, "") else float(v)


def mean(values):
    values = [v for v in values if v is not None]
    return sum(values) / len(values) if values else None


# ----------------------------------------------------------------------------------------------
# Swarm helpers

class Supervisor(Proc):
    """A supervisor driven through its console (stdin pipe; answers on stdout, text mode)."""

    def query(self, command, timeout=10.0):
        """Sends `command` then `metrics`; returns (text printed for command, metrics JSON).
        The metrics JSON line marks the end of the command's answer."""
        start = len(self.out())
        self.send(command)
        self.send("metrics")

        def answered():
            text = self.out()[start:]
            for i, line in enumerate(text.splitlines()):
                if line.startswith("{"):
                    return ("\n".join(text.splitlines()[:i]), json.loads(line))
            return None

        return poll(answered, timeout, "the supervisor's answer to '%s'" % command, 0.05)

    def status(self):
        text, metrics = self.query("status")
        return parse_status_table(text), metrics

    def metrics(self, timeout=10.0):
        start = len(self.out())
        self.send("metrics")
        return poll(lambda: last_json_line(self.out()[start:]), timeout, "the supervisor's metrics", 0.05)

    def wait_converged(self, timeout):
        """Runs `wait converged` at the console; True when converged, False on its timeout."""
        start = len(self.out())
        self.send("wait converged timeout=%g" % timeout)

        def done():
            text = self.out()[start:]
            if "converged at t=" in text:
                return "yes"
            if "wait converged: timed out" in text:
                return "no"
            return None

        return poll(done, timeout + 30, "the answer to 'wait converged'", 0.1) == "yes"

    def wait_agents(self, n, timeout):
        start = len(self.out())
        self.send("wait agents %d timeout=%g" % (n, timeout))

        def done():
            text = self.out()[start:]
            if re.search(r"^agents: \d+ alive", text, re.M):
                return "yes"
            if "wait agents: timed out" in text:
                return "no"
            return None

        return poll(done, timeout + 30, "the answer to 'wait agents'", 0.1) == "yes"

    def command(self, line, timeout=10.0):
        """Sends a command that publishes an epoch; returns the epoch number announced."""
        start = len(self.out())
        self.send(line)
        m = poll(lambda: re.search(r"^epoch (\d+):", self.out()[start:], re.M), timeout,
                 "the supervisor to publish '%s'" % line, 0.05)
        return int(m.group(1))


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
            p.stop()
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
            problems.append("new Fast DDS shared-memory files in %s: %s" % (SHM_DIR, new_shm))
        if failed or problems:
            self.print_logs()
        sys.stderr.write("[%s] %.1f s, run folder %s\n" % (self.id(), time.monotonic() - self.t0, self.run_dir))
        if problems:
            self.fail("after the test: " + "; ".join(problems))

    def _failed(self):
        outcome = getattr(self, "_outcome", None)
        result = getattr(outcome, "result", None)
        if result is None:
            return True
        # Sub-tests are recorded as _SubTest objects that point back to their test case.
        return any(getattr(t, "test_case", t) is self for t, _ in list(result.failures) + list(result.errors))

    def print_logs(self):
        names = []
        for root, _, files in os.walk(self.run_dir):
            for f in sorted(files):
                if f.endswith((".log", ".out")):
                    names.append(os.path.join(root, f))
        for path in sorted(names):
            lines = tail(path)
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

    def start_agent(self, i, config, domain=None, extra=(), seed=None, name=None):
        argv = [bin_path("shapeform_agent"), "--id", str(i), "--config", config,
                "--domain", str(self.domain if domain is None else domain)]
        if seed is not None:
            argv += ["--seed", str(seed)]
        argv += list(extra)
        return self.start(name or "agent_%d" % i, argv)

    def start_agents(self, n, config, domain=None, extra=(), seed=None, first=0, prefix="agent_"):
        agents = []
        for i in range(first, first + n):
            agents.append(self.start_agent(i, config, domain, extra, seed, name="%s%d" % (prefix, i)))
            time.sleep(0.02)  # stagger: no discovery storm
        return agents

    def start_meshed_agents(self, n, config, extra=(), timeout=60):
        """Starts agents 0..n-1 (seed 1) and waits until each logs hearing the n-1 others."""
        agents = self.start_agents(n, config, seed=1, extra=extra)
        poll(lambda: all("hearing %d neighbours" % (n - 1) in a.log() for a in agents), timeout,
             "the %d agents to hear each other" % n)
        return agents

    def start_supervisor(self, config, domain=None, script=None, record=None, json_mode=False, extra=(),
                         console=True, name="supervisor"):
        argv = [bin_path("shapeform_supervisor"), "--config", config,
                "--domain", str(self.domain if domain is None else domain)]
        if script is not None:
            argv += ["--script", script]
        if record is not None:
            argv += ["--record", record]
        if json_mode:
            argv += ["--json"]
        argv += list(extra)
        return self.start(name, argv, stdin="pipe" if console else None, cls=Supervisor)

    def write(self, name, text):
        path = os.path.join(self.run_dir, name)
        with open(path, "w") as f:
            f.write(text)
        return path

    def run_sim(self, config, args=()):
        """Runs shapeform_sim; returns its JSON object."""
        argv = [bin_path("shapeform_sim"), "--config", config] + list(args)
        r = subprocess.run(argv, capture_output=True, text=True, timeout=120)
        self.assertEqual(r.returncode, 0, "shapeform_sim failed: %s" % r.stderr[-2000:])
        return json.loads(r.stdout)

    def assert_all_alive(self, procs):
        dead = ["%s (status %s)" % (p.name, p.returncode) for p in procs if not p.running()]
        self.assertEqual(dead, [], "processes that stopped")


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
