"""Benchmark: wrench feasibility, capacity margin and tensions of whole workspaces.

Side by side, in one run on this machine:

1. the IPAnema 3 static sweep (feasibility + minimum 2-norm tensions +
   capacity margin for every grid pose) through ``workspace.run``, cold
   (first call: numba cache load or compile) and warm;
2. per-pose scipy ``linprog`` (HiGHS) feasibility on a sample of the same
   poses (feasibility only: no tensions, no margin);
3. per-pose cvxpy min-norm tensions (a Parameter problem compiled once,
   OSQP) on the same sample;
4. the plain hyperplane-shifting kernel (a determinant per facet normal, no
   basis factorisation) on the same sample;
5. the CASPR IROS-2016 wrench-closure grid of IPAnema 2 (14,823 poses at
   orientation (30, -30, 5) deg), end to end: load the design, sweep, summary.
   CASPR's paper (Lau et al., IROS 2016, Table I) timed it at 89-455 s.

Usage:  python scripts/bench_wrench.py [--sample 400] [--step 0.1]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

t_import = time.perf_counter()
import cdpr_design as cd  # noqa: E402
from cdpr_design import kernels as K  # noqa: E402
from cdpr_design.statics import kinematics as kin  # noqa: E402
from cdpr_design import workspaces as ws  # noqa: E402
from cdpr_design.workspaces import grid as wsg
from cdpr_design.statics.robot import combinations
t_import = time.perf_counter() - t_import


def sample_poses(design, grid, count, rng):
    idx = np.sort(rng.choice(grid.size, size=min(count, grid.size), replace=False))
    pos = np.vstack([wsg.grid_positions(grid, int(i), 1) for i in idx])
    ori = list(design.workspace.orientation)
    return [list(p) + ori for p in pos]


def per_pose_linprog(design, poses):
    from scipy.optimize import linprog

    tmin, tmax = design.tension_min, design.tension_max
    bounds = list(zip(tmin, tmax))
    feas = 0
    t0 = time.perf_counter()
    for pose in poses:
        W = kin.structure_matrix(design, pose)
        w = kin.required_wrench(design, pose)
        res = linprog(np.zeros(design.m), A_eq=W, b_eq=w, bounds=bounds, method="highs")
        feas += res.status == 0
    return time.perf_counter() - t0, feas


def per_pose_cvxpy(design, poses):
    import cvxpy as cp

    n, m = design.n, design.m
    Wp, wp, t = cp.Parameter((n, m)), cp.Parameter(n), cp.Variable(m)
    prob = cp.Problem(cp.Minimize(cp.sum_squares(t)),
                      [Wp @ t == wp, t >= design.tension_min, t <= design.tension_max])
    feas = 0
    t0 = time.perf_counter()
    for pose in poses:
        Wp.value = kin.structure_matrix(design, pose)
        wp.value = kin.required_wrench(design, pose)
        prob.solve(solver=cp.OSQP, warm_start=True)
        feas += prob.status in ("optimal", "optimal_inaccurate")
    return time.perf_counter() - t0, feas


def per_pose_plain_hsm(design, poses):
    combos = combinations(design.m, design.n)
    tmin, tmax = design.tension_min, design.tension_max
    Ws = [np.ascontiguousarray(kin.structure_matrix(design, p)) for p in poses]
    ws_ = [kin.required_wrench(design, p)[None, :] for p in poses]
    K.hsm_margin(Ws[0], ws_[0], tmin, tmax, combos)  # compile / load
    feas = 0
    t0 = time.perf_counter()
    for W, w in zip(Ws, ws_):
        ok, mg = K.hsm_margin(W, w, tmin, tmax, combos)
        feas += ok and mg >= 0
    return time.perf_counter() - t0, feas


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sample", type=int, default=400, help="poses for the per-pose baselines")
    ap.add_argument("--step", type=float, default=0.1, help="IPAnema 3 grid step [m]")
    ap.add_argument("--repeat", type=int, default=3, help="warm repetitions (best is kept)")
    args = ap.parse_args(argv)
    rng = np.random.default_rng(0)
    from cdpr_design.kernels import parallel

    print(f"kernel threads: {parallel.threads()}, import of cdpr_design: {t_import:.2f} s")

    # --- 1. IPAnema 3 static sweep
    d3 = cd.load(ROOT / "designs" / "ipanema3.yaml")
    grid = ws.make_grid(d3, step=args.step)
    t0 = time.perf_counter()
    tiny = ws.make_grid(d3, step=2.0)
    ws.run(d3, kind="static", grid=tiny, keep_maps=False)
    cold = time.perf_counter() - t0
    best = np.inf
    cpu = np.inf
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        c0 = time.process_time()
        res = ws.run(d3, kind="static", grid=grid, keep_maps=False)
        best = min(best, time.perf_counter() - t0)
        cpu = min(cpu, time.process_time() - c0)
    rate = res.poses / best
    poses = sample_poses(d3, grid, args.sample, rng)

    rows = [("kernel sweep (feasible + tensions + margin)", res.poses, best, rate, res.fraction)]
    for label, fn in (("per-pose scipy linprog (feasibility only)", per_pose_linprog),
                      ("per-pose cvxpy/OSQP min-norm (Parameters)", per_pose_cvxpy),
                      ("per-pose plain HSM kernel (margin only)", per_pose_plain_hsm)):
        dt, feas = fn(d3, poses)
        rows.append((label, len(poses), dt, len(poses) / dt, feas / len(poses)))

    print(f"\nIPAnema 3, static, grid step {args.step} m ({res.poses:,} poses), "
          f"orientation {list(d3.workspace.orientation)}; cold start (first sweep, "
          f"numba cache load or compile): {cold:.2f} s")
    print(f"kernel sweep CPU time: {cpu / res.poses * 1e6:.2f} us per pose (all threads); "
          f"on {parallel.threads()} idle cores that is "
          f"{parallel.threads() * res.poses / cpu:,.0f} poses/s "
          f"(wall clock above is slower when other processes share the cores)")
    print(f"{'method':46s} {'poses':>9s} {'time [s]':>9s} {'poses/s':>12s} {'feasible':>9s} {'speed-up':>9s}")
    for label, npos, dt, r, frac in rows:
        print(f"{label:46s} {npos:9,d} {dt:9.3f} {r:12,.0f} {frac:9.3f} {rate / r:9.1f}x")

    # --- 2. CASPR IROS 2016 wrench-closure grid of IPAnema 2
    t0 = time.perf_counter()
    d2 = cd.load(ROOT / "designs" / "ipanema2.yaml")
    r2 = ws.run(d2, kind="wrench-closure")
    first = time.perf_counter() - t0
    best2 = np.inf
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        d2 = cd.load(ROOT / "designs" / "ipanema2.yaml")
        r2 = ws.run(d2, kind="wrench-closure")
        _ = r2.summary()
        best2 = min(best2, time.perf_counter() - t0)
    print(f"\nIPAnema 2 wrench-closure, CASPR IROS-2016 grid: {r2.poses:,} poses, "
          f"{r2.feasible:,} in wrench closure ({r2.fraction:.3f})")
    print(f"  end to end (load + sweep + summary): first {first:.3f} s, warm {best2:.3f} s "
          f"({r2.poses / best2:,.0f} poses/s); CASPR (MATLAB, i7-4770): 89-455 s "
          f"-> {89 / best2:,.0f}x-{455 / best2:,.0f}x")


if __name__ == "__main__":
    main()
