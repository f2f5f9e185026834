"""The capacity margin by plain hyperplane shifting, and the square closed form allocating its
own work arrays, compiled with numba: the references the tests (and the benchmarks' per-pose
baseline) compare the product's factored kernels against.  The product never imports it.

References
----------
M. Gouttefarde, S. Krut, "Characterization of parallel manipulator available wrench set
facets", Advances in Robot Kinematics (ARK), 2010.  S. Bouchard, C. Gosselin, B. Moore, "On
the ability of a cable-driven robot to generate a prescribed set of wrenches", ASME Journal
of Mechanisms and Robotics 2(1), 2010.
"""

from __future__ import annotations

import numba
import numpy as np

from cdpr_design.kernels.hsm import facet_normal, square_eval_into, square_work
from cdpr_design.kernels.linalg import RANK_TOL

#: numba's documented options only: compiled on first use, cached on disk
njit = numba.njit(cache=True)


@njit
def square_eval(W, wreq, tmin, tmax, t):
    """Tensions and capacity margin of a square structure matrix.

    For m = n the tensions are unique, t = W^-1 w, and the capacity margin is
    min_i min(t_i - t_min,i, t_max,i - t_i) / ||row_i(W^-1)||_2, minimised over
    the required-wrench vertices (rows of ``wreq``); ``t`` receives the
    tensions for the first vertex.  Returns (rank_ok, margin).  This equals the
    hyperplane-shifting margin (the facet normals of a parallelotope are the
    rows of W^-1).
    """
    Winv, rn, a = square_work(W.shape[0])
    return square_eval_into(W, wreq, tmin, tmax, t, Winv, rn, a)


@njit
def hsm_margin(W, wreq, tmin, tmax, combos):
    """Capacity margin by the hyperplane shifting method.

    Gouttefarde & Krut, ARK 2010; Bouchard, Gosselin & Moore, ASME JMR 2010;
    Guay et al. 2014 (capacity margin).  For every subset S of n-1 columns of
    rank n-1, with unit normal nu and l_j = nu . w_j:

        s_S(w) = 1/2 sum_j |l_j| (t_max,j - t_min,j) - |nu . (W t_mid - w)|

    The margin is min over S and over the required-wrench vertices ``wreq``
    (nv, n).  Returns (rank_ok, margin); rank_ok is False (margin NaN) when W
    has rank < n.  A negative margin is the largest facet violation.
    """
    n, m = W.shape
    nv = wreq.shape[0]
    nu = np.empty(n)
    wmid = np.empty(n)
    for i in range(n):
        s = 0.0
        for j in range(m):
            s += W[i, j] * 0.5 * (tmin[j] + tmax[j])
        wmid[i] = s
    rank_ok = False
    margin = np.inf
    for c in range(combos.shape[0]):
        if not facet_normal(W, combos[c], nu):
            continue
        half = 0.0
        lmax = 0.0
        for j in range(m):
            lj = 0.0
            for i in range(n):
                lj += nu[i] * W[i, j]
            lj = abs(lj)
            if lj > lmax:
                lmax = lj
            half += 0.5 * lj * (tmax[j] - tmin[j])
        if lmax > RANK_TOL:
            rank_ok = True
        cmid = 0.0
        for i in range(n):
            cmid += nu[i] * wmid[i]
        for k in range(nv):
            cw = 0.0
            for i in range(n):
                cw += nu[i] * wreq[k, i]
            s = half - abs(cmid - cw)
            if s < margin:
                margin = s
    if not rank_ok:
        return False, np.nan
    return True, margin
