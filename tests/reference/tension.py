"""The capacity margin of one pose straight from the hyperplane-shifting kernels (the reference
the pose evaluation's margin is held to)."""

from __future__ import annotations

import numpy as np

from cdpr_design import kernels as K
from tests.reference.hsm import square_eval


def _arr(x, shape=None) -> np.ndarray:
    a = np.ascontiguousarray(x, dtype=float)
    return a.reshape(shape) if shape is not None else a


def capacity_margin(W, wreq, tmin, tmax) -> float:
    """Capacity margin [N] of the wrenches ``wreq`` (hyperplane shifting kernel).

    The smallest signed distance from a required wrench to a facet of the
    available wrench set {W t : t_min <= t <= t_max}; negative = the largest
    facet violation; NaN when rank W < n.
    """
    W = _arr(W)
    n, m = W.shape
    wreq = _arr(wreq).reshape(-1, n)
    if m == n:
        t = np.empty(m)
        ok, mg = square_eval(W, wreq, _arr(tmin, (m,)), _arr(tmax, (m,)), t)
        return float(mg) if ok else float("nan")
    scr = K.make_scratch(n, m, wreq.shape[0])
    if m < n or not K.basis_factor(W, scr[0], scr[18], scr[19], scr[20]):
        return float("nan")
    _, mg, _ = K.hsm_factored(W, wreq, wreq.shape[0], _arr(tmin, (m,)), _arr(tmax, (m,)), scr, False)
    return float(mg)
