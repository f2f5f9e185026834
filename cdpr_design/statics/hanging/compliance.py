"""The stiffness of a hanging effector at its hanging pose: stability, compliance, least stiffness.

At an equilibrium of a hanging effector (:mod:`cdpr_design.statics.hanging.at_positions`)
the cables' unstretched lengths are held by the winches, and a small displacement
x = (dp [m], w [rad]) of the effector (R -> exp([w]) R, the rotation about the platform
origin p) changes its potential energy to second order by x^T K x / 2, with

    K = H_L + sum_i k_i g_i g_i^T      (elastic cables, taut)

H_L the Hessian of the Lagrangian U + sum t_i |l_i| (the weight and the cables' geometric
terms, :meth:`~cdpr_design.statics.hanging.geometry.Geometry.lagrangian_hessian_many`),
g_i = d|l_i|/dx = (-u_i, -(R b_i) x u_i) and k_i = EA_i / L0_i = (EA_i + t_i) / L_i the
cable's axial stiffness at its unstretched length L0_i = L_i / (1 + t_i / EA_i).  K is the
stiffness matrix -dw/dx of the wrench w on the effector (moments about p) at fixed
unstretched lengths.  A rigid cable (ideal, EA = inf) is a constraint g_i . x = 0 instead:
K is then taken on the tangent space of the rigid taut cables' constraints, the reduced
Hessian of Carricato & Merlet (2013) that the hanging search judges stability by.  A cable
without tension (slack, or just slack: its length is its distance) adds nothing: a slack
cable resists no displacement, and a just slack one only those that stretch it (the softer
side is reported).

The equilibrium is stable when K (on the tangent space) is positive definite (its smallest
eigenvalue above 1e-9 of the weight, the hanging search's tolerance).  Then the
*compliance* C [m/N, rad/(N m)] maps a small wrench (f, m) applied about p to the
displacement it causes, x = C (f, m): C = K^-1 for elastic cables, Z (Z^T K Z)^-1 Z^T
for rigid ones (Z an orthonormal basis of the tangent space; C is zero along the rigid
cables).  The figures reported:

- ``min_stiffness`` [N/m]: 1 / the largest eigenvalue of C's translational block, the least
  stiffness against a force at p with the effector free to turn (the Schur complement of
  :func:`cdpr_design.kernels.stiffness.least_stiffness` for a fixed effector);
- ``min_rotational_stiffness`` [N m/rad]: 1 / the largest eigenvalue of C's rotational
  block, the least stiffness against a moment, the effector free to move;
- ``lowest_frequency`` [Hz]: the lowest natural frequency of K v = omega^2 M v on the
  tangent space, M the effector's rigid-body mass matrix at p (cable mass neglected).

Infinite stiffness (a displacement the rigid cables forbid entirely) is reported as inf;
NaN where the pose is unstable or the mass matrix is singular (frequency).  Units: SI.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cdpr_design.statics.hanging import geometry as hg


@dataclass
class HangingStiffness:
    """The stiffness of k hanging poses over ``dofs`` (d of them; see the module doc).

    ``stable`` (k,) bool; ``hessian_min`` (k,) the smallest eigenvalue of K on the tangent
    space (inf when the rigid cables lock the pose) [N/m, N m/rad mixed]; ``matrix`` (k, d, d)
    K [N/m, N/rad, N m/m, N m/rad]; ``compliance`` (k, d, d) C (NaN where unstable);
    ``min_stiffness`` (k,) [N/m]; ``min_rotational_stiffness`` (k,) [N m/rad] (NaN for a point
    mass, which has no rotation); ``lowest_frequency`` (k,) [Hz]; ``frequencies`` (k, r) [Hz]
    ascending, r the dimension of the tangent space (NaN-padded where it is smaller).
    """

    stable: np.ndarray
    hessian_min: np.ndarray
    matrix: np.ndarray
    compliance: np.ndarray
    min_stiffness: np.ndarray
    min_rotational_stiffness: np.ndarray
    lowest_frequency: np.ndarray
    frequencies: np.ndarray


def translations(dofs) -> int:
    """How many of ``dofs`` (indices of (dx, dy, dz, wx, wy, wz)) are translations (they come first)."""
    return sum(1 for j in dofs if j < 3)


def energy_hessian_many(geo: hg.Geometry, P, R, t, EA, dofs) -> np.ndarray:
    """K (k, d, d) of the module doc over ``dofs`` at k poses: P (k, 3) [m], R (k, 3, 3), tensions
    t (k, m) [N] (0 for a slack cable), ``EA`` (m,) [N] axial stiffnesses (inf: a rigid cable,
    which adds only its geometric term here)."""
    P = np.asarray(P, float).reshape(-1, 3)
    R = np.asarray(R, float).reshape(-1, 3, 3)
    t = np.asarray(t, float).reshape(-1, geo.m)
    cables = geo.cables_many(P, R)
    K = geo.lagrangian_hessian_many(P, R, t, cables)
    Rb, _, L, u = cables
    EA = np.broadcast_to(np.asarray(EA, float), (geo.m,))
    elastic = (t > 0.0) & np.isfinite(EA)[None, :]
    if elastic.any():
        with np.errstate(invalid="ignore", divide="ignore"):
            k = np.where(elastic, (np.where(np.isfinite(EA), EA, 0.0)[None, :] + t) / L, 0.0)
        g = -np.concatenate([np.where(elastic[..., None], u, 0.0),
                             np.where(elastic[..., None], np.cross(Rb, u), 0.0)], axis=2)
        K = K + np.einsum("km,kmi,kmj->kij", k, g, g)
    dofs = list(dofs)
    K = K[:, dofs][:, :, dofs]
    return 0.5 * (K + K.transpose(0, 2, 1))


def mass_matrix_many(mass: float, com, inertia, R, dofs) -> np.ndarray:
    """The effector's rigid-body mass matrices (k, d, d) [kg, kg m, kg m^2] at p for rotations R
    (k, 3, 3): [[m I, -m [R c]x], [m [R c]x, R I_c R^T - m [R c]x [R c]x]] (``com`` c (3,) [m] in
    platform coordinates, ``inertia`` I_c (3, 3) [kg m^2] about the centre of mass), over ``dofs``."""
    R = np.asarray(R, float).reshape(-1, 3, 3)
    S = hg.skew(np.einsum("kij,j->ki", R, np.asarray(com, float)))
    M = np.zeros((len(R), 6, 6))
    M[:, :3, :3] = mass * np.eye(3)
    M[:, :3, 3:] = -mass * S
    M[:, 3:, :3] = mass * S
    M[:, 3:, 3:] = R @ np.asarray(inertia, float) @ R.transpose(0, 2, 1) - mass * S @ S
    dofs = list(dofs)
    return M[:, dofs][:, :, dofs]


def hanging_stiffness(geo: hg.Geometry, P, R, t, dofs, EA=None, inertia=None) -> HangingStiffness:
    """:class:`HangingStiffness` of k hanging poses: positions P (k, 3) [m], rotations R (k, 3, 3),
    tensions t (k, m) [N] (a cable is taut above 1e-9 of the weight), over ``dofs``; ``EA`` (m,)
    [N] the cables' axial stiffnesses (None or inf: rigid cables, the reduced Hessian);
    ``inertia`` (3, 3) [kg m^2] about the centre of mass (None: no frequencies).  Rows with a NaN
    rotation (no hanging pose) are NaN and not stable."""
    P = np.asarray(P, float).reshape(-1, 3)
    R = np.asarray(R, float).reshape(-1, 3, 3)
    t = np.asarray(t, float).reshape(-1, geo.m)
    EA = np.full(geo.m, np.inf) if EA is None else np.broadcast_to(np.asarray(EA, float), (geo.m,))
    ok = np.isfinite(R).all(axis=(1, 2)) & np.isfinite(t).all(axis=1)
    taut = np.maximum(np.where(ok[:, None], t, 0.0), 0.0) > 1e-9 * geo.weight
    tt = np.where(taut, np.where(ok[:, None], t, 0.0), 0.0)
    Rs = np.where(ok[:, None, None], R, np.eye(3))
    K = energy_hessian_many(geo, P, Rs, tt, EA, dofs)
    # the rigid taut cables' constraints: the tangent space is the null space of their gradients
    Rb, _, _, u = geo.cables_many(P, Rs)
    G = -np.concatenate([u, np.cross(Rb, u)], axis=2)[:, :, list(dofs)]
    G = np.where((taut & ~np.isfinite(EA)[None, :])[..., None], G, 0.0)
    return stiffness_of(geo, K, G, ok, dofs, Rs, inertia)


def stiffness_of(geo: hg.Geometry, K, G, ok, dofs, R, inertia=None) -> HangingStiffness:
    """:class:`HangingStiffness` from the stiffness matrices K (k, d, d) over ``dofs`` of k poses and
    the gradients G (k, c, d) of their rigid constraints (rows of zeros: none), at rotations R
    (k, 3, 3); rows where ``ok`` (k,) is False are NaN and not stable."""
    k, d = len(K), len(dofs)
    ok = np.asarray(ok, bool)
    R = np.where(ok[:, None, None], R, np.eye(3))
    K = np.where(ok[:, None, None], K, 0.0)
    if G.shape[1]:
        _, sv, Vt = np.linalg.svd(G)
        rank = np.sum(sv > 1e-10 * np.maximum(1.0, sv[:, :1]), axis=1)
    else:
        Vt, rank = np.broadcast_to(np.eye(d), (k, d, d)), np.zeros(k, int)
    out = HangingStiffness(np.zeros(k, bool), np.full(k, np.nan), K, np.full((k, d, d), np.nan),
                           np.full(k, np.nan), np.full(k, np.nan), np.full(k, np.nan), np.full((k, d), np.nan))
    M = None if inertia is None else mass_matrix_many(geo.mass, geo.c, inertia, R, dofs)
    nt = translations(dofs)
    for r in np.unique(rank[ok]):
        rows = np.flatnonzero(ok & (rank == r))
        if r >= d:  # locked by rigid cables: no displacement is allowed
            out.stable[rows], out.hessian_min[rows] = True, np.inf
            out.compliance[rows] = 0.0
            _figures(out, rows, nt, d)
            continue
        Z = Vt[rows, r:].transpose(0, 2, 1)  # (n, d, d - r): the tangent space
        Kr = Z.transpose(0, 2, 1) @ K[rows] @ Z
        Kr = 0.5 * (Kr + Kr.transpose(0, 2, 1))
        h = np.linalg.eigvalsh(Kr)[:, 0]
        out.hessian_min[rows] = h
        good = h > 1e-9 * geo.weight
        out.stable[rows] = good
        rows, Z, Kr = rows[good], Z[good], Kr[good]
        if not rows.size:
            continue
        out.compliance[rows] = Z @ np.linalg.solve(Kr, Z.transpose(0, 2, 1))
        _figures(out, rows, nt, d)
        if M is not None:
            out.frequencies[rows, : d - r] = _frequencies(Kr, Z.transpose(0, 2, 1) @ M[rows] @ Z)
    out.lowest_frequency = out.frequencies[:, 0].copy()
    out.matrix = np.where(ok[:, None, None], K, np.nan)
    return out


def _figures(out: HangingStiffness, rows, nt: int, d: int) -> None:
    """The least translational and rotational stiffness of ``rows`` from their compliance."""
    C = out.compliance[rows]
    with np.errstate(divide="ignore"):
        out.min_stiffness[rows] = 1.0 / np.linalg.eigvalsh(C[:, :nt, :nt])[:, -1]
        if d > nt:
            out.min_rotational_stiffness[rows] = 1.0 / np.linalg.eigvalsh(C[:, nt:, nt:])[:, -1]
    # a compliance of exactly 0 (or round-off below it) is an infinite stiffness
    for name in ("min_stiffness", "min_rotational_stiffness"):
        v = getattr(out, name)
        v[rows] = np.where(v[rows] > 0.0, v[rows], np.where(np.isnan(v[rows]), np.nan, np.inf))


def _frequencies(Kr, Mr) -> np.ndarray:
    """Natural frequencies [Hz] (n, r) ascending of Kr y = omega^2 Mr y (stacked, Kr positive
    definite); NaN rows where Mr is not positive definite."""
    out = np.full(Kr.shape[:2], np.nan)
    ev = np.linalg.eigvalsh(Mr)
    good = ev[:, 0] > 1e-12 * np.maximum(ev[:, -1], 1e-300)
    if good.any():
        Lc = np.linalg.cholesky(Mr[good])
        Li = np.linalg.inv(Lc)
        A = Li @ Kr[good] @ Li.transpose(0, 2, 1)
        w2 = np.linalg.eigvalsh(0.5 * (A + A.transpose(0, 2, 1)))
        out[good] = np.sqrt(np.maximum(w2, 0.0)) / (2.0 * np.pi)
    return out
