#!/usr/bin/python3
"""A swarm on test hosts: agents spread over namespace hosts, a supervisor on another (standard library only).

    with netlab.NetLab("rel", hosts=4, subnet="10.201.10") as lab:
        swarm = LanSwarm(lab, bins, config, domain=230, run_dir=d, sets=["agent.status_rate_hz=4"])
        swarm.start(12)          # agents 0..11 over h1..h3, the supervisor on h4; `start` once all are heard
        ...
        swarm.stop()

The placement (`placement`) and the command lines (`agent_argv`, `supervisor_argv`: the program, its
--config/--json/--domain, and the lan profile bound to the host's address) are the one definition of
"a LAN swarm"; the integration tests and scripts/reliability.py start theirs from them. Processes are
started and stopped only through shapeform_procs (each by its own pid).
"""
import os
import time

import shapeform_procs as procs

AGENT_HOSTS = ("h1", "h2", "h3")  # the agents' hosts; the supervisor's is SUPERVISOR_HOST
SUPERVISOR_HOST = "h4"


def placement(n, hosts=AGENT_HOSTS):
    """{agent id: host} for agents 0..n-1 in equal consecutive blocks over hosts (12 over 3: 0-3 on h1...)."""
    per = -(-n // len(hosts))
    return {i: hosts[i // per] for i in range(n)}


def agent_argv(bins, lab, host, i, config, domain, seed=1, extra=()):
    """The command line of agent i on `host` (--json, seeded start, lan profile on the host's address)."""
    argv = [os.path.join(str(bins), "shapeform_agent"), "--id", i, "--config", config, "--json", "--domain", domain,
            "--seed", seed] + list(extra)
    return lab.on(host, argv + lab.lan_sets(host))


def supervisor_argv(bins, lab, host, config, domain, record=None, extra=()):
    """The command line of a supervisor on `host` (--json, console on stdin; recording into `record`)."""
    argv = [os.path.join(str(bins), "shapeform_supervisor"), "--config", config, "--json", "--domain", domain]
    argv += ["--record", record] if record else []
    return lab.on(host, argv + list(extra) + lab.lan_sets(host))


class LanSwarm:
    """A supervisor (console on a pipe) and agents on the hosts of a NetLab, every process with --json.
    `procs` lists every process ever started (stopped ones too), for the exit-status check at the end;
    a caller may add its own (stop() stops them too)."""

    def __init__(self, lab, bins, config, domain, run_dir, sets=()):
        self.lab, self.bins, self.config, self.domain, self.run_dir = lab, bins, config, domain, run_dir
        self.extra = procs.sets_args(sets)
        self.sup = None
        self.agents = {}  # id -> Proc (the newest process of that id)
        self.hosts = {}   # id -> host
        self.procs = []
        self._sups = 0

    def start_agent(self, i, host, name=None):
        p = procs.Proc(name or "agent_%d" % i, agent_argv(self.bins, self.lab, host, i, self.config, self.domain,
                                                         extra=self.extra), self.run_dir)
        self.agents[i], self.hosts[i] = p, host
        self.procs.append(p)
        return p

    def start_supervisor(self, host=SUPERVISOR_HOST):
        """A supervisor on `host`, recording into RUN/record_K (K counts the supervisors started)."""
        self._sups += 1
        record = os.path.join(str(self.run_dir), "record_%d" % self._sups)
        self.sup = procs.Proc("supervisor_%d" % self._sups, supervisor_argv(self.bins, self.lab, host, self.config,
                                                                            self.domain, record, self.extra),
                              self.run_dir, stdin="pipe")
        self.sup.host, self.sup.record = host, record
        self.procs.append(self.sup)
        return self.sup

    def start(self, n, hosts=AGENT_HOSTS, command=True, timeout=60):
        """The supervisor on SUPERVISOR_HOST and agents 0..n-1 over `hosts`; waits until the supervisor hears
        all n; command: then `start` (epoch 1). RuntimeError when the agents are not all heard in time."""
        self.start_supervisor()
        for i, host in placement(n, hosts).items():
            self.start_agent(i, host)
            time.sleep(0.02)  # stagger: no discovery storm
        if not self.wait("agents %d" % n, timeout):
            raise RuntimeError("the supervisor did not hear the %d agents within %g s" % (n, timeout))
        if command:
            self.command("start")

    # -- the supervisor's console
    def ask(self, line, kind, timeout=10, where=None):
        """Sends a console line; the first `kind` event after it."""
        since = self.sup.mark()
        self.sup.send(line)
        return self.sup.wait_event(kind, timeout, since, where, "the answer to '%s'" % line)

    def wait(self, what, timeout):
        """A console `wait WHAT timeout=S` (e.g. "agents 12", "converged"): True when met."""
        return self.ask("wait %s timeout=%g" % (what, timeout), "wait", timeout + 30)["ok"]

    def command(self, line):
        """A console command that publishes an epoch; the epoch."""
        return self.ask(line, "epoch")["epoch"]

    def stop(self):
        """Stops every running process of `procs` (the supervisor first, then the agents, then any other a
        caller added, such as a measuring tool); their exit codes by name."""
        first = ([self.sup] if self.sup else []) + list(self.agents.values())
        ordered = first + [p for p in self.procs if p not in first]
        procs.stop_all([p for p in ordered if p.running()], grace=10.0, spacing=0.02)
        return {p.name: p.returncode for p in self.procs}


if __name__ == "__main__":
    import shapeform_procs
    shapeform_procs.module_main(__file__, "a swarm on test hosts, for the LAN tests and scripts/reliability.py")
