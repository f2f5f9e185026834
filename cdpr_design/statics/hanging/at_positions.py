"""The orientation an under-constrained effector hangs in at commanded positions, batched.

At a commanded position p its cables are taut (their lengths are what put the
effector there) but its orientation R is not commanded: the effector turns
until the cable forces balance its weight, force *and* moment, with every
tension >= 0, and it rests there when that equilibrium is stable (the
reduced-Hessian test of Carricato & Merlet 2013).  :func:`hanging_orientations`
answers this for many positions at once, with numpy, and :func:`hanging_pose_arrays`
at one position with the other balanced orientations found:

* a planar rigid body on two cables: every balanced orientation is a root of a
  degree-2 trigonometric polynomial, in closed form
  (:mod:`cdpr_design.statics.hanging.planar2`);
* a point mass (every attachment at one point): the orientation changes no
  cable, and the centre of mass hangs straight below the attachment point;
* any other rigid body (a planar one on one cable, a spatial one on one to
  five): damped Newton's method on force and moment balance, unknowns the
  rotation and the tensions, from the starting orientations
  :data:`PLANAR_STARTS` / :data:`SPATIAL_STARTS` about the nominal one.  On
  four or five cables a spatial body's balanced orientations at one position
  form a family (m - 3 parameters: the lengths can still choose among them);
  there each step is the minimum-norm Newton step plus a pull along the
  family towards the nominal orientation, so the iteration heads for the
  member nearest to the nominal orientation (the KKT point of min |w|^2
  subject to balance, R = exp([w]) R_nominal).  On four cables the family is
  a curve, and :func:`~cdpr_design.statics.hanging.family.march_family`
  follows it from every balanced pulling candidate (predictor-corrector
  continuation) to its least tilted member with every tension >= 0, and to
  where its pulling members end (a cable just slack).  On five cables the
  marches walk the edges of the two-parameter family's pulling region, which
  are arcs of four-cable families
  (:func:`~cdpr_design.statics.hanging.family.with_marches`).

Of the balanced orientations found with tensions >= 0 and stable, the least
tilted one is the answer (``tilt`` = angle between the platform's vertical and
the frame's, |phi| for planar bodies); of equally tilted ones (a level body
that could hang at any yaw) the one nearest the nominal orientation
(:func:`~cdpr_design.statics.hanging.geometry.tilt_rank`).  Status codes
(:data:`~cdpr_design.statics.hanging.results.OK`, ...) say why a position has
none.

Units: SI (m, N, rad); conventions of :mod:`cdpr_design.statics.hanging.geometry`.

References
----------
M. Carricato, J.-P. Merlet, "Stability analysis of underconstrained
cable-driven parallel robots", IEEE Trans. Robotics 29(1), 288-296, 2013.
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from cdpr_design.errors import InputError
from cdpr_design.model.design import is_point_mass, is_underconstrained
from cdpr_design.statics.hanging import geometry as hg
from cdpr_design.statics.hanging import planar2
from cdpr_design.statics.hanging.balance import Balance, newton_many, on_cables, solve_sym
from cdpr_design.statics.hanging.family import with_marches
from cdpr_design.statics.hanging.results import (
    NO_BALANCE, OK, PUSHING, REASONS, UNSTABLE, HangingOrientations, HangingPose, NotUnderconstrained, orientation_of,
)

#: Starting rotation angles [rad] about z of the planar Newton search.
PLANAR_STARTS = (0.0, math.pi / 2, math.pi, -math.pi / 2)
#: Starting rotation vectors [rad] (frame axes) of the spatial Newton search.
SPATIAL_STARTS = ((0.0, 0.0, 0.0), (0.7, 0.0, 0.0), (-0.7, 0.0, 0.0), (0.0, 0.7, 0.0), (0.0, -0.7, 0.0),
                  (0.0, 0.0, math.pi))


# ----------------------------------------------------------------------------
# a point mass (other rigid bodies: balance, family)
# ----------------------------------------------------------------------------

def point_mass_many(geo: hg.Geometry, P, planar: bool, R):
    """A point mass at positions P (k, 3): tensions (k, m) [N] balancing its weight with the
    cables from the common attachment (least squares) and whether they do (k,)."""
    W, wg, *_ = Balance(geo, planar).wrenches(np.asarray(P, float), np.broadcast_to(R, (len(P), 3, 3)))
    d = 2 if planar else 3
    Wf, f = W[:, :d], -wg[:, :d]
    t = solve_sym(Wf.transpose(0, 2, 1) @ Wf, np.einsum("ndm,nd->nm", Wf, f))
    res = np.abs(np.einsum("ndm,nm->nd", Wf, t) - f).max(axis=1)
    return t, res <= 1e-8 * max(1.0, geo.weight)


# ----------------------------------------------------------------------------
# the hanging orientation: dispatch and choice
# ----------------------------------------------------------------------------

def hanging_orientations(geo: hg.Geometry, P, planar: bool, *, nominal=None,
                         alternatives: bool = False) -> HangingOrientations:
    """The hanging orientation at positions ``P`` (k, 2|3) [m] (see the module doc).

    ``nominal`` (3, 3): the orientation the Newton search starts about and is
    pulled towards (default level, R = I).  ``alternatives``: also list, per position, the
    other balanced orientations with tensions >= 0 (small k only).
    """
    P = np.asarray(P, float).reshape(len(P), -1)
    P3 = np.zeros((len(P), 3))
    P3[:, : P.shape[1]] = P[:, :3]
    up = -geo.g / np.linalg.norm(geo.g)
    # The closed forms (a point mass, a planar body on two cables) are solved for a unit weight (mass 1,
    # |g| = 1) and scaled back: their orientations do not depend on the weight W and their tensions and
    # reduced Hessian are linear in it, so no mass is too small for their tolerances (2e-308 kg
    # underflowed the planar roots: a traceback).  The Newton search of other bodies runs at the real
    # weight, its tolerances in N; its answers agree over masses to about 1e-9 deg (the tests).
    point = is_point_mass(geo.B)
    if point or (planar and geo.m == 2):
        unit, w = unit_geometry(geo, planar, point)
        if unit is None:  # the external force cancels the weight: nothing pulls it anywhere
            k = len(P3)
            out = (np.full((k, 3, 3), np.nan), np.full((k, geo.m), np.nan), np.full(k, NO_BALANCE, np.int8),
                   np.full(k, np.nan), [[] for _ in range(k)] if alternatives else [])
        else:
            out = (_hang_point(unit, P3, planar, nominal, alternatives) if point
                   else _hang_planar2(unit, P3, alternatives))
    else:
        w = 1.0
        out = _hang_general(geo, P3, planar, nominal, alternatives)
    R, t, status, hmin, alts = out
    bad = status != OK
    R[bad], t[bad], hmin[bad] = np.nan, np.nan, np.nan
    alts = [[(Ra, ta * w, st) for Ra, ta, st in per] for per in alts]
    return HangingOrientations(R, t * w, status, hmin * w, planar, up, alts)


def unit_geometry(geo: hg.Geometry, planar: bool, point: bool) -> tuple[hg.Geometry | None, float]:
    """The closed forms' effector of unit weight and the weight W [N] that scales its tensions and
    reduced Hessian back: the same body (mass 1, |g| = 1) where no external force acts.

    Under an external force F at the platform origin a planar body's loads, m g at R c and F at
    the origin, have the potential -(m g + F) . p - m g . R c, which equals -T . (p + R q) for
    every rotation about z with T = m g + F and, as complex numbers in the plane,
    q = conj(m g) c / conj(T): the body hangs as one of weight |T| along T with its centre of mass
    at q, exactly (balance, energy and Hessian alike).  A spatial point mass attached at the
    platform origin turns its centre of mass below the attachment whatever force acts there: its
    weight stays, the force is added to the balance.  (None, W) where T = 0 in the plane.

    Raises
    ------
    InputError
        For a spatial point mass attached away from the platform origin under an external force
        (its rotation is then not a closed form).
    """
    up = -geo.g / np.linalg.norm(geo.g)
    F = geo.force
    if not np.any(F):
        return hg.Geometry(geo.A, geo.B, geo.c, 1.0, -up), geo.weight
    if not planar:
        if point and np.any(geo.B[0]):
            raise InputError("an external force on a spatial point mass attached away from the platform origin "
                             "is not modelled")
        return hg.Geometry(geo.A, geo.B, geo.c, 1.0, -up, F / geo.weight), geo.weight
    G = complex(*(geo.mass * geo.g[:2]))
    T = G + complex(*F[:2])
    if abs(T) <= 1e-12 * max(geo.weight, float(np.linalg.norm(F))):
        return None, geo.weight
    q = G.conjugate() * complex(*geo.c[:2]) / T.conjugate()
    return hg.Geometry(geo.A, geo.B, (q.real, q.imag, 0.0), 1.0, (T.real / abs(T), T.imag / abs(T), 0.0)), abs(T)


def _statuses(found, pull, balanced):
    return np.where(found, OK, np.where(pull, UNSTABLE, np.where(balanced, PUSHING, NO_BALANCE))).astype(np.int8)


def _hang_planar2(geo, P, alternatives):
    k = len(P)
    phis, ts, hs, ok, degenerate = planar2.planar_two_cable(geo.A, geo.B, geo.c, geo.mass, geo.g, P)
    j, status, pull, stable = planar2.choose(phis, ts, hs, ok, degenerate, geo.weight)
    rows = np.arange(k)
    alts = []
    if alternatives:
        for i in range(k):
            alts.append([(hg.rot_z(phis[i, s]), np.maximum(ts[i, s], 0.0), bool(stable[i, s]))
                         for s in range(phis.shape[1]) if pull[i, s] and not (status[i] == OK and s == j[i])])
    return hg.rot_z_many(phis[rows, j]), np.maximum(ts[rows, j], 0.0), status, hs[rows, j].copy(), alts


#: Configurations whose stability is judged in one stacked call (bounds its memory: about ten
#: (n, m, 3, 3) arrays).
STABLE_BATCH = 32768


def _stable(geo, P, R, t, dofs):
    """(stable (k,), smallest reduced-Hessian eigenvalue (k,)) of k balanced poses: positions
    P (k, 3) [m], rotations R (k, 3, 3), tensions t (k, m) [N]; the taut cables are those
    above 1e-9 of the weight.  In slices of :data:`STABLE_BATCH`."""
    h = np.empty(len(P))
    for a in range(0, len(P), STABLE_BATCH):
        b = a + STABLE_BATCH
        h[a:b] = geo.reduced_hessian_min_many(P[a:b], R[a:b], np.maximum(t[a:b], 0.0),
                                              t[a:b] > 1e-9 * geo.weight, dofs)
    return h > 1e-9 * geo.weight, h


def taut_sets(m: int, planar: bool) -> list[tuple[int, ...]]:
    """The sets of taut cables searched: every cable, and for a spatial body on four or
    five cables also every three of them (the others slack: such a body generally hangs
    from three cables; with all taut its balanced orientations form a family)."""
    sets = [tuple(range(m))]
    if not planar and m > 3:
        sets += list(itertools.combinations(range(m), 3))
    return sets


def _hang_general(geo, P, planar, nominal, alternatives):
    """Newton from the nominal orientation for every taut set, then from the other starts
    where nothing was found; the least tilted stable pulling answer."""
    R0 = np.eye(3) if nominal is None else np.asarray(nominal, float)
    starts = [(0.0, 0.0, a) for a in PLANAR_STARTS] if planar else list(SPATIAL_STARTS)
    k = len(P)
    R, t, hmin = np.full((k, 3, 3), np.nan), np.full((k, geo.m), np.nan), np.full(k, np.nan)
    found, pull_any, bal_any = np.zeros(k, bool), np.zeros(k, bool), np.zeros(k, bool)
    seen = [[] for _ in range(k)]  # distinct candidates per position: (R, t, stable, tilt)
    for first, stage in ((True, starts[:1]), (False, starts[1:])):
        todo = np.arange(k) if first else np.flatnonzero(~found)
        if not todo.size or not stage:
            continue
        cands = []
        for S in taut_sets(geo.m, planar):
            Rs, tS, ok = newton_many(on_cables(geo, S), P[todo], planar, R0, stage)
            ts = np.zeros(tS.shape[:2] + (geo.m,))
            ts[:, :, list(S)] = tS
            cands.append((Rs, ts, ok))
        Rs = np.concatenate([c[0] for c in cands], axis=1)
        ts = np.concatenate([c[1] for c in cands], axis=1)
        balanced = np.concatenate([c[2] for c in cands], axis=1)
        if not planar and geo.m in (4, 5):
            Rs, ts, balanced = with_marches(geo, P[todo], Rs, ts, balanced, R0)
        _choose_general(geo, P, planar, todo, Rs, ts, balanced, R0, seen, found, alternatives)
        pull_any[todo] |= (balanced & np.all(ts >= -1e-9 * geo.weight, axis=2)).any(1)
        bal_any[todo] |= balanced.any(1)
    alts = []
    for i in range(k):
        best = min((c for c in seen[i] if c[2]), key=lambda c: c[3], default=None)
        if best is not None:
            R[i], t[i], hmin[i] = best[0], best[1], best[4]
        if alternatives:
            alts.append([c[:3] for c in seen[i] if c is not best])
    return R, t, _statuses(found, pull_any, bal_any), hmin, alts


def _choose_general(geo, P, planar, todo, Rs, ts, balanced, R0, seen, found, alternatives):
    """Appends to ``seen`` the pulling candidates of each position in order of tilt (of equally
    tilted ones the nearest the nominal rotation R0 first: :func:`~cdpr_design.statics.hanging.geometry.tilt_rank`), until a stable
    one (all of them with ``alternatives``), skipping those already seen, as (R, t, stable,
    rank, h); the stability of every pulling candidate is judged first, in one batch."""
    dofs = hg.DOFS_PLANAR if planar else hg.DOFS_SPATIAL
    pull = balanced & np.all(ts >= -1e-9 * geo.weight, axis=2)
    rank = hg.tilt_rank(Rs, -geo.g / np.linalg.norm(geo.g), R0)
    # the stability of every pulling candidate at once (the loop below may skip some of them)
    stable, h = np.zeros(pull.shape, bool), np.full(pull.shape, np.nan)
    n_, s_ = np.nonzero(pull)
    if n_.size:
        stable[n_, s_], h[n_, s_] = _stable(geo, P[todo[n_]], Rs[n_, s_], ts[n_, s_], dofs)
    for n, i in enumerate(todo):
        for s in np.argsort(np.where(pull[n], rank[n], np.inf), kind="stable"):
            if not pull[n, s] or (found[i] and not alternatives):
                break
            if any(hg.angle_from(Rs[n, s], c[0]) < 1e-7 for c in seen[i]):
                continue
            seen[i].append((Rs[n, s], np.maximum(ts[n, s], 0.0), bool(stable[n, s]), rank[n, s], h[n, s]))
            found[i] |= stable[n, s]


def _hang_point(geo, P, planar, nominal, alternatives):
    R0 = hg.point_mass_rotation(geo, planar, nominal)
    t, balanced = point_mass_many(geo, P, planar, R0)
    pull = balanced & np.all(t >= -1e-9 * geo.weight, axis=1)
    dofs = hg.DOFS_POINT2 if planar else hg.DOFS_POINT3
    k = len(P)
    found, hmin = np.zeros(k, bool), np.full(k, np.nan)
    rows = np.flatnonzero(pull)
    if rows.size:
        found[rows], hmin[rows] = _stable(geo, P[rows], np.broadcast_to(R0, (rows.size, 3, 3)), t[rows], dofs)
    alts = [[(R0, np.maximum(t[i], 0.0), False)] if pull[i] and not found[i] else [] for i in range(k)] \
        if alternatives else []
    R = np.broadcast_to(R0, (k, 3, 3)).copy()
    return R, np.maximum(t, 0.0), _statuses(found, pull, balanced), hmin, alts


# ----------------------------------------------------------------------------
# one position, with the other balanced orientations
# ----------------------------------------------------------------------------

def _infeasible(geo, p, planar, reason, alternatives=()):
    d = 2 if planar else 3
    return HangingPose(False, reason, np.asarray(p, float)[:d].copy(), np.full((3, 3), np.nan),
                       np.full(geo.m, np.nan), False, math.nan, np.full(geo.m, np.nan), planar, alternatives,
                       hg.up_of(geo))


def hanging_pose_arrays(A, B, c, mass, g, position, planar: bool, *, nominal=None) -> HangingPose:
    """The orientation an under-constrained effector takes at ``position`` [m].

    With the cables taut at that position, the orientation must balance the
    weight, force and moment (for a planar body on two cables: both cable
    lines and the vertical through the centre of mass meet in one point),
    with tensions >= 0, and be stable; of several such orientations the least
    tilted is returned (the others are in ``alternatives``).  A spatial body
    on four or five cables may hang from three of them, the others slack
    (:func:`taut_sets`).  The search is :func:`hanging_orientations`, the
    same as the workspace's.  A position the effector cannot hang at statically is ``feasible=False``
    with the reason: every balanced orientation needs a pushing cable, none is
    stable, or no orientation balances the weight.  Raises
    :class:`NotUnderconstrained` for a design whose cables fix its orientation.
    """
    geo = hg.checked_geometry(A, B, c, mass, g, planar)
    if not is_underconstrained(geo.m, geo.B, planar):
        raise NotUnderconstrained(
            f"{geo.m} cables can fix this effector's orientation: it is commanded, not free")
    p = np.zeros(3)
    pos = np.asarray(position, float).ravel()
    p[: pos.size] = pos
    h = hanging_orientations(geo, p[None], planar, nominal=nominal, alternatives=True)
    alts = tuple((orientation_of(R, planar), t, st) for R, t, st in h.alternatives[0])
    if h.status[0] != OK:
        return _infeasible(geo, p, planar, REASONS[h.status[0]], alts)
    R = h.rotation[0]
    d = 2 if planar else 3
    return HangingPose(True, "ok", p[:d].copy(), R, h.tensions[0], True, float(h.hessian_min[0]),
                       geo.cables(p, R)[2], planar, alts, hg.up_of(geo))
