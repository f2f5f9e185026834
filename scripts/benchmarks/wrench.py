"""Wrench feasibility, capacity margin and tensions of whole workspaces, against per-pose solvers.

In the same rounds on this machine:

1. the IPAnema 3 static sweep (feasibility + minimum 2-norm tensions + capacity margin for every
   grid pose) through ``workspaces.run``, warm (its first call: numba's cache loaded or compiled);
2. per-pose scipy ``linprog`` (HiGHS) feasibility on a sample of the same poses (feasibility only:
   no tensions, no margin);
3. per-pose cvxpy min-norm tensions (a Parameter problem compiled once, OSQP) on the same sample;
4. the plain hyperplane-shifting kernel (a determinant per facet normal, no basis factorisation) on
   the same sample;
5. the CASPR IROS-2016 wrench-closure grid of IPAnema 2 (14,823 poses at orientation (30, -30, 5)
   deg), end to end: load the design, sweep, summary; CASPR's paper (Lau et al., IROS 2016,
   Table I) timed it at 89-455 s.
"""

from __future__ import annotations

import sys

import numpy as np

from benchmarks import harness as h

OPTIONS = {"sample": 400, "step": 0.1}
QUICK = {"sample": 100, "step": 0.2}


def sample_poses(design, grid, count, rng):
    from cdpr_design.workspaces import grid as wsg

    idx = np.sort(rng.choice(grid.size, size=min(count, grid.size), replace=False))
    pos = np.vstack([wsg.grid_positions(grid, int(i), 1) for i in idx])
    ori = list(design.workspace.orientation)
    return [list(p) + ori for p in pos]


def per_pose_linprog(design, poses):
    from scipy.optimize import linprog

    from cdpr_design.statics import kinematics as kin

    tmin, tmax = design.tension_min, design.tension_max
    bounds = list(zip(tmin, tmax))
    feas = 0
    for pose in poses:
        W = kin.structure_matrix(design, pose)
        w = kin.required_wrench(design, pose)
        res = linprog(np.zeros(design.m), A_eq=W, b_eq=w, bounds=bounds, method="highs")
        feas += res.status == 0
    return feas


def per_pose_cvxpy(design, poses):
    import cvxpy as cp

    from cdpr_design.statics import kinematics as kin

    n, m = design.n, design.m
    Wp, wp, t = cp.Parameter((n, m)), cp.Parameter(n), cp.Variable(m)
    prob = cp.Problem(cp.Minimize(cp.sum_squares(t)),
                      [Wp @ t == wp, t >= design.tension_min, t <= design.tension_max])
    feas = 0
    for pose in poses:
        Wp.value = kin.structure_matrix(design, pose)
        wp.value = kin.required_wrench(design, pose)
        prob.solve(solver=cp.OSQP, warm_start=True)
        feas += prob.status in ("optimal", "optimal_inaccurate")
    return feas


def per_pose_plain_hsm(design, poses):
    sys.path.insert(0, str(h.ROOT))
    from cdpr_design.statics import kinematics as kin
    from cdpr_design.statics.robot import combinations
    from tests.reference.hsm import hsm_margin

    combos = combinations(design.m, design.n)
    tmin, tmax = design.tension_min, design.tension_max
    Ws = [np.ascontiguousarray(kin.structure_matrix(design, p)) for p in poses]
    ws_ = [kin.required_wrench(design, p)[None, :] for p in poses]
    hsm_margin(Ws[0], ws_[0], tmin, tmax, combos)  # compile / load
    feas = 0
    for W, w in zip(Ws, ws_):
        ok, mg = hsm_margin(W, w, tmin, tmax, combos)
        feas += ok and mg >= 0
    return feas


def run(b: h.Bench) -> None:
    import cdpr_design as cd
    from cdpr_design import workspaces as ws

    d3 = cd.load(h.ROOT / "designs" / "ipanema3.yaml")
    grid = ws.make_grid(d3, step=b.opt["step"])
    first, _ = h.timed(ws.run, d3, grid=ws.make_grid(d3, step=2.0), keep_maps=False)
    poses = sample_poses(d3, grid, b.opt["sample"], b.rng)
    per_pose_plain_hsm(d3, poses[:1])  # compiled or loaded
    out = {}
    t = h.rounds({"kernels": lambda: out.__setitem__("res", ws.run(d3, grid=grid, keep_maps=False)),
                  "linprog": lambda: out.__setitem__("linprog", per_pose_linprog(d3, poses)),
                  "cvxpy": lambda: out.__setitem__("cvxpy", per_pose_cvxpy(d3, poses)),
                  "plain HSM": lambda: out.__setitem__("plain HSM", per_pose_plain_hsm(d3, poses))}, b.rounds)
    res = out["res"]
    scale = res.poses / len(poses)
    b.say(f"IPAnema 3, static, step {b.opt['step']} m ({res.poses:,} poses, feasible {res.fraction:.3f}; the sample "
          + ", ".join(f"{k} {out[k] / len(poses):.3f}" for k in ("linprog", "cvxpy", "plain HSM"))
          + f"); first sweep (numba's cache loaded or compiled) {first.wall:.2f} s")
    label = f"IPAnema 3 static sweep, {res.poses:,} poses"
    b.row(f"{label} (feasible + tensions + margin)", f"{res.poses / h.best(t['kernels']):,.0f} poses/s, "
          f"{h.per_pose(h.best(t['kernels'], 'cpu'), res.poses)} CPU", h.ratios(t["linprog"], t["kernels"], scale=scale),
          "per-pose scipy linprog (feasibility only)")
    b.row(f"{label}", "", h.ratios(t["cvxpy"], t["kernels"], scale=scale), "per-pose cvxpy/OSQP min-norm (Parameters)")
    b.row(f"{label}", "", h.ratios(t["plain HSM"], t["kernels"], scale=scale), "per-pose plain HSM kernel (margin only)")

    def caspr():
        d2 = cd.load(h.ROOT / "designs" / "ipanema2.yaml")
        r2 = ws.run(d2, ws.Analysis(kind="wrench-closure"))
        r2.summary()
        out["r2"] = r2

    caspr()
    t2, _ = h.repeat(caspr, b.rounds)
    r2 = out["r2"]
    b.row(f"IPAnema 2 wrench-closure, CASPR IROS-2016 grid ({r2.poses:,} poses, {r2.feasible:,} in closure), end to "
          "end", f"{h.best(t2):.3f} s", h.spread([89 / h.best(t2), 455 / h.best(t2)]),
          "CASPR (MATLAB, i7-4770): 89-455 s, as published")
