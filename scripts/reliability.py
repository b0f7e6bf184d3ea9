#!/usr/bin/python3
"""Faults on a real swarm, measured: how fast the swarm notices, how fast it recovers, what it loses.

  scripts/reliability.py [--runs R] [--quick] [--only FAULT[,FAULT...]] [--laws paper,arc]
                         [--losses 0,10,20,40] [--out FILE] [--build DIR | --bin DIR] [--work DIR]
                         [--dry-run]

Faults (--only; default all): on a LAN of test hosts (scripts/netlab.sh: 12 agents over the hosts
h1..h3, the supervisor on h4, lan profile; needs root) for each law (the paper's: the circle scenario;
the arc law: arc_circle):
  loss       random loss of PCT % of UDP datagrams in and out of every host (each of --losses), from
             the `start` of a fresh swarm until it converged
  partition  one agent host cut off for 10 s, then healed
  cut        one agent host cut off for a duration of each class (--classes): just under the lease
             (1.0-1.9 s), just past it (2.05-2.6 s), long (5-60 s), spread over the runs; measured:
             how long after the heal everyone hears everyone again
  stop       one process (an agent, every 4th run the supervisor) stopped (SIGSTOP) for a duration of
             each class, then resumed; measured: how long after it everyone hears everyone again
  kill       kill -9 of 3 agents on 3 different hosts
  pause      one agent paused (SIGSTOP) for 5 s, then resumed
  supervisor the supervisor killed (kill -9) and started again at once on another host
and on loopback (no root needed):
  stall      one agent, or the supervisor, stalled 3, 5 or 20 s (the table "Stalls, partitions and membership")

Per run: detect (s), recover (s), samples lost (%), processes aborted, recording complete; the
definitions are in docs/RELIABILITY.md ("Faults on a LAN") and in measure_lan_run below. Every table
goes between its markers in --out (default docs/RELIABILITY.md; with --quick only when --out is given),
with the command line, the date, the git commit and the load average at the start; every run in
WORK/runs.json (WORK default runs/<UTC time>-reliability). Progress on stderr. --quick: a smoke run
(the arc law, losses 0 and 20 %, stalls of 5 s). --dry-run: print the plan and an estimate of its
duration, start nothing. --load N: N busy loops share the machine with the swarm for the whole run (a
loaded host; recorded with the tables). Run it alone on the machine if the numbers are to be published (they are
timings); the load average is recorded either way. Exit status: 0 ok (whatever was measured), 1
failure to run, 2 bad arguments.
"""
import argparse
import json
import math
import os
import signal
import statistics
import subprocess
import sys
import time
from pathlib import Path

sys.dont_write_bytecode = True  # no __pycache__ in scripts/
REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "scripts" / "lib"))
import shapeform_procs as procs  # noqa: E402

DOC = REPO / "docs" / "RELIABILITY.md"
GOAL_S = 3.0  # the recovery the swarm must achieve after a stall, s
LAN_FAULTS = ("partition", "kill", "pause", "supervisor", "loss", "cut", "stop")
HEAL_FAULTS = ("cut", "stop")  # rows per duration class; measured: everyone heard again
CLASSES = {  # duration classes of cut and stop, s (the lan profile's lease is 2 s, its announcements 0.5 s)
    "under": (1.0, 1.9),   # just under the lease
    "past": (2.05, 2.6),   # just past it
    "long": (5.0, 60.0),   # long: spread geometrically
}
HEARD_HOLD_S = 1.0  # everyone hears everyone once that has held this long
FAULTS = LAN_FAULTS + ("stall",)
LAWS = {"paper": "circle", "arc": "arc_circle"}  # law -> scenario
LAN_DOMAIN = 230   # outside the tests' (101..149, 150..229) and the launcher's (10..100) domains
LAN_SUBNET = "10.201.10"  # the test hosts' LAN (the integration tests use 10.200.x)
N_AGENTS = 12
PARTITION_S, PAUSE_S = 10.0, 5.0
HOLD_S = 2.0       # a recovery counts once it has held this long
STATUS_HZ = 4.0    # agents' status events: a neighbour count is seen within 0.25 s
POLL_S = 0.1       # the driver reads every output this often
RUN_S = {"loss": 25, "partition": 25, "kill": 25, "pause": 15, "supervisor": 12, "cut": 12, "stop": 12}  # rough,
# for --dry-run, plus the duration of cut and stop


def class_duration(cls, k, runs):
    """The duration of run k of `runs` in class cls: spread evenly over its range (long: geometrically)."""
    lo, hi = CLASSES[cls]
    f = k / (runs - 1) if runs > 1 else 0.5
    return lo * (hi / lo) ** f if cls == "long" else lo + (hi - lo) * f


def log(msg):
    print(msg, file=sys.stderr, flush=True)


class Swarm:
    """A supervisor (console on a pipe) and agents 0..n-1, all with --json, on one domain."""

    def __init__(self, bins, domain, n, run_dir, sets):
        self.n = n
        self.sup = None
        self.agents = []
        cfg = REPO / "config" / "scenarios" / "circle.yaml"
        common = ["--config", cfg, "--json", "--domain", domain] + procs.sets_args(sets)
        try:
            self.sup = procs.Proc("supervisor", [bins / "shapeform_supervisor"] + common, run_dir, stdin="pipe")
            for i in range(n):
                self.agents.append(procs.Proc("agent_%d" % i, [bins / "shapeform_agent", "--id", i, "--seed", 1] +
                                              common, run_dir))
                time.sleep(0.02)  # stagger: no discovery storm
            if not self.ask("wait agents %d timeout=60" % n, "wait", 90)["ok"]:
                raise RuntimeError("the supervisor did not hear the %d agents within 60 s" % n)
            self.command("start")
            if not self.ask("wait converged timeout=60", "wait", 90)["ok"]:
                raise RuntimeError("the swarm did not converge within 60 s")
        except BaseException:
            self.stop()
            raise

    def stop(self):
        procs.stop_all(([self.sup] if self.sup else []) + self.agents, grace=10.0, spacing=0.02)

    def ask(self, line, kind, timeout, where=None):
        since = self.sup.mark()
        self.sup.send(line)
        return self.sup.wait_event(kind, timeout, since, where, "the answer to '%s'" % line)

    def command(self, line):
        return self.ask(line, "epoch", 10)["epoch"]

    def alive(self):
        """Ids the supervisor reports alive now (its "agent" events replayed)."""
        ids = set()
        for e in self.sup.events("agent"):
            (ids.add if e["change"] == "joined" else ids.discard)(e["id"])
        return ids

    def everyone_hears_everyone(self, marks):
        """Every agent's newest status since its mark reports n-1 neighbours, and the supervisor has all alive."""
        for a, m in zip(self.agents, marks):
            heard = procs.neighbours_heard(a.out()[m:])
            if not heard or any(k != self.n - 1 for k in heard.values()):
                return False
        return self.alive() == set(range(self.n))


def measure_recovery(swarm, victim, t0, marks, hold_s, timeout_s):
    """Seconds from t0 (the SIGCONT) until every process hears every other again, or None if some process
    does not by timeout_s. Per process: an agent's time is the first moment its newest status reports
    all n-1 others (statuses of the stalled agent count from 0.3 s after the SIGCONT: its first tick may
    still report neighbours from samples the kernel buffered during the stall); the supervisor's is the
    moment from which it reports every agent alive without a break. Once every process has its time,
    the whole membership must be seen complete at once within the following hold_s (else: not
    recovered), and the result is the latest of the times."""
    first = {}        # agent name -> when it first heard everyone
    sup_since = None  # since when the supervisor reports every agent alive
    seen_whole = False
    marks = list(marks)
    late = [a is victim for a in swarm.agents]  # the stalled agent: its mark is taken 0.3 s after t0
    while True:
        now = time.monotonic()
        whole = True
        for i, a in enumerate(swarm.agents):
            if late[i] and now - t0 >= 0.3:
                marks[i], late[i] = a.mark(), False
            heard = {} if late[i] else procs.neighbours_heard(a.out()[marks[i]:])
            full = bool(heard) and all(k == swarm.n - 1 for k in heard.values())
            whole = whole and full
            if full and a.name not in first:
                first[a.name] = now
        if swarm.alive() == set(range(swarm.n)):
            sup_since = now if sup_since is None else sup_since
        else:
            sup_since, whole = None, False
        if len(first) == swarm.n and sup_since is not None:
            latest = max(max(first.values()), sup_since)
            seen_whole = seen_whole or whole
            if now >= latest + hold_s:
                return (latest - t0) if seen_whole else None
        if now - t0 > timeout_s + hold_s:
            return None
        time.sleep(0.05)


def run_trial(swarm, target, k, stall_s, args):
    victim = swarm.sup if target == "supervisor" else swarm.agents[k % swarm.n]
    victim_mark = victim.mark()
    victim.signal(signal.SIGSTOP)
    time.sleep(stall_s)
    marks = [a.mark() for a in swarm.agents]  # statuses from the resume on
    victim.signal(signal.SIGCONT)
    t0 = time.monotonic()
    recovery = measure_recovery(swarm, victim, t0, marks, args.hold, args.timeout)
    trial = {"target": target, "victim": victim.name, "stall_s": stall_s, "recovery_s": recovery,
             "recovered_events": len(victim.events("recovered", victim_mark)), "reconverged": False}
    if recovery is not None:
        # Everyone hears the supervisor: a new epoch reaches every agent; then the formation converges.
        since = [a.mark() for a in swarm.agents]
        epoch = swarm.command("start")
        adopted = procs.wait_for(lambda: all(any(e["epoch"] == epoch for e in a.events("command", m))
                                             for a, m in zip(swarm.agents, since)), 10)
        trial["epoch_adopted"] = bool(adopted)
        converged = swarm.ask("wait converged timeout=30", "wait", 60)["ok"]
        trial["reconverged"] = bool(adopted) and converged
    return trial


def fmt_s(v):
    return "-" if v is None else "%.2f" % v


def table(trials, stalls, targets):
    lines = ["| stalled process | stall (s) | trials | heard again within %g s | worst (s) | median (s) | "
             "re-converged |" % GOAL_S,
             "|---|---|---|---|---|---|---|"]
    for target in targets:
        for s in stalls:
            rows = [t for t in trials if t["target"] == target and t["stall_s"] == s]
            if not rows:
                continue
            rec = [t["recovery_s"] for t in rows]
            ok = [r for r in rec if r is not None]
            worst = "not within %g s" % rows[0]["timeout_s"] if len(ok) < len(rec) else fmt_s(max(ok))
            lines.append("| %s | %g | %d | %d | %s | %s | %d |" % (
                target, s, len(rows), sum(1 for r in ok if r <= GOAL_S), worst,
                fmt_s(statistics.median(ok)) if ok else "-", sum(1 for t in rows if t["reconverged"])))
    return "\n".join(lines) + "\n"


def run_stalls(args, bins, work):
    """The stall trials on loopback: one swarm per target and stall length, reused while it recovers."""
    # Statuses 4 times a second: the recovery is seen to within 0.25 s.
    sets = ["agent.status_rate_hz=4"] + args.set
    trials = []
    t_start = time.monotonic()
    for target in args.targets:
        for stall in args.stalls:
            swarm, k, n_swarm = None, 0, 0
            try:
                while k < args.trials:
                    if swarm is None:
                        n_swarm += 1
                        run_dir = work / ("stall_%s_%gs_%d" % (target, stall, n_swarm))
                        run_dir.mkdir(parents=True, exist_ok=True)
                        swarm = Swarm(bins, args.domain, args.agents, run_dir, sets)
                    t = run_trial(swarm, target, k, stall, args)
                    t["timeout_s"] = args.timeout
                    trials.append(t)
                    k += 1
                    log("[%4.0f s] fault stall, %s stalled %g s, trial %d/%d (%s): heard again after %s s, "
                        "re-converged %s" % (time.monotonic() - t_start, target, stall, k, args.trials, t["victim"],
                                             fmt_s(t["recovery_s"]), t["reconverged"]))
                    if t["recovery_s"] is None or not t["reconverged"]:
                        swarm.stop()  # the next trial starts from a whole swarm
                        swarm = None
            finally:
                if swarm is not None:
                    swarm.stop()
    return trials


# ------------------------------------------------------------------------------------------------
# Faults on a LAN of test hosts

class Tail:
    """The JSON events a process printed since the last read (complete lines only)."""

    def __init__(self, proc):
        self.proc, self.pos = proc, 0

    def read(self):
        try:
            with open(self.proc.out_path, "rb") as f:
                f.seek(self.pos)
                data = f.read()
        except FileNotFoundError:
            return []
        cut = data.rfind(b"\n") + 1
        self.pos += cut
        return procs.events(data[:cut].decode(errors="replace"))


class Watch:
    """What the driver sees of a LanSwarm, every POLL_S: the newest neighbour count of every agent (its
    status events), the agents the current supervisor reports alive (its "agent" events), whether it
    reports the swarm converged (its answer to `metrics`, asked every 0.25 s), each with the moment
    the driver read it (time.monotonic)."""

    def __init__(self, swarm):
        self.swarm = swarm
        self.tails = {}
        self.heard = {}       # agent id -> newest neighbours_heard
        self.alive = set()    # the current supervisor's view
        self.converged = False
        self.drops = []       # (t, id, by): the supervisor's "lost"/"left" events (by None), and agents that
                              # report fewer (by: the reporting agent)
        self.sup_drops = []   # (t, id): the supervisor's "lost"/"left" events only
        self.in_force = None  # when the current supervisor printed "in_force"
        self.exits = {}       # name -> (t, code) of processes that exited while watched
        self.expected_exits = set()
        self._asked = 0.0
        self.new_supervisor()

    def new_supervisor(self):
        self.alive, self.converged, self.in_force = set(), False, None

    def forget_statuses(self):
        """From now on, count only statuses printed after this moment."""
        self.heard = {}

    def tail(self, p):
        if p.name not in self.tails or self.tails[p.name].proc is not p:
            self.tails[p.name] = Tail(p)
        return self.tails[p.name]

    def poll(self, n_expected):
        now = time.monotonic()
        for i, a in list(self.swarm.agents.items()):
            for e in self.tail(a).read():
                if e.get("event") == "status":
                    before = self.heard.get(i)
                    if before is not None and before >= n_expected - 1 > e["neighbours_heard"]:
                        self.drops.append((now, None, i))
                    self.heard[i] = e["neighbours_heard"]
        sup = self.swarm.sup
        for e in self.tail(sup).read():
            kind = e.get("event")
            if kind == "agent":
                if e["change"] == "joined":
                    self.alive.add(e["id"])
                else:
                    self.alive.discard(e["id"])
                    self.drops.append((now, e["id"], None))
                    self.sup_drops.append((now, e["id"]))
            elif kind == "metrics":
                self.converged = bool(e.get("converged"))
            elif kind == "in_force" and self.in_force is None:
                self.in_force = now
        for p in self.swarm.procs:
            if not p.running() and p.name not in self.exits:
                self.exits[p.name] = (now, p.returncode)
        if sup.running() and now - self._asked >= 0.25:
            self._asked = now
            try:
                sup.send("metrics")
            except (BrokenPipeError, OSError):
                pass
        return now

    def whole(self, ids):
        """The swarm of `ids` is whole: the supervisor reports exactly them alive, each reports hearing all
        the others, and the supervisor says converged."""
        return (self.alive == set(ids) and self.converged and
                all(self.heard.get(i) == len(ids) - 1 for i in ids))

    def heard(self, ids):
        """Everyone hears everyone: the supervisor reports exactly `ids` alive and each reports hearing all
        the others."""
        return self.alive == set(ids) and all(self.heard.get(i) == len(ids) - 1 for i in ids)

    def until_whole(self, ids, t_from, timeout, hold=HOLD_S, test=None):
        """The first moment from t_from on after which the swarm of `ids` stays whole (or test(ids) holds)
        for `hold` seconds (seconds after t_from), or None when that does not happen within timeout seconds."""
        test = test or self.whole
        since = None
        while True:
            now = self.poll(len(ids))
            if test(ids):
                since = now if since is None else since
                if now - since >= hold:
                    return since - t_from
            else:
                since = None
            if now - t_from > timeout + hold:
                return None
            time.sleep(POLL_S)

    def sleep(self, seconds, n_expected):
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.poll(n_expected)
            time.sleep(min(POLL_S, max(0.0, end - time.monotonic())))

    def aborted(self, since):
        """Processes that exited by themselves after `since` (not the ones the fault killed)."""
        return sorted("%s (exit %s)" % (name, code) for name, (t, code) in self.exits.items()
                      if t >= since and name not in self.expected_exits)


def status_counters(echo_out):
    """{agent id: [(stamp s, ticks, samples_received)]} from shapeform_echo's lines of shapeform/status."""
    found = {}
    for line in procs.json_lines(procs.read_text(echo_out)):
        s = line.get("data", line)
        if "samples_received" in s and "ticks" in s:
            found.setdefault(s["id"], []).append((s["stamp_ns"] * 1e-9, s["ticks"], s["samples_received"]))
    for rows in found.values():
        rows.sort()
    return found


def counter_at(rows, t, k):
    """Counter k (1: ticks, 2: received) of one agent at time t, linear between its statuses, held
    beyond the first and the last."""
    if not rows:
        return None
    if t <= rows[0][0]:
        return rows[0][k]
    for a, b in zip(rows, rows[1:]):
        if a[0] <= t <= b[0]:
            f = (t - a[0]) / (b[0] - a[0]) if b[0] > a[0] else 1.0
            return a[k] + f * (b[k] - a[k])
    return rows[-1][k]


def samples_lost(counters, receivers, t0, t1):
    """Percent of the state samples the receivers should have received in [t0, t1] that they did not:
    expected = for each receiver, the states the other agents published meanwhile (their tick counts:
    one state per tick), received = its samples_received count. None without statuses."""
    expected = received = 0.0
    for r in receivers:
        rr = counters.get(r)
        if not rr or rr[-1][0] < t1 - 1.0:
            continue  # no status near the end of the window
        received += counter_at(rr, t1, 2) - counter_at(rr, t0, 2)
        for s, rows in counters.items():
            if s != r:
                expected += counter_at(rows, t1, 1) - counter_at(rows, t0, 1)
    if expected <= 0:
        return None
    return max(0.0, 100.0 * (1.0 - received / expected))


def recording_complete(record, period_s, since_wall, ids):
    """(complete, wall_s of its last row): the recording's metrics rows after since_wall have no gap longer
    than 2 metric periods and its positions rows after since_wall name every agent of `ids`."""
    rows = procs.read_csv(os.path.join(record, "metrics.csv"), numeric=True)
    walls = [r["wall_s"] for r in rows if r["wall_s"] is not None and r["wall_s"] >= since_wall]
    if len(walls) < 2:
        return False, since_wall
    gap_ok = max(b - a for a, b in zip(walls, walls[1:])) <= 2 * period_s + 1e-6
    seen = {int(r["agent"]) for r in procs.read_csv(os.path.join(record, "positions.csv"), numeric=True)
            if r["wall_s"] is not None and r["wall_s"] > since_wall}
    return gap_ok and set(ids) <= seen, walls[-1]


class LanRow:
    """One row of runs: a fault, a law, a loss level; a swarm reused from run to run (a fresh one per
    run for loss, and after a run that did not recover)."""

    def __init__(self, lab, bins, fault, law, loss, args, work):
        self.lab, self.bins, self.fault, self.law, self.loss, self.args = lab, bins, fault, law, loss, args
        self.config = REPO / "config" / "scenarios" / (LAWS[law] + ".yaml")
        self.work = work
        self.swarm = self.watch = self.echo = None
        self.n_swarms = 0
        self.rec_marks = {}  # record dir -> wall_s checked up to

    def up(self):
        import lanswarm
        self.n_swarms += 1
        level = self.loss if self.fault in HEAL_FAULTS else "loss%g" % self.loss
        run_dir = self.work / ("%s_%s_%s_%d" % (self.fault, self.law, level, self.n_swarms))
        run_dir.mkdir(parents=True, exist_ok=True)
        sets = ["agent.status_rate_hz=%g" % STATUS_HZ]
        self.swarm = lanswarm.LanSwarm(self.lab, self.bins, self.config, LAN_DOMAIN, run_dir, sets)
        self.watch = Watch(self.swarm)
        try:
            self.swarm.start(N_AGENTS, command=False)
            # The samples' counters: every agent's status, read on the supervisor's host.
            self.echo = procs.Proc("echo_status", self.lab.on(lanswarm.SUPERVISOR_HOST, [
                Path(self.bins) / "shapeform_echo", "shapeform/status", "--domain", LAN_DOMAIN] +
                self.lab.lan_sets(lanswarm.SUPERVISOR_HOST)), run_dir)
            self.swarm.procs.append(self.echo)
        except BaseException:
            self.down()
            raise

    def down(self):
        """Stops the swarm; names of its processes that exited abnormally when stopped."""
        if self.swarm is None:
            return []
        if self.echo is not None:  # the measuring tool first, alone: its exit is not the swarm's
            procs.stop_all([self.echo], grace=10.0)
        codes = self.swarm.stop()
        # A process that ends by our SIGTERM exits 0, or dies of it before its handler is installed (-15).
        bad = ["%s (exit %s)" % (name, "killed after 10 s" if code is None else code) for name, code in codes.items()
               if name not in self.watch.exits and name not in self.watch.expected_exits and code not in (0, -15)]
        for p in self.swarm.procs:
            text = p.log()
            hit = next((w for w in ("Assertion", "terminate called", "core dumped", "Aborted") if w in text), None)
            if hit:
                bad.append("%s (log: %s)" % (p.name, hit))
        self.swarm = self.watch = self.echo = None
        return bad

    def settle(self, ids, timeout=60):
        """Waits until the swarm of `ids` is whole (held HOLD_S); False when it is not within timeout."""
        return self.watch.until_whole(ids, time.monotonic(), timeout) is not None

    def check_recordings(self, ids):
        ok = True
        for sup in [p for p in self.swarm.procs if p.name.startswith("supervisor_")]:
            since = self.rec_marks.get(sup.record, 0.0)
            if since is None:
                continue  # finished and checked
            complete, last = recording_complete(sup.record, 0.1, since, ids if sup is self.swarm.sup else ())
            ok = ok and complete
            self.rec_marks[sup.record] = last if sup.running() else None
        return ok

    def run(self, k, last=False):
        """Run k (0-based): the fault, then its measures (a dict). last: the row's last run (the swarm is not
        made whole again for a next one)."""
        ids = list(range(N_AGENTS))
        t_ab = time.monotonic()
        if self.swarm is None:
            self.up()
            if self.fault != "loss":
                self.swarm.command("start")
        sw, w = self.swarm, self.watch
        if self.fault != "loss" and not self.settle(ids):
            raise RuntimeError("the swarm was not whole (all heard, converged) within 60 s before the fault")
        r = {"fault": self.fault, "law": self.law, "loss": self.loss, "run": k + 1, "detect_s": None,
             "recover_s": None, "lost_pct": None, "aborted": [], "recording": None}
        survivors = ids
        w.poll(N_AGENTS)  # everything printed before the fault is read before it
        w.drops, w.sup_drops = [], []
        if self.fault == "loss":
            for h in self.lab.hosts:
                if self.loss > 0:
                    self.lab.fault(h, "loss", self.loss)
            t_fault = time.monotonic()
            sw.command("start")
            t_end = t_fault
        elif self.fault == "partition":
            # From the moment netlab.sh returns: its rule is in place (the call takes up to a second or two
            # on a loaded machine; its duration is kept as fault_call_s).
            host = "h%d" % (1 + k % 3)
            t_call = time.monotonic()
            self.lab.fault(host, "partition")
            t_fault = time.monotonic()
            w.sleep(PARTITION_S, N_AGENTS)
            self.lab.fault(host, "heal")
            t_end = time.monotonic()
            r["victim"], r["fault_call_s"] = host, t_fault - t_call
        elif self.fault == "kill":
            victims = [(k % 4), 4 + (k + 1) % 4, 8 + (k + 2) % 4]  # one on each of h1, h2, h3
            t_fault = t_end = time.monotonic()
            for i in victims:
                w.expected_exits.add(sw.agents[i].name)
                sw.agents[i].signal(signal.SIGKILL)
            survivors = [i for i in ids if i not in victims]
            r["victim"] = victims
        elif self.fault in HEAL_FAULTS:
            # The duration from the moment the fault is in place (netlab.sh returned, SIGSTOP sent) to the
            # call that ends it; the time that call took is kept as end_call_s.
            d = class_duration(self.loss, k, self.args.runs)
            marks = {p: p.mark() for p in sw.procs if p.running()}
            victim = ("h%d" % (1 + k % 3) if self.fault == "cut" else
                      sw.sup if k % 4 == 3 else sw.agents[(5 * k + 1) % N_AGENTS])
            if self.fault == "cut":
                self.lab.fault(victim, "partition")
            else:
                victim.signal(signal.SIGSTOP)
            t_fault = time.monotonic()
            w.sleep(d, N_AGENTS)
            t_call = time.monotonic()
            if self.fault == "cut":
                self.lab.fault(victim, "heal")
            else:
                victim.signal(signal.SIGCONT)
            t_end = time.monotonic()
            r.update({"class": self.loss, "duration_s": t_call - t_fault, "end_call_s": t_end - t_call,
                      "victim": victim if self.fault == "cut" else victim.name})
        elif self.fault == "pause":
            victim = sw.agents[(5 * k + 1) % N_AGENTS]
            t_fault = time.monotonic()
            victim.signal(signal.SIGSTOP)
            w.sleep(PAUSE_S, N_AGENTS)
            victim.signal(signal.SIGCONT)
            t_end = time.monotonic()
            r["victim"] = victim.name
        else:  # supervisor
            old = sw.sup
            host = "h1" if old.host != "h1" else "h4"
            t_fault = t_end = time.monotonic()
            w.expected_exits.add(old.name)
            old.signal(signal.SIGKILL)
            old.wait(10)
            self.check_recordings(ids)  # the old recording up to the kill
            sw.start_supervisor(host)
            w.new_supervisor()
            r["victim"] = "%s -> %s" % (old.host, host)
        if self.fault not in ("supervisor",) + HEAL_FAULTS:
            # Detect: the first agent dropped (the supervisor's "lost"/"left", or an agent hearing fewer).
            # A partitioned host's agents hear the others stop as soon as netlab.sh has put its first rule
            # (packets in) in place, before the partition is complete: only the other side's view counts.
            def first_drop():
                w.poll(N_AGENTS)
                return [t for t, _, by in w.drops if t >= t_fault and
                        not (self.fault == "partition" and by is not None and sw.hosts[by] == r["victim"])]
            found = procs.wait_for(first_drop, 10 if self.fault != "loss" else 0, POLL_S)
            r["detect_s"] = (min(found) - t_fault) if found else None
        w.forget_statuses()
        timeout = self.args.timeout
        if self.fault in HEAL_FAULTS:
            # Everyone hears everyone again (statuses printed after the end of the fault), then the rest.
            r["heard_s"] = w.until_whole(survivors, t_end, timeout, HEARD_HOLD_S, w.heard)
            time.sleep(0.3)  # the events of the last tick
            rebuilt = [e.get("cause") for p, m in marks.items() for e in p.events("recovered", m)]
            r["recreated"] = len(rebuilt)
            r["recreated_causes"] = sorted(set(rebuilt))
        # Under loss too every agent must hear all the others: loss alone must not drop a neighbour
        # (agent.neighbour_timeout_periods, 40 by default, is far beyond the losses measured here).
        rec = w.until_whole(survivors, t_end, timeout)
        t_stop = time.monotonic() if rec is None else t_end + rec
        if self.fault == "supervisor":
            r["detect_s"] = None if w.in_force is None else w.in_force - t_fault
        r["recover_s"] = rec
        r["dropped"] = len({i for t, i in w.sup_drops if t >= t_fault})
        time.sleep(0.6)  # the echo's newest statuses
        r["lost_pct"] = samples_lost(status_counters(self.echo.out_path), survivors, t_fault, t_stop)
        r["aborted"] = w.aborted(t_ab)
        r["recording"] = self.check_recordings(survivors)
        # Back to the whole swarm for the next run.
        if self.fault == "loss":
            for h in self.lab.hosts:
                self.lab.fault(h, "heal")
            r["aborted"] += self.down()
        elif rec is None:
            r["aborted"] += self.down()  # the next run starts from a fresh swarm
        elif self.fault == "kill" and not last:
            for i in r["victim"]:
                sw.start_agent(i, sw.hosts[i], name="agent_%d_r%d" % (i, k + 1))
        return r

    def close(self):
        return self.down()


def run_lan(args, bins, work, plan, publish):
    import netlab
    runs = []
    t_start = time.monotonic()
    with netlab.NetLab("rel", hosts=4, subnet=LAN_SUBNET) as lab:
        for fault, law, loss in plan:
            row = LanRow(lab, bins, fault, law, loss, args, work)
            level = " %s" % loss if fault in HEAL_FAULTS else " %g %%" % loss if fault == "loss" else ""
            try:
                for k in range(args.runs):
                    try:
                        r = row.run(k, last=k + 1 == args.runs)
                    except (RuntimeError, AssertionError) as e:
                        r = {"fault": fault, "law": law, "loss": loss, "run": k + 1, "error": str(e),
                             "aborted": row.close()}
                    runs.append(r)
                    heard = (", %.2f s: everyone heard %s s after, %d participant(s) recreated" % (
                        r.get("duration_s", 0), fmt_s(r.get("heard_s")), r.get("recreated", 0))
                        if fault in HEAL_FAULTS else "")
                    log("[%4.0f s] fault %s%s, law %s, run %d/%d%s: detected %s s, recovered %s s, samples lost %s %%, "
                        "aborted %s, recording %s%s" % (
                            time.monotonic() - t_start, fault, level, law, k + 1, args.runs, heard,
                            fmt_s(r.get("detect_s")), fmt_s(r.get("recover_s")), fmt_pct(r.get("lost_pct")),
                            len(r.get("aborted", [])), {True: "complete", False: "INCOMPLETE", None: "-"}[r.get("recording")],
                            "; " + r["error"] if "error" in r else ""))
            finally:
                leftover = row.close()
                if leftover and runs:
                    runs[-1]["aborted"] = runs[-1].get("aborted", []) + leftover
            publish(runs, [])  # row by row: an interrupted run keeps what it measured
    return runs


def fmt_pct(v):
    return "-" if v is None else "%.1f" % v


def fmt_count(v):
    """A count, or a median of counts: 4, 4.5 (never 4.0)."""
    return "%d" % v if v == int(v) else "%.1f" % v


def med_worst(values, fmt, worst=max):
    vals = [v for v in values if v is not None]
    if not vals:
        return "-"
    return "%s / %s" % (fmt(statistics.median(vals)), fmt(worst(vals)))


TOOL = "echo_status"  # the measuring process (shapeform_echo): not part of the swarm


def swarm_aborted(r):
    return [a for a in r.get("aborted", []) if not a.startswith(TOOL)]


def rows_of(runs, fault):
    """The runs of `fault` grouped by (law, loss or class), in the order first measured."""
    groups = {}
    for r in runs:
        if r["fault"] == fault:
            groups.setdefault((r["law"], r["loss"]), []).append(r)
    return list(groups.items())


def heal_table(runs, fault):
    """cut and stop: per law and duration class, how long after the fault ended everyone heard everyone."""
    lines = ["| law | duration class | durations (s) | runs | everyone heard everyone after the end (s), median / "
             "worst | within %g s | participants recreated (causes) | processes aborted | recovered (converged) |"
             % GOAL_S, "|---|---|---|---|---|---|---|---|---|"]
    for (law, cls), rows in rows_of(runs, fault):
        durations = [r["duration_s"] for r in rows if "duration_s" in r]
        heard = [r.get("heard_s") for r in rows]
        causes = sorted({c for r in rows for c in r.get("recreated_causes", [])})
        lines.append("| %s | %s | %s | %d | %s | %d of %d | %d (%s) | %d | %d |" % (
            law, cls, "%.2f-%.2f" % (min(durations), max(durations)) if durations else "-", len(rows),
            med_worst(heard, fmt_s), sum(1 for v in heard if v is not None and v <= GOAL_S), len(rows),
            sum(r.get("recreated", 0) for r in rows), ", ".join(causes) or "none",
            sum(len(swarm_aborted(r)) for r in rows), sum(1 for r in rows if r.get("recover_s") is not None)))
    errors = [r["error"] for r in runs if r["fault"] == fault and "error" in r]
    if errors:
        lines.append("\nRuns that failed: %s." % "; ".join(errors))
    return "\n".join(lines) + "\n"


def lan_table(runs, fault):
    if fault in HEAL_FAULTS:
        return heal_table(runs, fault)
    head = ("| law | loss (%) | runs | detected after (s) | recovered | recovered after (s) | samples lost (%) | "
            "agents dropped | processes aborted | recording complete |")
    if fault == "supervisor":
        head = head.replace("detected after (s)", "command learnt after (s)")
    lines = [head, "|---|---|---|---|---|---|---|---|---|---|"]
    for (law, loss), rows in rows_of(runs, fault):
        rec = [r.get("recover_s") for r in rows]
        n_rec = sum(1 for v in rec if v is not None)
        rec_txt = med_worst(rec, fmt_s)
        if n_rec < len(rows):
            rec_txt = ("%s / " % rec_txt.split(" / ")[0] if n_rec else "") + "not within %g s" % rows[0].get("timeout_s", 0)
        lines.append("| %s | %g | %d | %s | %d | %s | %s | %s | %d | %d |" % (
            law, loss, len(rows), med_worst([r.get("detect_s") for r in rows], fmt_s), n_rec, rec_txt,
            med_worst([r.get("lost_pct") for r in rows], fmt_pct),
            med_worst([r.get("dropped") for r in rows], fmt_count), sum(len(swarm_aborted(r)) for r in rows),
            sum(1 for r in rows if r.get("recording"))))
    notes = sorted({a for r in runs if r["fault"] == fault for a in r.get("aborted", [])})
    tool = sum(1 for r in runs if r["fault"] == fault for a in r.get("aborted", []) if a.startswith(TOOL))
    if notes:
        lines.append("\nNot ended normally: %s%s." % (", ".join(a for a in notes if not a.startswith(TOOL)) or "no "
                     "process of the swarm", "; the measuring `shapeform_echo` (not counted above) %d time(s)" % tool
                     if tool else ""))
    return "\n".join(lines) + "\n"


# ------------------------------------------------------------------------------------------------
# The document

STALL_BEGIN = "<!-- stall table: begin (written by scripts/reliability.sh) -->"
STALL_END = "<!-- stall table: end -->"


def markers(fault):
    if fault == "stall":
        return STALL_BEGIN, STALL_END
    return ("<!-- %s table: begin (written by scripts/reliability.sh) -->" % fault, "<!-- %s table: end -->" % fault)


def replace_block(doc, fault, text):
    begin, end = markers(fault)
    if begin not in doc or end not in doc:
        raise SystemExit("reliability.py: the document has no markers for %s (%s ... %s)" % (fault, begin, end))
    head, rest = doc.split(begin, 1)
    _, tail = rest.split(end, 1)
    return head + begin + "\n" + text + end + tail


def provenance(argv, load, t0):
    """One line: when, which commit, the command line, the load at the start."""
    try:
        commit = subprocess.run(["git", "-C", str(REPO), "rev-parse", "--short", "HEAD"], capture_output=True,
                                text=True).stdout.strip() or "unknown"
    except OSError:
        commit = "unknown"
    return ("Measured %s UTC at commit %s with `scripts/reliability.sh %s`; load average at the start %.2f / "
            "%.2f / %.2f (1 / 5 / 15 min, %d cores); %.0f min.\n\n" % (
                time.strftime("%Y-%m-%d %H:%M", time.gmtime()), commit, " ".join(argv), load[0], load[1], load[2],
                os.cpu_count() or 0, (time.monotonic() - t0) / 60))


# ------------------------------------------------------------------------------------------------
# The program

def parse(argv):
    ap = argparse.ArgumentParser(
        prog="scripts/reliability.py", description=__doc__.split("\n\n")[0],
        usage="scripts/reliability.py [--runs R] [--quick] [--only FAULT[,FAULT...]] [--laws paper,arc] "
              "[--losses 0,10,20,40] [--out FILE] [--build DIR | --bin DIR] [--work DIR] [--dry-run]")
    ap.add_argument("--runs", type=int, default=5, help="runs per row (default 5; stalls: trials per row)")
    ap.add_argument("--quick", action="store_true",
                    help="a smoke run: the arc law, losses 0 and 20 %%, stalls of 5 s; the document only with --out")
    ap.add_argument("--only", default=",".join(FAULTS), help="faults, comma-separated, of: %s (default all)" %
                    ", ".join(FAULTS))
    ap.add_argument("--laws", default=None, help="laws of the LAN faults: paper, arc (default both; --quick: arc)")
    ap.add_argument("--losses", default=None, help="loss levels of the loss fault, %% (default 0,10,20,40; --quick: 0,20)")
    ap.add_argument("--out", default=None, help="the document whose tables are replaced (default docs/RELIABILITY.md; "
                    "--quick: none)")
    ap.add_argument("--build", default=str(REPO / "build"), help="build folder (default build/)")
    ap.add_argument("--bin", default=None, help="folder of the executables (default BUILD/bin)")
    ap.add_argument("--work", default=None, help="folder of the runs' outputs (default runs/<UTC time>-reliability)")
    ap.add_argument("--timeout", type=float, default=40.0, help="a run that has not recovered by then failed, s "
                    "(default 40)")
    ap.add_argument("--dry-run", action="store_true", help="print the plan and its estimated duration; start nothing")
    ap.add_argument("--classes", default=",".join(CLASSES), help="duration classes of cut and stop (default %s)" %
                    ",".join(CLASSES))
    ap.add_argument("--load", type=int, default=0, help="busy loops beside the swarm for the whole run (default 0)")
    ap.add_argument("--tables-from", action="append", default=[], metavar="RUNS_JSON",
                    help="write the tables of the faults in a runs.json of an earlier run (repeatable; later files "
                         "win per fault) into --out, with that run's provenance; start nothing")
    stall = ap.add_argument_group("stalls (loopback)")
    stall.add_argument("--stalls", default=None, help="stall lengths, s (default 3,5,20; --quick: 5)")
    stall.add_argument("--targets", default="agent,supervisor", help="stalled process kinds (default agent,supervisor)")
    stall.add_argument("--agents", type=int, default=12, help="agents in the swarm (default 12)")
    stall.add_argument("--domain", type=int, default=60, help="DDS domain (default 60)")
    stall.add_argument("--hold", type=float, default=2.5, help="after everyone heard everyone, the window in which the "
                       "whole membership must be seen complete at once, s (default 2.5)")
    stall.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                       help="a config override for every stalled swarm's process (repeatable)")
    args = ap.parse_args(argv)

    def numbers(text, what, lo, hi):
        try:
            vals = [float(x) for x in text.split(",")]
        except ValueError:
            ap.error("%s: expected comma-separated numbers, got '%s'" % (what, text[:40]))
        if not vals or any(not (lo <= v <= hi) for v in vals):
            ap.error("%s: each value must be in [%g, %g], got '%s'" % (what, lo, hi, text[:40]))
        return vals

    if args.runs < 1:
        ap.error("--runs: expected at least 1, got %d" % args.runs)
    if not (args.timeout > 0 and math.isfinite(args.timeout)):
        ap.error("--timeout: expected a positive number of seconds")
    args.only = args.only.split(",")
    bad = [f for f in args.only if f not in FAULTS]
    if bad:
        ap.error("--only: unknown fault '%s' (expected %s)" % (bad[0][:40], ", ".join(FAULTS)))
    args.laws = (args.laws or ("arc" if args.quick else "paper,arc")).split(",")
    bad = [x for x in args.laws if x not in LAWS]
    if bad:
        ap.error("--laws: unknown law '%s' (expected paper, arc)" % bad[0][:40])
    args.losses = numbers(args.losses or ("0,20" if args.quick else "0,10,20,40"), "--losses", 0, 100)
    args.stalls = numbers(args.stalls or ("5" if args.quick else "3,5,20"), "--stalls", 0.1, 600)
    args.targets = args.targets.split(",")
    if any(t not in ("agent", "supervisor") for t in args.targets):
        ap.error("--targets: expected agent and/or supervisor")
    args.trials = args.runs
    args.classes = args.classes.split(",")
    if any(c not in CLASSES for c in args.classes):
        ap.error("--classes: expected some of %s, got '%s'" % (", ".join(CLASSES), ",".join(args.classes)[:40]))
    if not 0 <= args.load <= 64:
        ap.error("--load: expected 0..64 busy loops, got %d" % args.load)
    if args.out is None and not args.quick:
        args.out = str(DOC)
    return args


def lan_plan(args):
    return [(f, law, loss) for f in LAN_FAULTS if f in args.only for law in args.laws
            for loss in (args.losses if f == "loss" else args.classes if f in HEAL_FAULTS else [0.0])]


def estimate_s(args, plan):
    lan = sum(args.runs * (RUN_S[f] + (20 if f == "loss" else 0)) + 25 +
              (sum(class_duration(c, k, args.runs) for k in range(args.runs)) if f in HEAL_FAULTS else 0)
              for f, _, c in plan)
    stall = (len(args.stalls) * len(args.targets) * (args.runs * (sum(args.stalls) / len(args.stalls) + 8) + 20)
             if "stall" in args.only else 0)
    return lan + stall


def rerender(args):
    """--tables-from: the tables of earlier runs into the document, nothing started."""
    if not args.out:
        log("reliability.py: --tables-from needs --out (or no --quick)")
        return 2
    doc = Path(args.out).read_text()
    for path in args.tables_from:
        saved = json.loads(Path(path).read_text())
        stamp = saved.get("provenance", "Measured by an earlier run (%s).\n\n" % path)
        for f in LAN_FAULTS:
            if any(r["fault"] == f for r in saved["lan"]):
                doc = replace_block(doc, f, stamp + lan_table(saved["lan"], f))
    Path(args.out).write_text(doc)
    log("tables written into %s" % args.out)
    return 0


def main(argv):
    args = parse(argv)
    # Started in the background, a script has SIGINT ignored: both signals end it through its clean-up
    # (every process stopped, the test hosts removed).
    signal.signal(signal.SIGINT, signal.default_int_handler)
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))
    plan = lan_plan(args)
    if args.tables_from and not args.dry_run:
        return rerender(args)
    if args.dry_run:
        for f, law, loss in plan:
            print("%s, %s law, %s: %d runs" % (f, law, ("class %s" % loss) if f in HEAL_FAULTS else "loss %g %%" % loss,
                                               args.runs))
        if "stall" in args.only:
            print("stall (loopback): %s stalled %s s, %d trials each" % (
                " and ".join(args.targets), ", ".join("%g" % s for s in args.stalls), args.runs))
        print("estimated %.0f min; tables into %s" % (estimate_s(args, plan) / 60, args.out or "(no document)"))
        return 0
    bins = Path(args.bin) if args.bin else Path(args.build) / "bin"
    for exe in ("shapeform_agent", "shapeform_supervisor", "shapeform_echo"):
        if not os.access(bins / exe, os.X_OK):
            log("reliability.py: %s not found (build first, or give --build/--bin)" % (bins / exe))
            return 1
    if plan:
        import netlab
        why = netlab.available()
        if why:
            log("reliability.py: the LAN faults need test hosts, which cannot be made here: %s "
                "(or --only stall)" % why)
            return 1
    work = Path(args.work) if args.work else REPO / "runs" / (time.strftime("%Y%m%d-%H%M%S", time.gmtime()) +
                                                             "-reliability")
    work.mkdir(parents=True, exist_ok=True)
    load, t0 = os.getloadavg(), time.monotonic()
    log("reliability: %d LAN rows and %s; estimated %.0f min; load average %.2f; outputs in %s" % (
        len(plan), "stalls" if "stall" in args.only else "no stalls", estimate_s(args, plan) / 60, load[0], work))

    def publish(runs, trials, final=False):
        """runs.json, and the tables of what was measured so far into the document."""
        for r in runs:
            r["timeout_s"] = args.timeout
        (work / "runs.json").write_text(json.dumps({"lan": runs, "stall": trials,
                                                    "provenance": provenance(argv, load, t0)}, indent=1))
        tables = {f: lan_table(runs, f) for f in LAN_FAULTS if any(r["fault"] == f for r in runs)}
        if trials:
            tables["stall"] = table(trials, args.stalls, args.targets)
        if final:
            for f, text in tables.items():
                print("%s\n\n%s" % (f, text))
        if args.out:
            out = Path(args.out)
            doc = out.read_text()
            stamp = provenance(argv, load, t0)
            for f, text in tables.items():
                doc = replace_block(doc, f, (stamp if f != "stall" else "") + text)
            out.write_text(doc)

    # A loaded host: busy loops for the whole run, stopped however it ends.
    burners = [subprocess.Popen(["/bin/sh", "-c", "while :; do :; done"]) for _ in range(args.load)]
    try:
        runs = run_lan(args, bins, work, plan, publish) if plan else []
        trials = run_stalls(args, bins, work) if "stall" in args.only else []
    finally:
        for b in burners:
            b.kill()
            b.wait()
    publish(runs, trials, final=True)
    if args.out:
        log("tables written into %s" % args.out)
    log("%d runs in %.0f s; every run in %s" % (len(runs) + len(trials), time.monotonic() - t0, work / "runs.json"))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
