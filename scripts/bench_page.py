#!/usr/bin/python3
"""Measures the viewer's page at N agents in a real browser (headless Chromium from Debian, Selenium).

For each N: the simulator records a run of N agents (`shapeform_sim --record`, the circle scenario),
its rows are retimed to one step every --period seconds (the simulator stamps them with its own, much
faster, compute time), `shapeform_view --replay` plays it, and the page is opened in headless Chromium.
Once the page draws N agents, over --seconds it measures, in the browser: frames received per second
(EventSource messages), frames drawn per second (window.shapeformDrawn.frames), characters per frame
(the events' data, what the wire carries less the SSE framing); and the view's CPU (% of one core,
utime + stime from /proc). Prints a Markdown table (and with --json one JSON line per N).

  scripts/bench_page.py [--build build] [--view PATH] [--agents 12,100,1000] [--seconds 10]
                        [--steps 400] [--period 0.1] [--work DIR] [--json] [--save LABEL [--commit C]]

--view runs another shapeform_view binary (an older build, for a before/after comparison). --save LABEL
stores the rows under LABEL in docs/figures/page_results.json, which bench/bench_report.py renders into
docs/BENCHMARKS.md ("The page at 12, 100 and 1000 agents"; `bench/bench_report.py --write-docs`).
"""
import argparse
import csv
import datetime
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

sys.dont_write_bytecode = True  # no __pycache__ in scripts/
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CHROMEDRIVER = "/usr/bin/chromedriver"
sys.path.insert(0, os.path.join(ROOT, "scripts", "lib"))
import shapeform_procs as procs  # noqa: E402

# Counts every EventSource message and its characters, whatever the page's own code does (so an older
# page is measured the same way).
COUNTER = """
window.__bench = {received: 0, chars: 0};
const Original = window.EventSource;
window.EventSource = function (url, options) {
  const es = new Original(url, options);
  es.addEventListener("message", (e) => { window.__bench.received += 1; window.__bench.chars += e.data.length; });
  return es;
};
window.EventSource.prototype = Original.prototype;
"""


def retime(src, period):
    """Rewrites the recording's wall_s to step * period (metrics rows are one per step, in order)."""
    steps = {}
    with open(os.path.join(src, "metrics.csv"), newline="") as f:
        for k, row in enumerate(csv.DictReader(f)):
            steps.setdefault(row["wall_s"], k)
    for name in ("metrics.csv", "positions.csv", "centre.csv", "commands.csv"):
        path = os.path.join(src, name)
        if not os.path.exists(path):
            continue
        with open(path, newline="") as f:
            rows = list(csv.reader(f))
        head = rows[0]
        w = head.index("wall_s")
        s = head.index("step") if "step" in head else None
        for r in rows[1:]:
            k = int(r[s]) if s is not None and r[s] != "" else steps.get(r[w], 0)
            r[w] = repr(k * period)
        with open(path, "w", newline="") as f:
            csv.writer(f, lineterminator="\n").writerows(rows)




def browser(work):
    from selenium import webdriver  # Debian: python3-selenium
    from selenium.webdriver.chrome.service import Service
    options = webdriver.ChromeOptions()
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--no-first-run",
                "--disable-extensions", "--disable-background-networking", "--disable-component-update",
                "--disable-sync", "--window-size=1240,900", "--user-data-dir=" + os.path.join(work, "chromium")):
        options.add_argument(arg)
    b = webdriver.Chrome(service=Service(CHROMEDRIVER, log_path=os.path.join(work, "chromedriver.log")), options=options)
    b.execute_cdp_cmd("Page.addScriptToEvaluateOnNewDocument", {"source": COUNTER})
    return b


def measure(args, b, n, work):
    rec = os.path.join(work, "rec%d" % n)
    shutil.rmtree(rec, ignore_errors=True)
    subprocess.run([os.path.join(args.build, "bin", "shapeform_sim"), "--config",
                    os.path.join(ROOT, "config", "scenarios", "circle.yaml"), "--agents", str(n), "--steps", str(args.steps),
                    "--record", rec], check=True, stdout=subprocess.DEVNULL)
    retime(rec, args.period)
    view = subprocess.Popen([args.view, "--replay", rec, "--port", "0", "--json"], stdout=subprocess.PIPE,
                            stderr=open(os.path.join(work, "view%d.err" % n), "w"), text=True)
    try:
        url = json.loads(view.stdout.readline())["url"]
        b.get(url)
        state = lambda: b.execute_script(  # noqa: E731
            "const d = window.shapeformDrawn; return [window.__bench.received, window.__bench.chars,"
            " d ? d.frames : 0, d && d.agents ? d.agents.length : 0]")
        procs.poll(lambda: state()[3] == n, 60, "the page to draw %d agents" % n)
        r0, c0, d0, _ = state()
        u0, t0 = procs.cpu_s(view.pid), time.monotonic()
        time.sleep(args.seconds)  # the measurement window
        r1, c1, d1, _ = state()
        u1, t1 = procs.cpu_s(view.pid), time.monotonic()
    finally:
        view.terminate()
        view.wait(10)
    dt = t1 - t0
    return {"agents": n, "received_per_s": (r1 - r0) / dt, "drawn_per_s": (d1 - d0) / dt,
            "chars_per_frame": (c1 - c0) / max(1, r1 - r0), "view_cpu_percent": 100.0 * (u1 - u0) / dt}


def main():
    ap = argparse.ArgumentParser(prog="scripts/bench_page.py", description=__doc__.split("\n\n")[0],
                                 usage="scripts/bench_page.py [--build build] [--view PATH] [--agents 12,100,1000] "
                                       "[--seconds 10] [--steps 400] [--period 0.1] [--work DIR] [--json] [--save LABEL [--commit C]]")
    ap.add_argument("--build", default=os.path.join(ROOT, "build"), help="build folder (default build)")
    ap.add_argument("--view", help="the shapeform_view binary (default BUILD/bin/shapeform_view)")
    ap.add_argument("--agents", default="12,100,1000", help="comma-separated agent counts (default 12,100,1000)")
    ap.add_argument("--seconds", type=float, default=10.0, help="measurement window per N (default 10)")
    ap.add_argument("--steps", type=int, default=400, help="simulator steps recorded (default 400)")
    ap.add_argument("--period", type=float, default=0.1, help="seconds of replay per step (default 0.1)")
    ap.add_argument("--work", help="folder for recordings and logs (default: a temporary one, removed)")
    ap.add_argument("--json", action="store_true", help="also print one JSON line per N")
    ap.add_argument("--save", metavar="LABEL", help="store the rows under LABEL in docs/figures/page_results.json")
    ap.add_argument("--commit", help="with --save: the commit --view was built from (default: this checkout's HEAD)")
    args = ap.parse_args()
    try:
        counts = [int(a) for a in args.agents.split(",")]
    except ValueError:
        ap.error("--agents: expected comma-separated integers such as 12,100,1000, got '%s'" % args.agents)
    args.view = args.view or os.path.join(args.build, "bin", "shapeform_view")
    for exe in (args.view, os.path.join(args.build, "bin", "shapeform_sim")):
        if not os.access(exe, os.X_OK):
            ap.error("%s: not an executable (build it, or give --build / --view)" % exe)
    if args.steps * args.period < args.seconds + 15:
        ap.error("--steps x --period: the replay (%g s) must outlast the window (--seconds %g) by 15 s"
                 % (args.steps * args.period, args.seconds))
    work = args.work or tempfile.mkdtemp(prefix="bench_page.")
    os.makedirs(work, exist_ok=True)
    load = os.getloadavg()[0]
    b = browser(work)
    rows = []
    try:
        for n in counts:
            rows.append(measure(args, b, n, work))
            if args.json:
                print(json.dumps(rows[-1]), flush=True)
    except AssertionError as e:  # a wait that timed out
        raise SystemExit("bench_page: %s" % e)
    finally:
        b.quit()
        if not args.work:
            shutil.rmtree(work, ignore_errors=True)
    if args.save:
        commit = args.commit or subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"],
                                               capture_output=True, text=True).stdout.strip() or "-"
        path = os.path.join(ROOT, "docs", "figures", "page_results.json")
        store = json.load(open(path)) if os.path.exists(path) else {}
        store[args.save] = {"when": datetime.datetime.now().strftime("%Y-%m-%d %H:%M"), "commit": commit,
                            "view": os.path.relpath(args.view, ROOT) if args.view.startswith(ROOT) else args.view,
                            "load": load, "command": " ".join(["scripts/bench_page.py"] + sys.argv[1:]), "rows": rows}
        with open(path, "w") as f:
            json.dump(store, f, indent=1)
            f.write("\n")
    print("| agents | frames/s received | frames/s drawn | characters per frame | view CPU (% of one core) |")
    print("|---|---|---|---|---|")
    for r in rows:
        print("| %d | %.1f | %.1f | %d | %.1f |" % (r["agents"], r["received_per_s"], r["drawn_per_s"],
                                                    r["chars_per_frame"], r["view_cpu_percent"]))


if __name__ == "__main__":
    main()
