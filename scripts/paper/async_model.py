#!/usr/bin/python3
"""A numpy model of the paper's law under the two schedules that matter for the comparison between
the simulator and the agent processes (used by scripts/paper/run.py and report.py to explain the differences).

- sync:  every agent steps from the positions of step k (Jacobi). This is shapeform_sim; the model is
         checked against the simulator's recorded series before it is trusted.
- async: what the processes do. Each agent ticks at the same rate but with its own fixed phase
         phi_i in [0, 1) of the period; at its tick it uses the latest state of every other agent, i.e.
         step k+1 of those whose tick came earlier in the period and step k of the others
         (Gauss-Seidel in phase order). Phases are drawn at random per run.

Static shapes only (line, circle, ellipse, square), Euler, the paper's gains by default.
"""
import math

import numpy as np

GAINS = dict(k1=0.1, k2=2.0, sigma=3.5, beta=1.2, r=0.1)
GOLDEN = 2.39996322972865332223


def target(shape, x, centre=None):
    """Targets x_T for positions x (n x 2), as common/core/shape.cpp (closed shapes about centre)."""
    kind = shape["kind"]
    if centre is not None and kind != "line":
        return target(shape, x - centre) + centre
    if kind == "line":
        m, c = shape["m"], shape["c"]
        t1 = (x[:, 0] + m * x[:, 1] - m * c) / (1 + m * m)
        return np.stack([t1, m * t1 + c], axis=1)
    if kind == "circle":
        n = np.hypot(x[:, 0], x[:, 1])
        d = np.where(n[:, None] > 0, x / np.where(n > 0, n, 1)[:, None], np.array([1.0, 0.0]))
        return shape["r0"] * d
    if kind == "ellipse":
        a, b = shape["a"], shape["b"]
        th = np.arctan2(a * x[:, 1], b * x[:, 0])
        return np.stack([a * np.cos(th), b * np.sin(th)], axis=1)
    if kind == "square":
        a = shape["a"]
        m = np.maximum(np.abs(x[:, 0]), np.abs(x[:, 1]))
        return np.where(m[:, None] > 0, (a / np.where(m > 0, m, 1))[:, None] * x, np.array([a, 0.0]))
    raise ValueError(kind)


def velocity_one(i, xi, others_idx, others_x, xt, g):
    d = others_x - xi
    d2 = (d * d).sum(axis=1)
    coh = g["k1"] * ((g["sigma"] ** 2 + d2) ** (-g["beta"]))[:, None] * d
    v = coh.sum(axis=0)
    dt_ = xt - xi
    v = v + g["k2"] * (g["sigma"] ** 2 + dt_ @ dt_) ** (-g["beta"]) * dt_
    if g["r"] != 0 and len(others_idx):
        # nearest neighbour, ties to the lowest id
        best = None
        for k in np.argsort(others_idx, kind="stable"):
            if best is None or d2[k] < d2[best]:
                best = k
        dd = xi - others_x[best]
        ln = math.hypot(dd[0], dd[1])
        if ln > 0:
            v = v + g["r"] / ln * dd
        else:
            v = v + g["r"] * np.array([math.cos(GOLDEN * i), math.sin(GOLDEN * i)])
    return v


def velocities(x, shape, g, centre=None):
    n = len(x)
    xt = target(shape, x, centre)
    d = x[None, :, :] - x[:, None, :]  # d[i, j] = x_j - x_i
    d2 = (d * d).sum(axis=2)
    w = (g["sigma"] ** 2 + d2) ** (-g["beta"])
    np.fill_diagonal(w, 0.0)
    v = g["k1"] * (w[:, :, None] * d).sum(axis=1)
    e = xt - x
    v += g["k2"] * ((g["sigma"] ** 2 + (e * e).sum(axis=1)) ** (-g["beta"]))[:, None] * e
    if g["r"] != 0 and n > 1:
        dd = d2.copy()
        np.fill_diagonal(dd, np.inf)
        nn = np.argmin(dd, axis=1)  # first minimum = lowest id on ties
        rep = x - x[nn]
        ln = np.hypot(rep[:, 0], rep[:, 1])
        esc = np.stack([np.cos(GOLDEN * np.arange(n)), np.sin(GOLDEN * np.arange(n))], axis=1)
        v += g["r"] * np.where(ln[:, None] > 0, rep / np.where(ln > 0, ln, 1)[:, None], esc)
    return v


def metrics(x, shape, centre=None):
    c = np.zeros(2) if centre is None else centre
    xt = target(shape, x, centre)
    err = np.hypot(*(x - xt).T)
    if shape["kind"] == "line":
        u = np.array([1.0, shape["m"]]) / math.hypot(1.0, shape["m"])
        order = np.argsort(x @ u, kind="stable")
        xs = x[order]
        gaps = np.hypot(*(xs[1:] - xs[:-1]).T)
    else:
        order = np.argsort(np.arctan2(x[:, 1] - c[1], x[:, 0] - c[0]), kind="stable")
        xs = x[order]
        gaps = np.hypot(*(np.roll(xs, -1, axis=0) - xs).T)
    d = np.hypot(*(x[None] - x[:, None]).transpose(2, 0, 1))
    iu = np.triu_indices(len(x), 1)
    m = {"shape_error_mean": float(err.mean()), "shape_error_max": float(err.max()),
         "gap_cv": float(gaps.std() / gaps.mean()) if gaps.mean() > 1e-12 else None,
         "min_separation": float(d[iu].min()), "extent": float(d[iu].max()), "clusters": clusters(d)}
    if centre is not None:
        m["centroid_error"] = float(np.hypot(*(x.mean(axis=0) - c)))
        m["ring_error"] = float(np.abs(np.hypot(*(x - c).T) - shape["r0"]).mean())
    return m


def clusters(d, link=0.05):
    """Single-linkage clusters at distance link, from the pairwise distance matrix."""
    n = len(d)
    parent = list(range(n))

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    c = n
    for i, j in zip(*np.nonzero(np.triu(d <= link, 1))):
        a, b = find(i), find(j)
        if a != b:
            parent[a] = b
            c -= 1
    return c


def centre_at(track, t):
    """C(t) and dC/dt of a tracking path (common/core/shape.cpp centre_at / centre_velocity)."""
    if track["path"] == "fixed":
        return np.array(track["point"], float), np.zeros(2)
    if track["path"] == "line":
        v = np.array(track["velocity"], float)
        return np.array(track["point"], float) + t * v, v
    w = 2 * math.pi / track["period"]
    a = track.get("phase", 0.0) + w * t
    o = np.array(track.get("origin", (0.0, 0.0)), float)
    R = track["radius"]
    return o + R * np.array([math.cos(a), math.sin(a)]), R * w * np.array([-math.sin(a), math.cos(a)])


def run(start, shape, steps, schedule="sync", phases=None, g=GAINS, dt=1.0, track=None, ff=False,
        compensate=False):
    """Positions over steps 0..steps (list of arrays) and per-step metrics (list of dicts).
    track: None (static shape) or a centre path dict (path fixed|line|circle, ...) for a circle
    shape around C(t); ff adds dC/dt to every agent's velocity (tracking.feedforward).
    compensate (async, ff): an agent moves the neighbours that already stepped in this period back by
    dC/dt*dt, i.e. it sees every neighbour in the centre's frame of its own step (x_j + v_C(t_i) (t_i -
    t_j) with the neighbours' model times, dC/dt at the agent's own time): what free-running agent
    processes do (agent::AgentLogic::step); without it, the agents before that rule."""
    x = np.array(start, dtype=float)
    n = len(x)
    cen = (lambda t: centre_at(track, t)) if track else (lambda t: (None, np.zeros(2)))
    out_x, out_m = [x.copy()], [metrics(x, shape, cen(0.0)[0])]
    order = np.argsort(phases) if schedule == "async" else None
    idx = np.arange(n)
    for k in range(steps):
        c, vc = cen(k * dt)
        add = vc if ff else np.zeros(2)
        if schedule == "sync":
            x = x + dt * (velocities(x, shape, g, c) + add)
        else:
            stepped = np.zeros(n, bool)
            for i in order:  # each agent in its phase order sees the others' newest positions
                others = idx != i
                ox = x[others]
                if compensate and ff:
                    ox = ox.copy()
                    ox[stepped[others]] -= dt * vc
                xt = target(shape, x[i:i + 1], c)[0]
                x[i] = x[i] + dt * (velocity_one(i, x[i].copy(), idx[others], ox, xt, g) + add)
                stepped[i] = True
        out_x.append(x.copy())
        out_m.append(metrics(x, shape, cen((k + 1) * dt)[0]))
    return out_x, out_m


SHAPES = {"line": dict(kind="line", m=-1.0, c=5.0), "circle": dict(kind="circle", r0=4.0),
          "ellipse": dict(kind="ellipse", a=4.0, b=2.0), "square": dict(kind="square", a=5.0)}


if __name__ == "__main__":
    # A module, not a program: it only says so (scripts/ holds nothing that cannot answer --help).
    import sys as _sys
    print("usage: import async_model -- async_model.py is a module: the numpy model of the reproduction (scripts/paper/run.py and report.py use it); it runs nothing itself")
    _sys.exit(0 if _sys.argv[1:] in ([], ["--help"], ["-h"]) else 2)
