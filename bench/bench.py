#!/usr/bin/env python3
"""shapeform benchmark driver (run it through scripts/bench.sh).

Starts real processes on loopback, reads the figures the processes publish about themselves
(AgentStatus through shapeform_bench_probe, SwarmMetrics for convergence, the supervisor's JSON
summary) plus kernel counters (/proc), takes the median over runs, stores the results in
OUT/figures/bench_results.json and renders OUT/BENCHMARKS.md from that file. OUT is runs/<UTC time>-bench
unless given (--out; --write-docs: the committed docs/). Rows not run keep the results they have in the
committed docs/figures/bench_results.json.

Every run gets its own DDS domain (--domain-base upwards) and stops only the processes it started
(scripts/lib/shapeform_procs.py).
"""
from __future__ import annotations

import argparse
import datetime as dt
import json
import math
import os
import platform
import shutil
import signal
import statistics
import subprocess
import sys
import threading
import time
import dataclasses
from dataclasses import dataclass
from pathlib import Path

sys.dont_write_bytecode = True  # no __pycache__ beside the sources
ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "scripts" / "lib"))
import shapeform_procs as procs  # noqa: E402
CLK_TCK = os.sysconf("SC_CLK_TCK")

# --------------------------------------------------------------------------------------------
# What can be run.

# Transport presets: --set overrides given to every process of a run (agents, supervisor, probe,
# baseline). "ds" additionally starts a discovery server on 127.0.0.1 for the run.
PRESETS: dict[str, dict] = {
    "default": {"sets": [], "ds": False, "secure": False,
                "about": "project defaults (loopback profile: unicast UDPv4 on 127.0.0.1, OS socket buffers)"},
}


def add_preset(name: str, sets: list[str], about: str, ds: bool = False, secure: bool = False) -> None:
    PRESETS[name] = {"sets": sets, "ds": ds, "about": about, "secure": secure}


BUF = "transport.socket_buffer_bytes=4194304"
ANN = ["transport.lease_s=10", "transport.announce_s=3"]
MC = "transport.multicast_data=true"
add_preset("buf", [BUF], "4 MiB UDP socket send/receive buffers (transport.socket_buffer_bytes)")
add_preset("mc", [MC], "State on multicast 239.255.0.1 on lo (transport.multicast_data)")
add_preset("mcbuf", [MC, BUF], "State on multicast on lo + 4 MiB socket buffers")
add_preset("ann", ANN, "participant lease 10 s, announcements every 3 s (instead of 2 s / 0.5 s)")
add_preset("bufann", [BUF] + ANN, "4 MiB socket buffers + lease 10 s / announce 3 s")
add_preset("mcann", [MC] + ANN, "State on multicast on lo + lease 10 s / announce 3 s")
BUF1 = "transport.socket_buffer_bytes=1048576"
add_preset("mcbuf1ann", [MC, BUF1] + ANN, "State on multicast on lo + 1 MiB socket buffers + lease 10 s / announce 3 s")
add_preset("mcbufann", [MC, BUF] + ANN, "State on multicast on lo + 4 MiB socket buffers + lease 10 s / announce 3 s")
add_preset("mcbufannsec", [MC, BUF] + ANN, "mcbufann + DDS Security (security.enabled: PKI-DH, permissions, "
           "AES-GCM; one keystore for the benchmark by scripts/make_keystore.sh)", secure=True)

def large_swarm_sets() -> list[str]:
    """The launcher's large-swarm overrides (config/large_swarm.sets, without its min_agents line)."""
    lines = (ROOT / "config" / "large_swarm.sets").read_text().splitlines()
    return [ln for ln in lines if "=" in ln and not ln.startswith(("#", "min_agents="))]


LARGE_MIN = int(next(ln.split("=", 1)[1] for ln in (ROOT / "config" / "large_swarm.sets").read_text().splitlines()
                     if ln.startswith("min_agents=")))
add_preset("large", large_swarm_sets(), f"what scripts/launch_swarm.sh sets from {LARGE_MIN} agent processes on "
           f"(config/large_swarm.sets): {', '.join(large_swarm_sets())}")
SEDP = "transport.static_edp=true"
add_preset("mcbufannsedp", [MC, BUF, SEDP] + ANN, "mcbufann + static endpoint discovery (transport.static_edp)")
add_preset("largesedp", large_swarm_sets() + [SEDP], "large + static endpoint discovery (transport.static_edp)")
add_preset("largequiet", large_swarm_sets() + ["agent.idle_rate_hz=0.2"],
           "large, but state every 5 s until the first command (agent.idle_rate_hz=0.2): the start-up traffic is "
           "almost only discovery")
add_preset("largeia1", large_swarm_sets() + ["transport.initial_announcements=1"],
           "large + 1 initial participant announcement (transport.initial_announcements; Fast DDS default 5 at 0.1 s)")
add_preset("largeia20", large_swarm_sets() + ["transport.initial_announcements=20", "transport.initial_announce_s=0.25"],
           "large + 20 initial participant announcements every 0.25 s (transport.initial_announcements, "
           "initial_announce_s)")
add_preset("ds", [], "discovery server on 127.0.0.1 (transport.profile=discovery-server)", ds=True)
add_preset("dsbuf", [BUF], "discovery server on 127.0.0.1 + 4 MiB socket buffers", ds=True)
add_preset("dsmcbufann", [MC, BUF] + ANN, "discovery server on 127.0.0.1 + State on multicast on lo + 4 MiB socket "
           "buffers + lease 10 s / announce 3 s", ds=True)


@dataclass
class Row:
    """One benchmark row: `kind` processes of N agents at `rate` Hz with a transport preset."""
    kind: str            # baseline | agents | group
    n: int
    rate: float
    preset: str = "default"
    stagger_s: float = 0.0
    group: int = 0       # agents per process (group; baseline: > 0 for the grouped shape, one batch per process)
    section: str = "main"
    view: bool = False   # shapeform_view beside the swarm, one browser-like client reading its event stream
    runs: int = 0        # runs of a main row when not given by --runs (0: the default, 3)

    @property
    def id(self) -> str:
        r = f"{self.rate:g}"
        s = f"{self.kind}-n{self.n}-r{r}"
        if self.group:
            s += f"-g{self.group}"
        if self.preset != "default":
            s += f"-{self.preset}"
        if self.stagger_s > 0:
            s += f"-st{int(round(self.stagger_s * 1000))}"
        if self.view:
            s += "-view"
        return s


# The configuration of the main table: the large-swarm settings the levers below arrived at.
MAIN_PRESET = "mcbufann"
MAIN_STAGGER = 0.0


def main_rows() -> list[Row]:
    rows = []
    for n in (10, 25, 50, 100):
        # At N = 100, what the launcher runs by default (config/large_swarm.sets, from LARGE_MIN agents on);
        # the N = 50 rows keep mcbufann, measured before those settings existed.
        preset = "large" if n >= 100 else MAIN_PRESET
        for rate in ((20.0, 50.0) if n <= 25 else (20.0,)):
            rows.append(Row("baseline", n, rate, preset, MAIN_STAGGER))
            rows.append(Row("agents", n, rate, preset, MAIN_STAGGER, runs=5 if n >= 100 else 0))
    # Several agents per process (shapeform_agent_group), measured the same way, each beside the bare
    # baseline of the same shape (one AgentStateBatch per process and tick). 1000 agents in 10 and in 20
    # processes; those use multicast state (lever 13), the few processes of N <= 100 the defaults.
    for n, k in ((50, 25), (100, 50), (100, 25), (1000, 100), (1000, 50)):
        preset = MAIN_PRESET if n >= 1000 else "default"
        rows.append(Row("baseline", n, 20.0, preset, 0.0, k))
        rows.append(Row("group", n, 20.0, preset, 0.0, k))
    return rows


def _lv(kind, n, preset, stagger=0.0, group=0, rate=20.0):
    return Row(kind, n, rate, preset, stagger, group, "lever")


# Levers: each a set of rows measured side by side. "note" is the reading of the measured numbers
# (kept short; the tables carry the numbers).
B, A, G = "baseline", "agents", "group"
LEVERS: list[dict] = [
    {"name": "1. Socket receive buffers",
     "question": "`transport.socket_buffer_bytes`: the factory sets the UDPv4 descriptor's send and receive buffer size; "
                 "`ss -uam` shows rb = 2 x min(request, net.core.rmem_max) on the input sockets (4 MiB requested, "
                 "rmem_max here 4 MiB, so 8 MiB). With the OS default (208 KiB) the kernel drops datagrams whenever a "
                 "process is descheduled for a few tens of ms.",
     "pairs": [(_lv(B, 50, "default"), _lv(B, 50, "buf")), (_lv(B, 100, "mcann"), _lv(B, 100, "mcbuf1ann")),
               (_lv(B, 100, "mcann"), _lv(B, 100, "mcbufann"))],
     "note": "Larger buffers turn drops into queueing: when the host is past its capacity the queue (and the data "
             "age) grows instead, so buffers only help while the CPU keeps up on average.",
     "extra": True},
    {"name": "2. Multicast data locators on loopback",
     "question": "`transport.multicast_data`: State readers listen on 239.255.0.1 (lo only), so each sample is one "
                 "datagram instead of N-1 and the kernel does the fan-out. Other topics and discovery stay unicast "
                 "(an earlier variant that also put discovery and the reliable topics on the group made every "
                 "heartbeat and acknowledgement reach every process and was slower).",
     "pairs": [(_lv(B, 100, "bufann"), _lv(B, 100, "mcbufann")), (_lv(A, 50, "bufann"), _lv(A, 50, "mcbufann")),
               (_lv(A, 25, "default"), _lv(A, 25, "mcbufann"))],
     "extra": True},
    {"name": "3. Participant announcement period and lease",
     "question": "`transport.announce_s` / `lease_s`: 0.5 s / 2 s (project default, for fast detection of killed "
                 "processes) against 3 s / 10 s. Each announcement goes to every participant id probed "
                 "(`max_participants` = 120) and is processed by every participant: about N x 120 / announce_s "
                 "datagrams per second for as long as the swarm runs.",
     "pairs": [(_lv(B, 100, "buf"), _lv(B, 100, "bufann")), (_lv(B, 100, "mcbuf"), _lv(B, 100, "mcbufann"))],
     "note": "Agents still notice a killed neighbour after `agent.neighbour_timeout_periods` (3 periods), whatever "
             "the lease; the lease only decides when Fast DDS forgets the dead participant's endpoints.",
     "extra": True},
    {"name": "4. Discovery server",
     "question": "`transport.profile: discovery-server` with `fast-discovery-server -i 0 -l 127.0.0.1` started from an "
                 "XML profile without builtin transports (one server per run, port 12000 + domain): participant and "
                 "endpoint discovery go through the server (O(N)) instead of the N x N mesh. Data stays peer to peer. "
                 "The clients' sync period is tuned to 0.1 s (`kDiscoveryServerSyncPeriod_s`; Fast DDS default "
                 "0.45 s: N = 10 discovered in 0.86 s instead of 1.14 s).",
     "pairs": [(_lv(A, 50, "default"), _lv(A, 50, "ds")), (_lv(B, 100, "mcbufann"), _lv(B, 100, "dsmcbufann")),
               (_lv(A, 100, "mcbufann"), _lv(A, 100, "dsmcbufann"))],
     "note": "Reading of the runs of 2026-11-22: runs measured before commit f23146a (see the row's commit in the "
             "last table) had one process more on the domain than Fast DDS 2.9 gave ports to (the server, the probe "
             "and 100 clients: 103 participants, 101 port slots): one client ran the whole window hearing nobody "
             "and unheard (two in the staggered run), which the delivery ratio counts: the port slots, not the "
             "server, as first read here. After the fix (the three agent runs at N = 100): in two runs every "
             "client matched every other, after 43 and 71 s; in the third, the agents never all heard each other "
             "within the run (each heard at most 98 of 99, although the probe heard all 100), which looks like "
             "the server overload that eProsima/Fast-DDS #5767 and #6359 report for 75 to 100 simultaneous "
             "starts. The server halved the agents' data age p99 against simple discovery, and nothing aborted.",
     "extra": True},
    {"name": "5. Staggered launch",
     "question": "Starting 100 processes at once (the launcher itself needs about 4 s) makes a discovery storm on 2 "
                 "cores; 50 ms between launches spreads the start over about 8 s.",
     "pairs": [(_lv(B, 100, "mcbufann"), _lv(B, 100, "mcbufann", 0.05)),
               (_lv(A, 100, "mcbufann"), _lv(A, 100, "mcbufann", 0.05))],
     "note": "Reading of the runs of 2026-11-22 (the agent rows measured after the port-slot fix, see 'What "
             "limits N = 100'): staggering did not help. At N = 100 the steady state (198,000 deliveries/s) "
             "saturates the host whatever the start, and runs there differ by as much as the effect."},
    {"name": "6. Several agents per process",
     "question": "`shapeform_agent_group --ids A-B`: the same loop and AgentLogic, one participant per process. The "
                 "host carries P x (N-1) x rate deliveries between P processes instead of N x (N-1) x rate; agents "
                 "of one process exchange state through Fast DDS's intra-process delivery.",
     "rows": [_lv(A, 100, "mcbufann"), _lv(G, 100, "default", 0.0, 50), _lv(G, 100, "default", 0.0, 25),
              _lv(G, 100, "default", 0.0, 10)],
     "pairs": [(_lv(A, 100, "mcbufann"), _lv(G, 100, "default", 0.0, 50)),
               (_lv(A, 100, "mcbufann"), _lv(G, 100, "default", 0.0, 10))]},
    {"name": "7. Per-sample path and threads (checked, nothing to change)",
     "question": "The listener (`dds::detail::Mailbox`) takes each sample into a reused buffer under an uncontended "
                 "mutex and pushes it into a vector swapped with the loop's (no allocation after warm-up); the loop "
                 "keeps one neighbour slot per agent and does O(N) work per tick. The ratio table above (agents / "
                 "bare baseline at the same N) is the measure of everything the agent adds. An agent process has "
                 "5 threads (main loop, Fast DDS event thread, receive threads); 2.9 has no setting that removes "
                 "any of them.",
     "pairs": []},
    {"name": "8. The browser view beside the swarm",
     "question": "`shapeform_view` (read-only participant: state, status, command, target, metrics) beside 100 "
                 "agents, with one client reading its Server-Sent Events as a browser does (15 frames/s, each "
                 "frame the whole scene as JSON: agents, trails, outline, charts). Its own CPU and RSS are "
                 "sampled from /proc like the supervisor's; the agents' figures show what it costs them.",
     "rows": [_lv(A, 100, "mcbufann"), Row(A, 100, 20.0, "mcbufann", 0.0, 0, "lever", True)],
     "pairs": [(_lv(A, 100, "mcbufann"), Row(A, 100, 20.0, "mcbufann", 0.0, 0, "lever", True))],
     "view": True},
    {"name": "9. DDS Security",
     "question": "`security.enabled` (`scripts/launch_swarm.sh --secure`, docs/SECURITY.md): every participant "
                 "authenticated (PKI-DH, ECDSA P-256 certificates), its endpoints checked against signed permissions, "
                 "discovery, liveliness and data encrypted with AES-GCM and every RTPS message signed. The main "
                 "table's agents at N = 10 and 25, plain and secured, measured one after the other in one "
                 "invocation (`--only agents-n10-r20-mcbufann --only agents-n25-r20-mcbufann`).",
     "pairs": [(_lv(A, 10, "mcbufann"), _lv(A, 10, "mcbufannsec")), (_lv(A, 25, "mcbufann"), _lv(A, 25, "mcbufannsec"))],
     "note": "Reading of the runs of 2026-12-02: at N = 10 security costs 2.6x the CPU per agent, +8 MB RSS, and "
             "doubles the data age; everyone still hears everyone in about 3 s. At N = 25 the 2 cores are nearly "
             "saturated (6.7 % per agent) and pairs of participants stay unmatched for minutes: Fast DDS 2.9.1 "
             "resends a lost handshake message after 0.5 s, doubling without limit, and a participant dropped "
             "by its lease under load starts a new handshake. Profile of a secured agent at N = 25 (perf): a "
             "third of its CPU in libcrypto, mostly OpenSSL 3.0's per-call algorithm lookup (hash-table walks, "
             "locks) behind each AES-GCM operation, not the cipher itself. Hand trials (25 agents, the project's "
             "lease 2 s / 0.5 s, 150 s each): 15 processes all matched in 7.5 s; 20 never (1 trial), 25 never (4 "
             "trials, with or without RTPS message signing or submessage encryption, with a 0.3 s stagger)."},
    {"name": "10. Slow until commanded",
     "question": "`agent.idle_rate_hz=2` (in config/large_swarm.sets, so the launcher's default from "
                 f"{LARGE_MIN} agents on): an agent publishes its state at 2 Hz until its first command (and "
                 "drops a neighbour after 3 of those periods meanwhile); the supervisor's `wait agents N` still "
                 "sees every agent hear the N - 1 others before it commands. Participant and endpoint discovery "
                 "then run beside N x (N - 1) x 2 deliveries per second instead of x 20.",
     "pairs": [(_lv(A, 100, "mcbufann"), _lv(A, 100, "large"))],
     "note": "Reading of the runs of 2026-12-02. The `mcbufann` row is from 2026-11-22; on 2026-12-02 the same "
             "configuration no longer reached 'everyone hears everyone' within 60 s on this host, with today's code "
             "and with the code of 2026-12-02 morning (commit b12350d) rebuilt alike (single runs, `scripts/bench.sh "
             "--no-main --no-sim --row agents:100:20:mcbufann --out DIR`): 45 s after launch the probe heard the "
             "statuses of only 22 to 27 of the 100 agents, so participant and endpoint discovery itself, not the "
             "state traffic, is what the host could not finish (the same day's N = 25 rows show a loop lateness p99 "
             "of 2.4 ms where 2026-11-22 measured 0.2 ms: this virtual machine schedules more slowly than it "
             "did). Slowing the agents to 2 Hz until the command did not make discovery finish either (the "
             "`large` runs: the supervisor's `wait agents 100` timed out at 60 s and commanded anyway); it "
             "removes the state traffic from the start-up but not the N x N endpoint matching. Part of that "
             "timeout was a supervisor bug found later that day (it took an agent publishing at 2 Hz for dead "
             "after its 1 s agent timeout; fixed in commit dce693c); the main `large` row's 5 runs after the fix "
             "still never had everyone hear everyone within the minute."},
    {"name": "11. Leaving without the participant goodbye",
     "question": "`agent.leave_by_lease` (in config/large_swarm.sets): on SIGTERM an agent disposes its state and "
                 "deletes its endpoints, which its peers hear at once, but not its participant, so no participant "
                 "goodbye (DATA(p[UD])) is sent and each peer drops the participant when its lease ends, on its own "
                 "event thread. In Fast DDS 2.9 a goodbye processed on the receive thread while the lease timer of "
                 "the same participant fires on the event thread leaves the timer's callback with a proxy already "
                 "released to the pool: the assert in PDP.cpp aborts that peer (PDP.cpp remove_remote_participant: "
                 "cancel_timer() does not wait for a running callback; ParticipantProxyData::clear() resets the "
                 "GUID). 100 processes stopping at once make 9,900 such removals, each one a chance; the lease "
                 "timer fires once per lease on a peer that hears traffic, so a 10 s lease already makes it 5x rarer "
                 "than 2 s. Unchanged upstream (eProsima/Fast-DDS#6502 open); the discovery server's clients keep no "
                 "lease timer for each other, which is why no discovery-server run aborted.",
     "pairs": [(_lv(A, 100, "mcbufann"), _lv(A, 100, "large"))],
     "note": "Reading of the runs of 2026-12-02: no `large` run aborted (agents leave by lease), where the "
             "`mcbufann` rows of 2026-11-22 (agents leaving with the goodbye) aborted 2 processes in 3 runs and the "
             "bare baseline 3 in 3. The bare baseline (`shapeform_bench_baseline`) still sends the goodbye: it "
             "measures Fast DDS as it is."},
    {"name": "12. Static endpoint discovery",
     "question": "`transport.static_edp`: Fast DDS STATIC EDP instead of simple endpoint discovery. Simple EDP "
                 "(SEDP) has every pair of participants exchange their writers and readers over reliable built-in "
                 "endpoints: N x (N-1) exchanges of about ten endpoints each, with heartbeats and acknowledgements, "
                 "all while the swarm starts. With static EDP each participant is given one description, generated "
                 "from the topic table (a writer and a reader of every topic, each with a user id), and announces "
                 "the user and entity ids of the endpoints it has in its participant announcement (SPDP), which it "
                 "sends anyway: a peer matches them as soon as it hears that announcement, with no further "
                 "message. Every process (agents, supervisor, probe, baseline) goes through the same factory.",
     "pairs": [(_lv(B, 100, "mcbufann"), _lv(B, 100, "mcbufannsedp")),
               (_lv(A, 100, "mcbufann"), _lv(A, 100, "mcbufannsedp")),
               (_lv(A, 100, "large"), _lv(A, 100, "largesedp"))],
     "note": "Reading of the runs of 2026-12-02 (`large` against `largesedp`, 3 runs each, one after the other): "
             "with static endpoint discovery 2 of 3 runs reached 'everyone hears everyone' (after 49.8 and 38.3 s), "
             "with simple endpoint discovery none within 60 s; neither converged, and the data age stayed that of "
             "a saturated host. Hand trials at N = 60 (single runs while other work shared the host): all heard "
             "all after 25 and 29 s with static discovery, not within 120 s without. It is the lever with an "
             "effect on discovery, but not one that reaches 10 s at N = 100 here; it stays off by default (every "
             "process of a swarm must use it, or they never match).",
     "extra": True},
    {"name": "13. Multicast state for 1000 agents in groups",
     "question": "1000 agents in 10 or 20 `shapeform_agent_group` processes with the project's default transport "
                 "(each AgentStateBatch sent by unicast to every other process: P sends of up to 13 KB per process "
                 "and tick) against `mcbufann` (one multicast send on lo per batch; the kernel delivers it to the P "
                 "readers). The receives stay P per process and tick: every process takes every batch. Measured "
                 "for the agents and for the bare grouped baseline of the same shape.",
     "pairs": [(_lv(B, 1000, "default", 0.0, 100), _lv(B, 1000, MAIN_PRESET, 0.0, 100)),
               (_lv(G, 1000, "default", 0.0, 100), _lv(G, 1000, MAIN_PRESET, 0.0, 100)),
               (_lv(B, 1000, "default", 0.0, 50), _lv(B, 1000, MAIN_PRESET, 0.0, 50)),
               (_lv(G, 1000, "default", 0.0, 50), _lv(G, 1000, MAIN_PRESET, 0.0, 50))],
     "note": "Reading of the runs of 2026-12-02 (the default-transport group rows are from the morning, 2 runs; the "
             "baselines single runs): multicast took the host from 28 to 22 % busy with 10 processes and from 62 to "
             "40 % with 20, the bare grouped baseline from 17 to 11 % and from 39 to 29 %. The datagrams sent fell "
             "by two thirds, those received stayed (every process still takes every batch): on loopback a unicast "
             "send does the receiver's kernel work in the sender's system call, P times per batch. The agents' "
             "own work above the baseline (unpacking, the table, the sorted arc list, statuses) is the rest: "
             "x1.5 the baseline's CPU per agent.",
     "extra": True},
    {"name": "14. Initial announcements",
     "question": "`transport.initial_announcements` / `initial_announce_s`: a new participant announces itself "
                 "this many times at this interval (Fast DDS default 5 at 0.1 s) before the period `announce_s` "
                 "(3 s here) takes over; each announcement goes to all 120 participant slots of the loopback "
                 "profile. One announcement (less start-up traffic) and 20 every 0.25 s (a newcomer keeps "
                 "announcing through the start-up storm) against the launcher's `large` settings.",
     "pairs": [(_lv(A, 100, "large"), _lv(A, 100, "largeia1")), (_lv(A, 100, "large"), _lv(A, 100, "largeia20"))],
     "note": "Reading of the runs of 2026-12-02 (single runs beside the `large` row): neither made 100 processes "
             "hear each other within the minute; the fewest agents any agent heard at best was 73 of 99 with one "
             "announcement and 83 with twenty, against 95 with Fast DDS's five. The initial announcements are "
             "N x count x 120 datagrams, a small part of the start-up traffic next to the announcements that "
             "discovery itself triggers (lever 15).",
     "extra": True},
    {"name": "15. What participant discovery costs",
     "question": "Agents that publish their state only every 5 s until the first command (`largequiet`), so "
                 "that the traffic from launch to 'everyone hears everyone' is almost only discovery: the "
                 "datagrams the host received in that time, at N = 50, 75 and 100. In Fast DDS 2.9 a participant "
                 "that discovers a new one sends its own announcement (DATA(p)) again to every participant it "
                 "knows and every slot it probes (PDPListener: assigning the newcomer's endpoints marks the "
                 "announcement unsent for all readers of the StatelessWriter), so N participants starting together "
                 "cause about N x (N - 1) announcements, each received and parsed by about N participants: N^3 "
                 "datagrams, a million at N = 100.",
     "rows": [_lv(A, 50, "largequiet"), _lv(A, 75, "largequiet"), _lv(A, 100, "largequiet")],
     "pairs": [],
     "note": "Reading of the runs of 2026-12-02 (single runs, after the supervisor fix of that day, commit dce693c: "
             "before it the supervisor took agents publishing every 5 s for dead, commanded at its 60 s timeout, "
             "and the full-rate traffic then slowed the rest of discovery). N = 50: everyone heard everyone after "
             "27 s, the host having received 1.0 million datagrams; N = 75: 53 s, 2.8 million (x2.7 for x1.5 "
             "processes; N^3 would be x3.4); N = 100: not within the minute, 2.2 million by the command at 61 s, "
             "with the host saturated (it received fewer datagrams per second than at N = 75). The same host "
             "had all of 50 agent processes hear each other in 2.8 s on 2026-11-22 (`agents-n50-r20-mcbufann`), "
             "so it is also slower than it was (lever 10); the growth with N is that of Fast DDS.",
     "extra": True},
]
# The rows of a lever, unless listed: the members of its pairs, in order.
for _lever in LEVERS:
    _lever.setdefault("rows", list({r.id: r for pair in _lever["pairs"] for r in pair}.values()))

# --------------------------------------------------------------------------------------------
# Small helpers.


def now_ns() -> int:
    # CLOCK_MONOTONIC: the same clock as std::chrono::steady_clock and every *_stamp_ns.
    return time.monotonic_ns()


def median(xs):
    xs = [x for x in xs if x is not None]
    if not xs:
        return None
    return statistics.median(xs)


def read_proc_cpu_ticks(pid: int) -> int | None:
    try:
        with open(f"/proc/{pid}/stat") as f:
            parts = f.read().rsplit(")", 1)[1].split()
        return int(parts[11]) + int(parts[12])  # utime + stime
    except (OSError, IndexError, ValueError):
        return None


def read_proc_rss_mb(pid: int) -> float | None:
    try:
        with open(f"/proc/{pid}/statm") as f:
            return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20
    except (OSError, IndexError, ValueError):
        return None


PF_KTHREAD = 0x00200000


def read_user_proc_ticks(pid: int) -> int | None:
    """utime + stime of a user-space process; None for kernel threads (ksoftirqd, kworkers: they mostly
    carry our own network traffic) and vanished processes."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            parts = f.read().rsplit(")", 1)[1].split()
        if int(parts[6]) & PF_KTHREAD:
            return None
        return int(parts[11]) + int(parts[12])
    except (OSError, IndexError, ValueError):
        return None


def read_host_cpu() -> tuple[int, int]:
    with open("/proc/stat") as f:
        vals = [int(v) for v in f.readline().split()[1:]]
    idle = vals[3] + vals[4]
    return sum(vals), idle


def read_udp_counters() -> dict[str, int]:
    with open("/proc/net/snmp") as f:
        lines = [l.split() for l in f if l.startswith("Udp:")]
    return dict(zip(lines[0][1:], (int(v) for v in lines[1][1:])))


class Sampler(threading.Thread):
    """Samples host CPU, UDP counters and the CPU of a few named processes every 0.5 s."""

    def __init__(self):
        super().__init__(daemon=True)
        self.pids: dict[str, int] = {}
        self.ours: list[int] = []
        self.samples: list[dict] = []
        self._halt = threading.Event()

    def run(self):
        while not self._halt.is_set():
            s = {"t": now_ns()}
            s["host_total"], s["host_idle"] = read_host_cpu()
            s["udp"] = read_udp_counters()
            for name, pid in list(self.pids.items()):
                s[name] = read_proc_cpu_ticks(pid)
                s[name + "_rss"] = read_proc_rss_mb(pid)
            # CPU of every process this run started (to tell our load from other jobs on the host).
            s["ours"] = {pid: read_proc_cpu_ticks(pid) for pid in list(self.ours)}
            s["foreign"] = {}
            ours = set(self.ours)
            for name in os.listdir("/proc"):
                if name.isdigit() and int(name) not in ours and int(name) != os.getpid():
                    t = read_user_proc_ticks(int(name))
                    if t is not None:
                        s["foreign"][int(name)] = t
            self.samples.append(s)
            self._halt.wait(0.5)

    def stop(self):
        self._halt.set()
        self.join()

    def window(self, t0: int, t1: int):
        inside = [s for s in self.samples if t0 <= s["t"] <= t1]
        return (inside[0], inside[-1]) if len(inside) >= 2 else (None, None)


class EventClient(threading.Thread):
    """Reads a shapeform_view event stream (/events) as a browser does and counts the frames."""

    def __init__(self, url: str):
        super().__init__(daemon=True)
        self.url = url
        self.frames: list[int] = []  # arrival times, ns
        self._halt = threading.Event()

    def run(self):
        import urllib.request
        try:
            with urllib.request.urlopen(self.url + "events", timeout=10) as stream:
                for line in stream:
                    if line.startswith(b"data: "):
                        self.frames.append(now_ns())
                    if self._halt.is_set():
                        return
        except OSError as e:
            log(f"view client: {e}")

    def stop(self):
        self._halt.set()
        self.join(5)

    def rate(self, t0: int, t1: int) -> float | None:
        n = sum(1 for t in self.frames if t0 <= t <= t1)
        return n / ((t1 - t0) / 1e9) if t1 > t0 else None


def read_csv(path: Path) -> list[dict]:
    """A probe CSV as rows of floats; rows cut by a kill are skipped."""
    return [r for r in procs.read_csv(path, numeric=True) if None not in r.values()]


# --------------------------------------------------------------------------------------------
# One run.


@dataclass
class Ctx:
    bin: Path
    runs_dir: Path
    window_s: float
    disc_timeout_s: float
    conv_timeout_s: float
    scenario: Path
    scenario_sets: list[str]
    status_rate_hz: float
    domain_base: int
    domain_count: int = 30
    next_domain: int = 0
    quiet_busy: float = 0.15
    max_other_pct: float = 25.0
    retries: int = 2
    quiet_wait_s: float = 600.0

    def domain(self) -> int:
        d = self.domain_base + self.next_domain % self.domain_count
        self.next_domain += 1
        return d


def log(msg: str) -> None:
    print(f"[bench] {msg}", file=sys.stderr, flush=True)


def ds_xml(path: Path, port: int) -> None:
    path.write_text(f"""<?xml version="1.0" encoding="UTF-8"?>
<dds><profiles xmlns="http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles">
  <transport_descriptors>
    <transport_descriptor><transport_id>udp_lo</transport_id><type>UDPv4</type>
      <interfaceWhiteList><address>127.0.0.1</address></interfaceWhiteList>
    </transport_descriptor>
  </transport_descriptors>
  <participant profile_name="bench_ds" is_default_profile="true"><rtps>
    <userTransports><transport_id>udp_lo</transport_id></userTransports>
    <useBuiltinTransports>false</useBuiltinTransports>
    <builtin>
      <discovery_config><discoveryProtocol>SERVER</discoveryProtocol></discovery_config>
      <metatrafficUnicastLocatorList><locator><udpv4><address>127.0.0.1</address><port>{port}</port></udpv4></locator></metatrafficUnicastLocatorList>
    </builtin>
  </rtps></participant>
</profiles></dds>
""")


def udp_port_bound(port: int) -> bool:
    try:
        with open("/proc/net/udp") as f:
            next(f)
            for line in f:
                local = line.split()[1]
                if int(local.split(":")[1], 16) == port:
                    return True
    except OSError:
        pass
    return False


def host_busy_over(seconds: float) -> float:
    """Host CPU busy fraction (0..1) over the next `seconds`."""
    t1, i1 = read_host_cpu()
    time.sleep(seconds)
    t2, i2 = read_host_cpu()
    return 1 - (i2 - i1) / max(1, t2 - t1)


def wait_quiet(ctx: Ctx) -> float:
    """Waits (up to ctx.quiet_wait_s) until the host is nearly idle, so other jobs do not skew a run.
    Returns the busy fraction seen last."""
    end = time.monotonic() + ctx.quiet_wait_s
    busy = host_busy_over(2.0)
    warned = False
    while busy > ctx.quiet_busy and time.monotonic() < end:
        if not warned:
            log(f"host {100 * busy:.0f} % busy with other work; waiting up to {ctx.quiet_wait_s:.0f} s for it to calm down")
            warned = True
        busy = host_busy_over(5.0)
    return busy


def run_once(ctx: Ctx, row: Row, run_idx: int) -> dict:
    busy_before = wait_quiet(ctx)
    domain = ctx.domain()
    rdir = ctx.runs_dir / row.id / f"run{run_idx}"
    if rdir.exists():
        shutil.rmtree(rdir)  # no stale logs of an earlier run (they are scanned for asserts)
    rdir.mkdir(parents=True)
    preset = PRESETS[row.preset]
    tsets = list(preset["sets"])
    ds_proc = None
    if preset["ds"]:
        port = 12000 + domain
        tsets += ["transport.profile=discovery-server", f"transport.discovery_server=127.0.0.1:{port}"]
    if preset["secure"]:
        # One keystore for the benchmark, extended to this row's agents (make_keystore.sh keeps what exists).
        keystore = ctx.runs_dir / "keystore"
        procs.run([ROOT / "scripts" / "make_keystore.sh", keystore, "--agents", str(row.n)], timeout=600)
        tsets += ["security.enabled=true", f"security.keystore={keystore}"]
    common = ["--domain", str(domain)] + procs.sets_args(tsets)
    rate_sets = [f"agent.rate_hz={row.rate:g}", f"agent.status_rate_hz={ctx.status_rate_hz:g}",
                 f"swarm.agents={row.n}"]

    sampler = Sampler()
    started: list[procs.Proc] = []
    client = None

    def spawn(name: str, argv: list[str]) -> procs.Proc:
        p = procs.Proc(name, argv, rdir, cwd=rdir, err_suffix=".err")
        sampler.ours.append(p.pid)
        started.append(p)
        return p

    result: dict = {"row": row.id, "run": run_idx, "domain": domain, "dir": str(rdir)}
    result["load_before"] = os.getloadavg()[0]
    result["busy_before_pct"] = 100 * busy_before
    try:
        if preset["ds"]:
            xml = rdir / "ds.xml"
            ds_xml(xml, port)
            ds_proc = spawn("ds", ["fast-discovery-server", "-i", "0", "-l", "127.0.0.1", "-p", str(port),
                                   "-x", str(xml)])
            if not procs.wait_for(lambda: udp_port_bound(port), 10):
                raise RuntimeError(f"discovery server did not bind 127.0.0.1:{port}")
            sampler.pids["ds"] = ds_proc.pid
        probe = spawn("probe", [str(ctx.bin / "shapeform_bench_probe"), "--out", str(rdir)] + common)
        line = procs.wait_for(lambda: probe.out() if "\n" in probe.out() or not probe.running() else "", 30)
        if not line.startswith("ready"):
            raise RuntimeError(f"probe did not start: {line!r}")
        sampler.start()
        t0 = now_ns()
        result["t0"] = t0
        sup = None
        if row.kind in ("agents", "group"):
            script = rdir / "script.txt"
            script.write_text(f"wait agents {row.n} timeout={ctx.disc_timeout_s:g}\nstart\n"
                              f"wait converged timeout={ctx.conv_timeout_s:g}\nsleep {ctx.window_s:g}\nquit\n")
            sup = spawn("supervisor", [str(ctx.bin / "shapeform_supervisor"), "--config", str(ctx.scenario),
                                       "--script", str(script), "--json"] + common +
                        procs.sets_args(rate_sets + ctx.scenario_sets))
            sampler.pids["sup"] = sup.pid
        if row.view:
            view = spawn("view", [str(ctx.bin / "shapeform_view"), "--config", str(ctx.scenario), "--port", "0",
                                  "--json"] + common + procs.sets_args(rate_sets + ctx.scenario_sets))
            start = view.wait_event("start", 30)
            sampler.pids["view"] = view.pid
            client = EventClient(start["url"])
            client.start()
        workers: list[procs.Proc] = []
        if row.group:
            for first in range(0, row.n, row.group):
                ids = f"{first}-{min(row.n, first + row.group) - 1}"
                if row.kind == "group":
                    argv = [str(ctx.bin / "shapeform_agent_group"), "--ids", ids, "--config", str(ctx.scenario),
                            "--seed", "1"] + common + procs.sets_args(rate_sets + ctx.scenario_sets)
                else:
                    argv = [str(ctx.bin / "shapeform_bench_baseline"), "--ids", ids] + common + \
                        procs.sets_args(rate_sets)
                workers.append(spawn(f"group{first}", argv))
                if row.stagger_s > 0:
                    time.sleep(row.stagger_s)
        else:
            for i in range(row.n):
                if row.kind == "agents":
                    argv = [str(ctx.bin / "shapeform_agent"), "--id", str(i), "--config", str(ctx.scenario),
                            "--seed", "1"] + common + procs.sets_args(rate_sets + ctx.scenario_sets)
                else:
                    argv = [str(ctx.bin / "shapeform_bench_baseline"), "--id", str(i)] + common + \
                        procs.sets_args(rate_sets)
                workers.append(spawn(f"p{i}", argv))
                if row.stagger_s > 0:
                    time.sleep(row.stagger_s)
        result["launch_s"] = (now_ns() - t0) / 1e9

        if sup is not None:
            limit = ctx.disc_timeout_s + ctx.conv_timeout_s + ctx.window_s + 60
            try:
                sup.wait(timeout=limit)
            except AssertionError:
                log(f"{row.id}: supervisor still running after {limit:.0f} s; stopping it")
            t_end = now_ns()
        else:
            # Baseline: wait until every process hears all others (or the discovery timeout), then the window.
            def all_heard() -> bool:
                rows = read_csv(rdir / "status.csv")
                full = {int(r["id"]) for r in rows if r["neighbours_heard"] >= row.n - 1}
                return len(full) >= row.n
            procs.wait_for(all_heard, ctx.disc_timeout_s, 0.5)
            time.sleep(ctx.window_s)
            t_end = now_ns()
        result["t_end"] = t_end
        early = [i for i, p in enumerate(workers) if not p.running()]
        codes = procs.stop_all(workers, grace=20, spacing=0.01)
        result["exit_codes"] = codes
        result["died_early"] = early
        if sup is not None:
            result["supervisor_exit"] = procs.stop_all([sup], grace=10)[0]
        procs.stop_all([probe], grace=10)
    finally:
        if sampler.is_alive():
            sampler.stop()
        if client is not None:
            client.stop()
        # After an error part-way: stop whatever this run started and is still alive (ours only).
        procs.stop_all([p for p in started if p is not ds_proc and p.running()], grace=10)
        if ds_proc is not None:
            procs.stop_all([ds_proc], grace=5)
    analyse(ctx, row, rdir, result, sampler)
    if client is not None:
        w1 = result["t_end"] - 0.5e9
        result["view_fps"] = client.rate(max(result["t0"], w1 - ctx.window_s * 1e9 + 1e9), w1)
    return result


# --------------------------------------------------------------------------------------------
# Figures of one run.


def interp_counter(statuses: list[dict], key: str, t: float) -> float | None:
    """Linear interpolation of a cumulative counter at steady time t (ns); None outside the range."""
    if not statuses or t < statuses[0]["stamp_ns"] or t > statuses[-1]["stamp_ns"]:
        return None
    for a, b in zip(statuses, statuses[1:]):
        if a["stamp_ns"] <= t <= b["stamp_ns"]:
            span = b["stamp_ns"] - a["stamp_ns"]
            f = 0.0 if span <= 0 else (t - a["stamp_ns"]) / span
            return a[key] + f * (b[key] - a[key])
    return statuses[-1][key]


def analyse(ctx: Ctx, row: Row, rdir: Path, res: dict, sampler: Sampler) -> None:
    n = row.n
    t0 = res["t0"]
    t_end = res["t_end"]
    w1 = t_end - 0.5e9
    w0 = max(t0, t_end - ctx.window_s * 1e9 + 0.5e9)
    res["window_s"] = (w1 - w0) / 1e9
    status = read_csv(rdir / "status.csv")
    by_id: dict[int, list[dict]] = {}
    for s in status:
        by_id.setdefault(int(s["id"]), []).append(s)
    for v in by_id.values():
        v.sort(key=lambda s: s["stamp_ns"])
    res["agents_reporting"] = len(by_id)

    # Everyone hears everyone: per agent, the first status reporting all n-1 others; the latest of those.
    firsts = []
    for i in range(n):
        f = next((s["stamp_ns"] for s in by_id.get(i, []) if s["neighbours_heard"] >= n - 1), None)
        firsts.append(f)
    res["all_heard_s"] = None if any(f is None for f in firsts) else (max(firsts) - t0) / 1e9
    res["heard_min"] = min((max((s["neighbours_heard"] for s in by_id.get(i, [])), default=0) for i in range(n)),
                           default=0)

    # Delivery over the window: each receiver's received count against the senders' publication rates.
    rates = {}
    recv = {}
    for i, ss in by_id.items():
        a, b = interp_counter(ss, "ticks", w0), interp_counter(ss, "ticks", w1)
        if a is not None and b is not None:
            rates[i] = (b - a) / ((w1 - w0) / 1e9)
        ra, rb = interp_counter(ss, "samples_received", w0), interp_counter(ss, "samples_received", w1)
        if ra is not None and rb is not None:
            recv[i] = rb - ra
    win = (w1 - w0) / 1e9
    expected = 0.0
    got = 0.0
    for i in range(n):
        exp_i = sum(r for j, r in rates.items() if j != i) * win
        # A sender that never reported is still owed to everyone: assume the nominal rate.
        exp_i += sum(row.rate for j in range(n) if j != i and j not in rates) * win
        expected += exp_i
        got += recv.get(i, 0.0)
    res["delivery"] = got / expected if expected > 0 else None
    lost = [interp_counter(ss, "samples_lost", w1) - interp_counter(ss, "samples_lost", w0)
            for ss in by_id.values() if interp_counter(ss, "samples_lost", w0) is not None
            and interp_counter(ss, "samples_lost", w1) is not None]
    res["seq_gaps_per_s"] = sum(lost) / win if lost else None

    inwin = [s for s in status if w0 <= s["stamp_ns"] <= w1]
    p50s = [s["age_p50_us"] for s in inwin if s["age_p50_us"] >= 0]
    p99s = [s["age_p99_us"] for s in inwin if s["age_p99_us"] >= 0]
    res["age_p50_ms"] = median(p50s) / 1e3 if p50s else None
    res["age_p99_ms"] = median(p99s) / 1e3 if p99s else None
    res["age_p99_worst_ms"] = max(p99s) / 1e3 if p99s else None
    res["age_p99_p90_ms"] = (sorted(p99s)[int(0.9 * (len(p99s) - 1))] / 1e3) if p99s else None

    # Loop lateness: each agent's p99 over its last 1024 ticks, at the end of the window.
    lat = []
    over = 0.0
    ticks = 0.0
    cpu = []
    rss = []
    for i, ss in by_id.items():
        last = [s for s in ss if s["stamp_ns"] <= w1]
        if last:
            lat.append(last[-1]["lateness_p99_us"])
            rss.append(last[-1]["rss_mb"])
        oa, ob = interp_counter(ss, "overruns", w0), interp_counter(ss, "overruns", w1)
        ta, tb = interp_counter(ss, "ticks", w0), interp_counter(ss, "ticks", w1)
        if None not in (oa, ob, ta, tb):
            over += ob - oa
            ticks += tb - ta
        c = [s["cpu_percent"] for s in ss if w0 <= s["stamp_ns"] <= w1]
        if c:
            cpu.append(sum(c) / len(c))
    res["lateness_p99_ms"] = median(lat) / 1e3 if lat else None
    res["lateness_p99_worst_ms"] = max(lat) / 1e3 if lat else None
    res["overruns"] = over
    res["overrun_pct"] = 100 * over / (over + ticks) if ticks > 0 else None
    res["cpu_pct"] = statistics.mean(cpu) if cpu else None
    res["cpu_pct_total"] = sum(cpu) if cpu else None
    res["rss_mb"] = median(rss)
    res["rss_mb_max"] = max(rss) if rss else None

    a, b = sampler.window(w0, w1)
    if a is not None:
        span_s = (b["t"] - a["t"]) / 1e9
        dt_total = b["host_total"] - a["host_total"]
        res["host_busy_pct"] = 100 * (1 - (b["host_idle"] - a["host_idle"]) / dt_total) if dt_total else None
        for name in ("sup", "ds", "view"):
            if a.get(name) is not None and b.get(name) is not None:
                res[f"{name}_cpu_pct"] = 100 * (b[name] - a[name]) / CLK_TCK / span_s
                res[f"{name}_rss_mb"] = b.get(name + "_rss")
        ours = 0.0
        for pid, tb in b["ours"].items():
            ta = a["ours"].get(pid)
            if ta is not None and tb is not None:
                ours += tb - ta
        res["ours_cpu_pct"] = 100 * ours / CLK_TCK / span_s  # % of one core
        # Other jobs: user-space processes this run did not start (present at both ends of the window,
        # plus the part a process that appeared or vanished in between used while it was sampled).
        foreign = 0
        samples = [x for x in sampler.samples if a["t"] <= x["t"] <= b["t"]]
        for prev, cur in zip(samples, samples[1:]):
            for pid, tc in cur["foreign"].items():
                tp = prev["foreign"].get(pid)
                if tp is not None and tc >= tp:
                    foreign += tc - tp
        res["other_cpu_pct"] = 100 * foreign / CLK_TCK / span_s
        if res.get("host_busy_pct") is not None:
            res["kernel_and_unattributed_pct"] = max(0.0, res["host_busy_pct"] * (os.cpu_count() or 1)
                                                      - res["ours_cpu_pct"] - res["other_cpu_pct"])
        ua, ub = a["udp"], b["udp"]
        res["udp_in_per_s"] = (ub["InDatagrams"] - ua["InDatagrams"]) / span_s
        res["udp_rcvbuf_errors_per_s"] = (ub["RcvbufErrors"] - ua["RcvbufErrors"]) / span_s
        res["udp_out_per_s"] = (ub["OutDatagrams"] - ua["OutDatagrams"]) / span_s

    # Convergence (agents): the first SwarmMetrics sample with converged set.
    metrics = read_csv(rdir / "metrics.csv")
    started = next((m["recv_ns"] for m in metrics if m["epoch"] >= 1), None)
    conv = next((m["recv_ns"] for m in metrics if m["epoch"] >= 1 and m["converged"] >= 1), None)
    res["start_s"] = (started - t0) / 1e9 if started else None
    res["converge_s"] = (conv - t0) / 1e9 if conv else None
    # Discovery's traffic: datagrams the host received from the first launch until everyone heard
    # everyone, or until the supervisor's command when that came first (agents then publish at full rate).
    ends = [t0 + res["all_heard_s"] * 1e9] if res.get("all_heard_s") is not None else []
    ends += [started] if started else []
    first = next((x for x in sampler.samples if x["t"] >= t0), None)
    last = next((x for x in reversed(sampler.samples) if x["t"] <= min(ends + [t_end]) + 0.5e9), None)
    if first is not None and last is not None and last["t"] > first["t"]:
        res["disc_udp_in"] = last["udp"]["InDatagrams"] - first["udp"]["InDatagrams"]
        res["disc_udp_s"] = (last["t"] - first["t"]) / 1e9
    j = procs.summary(procs.read_text(rdir / "supervisor.out"))
    if j:
        for key in ("converged", "shape_error_mean", "gap_cv", "agents_seen"):
            res["sup_converged" if key == "converged" else key] = j.get(key)

    codes = res.get("exit_codes", [])
    res["aborts"] = sum(1 for c in codes if c is not None and c < 0 and c != -signal.SIGTERM)
    res["bad_exits"] = sum(1 for c in codes if c is None or c != 0)
    asserts = 0
    for f in rdir.glob("*.err"):
        try:
            if "Assertion" in f.read_text(errors="replace"):
                asserts += 1
        except OSError:
            pass
    res["assert_lines"] = asserts


# --------------------------------------------------------------------------------------------
# Aggregation over runs and the report.

TIME_KEYS = ("all_heard_s", "converge_s")


def aggregate(runs: list[dict]) -> dict:
    agg: dict = {"runs": len(runs)}
    keys = sorted({k for r in runs for k, v in r.items() if isinstance(v, (int, float)) and not isinstance(v, bool)}
                  | set(TIME_KEYS))
    for k in keys:
        if k in ("run", "domain", "t0", "t_end"):
            continue
        vals = [r.get(k) for r in runs]
        if k in TIME_KEYS:  # not reached within the run's limit: never
            vals = [math.inf if v is None else v for v in vals]
        vals = [v for v in vals if v is not None]
        if not vals:
            continue
        agg[k] = statistics.median(vals)
        agg[k + "_range"] = [min(vals), max(vals)]
    for k in ("aborts", "bad_exits", "assert_lines"):
        agg[k + "_total"] = sum(r.get(k, 0) for r in runs)
    agg["sup_converged_runs"] = sum(1 for r in runs if r.get("sup_converged"))
    agg["converged_runs"] = sum(1 for r in runs if r.get("converge_s") is not None)
    return agg


def machine_info() -> dict:
    info = {"host_cpus": os.cpu_count(), "kernel": platform.release()}
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                info["cpu"] = line.split(":", 1)[1].strip()
                break
        for line in open("/proc/meminfo"):
            if line.startswith("MemTotal"):
                info["mem_gb"] = round(int(line.split()[1]) / 2**20, 1)
    except OSError:
        pass
    try:
        info["os"] = [l.split("=", 1)[1].strip().strip('"') for l in open("/etc/os-release")
                      if l.startswith("PRETTY_NAME")][0]
    except (OSError, IndexError):
        pass
    for k in ("rmem_max", "wmem_max", "rmem_default"):
        try:
            info[k] = int(open(f"/proc/sys/net/core/{k}").read())
        except OSError:
            pass
    try:
        out = subprocess.run(["dpkg-query", "-W", "-f=${Version}", "libfastrtps2.9"], capture_output=True, text=True)
        info["fastdds"] = out.stdout.strip() or None
    except OSError:
        pass
    return info


def git_commit() -> str:
    try:
        c = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True,
                           text=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(ROOT), "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True).stdout.strip()
        return c + ("+local changes" if dirty else "")
    except OSError:
        return "unknown"


# --------------------------------------------------------------------------------------------


def log_run(row: Row, k: int, r: dict) -> None:
    log(f"{row.id}: run {k + 1}: heard {fmt(r.get('all_heard_s'), 's')} deliv {fmt(r.get('delivery'), 'r')} "
        f"age p50 {fmt(r.get('age_p50_ms'), 'ms')} p99 {fmt(r.get('age_p99_ms'), 'ms')} "
        f"cpu {fmt(r.get('cpu_pct'), '%')} host {fmt(r.get('host_busy_pct'), '%')} "
        f"rcvbuf err/s {fmt(r.get('udp_rcvbuf_errors_per_s'), 'n')} conv {fmt(r.get('converge_s'), 's')} "
        f"aborts {r.get('aborts')} other load {fmt(r.get('other_cpu_pct'), '%')}")


def run_rows(ctx: Ctx, rows: list[Row], runs: int, store: dict) -> None:
    for row in rows:
        per = []
        for k in range(runs):
            for attempt in range(ctx.retries + 1):
                log(f"{row.id}: run {k + 1}/{runs}" + (f" (retry {attempt})" if attempt else ""))
                r = run_once(ctx, row, k)
                log_run(row, k, r)
                other = r.get("other_cpu_pct") or 0.0
                if other <= ctx.max_other_pct:
                    break
                log(f"{row.id}: run {k + 1}: other jobs used {other:.0f} % of a core during the window "
                    f"(limit {ctx.max_other_pct:.0f} %)" + ("; repeating it" if attempt < ctx.retries else "; keeping it"))
            r["attempts"] = attempt + 1
            per.append(r)

        entry = {"row": row.__dict__ | {"id": row.id}, "agg": aggregate(per), "runs": per,
                 "when": dt.datetime.now().isoformat(timespec="seconds"), "commit": git_commit()}
        store[row.id] = entry


def fmt(v, kind: str) -> str:
    if v is None:
        return "-"
    if isinstance(v, float) and math.isinf(v):
        return "never"
    if kind == "s":
        return f"{v:.1f} s"
    if kind == "r":
        return f"{100 * v:.2f} %"
    if kind == "ms":
        return f"{v:.2f} ms" if v < 10 else f"{v:.0f} ms"
    if kind == "%":
        return f"{v:.1f} %"
    if kind == "n":
        return f"{v:.0f}"
    return str(v)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter,
                                 usage="bench/bench.py [--quick] [--runs K] [--levers] [--only ROW]... [--row SPEC]... "
                                       "[--list] [--out DIR | --write-docs] [options]")
    ap.add_argument("--quick", action="store_true", help="1 run per row and short windows")
    ap.add_argument("--runs", type=int, help="runs per row (default 3; 1 with --quick)")
    ap.add_argument("--window", type=float, help="measurement window, s (default: max(30, 1100 ticks); 12 with --quick)")
    ap.add_argument("--only", action="append", default=[],
                    help="row id or prefix to run (repeatable); `sim`: the simulator rows")
    ap.add_argument("--row", action="append", default=[],
                    help="ad-hoc row KIND:N:RATE[:PRESET[:STAGGER_S[:GROUP[:view]]]] (stored, shown under experiments)")
    ap.add_argument("--levers", action="store_true", help="also run the lever rows")
    ap.add_argument("--lever-runs", type=int, default=1, help="runs per lever row that is not a main row (default 1)")
    ap.add_argument("--no-main", action="store_true", help="skip the main rows")
    ap.add_argument("--no-sim", action="store_true", help="skip the simulator rows")
    ap.add_argument("--build", default=str(ROOT / "build"), help="build directory (default build/)")
    ap.add_argument("--out", help="output folder (default runs/<UTC time>-bench)")
    ap.add_argument("--write-docs", action="store_true",
                    help="write into the committed docs/ (docs/BENCHMARKS.md, docs/figures/bench_results.json)")
    ap.add_argument("--runs-dir", help="where process logs and CSVs go (default OUT/runs; runs/bench with --write-docs)")
    ap.add_argument("--results", help="results file (default OUT/figures/bench_results.json)")
    ap.add_argument("--report", help="report file (default OUT/BENCHMARKS.md)")
    ap.add_argument("--domain-base", type=int, default=200, help="first DDS domain id (30 are used in turn)")
    ap.add_argument("--quiet-busy", type=float, default=15.0,
                    help="before each run wait until the host is at most this %% busy (default 15)")
    ap.add_argument("--quiet-wait", type=float, default=600.0, help="longest wait for a quiet host, s")
    ap.add_argument("--max-other-load", type=float, default=25.0,
                    help="repeat a run when other jobs used more than this %% of one core during its window (default 25)")
    ap.add_argument("--retries", type=int, default=2, help="how often a disturbed run is repeated (default 2)")
    ap.add_argument("--scenario", default="config/scenarios/arc_circle.yaml",
                    help="agents' and supervisor's config (default: the circle with the arc law, which converges at "
                         "every N; the paper law's circle cannot meet the convergence test's gap CV at N >= 50)")
    ap.add_argument("--render-only", action="store_true", help="only re-render the report from the results file")
    ap.add_argument("--list", action="store_true", help="list the row ids and exit")
    args = ap.parse_args(argv)
    docs = ROOT / "docs"
    out = docs if args.write_docs else Path(args.out or ROOT / "runs" / (
        time.strftime("%Y%m%dT%H%M%SZ", time.gmtime()) + "-bench")).resolve()
    args.results = args.results or str(out / "figures" / "bench_results.json")
    args.report = args.report or str(out / "BENCHMARKS.md")
    args.runs_dir = args.runs_dir or str(ROOT / "runs" / "bench" if out == docs else out / "runs")

    # Ctrl-C or SIGTERM: unwind so that run_once stops the processes it started (ours only).
    def interrupted(signum, frame):
        raise KeyboardInterrupt(f"signal {signum}")
    signal.signal(signal.SIGINT, interrupted)
    signal.signal(signal.SIGTERM, interrupted)

    from bench_report import render, sim_rows  # noqa: E402 (same folder)

    all_rows = main_rows()
    lever_rows = [r for lv in LEVERS for r in lv["rows"]]
    if args.list:
        for r in all_rows:
            print("main  ", r.id)
        for r in lever_rows:
            print("lever ", r.id)
        print("sim    sim (every simulator row)")
        return 0

    results_path = Path(args.results)
    committed = docs / "figures" / "bench_results.json"
    seed = results_path if results_path.exists() else committed  # rows not run keep their committed results
    store = json.loads(seed.read_text()) if seed.exists() else {}
    results_path.parent.mkdir(parents=True, exist_ok=True)
    store.setdefault("rows", {})
    store.setdefault("sim", {})
    if args.render_only:
        for e in store["rows"].values():  # the stored runs, aggregated by the current code
            e["agg"] = aggregate(e["runs"])
        results_path.write_text(json.dumps(store, indent=1, default=str))
        render(store, Path(args.report), report_plan(store))
        return 0

    bindir = Path(args.build).resolve() / "bin"
    for exe in ("shapeform_agent", "shapeform_supervisor", "shapeform_bench_baseline", "shapeform_bench_probe"):
        if not (bindir / exe).exists():
            print(f"bench: {bindir / exe} missing: run ./scripts/build.sh first", file=sys.stderr)
            return 2
    runs = args.runs or (1 if args.quick else 3)
    ctx = Ctx(bin=bindir, runs_dir=Path(args.runs_dir), window_s=0, disc_timeout_s=60 if not args.quick else 40,
              conv_timeout_s=60 if not args.quick else 40, scenario=(ROOT / args.scenario).resolve(),
              scenario_sets=SCENARIO_SETS, status_rate_hz=2.0, domain_base=args.domain_base,
              quiet_busy=args.quiet_busy / 100, quiet_wait_s=args.quiet_wait, max_other_pct=args.max_other_load,
              retries=args.retries)

    selected: list[Row] = []
    if not args.no_main:
        selected += all_rows
    if args.levers:
        # With --no-main, a lever row that is also a main row keeps its stored main result (median of its runs).
        selected += [r for r in lever_rows if not (args.no_main and r.id in {m.id for m in all_rows}
                                                  and r.id in store["rows"])]
    for spec in args.row:
        parts = spec.split(":")
        r = Row(parts[0], int(parts[1]), float(parts[2]), parts[3] if len(parts) > 3 else "default",
                float(parts[4]) if len(parts) > 4 else 0.0, int(parts[5]) if len(parts) > 5 else 0, "experiment",
                len(parts) > 6 and parts[6] == "view")
        if r.preset not in PRESETS:
            print(f"bench: unknown preset {r.preset}; known: {', '.join(PRESETS)}", file=sys.stderr)
            return 2
        selected.append(r)
    run_sim = not args.no_sim and ((not args.only and not args.row) or "sim" in args.only)
    only_rows = [o for o in args.only if o != "sim"]
    if args.only:
        pool = all_rows + lever_rows + selected
        ids = {r.id for r in pool}
        # A row id selects that row; anything else is a prefix (agents-n100 selects every N = 100 agent row).
        selected = [r for r in dict((r.id, r) for r in pool).values()
                    if any(r.id == o or (o not in ids and r.id.startswith(o)) for o in only_rows)]
        if not selected and not run_sim:
            print("bench: --only matched no row (see --list)", file=sys.stderr)
            return 2
    seen = set()
    selected = [r for r in selected if not (r.id in seen or seen.add(r.id))]

    store["machine"] = machine_info()
    store["commit"] = git_commit()
    store["date"] = dt.datetime.now().isoformat(timespec="seconds")
    store.pop("quick", None)  # per row since rows of several invocations share the file
    main_ids = {r.id for r in all_rows}
    for row in selected:
        if row.id in main_ids:
            row.section = "main"
        n_runs = args.runs or (row.runs or runs if row.section == "main" else args.lever_runs)
        ctx.window_s = args.window or (12.0 if args.quick else max(30.0, math.ceil(1100 / row.rate)))
        run_rows(ctx, [row], n_runs, store["rows"])
        store["rows"][row.id]["row"]["section"] = row.section
        store["rows"][row.id]["command"] = rerun_command(row, args, n_runs)
        store["rows"][row.id]["quick"] = bool(args.quick)
        results_path.parent.mkdir(parents=True, exist_ok=True)
        results_path.write_text(json.dumps(store, indent=1, default=str))
        render(store, Path(args.report), report_plan(store))  # partial results stay readable
    if run_sim:
        # Each call waits (up to two minutes) for a quiet host, as the agent rows do.
        sim_ctx = dataclasses.replace(ctx, quiet_wait_s=min(ctx.quiet_wait_s, 120.0))
        store["sim"] = sim_rows(bindir, args.quick, before=lambda: wait_quiet(sim_ctx))
        store["sim"]["commit"] = git_commit()
        store["sim"]["quick"] = bool(args.quick)
        results_path.write_text(json.dumps(store, indent=1, default=str))
    render(store, Path(args.report), report_plan(store))
    log(f"wrote {args.report} and {results_path}")
    return 0


def _get(store, rid, key):
    e = store.get("rows", {}).get(rid)
    return e["agg"].get(key) if e else None


def _summary(store, rid) -> str:
    from bench_report import f_ms, f_pct, f_s
    e = store.get("rows", {}).get(rid)
    if not e:
        return f"`{rid}`: not run yet"
    a = e["agg"]
    conv = f_s(a.get("converge_s")) if e["row"]["kind"] != "baseline" else "n/a"
    return (f"delivery {f_pct(a.get('delivery'))}, data age p50 {f_ms(a.get('age_p50_ms'))} / p99 "
            f"{f_ms(a.get('age_p99_ms'))}, everyone hears everyone: {f_s(a.get('all_heard_s'))}, "
            f"launch to converged: {conv}, {a.get('aborts_total', 0)} aborted processes in {a.get('runs', 1)} runs, "
            f"host {a.get('host_busy_pct', 0) or 0:.0f} % busy (`{rid}`)")


def _disc_reading(store: dict) -> str:
    """The measured cost of discovery (lever 15), as a clause; empty until measured."""
    parts = []
    for n in (50, 75, 100):
        rid = f"agents-n{n}-r20-largequiet"
        d, t, heard = _get(store, rid, "disc_udp_in"), _get(store, rid, "disc_udp_s"), _get(store, rid, "all_heard_s")
        if d is None or t is None:
            continue
        done = heard is not None and not math.isinf(heard)
        parts.append(f"N = {n}: {d / 1e6:.1f} million in {t:.0f} s" + ("" if done else " without finishing"))
    if not parts:
        return ""
    return (" (lever 15, agents silent but for a state every 5 s until commanded, datagrams the host received from "
            "launch to 'everyone hears everyone': " + "; ".join(parts) + ")")


def _limits_1000(store: dict, g100: str, g50: str, b100: str, b50: str) -> str:
    """What limits 1000 agents in groups, from the measured rows (empty until they are measured)."""
    busy = {rid: _get(store, rid, "host_busy_pct") for rid in (g100, g50, b100, b50)}
    if None in busy.values():
        return ""
    uni = {k: _get(store, f"group-n1000-r20-g{k}", "host_busy_pct") for k in (100, 50)}
    uni_txt = (f" With the default unicast transport each batch leaves a process as P sends, and the same rows "
               f"kept the host {uni[100]:.0f} % and {uni[50]:.0f} % busy (lever 13)."
               if None not in uni.values() else "")
    return (f" **1000 agents** in 10 processes of 100: each process publishes one AgentStateBatch per tick "
            f"(10 x 9 x 20 = 1,800 inter-process deliveries/s instead of 19,980,000 agent-to-agent updates), and its "
            f"agents share one table of the states heard and one sorted arc list per tick; the host was "
            f"{busy[g100]:.0f} % busy (the bare grouped baseline of the same shape {busy[b100]:.0f} %). In 20 "
            f"processes of 50 it was {busy[g50]:.0f} % busy (the bare baseline {busy[b50]:.0f} %): every process "
            "receives, unpacks and tables the states of all N agents every tick whatever it hosts, so that work, "
            "and the transport's part of it, which the baseline measures alone, grows with the number of processes "
            "times N." + uni_txt)


def report_plan(store: dict) -> dict:
    from bench_report import f_ms
    main = [r.id for r in main_rows()]
    mp = MAIN_PRESET
    n100, g50, g25 = "agents-n100-r20-large", "group-n100-r20-g50", "group-n100-r20-g25"
    n25, b25 = f"agents-n25-r20-{mp}", f"baseline-n25-r20-{mp}"
    b100 = "baseline-n100-r20-large"
    ds100 = f"agents-n100-r20-ds{mp}"
    ms = lambda v: f_ms(v)  # noqa: E731
    targets_100 = [
        ("N=100 at 20 Hz: delivery >= 99 %", "delivery", "min", 0.99, lambda v: f"{100 * v:.2f} %"),
        ("N=100 at 20 Hz: data age p99 <= 100 ms", "age_p99_ms", "max", 100.0, ms),
        ("N=100 at 20 Hz: everyone hears everyone within 10 s", "all_heard_s", "max", 10.0, lambda v: f"{v:.1f} s"),
        ("N=100 at 20 Hz: no process aborts", "aborts_total", "max", 0, str),
        ("N=100 at 20 Hz: the circle converges", "converged", "", 0, str),
    ]
    g1000, g1000b = f"group-n1000-r20-g100-{mp}", f"group-n1000-r20-g50-{mp}"
    bg1000, bg1000b = f"baseline-n1000-r20-g100-{mp}", f"baseline-n1000-r20-g50-{mp}"
    targets_1000 = [
        ("N=1000 at 20 Hz, 10-20 processes: delivery >= 99 %", "delivery", "min", 0.99, lambda v: f"{100 * v:.2f} %"),
        ("N=1000 at 20 Hz, 10-20 processes: data age p99 <= 100 ms", "age_p99_ms", "max", 100.0, ms),
        ("N=1000 at 20 Hz, 10-20 processes: everyone hears everyone within 10 s", "all_heard_s", "max", 10.0,
         lambda v: f"{v:.1f} s"),
        ("N=1000 at 20 Hz, 10-20 processes: the arc-law circle converges", "converged", "", 0, str),
        ("N=1000 at 20 Hz, 10-20 processes: the host at most half busy", "host_busy_pct", "max", 50.0,
         lambda v: f"{v:.0f} %"),
    ]
    targets_25 = [
        ("N=25 at 20 Hz: data age p50 <= 1 ms", "age_p50_ms", "max", 1.0, ms),
        ("N=25 at 20 Hz: data age p99 <= 5 ms", "age_p99_ms", "max", 5.0, ms),
        ("N=25 at 20 Hz: p50 age within 1.5x of the baseline", "ratio_p50", "max", 1.5, str),
        ("N=25 at 20 Hz: p99 age within 1.5x of the baseline", "ratio_p99", "max", 1.5, str),
        ("N=25 at 20 Hz: RSS <= 20 MB per agent", "rss_mb", "max", 20.0, lambda v: f"{v:.1f} MB"),
        ("N=25 at 20 Hz: loop lateness p99 <= 1 ms", "lateness_p99_ms", "max", 1.0, ms),
    ]
    headline = [
        "## Headline\n",
        f"- **100 agent processes at 20 Hz** (one process per agent, the launcher's large-swarm settings): {_summary(store, n100)}.",
        f"- **100 agent processes with a discovery server** (the same, discovery through `fast-discovery-server` on "
        f"127.0.0.1): {_summary(store, ds100)}.",
        f"- **The bare Fast DDS floor at N = 100** (same payload, transport and rate): {_summary(store, b100)}.",
        f"- **1000 agents in 10 processes of 100** (`shapeform_agent_group`, one AgentStateBatch per process and "
        f"tick, multicast on lo): {_summary(store, g1000)}; the bare baseline of that shape: {_summary(store, bg1000)}.",
        f"- **1000 agents in 20 processes of 50**: {_summary(store, g1000b)}; the bare baseline of that shape: "
        f"{_summary(store, bg1000b)}.",
        f"- **100 agents in 2 processes of 50** (`shapeform_agent_group`): {_summary(store, g50)}.",
        f"- **100 agents in 4 processes of 25**: {_summary(store, g25)}.",
        f"- **25 agent processes at 20 Hz**: {_summary(store, n25)}; baseline: {_summary(store, b25)}.",
    ]
    busy = _get(store, b100, "host_busy_pct")
    udp_in = _get(store, b100, "udp_in_per_s")
    ours = _get(store, b100, "ours_cpu_pct")
    g_busy = _get(store, g50, "host_busy_pct")

    def meets_100(rid):
        d, p99, heard = _get(store, rid, "delivery"), _get(store, rid, "age_p99_ms"), _get(store, rid, "all_heard_s")
        conv, aborts = _get(store, rid, "converge_s"), _get(store, rid, "aborts_total")
        return (None not in (d, p99, heard, conv) and d >= 0.99 and p99 <= 100 and heard <= 10
                and not math.isinf(conv) and not aborts)

    ds_busy = _get(store, ds100, "host_busy_pct")
    limits = (
        "**What limits N = 100 processes.** First, a bug, found and fixed on 2026-11-22 (commit f23146a): Fast DDS "
        "2.9 gives a participant whose port slot is taken 100 more tries (`builtin.mutation_tries`) and then creates "
        "it without any unicast port, silently. An N = 100 agent run has 102 participants on the domain (the "
        "agents, the supervisor, the probe), so one agent heard nobody and nobody heard it: every earlier N = 100 "
        "agent row (delivery about 97.8 %, data age p99 over 200 ms, 'everyone hears everyone' never, never "
        "converged) measured a swarm with a deaf member. The factory now allows `max_participants` slots and "
        "refuses a participant that got no port. What remains is the load. All-to-all state at 20 Hz is "
        "N x (N-1) x 20 = 198,000 sample deliveries per second, each a datagram that a process must receive and "
        "pass through Fast DDS (socket read, RTPS parsing, reader history, listener). "
        + (f"The bare baseline at N = 100 (no agent logic at all) received {udp_in:,.0f} datagrams/s on the host and "
           f"its processes used {ours:.0f} % of one core, {busy:.0f} % of the 2-core host busy in all: the transport "
           "alone fills the machine. " if None not in (busy, udp_in, ours) else "")
        + "Multicast removes the N-1 sends per sample but not the N-1 receives, and aligning every process's ticks "
        "on one clock grid (tried: `agent.phase_align`, single runs at N = 100: all hear all 34.6 s against 35.8 s, "
        "CPU per agent 1.9 % in both; removed again) does not make a receive cheaper. On a saturated host, the "
        "discovery of the last processes (N x N endpoint matching with simple discovery, about 100 process "
        "start-ups) waits for CPU, which is why 'everyone hears everyone' takes 35 s or more instead of 10; with "
        "simple discovery, Fast DDS 2.9 also aborts now and then on an assert in PDP.cpp (a lease timer of an "
        "already released participant proxy). The discovery server removes the aborts and halves the data age"
        + (f" (the host still {ds_busy:.0f} % busy)" if ds_busy is not None else "")
        + ", but its matching of about 100 clients starting at once is no faster here (lever 4). Hosting several agents per process divides the deliveries "
        "between processes: 2 processes of 50 agents carry 2 x 99 x 20 = 3,960 inter-process deliveries/s instead "
        "of 198,000"
        + (f", and the host was {g_busy:.0f} % busy" if g_busy is not None else "")
        + ("; that configuration meets every N = 100 target." if meets_100(g50) else ".")
        + ("" if not meets_100(n100) else " (One process per agent met the N = 100 targets as well in these runs.)")
        + " On 2026-12-02 this host no longer finished the discovery of 100 agent processes within a minute, with "
        "any of the settings or code versions tried (levers 10, 12, 14): the one-process-per-agent rows of that day "
        "miss 'everyone hears everyone' and the convergence, and their data age is that of a swarm still "
        "discovering itself while it runs. Discovery is the wall: in Fast DDS 2.9 a participant that discovers a "
        "new one sends its own announcement again to every participant it knows and every slot it probes, so N "
        "processes starting together make about N x N announcements, each received and parsed by about N "
        "processes, and simple endpoint discovery adds a reliable exchange per pair on top"
        + _disc_reading(store) + "."
        + _limits_1000(store, g1000, g1000b, bg1000, bg1000b))
    method = """- **Runs.** Each run uses its own DDS domain (200..229 in turn), starts `shapeform_bench_probe`, then (agent rows)
  the supervisor with the script `wait agents N; start; wait converged; sleep W; quit`, then the N processes
  (`shapeform_agent --id i --config config/scenarios/arc_circle.yaml --seed 1 --set agent.rate_hz=R
  --set agent.status_rate_hz=2`, or `shapeform_agent_group --ids A-B` for grouped rows, or
  `shapeform_bench_baseline --id i`, or `shapeform_bench_baseline --ids A-B` for grouped baseline rows).
  Baseline rows run until every agent hears all others, then W seconds.
  The measurement window is the last W seconds (W = 55 s at 20 Hz, 30 s at 50 Hz; 12 s with --quick).
  Processes are stopped with SIGTERM 10 ms apart; anything still alive after 20 s is killed and counted.
  Before each run the script waits for the host to be nearly idle; a run during which other jobs used more
  than 25 % of a core is repeated (up to twice); the "other load" column shows what remained.
- **All hear all**: from the first launch to the first status in which the last process reports N-1 neighbours
  heard (statuses every 0.5 s, so +-0.5 s). "never" = not within the discovery timeout (60 s; 40 s with --quick).
- **Delivery**: over the window, samples each process accepted (its `samples_received` counter) divided by what
  the others published in the same time (their `ticks` counters, one sample per tick); counters are
  interpolated at the window's ends. Agents hosted in the same process count as deliveries (in-process).
- **Data age**: receive time (listener, steady clock) minus the sender's stamp in the sample; each process
  reports p50 and p99 over each 0.5 s status period; the table gives the median over all processes and
  periods of the window, and the worst period's p99. Samples from agents hosted in the same process are not aged.
- **Lateness p99**: the agent loop's own p99 of tick start lateness over its last 1024 ticks (51 s at 20 Hz),
  taken at the end of the window; median over processes. **Overruns**: skipped periods / ticks in the window.
- **CPU % per agent**: the process's own CPU over each status period (% of one core), averaged over the
  window, mean over processes; grouped processes report their CPU divided by the agents they host (same for RSS).
  **Supervisor CPU** and **host busy** from `/proc` over the window; **other load** = host CPU used by processes
  this run did not start, in % of one core.
- **Launch to converged**: from the first launch to the first `SwarmMetrics` sample with `converged` (the
  supervisor's detector: shape error band held for 50 model time units and gap CV <= 0.15); "never" = not within
  the supervisor's `wait converged` timeout (60 s; 40 s with --quick). The scenario is
  the circle with the arc law (`config/scenarios/arc_circle.yaml`): with the paper's law the circle of 50 or
  more agents never reaches a gap CV of 0.15 even in the simulator (about 0.75), so it could not show whether
  the distributed swarm converges.
- **Baseline**: `bench/baseline.cpp`, one participant from `dds::create_participant` (same transport config),
  one AgentState writer and reader with the topic table's QoS, a listener that books age and sequence gaps in
  place, the same RateLoop and the same AgentStatus reports; no mailbox, no control law, no other topics.
  Grouped baseline rows (`-gK`): K ids per process, one AgentStateBatch writer and reader instead (each
  element booked as one agent's sample, co-hosted ids heard in-process as in `shapeform_agent_group`) and one
  AgentStatus per hosted id.
- **Aborts**: processes that died of a signal other than our SIGTERM. The usual cause is an assert that is
  live in Debian's Fast DDS 2.9 build: `PDP.cpp check_remote_participant_liveliness: Assertion
  GUID_t::unknown() != remote_participant->m_guid` (SIGABRT), when a remote participant's lease timer runs after
  its proxy was released; seen with simple discovery at N >= 50 on a saturated host."""
    return {"main": main, "targets": [(n100, targets_100), (ds100, targets_100), (g50, targets_100),
                                      (g1000, targets_1000), (g1000b, targets_1000), (n25, targets_25)],
            "headline": headline, "limits": limits,
            "main_intro": f"Main rows of N <= 50 use the transport settings `{MAIN_PRESET}` "
                          f"({PRESETS[MAIN_PRESET]['about']}); the N = 100 rows what the launcher runs by default "
                          f"from {LARGE_MIN} agents on (`large`: {PRESETS['large']['about']}); grouped rows of N <= 100 use the "
                          f"project defaults (a few participants do not need them), the 1000-agent rows `{MAIN_PRESET}` "
                          "(lever 13). The levers below compare them with the defaults.",
            "levers": [{"name": lv["name"], "question": lv["question"], "rows": [r.id for r in lv["rows"]],
                        "pairs": [(a.id, b.id) for a, b in lv.get("pairs", [])],
                        "note": lv.get("note", ""), "extra": lv.get("extra", False),
                        "view": lv.get("view", False)} for lv in LEVERS],
            "levers_intro": "Single runs unless a row is also a main row (then the median of its runs). The extra tables "
                            "give the kernel's UDP counters over the window (all processes of the host).",
            "presets": {k: v["about"] for k, v in PRESETS.items()}, "method": method}


def rerun_command(row: Row, args, runs: int) -> str:
    cmd = "scripts/bench.sh"
    if args.quick:
        cmd += " --quick"
    if row.section == "experiment":
        spec = f"{row.kind}:{row.n}:{row.rate:g}:{row.preset}:{row.stagger_s:g}:{row.group}" + (":view" if row.view else "")
        return f"{cmd} --runs {runs} --row {spec} --only {row.id}"
    return f"{cmd} --runs {runs} --only {row.id}"


SCENARIO_SETS: list[str] = []

if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    sys.exit(main())
