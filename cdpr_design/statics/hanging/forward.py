"""Where an effector rests for given cable lengths: the forward geometrico-static problem.

A cable can pull but never push, and a cable of length rho_i only keeps its
attachment within rho_i of its outlet.  For given cable lengths the effector
therefore rests where its potential energy

    U = -m g . (p + R c)            [J]

is smallest among the configurations with every |a_i - p - R b_i| <= rho_i
(Carricato & Merlet 2013; Abbasnejad & Carricato 2015).  At such a minimum
the taut cables' tensions are the Lagrange multipliers of the length
constraints: t_i >= 0, force and moment balance hold, and a slack cable
carries nothing.  An equilibrium is *stable* when the Hessian of the
Lagrangian U + sum t_i (|l_i| - rho_i) is positive definite on the tangent
space of the taut cables' constraints (the reduced Hessian of Carricato &
Merlet 2013).

:func:`fk_arrays` finds the lowest equilibrium and every other stable one
found, with its orientation among the unknowns; :func:`fk_held_arrays` the
same with the orientation held (the convex, translational problem).  On
plain arrays; :mod:`cdpr_design.statics.hanging.design` asks them for a
design.

Units: SI throughout (m, kg, N, rad).  Frame and effector conventions as in
docs/spec-format.md; planar designs live in the z = 0 plane with rotations
about z.  Swivel pulleys are not modelled here (point outlets).

References
----------
M. Carricato, J.-P. Merlet, "Stability analysis of underconstrained
cable-driven parallel robots", IEEE Transactions on Robotics 29(1),
288-296, 2013.
G. Abbasnejad, M. Carricato, "Direct geometrico-static problem of
underconstrained cable-driven parallel robots with n cables", IEEE
Transactions on Robotics 31(2), 468-478, 2015.
"""

from __future__ import annotations

import math

import numpy as np

from cdpr_design.errors import InputError
from cdpr_design.model.design import is_point_mass, is_underconstrained
from cdpr_design.model.limits import lengths_problem
from cdpr_design.statics.hanging import geometry as hg
from cdpr_design.statics.hanging import refine as rf
from cdpr_design.statics.hanging.results import Equilibrium, HangingFK, UnreachableLengths


# ----------------------------------------------------------------------------
# checks of the lengths
# ----------------------------------------------------------------------------

def _dofs(geo, planar):
    if is_point_mass(geo.B):
        return hg.DOFS_POINT2 if planar else hg.DOFS_POINT3
    return hg.DOFS_PLANAR if planar else hg.DOFS_SPATIAL


def _tolerances(geo, rho):
    ltol = 1e-9 * max(1.0, float(np.max(rho)))
    return ltol, 1e-10 * max(1.0, geo.weight)


def _name(names, i) -> str:
    return str(names[i]) if names is not None else str(i)


def _check_pairs(geo, rho, ltol, names=None):
    """Raise :class:`UnreachableLengths` for a pair of cables that cannot both reach."""
    why = lengths_problem(rho)
    if why:
        raise InputError(why)
    if np.any(rho < 1e-6):
        raise InputError(f"cable {_name(names, int(np.argmin(rho)))} is shorter than 1 micrometre: its "
                         "attachment would be pinned at its outlet, which the cable model does not cover")
    for i in range(geo.m):
        for j in range(i + 1, geo.m):
            d = float(np.linalg.norm(geo.A[i] - geo.A[j]))
            reach = rho[i] + rho[j] + float(np.linalg.norm(geo.B[i] - geo.B[j]))
            if d > reach + ltol:
                raise UnreachableLengths(
                    f"cables {_name(names, i)} and {_name(names, j)} cannot both reach the effector: their "
                    f"outlets are {d:.6g} m apart, more than the lengths {rho[i]:.6g} + {rho[j]:.6g} m plus the "
                    f"{reach - rho[i] - rho[j]:.6g} m between their attachments (short by {d - reach:.3g} m)")


def _lengths(geo, lengths, names):
    """The lengths as an (m,) array, checked; with the tolerances (length [m], force [N])."""
    rho = np.asarray(lengths, float).reshape(-1)
    if rho.size != geo.m:
        raise InputError(f"expected {geo.m} cable lengths, got {rho.size}")
    ltol, tol_f = _tolerances(geo, rho)
    _check_pairs(geo, rho, ltol, names)
    return rho, ltol, tol_f


# ----------------------------------------------------------------------------
# the forward geometrico-static problem
# ----------------------------------------------------------------------------

def _equilibrium(geo, rho, sol, dofs, planar) -> Equilibrium:
    p, R, t, S, rb, indet, rl = sol
    taut = [i for i in S if t[i] > 1e-9 * geo.weight]
    hmin = geo.reduced_hessian_min(p, R, t, taut, dofs)
    stable = bool(hmin > 1e-9 * geo.weight)
    d = 2 if planar else 3
    slack = tuple(i for i in range(geo.m) if t[i] <= 1e-9 * geo.weight)
    t = np.where(np.isin(np.arange(geo.m), slack), 0.0, t)
    return Equilibrium(p[:d].copy(), R, t, slack, geo.energy(p, R), stable, hmin, rb, rl, indet, planar,
                       hg.up_of(geo))


def _held(geo, rho, planar, R, ltol, tol_f, model):
    """The convex case, orientation R held (or irrelevant: a point mass): the platform
    origin is the lowest point of the balls |a_i - R b_i - p| <= rho_i."""
    d = 2 if planar else 3
    down = geo.g / np.linalg.norm(geo.g)
    C = (geo.A - geo.B @ R.T)[:, :d]
    x, ok, viol = hg.lowest_points(C[None], rho, down[:d], ltol)
    if not ok[0]:
        raise UnreachableLengths(
            "the balls |a_i - P| <= rho_i have no common point: every pair meets, but no point is "
            f"within reach of all cables (smallest excess {viol[0]:.3g} m)")
    q = np.zeros(3)
    q[:d] = x[0]
    dofs = hg.DOFS_POINT2 if planar else hg.DOFS_POINT3
    sol = rf.refine(geo, rho, q, R, dofs, tol_f, ltol)
    if sol is None:
        raise RuntimeError("held-orientation equilibrium: the active-set refinement failed")
    return HangingFK(**vars(_equilibrium(geo, rho, sol, dofs, planar)), equilibria=(), model=model,
                     underconstrained=is_underconstrained(geo.m, geo.B, planar))


def fk_held_arrays(A, B, c, mass, g, lengths, planar: bool, rotation, *, names=None) -> HangingFK:
    """:func:`fk_arrays` with the orientation held at ``rotation`` (3, 3): the translational
    geometrico-static problem, exact (the lowest point of an intersection of balls), then
    refined; tensions balance the force only (``model='held'``).  ``names`` label the
    cables in error messages."""
    geo = hg.checked_geometry(A, B, c, mass, g, planar)
    rho, ltol, tol_f = _lengths(geo, lengths, names)
    return _held(geo, rho, planar, np.asarray(rotation, float), ltol, tol_f, "held")


def _planar_starts(geo, rho, n_scan, nominal_phi, ltol):
    """Local minima of the exact energy profile E(phi) = min_p U over a circle of phi."""
    phis = np.sort(np.append(-math.pi + 2.0 * math.pi * np.arange(n_scan) / n_scan, nominal_phi))
    co, si = np.cos(phis), np.sin(phis)
    B2 = geo.B[:, :2]
    Rb = np.stack([co[:, None] * B2[:, 0] - si[:, None] * B2[:, 1],
                   si[:, None] * B2[:, 0] + co[:, None] * B2[:, 1]], axis=2)
    C = geo.A[None, :, :2] - Rb
    down = (geo.g / np.linalg.norm(geo.g))[:2]
    x, ok, viol = hg.lowest_points(C, rho, down, ltol)
    Rc = np.stack([co * geo.c[0] - si * geo.c[1], si * geo.c[0] + co * geo.c[1]], axis=1)
    E = np.where(ok, -geo.mass * ((x + Rc) @ geo.g[:2]), np.inf)
    starts = []
    n = len(phis)
    for k in range(n):
        minimum = np.isfinite(E[k]) and E[k] <= E[k - 1] and E[k] <= E[(k + 1) % n]
        plateau = E[k] == E[k - 1] and starts and starts[-1][0] == k - 1
        if minimum and not plateau:
            starts.append((k, np.r_[x[k], 0.0], hg.rot_z(phis[k])))
    if not starts:  # nothing feasible on the scan: try the least infeasible angles
        for k in np.argsort(viol)[:4]:
            starts.append((k, None, hg.rot_z(phis[k])))
    return [(p, R) for _, p, R in starts], float(np.min(viol))


def _spatial_starts(geo, rho, n_starts, nominal, ltol, seed):
    """Rotations sampled uniformly (plus identity and ``nominal``), the exact inner
    problem at each, and the lowest ``n_starts`` of them at least 30 deg apart."""
    rng = np.random.default_rng(seed)
    q = rng.normal(size=(2048, 4))
    q /= np.linalg.norm(q, axis=1)[:, None]
    w, xq, yq, zq = q.T
    Rs = np.stack([
        np.stack([1 - 2 * (yq ** 2 + zq ** 2), 2 * (xq * yq - zq * w), 2 * (xq * zq + yq * w)], -1),
        np.stack([2 * (xq * yq + zq * w), 1 - 2 * (xq ** 2 + zq ** 2), 2 * (yq * zq - xq * w)], -1),
        np.stack([2 * (xq * zq - yq * w), 2 * (yq * zq + xq * w), 1 - 2 * (xq ** 2 + yq ** 2)], -1)], axis=1)
    fixed = [np.eye(3)] + ([np.asarray(nominal, float)] if nominal is not None else [])
    Rs = np.concatenate([np.array(fixed), Rs])
    C = geo.A[None] - np.einsum("nij,mj->nmi", Rs, geo.B)
    down = geo.g / np.linalg.norm(geo.g)
    x, ok, viol = hg.lowest_points(C, rho, down, ltol)
    E = np.where(ok, -geo.mass * ((x + Rs @ geo.c) @ geo.g), np.inf)
    order = list(range(len(fixed))) + [k for k in np.argsort(E) if k >= len(fixed) and np.isfinite(E[k])]
    if not np.any(ok):
        order = list(range(len(fixed))) + list(np.argsort(viol)[:n_starts])
    chosen = []
    for k in order:
        if len(chosen) >= n_starts:
            break
        if any(hg.rotation_angle(Rs[k] @ Rs[j].T) < math.radians(30) for j in chosen) and k >= len(fixed):
            continue
        chosen.append(k)
    return [(x[k] if ok[k] else None, Rs[k]) for k in chosen], float(np.min(viol))


def _same(a: Equilibrium, b: Equilibrium, ls) -> bool:
    return (np.linalg.norm(a.position - b.position) < 1e-6 * (1 + ls)
            and hg.rotation_angle(a.rotation @ b.rotation.T) < 1e-6)


def fk_arrays(A, B, c, mass, g, lengths, planar: bool, *, nominal=None, n_scan: int = 720,
              n_starts: int = 12, seed: int = 0, names=None) -> HangingFK:
    """The resting configuration for cable ``lengths`` [m] (forward geometrico-static problem).

    ``A``, ``B`` (m, 2|3) outlets and attachments [m], ``c`` centre of mass in
    platform coordinates [m], ``mass`` [kg], ``g`` gravity [m/s^2],
    ``planar`` for designs in the z = 0 plane (rotation about z only).
    ``nominal`` (3, 3) is an extra start rotation (and the orientation of a
    point mass whose centre of mass is its attachment point).

    Method: a point mass (coincident attachments) solves the convex problem
    exactly (:func:`~cdpr_design.statics.hanging.geometry.lowest_points`).  A
    planar rigid body scans ``n_scan`` orientations; at each the lowest
    position is that exact convex problem, which gives the energy profile
    E(phi) = min_p U whose local minima are the stable equilibria.  A
    spatial rigid body evaluates E(R) on 2048 random rotations and starts
    SLSQP from the ``n_starts`` lowest ones at least 30 deg apart.  Every
    candidate is refined by Newton's method on force + moment balance and
    the taut lengths with an active set of cables (residual ~1e-10 N; SLSQP
    first where Newton alone does not reach a stable equilibrium), then
    tested for stability.  Where no start is feasible, a least-squares feasibility phase
    looks for a configuration first (locked poses of fully constrained robots).

    Raises :class:`UnreachableLengths` when no configuration satisfies every
    length (with the reason); ``names`` label the cables in the messages.
    """
    geo = hg.checked_geometry(A, B, c, mass, g, planar)
    rho, ltol, tol_f = _lengths(geo, lengths, names)
    if is_point_mass(geo.B):
        return _held(geo, rho, planar, hg.point_mass_rotation(geo, planar, nominal), ltol, tol_f, "point")
    dofs = _dofs(geo, planar)
    if planar:
        phi0 = 0.0 if nominal is None else math.atan2(nominal[1][0], nominal[0][0])
        starts, vmin = _planar_starts(geo, rho, n_scan, phi0, ltol)
    else:
        starts, vmin = _spatial_starts(geo, rho, n_starts, nominal, ltol, seed)
    found: list[Equilibrium] = []
    minimised = []  # SLSQP minima whose Newton refinement failed (fall-back)
    feasible_seen = False
    for p, R in starts:
        if p is None:
            guess = geo.A.mean(0) - R @ geo.B.mean(0)
            conf = rf.feasibility_phase(geo, rho, guess, R, dofs, ltol)
            if conf is None:
                continue
            p, R = conf
        feasible_seen = True
        # Newton first where the start is already close to an equilibrium: the planar
        # scan's minima, and configurations that as many taut cables as freedoms may lock
        near = np.count_nonzero(geo.cables(p, R)[2] >= rho - 1e-7)
        sol = rf.refine(geo, rho, p, R, dofs, tol_f, ltol) if planar or near >= len(dofs) else None
        if sol is None or not _is_minimum(geo, sol, dofs, rho, ltol):
            p2, R2 = rf.local_minimum(geo, rho, p, R, dofs)
            sol = rf.refine(geo, rho, p2, R2, dofs, tol_f, ltol)
            if sol is None and np.all(geo.cables(p2, R2)[2] <= rho + 1e3 * ltol):
                fallback = _unrefined(geo, rho, p2, R2, dofs)
                if fallback[4] <= 1e-6 * max(1.0, geo.weight):
                    minimised.append(fallback)
        if sol is None or np.any(geo.cables(sol[0], sol[1])[2] > rho + ltol):
            continue
        eq = _equilibrium(geo, rho, sol, dofs, planar)
        if not any(_same(eq, f, geo.size) for f in found):
            found.append(eq)
    if not feasible_seen:
        raise UnreachableLengths(
            "no configuration keeps every attachment within its cable length of its outlet "
            f"(smallest excess found {vmin:.3g} m over {len(starts)} starts)")
    if not found:  # Newton failed everywhere (near-singular geometry): keep SLSQP's minima
        found = [_equilibrium(geo, rho, sol, dofs, planar) for sol in minimised]
    if not found:
        raise RuntimeError("the equilibrium search failed from every start")
    # every candidate came out of a local minimisation: the lowest is where the effector
    # rests, even when it is only neutrally stable (a zero mode of the reduced Hessian)
    found.sort(key=lambda e: e.energy)
    best = found[0]
    others = tuple(e for e in found[1:] if e.stable)
    return HangingFK(**vars(best), equilibria=others, model="rigid",
                     underconstrained=is_underconstrained(geo.m, geo.B, planar))


def _unrefined(geo, rho, p, R, dofs):
    """A minimiser that Newton's method could not polish, in ``refine``'s format:
    non-negative least-squares tensions of the cables within 1e-7 m of their length."""
    dofs = list(dofs)
    L = geo.cables(p, R)[2]
    S = [int(i) for i in np.flatnonzero(L >= rho - 1e-7)]
    W, wg = geo.wrenches(p, R)
    t = np.zeros(geo.m)
    if S:
        t[S], _ = rf.nonnegative_tensions(W[np.ix_(dofs, S)], -wg[dofs])
    rb = float(np.max(np.abs(geo.balance(p, R, t)[dofs])))
    return p, R, t, S, rb, False, float(np.max(np.abs(L[S] - rho[S]), initial=0.0))


def _is_minimum(geo, sol, dofs, rho, ltol) -> bool:
    """A refined point that is a feasible, stable equilibrium (else SLSQP minimises first)."""
    p, R, t, S, rb, _, _ = sol
    taut = [i for i in S if t[i] > 1e-9 * geo.weight]
    return (rb <= 1e-8 * max(1.0, geo.weight) and np.all(geo.cables(p, R)[2] <= rho + ltol)
            and geo.reduced_hessian_min(p, R, t, taut, dofs) > 0)
