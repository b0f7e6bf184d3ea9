"""Test hosts from Python: a thin wrapper of scripts/netlab.sh (standard library only).

    with NetLab("d3", hosts=4, subnet="10.200.6") as lab:
        argv = lab.on("h1", [agent, "--id", "0", ...] + lab.lan_sets("h1"))
        lab.fault("h2", "partition"); lab.fault("h2", "heal")

A NetLab is removed on exit from the `with` block whatever happened (processes still on its hosts are
stopped first); `leftovers()` names anything of it still on the machine.
"""
import os
import subprocess

SCRIPT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "netlab.sh")
STATE_ROOT = "/run/shapeform-netlab"


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

    def fault(self, host, kind, percent=None):
        """kind: loss (percent), partition or heal."""
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
