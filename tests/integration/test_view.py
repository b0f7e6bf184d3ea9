#!/usr/bin/env python3
"""shapeform_view in a real browser (headless Chromium from Debian, driven by Selenium).

The page exposes what it drew as window.shapeformDrawn = {agents: [{id, x1, x2, state, model_time}],
outline_points, chart_points, chart_model_time (of the charts' newest point), model_time, frames,
mode, replay, zones (keep-out zones drawn), separation_points and separation_run_points (of the
separation chart), separation_limit (its dashed line, null without), safety_shown (the safety line),
blocked_mark, frames (drawn), received, resyncs}, and every alive agent state of every draw as
window.shapeformLog = [[id, model_time, x1, x2], ...]; the test compares that with the supervisor's
recording, never with pixels.

- live: the viewer and the page first, then an 8-agent lockstep swarm with the supervisor recording a
  row at every agent step (supervisor.metrics_rate_hz at the agents' 50 Hz).
  In lockstep the supervisor records every agent's position at the model time of the row (the
  agents' own step), and every drawn agent carries the model time of the state drawn: a drawn agent
  is compared with the recorded row of the same agent at that model time (at least 80 % of the drawn
  states have one; at 10 Hz only one in five did): most lie within 0.05 of it
  (the same state twice), every one within 0.5 (the supervisor's label can be a step off when it heard
  an agent late: see the comment there).
  While the swarm forms: 8 agents drawn alive, the commanded outline drawn, the charts advancing,
  frames as they come. The command carries a small separation and two keep-out zones well
  away from the agents' paths (the safety filter on, the zones never near an agent): both zones drawn,
  the safety line shown, the separation chart with points and its dashed line at the separation.
- replay: the same page on `shapeform_view --replay` of that recording: paused, the agents drawn are
  the recorded rows of the model time shown (within the frame's 1e-4 rounding) and the model time stands
  still, and what the page kept from the stream (a snapshot, then only changes: window.shapeformKept)
  equals a snapshot of GET /frame; a seek (the page's slider) shows the rows of the recording at the
  moment sought; play moves model time on; the recorded command brings its zones back; played at 10x
  from near its start to its end, the page's kept agents, trails (old points dropped), chart and
  command still equal a snapshot.
- screenshot (not in the suite; regenerates docs/figures/view.png): a 12-agent circle forming live.
      python3 tests/integration/test_view.py --bin build/bin --source . --domain 132 ViewTest.test_screenshot
"""
import json
import os
import sys
import threading
import urllib.request
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402
from harness import bin_path, poll, read_csv  # noqa: E402

from selenium import webdriver  # noqa: E402  (Debian: python3-selenium)
from selenium.webdriver.chrome.service import Service  # noqa: E402

AGENTS = 8
TOLERANCE = 0.05
# The frame rounds positions to 1e-4 (view/scene.hpp): a replayed row is drawn within half of that.
ROUNDED = 1e-4
RECORDING_S = 7.0
# A circle and a triangle outside the 10 x 10 start box (the circle of radius 4 forms inside it), and a
# separation far below the agents' spacing: the filter runs on every step, no agent comes near a zone.
MIN_SEPARATION = 0.05
KEEP_OUT = "[{circle: [7.5, 0, 0.5]}, {polygon: [[-7.5, -7.5], [-6.5, -7.5], [-7, -6.5]]}]"
CHROMEDRIVER = "/usr/bin/chromedriver"


class ViewTest(harness.SwarmTestCase):

    def setUp(self):
        super().setUp()
        self.browser = None

    def tearDown(self):
        if self.browser is not None:
            self.browser.quit()
        super().tearDown()

    def launch_browser(self):
        """Starts headless Chromium on a thread of its own (it takes seconds): join the thread returned."""
        def launch():
            options = webdriver.ChromeOptions()
            for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--no-first-run",
                        "--disable-extensions", "--disable-background-networking", "--disable-component-update",
                        "--disable-sync", "--window-size=1240,900",
                        "--user-data-dir=" + os.path.join(self.run_dir, "chromium")):
                options.add_argument(arg)
            service = Service(CHROMEDRIVER, log_path=os.path.join(self.run_dir, "chromedriver.log"))
            self.browser = webdriver.Chrome(service=service, options=options)
        thread = threading.Thread(target=launch)
        thread.start()
        return thread

    def open_page(self, launching, url):
        launching.join(60)
        self.assertIsNotNone(self.browser, "headless Chromium started (see chromedriver.log)")
        self.browser.get(url)

    def drawn(self):
        return self.browser.execute_script("return window.shapeformDrawn")

    def start_view(self, args, name="view"):
        view = self.start(name, [bin_path("shapeform_view"), "--port", "0", "--json"] + list(args))
        return view, view.wait_event("start", 20)["url"]

    def swarm_config(self, extra_sets=()):
        sets = ["agent.sync=lockstep", "supervisor.agent_timeout_s=5"] + list(extra_sets)
        return [a for s in sets for a in ("--set", s)]

    @staticmethod
    def rows_by_state(rows):
        """{agent: {model_time: (x1, x2)}} of positions.csv."""
        out = {}
        for r in rows:
            out.setdefault(int(r["agent"]), {})[r["model_time"]] = (r["x1"], r["x2"])
        return out

    def assert_drawn_match(self, seen, recorded, what, need, share=1.0, bound=TOLERANCE, tolerance=TOLERANCE,
                           with_row=0.0):
        """Of the drawn (id, model_time, x1, x2) with a recorded row of that agent at that model time (at
        least `need` of them, and at least `with_row` of all drawn), at least `share` lie within `tolerance` of
        it and every one within `bound`."""
        matched, close = 0, 0
        for (i, t, x1, x2) in seen:
            i = int(i)
            row = recorded.get(i, {}).get(t)
            if row is None:
                continue
            matched += 1
            off = max(abs(x1 - row[0]), abs(x2 - row[1]))
            close += off <= tolerance
            self.assertLessEqual(off, bound, "%s: agent %d at model time %g drawn at (%g, %g), recorded at (%g, %g)"
                                 % (what, i, t, x1, x2, row[0], row[1]))
        self.assertGreaterEqual(matched, need, "%s: drawn states with a recorded row at their model time" % what)
        self.assertGreaterEqual(matched, with_row * len(seen), "%s: share of the %d drawn states with a recorded row "
                                "at their model time" % (what, len(seen)))
        sys.stderr.write("%s: %d of %d drawn states with a recorded row, %d of them within %g of it\n"
                         % (what, matched, len(seen), close, tolerance))
        self.assertGreaterEqual(close, share * matched, "%s: drawn states within %g of the recorded row" % (what, tolerance))

    def assert_page_keeps_snapshot(self, url, chart_points=1):
        """Paused: what the page built from the snapshot and the deltas since (its agents, trails, centre
        path, chart, command) equals a snapshot of now (GET /frame, view/scene.hpp)."""
        with urllib.request.urlopen(url + "frame", timeout=10) as r:
            snap = json.loads(r.read().decode())
        page = self.browser.execute_script("return window.shapeformKept()")
        self.assertTrue(snap["full"])
        self.assertLessEqual(page["seq"], snap["seq"], "the page is not ahead of the newest frame")
        self.assertGreater(page["seq"], 1, "the page applied deltas after its snapshot")
        columns = snap["agent_columns"]
        self.assertEqual([{c: a.get(c) for c in columns} for a in page["agents"]],
                         [dict(zip(columns, row)) for row in snap["agents"]], "agents")
        trails = {}
        t = snap["trails"]
        for k in range(0, len(t), 4):
            trails.setdefault(str(t[k]), []).append([t[k + 1], t[k + 2], t[k + 3]])
        self.assertEqual({i: p for i, p in page["trails"].items() if p}, trails, "trails")
        self.assertGreater(sum(len(p) for p in trails.values()), AGENTS, "trails with points")
        self.assertEqual(page["centre_path"], snap["centre_path"]["points"], "centre path")
        self.assertEqual(page["chart_points"], snap["chart"]["points"], "chart points")
        self.assertGreaterEqual(len(page["chart_points"]), chart_points, "chart points kept")
        for key in ("outline", "keep_out", "fence", "min_separation"):
            self.assertEqual(page[key], snap[key], key)

    def check_bad_arguments(self):
        """Bad flags and a missing recording: exit 2 at once, naming the flag or the file."""
        missing = os.path.join(self.run_dir, "no_run")
        for args, message in ((["--bind", "localhost:1"], "--bind"), (["--port", "70000"], "--port"),
                              (["--fps", "0"], "--fps"), (["--replay", missing], missing + "/metrics.csv"),
                              (["--frobnicate"], "frobnicate")):
            with self.subTest(args=args):
                r = harness.procs.run([bin_path("shapeform_view")] + args, timeout=10, check=False)
                self.assertEqual(r.returncode, 2, r.stderr)
                self.assertIn(message, r.stderr)

    def test_live_and_replay(self):
        launching = self.launch_browser()  # meanwhile: the bad arguments, the viewer and the swarm
        self.check_bad_arguments()
        config = harness.scenario("circle")
        # The supervisor records a row at every agent step (metrics at the agents' 50 Hz, not 10 Hz): every
        # drawn state can then be compared with its row, however few frames a loaded host lets the page draw.
        extra = self.swarm_config(["safety.min_separation=%g" % MIN_SEPARATION, "safety.keep_out=" + KEEP_OUT,
                                   "supervisor.metrics_rate_hz=50"])
        record = os.path.join(self.run_dir, "record")
        view, url = self.start_view(["--config", config, "--domain", str(self.domain)] + extra)
        recording_from = time.monotonic()
        sup, agents = self.start_commanded_swarm(AGENTS, config, extra=extra, record=record)
        self.open_page(launching, url)

        # -- live: 8 agents alive, the outline, charts that grow, 10 frames/s or more
        d = poll(lambda: (lambda d: d if d and d.get("mode") == "live" and d["epoch"] == 1 and d["chart_model_time"] is not None and
                          sum(a["state"] == "alive" for a in d["agents"]) == AGENTS else None)(self.drawn()),
                 20, "the page to draw %d alive agents following epoch 1" % AGENTS)
        self.assertEqual(sorted(a["id"] for a in d["agents"]), list(range(AGENTS)))
        self.assertGreater(d["outline_points"], 0, "the commanded circle is drawn")
        self.assertEqual(d["zones"], 2, "the command's keep-out zones are drawn")
        self.assertEqual(d["separation_limit"], MIN_SEPARATION, "the separation's dashed line")
        self.assertTrue(d["safety_shown"], "the safety line is shown while the command filters")
        # What the page drew over 3 s: every alive agent state of every draw (window.shapeformLog), and, for
        # comparison, the states seen at this test's polls. Issue 29's "0 of 8 drawn states matched": the
        # supervisor recorded a row at each metrics tick (10 Hz) while the agents step at 50 Hz, so a drawn
        # state had a row only when it was at a recorded step (measured: 127 of 390, a third); the few
        # frames a loaded host's polls caught could hold none. Now a row at every step: all drawn states
        # but those the supervisor labels a step off have one (at least 80 %, asserted below).
        self.browser.execute_script("window.shapeformLog = []")
        at_reset = self.drawn()["frames"]
        first = poll(lambda: (lambda d: d if d["frames"] > at_reset else None)(self.drawn()), 5,
                     "a frame drawn after the log was emptied")
        polled = set()
        t0 = time.monotonic()
        while time.monotonic() - t0 < 3.0:
            d = self.drawn()
            polled |= {(a["id"], a["model_time"], a["x1"], a["x2"]) for a in d["agents"] if a["state"] == "alive"}
            time.sleep(0.05)
        seen = {tuple(e) for e in self.browser.execute_script(
            "const l = window.shapeformLog; window.shapeformLog = []; return l;")}
        self.assertLessEqual(polled, seen, "every state the polls saw is in the page's log of states drawn")
        last = self.drawn()
        elapsed = time.monotonic() - t0
        # The charts advance: their newest point is later (a long series is thinned, so its count may drop).
        self.assertGreater(last["chart_points"], 0, "chart points drawn")
        self.assertGreater(last["chart_model_time"], first["chart_model_time"], "the charts advance")
        self.assertGreater(last["separation_points"], 0, "the snapshot's smallest separation charted")
        self.assertGreater(last["separation_run_points"], 0, "the run's smallest separation charted")
        self.assertGreater(last["model_time"], first["model_time"], "model time advances on the page")
        # The stream goes on (its rate is measured by scripts/bench_page.py, not asserted here: a loaded
        # host may slow the page, and a page that fell 32 frames behind correctly starts anew from a
        # snapshot, which the replay's check below compares with the server's).
        self.assertGreater(last["frames"] - first["frames"], 5, "frames drawn in %.1f s" % elapsed)
        self.assertGreater(last["received"] - first["received"], 5, "frames received in %.1f s" % elapsed)
        self.assertEqual({s[0] for s in seen}, set(range(AGENTS)))

        # A recording of 7 s at least: the replay's last check plays it past trail_s (5 s) after its start.
        time.sleep(max(0.0, RECORDING_S - (time.monotonic() - recording_from)))
        sup.stop()  # flushes the recording
        harness.procs.stop_all(agents, grace=5.0)
        recorded = self.rows_by_state(read_csv(os.path.join(record, "positions.csv"), numeric=True))
        # The supervisor labels a row with the slowest agent's model time and takes an agent one step
        # ahead at its previous position; an agent it last heard two steps ahead (the slowest one's newest
        # sample still in flight) is then recorded a step off, and one step of the paper's law moves an
        # agent by up to about 0.1. So most drawn states, not all, equal their row; every one lies within
        # 0.5 of it (a wrong agent, axis or scale would be off by a neighbour's distance, about 2).
        self.assert_drawn_match(seen, recorded, "live", need=AGENTS, share=0.7, bound=0.5, with_row=0.8)
        polled_matched = sum(recorded.get(i, {}).get(t) is not None for (i, t, _, _) in polled)
        sys.stderr.write("live, as polled: %d of %d states with a recorded row\n" % (polled_matched, len(polled)))
        view.stop()

        # -- replay of that recording, in the same page
        view, url = self.start_view(["--replay", self.run_dir], name="replay")
        self.browser.get(url)
        poll(lambda: (lambda d: d and d.get("mode") == "replay" and len(d["agents"]) == AGENTS)(self.drawn()), 15,
             "the replay to draw %d agents" % AGENTS)
        # Paused once the agents have moved (the recording starts before the command: until then every
        # trail is one point, and a pause that early leaves the trails' check nothing to compare).
        poll(lambda: sum(len(p) for p in self.browser.execute_script("return window.shapeformKept()")["trails"].values())
             > AGENTS, 15, "the replay to draw trails of more than one point")
        self.browser.find_element("id", "play").click()  # pause
        d = poll(lambda: (lambda d: d if d["replay"] and not d["replay"]["playing"] else None)(self.drawn()), 5,
                 "the replay to pause")
        time.sleep(1.0)  # paused: nothing may move meanwhile
        d2 = self.drawn()
        self.assertGreater(d2["frames"], d["frames"], "frames keep coming while paused")
        self.assertEqual(d2["model_time"], d["model_time"], "paused: model time stands still")
        self.assertEqual(d2["replay"]["position_s"], d["replay"]["position_s"])
        alive = [a for a in d2["agents"] if a["state"] == "alive"]
        self.assertEqual(len(alive), AGENTS)
        for a in alive:
            self.assertEqual(a["model_time"], d2["model_time"], "agents drawn at the model time shown")
        self.assert_drawn_match({(a["id"], a["model_time"], a["x1"], a["x2"]) for a in alive}, recorded,
                                "replay (paused)", need=AGENTS, bound=ROUNDED, tolerance=ROUNDED)
        self.assert_page_keeps_snapshot(url)

        # Seek with the page's slider to 1 s from the start: the rows of the last metrics tick by then.
        metrics = read_csv(os.path.join(record, "metrics.csv"), numeric=True)
        start = min(r["wall_s"] for r in metrics)
        target = 1.0
        expect_t = max(r["model_time"] for r in metrics if r["wall_s"] <= start + target + 1e-9)
        self.browser.execute_script(
            "const s = document.getElementById('seek'); s.value = arguments[0];"
            "s.dispatchEvent(new Event('change'));", target)
        d = poll(lambda: (lambda d: d if abs(d["replay"]["position_s"] - target) < 0.02 else None)(self.drawn()), 5,
                 "the replay to show %g s" % target)
        self.assertEqual(d["model_time"], expect_t)
        alive = [a for a in d["agents"] if a["state"] == "alive"]
        self.assert_drawn_match({(a["id"], a["model_time"], a["x1"], a["x2"]) for a in alive}, recorded,
                                "replay (after the seek)", need=len(alive), bound=ROUNDED, tolerance=ROUNDED)
        self.assertTrue(all(a["model_time"] == expect_t for a in alive))

        self.browser.find_element("id", "play").click()  # play
        poll(lambda: self.drawn()["model_time"] > expect_t, 5, "model time to advance after play")
        # Once the replay reaches the recorded command (commands.csv), its shape is drawn.
        commanded = min(float(r["wall_s"]) for r in read_csv(os.path.join(record, "commands.csv")))
        self.browser.execute_script(
            "const s = document.getElementById('seek'); s.value = arguments[0];"
            "s.dispatchEvent(new Event('change'));", commanded - start + 0.5)
        poll(lambda: (lambda d: d["epoch"] == 1 and d["outline_points"] > 0 and d["zones"] == 2)(self.drawn()), 5,
             "the replay to draw the recorded command and its zones")
        # Back to 0.2 s (a full frame), then played at 10x to the end: the page, fed only deltas since, has
        # dropped the trail points older than trail_s (5 s) as the server did, appended the chart's points,
        # and holds what a snapshot of the end says.
        self.browser.execute_script(
            "const s = document.getElementById('seek'); s.value = arguments[0];"
            "s.dispatchEvent(new Event('change'));", 0.2)
        poll(lambda: self.drawn()["replay"]["position_s"] < 1.0, 5, "the replay back near its start")
        self.browser.execute_script(
            "const s = document.getElementById('speed'); s.value = '10'; s.dispatchEvent(new Event('change'));")
        d = poll(lambda: (lambda d: d if not d["replay"]["playing"] else None)(self.drawn()), 15,
                 "the replay to play to its end")
        self.assertGreater(d["replay"]["position_s"], 5.5, "played past trail_s after the seek back")
        self.assert_page_keeps_snapshot(url, chart_points=5)

    def test_screenshot(self):
        """Regenerates docs/figures/view.png: a 12-agent circle forming live."""
        config = harness.scenario("circle")
        launching = self.launch_browser()
        view, url = self.start_view(["--config", config, "--domain", str(self.domain)])
        self.start_commanded_swarm(12, config)
        self.open_page(launching, url)
        poll(lambda: (lambda d: d and d["chart_points"] > 40 and
                      sum(a["state"] == "alive" for a in d["agents"]) == 12)(self.drawn()), 30,
             "12 agents and some history drawn")
        out = os.path.join(harness.CONFIG["source"], "docs", "figures", "view.png")
        self.browser.set_window_size(1240, 820)
        self.browser.save_screenshot(out)
        sys.stderr.write("screenshot: %s\n" % out)


if __name__ == "__main__":
    harness.main()
