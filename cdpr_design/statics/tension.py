"""Tension distribution, capacity margin and wrench closure (numpy / cvxpy API).

Two layers:

- the exact numba kernels of :mod:`cdpr_design.kernels` (hyperplane
  shifting on a basis factorisation of W, and the Goldfarb-Idnani active-set
  solution of the minimum 2-norm tension problem), wrapped here for one
  pose or one structure matrix;
- cvxpy problem definitions (:func:`solve_cvxpy`) for every objective the
  ``pose --objective`` option offers (2-norm, infinity-norm and 1-norm of the
  tensions, each optionally weighted).  They cover what the kernels do not
  and are the reference the kernels are tested against.

References
----------
Gouttefarde & Krut, "Characterization of parallel manipulator available
wrench set facets", ARK 2010; Bouchard, Gosselin & Moore, ASME J. Mech.
Robotics 2(1), 2010 (hyperplane shifting); Guay, Cardou, Cruz-Ruiz & Caro,
ICRA 2014 (capacity margin); Goldfarb & Idnani, Math. Programming 27, 1983
(dual active-set QP).
"""

from __future__ import annotations

import numpy as np

from cdpr_design import kernels as K
from cdpr_design.statics.robot import KINDS, combinations

OBJECTIVES = ("min-norm", "min-max", "min-sum")


def _osqp_polish_key() -> str:
    try:
        from importlib.metadata import version
        return "polishing" if int(version("osqp").split(".")[0]) >= 1 else "polish"
    except Exception:  # pragma: no cover - metadata missing
        return "polish"


_OSQP_POLISH = _osqp_polish_key()


def _arr(x, shape=None) -> np.ndarray:
    a = np.ascontiguousarray(np.asarray(x, dtype=float))
    if shape is not None:
        a = a.reshape(shape)
    return a


def _check_weights(weights, m: int) -> np.ndarray | None:
    if weights is None:
        return None
    w = np.asarray(weights, dtype=float).reshape(-1)
    if w.size != m:
        raise ValueError(f"weights: expected {m} numbers (one per cable), got {w.size}")
    if not np.all(np.isfinite(w)) or np.any(w <= 0):
        raise ValueError("weights: expected finite positive numbers")
    return w


# ----------------------------------------------------------------------------
# Kernel wrappers (one structure matrix)
# ----------------------------------------------------------------------------


def evaluate(W, wreq, tmin, tmax, kind: str = "static") -> tuple[bool, float, np.ndarray]:
    """Feasibility, capacity margin [N] and min 2-norm tensions [N] for one W.

    Parameters
    ----------
    W : (n, m) structure matrix.
    wreq : (nv, n) or (n,) required wrenches W t = w [N, N m]; row 0 is the
        nominal one (its tensions are returned).
    tmin, tmax : (m,) tension bounds [N].
    kind : 'static' (row 0 only), 'wrench-feasible' (every row must be
        feasible) or 'wrench-closure' (positive spanning, bounds ignored).

    Returns
    -------
    feasible : bool
    margin : float
        Capacity margin (hyperplane shifting), NaN when rank W < n.
    tensions : (m,) array
        Minimum 2-norm feasible tensions at row 0, NaN where there are none.
    """
    W = _arr(W)
    n, m = W.shape
    wreq = _arr(wreq).reshape(-1, n)
    t = np.empty(m)
    f, mg = K.eval_pose(W, wreq, _arr(tmin, (m,)), _arr(tmax, (m,)), combinations(m, n),
                        KINDS[kind], t)
    return bool(f), float(mg), t


def min_norm(W, w, tmin, tmax, weights=None) -> np.ndarray | None:
    """Exact minimum (weighted) 2-norm tensions: min sum_i c_i t_i^2, W t = w, bounds.

    Weights c_i > 0 are handled by the change of variables t'_i = sqrt(c_i) t_i
    (W' = W diag(c)^-1/2, bounds scaled), which keeps the problem a projection.
    Returns None when no tensions within the bounds balance w, or rank W < n.
    Solved by the Goldfarb-Idnani kernel (:func:`cdpr_design.kernels.min_norm_tensions`).
    """
    W = _arr(W)
    n, m = W.shape
    tmin, tmax = _arr(tmin, (m,)), _arr(tmax, (m,))
    c = _check_weights(weights, m)
    s = np.ones(m) if c is None else np.sqrt(c)
    Ws = np.ascontiguousarray(W / s[None, :])
    t = np.empty(m)
    ok = K.min_norm_tensions(Ws, _arr(w, (n,)), tmin * s, tmax * s, t, K.make_scratch(n, m, 1))
    if not ok:
        return None
    return np.clip(t / s, tmin, tmax)



def wrench_closure(W) -> bool:
    """True when the columns of W positively span R^n (rank n and W t = 0 for some t > 0)."""
    W = _arr(W)
    n, m = W.shape
    if m <= n:
        return False
    scr = K.make_scratch(n, m, 1)
    if not K.basis_factor(W, scr[0], scr[18], scr[19], scr[20]):
        return False
    zeros = np.zeros((1, n))
    _, _, closure = K.hsm_factored(W, zeros, 1, np.zeros(m), np.ones(m), scr, True)
    return bool(closure)


def min_norm_many(W, wrenches, tmin, tmax) -> np.ndarray:
    """Exact minimum 2-norm tensions of one W for several wrenches: (k, n) -> (k, m) [N].

    Row k solves min |t|^2, W t = wrenches[k], t_min <= t <= t_max with the
    Goldfarb-Idnani kernel (:func:`cdpr_design.kernels.min_norm_tensions`,
    one scratch for every row); NaN rows where the bounds admit none or
    rank W < n.  The bounds must be finite (the kernel's tolerance scales
    with them): see :func:`min_norm_above` for lower bounds only.
    """
    W = _arr(W)
    n, m = W.shape
    wrenches = _arr(wrenches).reshape(-1, n)
    tmin, tmax = _arr(tmin, (m,)), _arr(tmax, (m,))
    out = np.full((wrenches.shape[0], m), np.nan)
    scr = K.make_scratch(n, m, 1)
    t = np.empty(m)
    for k in range(wrenches.shape[0]):
        if K.min_norm_tensions(W, wrenches[k], tmin, tmax, t, scr):
            out[k] = t
    return out


def min_norm_above(W, w, tmin) -> np.ndarray | None:
    """Exact minimum 2-norm tensions with lower bounds only: min |t|^2, W t = w, t >= t_min [N].

    The Goldfarb-Idnani kernel with infinite upper bounds (its tolerance is
    taken from the finite bounds).  None when rank W < n or no tensions above
    t_min balance w; a result that does not balance w to 1e-9 (relative) is
    never returned.
    """
    W = _arr(W)
    n, m = W.shape
    w, tmin = _arr(w, (n,)), _arr(tmin, (m,))
    t = np.empty(m)
    if not K.min_norm_tensions(W, w, tmin, np.full(m, np.inf), t, K.make_scratch(n, m, 1)):
        return None
    if np.linalg.norm(W @ t - w) > 1e-9 * (1.0 + np.linalg.norm(w)):
        return None
    return t


# ----------------------------------------------------------------------------
# cvxpy problem definitions (the reference, and the other objectives)
# ----------------------------------------------------------------------------


def cvxpy_problem(W, w, tmin, tmax, objective: str = "min-norm", weights=None):
    """The tension distribution problem as a cvxpy Problem and its variable.

    ``objective``: 'min-norm' (min sum_i c_i t_i^2), 'min-max'
    (min max_i c_i t_i) or 'min-sum' (min sum_i c_i t_i), with weights c
    (default 1); subject to W t = w and t_min <= t <= t_max.
    """
    import cvxpy as cp

    W = np.asarray(W, dtype=float)
    n, m = W.shape
    c = _check_weights(weights, m)
    c = np.ones(m) if c is None else c
    t = cp.Variable(m)
    if objective == "min-norm":
        obj = cp.Minimize(cp.sum(cp.multiply(c, cp.square(t))))
    elif objective == "min-max":
        obj = cp.Minimize(cp.max(cp.multiply(c, t)))
    elif objective == "min-sum":
        obj = cp.Minimize(c @ t)
    else:
        raise ValueError(f"objective: expected one of {', '.join(OBJECTIVES)}, got {objective!r}")
    cons = [W @ t == np.asarray(w, dtype=float).reshape(n),
            t >= np.asarray(tmin, dtype=float), t <= np.asarray(tmax, dtype=float)]
    return cp.Problem(obj, cons), t


def solve_cvxpy(W, w, tmin, tmax, objective: str = "min-norm", weights=None,
                solver: str | None = None, accurate: bool = False) -> np.ndarray | None:
    """Solve :func:`cvxpy_problem`; the tensions [N], or None when infeasible.

    Default solvers: OSQP (polished) for the 2-norm problem, Clarabel for
    the linear programs (min-max, min-sum).  ``accurate=True`` uses Clarabel
    with tight tolerances for every objective (the test oracle).
    """
    import cvxpy as cp

    prob, t = cvxpy_problem(W, w, tmin, tmax, objective, weights)
    if accurate or (solver or "").upper() == "CLARABEL":
        kw = dict(solver=cp.CLARABEL, tol_gap_abs=1e-12, tol_gap_rel=1e-12, tol_feas=1e-12)
    elif solver is not None:
        kw = dict(solver=solver.upper())
    elif objective == "min-norm":
        kw = dict(solver=cp.OSQP, eps_abs=1e-9, eps_rel=1e-9, max_iter=100000)
        kw[_OSQP_POLISH] = True
    else:
        kw = dict(solver=cp.CLARABEL)
    try:
        prob.solve(**kw)
    except cp.error.SolverError:
        return None
    if prob.status not in ("optimal", "optimal_inaccurate") or t.value is None:
        return None
    return np.clip(np.asarray(t.value, dtype=float), tmin, tmax)


def tensions_for_objective(W, w, tmin, tmax, objective: str = "min-norm", weights=None,
                           solver: str | None = None) -> np.ndarray | None:
    """Tensions [N] balancing the wrench ``w`` within the bounds [N], optimal for ``objective``.

    'min-norm': the exact (weighted) 2-norm kernel (:func:`min_norm`);
    'min-max' / 'min-sum': the infinity- / 1-norm with cvxpy (:func:`solve_cvxpy`).
    ``weights``: (m,) positive per-cable weights.  None when infeasible.
    """
    if objective == "min-norm":
        return min_norm(W, w, tmin, tmax, weights=weights)
    return solve_cvxpy(W, w, tmin, tmax, objective, weights, solver=solver)
