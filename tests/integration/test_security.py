#!/usr/bin/env python3
"""DDS Security on real processes: a secured swarm forms the circle while rogue participants try to
read it, feed it and command it; a capture on loopback finds none of its payloads in clear.

One keystore (scripts/make_keystore.sh) in the test's run folder: its two authorities were made 10 days
ago (faketime) with one enclave, agent_21, whose certificate expired 5 days ago; then the supervisor,
the viewer, agent_0..7 and the spare identities agent_20 and agent_22, valid now. A second keystore has
its own authorities. The swarm: a supervisor and 8 agents, each with its role's enclave. Beside it,
on the domain 2 above, a plain control (an agent, a command publisher and two readers) proves that
the capture sees what is not encrypted. The rogues, all running at once:
- a plain (unsecured) reader of the state topic: reads the plain rogue below but nothing of the swarm,
  while a secured viewer reads the swarm at once;
- a plain participant publishing agent 50's state, another publishing a line command at epoch 5:
  every secured process refuses them (its "refused" events), no agent hears agent 50, the supervisor
  never lists it, and no agent follows the line;
- a participant with agent permissions (agent_20) that writes a ShapeCommand: refused by its own
  access control (exit 2 naming the permission), no agent follows it;
- a supervisor certified by the other authority, an agent whose certificate expired (run 7 days in the
  past, so that its own checks pass), and a supervisor whose permissions document it signed itself
  (which passes its own check: it names the identity authority as its permissions authority): each
  is refused at join; for every pair of it and a swarm process one of the two reports the refusal,
  and none of its samples is used.
- the same expired enclave started in the present: exit 2 naming its certificate.
The swarm reaches the simulator's plateau; the capture of the swarm's ports holds neither the shape
kind text nor any agent position as 8 plain bytes, while the control's ports hold both.
"""
import os
import shutil
import struct
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402
import netlab  # noqa: E402
from harness import poll  # noqa: E402

AGENTS = 8
# Ports of a domain (RTPS: 7400 + 250 d, its participant slots and multicast within the next 250).
PORTS = 250


def port_range(domain):
    return 7400 + PORTS * domain, min(65535, 7400 + PORTS * domain + PORTS - 1)


def in_domain(packet, domain):
    lo, hi = port_range(domain)
    return lo <= packet.dport <= hi


class SecurityTest(harness.SwarmTestCase):

    def setUp(self):
        super().setUp()
        self.control = self.domain + 2
        source = harness.CONFIG["source"]
        make = os.path.join(source, "scripts", "make_keystore.sh")
        self.ks = os.path.join(self.run_dir, "keystore")
        self.other = os.path.join(self.run_dir, "other")
        faked = ["env", "FAKETIME_DONT_FAKE_MONOTONIC=1", "faketime", "-f"]
        harness.procs.run(faked + ["-10d", make, self.ks, "--enclave", "agent_21", "--days", "5"], timeout=60)
        harness.procs.run([make, self.ks, "--agents", str(AGENTS)], timeout=60)
        harness.procs.run([make, self.ks, "--enclave", "agent_20", "--enclave", "agent_22"], timeout=60)
        harness.procs.run([make, self.other, "--enclave", "supervisor"], timeout=60)
        self.self_signed_permissions("agent_22")
        # Run 7 days in the past: the library itself (the faketime wrapper would stay the parent, and a
        # SIGTERM to it alone would leave the program running); monotonic clocks stay true.
        self.past = ["env", "LD_PRELOAD=/usr/lib/x86_64-linux-gnu/faketime/libfaketimeMT.so.1", "FAKETIME=-7d",
                     "FAKETIME_DONT_FAKE_MONOTONIC=1"]

    def self_signed_permissions(self, name):
        """Enclave `name` gets the supervisor's grants, signed with its own key; it calls the identity
        authority its permissions authority, so its own checks pass and only its peers can tell."""
        e = os.path.join(self.ks, "enclaves", name)
        with open(os.path.join(self.ks, "enclaves", "supervisor", "permissions.xml")) as f:
            grants = f.read().replace("CN=supervisor", "CN=" + name).replace('"supervisor"', '"%s"' % name)
        with open(os.path.join(e, "permissions.xml"), "w") as f:
            f.write(grants)
        for doc, out in ((os.path.join(e, "permissions.xml"), "permissions.p7s"),
                         (os.path.join(self.ks, "enclaves", "governance.xml"), "governance.p7s")):
            harness.procs.run(["openssl", "smime", "-sign", "-in", doc, "-text", "-out", os.path.join(e, out),
                               "-signer", os.path.join(e, "cert.pem"), "-inkey", os.path.join(e, "key.pem")])
        shutil.copy(os.path.join(e, "identity_ca.cert.pem"), os.path.join(e, "permissions_ca.cert.pem"))

    def secured(self, identity=None, keystore=None):
        s = ["--set", "security.enabled=true", "--set", "security.keystore=" + (keystore or self.ks)]
        return s + (["--set", "security.identity=" + identity] if identity else [])

    def rogue(self, name, args, domain=None, prefix=()):
        argv = list(prefix) + [harness.bin_path("shapeform_rogue_publisher"), "--domain",
                               str(self.domain if domain is None else domain)] + list(args)
        return self.start(name, argv)

    def echo(self, name, topic, count, timeout, extra=(), domain=None):
        return self.start(name, [harness.bin_path("shapeform_echo"), topic, "--domain",
                                 str(self.domain if domain is None else domain), "--count", str(count),
                                 "--timeout", str(timeout)] + list(extra))

    def test_secured_swarm_refuses_rogues(self):
        circle = harness.scenario("circle")
        sim = self.run_sim(circle, ["--steps", "500", "--agents", str(AGENTS), "--seed", "1"])
        sets = ["--set", "swarm.agents=%d" % AGENTS, "--set", "agent.status_rate_hz=5"]
        bpf = "%s and (portrange %d-%d or portrange %d-%d)" % ((netlab.RTPS_FILTER,) + port_range(self.domain) +
                                                               port_range(self.control))
        cap = netlab.Capture(None, "lo", os.path.join(self.run_dir, "lo.pcap"), bpf).start()
        try:
            sup = self.start_supervisor(circle, extra=sets + self.secured())
            agents = self.start_agents(AGENTS, circle, seed=1, extra=sets + self.secured())
            # The plain control on its own domain: an agent and a command, each with a reader (8 participant
            # slots: on domain 232 the ports of slots past 62 would pass 65535).
            slots = ["--set", "transport.max_participants=8"]
            control_agent = self.start_agent(0, circle, domain=self.control, seed=1, extra=sets + slots,
                                             name="control_agent")
            self.echo("control_state", "shapeform/state", 100000, 0, domain=self.control, extra=slots)
            # (Many samples: a busy host's capture may miss a datagram, never all of them.)
            self.rogue("control_command", ["--topic", "command", "--field", "shape_kind=circle", "--count", "1000",
                                           "--rate", "20", "--stay"] + slots, domain=self.control)
            self.echo("control_command_reader", "shapeform/command", 100000, 0, domain=self.control, extra=slots)

            self.assertTrue(sup.wait_agents(AGENTS, 60), "the supervisor hears the %d secured agents" % AGENTS)
            poll(lambda: all(a.hears(AGENTS - 1) for a in agents), 30, "every agent to hear the 7 others")

            # The rogues, all at once.
            line = ["--topic", "command", "--field", "epoch=5", "--field", "shape_kind=line", "--stay"]
            state = lambda i: ["--topic", "state", "--field", "id=%d" % i, "--count", "200", "--rate", "20", "--stay"]
            plain_reader = self.echo("plain_reader", "shapeform/state", 100000, 0)
            viewer = self.echo("viewer_reader", "shapeform/state", 1, 30, extra=self.secured())
            plain_state = self.rogue("plain_state", state(50))
            plain_command = self.rogue("plain_command", line)
            other_ca = self.rogue("other_authority", line + self.secured("supervisor", self.other))
            expired = self.rogue("expired", state(21) + self.secured("agent_21"), prefix=self.past)
            self_signed = self.rogue("self_signed", line + self.secured("agent_22"))
            agent_perm = harness.procs.run([harness.bin_path("shapeform_rogue_publisher"), "--domain", str(self.domain),
                                            "--topic", "command", "--field", "epoch=5"] + self.secured("agent_20"),
                                           timeout=60, check=False)
            expired_now = harness.procs.run([harness.bin_path("shapeform_agent"), "--id", "21", "--domain",
                                             str(self.domain)] + self.secured("agent_21"), timeout=60, check=False)

            self.assertEqual(sup.command("start"), 1)
            self.assertTrue(sup.wait_converged(90), "the secured swarm converges")
            m = sup.metrics()
            self.assertLessEqual(abs(m["shape_error_mean"] - sim["shape_error_mean"]), 0.02,
                                 "the plateau: processes %.4f, simulator %.4f" % (m["shape_error_mean"],
                                                                                 sim["shape_error_mean"]))
            self.assertLessEqual(m["gap_cv"], 0.10)

            # Readers: the plain one read the plain agent 50 and nothing of the swarm; the secured viewer read it.
            self.assertEqual(viewer.wait(30), 0, "the secured viewer reads a state")
            ids = {e["data"]["id"] for e in plain_reader.events("sample")}
            self.assertIn(50, ids, "the plain reader works: it reads the plain rogue")
            self.assertEqual(ids & set(range(AGENTS)), set(), "swarm states read by the plain reader")
            # The agent-permission writer and the expired certificate: refused at start-up, exit 2, named.
            self.assertEqual(agent_perm.returncode, 2, agent_perm.stderr)
            self.assertIn("agent_20 (", agent_perm.stderr)
            self.assertIn("do not allow publishing shapeform/command", agent_perm.stderr)
            self.assertEqual(expired_now.returncode, 2, expired_now.stderr)
            self.assertIn(os.path.join("enclaves", "agent_21", "cert.pem") + " expired on", expired_now.stderr)

            # Who is who: the rogues' GUID prefixes (their "sent" events; the state rogues send for 10 s), the
            # supervisor's (the issuer of epoch 1) and the agents' (the refusals of the plain participants).
            rogues = {"plain_state": plain_state, "plain_command": plain_command, "other_authority": other_ca,
                      "expired": expired, "self_signed": self_signed}
            source = {k: r.wait_event("sent", 30, what="%s to publish" % k)["source"] for k, r in rogues.items()}
            issuer = agents[0].events("command")[-1]["issuer"]
            swarm = [sup] + agents
            poll(lambda: all({source["plain_state"], source["plain_command"]} <=
                             {e["participant"] for e in p.events("refused")} for p in swarm), 20,
                 "every secured process to report the two plain participants refused")
            guid = {p.name: {e["by"] for e in p.events("refused")} for p in swarm}
            for p in swarm:
                self.assertEqual(len(guid[p.name]), 1, "%s reports one identity of its own" % p.name)
            guid = {k: v.pop() for k, v in guid.items()}
            self.assertEqual(guid["supervisor"], issuer)

            # Refused at join: for each pair (rogue, swarm process) one side reports refusing the other.
            for k in ("other_authority", "expired", "self_signed"):
                def covered(k=k):
                    by_rogue = {e["participant"] for e in rogues[k].events("refused")}
                    return [p.name for p in swarm if guid[p.name] not in by_rogue and
                            source[k] not in {e["participant"] for e in p.events("refused")}]
                poll(lambda k=k: not covered(k), 30, "every pair of %s and a swarm process refused" % k)

            # None of their samples was used: every agent followed only epoch 1 of the supervisor, heard its
            # 7 peers and no more, and the supervisor lists agents 0..7 only.
            for a in agents:
                self.assertEqual([(e["epoch"], e["issuer"]) for e in a.events("command")], [(1, issuer)], a.name)
                self.assertEqual(max(e["neighbours_heard"] for e in a.events("status")), AGENTS - 1, a.name)
            rows, _ = sup.status()
            self.assertEqual(sorted(rows), list(range(AGENTS)))
            self.assertEqual(sup.events("rejected"), [], "no rogue command or state reached the supervisor")
            self.assertEqual(sup.events("in_force"), [], "no other command was ever in force")
            positions = {struct.pack("<d", v) for a in agents for e in a.events("status") for v in (e["x"], e["y"])}
            control_positions = {struct.pack("<d", v) for e in control_agent.events("status") for v in (e["x"], e["y"])}
            self.assert_all_alive([sup] + agents)
        finally:
            cap.stop()

        packets = cap.rtps()
        secured = [p.payload for p in packets if in_domain(p, self.domain)]
        control = [p.payload for p in packets if in_domain(p, self.control)]
        self.assertGreater(len(secured), 1000, "the capture saw the secured swarm's traffic")
        self.assertTrue(any(b"circle" in p for p in control), "the control's command is plain text")
        self.assertTrue(any(x in p for p in control for x in control_positions),
                        "the control agent's positions are plain bytes")
        self.assertEqual([p[:64] for p in secured if b"circle" in p], [],
                         "the shape kind text in the secured traffic")
        leaked = [x for x in positions if any(x in p for p in secured)]
        self.assertEqual(leaked, [], "agent positions as plain bytes in the secured traffic (of %d)" % len(positions))
        print("secured swarm: %d datagrams captured, none with the shape kind or any of %d positions; control: %d "
              "datagrams, plain" % (len(secured), len(positions), len(control)), flush=True)


if __name__ == "__main__":
    harness.main()
