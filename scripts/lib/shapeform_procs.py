#!/usr/bin/python3
"""Starting, stopping and reading shapeform processes (standard library only).

One library for everything that runs the project's programs from Python: the integration tests
(tests/integration/harness.py), the benchmark driver (bench/bench.py) and the paper's reproduction
(scripts/paper/run.py). Import it with a sys.path insert relative to the importing file:

    sys.path.insert(0, str(Path(__file__).resolve().parents[N] / "scripts" / "lib"))
    import shapeform_procs as procs

- `Proc`: a process in its own session (so a signal reaches only it and its children), stdout and
  stderr in files, stdin a pipe on request; stopped by its pid (SIGTERM, a grace period, then SIGKILL
  of its process group). `stop_all` stops many, spaced, with one grace period for all.
- `poll`: calls a condition until it holds or a timeout passes.
- Readers of machine output: `read_csv`, `json_lines`, `events`, `neighbours_heard`, `last_json_line`,
  `summary`.
- Leftover checks: `processes_in_group`, `shapeform_processes_on_domain`, `shm_files`.
"""
import csv
import json
import os
import re
import signal
import subprocess
import time

SHM_DIR = "/dev/shm"
SHM_PATTERN = re.compile(r"^(sem\.)?(fastrtps|fast_datasharing|fastdds)")


# ----------------------------------------------------------------------------------------------
# Waiting

def poll(predicate, timeout, what, interval=0.1):
    """Calls predicate() until it returns a truthy value (returned) or timeout seconds pass
    (AssertionError naming `what`)."""
    deadline = time.monotonic() + timeout
    while True:
        value = predicate()
        if value:
            return value
        if time.monotonic() >= deadline:
            raise AssertionError("timed out after %.0f s waiting for %s" % (timeout, what))
        time.sleep(interval)


def wait_for(predicate, timeout, interval=0.05):
    """Like poll, but returns the last value (falsy on timeout) instead of raising."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = predicate()
        if value:
            return value
        time.sleep(interval)
    return predicate()


# ----------------------------------------------------------------------------------------------
# Processes

def read_text(path):
    try:
        with open(path, "r", errors="replace") as f:
            return f.read()
    except FileNotFoundError:
        return ""


class Proc:
    """One process: its own session and process group, stdout in DIR/NAME.out and stderr in
    DIR/NAME.log (or the suffixes given)."""

    def __init__(self, name, argv, run_dir, stdin=None, env=None, cwd=None, out_suffix=".out",
                 err_suffix=".log"):
        self.name = name
        self.argv = [str(a) for a in argv]
        self.out_path = os.path.join(str(run_dir), name + out_suffix)
        self.log_path = os.path.join(str(run_dir), name + err_suffix)
        self._out = open(self.out_path, "wb")
        self._log = open(self.log_path, "wb")
        self.popen = subprocess.Popen(
            self.argv,
            stdin=subprocess.PIPE if stdin == "pipe" else subprocess.DEVNULL,
            stdout=self._out,
            stderr=self._log,
            start_new_session=True,  # own session and process group: signals reach only it
            env=env,
            cwd=cwd,
        )
        self.pid = self.popen.pid
        self._read = 0  # bytes of stdout consumed by next_event

    # -- state
    def running(self):
        return self.popen.poll() is None

    @property
    def returncode(self):
        return self.popen.poll()

    def wait(self, timeout):
        """Waits for the exit; returns the exit status (AssertionError on timeout)."""
        try:
            return self.popen.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            raise AssertionError("%s did not exit within %.0f s" % (self.name, timeout))

    # -- output
    def out(self):
        return read_text(self.out_path)

    def log(self):
        return read_text(self.log_path)

    def events(self, kind=None, since=0):
        """JSON event lines of stdout (a program run with --json), optionally of one kind."""
        return events(self.out()[since:], kind)

    def mark(self):
        """Position in stdout: pass it as `since` to see only what came after."""
        return len(self.out())

    def wait_event(self, kind, timeout, since=0, where=None, what=None):
        """The first event of `kind` after `since` (and satisfying where(event)); AssertionError on timeout."""
        def found():
            for e in self.events(kind, since):
                if where is None or where(e):
                    return e
            return None
        return poll(found, timeout, what or "%s to print a '%s' event" % (self.name, kind), 0.05)

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
            try:
                os.kill(self.pid, sig)
            except ProcessLookupError:
                pass

    def kernel_state(self):
        """The kernel's one-letter state of the process (R, S, D, T, Z...), 'gone' when it has exited."""
        return (_proc_stat(self.pid) or ("gone",))[0]

    def stop(self, grace=5.0):
        """SIGTERM, wait up to grace seconds, then SIGKILL of the group; returns the exit status."""
        stop_all([self], grace=grace)
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

    def _close(self):
        self.close_stdin()
        self._out.close()
        self._log.close()


def stop_all(procs, grace=10.0, spacing=0.0):
    """SIGTERM each running process (spacing seconds apart, so dozens of participants do not leave at
    the same instant), wait up to grace seconds for all, then SIGKILL the groups of those left.
    Returns the exit codes (None: had to be killed)."""
    for p in procs:
        if p.running():
            p.signal(signal.SIGTERM)
            if spacing > 0:
                time.sleep(spacing)
    deadline = time.monotonic() + grace
    codes = []
    for p in procs:
        try:
            codes.append(p.popen.wait(timeout=max(0.1, deadline - time.monotonic())))
        except subprocess.TimeoutExpired:
            p.kill_group()
            p.popen.wait()
            codes.append(None)
        p._close()
    return codes


def run(argv, timeout=None, check=True):
    """Runs a program to its end; returns the CompletedProcess (text). check: raise on a non-zero exit."""
    r = subprocess.run([str(a) for a in argv], capture_output=True, text=True, timeout=timeout,
                       stdin=subprocess.DEVNULL)
    if check and r.returncode != 0:
        raise RuntimeError("%s failed (exit %d): %s" % (os.path.basename(str(argv[0])), r.returncode,
                                                       r.stderr.strip()[-2000:]))
    return r


def sets_args(sets):
    """--set KEY=VALUE arguments for a list of overrides."""
    return [a for s in sets for a in ("--set", s)]


# ----------------------------------------------------------------------------------------------
# Machine output

def json_lines(text):
    """Every JSON object of a text, one per line (other lines are skipped)."""
    out = []
    for line in text.splitlines():
        line = line.strip()
        if line.startswith("{"):
            try:
                out.append(json.loads(line))
            except json.JSONDecodeError:
                pass  # a line cut by a kill
    return out


def events(text, kind=None):
    """The JSON event lines of a program run with --json, optionally only those with "event": kind."""
    return [e for e in json_lines(text) if kind is None or e.get("event") == kind]


def neighbours_heard(text):
    """{agent id: neighbours heard} from the newest status event of each agent in the JSON event lines of an
    agent (or agent group) run with --json."""
    return {e["id"]: e["neighbours_heard"] for e in events(text, "status")}


def last_json_line(text):
    """The last JSON object of a text (None when there is none)."""
    found = json_lines(text)
    return found[-1] if found else None


def summary(text):
    """A program's final JSON summary: the "summary" event, else the last JSON line (None if none)."""
    found = events(text, "summary")
    return found[-1] if found else last_json_line(text)


# CSV columns read as Python integers: command epochs are 64-bit counters.
INT_COLUMNS = ("epoch",)


def read_csv(path, numeric=False):
    """Rows of a CSV file as dicts ([] when the file is missing). numeric: values as floats (empty
    field -> None), except the integer columns of INT_COLUMNS (a 64-bit epoch does not fit a float),
    and rows that do not parse (a line cut by a kill) skipped."""
    try:
        with open(str(path), newline="") as f:
            rows = list(csv.DictReader(f))
    except FileNotFoundError:
        return []
    if not numeric:
        return rows
    out = []
    for r in rows:
        try:
            if None in r or None in r.values():
                continue  # too many or too few fields
            out.append({k: (None if v == "" else int(v) if k in INT_COLUMNS else float(v)) for k, v in r.items()})
        except ValueError:
            continue
    return out


# ----------------------------------------------------------------------------------------------
# Leftovers

def cpu_s(pid):
    """CPU time (user + system) a process has used so far, seconds (/proc/PID/stat)."""
    with open("/proc/%d/stat" % pid) as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _proc_stat(pid):
    """(state, pgrp) of a process, None when it is gone."""
    try:
        with open("/proc/%s/stat" % pid) as f:
            stat = f.read()
    except OSError:
        return None
    fields = stat[stat.rfind(")") + 2:].split()
    return fields[0], int(fields[2])


def processes_in_group(pgid):
    """Pids of live processes (not zombies) whose process group is pgid."""
    pids = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            st = _proc_stat(entry)
            if st and st[1] == pgid and st[0] != "Z":
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
        except OSError:
            continue
        st = _proc_stat(entry)
        if not st or st[0] == "Z" or not argv or "shapeform_" not in os.path.basename(argv[0]):
            continue
        if any(a == "--domain" and b == str(domain) for a, b in zip(argv, argv[1:])):
            found.append((int(entry), " ".join(argv)))
    return found


def shm_files():
    """Names of the Fast DDS shared-memory files in /dev/shm."""
    try:
        return {f for f in os.listdir(SHM_DIR) if SHM_PATTERN.match(f)}
    except FileNotFoundError:
        return set()


def module_main(path, what):
    """The `__main__` of a module of scripts/lib: it runs nothing, it says what it is (scripts/ holds
    nothing that cannot answer --help). Exits 0 for no argument or --help, 2 otherwise."""
    import sys as _sys
    name = os.path.basename(path)
    print("usage: import %s -- %s is a module: %s; it runs nothing itself" % (os.path.splitext(name)[0], name, what))
    _sys.exit(0 if _sys.argv[1:] in ([], ["--help"], ["-h"]) else 2)


if __name__ == "__main__":
    module_main(__file__, "the process library of the tests, the benchmarks and the reproduction")
