#!/usr/bin/env python3
"""A verdict that tells the truth: "converged" means on the commanded shape, steady, not growing, with
every agent on the command judged.

- A 20-wide start (`swarm.init_half_width: 20`): most agents escape the circle's reach (the paper's
  far field) while the swarm evens out; the launcher exits 3, its summary says not converged, off the
  shape. (It used to exit 0 at a mean shape error of 32.)
- Reshaping a converged circle of radius 4 to `shape circle r=28` leaves the swarm 24 units inside the
  new circle, steady for a while: not converged (it used to be called converged within a second). The
  paper's circle converges first, as ever.
- Eight agents on the paper's line, evenly spaced on it and still spreading: not converged, growing.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402


class VerdictTest(harness.SwarmTestCase):

    def test_wide_start_launcher_exit_3(self):
        build = os.path.dirname(harness.CONFIG["bin"])
        argv = ["bash", os.path.join(harness.CONFIG["source"], "scripts", "launch_swarm.sh"), "--build", build,
                "--runs", os.path.join(self.run_dir, "runs"), "--domain", str(self.domain), "-n", "12",
                "--scenario", "circle", "--set", "swarm.init_half_width=20", "--timeout", "15", "--json"]
        p = self.start("launcher", argv)
        self.assertEqual(p.wait(120), 3, "the launcher's exit status: not converged")
        s = harness.summary(p.out())
        self.assertEqual((s["converged"], s["verdict"], s["exit_status"], s["agents"]), (False, "off the shape", 3, 12))
        self.assertGreater(s["shape_error_mean"], 5.0)

    def test_reshape_far_is_not_converged(self):
        sup, agents = self.start_commanded_swarm(10, harness.scenario("circle"), ["--set", "swarm.agents=10"])
        self.assertTrue(sup.wait_converged(60), "the paper's circle converges")
        self.assertEqual(sup.metrics()["verdict"], "converged")
        self.assertEqual(sup.command("shape circle r=28"), 2)
        self.assertFalse(sup.wait_converged(4), "24 units inside the new circle is not converged")
        m = sup.metrics()
        self.assertEqual((m["epoch"], m["converged"], m["verdict"]), (2, False, "off the shape"))
        self.assertGreater(m["shape_error_mean"], 0.2 * 28)
        self.assert_all_alive(agents)
        sup.send("quit")
        self.assertEqual(sup.wait(20), 3, "a wait converged timed out: exit status 3")

    def test_growing_line_is_not_converged(self):
        config = harness.scenario("line")
        sup, agents = self.start_commanded_swarm(8, config, ["--set", "swarm.agents=8"])
        self.assertFalse(sup.wait_converged(10), "a line that keeps growing is not converged")
        first = sup.metrics()
        self.assertEqual((first["converged"], first["verdict"]), (False, "growing"))
        self.assertLess(first["shape_error_mean"], 0.05, "every agent is on the line")
        self.assertLess(first["gap_cv"], 0.15, "evenly spaced")
        harness.poll(lambda: sup.metrics()["extent"] > first["extent"] + 5, 20, "the line to keep growing")
        self.assertFalse(sup.metrics()["converged"])
        self.assert_all_alive(agents)
        sup.send("quit")
        self.assertEqual(sup.wait(20), 3, "a wait converged timed out: exit status 3")


if __name__ == "__main__":
    harness.main()
