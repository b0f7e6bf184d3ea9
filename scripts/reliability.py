#!/usr/bin/python3
"""Stall trials on a real swarm: how long after a stalled process resumes does everyone hear everyone?

  scripts/reliability.py [--build DIR | --bin DIR] [--trials N] [--stalls 3,5,20] [--targets agent,supervisor]
                         [--agents 12] [--domain 60] [--set KEY=VALUE] [--out DIR] [--write-docs]

For each target (an agent, the supervisor) and each stall length, one swarm (a supervisor and --agents
agents on the circle scenario, every process run with --json) runs --trials trials in sequence:
SIGSTOP of the target (a different agent each trial), SIGCONT after the stall, then the recovery time is
measured from the SIGCONT until every process hears every other again: the latest of the moments when
each agent's status first reports all the other agents heard ("neighbours_heard") and from which the
supervisor reports every agent alive (its "agent" events); the whole membership must then be seen
complete at once within --hold seconds. Then the supervisor publishes a new epoch (`start`): every agent must
adopt it (each hears the supervisor) and the formation must converge again (`wait converged`). A trial
that does not recover within --timeout seconds is a failure and its swarm is restarted for the next one.

Output: progress lines, a markdown table (trials, recovered within 3 s, worst and median recovery
time, re-converged) on stdout and in OUT/reliability.md with every trial in OUT/trials.json (default
runs/<UTC time>-reliability); --write-docs also puts the table into docs/RELIABILITY.md between its
markers. Processes are started and stopped only through scripts/lib/shapeform_procs.py; every process
is ours and is stopped by its own pid. Run it alone on the machine (under the integration-test lock):
the figures are timings.
"""
import argparse
import json
import os
import signal
import statistics
import sys
import time
from pathlib import Path

sys.dont_write_bytecode = True  # no __pycache__ in scripts/
REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "scripts" / "lib"))
import shapeform_procs as procs  # noqa: E402

DOC = REPO / "docs" / "RELIABILITY.md"
BEGIN = "<!-- stall table: begin (written by scripts/reliability.py --write-docs) -->"
END = "<!-- stall table: end -->"
GOAL_S = 3.0  # the recovery the swarm must achieve after a stall, s


def log(msg):
    print(msg, flush=True)


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


def write_docs(text):
    doc = DOC.read_text()
    if BEGIN not in doc or END not in doc:
        raise SystemExit("reliability.py: %s has no table markers (%s ... %s)" % (DOC, BEGIN, END))
    head, rest = doc.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    DOC.write_text(head + BEGIN + "\n" + text + END + tail)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 usage="scripts/reliability.py [--build DIR | --bin DIR] [--trials N] "
                                       "[--stalls 3,5,20] [--targets agent,supervisor] [--out DIR] [--write-docs]")
    ap.add_argument("--build", default=str(REPO / "build"), help="build folder (default build/)")
    ap.add_argument("--bin", default=None, help="folder of the executables (default BUILD/bin)")
    ap.add_argument("--trials", type=int, default=10, help="trials per stall length and target (default 10)")
    ap.add_argument("--stalls", default="3,5,20", help="stall lengths, seconds (default 3,5,20)")
    ap.add_argument("--targets", default="agent,supervisor", help="stalled process kinds (default agent,supervisor)")
    ap.add_argument("--agents", type=int, default=12, help="agents in the swarm (default 12)")
    ap.add_argument("--domain", type=int, default=60, help="DDS domain (default 60; the launcher's range 10..100)")
    ap.add_argument("--hold", type=float, default=2.5, help="after everyone heard everyone, the window in which the whole membership must be seen complete "
                         "at once, s (default 2.5)")
    ap.add_argument("--timeout", type=float, default=30.0, help="a trial fails when not recovered by then, s (default 30)")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="a config override for every process (repeatable), e.g. transport.lease_s=0.5")
    ap.add_argument("--out", default=None, help="output folder (default runs/<UTC time>-reliability)")
    ap.add_argument("--write-docs", action="store_true", help="also write the table into docs/RELIABILITY.md")
    args = ap.parse_args()

    bins = Path(args.bin) if args.bin else Path(args.build) / "bin"
    for exe in ("shapeform_agent", "shapeform_supervisor"):
        if not os.access(bins / exe, os.X_OK):
            raise SystemExit("reliability.py: %s not found (build first, or give --bin)" % (bins / exe))
    stalls = [float(s) for s in args.stalls.split(",")]
    targets = args.targets.split(",")
    if any(t not in ("agent", "supervisor") for t in targets):
        raise SystemExit("reliability.py: --targets takes agent and/or supervisor")
    out = Path(args.out) if args.out else REPO / "runs" / (time.strftime("%Y%m%d-%H%M%S", time.gmtime()) +
                                                         "-reliability")
    out.mkdir(parents=True, exist_ok=True)
    # Statuses 4 times a second: the recovery is seen to within 0.25 s.
    sets = ["agent.status_rate_hz=4"] + args.set
    trials = []
    t_start = time.monotonic()
    for target in targets:
        for stall in stalls:
            swarm, k, n_swarm = None, 0, 0
            try:
                while k < args.trials:
                    if swarm is None:
                        n_swarm += 1
                        run_dir = out / ("%s_%gs_%d" % (target, stall, n_swarm))
                        run_dir.mkdir(parents=True, exist_ok=True)
                        swarm = Swarm(bins, args.domain, args.agents, run_dir, sets)
                    t = run_trial(swarm, target, k, stall, args)
                    t["timeout_s"] = args.timeout
                    trials.append(t)
                    k += 1
                    log("[%4.0f s] %s stalled %g s, trial %d/%d (%s): heard again after %s s, re-converged %s" % (
                        time.monotonic() - t_start, target, stall, k, args.trials, t["victim"],
                        fmt_s(t["recovery_s"]), t["reconverged"]))
                    if t["recovery_s"] is None or not t["reconverged"]:
                        swarm.stop()  # the next trial starts from a whole swarm
                        swarm = None
            finally:
                if swarm is not None:
                    swarm.stop()
    text = table(trials, stalls, targets)
    (out / "trials.json").write_text(json.dumps(trials, indent=1))
    (out / "reliability.md").write_text(text)
    log("\n" + text)
    log("%d trials in %.0f s; every trial in %s" % (len(trials), time.monotonic() - t_start, out / "trials.json"))
    if args.write_docs:
        write_docs(text)
        log("table written into %s" % DOC)


if __name__ == "__main__":
    main()
