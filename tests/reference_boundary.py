"""Exact areas and volumes of point-mass workspaces, the references of tests/test_boundary.py.

A point mass m under gravity g hangs from cables to outlets a_i all at one height H (above it).
At rest t_i (a_i - p) / |a_i - p| summed over the cables balances m g up.  Write t_i = lambda_i
|a_i - p|: the vertical rows give sum lambda_i = m g / h (h = H - the height of p) and the
horizontal ones sum lambda_i (a_i - p) = 0 horizontally, so lambda_i = beta_i m g / h with
beta_i the barycentric coordinates of p's horizontal position in the outlets' segment (two
cables, planar) or triangle (three cables, spatial).  Hence

    t_i = beta_i m g sqrt(d_i^2 + h^2) / h,     d_i the horizontal distance from p to a_i,

which falls from infinity (h -> 0) to beta_i m g (h -> infinity).  So t_i >= 0 is beta_i >= 0
(p under the segment or triangle), t_i <= t_max is h >= f d_i / sqrt(t_max^2 - f^2) and
t_i >= t_min > f is h <= f d_i / sqrt(t_min^2 - f^2), with f = beta_i m g < t_max.  Over each
horizontal position the feasible heights are one interval; the area (volume) is the integral
of its length (clipped by the grid's box) over the segment (triangle).  The seed paper's robot
(designs/planar2.yaml) is such a point mass: its effector does not turn (motion 2T), so each
cable acts as from the outlet a_i - b_i to the effector's origin.
"""

from __future__ import annotations

import numpy as np
from scipy import integrate


def heights(beta, d, mg: float, tmin: float, tmax: float):
    """The feasible interval (h_lo, h_hi) of the depth h below the outlets, per horizontal
    position: ``beta`` and ``d`` (..., m) the barycentric coordinates and horizontal distances."""
    f = np.asarray(beta) * mg
    with np.errstate(divide="ignore", invalid="ignore"):
        lo = np.where(f >= tmax, np.inf, f * d / np.sqrt(np.maximum(tmax ** 2 - f ** 2, 0.0)))
        hi = np.where(tmin > f, f * d / np.sqrt(np.maximum(tmin ** 2 - f ** 2, 1e-300)), np.inf)
    return lo.max(axis=-1), hi.min(axis=-1)


def planar_area(x1: float, x2: float, H: float, mg: float, tmin: float, tmax: float,
                ylo: float, yhi: float) -> float:
    """Area [m^2] of the feasible set of a point mass on two cables from (x1, H) and (x2, H),
    x1 < x2, within ylo <= y <= yhi (adaptive quadrature, about 1e-12 relative)."""

    def length(x):
        beta = np.array([(x2 - x) / (x2 - x1), (x - x1) / (x2 - x1)])
        d = np.array([x - x1, x2 - x])
        lo, hi = heights(beta, d, mg, tmin, tmax)
        return max(0.0, min(yhi, H - lo) - max(ylo, H - hi))

    # the integrand's kinks: where the two cables' bounds swap, and where f = t_min
    kinks = [(x1 + x2) / 2]
    for frac in (tmin / mg,) if 0 < tmin < mg else ():
        kinks += [x1 + frac * (x2 - x1), x2 - frac * (x2 - x1)]
    v, _ = integrate.quad(length, x1, x2, points=sorted(kinks), limit=1000, epsabs=1e-13, epsrel=1e-12)
    return v


def spatial_volume(outlets, H: float, mg: float, tmax: float, zlo: float, zhi: float, ymax: float,
                   n: int = 1500) -> float:
    """Volume [m^3] of the feasible set (t_min = 0) of a point mass on three cables from the
    triangle ``outlets`` (3, 2) at height H, with zlo <= z <= zhi and y <= ``ymax`` (the triangle's
    third vertex above ``ymax``, its first two below): the triangle's integral minus that of the
    part above ``ymax``, each by the midpoint rule on n x n points of the square Duffy-mapped onto
    it (the integrand is continuous there; about 1e-8 relative at n = 1500)."""
    A = np.asarray(outlets, float)
    T = np.array([[A[0, 0] - A[2, 0], A[1, 0] - A[2, 0]], [A[0, 1] - A[2, 1], A[1, 1] - A[2, 1]]])
    Ti = np.linalg.inv(T)

    def depth(x, y):
        l0 = Ti[0, 0] * (x - A[2, 0]) + Ti[0, 1] * (y - A[2, 1])
        l1 = Ti[1, 0] * (x - A[2, 0]) + Ti[1, 1] * (y - A[2, 1])
        beta = np.clip(np.stack([l0, l1, 1 - l0 - l1], -1), 0.0, None)
        d = np.hypot(x[..., None] - A[:, 0], y[..., None] - A[:, 1])
        lo, _ = heights(beta, d, mg, 0.0, tmax)
        return np.clip(np.minimum(zhi, H - lo) - zlo, 0.0, None)

    def over(P0, P1, P2):
        u = (np.arange(n) + 0.5) / n
        J = abs((P0[0] - P2[0]) * (P1[1] - P2[1]) - (P0[1] - P2[1]) * (P1[0] - P2[0]))
        total = 0.0
        for uu in np.array_split(u, 10):
            U, S = np.meshgrid(uu, u, indexing="ij")
            V = (1 - U) * S
            x = P2[0] + U * (P0[0] - P2[0]) + V * (P1[0] - P2[0])
            y = P2[1] + U * (P0[1] - P2[1]) + V * (P1[1] - P2[1])
            total += float((depth(x, y) * (1 - U)).sum())
        return total * J / n ** 2

    t = (A[2, 1] - ymax) / (A[2, 1] - A[0, 1])
    apex = over(A[2] + (A[0] - A[2]) * t, A[2] + (A[1] - A[2]) * t, A[2]) if t > 0 else 0.0
    return over(A[0], A[1], A[2]) - apex
