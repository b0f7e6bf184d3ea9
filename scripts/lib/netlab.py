#!/usr/bin/python3
"""Test hosts from Python: a thin wrapper of scripts/netlab.sh (standard library only).

    with NetLab("d3", hosts=4, subnet="10.200.6") as lab:
        argv = lab.on("h1", [agent, "--id", "0", ...] + lab.lan_sets("h1"))
        lab.fault("h2", "partition"); lab.fault("h2", "heal")

A NetLab is removed on exit from the `with` block whatever happened (processes still on its hosts are
stopped first); `leftovers()` names anything of it still on the machine.

Captures (tcpdump inside a host's or the switch's namespace), proven live by a probe before they count:

    with lab.capture("h2", "eth1", "h2-eth1.pcap") as cap:
        lab.probe("h1", "eth1", cap)           # returns once the probe is in the capture
        ...                                    # run processes
        assert cap.rtps() == []                # no RTPS datagram but the probe
"""
import collections
import contextlib
import os
import socket
import struct
import subprocess
import threading
import time
import uuid

SCRIPT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "netlab.sh")
STATE_ROOT = "/run/shapeform-netlab"
# UDP datagrams whose payload starts with "RTPS": every packet of DDS, and the probes below.
RTPS_FILTER = "udp and udp[8:4] = 0x52545053"
# Payload prefix of a probe (passes RTPS_FILTER; Capture.rtps() leaves probes out).
PROBE_PREFIX = b"RTPS shapeform capture probe "
PROBE_PORT = 9  # discard: nobody listens, and a broadcast gets no ICMP answer

# One captured IPv4/UDP datagram: time (s, capture clock), addresses, ports, payload bytes.
Packet = collections.namedtuple("Packet", "time src sport dst dport payload")


def read_pcap(path):
    """The IPv4/UDP datagrams of a pcap file of Ethernet frames, in order; a record cut short (the file is
    still being written) ends the list."""
    with open(path, "rb") as f:
        data = f.read()
    if len(data) < 24:
        return []
    magic = data[:4]
    endian = {b"\xd4\xc3\xb2\xa1": "<", b"\xa1\xb2\xc3\xd4": ">", b"\x4d\x3c\xb2\xa1": "<",
              b"\xa1\xb2\x3c\x4d": ">"}.get(magic)
    if endian is None:
        raise ValueError("%s: not a pcap file" % path)
    fraction = 1e-9 if magic in (b"\x4d\x3c\xb2\xa1", b"\xa1\xb2\x3c\x4d") else 1e-6
    (linktype,) = struct.unpack(endian + "I", data[20:24])
    if linktype != 1:
        raise ValueError("%s: link type %d, expected Ethernet (1)" % (path, linktype))
    out, at = [], 24
    while at + 16 <= len(data):
        sec, frac, incl, _ = struct.unpack(endian + "IIII", data[at:at + 16])
        frame = data[at + 16:at + 16 + incl]
        if len(frame) < incl:
            break
        at += 16 + incl
        eth = 14 + (4 if frame[12:14] == b"\x81\x00" else 0)
        if frame[eth - 2:eth] != b"\x08\x00" or len(frame) < eth + 20:
            continue
        ihl = (frame[eth] & 0x0F) * 4
        if frame[eth + 9] != 17 or len(frame) < eth + ihl + 8:
            continue
        src, dst = socket.inet_ntoa(frame[eth + 12:eth + 16]), socket.inet_ntoa(frame[eth + 16:eth + 20])
        sport, dport = struct.unpack(">HH", frame[eth + ihl:eth + ihl + 4])
        out.append(Packet(sec + frac * fraction, src, sport, dst, dport, frame[eth + ihl + 8:]))
    return out


class Capture:
    """tcpdump on one interface of a namespace (None: the machine's own, e.g. its `lo`), writing every
    datagram that `bpf` selects to a pcap file (packet-buffered, so that it can be read while tcpdump runs).
    Made by NetLab.capture(), or directly."""

    def __init__(self, namespace, iface, path, bpf):
        self.namespace, self.iface, self.path, self.bpf = namespace, iface, path, bpf
        self.proc = None
        self._stderr = []

    def start(self, timeout=10.0):
        """Starts tcpdump; returns once it reports that it listens (raises if it does not)."""
        if os.path.exists(self.path):
            os.remove(self.path)
        where = ["ip", "netns", "exec", self.namespace] if self.namespace else []  # None: this namespace
        self.proc = subprocess.Popen(
            where + ["tcpdump", "-i", self.iface, "-n", "-U", "--immediate-mode", "-B", "32768",
             "-Z", "root", "-w", self.path, self.bpf],
            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        listening = threading.Event()

        def read_stderr():
            for line in self.proc.stderr:
                self._stderr.append(line.rstrip())
                if "listening on" in line:
                    listening.set()

        self._reader = threading.Thread(target=read_stderr, daemon=True)
        self._reader.start()
        deadline = time.monotonic() + timeout
        while not listening.wait(0.05):
            if self.proc.poll() is not None or time.monotonic() > deadline:
                self.stop()
                raise RuntimeError("tcpdump on %s %s did not start: %s" % (self.namespace, self.iface,
                                                                          " | ".join(self._stderr)))
        return self

    def running(self):
        return self.proc is not None and self.proc.poll() is None

    def stop(self):
        """Stops tcpdump (SIGTERM; it flushes the file). Idempotent."""
        if self.proc is None:
            return
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(5)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self._reader.join(5)  # ends at tcpdump's end of stderr
        self.proc.stderr.close()

    def packets(self):
        """Every datagram captured so far (probes included)."""
        return read_pcap(self.path) if os.path.exists(self.path) else []

    def rtps(self):
        """The captured datagrams that are not probes (with RTPS_FILTER: every RTPS datagram seen)."""
        return [p for p in self.packets() if not p.payload.startswith(PROBE_PREFIX)]

    def saw_probe(self, token):
        mark = PROBE_PREFIX + token.encode()
        return any(p.payload == mark for p in self.packets())

    def __repr__(self):
        return "capture %s %s" % (self.namespace, self.iface)


def available():
    """None when test hosts can be made here, else why not (root, ip, iptables)."""
    if os.geteuid() != 0:
        return "network namespaces need root"
    for tool in ("ip", "iptables"):
        if not any(os.access(os.path.join(d, tool), os.X_OK) for d in os.environ.get("PATH", "").split(":") +
                   ["/usr/sbin", "/sbin"]):
            return "%s is not installed (scripts/install_deps.sh)" % tool
    return None


class NetLab:
    """K hosts h1..hK: namespaces sf-NAME-hN with eth0 at SUBNET.N (the test LAN) and eth1 (another
    network that the lan profile must not use)."""

    def __init__(self, name, hosts, subnet):
        self.name = name
        self.hosts = ["h%d" % i for i in range(1, hosts + 1)]
        self.subnet = subnet
        a, b, c = subnet.split(".")
        self.other_subnet = "%s.%s.%d" % (a, b, int(c) + 1)

    def _run(self, *args, check=True):
        r = subprocess.run([SCRIPT] + [str(a) for a in args], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           text=True, timeout=60)
        if check and r.returncode != 0:
            raise RuntimeError("netlab.sh %s failed (%d): %s" % (" ".join(map(str, args)), r.returncode,
                                                                r.stderr.strip()))
        return r

    def up(self):
        if os.path.exists(os.path.join(STATE_ROOT, self.name)):
            self._run("down", self.name)  # left by a run that was itself killed: ours by name
        self._run("up", self.name, len(self.hosts), "--subnet", self.subnet)
        return self

    def down(self):
        self._run("down", self.name)

    def __enter__(self):
        return self.up()

    def __exit__(self, *exc):
        self.down()
        return False

    def namespace(self, host):
        return "sf-%s-%s" % (self.name, host)

    def address(self, host):
        return "%s.%d" % (self.subnet, self.hosts.index(host) + 1)

    def other_address(self, host):
        return "%s.%d" % (self.other_subnet, self.hosts.index(host) + 1)

    def on(self, host, argv):
        """argv run on `host` (its network namespace; same pid and file system)."""
        return ["ip", "netns", "exec", self.namespace(host)] + [str(a) for a in argv]

    def lan_sets(self, host, peers=None, multicast_data=False):
        """The --set flags of the lan profile bound to `host`'s test-LAN address (multicast discovery,
        or unicast to `peers` hosts)."""
        sets = ["transport.profile=lan", "transport.interfaces=[%s]" % self.address(host)]
        if peers:
            sets.append("transport.peers=[%s]" % ",".join(self.address(h) for h in peers))
        if multicast_data:
            sets.append("transport.multicast_data=true")
        return [x for s in sets for x in ("--set", s)]

    @contextlib.contextmanager
    def capture(self, host, iface, path, bpf=RTPS_FILTER):
        """A Capture of `iface` on `host` (h1..hK: eth0, eth1; "sw", the switch: br0 and br1) into the pcap
        file `path`, from entry (tcpdump listens) to exit. A capture proves nothing until a packet sent on
        purpose is seen in it: probe() it first."""
        cap = Capture(self.namespace(host), iface, path, bpf).start()
        try:
            yield cap
        finally:
            cap.stop()

    def probe(self, host, iface, captures, dst=None, timeout=10.0):
        """Sends datagrams with payload PROBE_PREFIX + a fresh token from `host` out of `iface` (eth0 or
        eth1) to `dst` (default: the subnet's broadcast address, which every host's interface on that
        bridge and the bridge itself see), once every 0.2 s until every capture of `captures` (one or a
        list) has one. Returns the token; raises when a capture missed it for `timeout` s: a capture that
        is dead or on the wrong interface must not pass a test by seeing nothing."""
        captures = list(captures) if isinstance(captures, (list, tuple)) else [captures]
        token = uuid.uuid4().hex[:12]
        source = {"eth0": self.address, "eth1": self.other_address}[iface](host)
        if dst is None:
            dst = source.rsplit(".", 1)[0] + ".255"
        code = ("import socket,sys;s=socket.socket(socket.AF_INET,socket.SOCK_DGRAM);"
                "s.setsockopt(socket.SOL_SOCKET,socket.SO_BROADCAST,1);"
                "s.setsockopt(socket.IPPROTO_IP,socket.IP_MULTICAST_IF,socket.inet_aton(sys.argv[1]));"
                "s.bind((sys.argv[1],0));s.sendto(sys.argv[4].encode('latin-1'),(sys.argv[2],int(sys.argv[3])))")
        payload = (PROBE_PREFIX + token.encode()).decode("latin-1")
        deadline = time.monotonic() + timeout
        while True:
            subprocess.run(self.on(host, ["python3", "-c", code, source, dst, PROBE_PORT, payload]),
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, timeout=10)
            missing = [c for c in captures if not c.saw_probe(token)]
            if not missing:
                return token
            if time.monotonic() > deadline:
                raise RuntimeError("probe %s from %s %s to %s not seen by %s" % (token, host, iface, dst, missing))
            time.sleep(0.2)

    def fault(self, host, kind, percent=None):
        """kind: loss (percent), partition, nomulticast or heal."""
        self._run("fault", self.name, host, kind, *([] if percent is None else [percent]))

    def pids(self, host):
        r = subprocess.run(["ip", "netns", "pids", self.namespace(host)], stdout=subprocess.PIPE,
                           stderr=subprocess.DEVNULL, text=True)
        return sorted(int(p) for p in r.stdout.split())

    def leftovers(self):
        """What of this lab is still on the machine (namespaces, its state file); [] when all is gone."""
        out = []
        r = subprocess.run(["ip", "netns", "list"], stdout=subprocess.PIPE, text=True)
        prefix = "sf-%s-" % self.name
        out += ["namespace " + line.split()[0] for line in r.stdout.splitlines() if line.startswith(prefix)]
        if os.path.exists(os.path.join(STATE_ROOT, self.name)):
            out.append("state file %s/%s" % (STATE_ROOT, self.name))
        return out


if __name__ == "__main__":
    import shapeform_procs
    shapeform_procs.module_main(__file__, "test hosts from Python, a thin wrapper of scripts/netlab.sh")
