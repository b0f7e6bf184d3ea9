#!/usr/bin/env python3
"""The lan transport profile on real interfaces: every process on a test host (a network namespace,
scripts/netlab.sh) bound to its eth0 address, while tcpdump listens on every host's eth1, on the switch's
br1 (the "other" network, where none of our datagrams may appear) and on the switch's br0 (the test LAN,
where the test reads what went unicast and what went multicast). Every capture runs before the first
process starts and is proven live by a probe datagram it must see, so a dead capture cannot pass a test.

One swarm per variant: multicast discovery; unicast peers on a LAN that drops multicast; state data on
multicast.

Run directly (root): test_lan_profile.py --bin build/bin --source . --domain 4 [unittest args]
"""
import contextlib
import ipaddress
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402
from harness import netlab, poll  # noqa: E402

AGENT_HOSTS = ("h1", "h2", "h3")  # 2 agents each; the supervisor on h4
PER_HOST = 2
GROUP = "239.255.0.1"


class LanProfileTest(harness.LanSwarmTestCase):

    def setUp(self):
        super().setUp()
        self.peers = None  # hosts listed in transport.peers (None: multicast discovery)
        self.multicast_data = False
        self.discovery_port = 7400 + 250 * self.domain  # the domain's discovery multicast port
        self.data_port = self.discovery_port + 1        # its user-data multicast port

    def on_host(self, host, argv):
        if host is None:
            raise ValueError("every process runs on a test host")
        return self.lab.on(host, list(argv) + self.lab.lan_sets(host, self.peers, self.multicast_data))

    @contextlib.contextmanager
    def captures(self):
        """(captures of every host's eth1 and the switch's br1, capture of the switch's br0), each live."""
        with contextlib.ExitStack() as stack:
            def cap(host, iface):
                path = os.path.join(self.run_dir, "%s-%s.pcap" % (host, iface))
                return stack.enter_context(self.lab.capture(host, iface, path))
            other = [cap(h, "eth1") for h in self.lab.hosts] + [cap("sw", "br1")]
            lan = cap("sw", "br0")
            self.lab.probe("h1", "eth1", other)
            self.lab.probe("h1", "eth0", lan)
            yield other, lan

    def start_swarm(self):
        """The supervisor on h4 and agents 0..5 on h1..h3 (arc circle, seed 1): every process hears every
        other, then the swarm is commanded and converges."""
        config = harness.scenario("arc_circle")
        extra = ["--set", "swarm.agents=%d" % (PER_HOST * len(AGENT_HOSTS))]
        sup = self.start_supervisor(config, extra=extra, host="h4")
        agents = [self.start_agent(k * PER_HOST + j, config, seed=1, extra=extra, host=host)
                  for k, host in enumerate(AGENT_HOSTS) for j in range(PER_HOST)]
        n = len(agents)
        self.assertTrue(sup.wait_agents(n, 30), "the supervisor on h4 hears all %d agents" % n)
        poll(lambda: all(a.hears(n - 1) for a in agents), 30, "every agent to hear the %d others" % (n - 1))
        self.assertEqual(sup.command("start"), 1)
        self.assertTrue(sup.wait_converged(60), "the swarm converges")
        self.assert_all_alive(agents + [sup])
        return sup, agents

    def assert_nothing_on(self, captures):
        for cap in captures:
            self.assertTrue(cap.running(), "%r still runs" % cap)
            seen = cap.rtps()
            self.assertEqual(["%s:%d > %s:%d" % (p.src, p.sport, p.dst, p.dport) for p in seen[:5]], [],
                             "%d RTPS datagrams on %r" % (len(seen), cap))

    def lan_packets(self, lan):
        """The RTPS datagrams on the test LAN; each from a host's LAN address, to one or to the group."""
        packets = lan.rtps()
        subnet = ipaddress.ip_network(self.lab.subnet + ".0/24")
        strays = ["%s > %s" % (p.src, p.dst) for p in packets
                  if ipaddress.ip_address(p.src) not in subnet or
                  (ipaddress.ip_address(p.dst) not in subnet and p.dst != GROUP)]
        self.assertEqual(strays[:5], [], "RTPS datagrams on the LAN from or to another network")
        return packets

    def senders(self, packets, dst, dport):
        return {p.src for p in packets if p.dst == dst and p.dport == dport}

    def addresses(self, hosts):
        return {self.lab.address(h) for h in hosts}

    def multicast_drops(self, host):
        """Packets dropped by the nomulticast rules of `host`: {"in": n, "out": n}."""
        out = subprocess.run(self.lab.on(host, ["iptables", "-nvxL", "SHAPEFORM"]), stdout=subprocess.PIPE,
                             text=True, check=True).stdout
        drops = {}
        for line in out.splitlines():
            f = line.split()
            if len(f) >= 9 and f[2] == "DROP" and f[-1] == "224.0.0.0/4":
                drops["in" if f[5] == "eth0" else "out"] = int(f[0])
        self.assertEqual(set(drops), {"in", "out"}, "the nomulticast rules of %s:\n%s" % (host, out))
        return drops

    # ------------------------------------------------------------------------------------------------

    def test_multicast_discovery(self):
        # No peers: discovery on the group, on eth0 only; state data unicast.
        with self.captures() as (other, lan):
            self.start_swarm()
            packets = self.lan_packets(lan)
            self.assertEqual(self.senders(packets, GROUP, self.discovery_port), self.addresses(self.lab.hosts),
                             "every host announces its participants on the discovery group")
            self.assertEqual(self.senders(packets, GROUP, self.data_port), set(), "no state data on the group")
            self.assert_nothing_on(other)

    def test_unicast_peers_without_multicast(self):
        # Every host drops multicast in and out of eth0: the peers variant still discovers everyone, and
        # tries no multicast at all (the drop rules count nothing until a probe of ours).
        for h in self.lab.hosts:
            self.lab.fault(h, "nomulticast")
        self.peers = self.lab.hosts
        with self.captures() as (other, lan):
            self.start_swarm()
            packets = self.lan_packets(lan)
            self.assertEqual({p.src for p in packets}, self.addresses(self.lab.hosts),
                             "every host's processes talk on the LAN")
            self.assertEqual([p for p in packets if p.dst == GROUP], [])
            self.assertEqual({h: self.multicast_drops(h) for h in self.lab.hosts},
                             {h: {"in": 0, "out": 0} for h in self.lab.hosts},
                             "multicast datagrams dropped on the hosts")
            self.assert_nothing_on(other)
        # The rules do drop multicast (and count it): a datagram to the group from h1 never reaches the LAN.
        with self.lab.capture("sw", "br0", os.path.join(self.run_dir, "sw-br0-probe.pcap")) as lan:
            self.lab.probe("h1", "eth0", lan)
            self.lab.probe("h1", "eth0", [], dst=GROUP)
            live = self.lab.probe("h1", "eth0", lan)  # sent after the group one: that one had its chance
            self.assertEqual(self.multicast_drops("h1")["out"], 1)
            self.assertEqual([p.dst for p in lan.packets() if p.dst == GROUP], [], live)

    def test_multicast_data(self):
        # transport.multicast_data on lan: every agent host sends state to the group's data port, on eth0
        # only; discovery stays on the discovery port.
        self.multicast_data = True
        with self.captures() as (other, lan):
            self.start_swarm()
            packets = self.lan_packets(lan)
            self.assertEqual(self.senders(packets, GROUP, self.data_port), self.addresses(AGENT_HOSTS),
                             "every agent host sends its state to the group")
            for h in AGENT_HOSTS:
                sent = sum(1 for p in packets if p.src == self.lab.address(h) and p.dport == self.data_port)
                self.assertGreaterEqual(sent, 20, "state datagrams from %s to the group" % h)
            self.assertEqual(self.senders(packets, GROUP, self.discovery_port), self.addresses(self.lab.hosts))
            self.assert_nothing_on(other)


if __name__ == "__main__":
    harness.main()
