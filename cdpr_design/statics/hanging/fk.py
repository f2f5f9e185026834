"""Where an effector hangs: the geometrico-static problem of cable robots.

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
Merlet 2013).  A robot is *under-constrained* when its taut cables cannot
fix every free degree of freedom: fewer than 3 cables for a planar rigid
body, fewer than 6 for a spatial one, fewer than its dimension for a point
mass (an effector whose attachments coincide); then its orientation is not
commanded but follows from the lengths.

Three questions are answered here, on plain arrays (``*_arrays``) and, thin
on top, for a :class:`~cdpr_design.model.design.Design`:

* :func:`fk` - the equilibrium for given lengths (forward geometrico-static
  problem): pose, orientation, tensions, slack cables, stability and every
  other stable equilibrium found; :func:`fk_held_arrays` the same with the
  orientation held, and :func:`equilibrium` whichever of the two the spec's
  ``effector.orientation`` and motion ask for (the ``fk`` command);
* :func:`pose_at` - the orientation an under-constrained effector takes at a
  commanded position with its cables taut, or why it cannot hang there
  (:mod:`cdpr_design.statics.hanging_at`, which also runs it over many
  positions for the workspaces);
* :func:`tilt_map` - the same over a workspace grid for a planar body on two
  cables (batched numba kernel :mod:`cdpr_design.kernels.hanging`).

Units: SI throughout (m, kg, N, rad; ``tilt_deg`` in degrees).  Frame and
effector conventions as in docs/spec-format.md; planar designs live in the
z = 0 plane with rotations about z.  Swivel pulleys are not modelled here
(point outlets).

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

import dataclasses
import math

import numpy as np

from cdpr_design.errors import InputError
from cdpr_design.statics import hanging_at as ha
from cdpr_design.statics import hanging_core as hc
from cdpr_design.model.design import has_weight
from cdpr_design.statics.hanging_core import is_point_mass, is_underconstrained  # noqa: F401 - re-exported
from cdpr_design.statics.hanging_results import (  # noqa: F401 - re-exported
    Equilibrium, HangingAt, HangingFK, NotUnderconstrained, TiltMap, UnreachableLengths, orientation_of, tilt_of,
)


# ----------------------------------------------------------------------------
# classification
# ----------------------------------------------------------------------------

def check_weight(mass: float, g) -> None:
    """An :class:`InputError` naming ``effector.mass`` and ``gravity`` unless the effector has a weight:
    an under-constrained effector hangs from its cables under it (mass [kg] > 0, |g| [m/s^2] > 0)."""
    gn = float(np.linalg.norm(np.asarray(g, float)))
    if not has_weight(mass, g):
        raise InputError(f"effector.mass, gravity: an under-constrained effector hangs from its cables under its "
                         f"weight, so it needs effector.mass > 0 and a non-zero gravity (got {mass:g} kg and "
                         f"|gravity| = {gn:g} m/s^2)")


def _prepare(A, B, c, mass, g, planar):
    A = np.atleast_2d(np.asarray(A, float))
    B = np.atleast_2d(np.asarray(B, float))
    pad = lambda X: np.hstack([X, np.zeros((X.shape[0], 3 - X.shape[1]))]) if X.shape[1] < 3 else X
    A, B = pad(A), pad(B)
    c = np.concatenate([np.asarray(c, float).ravel(), np.zeros(3)])[:3]
    g = np.concatenate([np.asarray(g, float).ravel(), np.zeros(3)])[:3]
    if A.shape != B.shape or A.shape[0] < 1:
        raise InputError(f"outlets {A.shape} and attachments {B.shape} must both be (m, 3)")
    check_weight(mass, g)
    if planar and (np.any(A[:, 2] != 0) or np.any(B[:, 2] != 0) or c[2] != 0 or g[2] != 0):
        raise InputError("a planar design lives in the z = 0 plane")
    return hc.Geometry(A, B, c, mass, g)


def _up(geo) -> tuple:
    return tuple(float(v) for v in -geo.g / np.linalg.norm(geo.g))


def _dofs(geo, planar):
    if is_point_mass(geo.B):
        return hc.DOFS_POINT2 if planar else hc.DOFS_POINT3
    return hc.DOFS_PLANAR if planar else hc.DOFS_SPATIAL


def _tolerances(geo, rho):
    ltol = 1e-9 * max(1.0, float(np.max(rho)))
    return ltol, 1e-10 * max(1.0, geo.weight)


def _name(names, i) -> str:
    return str(names[i]) if names is not None else str(i)


def _check_pairs(geo, rho, ltol, names=None):
    """Raise :class:`UnreachableLengths` for a pair of cables that cannot both reach."""
    if np.any(~np.isfinite(rho)) or np.any(rho < 0):
        raise InputError("cable lengths must be finite and non-negative")
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
                       _up(geo))


def _held(geo, rho, planar, R, ltol, tol_f, model):
    """The convex case, orientation R held (or irrelevant: a point mass): the platform
    origin is the lowest point of the balls |a_i - R b_i - p| <= rho_i."""
    d = 2 if planar else 3
    down = geo.g / np.linalg.norm(geo.g)
    C = (geo.A - geo.B @ R.T)[:, :d]
    x, ok, viol = hc.lowest_points(C[None], rho, down[:d], ltol)
    if not ok[0]:
        raise UnreachableLengths(
            "the balls |a_i - P| <= rho_i have no common point: every pair meets, but no point is "
            f"within reach of all cables (smallest excess {viol[0]:.3g} m)")
    q = np.zeros(3)
    q[:d] = x[0]
    dofs = hc.DOFS_POINT2 if planar else hc.DOFS_POINT3
    sol = hc.refine(geo, rho, q, R, dofs, tol_f, ltol)
    if sol is None:
        raise RuntimeError("held-orientation equilibrium: the active-set refinement failed")
    return HangingFK(**vars(_equilibrium(geo, rho, sol, dofs, planar)), equilibria=(), model=model,
                     underconstrained=is_underconstrained(geo.m, geo.B, planar))


def fk_held_arrays(A, B, c, mass, g, lengths, planar: bool, rotation, *, names=None) -> HangingFK:
    """:func:`fk_arrays` with the orientation held at ``rotation`` (3, 3): the translational
    geometrico-static problem, exact (the lowest point of an intersection of balls), then
    refined; tensions balance the force only (``model='held'``).  ``names`` label the
    cables in error messages."""
    geo = _prepare(A, B, c, mass, g, planar)
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
    x, ok, viol = hc.lowest_points(C, rho, down, ltol)
    Rc = np.stack([co * geo.c[0] - si * geo.c[1], si * geo.c[0] + co * geo.c[1]], axis=1)
    E = np.where(ok, -geo.mass * ((x + Rc) @ geo.g[:2]), np.inf)
    starts = []
    n = len(phis)
    for k in range(n):
        minimum = np.isfinite(E[k]) and E[k] <= E[k - 1] and E[k] <= E[(k + 1) % n]
        plateau = E[k] == E[k - 1] and starts and starts[-1][0] == k - 1
        if minimum and not plateau:
            starts.append((k, np.r_[x[k], 0.0], hc.rot_z(phis[k])))
    if not starts:  # nothing feasible on the scan: try the least infeasible angles
        for k in np.argsort(viol)[:4]:
            starts.append((k, None, hc.rot_z(phis[k])))
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
    x, ok, viol = hc.lowest_points(C, rho, down, ltol)
    E = np.where(ok, -geo.mass * ((x + Rs @ geo.c) @ geo.g), np.inf)
    order = list(range(len(fixed))) + [k for k in np.argsort(E) if k >= len(fixed) and np.isfinite(E[k])]
    if not np.any(ok):
        order = list(range(len(fixed))) + list(np.argsort(viol)[:n_starts])
    chosen = []
    for k in order:
        if len(chosen) >= n_starts:
            break
        if any(hc.rotation_angle(Rs[k] @ Rs[j].T) < math.radians(30) for j in chosen) and k >= len(fixed):
            continue
        chosen.append(k)
    return [(x[k] if ok[k] else None, Rs[k]) for k in chosen], float(np.min(viol))


def _same(a: Equilibrium, b: Equilibrium, ls) -> bool:
    return (np.linalg.norm(a.position - b.position) < 1e-6 * (1 + ls)
            and hc.rotation_angle(a.rotation @ b.rotation.T) < 1e-6)


def fk_arrays(A, B, c, mass, g, lengths, planar: bool, *, nominal=None, n_scan: int = 720,
              n_starts: int = 12, seed: int = 0, names=None) -> HangingFK:
    """The resting configuration for cable ``lengths`` [m] (forward geometrico-static problem).

    ``A``, ``B`` (m, 2|3) outlets and attachments [m], ``c`` centre of mass in
    platform coordinates [m], ``mass`` [kg], ``g`` gravity [m/s^2],
    ``planar`` for designs in the z = 0 plane (rotation about z only).
    ``nominal`` (3, 3) is an extra start rotation (and the orientation of a
    point mass whose centre of mass is its attachment point).

    Method: a point mass (coincident attachments) solves the convex problem
    exactly (:func:`~cdpr_design.statics.hanging_core.lowest_points`).  A
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
    geo = _prepare(A, B, c, mass, g, planar)
    rho, ltol, tol_f = _lengths(geo, lengths, names)
    if is_point_mass(geo.B):
        return _held(geo, rho, planar, ha.point_mass_rotation(geo, planar, nominal), ltol, tol_f, "point")
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
            conf = hc.feasibility_phase(geo, rho, guess, R, dofs, ltol)
            if conf is None:
                continue
            p, R = conf
        feasible_seen = True
        # Newton first where the start is already close to an equilibrium: the planar
        # scan's minima, and configurations that as many taut cables as freedoms may lock
        near = np.count_nonzero(geo.cables(p, R)[2] >= rho - 1e-7)
        sol = hc.refine(geo, rho, p, R, dofs, tol_f, ltol) if planar or near >= len(dofs) else None
        if sol is None or not _is_minimum(geo, sol, dofs, rho, ltol):
            p2, R2 = hc.local_minimum(geo, rho, p, R, dofs)
            sol = hc.refine(geo, rho, p2, R2, dofs, tol_f, ltol)
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
        t[S], _ = hc.nonnegative_tensions(W[np.ix_(dofs, S)], -wg[dofs])
    rb = float(np.max(np.abs(geo.balance(p, R, t)[dofs])))
    return p, R, t, S, rb, False, float(np.max(np.abs(L[S] - rho[S]), initial=0.0))


def _is_minimum(geo, sol, dofs, rho, ltol) -> bool:
    """A refined point that is a feasible, stable equilibrium (else SLSQP minimises first)."""
    p, R, t, S, rb, _, _ = sol
    taut = [i for i in S if t[i] > 1e-9 * geo.weight]
    return (rb <= 1e-8 * max(1.0, geo.weight) and np.all(geo.cables(p, R)[2] <= rho + ltol)
            and geo.reduced_hessian_min(p, R, t, taut, dofs) > 0)


# ----------------------------------------------------------------------------
# the hanging orientation at a commanded position
# ----------------------------------------------------------------------------

def _infeasible(geo, p, planar, reason, alternatives=()):
    d = 2 if planar else 3
    return HangingAt(False, reason, np.asarray(p, float)[:d].copy(), np.full((3, 3), np.nan),
                     np.full(geo.m, np.nan), False, math.nan, np.full(geo.m, np.nan), planar, alternatives,
                     _up(geo))


def pose_at_arrays(A, B, c, mass, g, position, planar: bool, *, nominal=None) -> HangingAt:
    """The orientation an under-constrained effector takes at ``position`` [m].

    With the cables taut at that position, the orientation must balance the
    weight, force and moment (for a planar body on two cables: both cable
    lines and the vertical through the centre of mass meet in one point),
    with tensions >= 0, and be stable; of several such orientations the least
    tilted is returned (the others are in ``alternatives``).  A spatial body
    on four or five cables may hang from three of them, the others slack
    (:func:`~cdpr_design.statics.hanging_at.taut_sets`).  The search is
    :func:`cdpr_design.statics.hanging_at.hang`, the same as the workspace's.
    A position the effector cannot hang at statically is ``feasible=False``
    with the reason: every balanced orientation needs a pushing cable, none is
    stable, or no orientation balances the weight.  Raises
    :class:`NotUnderconstrained` for a design whose cables fix its orientation.
    """
    geo = _prepare(A, B, c, mass, g, planar)
    if not is_underconstrained(geo.m, geo.B, planar):
        raise NotUnderconstrained(
            f"{geo.m} cables can fix this effector's orientation: it is commanded, not free")
    p = np.zeros(3)
    pos = np.asarray(position, float).ravel()
    p[: pos.size] = pos
    h = ha.hang(geo, p[None], planar, nominal=nominal, alternatives=True)
    alts = tuple((orientation_of(R, planar), t, st) for R, t, st in h.alternatives[0])
    if h.status[0] != ha.OK:
        return _infeasible(geo, p, planar, ha.REASONS[h.status[0]], alts)
    R = h.rotation[0]
    d = 2 if planar else 3
    return HangingAt(True, "ok", p[:d].copy(), R, h.tensions[0], True, float(h.hessian_min[0]),
                     geo.cables(p, R)[2], planar, alts, _up(geo))


# ----------------------------------------------------------------------------
# the tilt map (batched kernel) and the Design-level wrappers
# ----------------------------------------------------------------------------

def tilt_map_arrays(A, B, c, mass, g, positions):
    """:func:`pose_at` for a planar two-cable body at many positions (k, 2) [m], batched
    with numba.  Returns (phi (k,) [rad], tensions (k, 2) [N], status (k,))."""
    from cdpr_design.kernels import hanging as K

    geo = _prepare(A, B, c, mass, g, True)
    if geo.m != 2 or is_point_mass(geo.B):
        raise InputError("the batched tilt map is for a planar rigid body on two cables")
    P = np.ascontiguousarray(np.asarray(positions, float)[:, :2])
    phi, t, _, status, _ = K.hanging_tilt_batch(geo.A, geo.B, geo.c, geo.mass, geo.g, P)
    return phi, t, status


def design_arrays(design):
    """(outlets, attachments, centre of mass, mass, gravity, planar) of a design [m, kg, m/s^2]."""
    planar = design.motion.name in ("2T", "1R2T")
    return (design.outlets, design.attachments, np.asarray(design.effector.center_of_mass, float),
            float(design.effector.mass), np.asarray(design.gravity, float), planar)


def _within(design, t) -> bool:
    return bool(np.all(t >= design.tension_min - 1e-9) and np.all(t <= design.tension_max + 1e-9))


def fk(design, lengths, **options) -> HangingFK:
    """:func:`fk_arrays` for a design: where it hangs for cable ``lengths`` [m], with
    ``within_limits`` set from the design's tension limits."""
    A, B, c, mass, g, planar = design_arrays(design)
    r = fk_arrays(A, B, c, mass, g, lengths, planar, **options)
    return dataclasses.replace(r, within_limits=None if r.indeterminate else _within(design, r.tensions))


def pose_at(design, position, **options) -> HangingAt:
    """:func:`pose_at_arrays` for a design: its hanging orientation at ``position`` [m],
    with ``within_limits`` set from the design's tension limits."""
    A, B, c, mass, g, planar = design_arrays(design)
    r = pose_at_arrays(A, B, c, mass, g, position, planar, **options)
    return dataclasses.replace(r, within_limits=_within(design, r.tensions) if r.feasible else None)


def underconstrained(design) -> bool:
    """Whether the design's cables leave its orientation free (see :func:`is_underconstrained`)."""
    A, B, _, _, _, planar = design_arrays(design)
    return is_underconstrained(A.shape[0], B, planar)


def hangs_freely(design) -> bool:
    """``effector.orientation: free`` on an under-constrained design: its orientation is not
    commanded but follows from the cables and gravity (every analysis uses the hanging pose)."""
    return design.effector.orientation == "free" and underconstrained(design)


def nominal_rotation(design) -> np.ndarray:
    """The rotation of ``workspace.orientation`` (identity for 2T and 3T)."""
    from cdpr_design.statics.kinematics import rotation_matrix

    return rotation_matrix(*design.default_orientation_full())


def held_rotation(design) -> np.ndarray | None:
    """The rotation the spec holds the effector at for the forward problem, or None when
    the orientation is among its unknowns: ``effector.orientation: fixed`` on a translational
    motion (2T, 3T) holds it at the identity, the spec's model; rotational motions (1R2T, 3R3T)
    find it from the lengths, and ``free`` lets it hang."""
    if design.effector.orientation == "fixed" and not design.motion.rotational:
        return np.eye(3)
    return None


def point_outlets(design, what: str) -> None:
    """Raise an :class:`InputError` for a design with swivel pulleys (the hanging solvers
    model point outlets); ``what`` names the analysis."""
    from cdpr_design.statics.kinematics import has_pulleys

    if has_pulleys(design):
        raise InputError(f"{what}: the geometrico-static solver models point outlets, and this design has "
                         "swivel pulleys (cables[i].pulley)")


def equilibrium(design, lengths, **options) -> HangingFK:
    """Where the design's effector rests for cable ``lengths`` [m] under its spec (the ``fk``
    command): :func:`fk_held_arrays` at :func:`held_rotation` when the spec holds the
    orientation, else :func:`fk_arrays` started about :func:`nominal_rotation`.  Errors name
    the cables; ``within_limits`` from the design's tension limits."""
    point_outlets(design, "fk")
    A, B, c, mass, g, planar = design_arrays(design)
    held = held_rotation(design)
    names = design.cable_names
    if held is not None:
        r = fk_held_arrays(A, B, c, mass, g, lengths, planar, held, names=names)
    else:
        options.setdefault("nominal", nominal_rotation(design))
        r = fk_arrays(A, B, c, mass, g, lengths, planar, names=names, **options)
    return dataclasses.replace(r, within_limits=None if r.indeterminate else _within(design, r.tensions))


def tilt_map(design, axes=None, *, step: float | None = None) -> TiltMap:
    """The hanging orientation over a grid for a planar design on two cables.

    ``axes`` (xs, ys) [m], default the design's frame sampled every ``step``
    [m] (default 0.01 m; planar2: 151 x 151 positions).
    """
    from cdpr_design.kernels import hanging as K

    A, B, c, mass, g, planar = design_arrays(design)
    if not planar:
        raise InputError("the tilt map is for planar designs")
    if axes is None:
        st = 0.01 if step is None else float(step)
        lo, hi = design.frame_lower, design.frame_upper
        axes = tuple(lo[k] + st * np.arange(int(np.floor((hi[k] - lo[k]) / st + 1e-9)) + 1) for k in range(2))
    X, Y = np.meshgrid(axes[0], axes[1], indexing="ij")
    phi, t, status = tilt_map_arrays(A, B, c, mass, g, np.column_stack([X.ravel(), Y.ravel()]))
    shape = X.shape
    t = t.reshape(shape + (2,))
    with np.errstate(invalid="ignore"):
        within = (status.reshape(shape) == K.TILT_OK) & np.all(
            (t >= design.tension_min - 1e-9) & (t <= design.tension_max + 1e-9), axis=2)
    return TiltMap(tuple(np.asarray(a) for a in axes), phi.reshape(shape), t, status.reshape(shape),
                   K.TILT_REASONS, within)
