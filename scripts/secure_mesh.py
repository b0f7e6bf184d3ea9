#!/usr/bin/python3
"""How long a secured swarm takes to mesh on this host, and what it costs (docs/SECURITY.md, Cost).

  scripts/secure_mesh.py -n N [--groups G] [--runs R] [--plain] [--stagger S] [--gate S] [--timeout S]
                         [--domain D] [--keystore DIR] [--set key=value]... [--openssl-conf FILE]
                         [--pcap FILE] [--build DIR]

Starts N agents (no supervisor) on loopback, domain D (default 70), secured with the keystore DIR
(default: made once in /tmp/shapeform_mesh_keys by scripts/make_keystore.sh), as N agent processes
or, with --groups G, as G shapeform_agent_group processes of N/G agents each. Process k starts
k * S seconds after the first (--stagger, default 0: all at once); with --gate S2, also not before
process k-1 hears every agent started before it, or S2 seconds have passed (an agent prints its
"hearing" line at most about once a second: the gate is coarse to about 1 s). It reads each process's
"hearing K neighbours" lines (progress on stderr every 5 s) and reports, per run, one JSON line on
stdout:

  {"n":N,"processes":P,"secured":true,"stagger_s":S,"mesh_s":T or null,"heard_min":K,
   "cpu_pct_per_agent":C,"rss_mb_per_agent":M,"load_1min":L,...}

mesh_s: seconds from the first start until every agent hears all N-1 others (null: not within
--timeout, default 20 + N); heard_min: the least any process heard at the end. CPU: the processes'
CPU time over the 10 s after the mesh (or after the timeout), per agent, in % of one core. With
--pcap FILE, loopback traffic of the domain's ports is captured (tcpdump, needs root; the first 200
bytes of each datagram, enough for the RTPS headers and a handshake's destination) and the RTPS DATA
submessages of the handshake writer (ParticipantStatelessMessage, entity 0x000201c3) counted
(handshake_data, handshake_bytes: the datagrams' full sizes), and the distinct messages among them
(handshake_messages: by sender and sequence number; Fast DDS 2.9.1 sends each to every matched
participant, the project's transport only to its destination (common/dds/handshake_filter.hpp), and
a resend is a new message), the requests among those (handshake_requests: the first
message of a handshake; the others are replies and finals) and the pairs of participants they are
between (handshake_pairs: a pair is counted once, whichever way its messages go). handshake_by_10s
gives [datagrams, handshake_data, handshake_messages, handshake_requests, handshake_pairs] per 10 s of
the capture. kinds (and kinds_by_10s, per 10 s) counts the datagrams by what they carry (KINDS below:
handshake, announcement, key_exchange, protected, data, initial_acknack, acknack, heartbeat, other). A
saturated host drops datagrams from the capture: capture_seen is what the kernel's filter passed,
capture_kept what tcpdump wrote (the counts are of those). Every process started is stopped
before the next run. Exit 0 when every run meshed, 3 otherwise, 2 on bad arguments.
"""
import argparse
import json
import os
import re
import signal
import struct
import subprocess
import sys
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
HEARING = re.compile(r"hear(?:ing|s at least) (\d+) neighbours")
STATELESS_WRITER = bytes.fromhex("000201c3")


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    p.add_argument("-n", type=int, required=True, help="agents")
    p.add_argument("--groups", type=int, default=0, help="host the agents in G group processes")
    p.add_argument("--runs", type=int, default=1)
    p.add_argument("--plain", action="store_true", help="no security (the control)")
    p.add_argument("--stagger", type=float, default=0.0, help="seconds between process starts")
    p.add_argument("--gate", type=float, default=0.0,
                   help="start each process once the one before hears every agent started before it, "
                        "waiting at most this many seconds (default 0: no gate)")
    p.add_argument("--timeout", type=float, default=None)
    p.add_argument("--domain", type=int, default=70)
    p.add_argument("--keystore", default="/tmp/shapeform_mesh_keys")
    p.add_argument("--set", action="append", default=[], dest="sets")
    p.add_argument("--openssl-conf", default=None, help="OPENSSL_CONF for the agents")
    p.add_argument("--pcap", default=None)
    p.add_argument("--build", default=str(ROOT / "build"))
    a = p.parse_args()
    if a.n < 2:
        p.error("-n must be at least 2, got %d" % a.n)
    if a.groups < 0 or (a.groups and a.n % a.groups):
        p.error("--groups %d must divide -n %d" % (a.groups, a.n))
    if a.stagger < 0 or a.gate < 0:
        p.error("--stagger %g and --gate %g must be at least 0" % (a.stagger, a.gate))
    for s in a.sets:
        if "=" not in s:
            p.error("--set %r is not key=value" % s)
    if a.timeout is None:
        a.timeout = 20.0 + a.n
    return a


def cpu_ticks(pid):
    try:
        with open("/proc/%d/stat" % pid) as f:
            fields = f.read().rsplit(")", 1)[1].split()
        return int(fields[11]) + int(fields[12])
    except (OSError, IndexError, ValueError):
        return 0


def rss_mb(pid):
    try:
        with open("/proc/%d/status" % pid) as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return 0.0


class Member:
    """One process and the most neighbours its log says it (each of its agents) hears."""

    def __init__(self, cmd, env, log):
        self.heard = 0
        self.log = open(log, "w")
        self.proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env,
                                     start_new_session=True, text=True)
        self.thread = threading.Thread(target=self._read, daemon=True)
        self.thread.start()

    def _read(self):
        for line in self.proc.stderr:
            self.log.write(line)
            m = HEARING.search(line)
            if m:
                self.heard = int(m.group(1))

    def stop(self):
        if self.proc.poll() is None:
            os.killpg(self.proc.pid, signal.SIGTERM)

    def kill(self):
        if self.proc.poll() is None:
            os.killpg(self.proc.pid, signal.SIGKILL)


def handshake_of(body, flags):
    """A handshake DATA's (destination participant's GUID prefix, is a request) from its payload (a
    ParticipantGenericMessage: message_identity, related_message_identity, destination_participant_key,
    ...; a request relates to no message), or None when the capture cut it before the destination."""
    e = "<" if flags & 1 else ">"
    p = body[4 + struct.unpack(e + "H", body[2:4])[0]:]
    while flags & 2 and len(p) >= 4:  # inline QoS: a parameter list up to PID_SENTINEL
        pid, size = struct.unpack(e + "HH", p[:4])
        p = p[4 + size:]
        if pid == 1:
            break
    pl = p[4:]  # the encapsulation
    if len(pl) < 60:
        return None
    return pl[48:60], pl[24:40] == bytes(16)


SPDP_WRITER = bytes.fromhex("000100c2")
# What a datagram carries, by the most telling submessage in it (first in this order): a handshake message,
# a participant announcement, a submessage protected with the key exchange's own key (transformation key
# id 0: Fast DDS's ParticipantVolatileMessageSecure endpoints, which carry the key exchange), another
# protected submessage, other DATA, an initial ACKNACK (nothing received yet, nothing asked: a reader
# that has not heard a heartbeat from its writer), another ACKNACK, a HEARTBEAT, anything else.
KINDS = ("handshake", "announcement", "key_exchange", "protected", "data", "initial_acknack", "acknack",
         "heartbeat", "other")


def datagram_kind(rtps):
    """The kind (KINDS) of one RTPS datagram (as captured: maybe cut short)."""
    seen = set()
    off = 20
    while off + 4 <= len(rtps):
        sid, flags = rtps[off], rtps[off + 1]
        e = "<" if flags & 1 else ">"
        length = struct.unpack(e + "H", rtps[off + 2:off + 4])[0]
        body = rtps[off + 4:off + 4 + length] if length else rtps[off + 4:]
        if sid == 0x15:
            seen.add("handshake" if body[8:12] == STATELESS_WRITER else
                     "announcement" if body[8:12] == SPDP_WRITER else "data")
        elif sid == 0x31 and len(body) >= 8:  # SEC_PREFIX: transformation kind, then key id
            seen.add("key_exchange" if body[4:8] == bytes(4) else "protected")
        elif sid == 0x06 and len(body) >= 20:  # readerId, writerId, readerSNState base (high, low), numBits
            high, low, bits = struct.unpack(e + "iII", body[8:20])
            seen.add("initial_acknack" if (high, low, bits) == (0, 0, 0) else "acknack")
        elif sid == 0x07:
            seen.add("heartbeat")
        if length == 0:
            break
        off += 4 + length
    return next((k for k in KINDS if k in seen), "other")


def count_handshakes(pcap):
    """DATA submessages of the stateless (handshake) writer in a pcap of loopback, in all and per 10 s; and
    the datagrams by kind (KINDS), in all and per 10 s."""
    data = Path(pcap).read_bytes()
    if len(data) < 24:
        data = struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, 65535, 1)  # no capture: no datagram
    magic = struct.unpack("<I", data[:4])[0]
    endian = "<" if magic in (0xA1B2C3D4, 0xA1B23C4D) else ">"
    linktype = struct.unpack(endian + "I", data[20:24])[0]
    l2 = 14 if linktype == 1 else (16 if linktype == 113 else 4)
    # Per 10 s of the capture: [datagrams, handshake DATA, distinct messages, requests among them, pairs of
    # participants in a handshake]; the totals are their sums (sets: their unions, a message's resends and
    # a pair's handshake can fall in two periods).
    pos, hs_bytes, t0, buckets = 24, 0, None, {}
    while pos + 16 <= len(data):
        ts, _, incl, orig = struct.unpack(endian + "IIII", data[pos:pos + 16])
        pkt = data[pos + 16:pos + 16 + incl]
        pos += 16 + incl
        ip = pkt[l2:]
        if len(ip) < 28 or ip[9] != 17:
            continue
        header = (ip[0] & 0x0F) * 4
        udp = ip[header:]
        rtps = udp[8:]
        if rtps[:4] != b"RTPS":
            continue
        t0 = ts if t0 is None else t0
        bucket = buckets.setdefault((ts - t0) // 10, [0, 0, set(), set(), set(), {}])
        bucket[0] += 1
        kind = datagram_kind(rtps)
        bucket[5][kind] = bucket[5].get(kind, 0) + 1
        off = 20
        while off + 4 <= len(rtps):
            sid, flags = rtps[off], rtps[off + 1]
            length = struct.unpack(("<" if flags & 1 else ">") + "H", rtps[off + 2:off + 4])[0]
            body = rtps[off + 4:off + 4 + length] if length else rtps[off + 4:]
            if sid == 0x15 and body[8:12] == STATELESS_WRITER:
                message = (rtps[8:20], body[12:20])  # sender's GUID prefix, sequence number
                bucket[1] += 1
                bucket[2].add(message)
                hs_bytes += orig - l2 - header - 8  # the datagram's RTPS bytes, captured or not
                seen = handshake_of(body, flags)
                if seen:
                    if seen[1]:
                        bucket[3].add(message)
                    bucket[4].add(frozenset((rtps[8:20], seen[0])))
            if length == 0:
                break
            off += 4 + length
    by_10s = [buckets.get(k, [0, 0, set(), set(), set(), {}]) for k in range(max(buckets, default=-1) + 1)]
    union = lambda i: len(set().union(*(b[i] for b in by_10s)))
    in_order = lambda counts: {k: counts[k] for k in KINDS if counts.get(k)}
    return {"datagrams": sum(b[0] for b in by_10s), "handshake_data": sum(b[1] for b in by_10s),
            "handshake_messages": union(2), "handshake_requests": union(3), "handshake_pairs": union(4),
            "handshake_bytes": hs_bytes,
            "handshake_by_10s": [[b[0], b[1], len(b[2]), len(b[3]), len(b[4])] for b in by_10s],
            "kinds": in_order({k: sum(b[5].get(k, 0) for b in by_10s) for k in KINDS}),
            "kinds_by_10s": [in_order(b[5]) for b in by_10s]}


def capture_stats(text):
    """tcpdump's closing counts: {"capture_kept", "capture_seen", "capture_dropped"} (what it printed)."""
    names = {"captured": "capture_kept", "received by filter": "capture_seen", "dropped by kernel": "capture_dropped"}
    out = {}
    for number, what in re.findall(r"^(\d+) packets? (captured|received by filter|dropped by kernel)$", text, re.M):
        out[names[what]] = int(number)
    return out


def run_once(a, run_dir, label=""):
    """One run; `label` starts its progress lines."""
    binary = Path(a.build) / "bin" / ("shapeform_agent_group" if a.groups else "shapeform_agent")
    procs = a.groups or a.n
    per = a.n // procs
    env = dict(os.environ)
    if a.openssl_conf:
        env["OPENSSL_CONF"] = a.openssl_conf
    sets = [] if a.plain else ["security.enabled=true", "security.keystore=" + a.keystore]
    sets += ["swarm.agents=%d" % a.n] + a.sets
    tcpdump = None
    if a.pcap:
        base = 7400 + 250 * a.domain
        tcpdump = subprocess.Popen(["tcpdump", "-i", "lo", "-s", "200", "-B", "65536", "-w", a.pcap, "-U",
                                    "udp portrange %d-%d" % (base, base + 249)], stdout=subprocess.DEVNULL,
                                   stderr=subprocess.PIPE, text=True)
        time.sleep(0.5)  # tcpdump opens its socket; only a capture's completeness depends on it
    members = []
    starts = []
    load = os.getloadavg()[0]
    t0 = time.monotonic()
    mesh = None
    shown = [t0]

    def progress(final=""):
        """At most every 5 s (and at the end), on stderr: how far the run is."""
        now = time.monotonic()
        if not final and now < shown[0] + 5.0:
            return
        shown[0] = now
        heard = [m.heard for m in members] or [0]
        print("secure_mesh: %s%.0f s: %d of %d processes started, each hearing %d to %d of the %d others%s"
              % (label, now - t0, len(members), procs, min(heard), max(heard), a.n - 1, final),
              file=sys.stderr, flush=True)

    try:
        for k in range(procs):
            while time.monotonic() < t0 + k * a.stagger:
                time.sleep(0.02)
                progress()
            gate_end = time.monotonic() + a.gate
            while k > 0 and members[-1].heard < k * per - 1 and time.monotonic() < gate_end:
                time.sleep(0.02)
                progress()
            starts.append(round(time.monotonic() - t0, 2))
            ids = ["--ids", "%d-%d" % (k * per, k * per + per - 1)] if a.groups else ["--id", str(k)]
            cmd = [str(binary)] + ids + ["--seed", "1", "--domain", str(a.domain)]
            for s in sets:
                cmd += ["--set", s]
            members.append(Member(cmd, env, run_dir / ("proc_%d.log" % k)))
        while time.monotonic() < t0 + a.timeout:
            if all(m.heard >= a.n - 1 for m in members):
                mesh = time.monotonic() - t0
                break
            dead = [m for m in members if m.proc.poll() is not None]
            if dead:
                break
            time.sleep(0.05)
            progress()
        progress(": meshed" if mesh is not None else ": not meshed; the CPU over the next 10 s")
        c0 = sum(cpu_ticks(m.proc.pid) for m in members)
        w0 = time.monotonic()
        time.sleep(10.0)
        c1 = sum(cpu_ticks(m.proc.pid) for m in members)
        cpu = (c1 - c0) / os.sysconf("SC_CLK_TCK") / (time.monotonic() - w0) * 100.0 / a.n
        rss = sum(rss_mb(m.proc.pid) for m in members) / a.n
        heard_min = min(m.heard for m in members)
        exited = [i for i, m in enumerate(members) if m.proc.poll() is not None]
    finally:
        for m in members:
            m.stop()
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline and any(m.proc.poll() is None for m in members):
            time.sleep(0.1)
        for m in members:
            m.kill()
            m.proc.wait()
            m.thread.join(timeout=5)
            m.log.close()
        capture = {}
        if tcpdump:
            tcpdump.send_signal(signal.SIGINT)
            capture = capture_stats(tcpdump.communicate()[1])
    out = {"n": a.n, "processes": procs, "secured": not a.plain, "stagger_s": a.stagger,
           "gate_s": a.gate, "starts_s": starts, "mesh_s": None if mesh is None else round(mesh, 2), "heard_min": heard_min,
           "cpu_pct_per_agent": round(cpu, 2), "rss_mb_per_agent": round(rss, 1), "load_1min": round(load, 2),
           "sets": a.sets, "openssl_conf": a.openssl_conf, "exited": exited}
    if a.pcap:
        out.update(capture)
        out.update(count_handshakes(a.pcap))
    return out


def main():
    a = parse_args()
    # A group process's identity is its first agent's (docs/SECURITY.md): only those enclaves are needed.
    step = a.n // a.groups if a.groups else 1
    missing = [k for k in range(0, a.n, step) if not Path(a.keystore, "enclaves", "agent_%d" % k).is_dir()]
    if not a.plain and missing:
        args = [str(ROOT / "scripts" / "make_keystore.sh"), a.keystore]
        for k in missing:
            args += ["--enclave", "agent_%d" % k]
        subprocess.run(args, check=True, stdout=subprocess.DEVNULL)
    work = ROOT / "runs" / (time.strftime("%Y%m%dT%H%M%S", time.gmtime()) + "-secure_mesh")
    ok = True
    for r in range(a.runs):
        run_dir = work / ("run_%d" % r)
        run_dir.mkdir(parents=True, exist_ok=True)
        res = run_once(a, run_dir, "run %d of %d, " % (r + 1, a.runs) if a.runs > 1 else "")
        res["run"] = r
        res["logs"] = str(run_dir)
        print(json.dumps(res), flush=True)
        ok = ok and res["mesh_s"] is not None
    return 0 if ok else 3


if __name__ == "__main__":
    sys.exit(main())
