#!/usr/bin/env python3
"""Commands at the supervisor's console and in scripts, with a live swarm of agent processes.

- A shape change mid-run (circle, then `shape square a=5`) re-converges on the new epoch.
- Bad console lines are each rejected with one line naming the problem; the swarm is unaffected.
- Equation and point shapes from the console (arc law): a polar star and a polygon are formed; a
  malformed expression is refused and the swarm keeps its shape.
- A --script with a bad line exits with status 2 and sends nothing.
"""
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402

AGENTS = 10


def messages(stderr):
    """The supervisor's messages in a piece of its stderr: without its log lines ("[supervisor] ...") and
    the human copy of its answers (the metrics object, printed on stderr beside the JSON event)."""
    return [l for l in stderr.splitlines() if not l.startswith(("[supervisor]", "{"))]
SETS = ["--set", "swarm.agents=%d" % AGENTS]


class CommandsTest(harness.SwarmTestCase):

    def converged_swarm(self, scenario="circle"):
        """10 agents on a scenario's shape, started and converged; returns (supervisor, agents)."""
        config = harness.scenario(scenario)
        sup, agents = self.start_commanded_swarm(AGENTS, config, SETS)
        self.assertTrue(sup.wait_converged(60), "the %s scenario converges" % scenario)
        return sup, agents

    def test_shape_change_reconverges(self):
        sup, agents = self.converged_swarm()
        self.assertEqual(sup.metrics()["epoch"], 1)
        self.assertEqual(sup.command("shape square a=5"), 2)
        # The circle of radius ~4 lies 1 to 3 units off the square of half side 5: right after the
        # command the square's error is large, and the old convergence does not count.
        first = sup.metrics()
        self.assertEqual(first["epoch"], 2)
        self.assertFalse(first["converged"], "convergence restarts with the new epoch")
        self.assertTrue(sup.wait_converged(90), "the square converges")
        rows, metrics = sup.status()
        self.assertEqual(sorted(rows), list(range(AGENTS)))
        for i, r in rows.items():
            self.assertTrue(r["alive"], "agent %d" % i)
            self.assertEqual(r["epoch"], 2, "agent %d follows the new epoch" % i)
            self.assertLess(r["shape_error"], 1.0, "agent %d is near the square" % i)
        self.assertEqual(metrics["epoch"], 2)
        self.assertEqual(metrics["agents"], AGENTS)
        self.assertLess(metrics["shape_error_mean"], 0.6, "on the square, not the old circle")
        self.assertLessEqual(metrics["gap_cv"], 0.15)
        self.assert_all_alive(agents)
        sup.send("quit")
        self.assertEqual(sup.wait(20), 0)

    # Each bad line and a fragment of the one-line message that must name its problem.
    BAD_LINES = [
        ("frobnicate", r"unknown command 'frobnicate'"),
        ("shape hexagon r=1", r"unknown shape 'hexagon'"),
        ("shape circle r=4 q=1", r"unknown parameter 'q'"),
        ("shape circle", r"missing parameter r"),
        ("shape ellipse a=4", r"missing parameter b"),
        ("shape circle r=abc", r"not a number: 'abc'"),
        ("shape square a=-5", r"a must be > 0"),
        ("shape circle r=0", r"r must be > 0"),
        ("shape circle r=nan", r"r must be finite"),
        ("shape square a=inf", r"a must be finite"),
        ("gains k1=1e999", r"k1 must be finite"),
        ("gains sigma=-inf", r"sigma must be finite"),
        ("track line from=0,0 vel=0.1,0.1 r=2 ff=maybe", r"ff must be on or off"),
        ("track circle radius=6 period=200", r"missing parameter r"),
        ("track line from=0 vel=1,1 r=2", r"from must be x,y"),
        ("integrator rk4 dt=20", r"dt must be <= 10"),
        ("integrator leapfrog", r"unknown method 'leapfrog'"),
        ("wait agents 2.5", r"N must be an integer"),
        ("max_speed -1", r"must be >= 0"),
        ("shape line m=1 c=\"2", r"unterminated double quote"),
    ]

    def test_bad_console_lines_rejected(self):
        sup, agents = self.converged_swarm()
        for line, message in self.BAD_LINES:
            log_start = len(sup.log())
            out_start = sup.mark()
            sup.send(line)
            metrics = sup.metrics()  # the answer to the next line: the bad one has been handled
            new_err = messages(sup.log()[log_start:])
            self.assertEqual(len(new_err), 1, "one line for %r, got %r" % (line, new_err))
            self.assertRegex(new_err[0], message, "the message for %r" % line)
            self.assertEqual(sup.events("epoch", out_start), [], "nothing published for %r" % line)
            self.assertEqual(metrics["epoch"], 1, "epoch unchanged after %r" % line)
        # The swarm is unaffected: same epoch everywhere, still converged, every process running.
        self.assertTrue(sup.wait_converged(30))
        rows, metrics = sup.status()
        self.assertEqual(sorted(rows), list(range(AGENTS)))
        for i, r in rows.items():
            self.assertEqual((r["alive"], r["epoch"]), (True, 1), "agent %d" % i)
        self.assertEqual(metrics["epoch"], 1)
        self.assert_all_alive(agents + [sup])
        for a in agents:
            self.assertEqual(a.epochs(), [1], "%s followed exactly one command" % a.name)
        sup.send("quit")
        self.assertEqual(sup.wait(20), 0, "bad console lines do not change the exit status")

    def test_equation_shapes_from_the_console(self):
        # The arc law's acceptance criteria at the console of a running swarm (arc law, 10 processes): a
        # polar star and a polygon are formed exactly and evenly; a malformed expression is refused with a
        # message and the swarm keeps the shape it has.
        sup, agents = self.converged_swarm("arc_circle")

        def formed(epoch, size):
            self.assertTrue(sup.wait_converged(90), "epoch %d converges" % epoch)
            m = sup.metrics()
            self.assertEqual(m["epoch"], epoch)
            self.assertLessEqual(m["curve_error_mean"], 1e-3 * size, m)
            self.assertLessEqual(m["arc_gap_cv"], 0.01, m)
            rows, _ = sup.status()
            self.assertTrue(all(r["epoch"] == epoch for r in rows.values()), rows)
            return m

        self.assertEqual(sup.command('shape polar r="4+cos(5*phi)"'), 2)
        star = formed(2, 5.0)

        log_start, out_start = len(sup.log()), sup.mark()
        sup.send('shape polar r="4+cos(5*phi"')  # malformed: unbalanced parenthesis
        after = sup.metrics()
        new_err = messages(sup.log()[log_start:])
        self.assertEqual(len(new_err), 1, new_err)
        self.assertRegex(new_err[0], r"^shape polar: r\(phi\) = '4\+cos\(5\*phi'")
        self.assertEqual(sup.events("epoch", out_start), [])
        self.assertEqual(after["epoch"], 2)
        self.assertTrue(after["converged"])
        self.assertLessEqual(after["curve_error_mean"], 1e-3 * 5.0)
        self.assertAlmostEqual(after["curve_error_mean"], star["curve_error_mean"], delta=1e-3)

        self.assertEqual(sup.command('shape polygon points="-4,-3;4,-3;4,2;0,5;-4,2"'), 3)
        formed(3, 5.0)
        self.assert_all_alive(agents + [sup])
        sup.send("quit")
        self.assertEqual(sup.wait(20), 0)

    def test_bad_script_exits_2_and_sends_nothing(self):
        config = harness.scenario("circle")
        # The two agents hear each other: the domain works, so a command sent would arrive.
        agents = self.start_meshed_agents(2, config, SETS, timeout=30)
        script = self.write("bad_script.txt",
                            "wait agents 2 timeout=10\n"
                            "shape circle r=3\n"       # fine, but must not be sent
                            "start\n"
                            "shape circle r=-3\n"      # line 4: out of range
                            "gains k3=1\n"             # line 5: unknown parameter
                            "wait converged timeout=5\n"
                            "quit\n")
        bad = self.start_supervisor(config, script=script, console=False, name="bad_supervisor")
        self.assertEqual(bad.wait(30), 2, "a bad script line is exit status 2")
        errors = bad.log().splitlines()
        self.assertTrue(any(re.search(r"bad_script\.txt:4: .*r must be > 0", l) for l in errors), errors)
        self.assertTrue(any(re.search(r"bad_script\.txt:5: .*unknown parameter 'k3'", l) for l in errors), errors)
        # Nothing was sent: the agents were running and matched, so any command published would
        # have been adopted (a "command" event); a probe supervisor sees both agents
        # still at epoch 0, holding their starts.
        probe = self.start_supervisor(config, extra=SETS, name="probe_supervisor")
        self.assertTrue(probe.wait_agents(2, 30))
        rows, metrics = probe.status()
        self.assertEqual(sorted(rows), [0, 1])
        for i, r in rows.items():
            self.assertEqual(r["epoch"], 0, "agent %d never got a command" % i)
        for a in agents:
            self.assertEqual(a.epochs(), [], "%s adopted no command" % a.name)
        self.assert_all_alive(agents)


if __name__ == "__main__":
    harness.main()
