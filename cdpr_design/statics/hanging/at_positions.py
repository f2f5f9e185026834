"""The orientation an under-constrained effector hangs in at commanded positions, batched.

At a commanded position p its cables are taut (their lengths are what put the
effector there) but its orientation R is not commanded: the effector turns
until the cable forces balance its weight, force *and* moment, with every
tension >= 0, and it rests there when that equilibrium is stable (the
reduced-Hessian test of Carricato & Merlet 2013).  :func:`hang` answers this
for many positions at once, with numpy:

* a planar rigid body on two cables: every balanced orientation is a root of a
  degree-2 trigonometric polynomial, the method of
  :mod:`cdpr_design.kernels.hanging`; :func:`planar_two_cable` runs it with
  numpy, vectorised over the positions with the kernel's formulas, tolerances
  and choice (the numba kernel is its fast twin; the tests hold them equal);
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
  a curve, and :func:`~cdpr_design.statics.hanging_family.march_family`
  follows it from every balanced pulling candidate (predictor-corrector
  continuation) to its least tilted member with every tension >= 0, and to
  where its pulling members end (a cable just slack).  On five cables the
  marches walk the edges of the two-parameter family's pulling region, which
  are arcs of four-cable families
  (:func:`~cdpr_design.statics.hanging_family.with_marches`).

Of the balanced orientations found with tensions >= 0 and stable, the least
tilted one is the answer (``tilt`` = angle between the platform's vertical and
the frame's, |phi| for planar bodies); of equally tilted ones (a level body
that could hang at any yaw) the one nearest the nominal orientation
(:func:`~cdpr_design.statics.hanging_core.tilt_rank`).  Status codes
(:data:`OK`, ...) say why a position has none; they equal the kernel's
``TILT_*`` codes (a test checks).

Units: SI (m, N, rad); conventions of :mod:`cdpr_design.statics.hanging_core`.

References
----------
M. Carricato, J.-P. Merlet, "Stability analysis of underconstrained
cable-driven parallel robots", IEEE Trans. Robotics 29(1), 288-296, 2013.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field

import numpy as np

from cdpr_design.statics import hanging_core as hc
from cdpr_design.statics.hanging_core import tilt_many, tilt_rank
from cdpr_design.statics.hanging_family import with_marches
from cdpr_design.statics.hanging_newton import Balance, newton_many, solve_sym, subset

#: A stable equilibrium with every tension >= 0 was found.
OK = 0
#: Balanced orientations exist, but each needs a pushing (negative) cable.
PUSHING = 1
#: Balanced orientations with tensions >= 0 exist, but none is stable.
UNSTABLE = 2
#: No orientation balances the weight with the cables taut.
NO_BALANCE = 3
#: Degenerate input: a zero-length cable, or every orientation balances.
DEGENERATE = 4

#: Why a position has no hanging orientation, indexed by status code.
REASONS = (
    "ok",
    "every balanced orientation needs a pushing cable",
    "the balanced orientations with pulling cables are unstable",
    "no orientation balances the weight with the cables taut",
    "degenerate geometry (zero-length cable or indifferent balance)",
)

#: Starting rotation angles [rad] about z of the planar Newton search.
PLANAR_STARTS = (0.0, math.pi / 2, math.pi, -math.pi / 2)
#: Starting rotation vectors [rad] (frame axes) of the spatial Newton search.
SPATIAL_STARTS = ((0.0, 0.0, 0.0), (0.7, 0.0, 0.0), (-0.7, 0.0, 0.0), (0.0, 0.7, 0.0), (0.0, -0.7, 0.0),
                  (0.0, 0.0, math.pi))


@dataclass
class Hanging:
    """The hanging orientation at k positions.

    ``rotation`` (k, 3, 3) and ``tensions`` (k, m) [N] are NaN where
    ``status`` (k,) is not :data:`OK`; ``hessian_min`` (k,) the smallest
    eigenvalue of the reduced Hessian there; ``up`` the frame's unit vertical
    (-g/|g|).  ``alternatives`` (when asked for) holds, per position, the
    other balanced orientations found with tensions >= 0, as (rotation,
    tensions, stable) tuples.
    """

    rotation: np.ndarray
    tensions: np.ndarray
    status: np.ndarray
    hessian_min: np.ndarray
    planar: bool
    up: np.ndarray
    alternatives: list = field(default_factory=list)

    @classmethod
    def joined(cls, parts: list["Hanging"]) -> "Hanging":
        """The answers of consecutive runs of positions (``parts`` in order) as one."""
        first = parts[0]
        return cls(*(np.concatenate([getattr(h, name) for h in parts])
                     for name in ("rotation", "tensions", "status", "hessian_min")),
                   first.planar, first.up, [a for h in parts for a in h.alternatives])

    @property
    def feasible(self) -> np.ndarray:
        return self.status == OK

    @property
    def tilt_deg(self) -> np.ndarray:
        """Angle [deg] between the platform's vertical R up and up; NaN where it cannot hang."""
        return tilt_many(self.rotation, self.up)

    @property
    def orientation(self) -> np.ndarray:
        """phi (k,) [rad] about z (planar) or (k, 3) [rx, ry, rz] [rad], R = Rx Ry Rz (spatial)."""
        if self.planar:
            return np.arctan2(self.rotation[:, 1, 0], self.rotation[:, 0, 0])
        return hc.euler_xyz(self.rotation)


def _cr(ax, ay, bx, by):
    return ax * by - ay * bx


# ----------------------------------------------------------------------------
# planar rigid body on two cables (numpy twin of kernels.hanging)
# ----------------------------------------------------------------------------

def _geometry2(phi, A, B, c, px, py):
    """v_1, v_2, R b_1, R b_2, R c at angles phi (broadcast with px, py)."""
    co, si = np.cos(phi), np.sin(phi)
    rb1 = (co * B[0, 0] - si * B[0, 1], si * B[0, 0] + co * B[0, 1])
    rb2 = (co * B[1, 0] - si * B[1, 1], si * B[1, 0] + co * B[1, 1])
    rc = (co * c[0] - si * c[1], si * c[0] + co * c[1])
    v1 = (A[0, 0] - px - rb1[0], A[0, 1] - py - rb1[1])
    v2 = (A[1, 0] - px - rb2[0], A[1, 1] - py - rb2[1])
    return v1, v2, rb1, rb2, rc


def _moment2(phi, A, B, c, fx, fy, px, py):
    """M(phi) of kernels.hanging.moment_residual, broadcast over arrays."""
    v1, v2, rb1, rb2, rc = _geometry2(phi, A, B, c, px, py)
    m1 = _cr(rb1[0] - rc[0], rb1[1] - rc[1], v1[0], v1[1])
    m2 = _cr(rb2[0] - rc[0], rb2[1] - rc[1], v2[0], v2[1])
    return _cr(fx, fy, v2[0], v2[1]) * m1 + _cr(v1[0], v1[1], fx, fy) * m2


def _trig_roots(coef):
    """Roots phi (k, 4) (NaN padded) of the trigonometric polynomial with coefficients
    ``coef`` (5, k) and a flag (k,) where M vanishes identically (kernels.hanging.trig_roots)."""
    k = coef.shape[1]
    scale = np.abs(coef).sum(axis=0)
    c4 = 0.5 * (coef[3] - 1j * coef[4])
    c3 = 0.5 * (coef[1] - 1j * coef[2])
    c2 = coef[0] + 0j
    c1, c0 = np.conj(c3), np.conj(c4)
    tiny = 1e-13 * scale
    quart = np.abs(c4) > tiny
    quad = ~quart & (np.abs(c3) > tiny)
    degenerate = ~(scale > 0) | ~np.isfinite(scale) | ~(quart | quad)
    z = np.full((k, 4), np.nan + 0j)
    q = np.flatnonzero(quart & ~degenerate)
    if q.size:
        C = np.zeros((q.size, 4, 4), complex)
        C[:, 0] = -np.stack([c3[q], c2[q], c1[q], c0[q]], axis=1) / c4[q, None]
        C[:, 1, 0] = C[:, 2, 1] = C[:, 3, 2] = 1.0
        z[q] = np.linalg.eigvals(C)
    q = np.flatnonzero(quad & ~degenerate)
    if q.size:
        C = np.zeros((q.size, 2, 2), complex)
        C[:, 0] = -np.stack([c2[q], c1[q]], axis=1) / c3[q, None]
        C[:, 1, 0] = 1.0
        z[q, :2] = np.linalg.eigvals(C)
    near = np.abs(np.abs(z) - 1.0) < 1e-3
    return np.where(near, np.arctan2(z.imag, z.real), np.nan), degenerate


def _polish2(phi, coef, A, B, c, fx, fy, px, py):
    """Eight Newton steps on M at most (kernels.hanging.polish_root); (phi, |M(phi)|)."""
    active = np.isfinite(phi)
    for _ in range(8):
        if not active.any():
            break
        f = _moment2(phi, A, B, c, fx, fy, px, py)
        d = (-coef[1] * np.sin(phi) + coef[2] * np.cos(phi) - 2.0 * coef[3] * np.sin(2.0 * phi)
             + 2.0 * coef[4] * np.cos(2.0 * phi))
        active &= d != 0.0
        with np.errstate(divide="ignore", invalid="ignore"):
            step = np.where(active, f / d, 0.0)
        phi = phi - step
        active &= np.abs(step) >= 1e-15
    phi = np.arctan2(np.sin(phi), np.cos(phi))
    return phi, np.abs(_moment2(phi, A, B, c, fx, fy, px, py))


def _equilibrium2(phi, A, B, c, mass, gx, gy, px, py):
    """Tensions, reduced Hessian h and a geometry flag (kernels.hanging.equilibrium_at)."""
    fx, fy = -mass * gx, -mass * gy
    v1, v2, rb1, rb2, rc = _geometry2(phi, A, B, c, px, py)
    L1, L2 = np.hypot(*v1), np.hypot(*v2)
    D = _cr(v1[0], v1[1], v2[0], v2[1])
    ok = (L1 > 1e-12) & (L2 > 1e-12) & (np.abs(D) > 1e-12 * L1 * L2)
    with np.errstate(divide="ignore", invalid="ignore"):
        t1 = _cr(fx, fy, v2[0], v2[1]) / D * L1
        t2 = _cr(v1[0], v1[1], fx, fy) / D * L2
        u1, u2 = (v1[0] / L1, v1[1] / L1), (v2[0] / L2, v2[1] / L2)
        g1 = (-u1[0], -u1[1], -_cr(rb1[0], rb1[1], u1[0], u1[1]))
        g2 = (-u2[0], -u2[1], -_cr(rb2[0], rb2[1], u2[0], u2[1]))
        nx = g1[1] * g2[2] - g1[2] * g2[1]
        ny = g1[2] * g2[0] - g1[0] * g2[2]
        nt = g1[0] * g2[1] - g1[1] * g2[0]
        nn = nx * nx + ny * ny + nt * nt
        h = (mass * (gx * rc[0] + gy * rc[1])) * nt * nt
        q1 = u1[1] * nx - u1[0] * ny - (rb1[0] * u1[0] + rb1[1] * u1[1]) * nt
        q2 = u2[1] * nx - u2[0] * ny - (rb2[0] * u2[0] + rb2[1] * u2[1]) * nt
        h = h + t1 * (q1 * q1 / L1 + (u1[0] * rb1[0] + u1[1] * rb1[1]) * nt * nt)
        h = h + t2 * (q2 * q2 / L2 + (u2[0] * rb2[0] + u2[1] * rb2[1]) * nt * nt)
        h = h / nn
    return t1, t2, h, ok


def planar_two_cable(A, B, c, mass, g, P):
    """Every balanced orientation of a planar body on two taut cables at positions P (k, >=2) [m].

    ``A``, ``B`` (2, >=2) outlets and attachments [m], ``c`` centre of mass
    (platform) [m], ``mass`` [kg], ``g`` gravity [m/s^2].  Returns (phi (k, 4)
    [rad], tensions (k, 4, 2) [N], h (k, 4) reduced Hessian, ok (k, 4): a real
    root with a proper geometry, degenerate (k,)).  Same formulas, order and
    tolerances as :func:`cdpr_design.kernels.hanging.hanging_tilt`.
    """
    A, B, c, g, P = (np.asarray(x, float) for x in (A, B, c, g, P))
    px, py = P[:, 0], P[:, 1]
    fx, fy = -mass * g[0], -mass * g[1]
    coef = np.zeros((5, P.shape[0]))
    for k in range(5):
        t = 2.0 * math.pi * k / 5.0
        mk = _moment2(t, A, B, c, fx, fy, px, py)
        coef += np.array([mk / 5.0, 0.4 * mk * math.cos(t), 0.4 * mk * math.sin(t),
                          0.4 * mk * math.cos(2.0 * t), 0.4 * mk * math.sin(2.0 * t)])
    phi0, degenerate = _trig_roots(coef)
    X = lambda v: v[:, None]  # noqa: E731 - broadcast per-position values over the roots
    phi, res = _polish2(phi0, X(coef.T).transpose(2, 0, 1), A, B, c, fx, fy, X(px), X(py))
    scale = np.abs(coef).sum(axis=0)
    real = res <= 1e-9 * X(scale)
    t1, t2, h, ok = _equilibrium2(phi, A, B, c, mass, g[0], g[1], X(px), X(py))
    ok &= real
    return phi, np.stack([t1, t2], axis=-1), h, ok, degenerate


def _choose_planar2(phi, t, h, ok, degenerate, weight):
    """The kernel's choice: of the stable roots with t >= 0, the one closest to level."""
    ttol = 1e-9 * weight
    pull = ok & np.all(t >= -ttol, axis=-1)
    stable = pull & (h > 1e-10 * weight)
    key = np.where(stable, np.abs(phi), np.inf)
    j = np.argmin(key, axis=1)
    rows = np.arange(phi.shape[0])
    found = np.isfinite(key[rows, j])
    status = np.where(found, OK, np.where(pull.any(1), UNSTABLE, np.where(ok.any(1), PUSHING, NO_BALANCE)))
    status = np.where(degenerate, DEGENERATE, status).astype(np.int8)
    return j, status, pull, stable


# ----------------------------------------------------------------------------
# a point mass (other rigid bodies: hanging_newton, hanging_family)
# ----------------------------------------------------------------------------

def point_mass_many(geo: hc.Geometry, P, planar: bool, R):
    """A point mass at positions P (k, 3): tensions (k, m) [N] balancing its weight with the
    cables from the common attachment (least squares) and whether they do (k,)."""
    W, wg, *_ = Balance(geo, planar).parts(np.asarray(P, float), np.broadcast_to(R, (len(P), 3, 3)))
    d = 2 if planar else 3
    Wf, f = W[:, :d], -wg[:, :d]
    t = solve_sym(Wf.transpose(0, 2, 1) @ Wf, np.einsum("ndm,nd->nm", Wf, f))
    res = np.abs(np.einsum("ndm,nm->nd", Wf, t) - f).max(axis=1)
    return t, res <= 1e-8 * max(1.0, geo.weight)


def point_mass_rotation(geo: hc.Geometry, planar: bool, nominal=None) -> np.ndarray:
    """The rotation that puts a point mass's centre of mass straight below its attachment
    point (the smallest such rotation; ``nominal`` when they coincide)."""
    down = geo.g / np.linalg.norm(geo.g)
    arm = geo.c - geo.B[0]
    if np.linalg.norm(arm) > 1e-12 * geo.size:
        if planar:
            return hc.rot_z(math.atan2(down[1], down[0]) - math.atan2(arm[1], arm[0]))
        return hc.align(arm, down)
    return np.eye(3) if nominal is None else np.asarray(nominal, float)


# ----------------------------------------------------------------------------
# the hanging orientation: dispatch and choice
# ----------------------------------------------------------------------------

def rot_z_many(phi) -> np.ndarray:
    """Rotations (k, 3, 3) about z by angles phi (k,) [rad]."""
    co, si = np.cos(phi), np.sin(phi)
    R = np.zeros(np.shape(phi) + (3, 3))
    R[..., 0, 0], R[..., 0, 1], R[..., 1, 0], R[..., 1, 1], R[..., 2, 2] = co, -si, si, co, 1.0
    return R


def hang(geo: hc.Geometry, P, planar: bool, *, nominal=None, engine: str = "numpy",
         alternatives: bool = False) -> Hanging:
    """The hanging orientation at positions ``P`` (k, 2|3) [m] (see the module doc).

    ``nominal`` (3, 3): the orientation the Newton search starts about and is
    pulled towards (default level, R = I).  ``engine``: ``numpy``, or
    ``numba`` for the planar two-cable kernel (same answers; the other
    bodies are always numpy).  ``alternatives``: also list, per position, the
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
    point = hc.is_point_mass(geo.B)
    if point or (planar and geo.m == 2):
        w = geo.weight
        unit = hc.Geometry(geo.A, geo.B, geo.c, 1.0, -up)
        out = (_hang_point(unit, P3, planar, nominal, alternatives) if point
               else _hang_planar2(unit, P3, engine, alternatives))
    else:
        w = 1.0
        out = _hang_general(geo, P3, planar, nominal, alternatives)
    R, t, status, hmin, alts = out
    bad = status != OK
    R[bad], t[bad], hmin[bad] = np.nan, np.nan, np.nan
    alts = [[(Ra, ta * w, st) for Ra, ta, st in per] for per in alts]
    return Hanging(R, t * w, status, hmin * w, planar, up, alts)


def _statuses(found, pull, balanced):
    return np.where(found, OK, np.where(pull, UNSTABLE, np.where(balanced, PUSHING, NO_BALANCE))).astype(np.int8)


def _hang_planar2(geo, P, engine, alternatives):
    k = len(P)
    if engine == "numba" and not alternatives:
        from cdpr_design.kernels import hanging as K  # numba, on first use

        phi, t, h, status, _ = K.hanging_tilt_batch(geo.A, geo.B, geo.c, geo.mass, geo.g,
                                                    np.ascontiguousarray(P[:, :2]))
        return rot_z_many(phi), t, status.astype(np.int8), h, []
    phis, ts, hs, ok, degenerate = planar_two_cable(geo.A, geo.B, geo.c, geo.mass, geo.g, P)
    j, status, pull, stable = _choose_planar2(phis, ts, hs, ok, degenerate, geo.weight)
    rows = np.arange(k)
    alts = []
    if alternatives:
        for i in range(k):
            alts.append([(hc.rot_z(phis[i, s]), np.maximum(ts[i, s], 0.0), bool(stable[i, s]))
                         for s in range(phis.shape[1]) if pull[i, s] and not (status[i] == OK and s == j[i])])
    return rot_z_many(phis[rows, j]), np.maximum(ts[rows, j], 0.0), status, hs[rows, j].copy(), alts


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
            Rs, tS, ok = newton_many(subset(geo, S), P[todo], planar, R0, stage)
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
    tilted ones the nearest the nominal rotation R0 first: :func:`tilt_rank`), until a stable
    one (all of them with ``alternatives``), skipping those already seen, as (R, t, stable,
    rank, h); the stability of every pulling candidate is judged first, in one batch."""
    dofs = hc.DOFS_PLANAR if planar else hc.DOFS_SPATIAL
    pull = balanced & np.all(ts >= -1e-9 * geo.weight, axis=2)
    rank = tilt_rank(Rs, -geo.g / np.linalg.norm(geo.g), R0)
    # the stability of every pulling candidate at once (the loop below may skip some of them)
    stable, h = np.zeros(pull.shape, bool), np.full(pull.shape, np.nan)
    n_, s_ = np.nonzero(pull)
    if n_.size:
        stable[n_, s_], h[n_, s_] = _stable(geo, P[todo[n_]], Rs[n_, s_], ts[n_, s_], dofs)
    for n, i in enumerate(todo):
        for s in np.argsort(np.where(pull[n], rank[n], np.inf), kind="stable"):
            if not pull[n, s] or (found[i] and not alternatives):
                break
            if any(hc.angle_from(Rs[n, s], c[0]) < 1e-7 for c in seen[i]):
                continue
            seen[i].append((Rs[n, s], np.maximum(ts[n, s], 0.0), bool(stable[n, s]), rank[n, s], h[n, s]))
            found[i] |= stable[n, s]


def _hang_point(geo, P, planar, nominal, alternatives):
    R0 = point_mass_rotation(geo, planar, nominal)
    t, balanced = point_mass_many(geo, P, planar, R0)
    pull = balanced & np.all(t >= -1e-9 * geo.weight, axis=1)
    dofs = hc.DOFS_POINT2 if planar else hc.DOFS_POINT3
    k = len(P)
    found, hmin = np.zeros(k, bool), np.full(k, np.nan)
    rows = np.flatnonzero(pull)
    if rows.size:
        found[rows], hmin[rows] = _stable(geo, P[rows], np.broadcast_to(R0, (rows.size, 3, 3)), t[rows], dofs)
    alts = [[(R0, np.maximum(t[i], 0.0), False)] if pull[i] and not found[i] else [] for i in range(k)] \
        if alternatives else []
    R = np.broadcast_to(R0, (k, 3, 3)).copy()
    return R, np.maximum(t, 0.0), _statuses(found, pull, balanced), hmin, alts
