"""A second, slower route to one pose's statics, kept for the tests: the kernel wrappers of
:mod:`cdpr_design.statics.tension` and cvxpy composed by hand (geometry from
:mod:`cdpr_design.statics.kinematics`, required wrenches written out here), against which the
product's one pose API (:func:`cdpr_design.workspaces.pose.evaluate_pose`) is compared; and the
per-pose sagging kernel called on one pose with any required wrench (:func:`sagging_pose`), the
reference of the batched sagging kernels."""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from cdpr_design.model.design import Design
from cdpr_design.statics import kinematics as kin
from cdpr_design.statics.robot import KINDS
from cdpr_design.statics.tension import (OBJECTIVES, _check_weights, evaluate, min_norm, solve_cvxpy,
                                         wrench_closure)




@dataclass(frozen=True)
class PoseAnalysis:
    """Statics of one pose. Infeasible poses are flags and NaNs, not errors.

    Attributes
    ----------
    pose : (ncoords,) array, the pose in the motion's coordinates.
    kind, objective : str
    feasible : bool
        static / wrench-feasible: every required wrench is balanced within
        the bounds (and tensions were found); wrench-closure: W positively spans R^n.
    margin : float
        Capacity margin [N] over the required wrenches (NaN if rank W < n).
    tensions : (m,) array
        Tensions [N] at the nominal wrench for the objective; NaN where none.
    W : (n, m) structure matrix.
    wrenches : (nv, n) required wrenches; row 0 the nominal one (gravity only).
    lengths : (m,) cable lengths [m].
    rank_ok : bool
        rank W = n and no cable has zero length.
    closure : bool
        W positively spans R^n (whatever ``kind``).
    """

    pose: np.ndarray
    kind: str
    objective: str
    feasible: bool
    margin: float
    tensions: np.ndarray
    W: np.ndarray
    wrenches: np.ndarray
    lengths: np.ndarray
    rank_ok: bool
    closure: bool


def required_wrenches(design: Design, pose, kind: str = "static") -> np.ndarray:
    """Required-wrench vertices at a pose, (nv, n): row 0 = -gravity; for
    ``wrench-feasible`` every vertex of ``workspace.external_wrench`` added."""
    g = kin.gravity_wrench(design, pose)
    rows = [-g]
    box = design.workspace.external_wrench
    if kind == "wrench-feasible" and box is not None:
        lo, hi = np.asarray(box.lower, float), np.asarray(box.upper, float)
        choices = [(lo[i],) if lo[i] == hi[i] else (lo[i], hi[i]) for i in range(lo.size)]
        for v in itertools.product(*choices):
            rows.append(-(g + np.asarray(v)))
    return np.ascontiguousarray(np.array(rows, dtype=float))


def analyse_pose(design: Design, pose, kind: str = "static", objective: str = "min-norm",
                 weights=None, solver: str | None = None) -> PoseAnalysis:
    """Feasibility, capacity margin and tension distribution at one pose.

    Parameters
    ----------
    design : Design
    pose : sequence of float, the motion's pose coordinates.
    kind : 'static' | 'wrench-feasible' | 'wrench-closure'
    objective : 'min-norm' | 'min-max' | 'min-sum'
        Tension objective at the nominal wrench: 2-norm (exact kernel, also
        weighted), infinity-norm or 1-norm (cvxpy).
    weights : (m,) positive, optional; per-cable weights of the objective.
    """
    if kind not in KINDS:
        raise ValueError(f"kind: expected one of {', '.join(KINDS)}, got {kind!r}")
    if objective not in OBJECTIVES:
        raise ValueError(f"objective: expected one of {', '.join(OBJECTIVES)}, got {objective!r}")
    m = design.m
    c = _check_weights(weights, m)
    pose = np.asarray(pose, dtype=float).reshape(-1)
    geo = kin.cable_geometry(design, pose)
    W = np.ascontiguousarray(kin.structure_matrix(design, pose))
    wreq = required_wrenches(design, pose, kind)
    tmin, tmax = design.tension_min, design.tension_max
    zero_len = bool(np.any(geo.lengths <= 1e-12))
    nan = np.full(m, np.nan)
    if zero_len:
        return PoseAnalysis(pose, kind, objective, False, float("nan"), nan, W, wreq,
                            geo.lengths, False, False)
    feasible, margin, t = evaluate(W, wreq, tmin, tmax, kind)
    rank_ok = bool(np.isfinite(margin))
    closure = wrench_closure(W) if rank_ok else False
    has_t = bool(np.all(np.isfinite(t)))
    if has_t and (objective != "min-norm" or c is not None):
        if objective == "min-norm":
            t2 = min_norm(W, wreq[0], tmin, tmax, weights=c)
        else:
            t2 = solve_cvxpy(W, wreq[0], tmin, tmax, objective, c, solver=solver)
        t = nan if t2 is None else t2
        if t2 is None and kind != "wrench-closure":
            feasible = False
    return PoseAnalysis(pose, kind, objective, bool(feasible), float(margin), t, W, wreq,
                        geo.lengths, rank_ok, closure)


def sagging_pose(design: Design, full: np.ndarray, wreq: np.ndarray, combos: np.ndarray, kcode: int):
    """One pose (full [x, y, z, rx, ry, rz] [m, rad]) with sagging cables under the required
    wrenches ``wreq`` (nv, n) [N, N m] (any wrench: a path's samples add inertia), minimum-norm
    tensions, through the per-pose kernel (:func:`cdpr_design.kernels.sagging.sag_pose`) called
    once: the reference of the batched kernels (the product evaluates poses in batches).

    Returns (feasible, margin [N], tensions (m,) [N], lengths (m,) [m], W (n, m), CableState).
    The margin is NaN unless the shapes converged.
    """
    from cdpr_design.kernels import sagging as KS
    from cdpr_design.kernels.sag_fixed import make_sag_scratch
    from cdpr_design.statics.cables import MAX_ITERATIONS, STATUS, CableState, sag_cables
    from cdpr_design.statics.robot import cable_arrays

    arr = cable_arrays(design)
    m, n = design.m, design.n
    R = kin.rotation_matrix(*full[3:])
    Rb = np.ascontiguousarray(design.attachments @ R.T)
    sc = make_sag_scratch(n, m, wreq.shape[0])
    out = KS.make_pose_outputs(m)
    robot = KS.sag_robot(design.outlets, sag_cables(arr, design.rows, design.tension_min, design.tension_max), wreq,
                         combos, kcode, MAX_ITERATIONS)
    st, feas, margin = KS.sag_pose(full[0], full[1], full[2], Rb, robot, out, sc, KS.redundancy(n, m))
    t, ta, l0, sg, L, W = out.t, out.outlet, out.L0, out.sag, out.lengths, sc.fixed.W
    return bool(feas), float(margin), t, L, W, CableState(ta, l0, sg, STATUS[st])
