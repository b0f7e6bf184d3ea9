#!/usr/bin/python3
"""Runs the experiments of Goswami et al. (arXiv 1410.3864) on real agent processes and in the
simulator from the same start, into a run folder (analysed by analyse.py, written up by report.py;
scripts/reproduce_paper.sh chains the three and the figures).

  scripts/paper/run.py --data DIR [--build DIR] [--quick] [--seed S] [--domain D] [--only NAME,...]

Per experiment: DATA/<name>/start.csv (the simulator's seeded start, given to both runs),
DATA/<name>/sim/{metrics.csv,positions.csv,summary.json}, DATA/<name>/dist/{metrics.csv,positions.csv,
summary.json,logs/} and DATA/<name>/async.json (the asynchronous model); simulator-only studies of the
model's limits go to DATA/limits/. DATA/manifest.json lists what ran. Standard library only, except the
asynchronous model (async_model.py, numpy). Every child process is ours and is stopped by its own pid.
"""
import argparse
import json
import os
import shutil
import sys
import time
from dataclasses import asdict
from pathlib import Path

sys.dont_write_bytecode = True  # no __pycache__ in scripts/
sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "lib"))
import shapeform_procs as procs  # noqa: E402
from analyse import fmt, read_csv  # noqa: E402
from experiments import AGENT_RATE_HZ, REPO, SCEN, experiments, limit_runs  # noqa: E402
from shapeform_procs import sets_args  # noqa: E402

# ---------------------------------------------------------------------------------------------
# Small helpers


def log(msg):
    print(msg, flush=True)


def sim_start(bins, scenario, agents, seed):
    """The simulator's seeded uniform start for this scenario (its steps=0 final positions)."""
    out = procs.run([bins / "shapeform_sim", "--config", SCEN / f"{scenario}.yaml", "--agents", agents, "--seed",
                     seed, "--steps", "0"])
    return json.loads(out.stdout)["final_positions"]


def write_start(path, pts):
    with open(path, "w") as f:
        for x, y in pts:
            f.write(f"{x:.17g},{y:.17g}\n")


# ---------------------------------------------------------------------------------------------
# Runs


def run_sim(bins, exp, start_csv, out_dir):
    out_dir.mkdir(parents=True, exist_ok=True)
    out = procs.run([bins / "shapeform_sim", "--config", SCEN / f"{exp.scenario}.yaml", "--init", start_csv,
                     "--steps", exp.steps, "--csv", out_dir / "metrics.csv", "--positions",
                     out_dir / "positions.csv"] + sets_args(exp.sets))
    summary = json.loads(out.stdout)
    (out_dir / "summary.json").write_text(json.dumps(summary, indent=1))
    return summary


def run_dist_direct(bins, exp, start_pts, out_dir, domain, extra_sets):
    """Agents and supervisor started here, one process each, on loopback."""
    logs = out_dir / "logs"
    logs.mkdir(parents=True, exist_ok=True)
    rec = out_dir / "rec"
    if rec.exists():
        shutil.rmtree(rec)
    cfg = SCEN / f"{exp.scenario}.yaml"
    sets = sets_args(exp.sets + extra_sets)
    agents = []
    try:
        for i, (x, y) in enumerate(start_pts):
            agents.append(procs.Proc(f"agent_{i}", [bins / "shapeform_agent", "--id", i, "--config", cfg, "--domain",
                                                    domain, "--start", f"{x:.17g},{y:.17g}", "--json"] + sets, logs))
        # Start the command only once every agent hears all the others (their status events), so that no
        # agent takes its first steps with an incomplete neighbour table (the simulator's agents all see
        # each other).
        n = len(start_pts)

        def meshed():
            dead = [a.name for a in agents if not a.running()]
            if dead:
                raise RuntimeError(f"{', '.join(dead)} exited early; see {logs}")
            return all(procs.neighbours_heard(a.out()) == {i: n - 1} for i, a in enumerate(agents))

        if not procs.wait_for(meshed, 60, 0.2):
            log(f"    warning: not every agent heard {n - 1} neighbours within 60 s; starting anyway")
        script = out_dir / "script.txt"
        timeout = exp.steps / AGENT_RATE_HZ * 3 + 30
        script.write_text(f"wait agents {n} timeout=60\nstart\nwait time {exp.steps} timeout={timeout:.0f}\nquit\n")
        sup = procs.Proc("supervisor", [bins / "shapeform_supervisor", "--config", cfg, "--domain", domain, "--script",
                                        script, "--record", rec, "--json"] + sets, logs)
        try:
            status = sup.wait(timeout + 90)
        finally:
            procs.stop_all([sup])
        if status != 0:
            raise RuntimeError(f"supervisor exit status {status}; see {logs}/supervisor.log")
        summary = procs.summary(sup.out())
    finally:
        procs.stop_all(agents)
    shutil.move(str(rec / "metrics.csv"), out_dir / "metrics.csv")
    shutil.move(str(rec / "positions.csv"), out_dir / "positions.csv")
    shutil.rmtree(rec, ignore_errors=True)
    return summary


def run_dist_launcher(launcher, build, exp, start_csv, out_dir, domain, extra_sets):
    """The same run through scripts/launch_swarm.sh (one launcher for the project)."""
    logs = out_dir / "logs"
    logs.mkdir(parents=True, exist_ok=True)
    rec = out_dir / "rec"
    if rec.exists():
        shutil.rmtree(rec)
    timeout = exp.steps / AGENT_RATE_HZ * 3 + 60
    cmd = [str(launcher), "-n", str(exp.agents), "--scenario", exp.scenario, "--domain", str(domain), "--record",
           str(rec), "--init", str(start_csv), "--steps", str(exp.steps), "--timeout", f"{timeout:.0f}", "--json",
           "--build", str(build), "--runs", str(logs)] + sets_args(exp.sets + extra_sets)
    out = procs.run(cmd, timeout=timeout + 120, check=False)
    (logs / "launcher.out").write_text(out.stdout)
    (logs / "launcher.err").write_text(out.stderr)
    summary = procs.summary(out.stdout)
    # 3 after all K iterations is the verdict (not converged), a result like any other; 3 before them
    # is a wait that timed out.
    done = summary is not None and summary.get("steps", 0) >= exp.steps
    if not (out.returncode == 0 or (out.returncode == 3 and done)):
        raise RuntimeError(f"launch_swarm.sh exit status {out.returncode}; see {logs}/launcher.err")
    shutil.move(str(rec / "metrics.csv"), out_dir / "metrics.csv")
    shutil.move(str(rec / "positions.csv"), out_dir / "positions.csv")
    return summary


def cpu_jiffies():
    """(busy, total) jiffies of the whole machine from /proc/stat."""
    with open("/proc/stat") as f:
        v = [int(x) for x in f.readline().split()[1:]]
    idle = v[3] + (v[4] if len(v) > 4 else 0)
    total = sum(v[:8])
    return total - idle, total


def own_cpu_s():
    """CPU seconds of this process and of its waited-for descendants."""
    import resource
    s, c = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return s.ru_utime + s.ru_stime + c.ru_utime + c.ru_stime


def wait_idle(max_wait_s, busy_cores_max=0.5):
    """Waits (up to max_wait_s) until other programs use less than busy_cores_max cores, so the agent
    processes get their ticks on time. Returns the busy cores seen last."""
    hz = os.sysconf("SC_CLK_TCK")
    t_end = time.monotonic() + max_wait_s
    warned = False
    while True:
        b0, _ = cpu_jiffies()
        t0 = time.monotonic()
        time.sleep(1.0)
        b1, _ = cpu_jiffies()
        busy = (b1 - b0) / hz / (time.monotonic() - t0)
        if busy < busy_cores_max or time.monotonic() >= t_end:
            return busy
        if not warned:
            log(f"    machine busy ({busy:.1f} cores used by other programs); waiting up to {max_wait_s:.0f} s")
            warned = True


def async_reference(exp, start, draws, out_path):
    """The experiment in async_model: the simulator's schedule (sync) and `draws` random tick
    phasings of the processes (async), per-step metrics at the steps the report uses."""
    import async_model as M
    import random
    g = dict(M.GAINS)
    if "r" in exp.model:
        g["r"] = exp.model["r"]
    kw = dict(g=g, track=exp.model.get("track"), ff=exp.model.get("ff", False))
    K = exp.steps
    keys = ["shape_error_mean", "shape_error_max", "gap_cv", "min_separation", "clusters", "extent",
            "centroid_error", "ring_error"]

    def series(ms):
        return {key: [m.get(key) for m in ms] for key in keys}

    out = {"steps": K, "sync": None, "async": []}
    _, ms = M.run(start, exp.model["shape"], K, "sync", **kw)
    out["sync"] = series(ms)
    rng = random.Random(12345)
    phasings = [[rng.random() for _ in start] for _ in range(draws)]
    for ph in phasings:
        _, ms = M.run(start, exp.model["shape"], K, "async", ph, **kw)
        out["async"].append(series(ms))
    if kw["ff"]:
        out["async_compensated"] = []
        for ph in phasings:
            _, ms = M.run(start, exp.model["shape"], K, "async", ph, compensate=True, **kw)
            out["async_compensated"].append(series(ms))
    Path(out_path).write_text(json.dumps(out))


def run_problem(dist_dir, exp):
    """Why a distributed run does not stand for the experiment (or ""): the supervisor lost agents, or
    the machine stalled (gaps in the supervisor's per-iteration record)."""
    rows = [r for r in read_csv(dist_dir / "metrics.csv") if r["epoch"] and r["epoch"] >= 1]
    if not rows or rows[-1]["model_time"] < exp.steps - 1:
        return "the record stops early"
    missing = sum(1 for r in rows if (r["agents_alive"] or 0) < exp.agents)
    if missing:
        return f"agents unheard by the supervisor in {missing} of {len(rows)} samples"
    ts = [r["model_time"] for r in rows]
    gap = max(b - a for a, b in zip(ts, ts[1:]))
    if gap > 5:
        return f"the machine stalled: a gap of {gap:.0f} iterations in the supervisor's record"
    return ""


def cmd_run(a):
    build = Path(a.build).resolve()
    bins = build / "bin"
    for exe in ("shapeform_sim", "shapeform_agent", "shapeform_supervisor"):
        if not (bins / exe).exists():
            sys.exit(f"run: {bins / exe} not found (build first)")
    data = Path(a.data).resolve()
    data.mkdir(parents=True, exist_ok=True)
    launcher = REPO / "scripts" / "launch_swarm.sh"
    backend = a.backend
    if backend == "auto":
        backend = "launcher" if launcher.exists() and os.access(launcher, os.X_OK) else "direct"
    exps = experiments(a.quick)
    only = set(a.only.split(",")) if a.only else None
    niced = 0
    if a.nice:
        # The agents tick on a wall clock: on a shared machine, let them (our children inherit this)
        # go before compilers and the like, so that fewer ticks come late or are skipped.
        try:
            os.nice(a.nice)
            niced = a.nice
        except PermissionError:
            log(f"note: cannot raise priority (nice {a.nice}) without privileges; running at normal priority")
    old = {}
    if only and (data / "manifest.json").exists():  # a partial rerun keeps the other entries
        old = {e["name"]: e for e in json.loads((data / "manifest.json").read_text()).get("experiments", [])}
    manifest = {"quick": a.quick, "seed": a.seed, "backend": backend, "experiments": [], "limits": [],
                "async_draws": a.async_draws, "started": time.strftime("%Y-%m-%d %H:%M:%S"),
                "cores": os.cpu_count(), "nice": niced}
    t_all = time.monotonic()
    hz = os.sysconf("SC_CLK_TCK")
    # Every distributed run records every metrics tick: the supervisor samples each iteration.
    # A neighbour is dropped only after 0.5 s of silence (default 3 periods): no agent leaves in these
    # experiments, and a short stall of the machine should not change the law an agent computes.
    # Lockstep: every process takes step k+1 from its neighbours' step-k states, the simulator's update
    # (agent.sync in config/README.md); free-running processes are the async model's columns.
    extra = [f"supervisor.metrics_rate_hz={AGENT_RATE_HZ:g}", "agent.neighbour_timeout_periods=25", "agent.sync=lockstep"]
    failures = 0
    todo = [e for e in exps if not only or e.name in only or e.group in only]
    for idx, exp in enumerate(exps):
        if exp not in todo:
            if exp.name in old:
                manifest["experiments"].append(old[exp.name])
            continue
        t0 = time.monotonic()
        d = data / exp.name
        d.mkdir(parents=True, exist_ok=True)
        pts = [(x + exp.start_offset[0], y + exp.start_offset[1])
               for x, y in sim_start(bins, exp.scenario, exp.agents, a.seed)]
        start_csv = d / "start.csv"
        write_start(start_csv, pts)
        entry = asdict(exp)
        entry["seed"] = a.seed
        try:
            run_sim(bins, exp, start_csv, d / "sim")
            async_reference(exp, pts, a.async_draws, d / "async.json")
            for attempt in range(1, a.attempts + 1):
                busy_before = wait_idle(a.max_wait_idle)
                dom = a.domain + idx % a.domains  # runs are sequential: a domain is free again after its run
                b0, _ = cpu_jiffies()
                c0, w0 = own_cpu_s(), time.monotonic()
                if backend == "launcher":
                    s = run_dist_launcher(launcher, build, exp, start_csv, d / "dist", dom, extra)
                else:
                    s = run_dist_direct(bins, exp, pts, d / "dist", dom, extra)
                b1, _ = cpu_jiffies()
                wall = time.monotonic() - w0
                ours = own_cpu_s() - c0
                other = max(0.0, (b1 - b0) / hz - ours) / wall
                problem = run_problem(d / "dist", exp)
                entry.update(ok=True, domain=dom, dist_wall_s=round(wall, 1), own_cores=round(ours / wall, 2),
                             other_cores=round(other, 2), other_cores_before=round(busy_before, 2), attempts=attempt,
                             problem=problem)
                if not problem:
                    break
                log(f"    {exp.name}: attempt {attempt}: {problem} (other programs used {other:.1f} cores)"
                    + ("; running it again" if attempt < a.attempts else "; keeping it, flagged"))
            (d / "dist" / "summary.json").write_text(json.dumps(s, indent=1))
            sim_s = json.loads((d / "sim" / "summary.json").read_text())
            if exp.group == "tracking":
                msg = (f"centroid error dist {fmt(s.get('centroid_error'))} sim {fmt(sim_s.get('centroid_error'))}, "
                       f"ring error dist {fmt(s.get('ring_error'))} sim {fmt(sim_s.get('ring_error'))}")
            else:
                msg = (f"shape error dist {fmt(s.get('shape_error_mean'))} sim {fmt(sim_s.get('shape_error_mean'))}, "
                       f"gap CV dist {fmt(s.get('gap_cv'))} sim {fmt(sim_s.get('gap_cv'))}")
            if other > 0.3:
                msg += f" [other programs used {other:.1f} cores during the run]"
            if entry["problem"]:
                msg += f" [FLAGGED: {entry['problem']}]"
        except Exception as e:  # report and go on with the next experiment
            entry["ok"] = False
            entry["error"] = str(e)
            failures += 1
            msg = f"FAILED: {e}"
        entry["seconds"] = round(time.monotonic() - t0, 1)
        manifest["experiments"].append(entry)
        log(f"[{idx + 1:2d}/{len(exps)}] {exp.name:21s} {exp.agents} agents, {exp.steps:4d} steps, "
            f"{entry['seconds']:5.1f} s: {msg}")
    if not only or "limits" in only:
        t0 = time.monotonic()
        ld = data / "limits"
        ld.mkdir(parents=True, exist_ok=True)
        for name, scen, n, k, extra_args in limit_runs(a.quick):
            cmd = [str(bins / "shapeform_sim"), "--config", str(SCEN / f"{scen}.yaml"), "--agents", str(n), "--seed",
                   str(a.seed), "--steps", str(k), "--csv", str(ld / f"{name}_metrics.csv")] + extra_args
            if not name.startswith("circle_rk4"):
                cmd += ["--positions", str(ld / f"{name}_positions.csv")]
            out = procs.run(cmd, check=False)
            if out.returncode != 0:
                log(f"    limits {name}: shapeform_sim failed: {out.stderr.strip()}")
                failures += 1
                continue
            (ld / f"{name}_summary.json").write_text(out.stdout)
            manifest["limits"].append({"name": name, "scenario": scen, "agents": n, "steps": k, "args": extra_args})
        # Seeds 1..20 of the simulator: is the one seed of the experiments typical?
        seeds = {}
        for scen in ("line", "circle", "ellipse", "square", "ellipse_no_repulsion", "square_no_repulsion",
                     "track_line", "track_circle"):
            steps = 200 if scen.endswith("no_repulsion") or scen.startswith("track") else 500
            vals = []
            for sd in range(1, 21):
                out = procs.run([bins / "shapeform_sim", "--config", SCEN / f"{scen}.yaml", "--seed", sd, "--steps",
                                 steps])
                j = json.loads(out.stdout)
                j.pop("final_positions", None)
                vals.append(j)
            seeds[scen] = {"steps": steps, "runs": vals}
        (ld / "seeds.json").write_text(json.dumps(seeds))
        log(f"[limits] simulator only: circle N=10/20/50, line N=12/15/20, RK4 dt=0.05, line path with "
            f"feed-forward to 1000, seeds 1-20: {time.monotonic() - t0:.1f} s")
    elif (data / "manifest.json").exists():
        manifest["limits"] = json.loads((data / "manifest.json").read_text()).get("limits", [])
    manifest["seconds"] = round(time.monotonic() - t_all, 1)
    if only and (data / "manifest.json").exists():
        manifest["seconds_partial"] = manifest["seconds"]
        manifest["seconds"] = json.loads((data / "manifest.json").read_text()).get("seconds", manifest["seconds"])
    (data / "manifest.json").write_text(json.dumps(manifest, indent=1))
    log(f"experiments done in {time.monotonic() - t_all:.0f} s, {failures} failure(s); data in {data}")
    return 1 if failures else 0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                 usage="scripts/paper/run.py --data DIR [--build DIR] [--quick] [options]")
    ap.add_argument("--build", default=str(REPO / "build"))
    ap.add_argument("--data", required=True, help="the run folder to record into")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--domain", type=int, default=131,
                    help="first DDS domain id; experiment i uses domain + i %% domains (131..139 by default: the "
                         "integration tests use 101..130 and 140..149, the DDS unit tests 150..229)")
    ap.add_argument("--domains", type=int, default=9, help="how many domain ids from --domain to cycle through")
    ap.add_argument("--only", default="", help="comma-separated experiment names or groups")
    ap.add_argument("--backend", choices=["auto", "launcher", "direct"], default="auto",
                    help="launcher: scripts/launch_swarm.sh; direct: start the processes here (and start the "
                         "command only once every agent hears all the others); auto: launcher if present")
    ap.add_argument("--nice", type=int, default=-10,
                    help="niceness increment for this runner and the processes it starts (0: leave alone)")
    ap.add_argument("--attempts", type=int, default=3,
                    help="runs of a distributed experiment when the machine stalls or agents go unheard")
    ap.add_argument("--async-draws", type=int, default=10, help="random tick phasings for the asynchronous model")
    ap.add_argument("--max-wait-idle", type=float, default=30.0,
                    help="seconds to wait for other programs to leave the CPUs before each distributed run")
    return cmd_run(ap.parse_args())


if __name__ == "__main__":
    sys.exit(main())
